"""Grain motion speed: compiled vs Python accurate mode, accurate vs paper mode, batch vs loop, effects off.

Every time is the median of interleaved repeats with min/max (benchmarks/timing.py);
each method's impact-time error is printed beside its time.

Run: python benchmarks/bench_grain_motion.py [--quick]   (a few minutes; --quick about one)
"""
from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from dataclasses import replace

import numpy as np

from timing import interleaved, machine, ratio

from scipy.optimize import brentq

from symmech.core import pipeline
from symmech.core.scene import SymmechError
from symmech.generated import grain_motion as gm
from symmech.grain import flight, motion, paper_mode
from symmech.grain.motion_engine import driver as compiled
from symmech.grain.coulomb_law import ImpactLaw

G = 9.81


def sphere_scene():
    """Sphere on a vertically vibrating plate near its period-1 orbit (Gamma = 1.3, e = 0.5)."""
    e, gamma, freq = 0.5, 1.3, 20.0
    w = 2 * math.pi * freq
    phi = math.acos(math.pi * (1 - e) / ((1 + e) * gamma))
    vib = flight.Vibration(gamma * G / w**2, w, phi, (0.0, 0.0, 1.0))
    law = ImpactLaw("coulomb", e_n=e, e_t=0.0, mu=0.0, check_printed=False)
    model = motion.Model((1e-3,) * 3, 1e-6, (0.0, 0.0, -G), vib, law, 0.5, motion.Effects(rotation=False))
    v0 = 1.05 * G / freq / 2 - vib.amplitude * w * math.cos(phi)
    st = motion.State(0.0, np.array([0.0, 0.0, 1e-3]), np.array([0.0, 0.0, v0]), np.array([1.0, 0, 0, 0]),
                      np.zeros(3))
    return model, st


def equal_accuracy(repeats):
    model, st = sphere_scene()
    T = model.period
    t_end = 20.5 * T
    base = motion.Numerics(scan_step=T / 40, sample_interval=T, nodes=50)
    ref = motion.simulate(model, replace(base, tolerance=1e-13), st, t_end)
    ref_times = np.array([i["t"] for i in ref.impacts])

    def err(res):
        got = np.array([i["t"] for i in res.impacts])
        if len(got) != len(ref_times):
            return math.inf
        return float(np.max(np.abs(got - ref_times)) / T)

    print("one grain, sphere bouncing 20 periods: impact-time error / T beside the time per run")
    runs = {}
    for tol in (1e-4, 1e-6, 1e-8):
        runs[f"accurate tol={tol:g}"] = lambda tol=tol: motion.simulate(model, replace(base, tolerance=tol), st, t_end)
    for steps in (200, 1000, 5000):
        num = replace(base, mode="paper", dt=T / steps)
        runs[f"paper dt=T/{steps}"] = lambda num=num: paper_mode.simulate(model, num, st, t_end)
    stats = interleaved(runs, repeats)
    errors = {label: err(run()) for label, run in runs.items()}
    for label, s in stats.items():
        print(f"  {label:<24} error {errors[label]:9.2e}  {s.text()}")
    # Equal accuracy: the cheapest accurate run at least as accurate as the most accurate paper run.
    best_paper = min((k for k in runs if k.startswith("paper")), key=errors.get)
    match = [k for k in runs if k.startswith("accurate") and errors[k] <= errors[best_paper]]
    if not match:
        print(f"no accurate run reaches the best paper error {errors[best_paper]:.1e}\n")
        return
    acc = min(match, key=lambda k: stats[k].median)
    print(f"at error <= {errors[best_paper]:.1e} (accurate {errors[acc]:.1e}): {acc} vs {best_paper}: "
          f"paper/accurate time {ratio(stats[best_paper], stats[acc])}\n")


