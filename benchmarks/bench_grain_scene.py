"""The README's main job (`symmech run scenes/grain_default.toml --out out`): what the contract costs.

Interleaved repeats of
  bare     the simulation alone (prepared scene, no budget checks, no output);
  guarded  the same simulation as `run` does it (progress, per-phase budget and stagnation
           checks, the 0.25 s watchdog);
  job      the whole job: read + validate + prepare + estimate + guarded run + finite
           checks + CSV/JSON/plots written into a temporary folder and renamed into place.
Prints medians with min/max (benchmarks/timing.py) and the ratios to `bare`.

Usage: python benchmarks/bench_grain_scene.py [--quick] [--repeats 5] [--scene scenes/grain_default.toml]
"""
import argparse
import tempfile
import tomllib
from pathlib import Path

from timing import interleaved, machine, ratio

from symmech.core import pipeline
from symmech.core.context import Context
from symmech.grain import motion_scene


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="the scene's first 0.2 s only")
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--scene", default=str(Path(__file__).resolve().parents[1] / "scenes" / "grain_default.toml"))
    ns = p.parse_args()
    data = tomllib.loads(Path(ns.scene).read_text())
    if ns.quick:
        data["duration"] = min(data.get("duration", 0.2), 0.2)
    scene = pipeline.load(data)
    out = Path(tempfile.mkdtemp()) / "out"
    stats = interleaved({
        "bare": lambda: motion_scene.simulate(scene.setup),
        "guarded": lambda: scene.run(Context(quiet=True)),
        "job": lambda: pipeline.run_to(data, out, Context(quiet=True)),
        "validate + prepare": lambda: pipeline.load(data),
    }, ns.repeats)
    print(f"machine: {machine()}; {ns.scene}, duration {data.get('duration')} s")
    for name, s in stats.items():
        print(f"{name:18s} {s.text()}   this/bare {ratio(s, stats['bare'])}")


if __name__ == "__main__":
    main()
