"""The compiled grain engine of this tree against another source tree (``--before DIR``, e.g. a ``git archive``
of an earlier commit), in CPU seconds (user + sys of fresh processes: the shared machine's wall time is
noise): the cold compile (empty ``NUMBA_CACHE_DIR`` each time), the warm run of the whole default scene (best
of 3 calls per process, each tree on its own persistent cache), interleaved; then whether the two trees'
results (trajectory and impact rows) are equal bit for bit. ``--sweep N``: N interleaved rounds of a sample of the
bundled separation sweep's grains instead (:data:`SWEEP_POINTS` x 2 populations x 8 grains through
``motion_scene.simulate_many``, as the sweep runs them), CPU per grain, each tree on its own warm cache (``symmech
warm`` it first: ``NUMBA_CACHE_DIR`` of this process, ``--before-cache`` of the other), their trajectory and impact
rows compared bit for bit. With ``--before-cache`` and no ``--sweep`` the warm runs use the two warm caches (this
tree's ``NUMBA_CACHE_DIR``, ``--before-cache``; ``symmech warm`` each first) instead of fresh ones, and ``--cold 0``
skips the cold compiles: the warm comparison alone, impacts per CPU-second beside each time.

    git archive HEAD~3 | tar -x -C /tmp/before
    python benchmarks/bench_grain_before.py --before /tmp/before --cold 3 --warm 5
    python benchmarks/bench_grain_before.py --before /tmp/before --before-cache /tmp/cache --sweep 5
    python benchmarks/bench_grain_before.py --before /tmp/before --before-cache /tmp/cache --cold 0 --warm 7
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
from pathlib import Path

import numpy as np
from timing import child_cpu, tree_env

HERE = Path(__file__).resolve().parents[1]
SETUP = ("import time, numpy as np; from symmech.core import pipeline; from symmech.grain.motion_engine import driver as compiled; "
         "sc = pipeline.load('scenes/grain_default.toml').setup; ")
COLD = SETUP + "compiled.simulate(sc.model, sc.numerics, sc.start, 0.01)"
WARM = SETUP + ("compiled.simulate(sc.model, sc.numerics, sc.start, 0.01); ts = []\n"
                "for _ in range(3):\n"
                "    c = time.process_time(); r = compiled.simulate(sc.model, sc.numerics, sc.start, "
                "sc.start.t + sc.duration); ts.append(time.process_time() - c)\n"
                "print(min(ts)); np.save(OUT + '_rows.npy', r.trajectory); np.save(OUT + '_imps.npy', r.impact_log.rows)")


# Low-throw corner (stiff slips), mid-plane, high-throw corner of the 12 x 12 plane: (amplitude, frequency) indices.
SWEEP_POINTS = [(0, 0), (0, 3), (3, 0), (3, 3), (6, 3), (6, 6), (9, 3), (9, 9)]
SWEEP = ("import time, tomllib, numpy as np; from symmech.core import pipeline; from symmech.grain import sweep, "
         "motion_scene\n"
         "raw = tomllib.load(open('scenes/grain_separation.toml', 'rb')); p = sweep.plan(raw, pipeline.load(raw).resolved)\n"
         f"scenes = [pipeline.load(d).setup for i, j in {SWEEP_POINTS} for k in range(2) for d in sweep.grains(p, k, i, j, 0, 8)]\n"
         "ms = motion_scene.simulate_many(scenes, workers=1); c = time.process_time()\n"
         "for _ in range(2):\n"
         "    motion_scene.simulate_many(scenes, workers=1)\n"
         "print((time.process_time() - c) / 2 / len(scenes)); assert ms[0].extra['engine'] == 'compiled'\n"
         "np.save(OUT + '_rows.npy', np.concatenate([m.trajectory for m in ms])); "
         "np.save(OUT + '_imps.npy', np.concatenate([m.impact_log.rows for m in ms]))")


def child(tree: Path, code: str, cache: str) -> tuple[float, str]:
    """(CPU seconds, stdout) of ``code`` in a fresh process on ``tree`` with numba's cache in ``cache``."""
    env = {**tree_env(tree), "NUMBA_CACHE_DIR": cache}
    cpu, done = child_cpu([sys.executable, "-c", code], cwd=tree, env=env, capture_output=True, text=True)
    return cpu, done.stdout


