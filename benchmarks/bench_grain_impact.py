"""Grain impact benchmarks, side by side in one run, against the strongest baselines.

1. H for N configurations in one batch call: the generated numba twin (2 threads
   and 1), the generated numpy module, ``sympy.lambdify(..., cse=True)``, a
   hand-written numba loop (2 threads and 1) and hand-written numpy; the max
   relative difference to the generated numpy module beside each.
2. One call on Python floats (the event loop's case): the numba scalar twin,
   a plain ``math`` transcription, lambdify(cse=True) on ``math``, and the
   numpy module.
3. Impact solves per second: the robust batch solver vs scipy.optimize.root
   per impact, residual of (19) beside each.
4. ``symmech codegen``: full (fresh folder) and with nothing changed.

Every figure is the median of interleaved repeats with min and max.
Usage: python benchmarks/bench_grain_impact.py [--quick]
"""
import argparse
import subprocess
import sys
import tempfile
from math import cos, sin, sqrt

import numba
import numpy as np
import sympy

from timing import interleaved, machine, ratio

from symmech.numerics import kernels
from symmech.generated import grain_impact as g
from symmech.grain import derive
from symmech.grain.impact import residual_19, solve_robust_batch, solve_scipy

NB = kernels.load("grain_impact")


def configurations(n, seed=0):
    """Semi-axes log-uniform in [0.1, 3] mm, orientation uniform on SO(3)."""
    rng = np.random.default_rng(seed)
    axes = np.exp(rng.uniform(np.log(1e-4), np.log(3e-3), (n, 3)))
    angles = np.column_stack([rng.uniform(-np.pi, np.pi, n), np.arccos(rng.uniform(-1, 1, n)),
                              rng.uniform(-np.pi, np.pi, n)])
    return axes, angles


def H_math(a, b, c, psi, theta, phi):
    """H = E - [R]x P^-1 [R]x by hand, unrolled on floats: row-major 9-tuple.

    Q from z-x-z angles, R = Q r with r the support point of the ellipsoid for
    the surface normal, P^-1 = Q diag(5/(b²+c²), ...) Qᵀ (unit mass).
    """
    cps, sps, cth, sth, cph, sph = cos(psi), sin(psi), cos(theta), sin(theta), cos(phi), sin(phi)
    q00, q01, q02 = cps * cph - sps * cth * sph, -cps * sph - sps * cth * cph, sps * sth
    q10, q11, q12 = sps * cph + cps * cth * sph, -sps * sph + cps * cth * cph, -cps * sth
    q20, q21, q22 = sth * sph, sth * cph, cth
    a2, b2, c2 = a * a, b * b, c * c
    s = -1.0 / sqrt(a2 * q20 * q20 + b2 * q21 * q21 + c2 * q22 * q22)
    r0, r1, r2 = a2 * q20 * s, b2 * q21 * s, c2 * q22 * s
    x = q00 * r0 + q01 * r1 + q02 * r2
    y = q10 * r0 + q11 * r1 + q12 * r2
    z = q20 * r0 + q21 * r1 + q22 * r2
    i0, i1, i2 = 5.0 / (b2 + c2), 5.0 / (a2 + c2), 5.0 / (a2 + b2)
    p00 = i0 * q00 * q00 + i1 * q01 * q01 + i2 * q02 * q02
    p01 = i0 * q00 * q10 + i1 * q01 * q11 + i2 * q02 * q12
    p02 = i0 * q00 * q20 + i1 * q01 * q21 + i2 * q02 * q22
    p11 = i0 * q10 * q10 + i1 * q11 * q11 + i2 * q12 * q12
    p12 = i0 * q10 * q20 + i1 * q11 * q21 + i2 * q12 * q22
    p22 = i0 * q20 * q20 + i1 * q21 * q21 + i2 * q22 * q22
    # T = P^-1 [R]x, then H = E - [R]x T
    t00, t01, t02 = p01 * z - p02 * y, p02 * x - p00 * z, p00 * y - p01 * x
    t10, t11, t12 = p11 * z - p12 * y, p12 * x - p01 * z, p01 * y - p11 * x
    t20, t21, t22 = p12 * z - p22 * y, p22 * x - p02 * z, p02 * y - p12 * x
    return (1.0 + z * t10 - y * t20, z * t11 - y * t21, z * t12 - y * t22,
            x * t20 - z * t00, 1.0 + x * t21 - z * t01, x * t22 - z * t02,
            y * t00 - x * t10, y * t01 - x * t11, 1.0 + y * t02 - x * t12)


