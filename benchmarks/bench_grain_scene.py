"""The README's main job (`symmech run scenes/grain_default.toml --out out`): what the contract costs.

Interleaved repeats of
  bare     the simulation alone (prepared scene, no budget checks, no output);
  guarded  the same simulation as `run` does it (progress, per-phase budget and stagnation
           checks, the 0.25 s watchdog);
  job      the whole job: read + validate + prepare + estimate + guarded run + finite
           checks + CSV/JSON/plots written into a temporary folder and renamed into place.
Prints medians with the median absolute deviation, and the ratios to `bare`.

Usage: python benchmarks/bench_grain_scene.py [--repeats 5] [--scene scenes/grain_default.toml]
"""
import argparse
import statistics
import tempfile
import time
from pathlib import Path

from symmech.core import pipeline
from symmech.core.context import Context
from symmech.grain import motion_scene


def timed(fn) -> float:
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--scene", default=str(Path(__file__).resolve().parents[1] / "scenes" / "grain_default.toml"))
    ns = p.parse_args()
    scene = pipeline.load(ns.scene)
    out = Path(tempfile.mkdtemp()) / "out"
    runs = {
        "bare": lambda: motion_scene.simulate(scene.setup),
        "guarded": lambda: scene.run(Context(quiet=True)),
        "job": lambda: pipeline.run_to(ns.scene, out, Context(quiet=True)),
    }
    times = {name: [] for name in runs}
    for _ in range(ns.repeats):
        for name, fn in runs.items():
            times[name].append(timed(fn))
    bare = statistics.median(times["bare"])
    for name, ts in times.items():
        median = statistics.median(ts)
        mad = statistics.median(abs(t - median) for t in ts)
        print(f"{name:8s} {median:7.3f} s ± {mad:.3f} (median ± MAD of {len(ts)})   ratio to bare {median / bare:.3f}")
    load = timed(lambda: pipeline.load(ns.scene))
    print(f"validate + prepare alone: {load * 1e3:.1f} ms")


if __name__ == "__main__":
    main()
