"""The cost of the bundled design sweep (scenes/trolley_elastic_sweep.toml, 20 x 20 points): CPU seconds per
point, the client's validation of every point, and the wall time they imply on 2 idle cores.

CPU time (``time.process_time``) rather than wall time: each point is one process's work on one BLAS thread
(as the sweep runs it), so its CPU seconds do not depend on how many other sessions share the cores; the
implied wall time of the whole sweep is validation + points x CPU per point / workers. Points are taken at
the corners and the centre of the plane (the cost varies with speed and stiffness), interleaved over rounds.

    python benchmarks/bench_trolley_sweep.py [--quick]   # --quick: one round
"""
from __future__ import annotations

import statistics
import sys
import time
from pathlib import Path

from symmech.core import pipeline
from symmech.core.scene import read_toml
from symmech.trolley import sweep

from timing import machine

SCENE = Path(__file__).resolve().parents[1] / "scenes" / "trolley_elastic_sweep.toml"
WORKERS = 2


def cpu(fn) -> float:
    start = time.process_time()
    fn()
    return time.process_time() - start


def main(quick: bool) -> None:
    raw = read_toml(SCENE)
    p = sweep.plan(raw, pipeline.load(raw).resolved)
    nx, ny = p.shape
    corners = [(0, 0), (nx - 1, ny - 1), (0, ny - 1), (nx - 1, 0), (nx // 2, ny // 2)]
    sweep.evaluate(p.point(0, 0), 1e9)  # imports and first-use costs, paid once per worker
    rounds = 1 if quick else 5
    validate = [cpu(lambda: sweep.validate(p)) for _ in range(rounds)]
    per_point = [cpu(lambda: sweep.evaluate(p.point(i, j), 1e9)) for _ in range(rounds) for i, j in corners]
    point, check = statistics.median(per_point), statistics.median(validate)
    points = nx * ny
    print(f"{machine()}; {SCENE.name}: {nx} x {ny} points, {rounds} round(s) over {len(corners)} points")
    print(f"  CPU per point       {point:8.3g} s (min {min(per_point):.3g}, max {max(per_point):.3g}, "
          f"n={len(per_point)})")
    print(f"  validate all points {check:8.3g} s CPU (client, serial)")
    print(f"  implied wall time on {WORKERS} idle cores: {check + points * point / WORKERS:.4g} s")


if __name__ == "__main__":
    main("--quick" in sys.argv)
