"""Scene kind ``impact``: one impact of an ellipsoidal grain (fields in docs/scenes-impact.md).

The scene is declared once in :data:`SCHEMA` (the docs' field table is generated
from it); ``prepare`` checks that the contact point approaches the plane before
anything is solved; ``precision`` is the solvers' work-precision study.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from symmech.core import precision as wp
from symmech.core import plotting, registry
from symmech.core.context import Context
from symmech.core.results import Check, Headline, Result, at_most
from symmech.core.scene import SceneError
from symmech.core.schema import Choice, Float, Int, Str, Table, plot_output
from symmech.core.watchdog import watchdog
from symmech.generated import grain_impact as gen
from symmech.generated import grain_impact_printed as printed
from symmech.grain import fields, plots
from symmech.grain.body import Ellipsoid, euler_from_matrix, rotation
from symmech.grain.impact import (ENERGY_RTOL, RESIDUAL_TOLERANCE, SOLVERS, DescentOptions, euler_rates,
                                  impact_geometry, solve_descent_batch, solve_impact, solve_robust_batch, solve_scipy)

ROLE = "kind"  # found by symmech.core.discovery

# CPU time of the paper's descent per step and per golden-section iteration (measured on the
# default scene with `paper-corrected`, 200-1000 steps, 60-200 iterations), for the estimate.
SECONDS_PER_DESCENT_STEP = 3e-3
SECONDS_PER_LINE_ITERATION = 2e-6
ONE_IMPACT_SECONDS = 2e-3  # the other solvers' run of the default scene (1.6 ms on 2 loaded cores)
_DESCENT = DescentOptions()

SCHEMA = Table("an impact scene", {
    "kind": Choice("selects this kind", choices=("impact",)),
    "title": Str("free text", default=""),
    "body": fields.BODY,
    "state": Table("before the impact, surface frame (X, Y in the plane, Z the outward normal), relative to "
                   "the surface; the contact point must approach the plane (u_Kz(0) < 0)", {
        "velocity": fields.velocity("centre-of-mass velocity"),
        "angular_velocity": fields.angular_velocity("angular velocity", default=[0.0, 0.0, 0.0]),
    }),
    "impact": Table("the printed law (14)-(18)", {
        "e": Float("normal restitution: ż_K = −e ż_K(0) (14)", lo=0.0, hi=1.0),
        "lambda": Float("tangential reduction: |V_K| = (1 − λ)|V_K(0)| (17)", lo=0.0, hi=1.0),
    }),
    "solver": Table("the impact solver", {
        "name": Choice("see Solvers below", choices=SOLVERS, default="robust"),
        "tol": Float("Newton tolerance on μ (robust) / `xtol` (scipy)", unit="rad", lo=0.0, lo_open=True, hi=1e-2,
                     default=1e-14),
        "max_steps": Int("S, descent steps (paper solvers)", lo=1, hi=1_000_000, default=_DESCENT.max_steps),
        "descent_tol": Float("δ of the stop rule Φ ≤ δ, relative to m|u_K(0)| (its square for `paper-corrected`)",
                             lo=0.0, lo_open=True, hi=1.0, default=_DESCENT.tol),
        "step_max": Float("Δ_max of the line search (29)", lo=0.0, lo_open=True, hi=1e3,
                          default=_DESCENT.step_max),
        "line_iterations": Int("R, golden-section iterations", lo=1, hi=1000, default=_DESCENT.line_iterations),
        "line_tol": Float("ε, golden-section bracket width", lo=0.0, lo_open=True, hi=1.0,
                          default=_DESCENT.line_tol),
    }, default={}),
    "precision": Table("reserved for `symmech bench precision` (no fields yet)", {}, default={}),
    "output": plot_output(plots.IMPACT, default=tuple(plots.IMPACT)),
})


@dataclass(frozen=True)
class ImpactScene:
    """A prepared impact: the body, its state before the impact, the printed law's e and λ, the solver."""

    body: Ellipsoid
    angles: np.ndarray  # (psi, theta, phi) [rad]
    velocity: np.ndarray  # centre of mass before, surface frame [m/s]
    angular_velocity: np.ndarray  # before, surface frame [rad/s]
    e: float
    lam: float
    solver: str
    tol: float
    descent: DescentOptions
    output: dict  # the resolved [output] table: plots and formats


def prepare(r: dict) -> ImpactScene:
    """The impact of a resolved scene; SceneError unless its contact point approaches the plane."""
    s = r["solver"]
    descent = DescentOptions(max_steps=s["max_steps"], tol=s["descent_tol"], step_max=s["step_max"],
                             line_iterations=s["line_iterations"], line_tol=s["line_tol"])
    sc = ImpactScene(Ellipsoid(*r["body"]["semi_axes"], fields.body_mass(r["body"])),
                     np.array(r["body"]["orientation"]), np.array(r["state"]["velocity"]),
                     np.array(r["state"]["angular_velocity"]), r["impact"]["e"], r["impact"]["lambda"], s["name"],
                     s["tol"], descent, r["output"])
    uK0 = _contact_velocity(sc)
    if not uK0[2] < 0:
        raise SceneError("state.velocity", f"the contact point is not approaching the plane: u_Kz(0) = {uK0[2]:.6g} m/s "
                                           "must be < 0 (velocity + angular_velocity x contact offset)")
    return sc


