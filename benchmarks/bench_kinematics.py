"""core.kinematics on one vector (the ODE right-hand-side case) against a hand-written numpy literal.

The sliding ODE builds one skew matrix per right-hand-side evaluation; this checks that the shared
function costs about what the literal it replaced did, and how much the scalar fast path saves over
the batch path (a (1, 3) stack of the same vector). Differences are reported beside the times.

Run: python benchmarks/bench_kinematics.py [--quick]
"""
from __future__ import annotations

import sys

import numpy as np

from timing import interleaved, machine, ratio

from symmech.core import kinematics as kin


def _literal_skew(r):
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def _literal_roll(delta):
    c, s = np.cos(delta), np.sin(delta)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, s], [0.0, -s, c]])


def main() -> None:
    number = 2_000 if "--quick" in sys.argv else 20_000
    r, stack, delta = np.array([0.3, -1.2, 0.7]), np.array([[0.3, -1.2, 0.7]]), 0.4
    print(machine())
    for what, fast, batch, literal in (
            ("skew", lambda: kin.skew(r), lambda: kin.skew(stack), lambda: _literal_skew(r)),
            ("elementary (x1, passive)", lambda: kin.elementary(0, delta),
             lambda: kin.elementary(0, np.array([delta])), lambda: _literal_roll(delta))):
        diff = float(np.abs(fast() - literal()).max() + np.abs(batch()[0] - literal()).max())
        t = interleaved({"fast": fast, "batch": batch, "literal": literal}, repeats=7, number=number)
        print(f"{what}: core one vector {t['fast'].text('us', 1e6)}; core (1, ...) batch "
              f"{t['batch'].text('us', 1e6)}; literal {t['literal'].text('us', 1e6)}")
        print(f"  batch/fast {ratio(t['batch'], t['fast'])}, fast/literal {ratio(t['fast'], t['literal'])}, "
              f"max abs difference to the literal {diff:.1e}")


if __name__ == "__main__":
    main()
