"""One impact of an ellipsoidal grain on a plane: the printed impact law, solved three ways.

Contract (seed 000, (1), (13)-(18)), all vectors in the surface frame KXYZ,
velocities relative to the surface:

    m (u_K - u_K(0)) = H T,     u_K = u_C + omega x R
    u_Kz = -e u_Kz(0)                                   (14)
    (u_Kx, u_Ky) = (1 - lambda) |V_K(0)| (cos mu, sin mu)   (15)-(17)
    T_y = T_x tan mu  (tangential impulse collinear with the new tangential velocity) (18)

Solvers (``solver=``):

* ``"robust"`` (default): the exact reduction. Eliminating T gives one scalar
  equation F(mu) = det[H d(mu), H e_z, du_K(mu)] = 0, a trigonometric polynomial
  of degree 2 (:func:`symmech.grain.derive.mu_equation`). Its roots are the
  unit-circle eigenvalues of a 4x4 companion matrix, polished by Newton on F;
  for each root T = m H^-1 du_K(mu). Root rule: among admissible roots (normal
  impulse T_z >= 0 and no kinetic energy created) take the one with the smallest
  tangential impulse |T_t|; it is the root that merely slows the contact point
  (for a sphere, mu = direction of the incoming slip) rather than reversing it.
  When no root is admissible the smallest-|T_t| root is returned with
  ``admissible=False`` and a warning saying why. With zero post-impact
  tangential speed ((1-lambda)|V_K(0)| = 0) mu is immaterial and T follows from
  one linear solve.
* ``"paper"``: the printed method: gradient descent on Phi (24) with the printed
  gradient (25)-(27) and golden-section line search (28)-(40). Phi as printed is
  the plain sum of the residuals, unbounded below, so the method stops at once
  with a wrong answer; it is kept to reproduce the paper, and its residual is
  reported honestly.
* ``"paper-corrected"``: the same descent and line search on the consistent
  functional (sum of squared residuals) with its derived gradient.
* ``"scipy"``: ``scipy.optimize.root`` per impact on (19) (baseline).

Every solver reports the residual of (19) in its cos(mu)-scaled form
``|H (tau cos mu, tau sin mu, T_z) - m du_K(mu)| / (m |u_K(0)|)`` with
``tau = T_x / cos mu``, which stays finite at mu = +-90 degrees.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from symmech.core import kinematics as kin
from symmech.generated import grain_impact as gen
from symmech.generated import grain_impact_printed as printed
from symmech.grain.body import Ellipsoid, euler_from_matrix

SOLVERS = ("robust", "paper", "paper-corrected", "scipy")
ENERGY_RTOL = 1e-9  # relative slack before a kinetic-energy gain counts as created energy
RESIDUAL_TOLERANCE = 1e-8  # relative residual of (19) below which an impact counts as solved
GIMBAL_WARN = 1e-2  # |sin theta| below this: Euler rates amplified by 1/sin theta, warn
GIMBAL_UNDEFINED = 1e-9  # |sin theta| below this: psi' and phi' are not defined


class ImpactError(ValueError):
    """The impact cannot be computed for these inputs (e.g. the contact point is separating)."""


@dataclass
class ImpactResult:
    """Outcome of one impact; vectors in the surface frame, SI units."""

    T: np.ndarray  # impulse on the body at K, (3,) [N s]
    mu: float  # angle of the tangential impulse / velocity from X [rad]
    uK_before: np.ndarray  # contact-point velocity before, (3,) [m/s]
    uK_after: np.ndarray  # contact-point velocity after, (3,) [m/s]
    v_c_after: np.ndarray  # centre-of-mass velocity after, (3,) [m/s]
    omega_after: np.ndarray  # angular velocity after, (3,) [rad/s]
    ke_before: float  # [J]
    ke_after: float  # [J]
    solver: str
    iterations: int
    residual: float  # residual of (19), relative (see module docstring)
    converged: bool
    admissible: bool
    warnings: list[str] = field(default_factory=list)
    roots: list[dict] = field(default_factory=list)  # robust solver: every root and its verdict


# --------------------------------------------------------------------------- geometry


def _h_args(H):
    """The six independent entries of H (..., 3, 3) in generated-argument order."""
    return H[..., 0, 0], H[..., 0, 1], H[..., 0, 2], H[..., 1, 1], H[..., 1, 2], H[..., 2, 2]


def impact_geometry(body: Ellipsoid, Q):
    """Euler angles (...,3), contact offset R (...,3) [m] and H (...,3,3) for orientation(s) Q."""
    angles = euler_from_matrix(Q)
    psi, theta, phi = angles[..., 0], angles[..., 1], angles[..., 2]
    R = gen.contact_offset(body.a, body.b, body.c, psi, theta, phi)
    H = gen.H(body.a, body.b, body.c, psi, theta, phi)
    return angles, R, H


def reduction_tensor(body: Ellipsoid, Q) -> np.ndarray:
    """H for orientation(s) Q (..., 3, 3): m du_K = H T."""
    return impact_geometry(body, Q)[2]


def _prescribed_uK(uK0, e, lam, mu):
    """Contact-point velocity after the impact demanded by (14)-(17) for angle(s) mu."""
    speed = (1.0 - lam) * np.hypot(uK0[..., 0], uK0[..., 1])
    parts = np.broadcast_arrays(speed * np.cos(mu), speed * np.sin(mu), -e * uK0[..., 2])
    return np.stack(parts, axis=-1)


def residual_19(H, m, e, lam, uK0, T, mu):
    """Relative residual of (19), cos(mu)-scaled; T is the full impulse (..., 3)."""
    d = np.stack([np.cos(mu), np.sin(mu)], axis=-1)
    tau = np.sum(T[..., :2] * d, axis=-1)  # impulse along the tangential direction mu
    T_line = np.stack([tau * d[..., 0], tau * d[..., 1], T[..., 2]], axis=-1)
    du = _prescribed_uK(uK0, e, lam, mu) - uK0
    m = np.asarray(m, float)
    r = np.einsum("...ij,...j->...i", H, T_line) - m[..., None] * du
    off_line = np.abs(T[..., 1] * d[..., 0] - T[..., 0] * d[..., 1])  # violation of (18)
    scale = m * np.linalg.norm(uK0, axis=-1)
    return (np.linalg.norm(r, axis=-1) + off_line) / scale


# --------------------------------------------------------------------------- robust solver


def _trig_roots(k, tol, max_iter=12):
    """Real roots of F = k0 + k1c cos + k1s sin + k2c cos2 + k2s sin2, batch (N, 5) -> (N, 4).

    With mu = delta + 2 atan(t), (1 + t^2)^2 F is a real quartic in t; delta is
    the one of five equally spaced shifts that maximises |F(delta + pi)|, the
    quartic's leading coefficient, which F (at most 4 roots) cannot make zero at
    all five. Real eigenvalues of the companion matrix give t; Newton on F
    polishes mu; unused slots are NaN. Returns (roots, Newton iterations).
    """
    k0, k1c, k1s, k2c, k2s = (k[:, i] for i in range(5))

    def F(mu, rows=slice(None)):
        return (k0[rows, None] + k1c[rows, None] * np.cos(mu) + k1s[rows, None] * np.sin(mu)
                + k2c[rows, None] * np.cos(2 * mu) + k2s[rows, None] * np.sin(2 * mu))

    def dF(mu, rows):
        return (-k1c[rows, None] * np.sin(mu) + k1s[rows, None] * np.cos(mu)
                - 2 * k2c[rows, None] * np.sin(2 * mu) + 2 * k2s[rows, None] * np.cos(2 * mu))

    n = len(k)
    shifts = np.arange(5) * (2 * np.pi / 5)
    delta = shifts[np.argmax(np.abs(F(shifts[None, :] + np.pi)), axis=1)]
    c1, s1, c2, s2 = np.cos(delta), np.sin(delta), np.cos(2 * delta), np.sin(2 * delta)
    a1c, a1s = k1c * c1 + k1s * s1, -k1c * s1 + k1s * c1  # coefficients in mu - delta
    a2c, a2s = k2c * c2 + k2s * s2, -k2c * s2 + k2s * c2
    quartic = np.stack([k0 - a1c + a2c, 2 * a1s - 4 * a2s, 2 * k0 - 6 * a2c,
                        2 * a1s + 4 * a2s, k0 + a1c + a2c], axis=1)
    solvable = np.abs(quartic[:, 0]) > 0  # False only where F vanishes identically
    companion = np.zeros((n, 4, 4))
    companion[solvable, 0, :] = -quartic[solvable, 1:] / quartic[solvable, :1]
    companion[:, [1, 2, 3], [0, 1, 2]] = 1.0
    t = np.linalg.eigvals(companion)
    real = (np.abs(t.imag) <= 1e-6 * (1.0 + np.abs(t.real))) & solvable[:, None]
    roots = np.where(real, delta[:, None] + 2 * np.arctan(t.real), np.nan)

    iterations = 0
    active = np.flatnonzero(np.any(real, axis=1))
    for iterations in range(1, max_iter + 1):  # noqa: B007 (the count is returned)
        if active.size == 0:
            break
        r = roots[active]
        slope = dF(r, active)
        step = np.where(np.isnan(r) | (slope == 0), 0.0, F(r, active) / np.where(slope == 0, 1.0, slope))
        roots[active] = r - np.clip(step, -0.5, 0.5)
        active = active[np.any(np.abs(step) > tol, axis=1)]
    scale = np.abs(k).sum(axis=1)
    roots[np.abs(F(roots)) > 1e-9 * scale[:, None]] = np.nan
    roots = np.mod(roots + np.pi, 2 * np.pi) - np.pi
    # Duplicates: a double root appears as two nearly equal eigenvalues.
    roots = np.sort(roots, axis=1)  # NaN last
    gap = np.diff(roots, axis=1)
    roots[:, 1:][gap < 1e-7] = np.nan
    count = np.sum(~np.isnan(roots), axis=1)
    last = roots[np.arange(n), np.maximum(count - 1, 0)]
    wrap = (count > 1) & (np.abs(np.mod(last - roots[:, 0] + np.pi, 2 * np.pi) - np.pi) < 1e-7)
    roots[wrap, np.maximum(count[wrap] - 1, 0)] = np.nan
    return roots, iterations


@dataclass
class ImpactBatch:
    """Robust-solver results for N impacts; arrays with a leading axis N."""

    T: np.ndarray  # (N, 3) [N s]
    mu: np.ndarray  # (N,) [rad]
    uK_after: np.ndarray  # (N, 3) [m/s]
    residual: np.ndarray  # (N,)
    admissible: np.ndarray  # (N,) bool
    energy_created: np.ndarray  # (N,) bool: the chosen root gains kinetic energy
    pulling: np.ndarray  # (N,) bool: the chosen root has T_z < 0
    delta_ke: np.ndarray  # (N,) [J]
    roots_mu: np.ndarray  # (N, 4) every root, NaN where unused
    roots_T: np.ndarray  # (N, 4, 3)
    roots_delta_ke: np.ndarray  # (N, 4) [J]
    iterations: int


def solve_robust_batch(H, m, e, lam, uK0, tol=1e-14, max_iter=12) -> ImpactBatch:
    """Vectorised exact solve of the printed law for N impacts.

    H (N,3,3), m scalar or (N,) [kg], e, lam scalars or (N,), uK0 (N,3) [m/s]
    with uK0[:, 2] < 0. ``tol`` is the Newton step tolerance on mu [rad] and
    ``max_iter`` caps the Newton polish of the eigenvalue roots.
    """
    H = np.asarray(H, float)
    uK0 = np.asarray(uK0, float)
    n = len(uK0)
    m, e, lam = (np.broadcast_to(np.asarray(x, float), (n,)) for x in (m, e, lam))
    k = gen.mu_equation(*_h_args(H), lam, e, uK0[:, 0], uK0[:, 1], uK0[:, 2])
    # lam > 1 (a tangential reversal) makes the signed speed negative: only its size says stuck
    speed_after = np.abs(1.0 - lam) * np.hypot(uK0[:, 0], uK0[:, 1])
    stuck = speed_after <= 1e-14 * np.linalg.norm(uK0, axis=1)
    roots, iterations = _trig_roots(k, tol, max_iter)
    # Zero tangential speed after: mu is immaterial, one linear solve gives T.
    roots[stuck] = np.nan
    roots[stuck, 0] = 0.0

    mu_all = np.where(np.isnan(roots), 0.0, roots)
    du = _prescribed_uK(uK0[:, None, :], e[:, None], lam[:, None], mu_all) - uK0[:, None, :]
    T_all = m[:, None, None] * np.linalg.solve(H[:, None], du[..., None])[..., 0]
    uK1 = uK0[:, None, :] + du
    dke = 0.5 * np.sum(T_all * (uK0[:, None, :] + uK1), axis=-1)
    valid = ~np.isnan(roots)
    ke_scale = 0.5 * m * np.sum(uK0**2, axis=1)
    gains = dke > ENERGY_RTOL * ke_scale[:, None]
    pulls = T_all[..., 2] < -1e-12 * np.linalg.norm(T_all, axis=-1)
    tangential = np.hypot(T_all[..., 0], T_all[..., 1])
    # Preference: admissible, then energy-creating, then pulling; smallest |T_t| within.
    rank = np.where(pulls, 2.0, np.where(gains, 1.0, 0.0))
    big = 10.0 * np.max(np.where(valid, tangential, 0.0), axis=1, keepdims=True) + 1.0
    choice = np.argmin(np.where(valid, rank * big + tangential, np.inf), axis=1)
    pick = (np.arange(n), choice)
    found = valid.any(axis=1)  # never False in tests; if it were, say so with NaN
    T = np.where(found[:, None], T_all[pick], np.nan)
    mu = roots[pick]
    mu_stuck = np.arctan2(T[:, 1], T[:, 0])
    mu = np.where(stuck, np.where(np.hypot(T[:, 0], T[:, 1]) > 0, mu_stuck, 0.0), mu)
    residual = residual_19(H, m, e, lam, uK0, T, mu)
    return ImpactBatch(T=T, mu=mu, uK_after=uK1[pick], residual=residual,
                       admissible=found & ~(gains[pick] | pulls[pick]), energy_created=gains[pick],
                       pulling=pulls[pick], delta_ke=dke[pick],
                       roots_mu=roots, roots_T=T_all, roots_delta_ke=np.where(valid, dke, np.nan),
                       iterations=iterations)


# --------------------------------------------------------------------------- paper's descent


@dataclass(frozen=True)
class DescentOptions:
    """Knobs of the paper's gradient descent (21)-(40).

    max_steps: S, descent steps; tol: delta of the stop rule Phi <= delta, relative
    to m|u_K(0)| (to its square for the corrected, squared functional);
    step_max: Delta_max of (29) [variables' units]; line_iterations: R;
    line_tol: epsilon, absolute width at which the golden section stops.
    """

    max_steps: int = 1000
    tol: float = 1e-12
    step_max: float = 1.0
    line_iterations: int = 60
    line_tol: float = 1e-14

    def __post_init__(self):
        if self.max_steps < 1 or self.line_iterations < 1:
            raise ValueError("descent max_steps and line_iterations must be >= 1")
        if not (self.tol > 0 and self.step_max > 0 and self.line_tol > 0):
            raise ValueError("descent tol, step_max and line_tol must be > 0")


def _golden_section(xi, lo, hi, iterations, eps):
    """Minimise xi(step) over [lo, hi] per batch element, as (30)-(40) prescribe.

    The interior point kept from the previous interval is reused ((36), (40));
    the other is the golden point of the new interval farthest from it (37).
    Returns the midpoint of the final interval.
    """
    r1, r2 = (3 - np.sqrt(5)) / 2, (np.sqrt(5) - 1) / 2
    l1, l2 = lo + r1 * (hi - lo), lo + r2 * (hi - lo)
    x1, x2 = xi(l1), xi(l2)
    for _ in range(iterations):
        active = (hi - lo) > eps
        if not active.any():
            break
        left = x1 <= x2  # (34)-(36): keep [lo, l2]; else (38)-(40): keep [l1, hi]
        new_lo = np.where(left, lo, l1)
        new_hi = np.where(left, l2, hi)
        kept = np.where(left, l1, l2)
        kept_x = np.where(left, x1, x2)
        g1, g2 = new_lo + r1 * (new_hi - new_lo), new_lo + r2 * (new_hi - new_lo)
        other = np.where(np.abs(kept - g1) >= np.abs(kept - g2), g1, g2)  # (37)
        other_x = xi(other)
        nl1 = np.minimum(kept, other)
        nl2 = np.maximum(kept, other)
        nx1 = np.where(kept <= other, kept_x, other_x)
        nx2 = np.where(kept <= other, other_x, kept_x)
        lo, hi = np.where(active, new_lo, lo), np.where(active, new_hi, hi)
        l1, l2 = np.where(active, nl1, l1), np.where(active, nl2, l2)
        x1, x2 = np.where(active, nx1, x1), np.where(active, nx2, x2)
    return lo, hi


def solve_descent_batch(H, m, e, lam, uK0, variant="paper", options=DescentOptions()):
    """The paper's descent for N impacts; returns (T (N,3), mu (N,), steps (N,), stopped (N,)).

    ``variant="paper"`` uses (24)-(27) as printed, ``"paper-corrected"`` the sum of
    squared residuals and its derived gradient, in dimensionless variables. Start (an assumption; the paper
    gives none): T_x = 0, T_z = -m(1+e)u_Kz(0)/h_zz, mu = direction of the incoming slip.
    ``stopped`` is True where the stop rule Phi <= delta fired before S steps. A
    descent that crosses a pole of tan(mu) diverges; its T is then inf or NaN and
    its residual of (19) says so.
    """
    n = len(uK0)
    m, e, lam = (np.broadcast_to(np.asarray(x, float), (n,)) for x in (m, e, lam))
    fixed = (*_h_args(H), m, lam, e, uK0[:, 0], uK0[:, 1], uK0[:, 2])
    momentum = m * np.linalg.norm(uK0, axis=1)
    if variant == "paper":
        scale, norm = np.ones(n), np.ones(n)  # as printed: raw variables, Phi in N s
        phi_raw, grad_raw = printed.functional, printed.gradient
    elif variant == "paper-corrected":
        # Impulses in units of m|u_K(0)| and Phi divided by (m|u_K(0)|)^2, so one
        # step length suits T and mu alike.
        scale, norm = momentum, momentum**2
        phi_raw, grad_raw = gen.descent_functional, gen.descent_gradient
    else:
        raise ValueError(f"unknown descent variant {variant!r}")
    units = np.stack([scale, scale, np.ones(n)], axis=1)

    def phi_f(y):
        z = y * units
        return phi_raw(z[:, 0], z[:, 1], z[:, 2], *fixed) / norm

    def grad_f(y):
        z = y * units
        return grad_raw(z[:, 0], z[:, 1], z[:, 2], *fixed) * units / norm[:, None]

    delta = options.tol * (momentum if variant == "paper" else np.ones(n))
    x = np.stack([np.zeros(n), -m * (1 + e) * uK0[:, 2] / H[:, 2, 2],
                  np.arctan2(uK0[:, 1], uK0[:, 0])], axis=1) / units
    steps = np.zeros(n, int)
    stopped = np.zeros(n, bool)
    with np.errstate(all="ignore"):  # a descent through a pole of tan(mu) overflows; reported as NaN
        for _ in range(options.max_steps):
            stopped |= phi_f(x) <= delta
            active = ~stopped
            if not active.any():
                break
            g = grad_f(x)
            step = 0.5 * sum(_golden_section(lambda h: phi_f(x - h[:, None] * g), np.zeros(n),
                                             np.full(n, options.step_max), options.line_iterations,
                                             options.line_tol))
            x = np.where(active[:, None], x - step[:, None] * g, x)
            steps += active
    x = x * units
    Tx, Tz, mu = x[:, 0], x[:, 1], x[:, 2]
    T = np.stack([Tx, Tx * np.tan(mu), Tz], axis=1)
    return T, mu, steps, stopped


# --------------------------------------------------------------------------- scipy baseline


def solve_scipy(H, m, e, lam, uK0, xtol=1e-12):
    """scipy.optimize.root ('hybr') on the cos-scaled (19) in (tau, T_z, mu) for one impact."""
    from scipy.optimize import root

    def equations(x):
        tau, Tz, mu = x
        T = np.array([tau * np.cos(mu), tau * np.sin(mu), Tz])
        return (H @ T - m * (_prescribed_uK(uK0, e, lam, mu) - uK0)) / (m * np.linalg.norm(uK0))

    start = np.array([0.0, -m * (1 + e) * uK0[2] / H[2, 2], np.arctan2(uK0[1], uK0[0])])
    sol = root(equations, start, method="hybr", options={"xtol": xtol})
    tau, Tz, mu = sol.x
    T = np.array([tau * np.cos(mu), tau * np.sin(mu), Tz])
    return T, float(mu), int(sol.nfev), bool(sol.success)


# --------------------------------------------------------------------------- one impact


def kinetic_energy(body: Ellipsoid, Q, v_c, omega) -> float:
    """Translational plus rotational kinetic energy [J]; omega in the surface frame."""
    w_body = Q.T @ omega
    return 0.5 * body.mass * float(v_c @ v_c) + 0.5 * float(body.inertia @ w_body**2)


def euler_rates(Q, omega):
    """Euler-angle rates (theta', psi', phi') [rad/s] for angular velocity omega (surface frame).

    Returns (rates or None, warning or None); rates are None at gimbal lock.
    """
    psi, theta, phi = euler_from_matrix(Q)
    W = gen.euler_rate_matrix(theta, phi)
    s = abs(np.sin(theta))
    if s < GIMBAL_UNDEFINED:
        return None, (f"gimbal lock: sin(theta) = {s:.2e}; the Euler rates psi' and phi' are undefined "
                      "(only psi' + phi' is), the angular velocity is reported instead")
    rates = np.linalg.solve(W, Q.T @ omega)
    warning = None
    if s < GIMBAL_WARN:
        warning = (f"near gimbal lock: sin(theta) = {s:.2e}; Euler rates are amplified by "
                   f"1/sin(theta) = {1 / s:.3g}, use the angular velocity instead")
    return rates, warning


def solve_impact(body: Ellipsoid, Q, v_c, omega, e: float, lam: float, solver: str = "robust",
                 descent: DescentOptions = DescentOptions(), tol: float = 1e-14) -> ImpactResult:
    """Solve one impact of ``body`` at orientation ``Q`` (body axes as columns).

    v_c (3,) [m/s] centre velocity and omega (3,) [rad/s] angular velocity before
    the impact, surface frame, relative to the surface. Raises ImpactError when the
    contact point is not approaching the plane.
    """
    if solver not in SOLVERS:
        raise ValueError(f"unknown solver {solver!r}; choose one of {', '.join(SOLVERS)}")
    if not (0.0 <= e <= 1.0) or not (0.0 <= lam <= 1.0):
        raise ValueError(f"e = {e} and lambda = {lam} must lie in [0, 1]")
    Q, v_c, omega = (np.asarray(x, float) for x in (Q, v_c, omega))
    _, R, H = impact_geometry(body, Q)
    uK0 = v_c + np.cross(omega, R)
    if not uK0[2] < 0:
        raise ImpactError(f"the contact point is not approaching the plane: u_Kz(0) = {uK0[2]:.6g} m/s "
                          "must be < 0")
    m = body.mass
    warnings: list[str] = []
    roots: list[dict] = []
    admissible = True
    if solver == "robust":
        batch = solve_robust_batch(H[None], m, e, lam, uK0[None], tol=tol)
        T, mu, iterations = batch.T[0], float(batch.mu[0]), batch.iterations
        admissible = bool(batch.admissible[0])
        for r_mu, r_T, r_dke in zip(batch.roots_mu[0], batch.roots_T[0], batch.roots_delta_ke[0]):
            if not np.isnan(r_mu):
                roots.append({"mu": float(r_mu), "T": r_T.tolist(), "delta_ke": float(r_dke),
                              "creates_energy": bool(r_dke > ENERGY_RTOL * 0.5 * m * uK0 @ uK0),
                              "pulling": bool(r_T[2] < 0)})
        if not admissible:
            reasons = []
            if batch.energy_created[0]:
                reasons.append(f"creates kinetic energy (+{batch.delta_ke[0]:.3g} J)")
            if batch.pulling[0]:
                reasons.append(f"pulls the grain into the plane (T_z = {T[2]:.3g} N s)")
            warnings.append("no admissible root of the printed impact law: the least-impulse root "
                            + " and ".join(reasons))
    elif solver in ("paper", "paper-corrected"):
        Tb, mub, steps, stopped = solve_descent_batch(H[None], m, e, lam, uK0[None], solver, descent)
        T, mu, iterations = Tb[0], float(mub[0]), int(steps[0])
        if stopped[0]:
            warnings.append(f"descent stop rule Phi <= delta fired after {iterations} steps")
    else:
        T, mu, iterations, ok = solve_scipy(H, m, e, lam, uK0, xtol=max(tol, 1e-15))
        if not ok:
            warnings.append("scipy.optimize.root reports failure")
    residual = float(residual_19(H, m, e, lam, uK0, T, mu))
    converged = bool(residual < RESIDUAL_TOLERANCE)  # False for NaN too
    if not converged:
        warnings.append(f"solver '{solver}' did not solve (19): relative residual {residual:.3g}")
    v_after = v_c + T / m
    inv_inertia = kin.rotate_tensor(Q, np.diag(1.0 / body.inertia))
    omega_after = omega + inv_inertia @ np.cross(R, T)
    uK1 = v_after + np.cross(omega_after, R)
    ke0 = kinetic_energy(body, Q, v_c, omega)
    ke1 = kinetic_energy(body, Q, v_after, omega_after)
    if converged and ke1 > ke0 * (1 + ENERGY_RTOL):
        warnings.append(f"the impact creates kinetic energy: {ke0:.6g} J -> {ke1:.6g} J")
    if abs(T[2]) > 0 and np.hypot(T[0], T[1]) > 10 * abs(T[2]):
        warnings.append(f"tangential impulse {np.hypot(T[0], T[1]):.3g} N s exceeds 10x the normal "
                        f"impulse {T[2]:.3g} N s (grazing impact: the printed law demands friction "
                        "without normal load)")
    return ImpactResult(T=T, mu=mu, uK_before=uK0, uK_after=uK1, v_c_after=v_after,
                        omega_after=omega_after, ke_before=ke0, ke_after=ke1, solver=solver,
                        iterations=int(iterations), residual=residual, converged=converged,
                        admissible=admissible and converged and ke1 <= ke0 * (1 + ENERGY_RTOL),
                        warnings=warnings, roots=roots)
