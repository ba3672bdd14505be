"""The main job in a fresh process, its stages, and the overhead of the validate-first pipeline.

Part 1, the README's main job (``symmech run scenes/grain_default.toml --out DIR``), each
contender a fresh interpreter, interleaved over ``--repeats`` (>= 5) rounds: ``python -c pass``
(interpreter start), ``python -c "import numpy, scipy, matplotlib"`` (the baseline:
the main job should take under 4x its time), ``symmech run`` with the scene's default plots (on the
engine built ahead of time when ``symmech warm`` built it), the same on numba's cache
(``SYMMECH_AHEAD_OF_TIME=0``) and with ``--no-plots``, the same run through ``main(argv)`` called from Python (without the command
line's garbage-collector tuning: its effect), and a stage probe (run under ``-X importtime``) that
times imports of the CLI and the kind, validation, simulation, plots and writing, and attributes
every import — also the lazy ones inside a stage — to the stage that triggered it. The probe calls
the pipeline itself, so its collections are untuned and its exit is not timed.

Part 1b, in one process: every figure the kind can draw, in PNG and in SVG, each alone.

Part 2 (skipped with ``--quick``), in one process: (a) the strongest baseline, ``kind.run``
on an already prepared scene with its tables, files and plots written straight into an existing
folder with a plain JSON summary — no reading, validation, finite checks, lock, temporary folder
or rename; (b) the whole of ``pipeline.run_to``. Then, without plots, 20 interleaved repeats of
the writing alone: plain writes vs ``pipeline.write`` (lock, temporary folder, module hashes,
strict JSON, rename, old folder removed).

    python benchmarks/bench_pipeline.py [--quick]                # scenes/grain_default.toml
    python benchmarks/bench_pipeline.py scenes/smm_excavator.toml --repeats 7
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from timing import interleaved, machine, ratio

from symmech.core import pipeline
from symmech.core.context import Context

NUMBA_ONLY = "same, numba's cache (SYMMECH_AHEAD_OF_TIME=0)"
STAGES = ("imports", "validate", "simulation", "plots", "writing")
# symmech run through main(argv): the same command without the command line's gc tuning (cli.main).
UNTUNED = "import sys; from symmech.cli import main; sys.exit(main(['run', *sys.argv[1:]]))"
# Runs in a fresh interpreter under -X importtime; marks each stage on stderr so that the
# import lines that follow belong to it, and prints the stage wall times [s] as JSON.
PROBE = """
import json, sys, time, tempfile, tomllib
from pathlib import Path
scene_file, out = sys.argv[1], Path(sys.argv[2])
times = {}
def stage(name, start):
    times[name] = time.perf_counter() - start
    print(f"STAGE {name}", file=sys.stderr, flush=True)
print("STAGE start", file=sys.stderr, flush=True)  # imports before here: interpreter and probe, not symmech
start = time.perf_counter()
import symmech.cli
from symmech.core import pipeline, registry
from symmech.core.context import Context
registry.get(tomllib.loads(Path(scene_file).read_text())["kind"])
stage("imports", start); start = time.perf_counter()
scene = pipeline.load(scene_file)
stage("validate", start); start = time.perf_counter()
result = scene.run(Context(quiet=True))
stage("simulation", start); start = time.perf_counter()
with tempfile.TemporaryDirectory() as folder:
    plots = result.plots(Path(folder)) if result.plots else []
