"""Grain motion speed: accurate vs paper mode at equal accuracy, batch vs loop, effects switched off.

Run: python benchmarks/bench_grain_motion.py   (prints side-by-side ratios; about a minute)
"""
from __future__ import annotations

import math
import time
from dataclasses import replace

import numpy as np

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


def timed(fn):
    start = time.perf_counter()
    out = fn()
    return time.perf_counter() - start, out


def equal_accuracy():
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

    print("one grain, sphere bouncing 20 periods: impact-time error / T vs impacts per second")
    print(f"{'method':<34}{'error':>10}{'impacts/s':>12}")
    rows = []
    for tol in (1e-4, 1e-6, 1e-8):
        sec, res = timed(lambda: motion.simulate(model, replace(base, tolerance=tol), st, t_end))
        rows.append(("accurate", tol, err(res), len(res.impacts) / sec))
    for steps in (200, 1000, 5000):
        num = replace(base, mode="paper", dt=T / steps)
        sec, res = timed(lambda: paper_mode.simulate(model, num, st, t_end))
        rows.append(("paper", steps, err(res), len(res.impacts) / sec))
    for kind, knob, e, rate in rows:
        label = f"accurate tol={knob:g}" if kind == "accurate" else f"paper dt=T/{knob}"
        print(f"{label:<34}{e:>10.2e}{rate:>12.1f}")
    # Equal accuracy: the cheapest accurate run that is at least as accurate as the best paper run.
    best_paper = min((r for r in rows if r[0] == "paper"), key=lambda r: r[2])
    match = [r for r in rows if r[0] == "accurate" and r[2] <= best_paper[2]]
    acc = max(match, key=lambda r: r[3])
    print(f"at error <= {best_paper[2]:.1e}: accurate {acc[3]:.1f} impacts/s vs paper {best_paper[3]:.1f} "
          f"impacts/s -> ratio {acc[3] / best_paper[3]:.1f}x\n")


def batch_vs_loop(n=10_000, loop_sample=100):
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
    sec_batch, (_, _, count, _) = timed(lambda: paper_mode.simulate_batch(model, num, axes, mass, r0, v0, ang, w0,
                                                                          t_end))
    k = slice(0, loop_sample)

    def loop():
        return sum(paper_mode.simulate_batch(model, num, axes[i:i + 1], mass[i:i + 1], r0[i:i + 1], v0[i:i + 1],
                                             ang[i:i + 1], w0[i:i + 1], t_end)[2][0]
                   for i in range(k.start, k.stop))
    sec_loop, loop_count = timed(loop)
    per_grain_loop = sec_loop / loop_sample
    print(f"batch of {n} grains (paper mode, dt = T/200, 100 nodes, {t_end:.2f} s, {count.sum()} impacts):")
    print(f"  vectorised: {sec_batch:.2f} s ({sec_batch / n * 1e3:.3f} ms/grain)")
    print(f"  Python loop over grains: {per_grain_loop * 1e3:.2f} ms/grain (timed on {loop_sample}, "
          f"{loop_count} impacts; {per_grain_loop * n:.0f} s extrapolated)")
    print(f"  speed-up: {per_grain_loop * n / sec_batch:.1f}x (target >= 20x)\n")


def effects_off():
    vib = flight.Vibration(1.0e-3, 2 * math.pi * 25, 0.0, (math.cos(0.5), 0.0, math.sin(0.5)))
    law = ImpactLaw("coulomb", e_n=0.4, e_t=-0.3, mu=0.5, check_printed=False)
    full = motion.Model((2e-3, 1.2e-3, 1e-3), 1.3e-5, tuple(gm.gravity(G, 0.05, 0.0)), vib, law, 0.5)
    st = motion.State(0.0, np.array([0.0, 0.0, 4e-3]), np.zeros(3), np.array([0.9, 0.3, 0.2, 0.1]) / 0.995,
                      np.array([10.0, -20.0, 5.0]))
    T = full.period
    num = motion.Numerics(tolerance=1e-9, scan_step=T / 40, sample_interval=T / 10)
    print("accurate mode, 1 s of an ellipsoidal grain: effects switched off (the motion changes with the")
    print("physics; equal results for zeroed parameters are asserted in tests/test_grain_motion_parts.py)")
    base, res = timed(lambda: motion.simulate(full, num, st, 1.0))
    print(f"  {'all effects on':<22}{base:8.2f} s                     ({len(res.impacts)} impacts)")
    for name in ("rotation", "friction", "inclination", "vibration"):
        model = replace(full, effects=motion.Effects(**{name: False}))
        if name == "inclination":
            model = replace(model, g_k=(0.0, 0.0, -G))
        sec, res = timed(lambda: motion.simulate(model, num, st, 1.0))
        print(f"  {name + ' off':<22}{sec:8.2f} s   speed-up {base / sec:.2f}x   ({len(res.impacts)} impacts)")
    print()


if __name__ == "__main__":
    equal_accuracy()
    batch_vs_loop()
    effects_off()
