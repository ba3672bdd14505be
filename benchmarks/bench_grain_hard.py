"""Grains of the bundled separation sweep that slip while turning: Radau below the stiff slip speed and DOP853
above it (this code) against Radau for the whole slip and DOP853 throughout (the integrator before the stiff-slip
fix), seconds per grain and the difference of the results.

Grains at sweep point (0.6 mm, 25 Hz) never lift off (normal throw number 0.75) and stick and slip all along;
both integrators finish them, so the comparison measures what Radau costs where DOP853 did not stall. The
grains that stalled DOP853 (0.6 mm, 18 Hz) are timed with Radau alone.

Run: python benchmarks/bench_grain_hard.py [--quick]
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from timing import interleaved, machine, ratio  # noqa: E402

from symmech.core import pipeline  # noqa: E402
from symmech.core.scene import read_toml  # noqa: E402
from symmech.grain import motion_scene, sliding, sweep  # noqa: E402

SCENE = Path(__file__).resolve().parents[1] / "scenes" / "grain_separation.toml"


def grains(i: int, j: int, pop: str, count: int) -> list:
    raw = read_toml(SCENE)
    p = sweep.plan(raw, pipeline.load(raw).resolved)
    return [pipeline.load(d).setup for d in p.grains[p.names.index(pop)][i][j][:count]]


def run(scenes, how: str = "hybrid"):
    """Final positions of the scenes; ``how``: "hybrid" (this code), "radau" (the whole anisotropic slip
    implicit) or "dop853" (every phase explicit)."""
    init, power = sliding._Contact.__init__, sliding.SLIP_STIFF_POWER

    def dop853_only(self, *a):
        init(self, *a)
        self.stiff_slip = False
    sliding._Contact.__init__ = dop853_only if how == "dop853" else init
    sliding.SLIP_STIFF_POWER = -10.0 if how == "radau" else power  # s_stiff = tol^power v_scale: huge
    try:
        return [motion_scene.simulate(sc).final.r for sc in scenes]
    finally:
        sliding._Contact.__init__, sliding.SLIP_STIFF_POWER = init, power


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    count, repeats = (1, 3) if args.quick else (3, 5)
    print(machine())
    for pop in ("crop", "weed"):
        both = grains(0, 1, pop, count)
        ref = run(both)
        dx = {how: max(abs(a - b).max() for a, b in zip(ref, run(both, how))) for how in ("radau", "dop853")}
        t = interleaved({how: (lambda how=how: run(both, how)) for how in ("hybrid", "radau", "dop853")}, repeats)
        print(f"{pop}, 0.6 mm 25 Hz, {count} grain(s): hybrid {t['hybrid'].text()}, Radau {t['radau'].text()}, "
              f"DOP853 {t['dop853'].text()}; Radau/hybrid {ratio(t['radau'], t['hybrid'])}, DOP853/hybrid "
              f"{ratio(t['dop853'], t['hybrid'])}; max |r - r_hybrid| Radau {dx['radau']:.2e} m, "
              f"DOP853 {dx['dop853']:.2e} m")
        stalled = grains(0, 0, pop, count)
        t = interleaved({how: (lambda how=how: run(stalled, how)) for how in ("hybrid", "radau")}, repeats)
        print(f"{pop}, 0.6 mm 18 Hz (DOP853 stalls), {count} grain(s): hybrid {t['hybrid'].text()}, "
              f"Radau {t['radau'].text()}, Radau/hybrid {ratio(t['radau'], t['hybrid'])}")


if __name__ == "__main__":
    main()