_H_math_nb = numba.njit(H_math)


@numba.njit(parallel=True)
def hand_numba_loop(a, b, c, psi, theta, phi, out):
    """The same hand transcription as a numba prange loop."""
    for k in numba.prange(a.shape[0]):
        h = _H_math_nb(a[k], b[k], c[k], psi[k], theta[k], phi[k])
        for i in range(9):
            out[k, i // 3, i % 3] = h[i]


def hand_numpy_H(axes, angles):
    """Plain numpy: Q from elementary rotations, support point, H = E - [R]x P^-1 [R]x."""
    psi, theta, phi = angles.T
    cps, sps, cth, sth, cph, sph = np.cos(psi), np.sin(psi), np.cos(theta), np.sin(theta), np.cos(phi), np.sin(phi)
    Q = np.empty((len(axes), 3, 3))
    Q[:, 0] = np.column_stack([cps * cph - sps * cth * sph, -cps * sph - sps * cth * cph, sps * sth])
    Q[:, 1] = np.column_stack([sps * cph + cps * cth * sph, -sps * sph + cps * cth * cph, -cps * sth])
    Q[:, 2] = np.column_stack([sth * sph, sth * cph, cth])
    D2 = axes**2
    n_body = Q[:, 2, :]
    R = np.einsum("nij,nj->ni", Q, -D2 * n_body / np.sqrt(np.sum(D2 * n_body**2, axis=1))[:, None])
    a2, b2, c2 = D2.T
    inv_P = np.einsum("nij,nj,nkj->nik", Q, 5.0 / np.column_stack([b2 + c2, a2 + c2, a2 + b2]), Q)
    S = np.zeros((len(axes), 3, 3))
    S[:, 0, 1], S[:, 0, 2], S[:, 1, 2] = -R[:, 2], R[:, 1], -R[:, 0]
    S[:, 1, 0], S[:, 2, 0], S[:, 2, 1] = R[:, 2], -R[:, 1], R[:, 0]
    return np.eye(3) - S @ inv_P @ S


def rel_error(H, reference):
    return np.max(np.abs(H - reference).max(axis=(-2, -1)) / np.abs(reference).max(axis=(-2, -1)))


def with_threads(n, fn):
    def run():
        numba.set_num_threads(n)
        return fn()
    return run


def bench_H(n, repeats):
    axes, angles = configurations(n)
    args = tuple(np.ascontiguousarray(x) for x in (*axes.T, *angles.T))
    symbols = [derive.a, derive.b, derive.c, derive.psi, derive.theta, derive.phi]
    lambdified = sympy.lambdify(symbols, derive.reduction_tensor(), "numpy", cse=True)
    out = np.empty((n, 3, 3))
    NB.H(*(x[:10] for x in args))  # compile (or load from cache) outside the timing
    hand_numba_loop(*(x[:10] for x in args), out[:10])
    threads = numba.config.NUMBA_NUM_THREADS
    contenders = {
        f"generated numba, {threads} threads": with_threads(threads, lambda: NB.H(*args)),
        "generated numba, 1 thread": with_threads(1, lambda: NB.H(*args)),
        f"hand-written numba loop, {threads} thr": with_threads(threads, lambda: hand_numba_loop(*args, out)),
        "hand-written numba loop, 1 thread": with_threads(1, lambda: hand_numba_loop(*args, out)),
        "generated numpy": lambda: g.H(*args),
        "lambdify(cse=True)": lambda: lambdified(*args),
        "hand-written numpy": lambda: hand_numpy_H(axes, angles),
    }
    stats = interleaved(contenders, repeats)
    numba.set_num_threads(threads)
    reference = g.H(*args)
    errors = {
        f"generated numba, {threads} threads": rel_error(NB.H(*args), reference),
        "generated numba, 1 thread": rel_error(NB.H(*args), reference),
        f"hand-written numba loop, {threads} thr": (hand_numba_loop(*args, out), rel_error(out, reference))[1],
        "hand-written numba loop, 1 thread": rel_error(out, reference),
        "generated numpy": 0.0,
        "lambdify(cse=True)": rel_error(np.moveaxis(np.asarray(lambdified(*args)), -1, 0), reference),
        "hand-written numpy": rel_error(hand_numpy_H(axes, angles), reference),
    }
    base = stats["lambdify(cse=True)"]
    print(f"\n[1] H for {n:.0e} configurations, one batch call (max rel. diff to generated numpy)")
    for name, s in stats.items():
        print(f"    {name:38s} {s.text()}  lambdify/this {ratio(base, s)}  diff {errors[name]:.1e}")
    print(f"    targets: compiled >= 5x lambdify(cse=True) on {threads} cores, >= 3x on one")


def bench_scalar(repeats):
    axes, angles = configurations(1, seed=3)
    args = tuple(float(x) for x in (*axes[0], *angles[0]))
    symbols = [derive.a, derive.b, derive.c, derive.psi, derive.theta, derive.phi]
    lambdified = sympy.lambdify(symbols, derive.reduction_tensor().tolist(), "math", cse=True)
    NB.H_scalar(*args)
    assert np.abs(np.array(H_math(*args)).reshape(3, 3) - g.H(*args)).max() < 1e-12
    stats = interleaved({
        "numba scalar twin H_scalar": lambda: NB.H_scalar(*args),
        "plain math transcription": lambda: H_math(*args),
        "lambdify(cse=True, 'math')": lambda: lambdified(*args),
        "generated numpy on floats": lambda: g.H(*args),
    }, repeats, number=2000)
    base = stats["plain math transcription"]
    print("\n[2] one H call on Python floats (the event loop's case)")
    for name, s in stats.items():
        print(f"    {name:30s} {s.text('us', 1e6)}  this/plain math {ratio(s, base)}")
    print("    target: scalar call <= 2x a plain math transcription")


def bench_solvers(n, n_scipy, repeats):
    axes, angles = configurations(n, seed=1)
    rng = np.random.default_rng(2)
    u = rng.normal(size=(n, 3))
    u[:, 2] = -np.abs(u[:, 2]) - 1e-3
    e, lam, m = rng.uniform(0, 1, n), rng.uniform(0, 1, n), 1e-5
    H = g.H(*axes.T, *angles.T)

    def scipy_loop():
        return [solve_scipy(H[i], m, e[i], lam[i], u[i])[:2] for i in range(n_scipy)]

    stats = interleaved({"robust batch": lambda: solve_robust_batch(H, m, e, lam, u), "scipy loop": scipy_loop},
                        repeats)
    batch = solve_robust_batch(H, m, e, lam, u)
    res_scipy = np.array([residual_19(H[i], m, e[i], lam[i], u[i], T, mu) for i, (T, mu) in enumerate(scipy_loop())])
    per_robust = stats["robust batch"].median / n
    per_scipy = stats["scipy loop"].median / n_scipy
    print("\n[3] impact solves, printed law, random grains (relative residual of (19))")
    print(f"    robust batch of {n:.0e}       {1 / per_robust:12.0f} impacts/s  {stats['robust batch'].text()}  "
          f"residual max {np.max(batch.residual):.1e}")
    print(f"    scipy.optimize.root x {n_scipy:<5d} {1 / per_scipy:12.0f} impacts/s  {stats['scipy loop'].text()}  "
          f"residual max {np.max(res_scipy):.1e}   per impact: scipy/robust {per_scipy / per_robust:.0f}x")


def bench_codegen(repeats, fresh_repeats):
    def codegen(*flags):
        return lambda: subprocess.run([sys.executable, "-m", "symmech", "codegen", *flags], check=True,
                                      capture_output=True)

    stats = interleaved({
        "codegen --check, nothing changed": codegen("--check"),
        "codegen, nothing changed": codegen(),
        "python -c 'import sympy' (floor)": lambda: subprocess.run([sys.executable, "-c", "import sympy"], check=True),
    }, repeats)
    with tempfile.TemporaryDirectory() as tmp:
        stats |= interleaved({"codegen into a fresh folder": lambda: codegen("--dir", tempfile.mkdtemp(dir=tmp))()},
                             fresh_repeats)
    print("\n[4] `symmech codegen` (fresh process each)")
    for name, s in stats.items():
        print(f"    {name:34s} {s.text()}")
    print("    target: no-change codegen and --check under 2 s")


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="smaller batches, fewer solver and codegen runs")
    quick = p.parse_args().quick
    print(f"machine: {machine()}")
    bench_H(10**5 if quick else 10**6, 5 if quick else 7)
    bench_scalar(5 if quick else 9)
    bench_solvers(10**4 if quick else 10**5, 100 if quick else 1000, 5)
    bench_codegen(5, 1 if quick else 5)


if __name__ == "__main__":
    main()
