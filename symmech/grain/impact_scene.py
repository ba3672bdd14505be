"""Scene kind ``impact``: one impact of an ellipsoidal grain (fields in docs/scenes-impact.md)."""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from symmech.core import precision as wp
from symmech.core.scene import SceneError, Section, SymmechError
from symmech.generated import grain_impact as gen
from symmech.generated import grain_impact_printed as printed
from symmech.grain import plots
from symmech.grain.body import Ellipsoid, euler_from_matrix, rotation
from symmech.grain.impact import (SOLVERS, DescentOptions, ImpactError, euler_rates, impact_geometry,
                                  solve_descent_batch, solve_impact, solve_robust_batch, solve_scipy)


@dataclass(frozen=True)
class ImpactScene:
    body: Ellipsoid
    angles: np.ndarray  # (psi, theta, phi) [rad]
    velocity: np.ndarray  # centre of mass before, surface frame [m/s]
    angular_velocity: np.ndarray  # before, surface frame [rad/s]
    e: float
    lam: float
    solver: str
    tol: float
    descent: DescentOptions


def parse(scene: Section) -> ImpactScene:
    """Validate an impact scene; every problem names its field."""
    body = scene.section("body")
    a, b, c = body.vector("semi_axes", 3, unit="m", lo=0.0, lo_open=True)
    if body.has("mass") == body.has("density"):
        raise SceneError("body.mass", "give exactly one of body.mass [kg] or body.density [kg/m^3]")
    if body.has("mass"):
        mass = body.float("mass", unit="kg", lo=0.0, lo_open=True)
    else:
        mass = body.float("density", unit="kg/m^3", lo=0.0, lo_open=True) * 4.0 / 3.0 * math.pi * a * b * c
    angles = np.array(body.vector("orientation", 3, unit="rad", default=[0.0, 0.0, 0.0]))
    body.finish()
    state = scene.section("state")
    velocity = np.array(state.vector("velocity", 3, unit="m/s"))
    angular_velocity = np.array(state.vector("angular_velocity", 3, unit="rad/s", default=[0.0, 0.0, 0.0]))
    state.finish()
    law = scene.section("impact")
    e = law.float("e", unit="", lo=0.0, hi=1.0)
    lam = law.float("lambda", unit="", lo=0.0, hi=1.0)
    law.finish()
    solver = scene.section("solver", default={})
    name = solver.choice("name", SOLVERS, default="robust")
    tol = solver.float("tol", unit="rad", default=1e-14, lo=0.0, lo_open=True)
    defaults = DescentOptions()
    descent = DescentOptions(
        max_steps=solver.int("max_steps", default=defaults.max_steps, lo=1),
        tol=solver.float("descent_tol", unit="", default=defaults.tol, lo=0.0, lo_open=True),
        step_max=solver.float("step_max", unit="", default=defaults.step_max, lo=0.0, lo_open=True),
        line_iterations=solver.int("line_iterations", default=defaults.line_iterations, lo=1),
        line_tol=solver.float("line_tol", unit="", default=defaults.line_tol, lo=0.0, lo_open=True))
    solver.finish()
    scene.section("precision", default={})  # read by `bench precision` only
    scene.str("title", default="")
    scene.finish()
    return ImpactScene(Ellipsoid(a, b, c, mass), angles, velocity, angular_velocity, e, lam, name, tol, descent)


def _euler_paths(sc: ImpactScene, Q, R, T, omega_after):
    """Euler rates after the impact three ways: from omega, derived Cramer (43)-(60), printed."""
    psi, theta, phi = euler_from_matrix(Q)
    J = sc.body.inertia
    rates_after, warning = euler_rates(Q, omega_after)
    rates_before, _ = euler_rates(Q, sc.angular_velocity)
    out = {"from_angular_velocity": None if rates_after is None else rates_after.tolist()}
    if rates_before is None or rates_after is None:
        out["cramer_derived"] = out["cramer_printed"] = None
        return out, warning
    Rb, Tb = Q.T @ R, Q.T @ T
    for key, module in (("cramer_derived", gen), ("cramer_printed", printed)):
        A = module.euler_rate_system(*J, theta, phi)
        b = module.euler_rate_rhs(*J, theta, phi, *Rb, *Tb, *rates_before)
        out[key] = module.cramer_solution(*A.ravel(), *b).tolist()
    return out, warning


