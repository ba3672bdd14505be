"""Elastic trolley: what accuracy costs in time (work-precision, stiff rollers), and the compiled engine
against the Python one.

``stiff`` (default part): a 10 kg trolley on rollers of 1e8 N/m (fastest mode ~5000 rad/s, damped) along
the paper's helix, t in [0, T]. Methods: Radau and BDF with the analytic Jacobian of the invariants, Radau
with scipy's finite-difference Jacobian, explicit DOP853. Error: max |P - P_ref| of the reactions over the
grid relative to max |P_ref|, the reference by DOP853 at rtol 1e-10. The absolute tolerance of the
coordinates is rtol x 1e-6 m (deflections are ~1e-6 m): with k = 1e8 N/m an absolute error e of q is an
error k e of the reactions.

``engines``: the bundled scene (scenes/trolley_elastic_helix.toml, 3 s, 1000 outputs) at rtol 1e-8 on the
compiled and the Python engine, case 1 and case 2 (error of the compiled P0…P5 against the Python engine's,
relative to max|P|); a 60 s ride on the same helix with the bundled mast at rtol 1e-6 (compiled only).

``traction``: the bundled scene driven by a traction P0 = 400 + 300 sin 3t - 2 V0² N from 5 m/s instead of its
speed, 0.3 s (100 outputs), case 1, rtol 1e-8, on both engines (the Python engine differences its Jacobian).

``cold``: the compile of the compiled engine into an empty numba cache (fresh process, NUMBA_CACHE_DIR).

Times are whole ``simulate`` calls (table, integration, outputs), medians of interleaved repeats (every
variant once per round) with the spread (min-max).

``cases``, ``ride``: case 2 against case 1 on the compiled engine only, the 60 s ride (parts of ``engines``).

Usage: python benchmarks/bench_trolley_elastic.py [--quick] [--part stiff|engines|cases|ride|traction|cold|all]
[--repeats N]
"""
import argparse
import copy
import os
import subprocess
import sys
import tempfile
import time
import tomllib

import numpy as np

from symmech.core import pipeline, scene
from symmech.trolley.elastic import system as el, body as el_body, simulate as el_sim
from symmech.trolley.elastic import scene as elastic_scene

SCENE = {"kind": "trolley", "frame": "frenet", "track": {"type": "helix", "radius": 7.0, "rise": 5 / (2 * np.pi)},
         "trolley": {"mass": 10.0, "com": [1.0, 0.5, 0.0], "axle_distance": 2.0, "half_gauge": 1.0},
         "motion": {"speed": "3*t + 7*sin(t/2)"}, "time": {"t_end": 2.0, "steps": 20}}
BUNDLED = tomllib.loads((scene.scenes_folder() / "trolley_elastic_helix.toml").read_text(encoding="utf-8"))


def setup():
    drive = elastic_scene.drive_of(pipeline.load(SCENE).setup, 1)
    mdl = el_body.ElasticModel(10.0, (1.0, 0.5, 0.0), (1.0, 2.0, 1.5, 0, 0, 0), 2.0, 1.0, 9.81,
                          el_body.Rollers((1e8,) * 5, (1e3,) * 5))
    return el.System(mdl), drive


def stiff(quick: bool, repeats: int):
    system, drive = setup()
    t = np.linspace(0.0, 1.0 if quick else 2.0, 21)
    # explicit reference: it resolves the start transient of the 5000 rad/s modes, which the
    # L-stable implicit methods may damp faster than the physics once their steps grow
    ref = el_sim.simulate(system, drive, t, method="DOP853", rtol=1e-10, atol_q=1e-17)["P"]
    scale = np.abs(ref).max()
    methods = {"Radau, analytic J": dict(method="Radau"), "BDF, analytic J": dict(method="BDF"),
               "Radau, FD J": dict(method="Radau", analytic_jacobian=False), "DOP853": dict(method="DOP853")}
    tols = (1e-5, 1e-7) if quick else (1e-5, 1e-6, 1e-7, 1e-8, 1e-9)
    times = {(m, r): [] for m in methods for r in tols}
    errors, nfev = {}, {}
    for _ in range(repeats):
        for rtol in tols:
            for name, kw in methods.items():
                start = time.perf_counter()
                out = el_sim.simulate(system, drive, t, rtol=rtol, atol_q=rtol * 1e-6, **kw)
                times[(name, rtol)].append(time.perf_counter() - start)
                errors[(name, rtol)] = np.abs(out["P"] - ref).max() / scale
                nfev[(name, rtol)] = out["nfev"]
    print(f"{'method':<20} {'rtol':>7} {'median s':>9} {'rel error':>10} {'nfev':>7}")
    for (name, rtol), ts in times.items():
        print(f"{name:<20} {rtol:>7.0e} {np.median(ts):>9.3f} {errors[(name, rtol)]:>10.2e} {nfev[(name, rtol)]:>7}")


