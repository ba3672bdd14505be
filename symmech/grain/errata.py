"""Seed 000, eqs (3)-(60): printed formulas against the derivation, at seeded random points."""
from __future__ import annotations

import numpy as np

from symmech.core.errata import Check, NotCompared
from symmech.generated import grain_impact as gen
from symmech.generated import grain_impact_printed as printed
from symmech.grain import SEED

ROLE = "errata"  # found by symmech.core.discovery


def _geometry(rng, n):
    axes = np.exp(rng.uniform(np.log(2e-4), np.log(2e-3), (n, 3)))
    return {"a": axes[:, 0], "b": axes[:, 1], "c": axes[:, 2],
            "psi": rng.uniform(-np.pi, np.pi, n), "theta": np.arccos(rng.uniform(-1, 1, n)),
            "phi": rng.uniform(-np.pi, np.pi, n)}


def _geo(x):
    return x["a"], x["b"], x["c"], x["psi"], x["theta"], x["phi"]


def _impact_point(rng, n):
    """Geometry, impact state and a trial point (T_x, T_z, mu) of the descent."""
    x = _geometry(rng, n)
    x.update(m=np.exp(rng.uniform(np.log(1e-6), np.log(1e-4), n)), lam=rng.uniform(0, 1, n),
             e=rng.uniform(0, 1, n), ux0=rng.normal(size=n), uy0=rng.normal(size=n),
             uz0=-np.abs(rng.normal(size=n)))
    scale = x["m"]
    x.update(Tx=scale * rng.normal(size=n), Tz=scale * np.abs(rng.normal(size=n)),
             mu=rng.uniform(-1.4, 1.4, n))
    return x


def _descent_args(x):
    H = gen.H(*_geo(x))
    h = (H[:, 0, 0], H[:, 0, 1], H[:, 0, 2], H[:, 1, 1], H[:, 1, 2], H[:, 2, 2])
    return (x["Tx"], x["Tz"], x["mu"], *h, x["m"], x["lam"], x["e"], x["ux0"], x["uy0"], x["uz0"])


def _euler_system_point(rng, n):
    x = {"Jx": rng.uniform(1e-12, 1e-10, n), "Jy": rng.uniform(1e-12, 1e-10, n),
         "Jz": rng.uniform(1e-12, 1e-10, n), "theta": np.arccos(rng.uniform(-1, 1, n)),
         "phi": rng.uniform(-np.pi, np.pi, n)}
    for k in ("Rx", "Ry", "Rz"):
        x[k] = rng.normal(scale=1e-3, size=n)
    for k in ("Tx", "Ty", "Tz"):
        x[k] = rng.normal(scale=1e-6, size=n)
    for k in ("dtheta", "dpsi", "dphi"):
        x[k] = rng.normal(scale=10.0, size=n)
    return x


def _system(module, x):
    return module.euler_rate_system(x["Jx"], x["Jy"], x["Jz"], x["theta"], x["phi"])


def _rhs(module, x):
    return module.euler_rate_rhs(x["Jx"], x["Jy"], x["Jz"], x["theta"], x["phi"], x["Rx"], x["Ry"],
                                 x["Rz"], x["Tx"], x["Ty"], x["Tz"], x["dtheta"], x["dpsi"], x["dphi"])


def _euler_rates_after(module, x):
    A, b = _system(module, x), _rhs(module, x)
    return module.cramer_solution(*(A[:, i, j] for i in range(3) for j in range(3)), *(b[:, i] for i in range(3)))


def _cramer_point(rng, n):
    x = {f"a{i}{j}": rng.normal(size=n) for i in (1, 2, 3) for j in (1, 2, 3)}
    x.update({f"b{i}": rng.normal(size=n) for i in (1, 2, 3)})
    return x


def _cramer(module):
    return lambda x: module.cramer_solution(*(x[f"a{i}{j}"] for i in (1, 2, 3) for j in (1, 2, 3)),
                                            x["b1"], x["b2"], x["b3"])


def _printed_H(x):
    R = gen.contact_offset(*_geo(x))
    P = gen.inertia_ratio(*_geo(x))
    return printed.H(R[:, 0], R[:, 1], R[:, 2], P[:, 0, 0], P[:, 0, 1], P[:, 0, 2], P[:, 1, 1],
                     P[:, 1, 2], P[:, 2, 2])


def _body_point(rng, n):
    x = _geometry(rng, n)
    x.update(Rx=rng.normal(size=n), Ry=rng.normal(size=n), Rz=rng.normal(size=n))
    return x


def _velocity_point(rng, n):
    return {"vx": rng.normal(size=n), "vy": rng.normal(size=n), "vz": rng.normal(size=n),
            "Tx": rng.normal(size=n) * 1e-5, "Ty": rng.normal(size=n) * 1e-5, "Tz": rng.normal(size=n) * 1e-5,
            "m": rng.uniform(1e-6, 1e-4, n)}


def _velocity(module):
    return lambda x: module.centre_velocity_after(x["vx"], x["vy"], x["vz"], x["Tx"], x["Ty"], x["Tz"], x["m"])


