"""Sideways-sliding population: CPU time per grain and agreement with an independent event-driven reference.

Point masses on a 3 degree incline vibrating at Gamma_v = 1.3 (lift-off once a period), started on the
plane with 1-5 cm/s sideways. Each grain gets at most ``--cap`` CPU seconds (a run past it
counts as stalled), so the script also measures code that hangs.

Run: python benchmarks/bench_grain_sliding.py [--grains 50] [--duration 0.5] [--cap 30] [--rotation]
"""
from __future__ import annotations

import argparse
import signal
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from grain_sliding_reference import RADIUS, conveyor, on_plane, population, reference  # noqa: E402

from symmech.grain import motion  # noqa: E402


class _Cap(Exception):
    pass


def _alarm(*_):
    raise _Cap


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--grains", type=int, default=50)
    ap.add_argument("--duration", type=float, default=0.5)
    ap.add_argument("--cap", type=float, default=30.0)
    ap.add_argument("--rotation", action="store_true", help="rolling spheres (timing only: no reference)")
    args = ap.parse_args()
    signal.signal(signal.SIGVTALRM, _alarm)
    cpu, transport_err, lateral_err, stalled = [], [], [], 0
    for phase, v0 in zip(*population(args.grains, 7)):
        model = conveyor(phase, rotation=args.rotation)
        num = motion.Numerics(tolerance=1e-11, scan_step=model.period / 40, sample_interval=model.period / 4)
        start = time.process_time()
        signal.setitimer(signal.ITIMER_VIRTUAL, args.cap)
        try:
            res = motion.simulate(model, num, on_plane(v=(*v0, 0.0)), args.duration)
        except _Cap:
            stalled += 1
            cpu.append(args.cap)
            continue
        finally:
            signal.setitimer(signal.ITIMER_VIRTUAL, 0)
        cpu.append(time.process_time() - start)
        if args.rotation:
            continue
        r_ref, _ = reference(model.g_k, model.vibration, model.mu, RADIUS, v0, args.duration)
        transport_err.append(abs(res.final.r[0] - r_ref[0]) / abs(r_ref[0]))
        lateral_err.append(abs(res.final.r[1] - r_ref[1]))
    cpu = np.array(cpu)
    print(f"{args.grains} grains, {args.duration} s each: CPU median {np.median(cpu):.3g} s, max {cpu.max():.3g} s, "
          f"total {cpu.sum():.3g} s; stalled past {args.cap:g} s: {stalled}")
    if transport_err:
        print(f"transport velocity vs reference: max relative error {max(transport_err):.2e}; "
              f"sideways position max error {max(lateral_err):.2e} m")


if __name__ == "__main__":
    main()