def exact_flight_brentq(model, st, t_end, xtol):
    """Plain-Python baseline for the bouncing sphere (point mass, vertical vibration): exact parabolic flight
    of the centre, the gap scanned at T/40 and refined by scipy's brentq, normal restitution: impact times."""
    vib, e, g, radius = model.vibration, model.law.e_n, -model.g_k[2], model.axes[0]
    A, w, ph = vib.amplitude, vib.omega, vib.phase
    step = model.period / 40
    t0, z0, v0 = st.t, float(st.r[2]), float(st.v[2])
    times = []
    while True:
        va, za = v0 + A * w * math.cos(w * t0 + ph), z0 + A * math.sin(w * t0 + ph)  # absolute

        def gap(t):
            tau = t - t0
            return za + va * tau - 0.5 * g * tau * tau - A * math.sin(w * t + ph) - radius

        a, tc = t0, None
        while a < t_end:
            b = min(a + step, t_end)
            if gap(b) <= 0.0:
                tc = brentq(gap, a, b, xtol=xtol)
                break
            a = b
        if tc is None:
            return times
        v_rel = va - g * (tc - t0) - A * w * math.cos(w * tc + ph)
        t0, z0, v0 = tc, radius, -e * v_rel
        times.append(tc)


def compiled_sphere(repeats):
    """Sphere, 20 impacts: compiled accurate mode vs the Python loop vs exact flight + brentq in plain Python."""
    model, st = sphere_scene()
    T = model.period
    t_end = 20.5 * T
    base = motion.Numerics(scan_step=T / 40, sample_interval=T)
    ref = np.array([i["t"] for i in motion.simulate(model, replace(base, tolerance=1e-13), st, t_end).impacts])
    num = replace(base, tolerance=1e-10)
    runs = {"compiled accurate tol=1e-10": lambda: compiled.simulate(model, num, st, t_end),
            "compiled, impact log built": lambda: compiled.simulate(model, num, st, t_end).impacts,
            "Python accurate tol=1e-10": lambda: motion.simulate(model, num, st, t_end),
            "plain Python flight+brentq xtol=1e-12": lambda: exact_flight_brentq(model, st, t_end, 1e-12)}
    def err(out):  # out: a Motion, its impact log, or impact times
        log = out.impacts if isinstance(out, motion.Motion) else out
        got = np.array([i["t"] if isinstance(i, dict) else i for i in log])
        return float(np.max(np.abs(got - ref)) / T) if len(got) == len(ref) else math.inf

    errors = {label: err(run()) for label, run in runs.items()}  # also the warm-up (numba cache load)
    stats = interleaved(runs, repeats, number=10)
    print(f"sphere, {len(ref)} impacts in 20 periods: impact-time error / T beside the time per run")
    for label, s in stats.items():
        print(f"  {label:<40} error {errors[label]:9.2e}  {s.text('ms', 1e3)}")
    base_label = "plain Python flight+brentq xtol=1e-12"
    print(f"  compiled vs plain Python: {ratio(stats[base_label], stats['compiled accurate tol=1e-10'])} faster "
          f"({ratio(stats[base_label], stats['compiled, impact log built'])} with the impact log built); "
          f"vs the Python loop: {ratio(stats['Python accurate tol=1e-10'], stats['compiled accurate tol=1e-10'])}"
          "\n")


def compiled_ellipsoid(duration, repeats):
    """The bundled default scene (ellipsoid, throw vibration, sliding with spin): compiled vs the Python loop."""
    sc = pipeline.load("scenes/grain_default.toml").setup
    runs = {"compiled": lambda: compiled.simulate(sc.model, sc.numerics, sc.start, duration),
            "Python": lambda: motion.simulate(sc.model, sc.numerics, sc.start, duration)}
    c, p = runs["compiled"](), runs["Python"]()  # also the warm-up (numba cache load)
    stats = interleaved(runs, repeats)
    n = min(len(c.impacts), len(p.impacts))
    dt = max((abs(a["t"] - b["t"]) for a, b in zip(c.impacts[:n], p.impacts[:n])), default=0.0)
    dr = float(np.linalg.norm(c.final.r - p.final.r))
    print(f"default scene (ellipsoid), {duration:g} s: {len(c.impacts)} / {len(p.impacts)} impacts "
          f"(compiled / Python), max impact-time difference {dt:.2e} s, final position difference {dr:.2e} m")
    for label, s in stats.items():
        print(f"  {label:<10} {s.text()}")
    print(f"  Python/compiled: {ratio(stats['Python'], stats['compiled'])} (target >= 50x)\n")