def checks() -> list[Check]:
    out = [
        Check(SEED, "(11)-(12)", "inertia tensor P = I/m in the surface frame",
              _geometry, lambda x: printed.inertia_ratio(*_geo(x)), lambda x: gen.inertia_ratio(*_geo(x)),
              note="printed (12) sums radii of gyration rho_r instead of their squares, and (11) then "
                   "negates the off-diagonal entries, giving the wrong sign; derived P = Q diag(rho^2) Q^T"),
        Check(SEED, "(3)-(10)", "reduction tensor H from R and the cofactors of P",
              _geometry, _printed_H, lambda x: gen.H(*_geo(x)),
              note="evaluated with the derived P; with the printed (12) H inherits its error"),
        Check(SEED, "(19)", "impact system for T_x, T_z, mu", _impact_point,
              lambda x: printed.system_19_residual(*_descent_args(x)),
              lambda x: gen.system_19_residual(*_descent_args(x))),
        Check(SEED, "(24)", "descent functional Phi", _impact_point,
              lambda x: printed.functional(*_descent_args(x)),
              lambda x: gen.descent_functional(*_descent_args(x)),
              note="printed Phi is the plain sum of the residuals of (19): linear in T_x, T_z and "
                   "unbounded below, so its minimum is not the solution; the consistent functional is "
                   "the sum of squared residuals"),
    ]
    for k, eq, name in ((0, "(25)", "T_x"), (1, "(26)", "T_z"), (2, "(27)", "mu")):
        out.append(Check(SEED, eq, f"dPhi/d{name} of the printed (24)", _impact_point,
                         lambda x, k=k: printed.gradient(*_descent_args(x))[:, k],
                         lambda x, k=k: printed.functional_gradient(*_descent_args(x))[:, k],
                         note="(27) drops h_xy from the tan(mu) term" if k == 2 else ""))
    out.append(Check(SEED, "(41)", "centre-of-mass velocity after the impact", _velocity_point,
                     _velocity(printed), _velocity(gen)))
    for i in range(3):
        for j in range(3):
            eq = f"({44 + 3 * i + j})"
            note = "printed a_32 = J'_z cos(phi(0)); the kinematics give J'_z cos(theta(0))" if (i, j) == (2, 1) else ""
            out.append(Check(SEED, eq, f"coefficient a_{i + 1}{j + 1} of (43)", _euler_system_point,
                             lambda x, i=i, j=j: _system(printed, x)[:, i, j],
                             lambda x, i=i, j=j: _system(gen, x)[:, i, j], note=note))
    for i in range(3):
        note = "printed b_3 has theta'(0) cos(theta(0)); the kinematics give psi'(0) cos(theta(0))" if i == 2 else ""
        out.append(Check(SEED, f"({53 + i})", f"right-hand side b_{i + 1} of (43)", _euler_system_point,
                         lambda x, i=i: _rhs(printed, x)[:, i], lambda x, i=i: _rhs(gen, x)[:, i], note=note))
    out += [
        Check(SEED, "(56)", "contact offset in body axes", _body_point,
              lambda x: printed.body_components(x["Rx"], x["Ry"], x["Rz"], x["psi"], x["theta"], x["phi"]),
              lambda x: gen.body_components(x["Rx"], x["Ry"], x["Rz"], x["psi"], x["theta"], x["phi"])),
        Check(SEED, "(58)-(60)", "Cramer's rule for a 3x3 system", _cramer_point,
              _cramer(printed), _cramer(gen)),
        Check(SEED, "(43)-(60)", "Euler-angle rates after the impact, whole printed chain",
              _euler_system_point, lambda x: _euler_rates_after(printed, x),
              lambda x: _euler_rates_after(gen, x),
              note="inherits the misprints of (51) and (55); the Cramer formulas themselves agree"),
    ]
    return out


def not_compared() -> list[NotCompared]:
    """Printed items of eqs. (1)-(60) that are definitions or procedures rather than formulas to compare."""
    rows = [
        ("(1)-(2)", "impulse-momentum balance with the reduction tensor H", "the definition of H; H itself is "
         "compared as (3)-(10)"),
        ("(13)-(18)", "impact system: (13) with the law (14)-(17) and (18)", "reduced exactly to (19), compared; "
         "the robust solver reproduces (14)-(18) exactly at 300 random impacts (tests/test_grain_impact_solver.py)"),
        ("(20)", "|V_K(0)| = sqrt(x'^2 + y'^2)", "a definition used by (19)"),
        ("(21)-(23)", "descent: minimiser, step and gradient vector", "a procedure; run as printed by the "
         "`paper` impact solver, whose failure follows from (24) (compared)"),
        ("(28)-(40)", "golden-section line search", "a procedure; its contraction 0.618 is fitted in "
         "tests/test_grain_impact_solver.py"),
        ("(42)", "angular momentum change = R x T", "used inside (41), (43)-(60), compared as a chain"),
        ("(57)", "impulse components in body axes (direction cosines)", "a rotation of T; compared inside the "
         "chain (43)-(60)"),
    ]
    return [NotCompared(SEED, eq, text, why) for eq, text, why in rows]