def _contact_velocity(sc: ImpactScene) -> np.ndarray:
    """u_K(0) (3,) [m/s]: velocity of the contact point before the impact."""
    _, R, _ = impact_geometry(sc.body, rotation(sc.angles))
    return sc.velocity + np.cross(sc.angular_velocity, R)


def estimate(sc: ImpactScene) -> registry.Estimate:
    """The paper's descent costs up to max_steps line searches of line_iterations; the other solvers are instant."""
    if sc.solver in ("paper", "paper-corrected"):
        d = sc.descent
        seconds = d.max_steps * (SECONDS_PER_DESCENT_STEP + d.line_iterations * SECONDS_PER_LINE_ITERATION)
        return registry.Estimate(seconds, f"up to {d.max_steps} descent steps x {d.line_iterations} line iterations")
    return registry.Estimate(ONE_IMPACT_SECONDS, "one impact")


def sample(sc: ImpactScene, share: float) -> ImpactScene | None:
    """For :func:`symmech.core.sample.timed`: the scene itself when its solver is instant (one impact is the least
    it can run, and milliseconds of a loaded machine's time slices are far from the count model's); None for the
    paper's descent, which stops where it converges (a shorter descent may cost as much as the whole)."""
    return None if sc.solver in ("paper", "paper-corrected") else sc


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


def run(sc: ImpactScene, ctx: Context) -> Result:
    """Solve the impact: impulse, velocities after, Euler rates three ways, every root, and the plot."""
    Q = rotation(sc.angles)
    with watchdog(ctx, where=f"impact solver {sc.solver}"):
        result = solve_impact(sc.body, Q, sc.velocity, sc.angular_velocity, sc.e, sc.lam,
                              solver=sc.solver, descent=sc.descent, tol=sc.tol)
    _, R, H = impact_geometry(sc.body, Q)
    rates, gimbal = _euler_paths(sc, Q, R, result.T, result.omega_after)
    summary = {
        "captions": plotting.captions(plots.IMPACT, sc.output),
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
    }

    def draw(folder: Path) -> list[Path]:
        return plots.impact_plots(H, sc, result, folder, sc.output)

    return Result("impact", summary, plots=draw, warnings=list(result.warnings) + ([gimbal] if gimbal else []),
                  headline=_headline(result), checks=_checks(result))


def _headline(r) -> list[Headline]:
    """The impulse and the state just after the impact."""
    lost = r.ke_before - r.ke_after
    return [Headline("normal impulse", r.T[2], "N s", "T_z, along the plane's normal"),
            Headline("tangential impulse", float(np.hypot(r.T[0], r.T[1])), "N s", "|(T_x, T_y)|, friction"),
            *(Headline(f"centre velocity after, {x}", v, "m/s", "velocity of the centre just after the impact")
              for x, v in zip("xyz", r.v_c_after)),
            Headline("angular speed after", float(np.linalg.norm(r.omega_after)), "rad/s", "|ω| after the impact"),
            Headline("rebound velocity of the contact point", r.uK_after[2], "m/s",
                     "its velocity along the normal after the impact (> 0: it leaves the plane)"),
            Headline("kinetic energy lost", lost, "J", f"{100 * lost / r.ke_before:.3g} % of the energy before")]


def _checks(r) -> list[Check]:
    return [at_most("impact equations (19) solved (relative residual)", r.residual, RESIDUAL_TOLERANCE),
            at_most("kinetic energy after / before (no energy created)", r.ke_after / r.ke_before,
                    1 + ENERGY_RTOL),
            Check("an admissible root: no energy created, no pull into the plane", float(r.admissible), "1",
                  "= 1 (admissible)", "pass" if r.admissible else "fail")]


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


def precision(sc: ImpactScene, ctx: Context) -> Result:
    """Work-precision study of the impact solvers on this scene's impact."""
    _, _, H = impact_geometry(sc.body, rotation(sc.angles))
    uK0 = _contact_velocity(sc)
    m = sc.body.mass
    base = solve_robust_batch(H[None], m, sc.e, sc.lam, uK0[None])
    T_ref = _reference(H, m, sc.e, sc.lam, uK0, base.T[0], float(base.mu[0]))
    norm = np.linalg.norm(T_ref)
    rows = []

    def add(method, knob, value, fn):
        ctx.tick(f"impact precision study, {method}")
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
    reference = "mpmath.findroot at 50 digits on (19), H taken as exact"
    return wp.result("impact", rows, "precision_impact", "Impact solvers: work-precision", reference)


registry.register(registry.Kind(
    name="impact", summary="one impact of an ellipsoidal grain on a plane (seed 000, eqs (1)-(60))",
    schema=SCHEMA, prepare=prepare, run=run, estimate=estimate, sample=sample, precision=precision,
    docs="docs/scenes-impact.md"))
