"""Grain impact benchmarks, measured side by side in one run.

1. H for 10^6 configurations in one batch call: generated module vs naive
   sympy.lambdify of the unsimplified expressions vs hand-written numpy.
2. Impact solves per second (batch of 10^5): robust batch solver vs the paper's
   descent (as printed, and corrected) vs scipy.optimize.root per impact, with
   the residual of (19) each reaches.
3. Wall time of a full `symmech codegen`.

Usage: python benchmarks/bench_grain_impact.py [--quick]
"""
import argparse
import subprocess
import sys
import tempfile
import time

import numpy as np
import sympy

from symmech.generated import grain_impact as g
from symmech.grain import derive
from symmech.grain.impact import DescentOptions, residual_19, solve_descent_batch, solve_robust_batch, solve_scipy


def timed(fn, repeats=3):
    best, out = np.inf, None
    for _ in range(repeats):
        start = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - start)
    return best, out


def configurations(n, seed=0):
    rng = np.random.default_rng(seed)
    axes = np.exp(rng.uniform(np.log(1e-4), np.log(3e-3), (n, 3)))
    angles = np.column_stack([rng.uniform(-np.pi, np.pi, n), np.arccos(rng.uniform(-1, 1, n)),
                              rng.uniform(-np.pi, np.pi, n)])
    return axes, angles


def hand_written_H(axes, angles):
    """Plain numpy: Q from elementary rotations, support point, H = E - [R]x P^-1 [R]x."""
    psi, theta, phi = angles.T
    cps, sps, cth, sth, cph, sph = np.cos(psi), np.sin(psi), np.cos(theta), np.sin(theta), np.cos(phi), np.sin(phi)
    Q = np.empty((len(axes), 3, 3))
    Q[:, 0, 0] = cps * cph - sps * cth * sph
    Q[:, 0, 1] = -cps * sph - sps * cth * cph
    Q[:, 0, 2] = sps * sth
    Q[:, 1, 0] = sps * cph + cps * cth * sph
    Q[:, 1, 1] = -sps * sph + cps * cth * cph
    Q[:, 1, 2] = -cps * sth
    Q[:, 2, 0] = sth * sph
    Q[:, 2, 1] = sth * cph
    Q[:, 2, 2] = cth
    D2 = axes**2
    n_body = Q[:, 2, :]
    R = np.einsum("nij,nj->ni", Q, -D2 * n_body / np.sqrt(np.sum(D2 * n_body**2, axis=1))[:, None])
    a2, b2, c2 = D2.T
    inv_rho2 = 5.0 / np.column_stack([b2 + c2, a2 + c2, a2 + b2])
    inv_P = np.einsum("nij,nj,nkj->nik", Q, inv_rho2, Q)
    S = np.zeros((len(axes), 3, 3))
    S[:, 0, 1], S[:, 0, 2], S[:, 1, 2] = -R[:, 2], R[:, 1], -R[:, 0]
    S[:, 1, 0], S[:, 2, 0], S[:, 2, 1] = R[:, 2], -R[:, 1], R[:, 0]
    return np.eye(3) - S @ inv_P @ S


def bench_H(n):
    axes, angles = configurations(n)
    args = (*axes.T, *angles.T)
    naive = sympy.lambdify([derive.a, derive.b, derive.c, derive.psi, derive.theta, derive.phi],
                           derive.reduction_tensor(), "numpy", cse=False)
    t_gen, H = timed(lambda: g.H(*args))
    t_naive, H_naive = timed(lambda: naive(*args), repeats=1)
    t_hand, H_hand = timed(lambda: hand_written_H(axes, angles))
    H_naive = np.moveaxis(np.array(H_naive, dtype=float), -1, 0)
    print(f"\n[1] H for {n:.0e} configurations in one batch call")
    print(f"    generated module      {t_gen:8.3f} s")
    print(f"    naive lambdify        {t_naive:8.3f} s   ratio naive/generated = {t_naive / t_gen:6.1f}x")
    print(f"    hand-written numpy    {t_hand:8.3f} s   ratio hand/generated  = {t_hand / t_gen:6.1f}x")
    scale = np.abs(H_hand).max(axis=(1, 2))
    print(f"    max rel diff generated vs hand {np.max(np.abs(H - H_hand).max(axis=(1, 2)) / scale):.1e},"
          f" vs naive {np.max(np.abs(H - H_naive).max(axis=(1, 2)) / scale):.1e}")


def bench_solvers(n, n_scipy, n_descent):
    axes, angles = configurations(n, seed=1)
    rng = np.random.default_rng(2)
    u = rng.normal(size=(n, 3))
    u[:, 2] = -np.abs(u[:, 2]) - 1e-3
    e, lam, m = rng.uniform(0, 1, n), rng.uniform(0, 1, n), 1e-5
    H = g.H(*axes.T, *angles.T)
    print(f"\n[2] impact solves, printed law, random grains (residual of (19), relative)")
    t_robust, batch = timed(lambda: solve_robust_batch(H, m, e, lam, u))
    rate_robust = n / t_robust
    print(f"    robust batch ({n:.0e})         {rate_robust:12.0f} impacts/s   residual median "
          f"{np.median(batch.residual):.1e} max {np.max(batch.residual):.1e}")
    k = slice(0, n_scipy)
    start = time.perf_counter()
    res = []
    for i in range(n_scipy):
        T, mu, _, _ = solve_scipy(H[i], m, e[i], lam[i], u[i])
        res.append(residual_19(H[i], m, e[i], lam[i], u[i], T, mu))
    rate_scipy = n_scipy / (time.perf_counter() - start)
    res = np.array(res)
    print(f"    scipy.optimize.root ({n_scipy} of them) {rate_scipy:12.0f} impacts/s   residual median "
          f"{np.median(res):.1e} max {np.max(res):.1e}   robust is {rate_robust / rate_scipy:.0f}x faster")
    print(f"    robust residual on the same {n_scipy}: max {np.max(batch.residual[k]):.1e}")
    k = slice(0, n_descent)
    for variant, steps in (("paper", 1000), ("paper-corrected", 100), ("paper-corrected", 1000)):
        start = time.perf_counter()
        T, mu, done, _ = solve_descent_batch(H[k], m, e[k], lam[k], u[k], variant,
                                             DescentOptions(max_steps=steps, line_iterations=40))
        rate = n_descent / (time.perf_counter() - start)
        r = residual_19(H[k], m, e[k], lam[k], u[k], T, mu)
        print(f"    descent {variant:15s} S={steps:<5d} ({n_descent}) {rate:10.0f} impacts/s   residual median "
              f"{np.nanmedian(r):.1e} max {np.nanmax(r):.1e}")


def bench_codegen():
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "symmech", "codegen", "--dir", tmp], check=True,
                       capture_output=True)
        print(f"\n[3] full `symmech codegen` (fresh process): {time.perf_counter() - start:.1f} s")


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="smaller batches")
    quick = p.parse_args().quick
    bench_H(10**5 if quick else 10**6)
    bench_solvers(10**4 if quick else 10**5, 200 if quick else 2000, 1000 if quick else 2000)
    bench_codegen()


if __name__ == "__main__":
    main()