def bundled(case: int = 1, t_end: float | None = None, steps: int | None = None):
    doc = copy.deepcopy(BUNDLED)
    doc["effects"]["local_curvature"] = case == 2
    if t_end is not None:
        doc["time"] = {"t_end": t_end, "steps": steps}
    return pipeline.load(doc).setup.elastic


def run(setup, engine: str, rtol: float) -> tuple[float, dict]:
    st = elastic_scene.Setup(**{**setup.__dict__, "engine": engine})
    start = time.perf_counter()
    out = elastic_scene.simulate(st, rtol=rtol)
    assert out["engine"] == engine, out["engine_reason"]
    return time.perf_counter() - start, out


def spread(ts) -> str:
    return f"{np.median(ts):8.3f} ({min(ts):.3f}-{max(ts):.3f})"


def engines(quick: bool, repeats: int):
    rtol = 1e-8
    variants = {("case 1", "compiled"): (bundled(1), "compiled"), ("case 1", "python"): (bundled(1), "python"),
                ("case 2", "compiled"): (bundled(2), "compiled"), ("case 2", "python"): (bundled(2), "python")}
    if quick:
        variants = {k: (bundled(int(k[0][-1]), 0.3, 100), e) for k, (_, e) in variants.items()}
    run(variants[("case 1", "compiled")][0], "compiled", rtol)  # loads the cache (or compiles) untimed
    times = {k: [] for k in variants}
    outs = {}
    for _ in range(repeats):
        for key, (st, engine) in variants.items():
            seconds, outs[key] = run(st, engine, rtol)
            times[key].append(seconds)
    print(f"bundled scene (3 s, 1000 outputs), rtol {rtol:g}; s: median (min-max) of {repeats} interleaved rounds")
    print(f"{'case':<7} {'compiled s':>24} {'python s':>24} {'speed-up':>9} {'|dP|/max|P|':>12} {'nfev c/p':>13} "
          f"{'table nodes, error':>22}")
    for case in ("case 1", "case 2"):
        c, p = outs[(case, "compiled")], outs[(case, "python")]
        error = np.abs(c["P"] - p["P"]).max() / np.abs(p["P"]).max()
        ratio = np.median(times[(case, "python")]) / np.median(times[(case, "compiled")])
        print(f"{case:<7} {spread(times[(case, 'compiled')]):>24} {spread(times[(case, 'python')]):>24} "
              f"{ratio:>8.1f}x {error:>12.2e} {c['nfev']:>6}/{p['nfev']:<6} "
              f"{c['frame_table_nodes']:>8} {c['frame_interpolation_error']:>9.1e}")
    for engine in ("compiled", "python"):
        ratio = np.median(times[("case 2", engine)]) / np.median(times[("case 1", engine)])
        print(f"case 2 / case 1 time, {engine}: {ratio:.2f}")
    ride(quick, repeats)


def cases(repeats: int):
    """Case 2 against case 1 on the compiled engine alone (the bundled scene, rtol 1e-8)."""
    setups = {case: bundled(case) for case in (1, 2)}
    run(setups[1], "compiled", 1e-8)
    times = {case: [] for case in setups}
    for _ in range(repeats):
        for case, st in setups.items():
            times[case].append(run(st, "compiled", 1e-8)[0])
    print(f"compiled, bundled scene, rtol 1e-8: case 1 {spread(times[1])} s, case 2 {spread(times[2])} s, "
          f"case 2 / case 1 {np.median(times[2]) / np.median(times[1]):.2f}")


