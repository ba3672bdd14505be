"""Estimate against actual time of every bundled scene's run and of sweeps, each in a fresh process.

    python benchmarks/bench_estimates.py                 # every bundled scene's run, and the sweeps below
    python benchmarks/bench_estimates.py --cold          # the same, each on an empty NUMBA_CACHE_DIR
    python benchmarks/bench_estimates.py grain_default   # only the names given

A run's estimate is the one `symmech run` tells (pipeline.Scene.estimate: the count model scaled by a timed
sample; summary.json's `estimate`), its actual the run stage's wall time (summary.json's timing_s.run). A sweep's
estimate is the last one `symmech sweep` tells (the total from its start; summary.json's `estimate`), its actual
the sweep's whole wall time; first/act is the first one it tells (on a cold cache, before the compile). Ratios
est/actual.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import tomllib

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "scenes"
# name: (scene file, points per swept axis, grains per population; None: as bundled): small copies of the two
# large bundled sweeps (minutes of CPU on 2 cores) and the other bundled sweeps whole
SWEEPS = {
    "grain_separation_3x3x8": ("grain_separation.toml", 3, 8),
    "trolley_elastic_sweep_3x3": ("trolley_elastic_sweep.toml", 3, None),
    "grain_transport_sweep": ("grain_transport_sweep.toml", None, None),
    "trolley_speed_sweep": ("trolley_speed_sweep.toml", None, None),
}


def one_run(path: str) -> dict:
    from symmech.core import pipeline
    from symmech.core.context import Context

    class Silent(Context):  # not quiet, as `symmech run`: the estimate it tells, timed samples included
        def say(self, message: str) -> None:
            pass

    with tempfile.TemporaryDirectory() as folder:
        scene = pipeline.load(path)
        result = scene.run(Silent(quiet=False))
        pipeline.write(result, Path(folder) / "out", scene, plots=False)
    return {"estimate": scene.cost and scene.cost.seconds, "actual": scene.timing["run"],
            "sampled": scene.timing["estimate"], "what": scene.cost and scene.cost.what}


def one_sweep(name: str) -> dict:
    from symmech.core import sweep
    from symmech.core.context import Context

    file, num, count = SWEEPS[name]
    raw = tomllib.loads((SCENES / file).read_text())
    for axis in ("x", "y") if num else ():
        raw["sweep"][axis]["num"] = num
    for population in raw.get("population", []) if count else ():
        population["count"] = count
    told = []

    class Recording(Context):
        def say(self, message: str) -> None:
            told.append(message)

    ctx = Recording(quiet=True)
    with tempfile.TemporaryDirectory() as folder:
        sweep.run(raw, Path(folder) / "out", ctx)
    estimates = [m for m in told if m.startswith("estimated sweep time")]
    return {"estimate": float(estimates[-1].split()[3]), "first": float(estimates[0].split()[3]),
            "actual": ctx.elapsed(), "what": estimates[-1]}


def measure(name: str, cold: bool) -> dict:
    env = dict(os.environ)
    with tempfile.TemporaryDirectory() as cache:
        if cold:
            env["NUMBA_CACHE_DIR"] = cache
        what = "sweep" if name in SWEEPS else "run"
        target = name if what == "sweep" else str(SCENES / f"{name}.toml")
        out = subprocess.run([sys.executable, __file__, "--one", what, target], env=env, capture_output=True,
                             text=True, check=True)
    return json.loads(out.stdout.splitlines()[-1])


def main(argv: list[str]) -> None:
    if argv[:1] == ["--one"]:
        print(json.dumps(one_run(argv[2]) if argv[1] == "run" else one_sweep(argv[2])))
        return
    cold = "--cold" in argv
    names = [a for a in argv if not a.startswith("--")] or \
        sorted(p.stem for p in SCENES.glob("*.toml") if "sweep" not in p.stem) + list(SWEEPS)
    print(f"{'name':32s} {'estimate s':>10s} {'actual s':>9s} {'est/act':>8s} {'first/act':>9s}  "
          f"({'cold' if cold else 'warm'})")
    for name in names:
        m = measure(name, cold)
        est = m["estimate"]
        ratio = f"{est / m['actual']:8.2f}" if est else "       -"
        first = f"{m['first'] / m['actual']:9.2f}" if "first" in m else "        -"
        print(f"{name:32s} {est or 0:10.3g} {m['actual']:9.3g} {ratio} {first}  {m.get('what') or ''}", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
