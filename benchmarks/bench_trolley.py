"""Trolley speed, measured side by side in one run (ratios, not absolute times).

1. The paper's helix example end to end (5000 steps, cases 1 and 2), both conventions.
2. 10^6 track points (10^5 with --quick) in one batch call: angles θ, dθ/ds,
   d²θ/ds², V0, V̇0 -> reactions P0…P5 through the fused generated function
   ``reactions_along_track`` (numpy and numba), the chain of five generated functions
   glued with numpy (numpy modules and their numba twins), through ``sympy.lambdify`` of the composed expressions
   with ``cse=True`` (the strongest lambdify) and without, and hand-written numpy.

Medians of interleaved repeats with min/max (benchmarks/timing.py).
Usage: python benchmarks/bench_trolley.py [--quick]
"""
from __future__ import annotations

import argparse
import copy
import tempfile
from pathlib import Path

import numpy as np
import sympy as sp

from timing import interleaved, machine, ratio

from symmech.core import pipeline
from symmech.numerics import kernels
from symmech.core.context import Context
from symmech.generated import trolley_dynamics
from symmech.generated import trolley_frame
from symmech.trolley import derive, scene, tables

BODY = dict(m=100.0, r=(1.0, 0.5, 0.2), inertia=(10.0, 20.0, 30.0, 1.0, 2.0, 3.0), g0=9.81, l=2.0, ah=1.0)


def generated(th, dth, ddth, v0, dv0, frm=trolley_frame, dyn=trolley_dynamics):
    lam = frm.Lambda(*th)
    W = frm.omega_per_length(*th, *dth)
    dW = frm.omega_per_length_rate(*th, *dth, *ddth)
    zero, one = np.zeros_like(v0), np.ones_like(v0)
    c = dyn.point_coefficients(one, zero, zero, zero, zero, zero, *W.T, *dW.T, *BODY["r"])
    a = dv0[:, None] * c[:, :3] + (v0**2)[:, None] * c[:, 3:]
    w = v0[:, None] * W
    dw = dv0[:, None] * W + (v0**2)[:, None] * dW
    return dyn.reactions(BODY["m"], *BODY["r"], *BODY["inertia"], *a.T, *w.T, *dw.T, *lam[:, :, 1].T,
                         BODY["g0"], BODY["l"], BODY["ah"])


def composed_expressions(cse):
    """P0…P5 as one unsimplified sympy expression of θ, θ', θ'', V0, V̇0, lambdified."""
    v0, dv0 = sp.symbols("V0 dV0", real=True)
    omega, omega_rate = (nm.matrix for nm in derive.omega_functions())
    coef = derive.point_coefficients()
    W = sp.symbols("W1 W2 W3", real=True)
    dW = sp.symbols("dW1 dW2 dW3", real=True)
    r = sp.symbols("r1 r2 r3", real=True)
    e = sp.symbols("e1 e2 e3", real=True)
    de = sp.symbols("de1 de2 de3", real=True)
    subs = {**dict(zip(W, omega)), **dict(zip(dW, omega_rate)), **dict(zip(r, BODY["r"])),
            **dict(zip(e, (1, 0, 0))), **dict(zip(de, (0, 0, 0)))}
    c = coef.matrix.subs(subs)
    a = dv0 * c[:3, :] + v0**2 * c[3:, :]
    rx = derive.reactions(True)
    lam = derive.rotation_matrix()
    names = {s.name: s for s in rx.matrix.free_symbols}
    values = {"m": BODY["m"], "g0": BODY["g0"], "l": BODY["l"], "ah": BODY["ah"]}
    values.update({f"r{i + 1}": BODY["r"][i] for i in range(3)})
    values.update(dict(zip(("I11", "I22", "I33", "I12", "I23", "I13"), BODY["inertia"])))
    for i in range(3):
        values[f"acc{i + 1}"] = a[i]
        values[f"w{i + 1}"] = v0 * omega[i]
        values[f"dw{i + 1}"] = dv0 * omega[i] + v0**2 * omega_rate[i]
        values[f"nu{i + 1}"] = lam[i, 1]
    expr = rx.matrix.subs({names[k]: v for k, v in values.items() if k in names})
    args = list(derive.THETA + derive.DTHETA + derive.DDTHETA) + [v0, dv0]
    return sp.lambdify(args, list(expr), modules="numpy", cse=cse)


