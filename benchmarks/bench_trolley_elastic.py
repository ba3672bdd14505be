"""Elastic trolley: what accuracy costs in time (work-precision), stiff rollers.

A 10 kg trolley on rollers of 1e8 N/m (fastest mode ~5000 rad/s, damped) along the paper's
helix, t in [0, T]. Methods: Radau and BDF with the analytic Jacobian of the invariants,
Radau with scipy's finite-difference Jacobian, explicit DOP853. Error: max |P - P_ref| of
the reactions over the grid relative to max |P_ref|, the reference by DOP853 at rtol 1e-10.
Times are medians of interleaved repeats (all methods once per round). The absolute
tolerance of the coordinates is rtol x 1e-6 m (deflections are ~1e-6 m): with k = 1e8 N/m an
absolute error e of q is an error k e of the reactions.

Usage: python benchmarks/bench_trolley_elastic.py [--quick]
"""
import argparse
import time

import numpy as np

from symmech.core import pipeline
from symmech.trolley import elastic as el
from symmech.trolley import elastic_scene

SCENE = {"kind": "trolley", "frame": "frenet", "track": {"type": "helix", "radius": 7.0, "rise": 5 / (2 * np.pi)},
         "trolley": {"mass": 10.0, "com": [1.0, 0.5, 0.0], "axle_distance": 2.0, "half_gauge": 1.0},
         "motion": {"speed": "3*t + 7*sin(t/2)"}, "time": {"t_end": 2.0, "steps": 20}}


def setup():
    drive = elastic_scene.drive_of(pipeline.load(SCENE).setup, 1)
    mdl = el.ElasticModel(10.0, (1.0, 0.5, 0.0), (1.0, 2.0, 1.5, 0, 0, 0), 2.0, 1.0, 9.81,
                          el.Rollers((1e8,) * 5, (1e3,) * 5))
    return el.System(mdl), drive


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    args = ap.parse_args()
    system, drive = setup()
    t = np.linspace(0.0, 1.0 if args.quick else 2.0, 21)
    # explicit reference: it resolves the start transient of the 5000 rad/s modes, which the
    # L-stable implicit methods may damp faster than the physics once their steps grow
    ref = el.simulate(system, drive, t, method="DOP853", rtol=1e-10, atol_q=1e-17)["P"]
    scale = np.abs(ref).max()
    methods = {"Radau, analytic J": dict(method="Radau"), "BDF, analytic J": dict(method="BDF"),
               "Radau, FD J": dict(method="Radau", analytic_jacobian=False), "DOP853": dict(method="DOP853")}
    tols = (1e-5, 1e-7) if args.quick else (1e-5, 1e-6, 1e-7, 1e-8, 1e-9)
    repeats = 1 if args.quick else 5
    times = {(m, r): [] for m in methods for r in tols}
    errors, nfev = {}, {}
    for _ in range(repeats):
        for rtol in tols:
            for name, kw in methods.items():
                start = time.perf_counter()
                out = el.simulate(system, drive, t, rtol=rtol, atol_q=rtol * 1e-6, **kw)
                times[(name, rtol)].append(time.perf_counter() - start)
                errors[(name, rtol)] = np.abs(out["P"] - ref).max() / scale
                nfev[(name, rtol)] = out["nfev"]
    print(f"{'method':<20} {'rtol':>7} {'median s':>9} {'rel error':>10} {'nfev':>7}")
    for (name, rtol), ts in times.items():
        print(f"{name:<20} {rtol:>7.0e} {np.median(ts):>9.3f} {errors[(name, rtol)]:>10.2e} {nfev[(name, rtol)]:>7}")


if __name__ == "__main__":
    main()