stage("plots", start); start = time.perf_counter()
pipeline.write(result, out, scene, plots=False)
stage("writing", start)
print(json.dumps({"seconds": times, "plots": [Path(p).name for p in plots]}))
"""


def _imports_by_stage(stderr: str) -> dict[str, float]:
    """Seconds of import (sum of -X importtime self times) per stage marked in ``stderr``; the
    imports before the ``start`` mark (interpreter start-up, the probe's own) are left out."""
    spent = dict.fromkeys(("start", *STAGES), 0.0)
    pending = 0.0
    for line in stderr.splitlines():
        if line.startswith("STAGE "):
            spent[line.split()[1]] += pending
            pending = 0.0
        elif line.startswith("import time:") and line.split("|")[0].split(":")[1].strip().isdigit():
            pending += int(line.split("|")[0].split(":")[1]) * 1e-6
    return spent


# the libraries the main job cannot do without (numba's BLAS/LAPACK bindings import scipy.linalg)
FLOOR = "floor: import numba, scipy.linalg, matplotlib figure + Agg"
# ... and numba's CPU target set up, as loading any cached compiled function does first (its typing and
# lowering registries: numba.np.arraymath, linalg, ...): the floor of a run on the cached engine
FLOOR_LOAD = "floor + numba's target set up (any cache load)"
FLOOR_IMPORTS = "import numba, scipy.linalg, matplotlib.figure, matplotlib.backends.backend_agg"


def main_job(scene: str, repeats: int) -> None:
    """Part 1: the main job and its baseline in fresh processes; stages from the probe."""
    scene = str(Path(scene).resolve())
    probes = []
    with tempfile.TemporaryDirectory() as tmp:
        def fresh(*args, env=None):
            return lambda: subprocess.run([sys.executable, *args], check=True, capture_output=True, cwd=tmp,
                                          env=env and {**os.environ, **env})

        def probe():
            proc = subprocess.run([sys.executable, "-X", "importtime", "-c", PROBE, scene, str(Path(tmp) / "p")],
                                  check=True, capture_output=True, text=True, cwd=tmp)
            probes.append((json.loads(proc.stdout.splitlines()[-1]), _imports_by_stage(proc.stderr)))

        fresh("-m", "symmech", "run", scene, "--out", "warm", "--quiet")()  # compile caches, disk cache
        stats = interleaved({
            "python -c pass": fresh("-c", "pass"),
            'python -c "import numpy, scipy, matplotlib"': fresh("-c", "import numpy, scipy, matplotlib"),
            FLOOR: fresh("-c", FLOOR_IMPORTS),
            FLOOR_LOAD: fresh("-c", FLOOR_IMPORTS + "; numba.core.registry.cpu_target.target_context.refresh()"),
            "symmech run SCENE --out DIR (default plots)": fresh("-m", "symmech", "run", scene, "--out", "a",
                                                                "--quiet"),
            NUMBA_ONLY: fresh("-m", "symmech", "run", scene, "--out", "n", "--quiet",
                              env={"SYMMECH_AHEAD_OF_TIME": "0"}),
            "symmech run SCENE --out DIR --no-plots": fresh("-m", "symmech", "run", scene, "--out", "b",
                                                           "--quiet", "--no-plots"),
            "same (default plots), gc untuned: main(argv)": fresh("-c", UNTUNED, scene, "--out", "c", "--quiet"),
            "stage probe (under -X importtime)": probe,
        }, repeats=repeats)
    print(f"{machine()}; scene {scene}; {repeats} interleaved rounds, each contender a fresh process")
    for name, st in stats.items():
        print(f"  {name:<50} {st.text()}")
    base = stats['python -c "import numpy, scipy, matplotlib"']
    for name in ("symmech run SCENE --out DIR (default plots)", NUMBA_ONLY, "symmech run SCENE --out DIR --no-plots"):
        print(f"  {name} / baseline: {ratio(stats[name], base)}   (target <= 4x)")
    print(f"  floor: importing the libraries the job uses / baseline: {ratio(stats[FLOOR], base)}")
    print(f"  floor with numba's target set up / baseline: {ratio(stats[FLOOR_LOAD], base)}")
    untuned = stats["same (default plots), gc untuned: main(argv)"]
    print(f"  gc untuned / symmech run (default plots): "
          f"{ratio(untuned, stats['symmech run SCENE --out DIR (default plots)'])}")
    print(f"  plots drawn by default: {', '.join(probes[0][0]['plots']) or 'none'}")
    print("  stages of the probe: wall median (min, max) [s], of which imports median [s]")
    for stage in STAGES:
        wall = [p[0]["seconds"][stage] for p in probes]
        imports = [p[1][stage] for p in probes]
        print(f"    {stage:<11} {statistics.median(wall):8.3f} ({min(wall):.3f}, {max(wall):.3f})"
              f"   imports {statistics.median(imports):.3f}")


def per_figure(scene_file: str, repeats: int) -> None:
    """Part 1b: each figure of the kind in each format, drawn from one run, interleaved.

    A kind's draw closure reads the scene's resolved ``[output]`` table, so changing that
    table between calls selects the figure and the format."""
    scene = pipeline.load(scene_file)
    result = scene.run(Context(quiet=True))
    output = scene.resolved["output"]
    names = scene.kind.schema.fields["output"].fields["plots"].choices
    with tempfile.TemporaryDirectory() as tmp:
        def one(name, fmt):
            def draw():
                output.update(plots=[name], formats=[fmt])
                result.plots(Path(tmp))
            return draw

        result.plots(Path(tmp))  # matplotlib imported outside the timing
        stats = interleaved({f"{n}.{f}": one(n, f) for n in names for f in ("png", "svg")}, repeats=repeats)
    print("  each figure, drawn and written alone from one run (in process, matplotlib imported):")
    for name, st in stats.items():
        print(f"    {name:<24} {st.text()}")


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scene", nargs="?", default=str(Path(__file__).parents[1] / "scenes" / "grain_default.toml"))
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--plots", action="store_true", help="part 2: include plots in (a) and (b)")
    p.add_argument("--quick", action="store_true", help="part 1 only (the main job in fresh processes)")
    a = p.parse_args()
    main_job(a.scene, max(5, a.repeats))
    per_figure(a.scene, max(5, a.repeats))
    if a.quick:
        return
    print("\npart 2: pipeline overhead in one process")
    scene = pipeline.load(a.scene)
    bare, whole, stages = [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        pipeline.run_to(a.scene, Path(tmp) / "out", Context(quiet=True), plots=a.plots)  # warm imports
        plain = Path(tmp) / "plain"
        plain.mkdir()
        for _ in range(max(5, a.repeats)):
            start = time.perf_counter()
            result = scene.kind.run(scene.setup, Context(quiet=True))
            pipeline.write_files(plain, result, a.plots)
            (plain / "summary.json").write_text(json.dumps(result.summary, default=str))
            bare.append(time.perf_counter() - start)
            start = time.perf_counter()
            pipeline.run_to(a.scene, Path(tmp) / "out", Context(quiet=True), plots=a.plots)
            whole.append(time.perf_counter() - start)
            stages.append(json.loads((Path(tmp) / "out" / "summary.json").read_text())["timing_s"])

    def show(name, xs):
        print(f"{name:<44} median {statistics.median(xs):9.4f} s  (min {min(xs):.4f}, max {max(xs):.4f})")

    print(f"scene {a.scene}, {len(bare)} interleaved repeats, plots {'on' if a.plots else 'off'}")
    show("(a) kind.run + plain writes", bare)
    show("(b) symmech run path (pipeline.run_to)", whole)
    for stage in stages[0]:
        show(f"    stage {stage}", [s[stage] for s in stages])
    ratio = [w / b for w, b in zip(whole, bare)]
    print(f"ratio (b)/(a): median {statistics.median(ratio):.4f} (min {min(ratio):.4f}, max {max(ratio):.4f})")
    plain_writes, atomic_writes = [], []
    with tempfile.TemporaryDirectory() as tmp:
        plain = Path(tmp) / "plain"
        plain.mkdir()
        result = scene.run(Context(quiet=True))
        for _ in range(20):
            start = time.perf_counter()
            pipeline.write_files(plain, result, False)
            (plain / "summary.json").write_text(json.dumps(result.summary, default=str))
            plain_writes.append(time.perf_counter() - start)
            start = time.perf_counter()
            pipeline.write(result, Path(tmp) / "out", scene, plots=False)
            atomic_writes.append(time.perf_counter() - start)
    show("(c) plain writes, no plots", plain_writes)
    show("(d) pipeline.write, no plots", atomic_writes)
    extra = statistics.median(atomic_writes) - statistics.median(plain_writes)
    print(f"atomic-write overhead (d)-(c): {extra * 1e3:.1f} ms = {extra / statistics.median(bare):.2e} of (a); "
          f"validation {statistics.median(s['validate'] for s in stages) * 1e3:.2f} ms")


if __name__ == "__main__":
    main()