def hand_numpy(th, dth, ddth, v0, dv0):
    """The same chain written directly with numpy arrays."""
    (t1, _, t3), (d1, d2, d3), (dd1, dd2, dd3) = th, dth, ddth
    s1, s3, c1, c3 = np.sin(t1), np.sin(t3), np.cos(t1), np.cos(t3)
    W = np.stack([d1 + s3 * d2, c1 * c3 * d2 + s1 * d3, -s1 * c3 * d2 + c1 * d3], axis=1)
    dW = np.stack([dd1 + s3 * dd2 + c3 * d3 * d2,
                   c1 * c3 * dd2 + s1 * dd3 - s1 * c3 * d1 * d2 - c1 * s3 * d3 * d2 + c1 * d1 * d3,
                   -s1 * c3 * dd2 + c1 * dd3 - c1 * c3 * d1 * d2 + s1 * s3 * d3 * d2 - s1 * d1 * d3], axis=1)
    r = np.array(BODY["r"])
    e1 = np.array([1.0, 0.0, 0.0])
    alpha = e1 + np.cross(W, r)
    beta = np.cross(W, e1) + np.cross(dW, r) + np.cross(W, np.cross(W, r))
    a = dv0[:, None] * alpha + (v0**2)[:, None] * beta
    w = v0[:, None] * W
    dw = dv0[:, None] * W + (v0**2)[:, None] * dW
    nu = np.stack([s3, c1 * c3, -s1 * c3], axis=1)
    i11, i22, i33, i12, i23, i13 = BODY["inertia"]
    icm = np.array([[i11, i12, i13], [i12, i22, i23], [i13, i23, i33]])
    m, g0, l, ah = BODY["m"], BODY["g0"], BODY["l"], BODY["ah"]
    F = m * (a + g0 * nu)
    M = np.cross(r, F) + dw @ icm + np.cross(w, w @ icm)
    p5 = -M[:, 1] / l
    p3 = M[:, 2] / l
    p1 = (F[:, 1] - p3 + M[:, 0] / ah) / 2  # B at x3 = -a: M1 = a (P1 - P2)
    p2 = (F[:, 1] - p3 - M[:, 0] / ah) / 2
    return np.stack([F[:, 0], p1, p2, p3, F[:, 2] - p5, p5], axis=1)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="10^5 track points, fewer repeats")
    quick = p.parse_args().quick
    repeats = 5 if quick else 7
    print(f"machine: {machine()}")
    for conventions in ("paper", "physics"):
        data = copy.deepcopy(tables.PAPER_EXAMPLE)
        data["conventions"] = conventions
        setup = pipeline.load(copy.deepcopy(data)).setup
        with tempfile.TemporaryDirectory() as tmp:
            stats = interleaved({
                "computation": lambda: scene.compute(setup),
                "whole run": lambda: pipeline.run_to(copy.deepcopy(data), Path(tmp) / "out", Context(quiet=True)),
            }, repeats)
        print(f"paper example, 5000 steps, cases 1+2, conventions={conventions}: computation "
              f"{stats['computation'].text()}; whole run with validation, CSV and plots {stats['whole run'].text()}")

    n = 10**5 if quick else 10**6
    rng = np.random.default_rng(1)
    th = rng.uniform(-1.2, 1.2, (3, n))
    dth, ddth = rng.normal(size=(2, 3, n)) * 0.1
    v0, dv0 = rng.uniform(0, 50, n), rng.normal(size=n)
    lambdified = {cse: composed_expressions(cse) for cse in (True, False)}
    compiled = {"frm": kernels.load("trolley_frame"), "dyn": kernels.load("trolley_dynamics")}
    params = (BODY["m"], *BODY["r"], *BODY["inertia"], BODY["g0"], BODY["l"], BODY["ah"])
    contenders = {
        "fused numba": lambda: compiled["dyn"].reactions_along_track(*th, *dth, *ddth, v0, dv0, *params),
        "fused numpy": lambda: trolley_dynamics.reactions_along_track(*th, *dth, *ddth, v0, dv0, *params),
        "generated numba": lambda: generated(th, dth, ddth, v0, dv0, **compiled),
        "generated numpy": lambda: generated(th, dth, ddth, v0, dv0),
        "lambdify(cse=True)": lambda: np.stack(lambdified[True](*th, *dth, *ddth, v0, dv0), axis=1),
        "lambdify(cse=False)": lambda: np.stack(lambdified[False](*th, *dth, *ddth, v0, dv0), axis=1),
        "hand-written numpy": lambda: hand_numpy(th, dth, ddth, v0, dv0),
    }
    ref = generated(th, dth, ddth, v0, dv0)
    scale = np.abs(ref).max()
    errors = {}
    for name, fn in contenders.items():  # also compiles the numba kernels outside the timing
        errors[name] = float(np.abs(fn() - ref).max() / scale)
        assert errors[name] < 1e-8, (name, errors[name])
    stats = interleaved(contenders, repeats)
    print(f"{n:.0e} track points -> reactions, one batch call")
    for name, st in stats.items():
        print(f"    {name:22s} {st.text()}  lambdify(cse=True)/this {ratio(stats['lambdify(cse=True)'], st)}  "
              f"max |P - chain| / max |P| {errors[name]:.1e}")


if __name__ == "__main__":
    main()
