"""Grain motion speed: accurate vs paper mode at equal accuracy, batch vs loop, effects switched off.

Every time is the median of interleaved repeats with min/max (benchmarks/timing.py);
each method's impact-time error is printed beside its time.

Run: python benchmarks/bench_grain_motion.py [--quick]   (a few minutes; --quick about one)
"""
from __future__ import annotations

import argparse
import math
from dataclasses import replace

import numpy as np

from timing import interleaved, machine, ratio

from symmech.generated import grain_motion as gm
from symmech.grain import flight, motion, paper_mode
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
    equal_accuracy(5)
    batch_vs_loop(1000 if quick else 10_000, 20 if quick else 100, 5)
    effects_off(0.1 if quick else 1.0, 5)


if __name__ == "__main__":
    main()