def ride(quick: bool, repeats: int):
    """60 s on the helix with the bundled mast at rtol 1e-6, outputs at the bundled 333 Hz (compiled)."""
    t_end = 6.0 if quick else 60.0
    st = bundled(1, t_end, int(round(t_end / 0.003)))
    times, cpu = [], []
    for _ in range(repeats):
        start = time.process_time()  # the CPU the ride needs: on a shared machine the wall time grows with the load
        seconds, out = run(st, "compiled", 1e-6)
        times.append(seconds)
        cpu.append(time.process_time() - start)
    print(f"{t_end:g} s ride, rtol 1e-6, {len(out['t'])} outputs, compiled: {spread(times)} s (CPU {spread(cpu)} s), "
          f"nfev {out['nfev']}, steps {out['steps']}, table {out['frame_table_nodes']} nodes "
          f"(error {out['frame_interpolation_error']:.1e}), "
          f"energy residual {np.abs(elastic_scene.energy_residual(out)).max():.2e} J")


def traction(quick: bool, repeats: int):
    """Compiled against Python with traction (the bundled scene, 0.3 s, case 1, rtol 1e-8)."""
    doc = copy.deepcopy(BUNDLED)
    doc["time"] = {"t_end": 0.06 if quick else 0.3, "steps": 20 if quick else 100}
    doc["effects"]["traction"] = True
    doc["motion"] = {"traction": "400 + 300*sin(3*t) - 2*v**2", "initial_speed": 5.0}
    doc["elastic"]["numerics"] = {"modal_samples": 0}
    st = pipeline.load(doc).setup.elastic
    run(st, "compiled", 1e-8)  # loads the cache (or compiles) untimed
    times, outs = {"compiled": [], "python": []}, {}
    for _ in range(repeats):
        for engine in times:
            seconds, outs[engine] = run(st, engine, 1e-8)
            times[engine].append(seconds)
    c, p = outs["compiled"], outs["python"]
    ratio = np.median(times["python"]) / np.median(times["compiled"])
    print(f"traction, {doc['time']['t_end']:g} s ({len(c['t'])} outputs), case 1, rtol 1e-8; s: median (min-max) of "
          f"{repeats} interleaved rounds")
    print(f"compiled {spread(times['compiled'])} s, python {spread(times['python'])} s, {ratio:.1f}x; "
          f"|dP|/max|P| {np.abs(c['P'] - p['P']).max() / np.abs(p['P']).max():.2e}, "
          f"|ds|/max|s| {np.abs(c['s'] - p['s']).max() / np.abs(p['s']).max():.2e}; nfev {c['nfev']}/{p['nfev']}; "
          f"table {c['frame_table_nodes']} nodes (error {c['frame_interpolation_error']:.1e})")


def cold():
    """Wall and CPU time of `symmech warm --engine elastic` into an empty numba cache."""
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        start = time.perf_counter()
        before = os.times()
        subprocess.run([sys.executable, "-m", "symmech", "warm", "--engine", "elastic", "--quiet"], env=env,
                       check=True, capture_output=True)
        after = os.times()
        cpu = (after.children_user - before.children_user) + (after.children_system - before.children_system)
        print(f"cold compile of the elastic engine: {time.perf_counter() - start:.1f} s wall, {cpu:.1f} s CPU")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--part", choices=("stiff", "engines", "cases", "ride", "traction", "cold", "all"), default="all")
    ap.add_argument("--repeats", type=int, default=None)
    args = ap.parse_args()
    repeats = args.repeats or (1 if args.quick else 5)
    if args.part in ("stiff", "all"):
        stiff(args.quick, repeats)
    if args.part in ("engines", "all"):
        engines(args.quick, repeats)
    if args.part == "cases":
        cases(repeats)
    if args.part == "ride":
        ride(args.quick, repeats)
    if args.part in ("traction", "all"):
        traction(args.quick, repeats)
    if args.part in ("cold", "all"):
        cold()


if __name__ == "__main__":
    main()