def run(scene: Section, out: Path) -> dict:
    sc = parse(scene)
    Q = rotation(sc.angles)
    try:
        result = solve_impact(sc.body, Q, sc.velocity, sc.angular_velocity, sc.e, sc.lam,
                              solver=sc.solver, descent=sc.descent, tol=sc.tol)
    except ImpactError as exc:
        raise SymmechError(f"state: {exc}") from None
    _, R, H = impact_geometry(sc.body, Q)
    rates, gimbal = _euler_paths(sc, Q, R, result.T, result.omega_after)
    warnings = list(result.warnings) + ([gimbal] if gimbal else [])
    plots.impact_plot(out / "impact.png", H, sc, result)
    return {
        "kind": "impact",
        "solver": {"name": result.solver, "iterations": result.iterations,
                   "residual_19": result.residual, "converged": result.converged},
        "impulse_T": result.T.tolist(),
        "mu": result.mu,
        "contact_offset_R": R.tolist(),
        "reduction_tensor_H": H.tolist(),
        "contact_velocity_before": result.uK_before.tolist(),
        "contact_velocity_after": result.uK_after.tolist(),
        "centre_velocity_after": result.v_c_after.tolist(),
        "angular_velocity_after": result.omega_after.tolist(),
        "euler_rates_after": rates,
        "kinetic_energy_before": result.ke_before,
        "kinetic_energy_after": result.ke_after,
        "admissible": result.admissible,
        "roots": result.roots,
        "warnings": warnings,
    }


# --------------------------------------------------------------------------- precision


def _reference(H, m, e, lam, uK0, T, mu, digits=50):
    """T refined in extended precision (mpmath) from a float64 solution; H taken as exact."""
    import mpmath

    with mpmath.workdps(digits):
        Hm = mpmath.matrix(H.tolist())
        u = [mpmath.mpf(x) for x in uK0]
        speed = (1 - mpmath.mpf(lam)) * mpmath.sqrt(u[0]**2 + u[1]**2)

        def equations(tau, Tz, angle):
            vec = mpmath.matrix([tau * mpmath.cos(angle), tau * mpmath.sin(angle), Tz])
            r = Hm * vec
            du = [speed * mpmath.cos(angle) - u[0], speed * mpmath.sin(angle) - u[1], -(1 + e) * u[2]]
            return [r[i] - m * du[i] for i in range(3)]

        tau0 = T[0] * math.cos(mu) + T[1] * math.sin(mu)
        tau, Tz, angle = mpmath.findroot(equations, (tau0, T[2], mu))
        return np.array([float(tau * mpmath.cos(angle)), float(tau * mpmath.sin(angle)), float(Tz)])


def precision(scene: Section, out: Path) -> dict:
    """Work-precision study of the impact solvers on this scene's impact."""
    sc = parse(scene)
    Q = rotation(sc.angles)
    _, R, H = impact_geometry(sc.body, Q)
    uK0 = sc.velocity + np.cross(sc.angular_velocity, R)
    if not uK0[2] < 0:
        raise SymmechError(f"state: the contact point is not approaching the plane (u_Kz = {uK0[2]:.6g} m/s)")
    m = sc.body.mass
    base = solve_robust_batch(H[None], m, sc.e, sc.lam, uK0[None])
    T_ref = _reference(H, m, sc.e, sc.lam, uK0, base.T[0], float(base.mu[0]))
    norm = np.linalg.norm(T_ref)
    rows = []

    def add(method, knob, value, fn):
        seconds, T = wp.best_time(fn, repeats=3)
        rows.append({"method": method, "knob": knob, "value": value, "seconds": seconds,
                     "error": float(np.linalg.norm(T - T_ref) / norm)})

    for iters in (0, 1, 2, 3):
        add("robust (exact reduction)", "newton_iterations", iters,
            lambda: solve_robust_batch(H[None], m, sc.e, sc.lam, uK0[None], max_iter=iters).T[0])
    for xtol in (1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12):
        add("scipy.optimize.root", "xtol", xtol, lambda: solve_scipy(H, m, sc.e, sc.lam, uK0, xtol=xtol)[0])
    for variant in ("paper", "paper-corrected"):
        for steps in (1, 10, 100, 1000):
            options = DescentOptions(max_steps=steps, line_iterations=40)
            add(f"descent ({variant})", "max_steps", steps,
                lambda: solve_descent_batch(H[None], m, sc.e, sc.lam, uK0[None], variant, options)[0][0])
    files = wp.write(rows, out, "precision_impact", "Impact solvers: work-precision",
                     "mpmath.findroot at 50 digits on (19), H taken as exact")
    return {"files": [str(f) for f in files], "rows": rows}