def _grain(sc, k, duration):
    """Grain k of a population around the default scene: start height, velocity and spin drawn with seed k."""
    rng = np.random.default_rng(k)
    start = replace(sc.start, r=sc.start.r + np.array([0.0, 0.0, rng.uniform(0, 3e-3)]),
                    v=rng.normal(scale=0.05, size=3), w=rng.normal(scale=20, size=3))
    try:
        return compiled.simulate(sc.model, sc.numerics, start, duration)
    except SymmechError:
        return None


def compiled_population(n, duration, repeats):
    """n grains x duration on threads (the compiled loop releases the GIL): 1 vs 2 workers, 10^4 extrapolated."""
    sc = pipeline.load("scenes/grain_default.toml").setup

    def run(workers):
        with ThreadPoolExecutor(workers) as pool:
            return list(pool.map(lambda k: _grain(sc, k, duration), range(n)))

    out = run(2)
    stats = interleaved({"1 thread": lambda: run(1), "2 threads": lambda: run(2)}, repeats)
    failed = sum(r is None for r in out)
    impacts = sum(len(r.impacts) for r in out if r is not None)
    print(f"population of {n} grains x {duration:g} s (default scene, random height, velocity, spin; "
          f"{impacts} impacts, {failed} stopped by a guard):")
    for label, s in stats.items():
        per = s.median / n
        print(f"  {label:<10} {s.text()}  {per * 1e3:.1f} ms/grain -> 10^4 grains x {duration:g} s: "
              f"{per * 1e4 / 60:.1f} min")
    print(f"  1/2 threads: {ratio(stats['1 thread'], stats['2 threads'])} (target: 10^4 x 2 s < 10 min)\n")


def compile_cost(repeats, cold):
    """Fresh processes: import + first call of the compiled loop with the numba cache (and, unless quick,
    one cold run with an empty cache: the one-off compilation after an install)."""
    code = ("import time; t = time.perf_counter(); from symmech.core import pipeline; "
            "from symmech.grain.motion_engine import driver as compiled; sc = pipeline.load('scenes/grain_default.toml').setup; "
            "compiled.simulate(sc.model, sc.numerics, sc.start, 0.01); print(time.perf_counter() - t)")

    def fresh(env=None):
        return float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                                    env=env).stdout.split()[-1])

    print("compile cost: import + load + first call of the compiled loop in a fresh process")
    cached = sorted(fresh() for _ in range(repeats))
    print(f"  cached (numba cache beside the module): median {cached[len(cached) // 2]:.2f} s "
          f"(min {cached[0]:.2f}, max {cached[-1]:.2f}, n={repeats})")
    if cold:
        with tempfile.TemporaryDirectory() as cache:
            seconds = fresh({**os.environ, "NUMBA_CACHE_DIR": cache})
        print(f"  cold (empty NUMBA_CACHE_DIR, single shot: compiles everything): {seconds:.1f} s")
    print()