def summary(xs: list) -> str:
    if not xs:
        return "(not run)"
    return f"{statistics.median(xs):.4g} s (min {min(xs):.4g}, max {max(xs):.4g}, n={len(xs)})"


def sweep_grains(trees: dict, caches: dict, rounds: int) -> None:
    """CPU per grain of the sweep's sample on each tree (fresh processes, warm caches, interleaved), rows compared."""
    with tempfile.TemporaryDirectory() as work:
        cpu = {k: [] for k in trees}
        for _ in range(rounds):
            for name, tree in trees.items():
                code = f"OUT = {str(Path(work) / name)!r}\n" + SWEEP
                cpu[name].append(float(child(tree, code, caches[name])[1]))
        equal = all(np.array_equal(np.load(Path(work) / f"this_{k}.npy").view(np.int64),
                                   np.load(Path(work) / f"before_{k}.npy").view(np.int64)) for k in ("rows", "imps"))
    for name in trees:
        ms = [1e3 * x for x in cpu[name]]
        print(f"{name:<7} sweep sample {statistics.median(ms):.3f} ms CPU per grain (min {min(ms):.3f}, max {max(ms):.3f}, "
              f"n={len(ms)})")
    print(f"before / this: {statistics.median(cpu['before']) / statistics.median(cpu['this']):.3f}; "
          f"rows bit for bit equal: {equal}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", type=Path, required=True)
    ap.add_argument("--cold", type=int, default=3)
    ap.add_argument("--warm", type=int, default=5)
    ap.add_argument("--sweep", type=int, default=0, help="rounds of the sweep sample instead (warm caches)")
    ap.add_argument("--before-cache", help="the before tree's warm NUMBA_CACHE_DIR (with --sweep)")
    ns = ap.parse_args()
    trees = {"this": HERE, "before": ns.before.resolve()}
    if ns.sweep:
        return sweep_grains(trees, {"this": os.environ["NUMBA_CACHE_DIR"], "before": ns.before_cache}, ns.sweep)
    cold = {k: [] for k in trees}
    for _ in range(ns.cold):
        for name, tree in trees.items():
            with tempfile.TemporaryDirectory() as cache:
                cold[name].append(child(tree, COLD, cache)[0])
    with tempfile.TemporaryDirectory() as work:
        caches = {name: str(Path(work) / f"cache_{name}") for name in trees}
        if ns.before_cache:
            caches = {"this": os.environ["NUMBA_CACHE_DIR"], "before": ns.before_cache}
        warm = {k: [] for k in trees}
        for _ in range(ns.warm):
            for name, tree in trees.items():
                code = f"OUT = {str(Path(work) / name)!r}\n" + WARM
                warm[name].append(float(child(tree, code, caches[name])[1]))
        equal = all(np.array_equal(np.load(Path(work) / f"this_{k}.npy").view(np.int64),
                                   np.load(Path(work) / f"before_{k}.npy").view(np.int64)) for k in ("rows", "imps"))
        impacts = {name: len(np.load(Path(work) / f"{name}_imps.npy")) for name in trees}
    for name in trees:
        print(f"{name:<7} cold compile {summary(cold[name])} CPU; warm default scene {summary(warm[name])} CPU, "
              f"{impacts[name]} impacts: {impacts[name] / statistics.median(warm[name]):,.0f} per CPU-second")
    if ns.cold:
        print(f"this / before cold: {statistics.median(cold['this']) / statistics.median(cold['before']):.3f}")
    print(f"this / before warm: {statistics.median(warm['this']) / statistics.median(warm['before']):.3f}; "
          f"results bit for bit equal: {equal}")


if __name__ == "__main__":
    main()