def batch_vs_loop(n, loop_sample, repeats):
    rng = np.random.default_rng(0)
    vib = flight.Vibration(1.0e-3, 2 * math.pi * 25, 0.0, (math.cos(0.5), 0.0, math.sin(0.5)))
    law = ImpactLaw("coulomb", e_n=0.4, e_t=-0.3, mu=0.5, check_printed=False)
    model = motion.Model((1e-3,) * 3, 1e-5, tuple(gm.gravity(G, 0.05, 0.0)), vib, law, 0.5)
    axes = rng.uniform(0.5e-3, 3e-3, (n, 3))
    mass = 1300 * 4 / 3 * math.pi * axes.prod(axis=1)
    r0 = np.column_stack([np.zeros(n), np.zeros(n), axes.max(axis=1) + rng.uniform(0, 3e-3, n)])
    v0 = rng.normal(scale=0.05, size=(n, 3))
    ang = rng.uniform(0.1, 3.0, (n, 3))
    w0 = rng.normal(scale=20, size=(n, 3))
    T = model.period
    num = motion.Numerics(mode="paper", dt=T / 200, nodes=100)
    t_end = 4 * T

    def batch():
        return paper_mode.simulate_batch(model, num, axes, mass, r0, v0, ang, w0, t_end)

    def loop():
        return sum(paper_mode.simulate_batch(model, num, axes[i:i + 1], mass[i:i + 1], r0[i:i + 1], v0[i:i + 1],
                                             ang[i:i + 1], w0[i:i + 1], t_end)[2][0]
                   for i in range(loop_sample))

    stats = interleaved({"batch": batch, "loop": loop}, repeats)
    count, loop_count = batch()[2], loop()
    per_batch, per_loop = stats["batch"].median / n, stats["loop"].median / loop_sample
    print(f"batch of {n} grains (paper mode, dt = T/200, 100 nodes, {t_end:.2f} s, {count.sum()} impacts):")
    print(f"  vectorised: {stats['batch'].text()} ({per_batch * 1e3:.3f} ms/grain)")
    print(f"  Python loop over {loop_sample} grains: {stats['loop'].text()} ({per_loop * 1e3:.2f} ms/grain, "
          f"{loop_count} impacts)")
    print(f"  per grain, loop/batch: {per_loop / per_batch:.1f}x (target >= 20x)\n")


def effects_off(duration, repeats):
    vib = flight.Vibration(1.0e-3, 2 * math.pi * 25, 0.0, (math.cos(0.5), 0.0, math.sin(0.5)))
    law = ImpactLaw("coulomb", e_n=0.4, e_t=-0.3, mu=0.5, check_printed=False)
    full = motion.Model((2e-3, 1.2e-3, 1e-3), 1.3e-5, tuple(gm.gravity(G, 0.05, 0.0)), vib, law, 0.5)
    st = motion.State(0.0, np.array([0.0, 0.0, 4e-3]), np.zeros(3), np.array([0.9, 0.3, 0.2, 0.1]) / 0.995,
                      np.array([10.0, -20.0, 5.0]))
    T = full.period
    num = motion.Numerics(tolerance=1e-9, scan_step=T / 40, sample_interval=T / 10)
    print(f"accurate mode, {duration:g} s of an ellipsoidal grain: effects switched off (the motion changes with")
    print("the physics; equal results for zeroed parameters are asserted in tests/test_grain_motion_parts.py)")
    models = {"all effects on": full}
    for name in ("rotation", "friction", "inclination", "vibration"):
        model = replace(full, effects=motion.Effects(**{name: False}))
        models[f"{name} off"] = replace(model, g_k=(0.0, 0.0, -G)) if name == "inclination" else model
    runs = {label: (lambda m=m: motion.simulate(m, num, st, duration)) for label, m in models.items()}
    stats = interleaved(runs, repeats)
    for label, s in stats.items():
        impacts = len(runs[label]().impacts)
        print(f"  {label:<16} {s.text()}  all-on/this {ratio(stats['all effects on'], s)}  ({impacts} impacts)")
    print()


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="smaller batch, shorter ellipsoid run")
    quick = p.parse_args().quick
    print(f"machine: {machine()}")
    started = time.perf_counter()
    compiled_sphere(5)
    compiled_ellipsoid(0.5 if quick else 2.0, 5)
    compiled_population(20 if quick else 100, 2.0, 5)
    compile_cost(5, cold=not quick)
    print(f"(compiled-engine sections: {time.perf_counter() - started:.0f} s)\n")
    equal_accuracy(5)
    batch_vs_loop(1000 if quick else 10_000, 20 if quick else 100, 5)
    effects_off(0.1 if quick else 1.0, 5)


if __name__ == "__main__":
    main()
