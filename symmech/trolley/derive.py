"""Layer 1: derivations for the rigid trolley on a curved track (seed 002).

Frames are *passive*: ``Lambda`` maps fixed-frame components (O*X1X2X3, X2 up)
to moving-frame components (Ox1x2x3, x1 along the tangent). Angles are the
paper's aircraft angles θ1 (roll), θ2 (yaw, about X2), θ3 (pitch), applied in
the order θ2 -> θ3 -> θ1.

Quantities "per unit length" are derivatives with respect to the arc length s
of the midline: the angular velocity is ω = V0 Ω, its rate ω̇ = V̇0 Ω + V0² Ω'.
"""
from __future__ import annotations

import sympy as sp

from symmech.core import kinematics as kin
from symmech.core.derivation import ModuleSpec, NamedMatrix, args_of

ROLE = "derivation"  # found by symmech.core.discovery

SOURCE = "seed 002, Gnezdilov & Russkikh (2016), rigid trolley on a two-rail track"

th1, th2, th3 = sp.symbols("th1 th2 th3", real=True)
dth1, dth2, dth3 = sp.symbols("dth1 dth2 dth3", real=True)
ddth1, ddth2, ddth3 = sp.symbols("ddth1 ddth2 ddth3", real=True)
THETA = (th1, th2, th3)
DTHETA = (dth1, dth2, dth3)
DDTHETA = (ddth1, ddth2, ddth3)

ANGLE_ARGS = args_of([
    (th1, "roll θ1 (twist of the cross-section about the tangent)", "rad"),
    (th2, "yaw θ2 (about the fixed vertical X2)", "rad"),
    (th3, "pitch θ3 (slope of the tangent)", "rad"),
])
DANGLE_ARGS = args_of([(d, f"dθ{i + 1}/ds", "rad/m") for i, d in enumerate(DTHETA)])
DDANGLE_ARGS = args_of([(d, f"d²θ{i + 1}/ds²", "rad/m^2") for i, d in enumerate(DDTHETA)])


def rotation_matrix() -> sp.Matrix:
    """Λ(θ1, θ2, θ3) = R1(θ1) R3(θ3) R2(θ2): yaw, then pitch, then roll."""
    return kin.sequence((1, 2, 0), (th2, th3, th1), kin.SYMPY)


def angular_velocity_matrix() -> sp.Matrix:
    """A with ω = A θ̇: each rate about its own intermediate axis, in moving components."""
    r1, r3 = kin.elementary(0, th1, kin.SYMPY), kin.elementary(2, th3, kin.SYMPY)
    e = sp.eye(3)
    return sp.Matrix.hstack(e[:, 0], r1 * r3 * e[:, 1], r1 * e[:, 2])


def angles_from_tangent():
    """θ2, θ3 and their first two s-derivatives from the unit tangent dX0/ds.

    The tangent relations dX01/ds = c2 c3, dX02/ds = s3, dX03/ds = -s2 c3 invert
    to θ3 = asin(t2), θ2 = atan2(-t3, t1) (singular where the tangent is vertical).
    """
    s = sp.Symbol("s", real=True)
    names = ("t1 t2 t3", "dt1 dt2 dt3", "ddt1 ddt2 ddt3")
    t, dt, ddt = (sp.symbols(n, real=True) for n in names)
    f = [sp.Function(f"T{i}")(s) for i in range(3)]
    angle3 = sp.asin(f[1])
    angle2 = sp.atan2(-f[2], f[0])
    subs = {}
    for i in range(3):
        subs[f[i].diff(s, 2)] = ddt[i]
    for i in range(3):
        subs[f[i].diff(s)] = dt[i]
    for i in range(3):
        subs[f[i]] = t[i]
    rows = [angle2, angle3, angle2.diff(s), angle3.diff(s), angle2.diff(s, 2), angle3.diff(s, 2)]
    matrix = sp.Matrix([r.subs(subs) for r in rows])
    args = args_of([(v, f"{kind} of the unit tangent component {i + 1}", unit)
                    for kind, vec, unit in (("value", t, "1"), ("d/ds", dt, "1/m"), ("d²/ds²", ddt, "1/m^2"))
                    for i, v in enumerate(vec)])
    return NamedMatrix(
        "angles_from_tangent", matrix, args,
        "[θ2, θ3, dθ2/ds, dθ3/ds, d²θ2/ds², d²θ3/ds²] from the unit tangent and its derivatives",
        "rad, rad/m, rad/m^2", "tangent relations dX0/ds = Λᵀ e1")


def _vec_args(prefix: str, meaning: str, unit: str):
    syms = sp.symbols(f"{prefix}1 {prefix}2 {prefix}3", real=True)
    return syms, args_of([(s, f"{meaning}, component {i + 1}", unit) for i, s in enumerate(syms)])


def point_coefficients() -> NamedMatrix:
    """α, β with V = V0 α and a = V̇0 α + V0² β for a point r fixed in the body frame.

    e is the direction of the velocity of O in body components, e' its s-derivative
    (body components), Ω the angular velocity per unit length and Ω' its s-derivative.
    From V = V0 + ω × r, a = a0 + ω̇ × r + ω × (ω × r), a0 = V̇0 + ω × V0.
    """
    e, e_args = _vec_args("e", "direction of the velocity of O (body frame)", "1")
    de, de_args = _vec_args("de", "d/ds of the velocity direction of O (body frame)", "1/m")
    w, w_args = _vec_args("W", "angular velocity per unit length Ω", "rad/m")
    dw, dw_args = _vec_args("dW", "dΩ/ds", "rad/m^2")
    r, r_args = _vec_args("r", "body point in the body frame", "m")
    e, de, w, dw, r = (sp.Matrix(v) for v in (e, de, w, dw, r))
    alpha = e + w.cross(r)
    beta = de + w.cross(e) + dw.cross(r) + w.cross(w.cross(r))
    return NamedMatrix(
        "point_coefficients", sp.Matrix.vstack(alpha, beta),
        e_args + de_args + w_args + dw_args + r_args,
        "[α; β]: velocity V = V0 α and acceleration a = V̇0 α + V0² β of a body point",
        "1 (α), 1/m (β)", "V, a0, a (before (1)); ω = A dθ/ds V0")


def reactions(gravity: bool) -> NamedMatrix:
    """Reactions P0…P5 from the rigid-body equations (11).

    Body of mass m with centre of mass at r (body frame) and central inertia I.
    Contact points and directions (body frame, origin O on the midline):
    P0 at O along x1 (traction), P4 at O along x3, P1 at B = (0, 0, -a) along x2,
    P2 at C = (0, 0, +a) along x2, P3 and P5 at A = (l, 0, 0) along x2 and x3.
    """
    m, g0, l, ah = sp.symbols("m g0 l ah", positive=True)
    r, r_args = _vec_args("r", "centre of mass of the body", "m")
    acc, acc_args = _vec_args("acc", "acceleration of the centre of mass (body frame)", "m/s^2")
    w, w_args = _vec_args("w", "angular velocity ω (body frame)", "rad/s")
    dw, dw_args = _vec_args("dw", "angular acceleration ω̇ (body frame)", "rad/s^2")
    nu, nu_args = _vec_args("nu", "upward unit vector ν = Λ [0 1 0]ᵀ (body frame)", "1")
    inertia = sp.symbols("I11 I22 I33 I12 I23 I13", real=True)
    icm = kin.inertia_matrix(inertia, kin.SYMPY)
    r, acc, w, dw, nu = (sp.Matrix(v) for v in (r, acc, w, dw, nu))
    # (11) with L0 = m r, I00 = Icm + m(|r|² E - r rᵀ), a0 eliminated through the
    # acceleration of the centre of mass; gravity P_g = -g0 m ν, M_g = r × P_g.
    force = m * acc
    moment = r.cross(m * acc) + icm * dw + w.cross(icm * w)
    if gravity:
        force += m * g0 * nu
        moment += r.cross(m * g0 * nu)
    p = sp.symbols("P0:6")
    points = {0: (0, 0, 0), 1: (0, 0, -ah), 2: (0, 0, ah), 3: (l, 0, 0), 4: (0, 0, 0), 5: (l, 0, 0)}
    axes = {0: 0, 1: 1, 2: 1, 3: 1, 4: 2, 5: 2}
    f_sum, m_sum = sp.zeros(3, 1), sp.zeros(3, 1)
    for k in range(6):
        fk = sp.zeros(3, 1)
        fk[axes[k]] = p[k]
        f_sum += fk
        m_sum += sp.Matrix(points[k]).cross(fk)
    solution = sp.solve(list(f_sum - force) + list(m_sum - moment), p, dict=True)[0]
    args = args_of([(m, "mass of the body", "kg")]) + r_args + args_of(
        [(s, f"central inertia {s.name[1:]}", "kg m^2") for s in inertia]) + acc_args + w_args + dw_args
    if gravity:
        args += nu_args + args_of([(g0, "gravitational acceleration", "m/s^2")])
    args += args_of([(l, "axle distance OA", "m"), (ah, "half track gauge OB = OC", "m")])
    return NamedMatrix(
        "reactions" if gravity else "reactions_no_gravity",
        sp.Matrix([solution[pk] for pk in p]), args,
        "reactions P0…P5 of the track on the trolley" + ("" if gravity else " without gravity"),
        "N", "(11)")


RIGID_BODY_ARGS_DOC = (("r", "centre of mass from O (body frame)", "m"),
                       ("a0", "acceleration of the reference point O (body frame)", "m/s^2"),
                       ("w", "angular velocity ω (body frame)", "rad/s"),
                       ("dw", "angular acceleration ω̇ (body frame)", "rad/s^2"))


def rigid_body_args():
    """Symbols and arguments (m, r, central inertia, a0, ω, ω̇) shared by (11) as printed and as derived."""
    m = sp.Symbol("m", positive=True)
    vecs = [_vec_args(*doc) for doc in RIGID_BODY_ARGS_DOC]
    inertia = sp.symbols("I11 I22 I33 I12 I23 I13", real=True)
    args = args_of([(m, "mass of the body", "kg")]) + vecs[0][1] + args_of(
        [(s, f"central inertia {s.name[1:]}", "kg m^2") for s in inertia])
    for _, a in vecs[1:]:
        args += a
    icm = kin.inertia_matrix(inertia, kin.SYMPY)
    r, a0, w, dw = (sp.Matrix(v) for v, _ in vecs)
    return m, r, icm, a0, w, dw, args


def newton_euler() -> NamedMatrix:
    """Force and moment about O that move the body, from Newton's and Euler's laws for the centre of
    mass: F = m a_c with a_c = a0 + ω̇ × r + ω × (ω × r); M_O = r × F + I_c ω̇ + ω × I_c ω."""
    m, r, icm, a0, w, dw, args = rigid_body_args()
    force = m * (a0 + dw.cross(r) + w.cross(w.cross(r)))
    moment = r.cross(force) + icm * dw + w.cross(icm * w)
    return NamedMatrix("newton_euler", sp.Matrix.vstack(force, moment), args,
                       "[P; M]: resultant force and moment about O of the rigid body (Newton-Euler)", "N, N m",
                       "(11)")


def chord_coefficients() -> NamedMatrix:
    """[l_i0, l_i1, l_i2, l_i3] of (14): Λ̄ ΔR̄ = [l, 0, 0]ᵀ to first order in Δθ."""
    dX, dX_args = _vec_args("dX", "chord ΔR̄ = R0(s_A) - R0(s_O) (fixed frame)", "m")
    lam = rotation_matrix()
    dx = sp.Matrix(dX)
    cols = [lam * dx] + [lam.diff(t) * dx for t in THETA]
    return NamedMatrix("chord_coefficients", sp.Matrix.hstack(*cols), ANGLE_ARGS + dX_args,
                       "coefficients l_ij of the linear system for Δθ", "m", "(14)")


def lambda_bar_linear() -> NamedMatrix:
    """Λ̄ = Λ + Σ ∂Λ/∂θi Δθi (13)."""
    d = sp.symbols("dlt1 dlt2 dlt3", real=True)
    lam = rotation_matrix()
    bar = lam + sum((lam.diff(t) * di for t, di in zip(THETA, d)), sp.zeros(3, 3))
    args = ANGLE_ARGS + args_of([(di, f"small angle Δθ{i + 1}", "rad") for i, di in enumerate(d)])
    return NamedMatrix("Lambda_bar_linear", bar, args, "Λ̄ to first order in Δθ", "1", "(13)")


def rodrigues() -> NamedMatrix:
    """Λ* = Rᵀ, R the rotation by Ψ about the unit axis ξ (passive form, as in the paper)."""
    psi = sp.Symbol("psi", real=True)
    xi, xi_args = _vec_args("xi", "unit rotation axis ξ (moving frame)", "1")
    active = kin.rodrigues(xi, psi, kin.SYMPY)
    args = args_of([(psi, "rotation angle Ψ", "rad")]) + xi_args
    return NamedMatrix("rodrigues", active.T, args, "Λ* by Rodrigues' formula", "1", "Λ* (helix example)")


def chord_rotation() -> NamedMatrix:
    """Λ* turning x1 onto the unit chord direction ρ (moving frame) by the smallest rotation.

    R = E + ǩ + ǩ²/(1 + ρ1), k = e1 × ρ: Rodrigues with ξ = k/|k|, sin Ψ = |k|,
    cos Ψ = ρ1, written without dividing by sin Ψ so it stays smooth on straight track.
    """
    rho, rho_args = _vec_args("rho", "unit chord direction O->A (moving frame)", "1")
    k = sp.Matrix([0, -rho[2], rho[1]])
    K = kin.skew(k, kin.SYMPY)
    active = sp.eye(3) + K + K * K / (1 + rho[0])
    return NamedMatrix("chord_rotation", active.T, rho_args,
                       "Λ* (x -> x̄) turning x1 onto the chord", "1", "Λ* = Λ̄ Λᵀ")


def omega_functions() -> list[NamedMatrix]:
    a = angular_velocity_matrix()
    dtheta = sp.Matrix(DTHETA)
    rate_a = sum((a.diff(t) * d for t, d in zip(THETA, DTHETA)), sp.zeros(3, 3))
    omega = NamedMatrix("omega_per_length", a * dtheta, ANGLE_ARGS + DANGLE_ARGS,
                        "Ω = A dθ/ds (ω = V0 Ω)", "rad/m", "ω = A dθ/ds |V0|")
    omega_rate = NamedMatrix("omega_per_length_rate", rate_a * dtheta + a * sp.Matrix(DDTHETA),
                             ANGLE_ARGS + DANGLE_ARGS + DDANGLE_ARGS,
                             "dΩ/ds = dA/ds dθ/ds + A d²θ/ds²", "rad/m^2", "ω̇ along the track")
    return [omega, omega_rate]


def reactions_along_track() -> NamedMatrix:
    """P0…P5 straight from the angles θ, their s-derivatives and V0, V̇0: the chain Ω, Ω' ->
    point coefficients (e = x1, e' = 0: O moves along the tangent) -> a, ω, ω̇, ν = Λ e2 ->
    reactions (11), substituted into one expression so the emitter's CSE spans the whole
    chain and no numpy glue runs between generated calls."""
    v0, dv0 = sp.symbols("V0 dV0", real=True)
    omega, omega_rate = (sp.Matrix(nm.matrix) for nm in omega_functions())
    coef = point_coefficients()
    fill = dict(zip([a.symbol for a in coef.args[:6]], (1, 0, 0, 0, 0, 0)))
    fill.update(zip([a.symbol for a in coef.args[6:12]], list(omega) + list(omega_rate)))
    alpha_beta = coef.matrix.xreplace(fill)  # r stays symbolic: the reactions' own r1..r3
    rx = reactions(True)
    acc = dv0 * alpha_beta[:3, :] + v0**2 * alpha_beta[3:, :]
    nu = rotation_matrix()[:, 1]
    values = {}
    for i in range(3):
        values[f"acc{i + 1}"], values[f"nu{i + 1}"] = acc[i], nu[i]
        values[f"w{i + 1}"], values[f"dw{i + 1}"] = v0 * omega[i], dv0 * omega[i] + v0**2 * omega_rate[i]
    by_name = {a.symbol.name: a.symbol for a in rx.args}
    r_syms = {a.symbol.name: a.symbol for a in coef.args[12:]}
    expr = rx.matrix.xreplace({by_name[k]: v.xreplace({r_syms[n]: by_name[n] for n in r_syms})
                               for k, v in values.items()})
    kept = [a for a in rx.args if a.symbol.name not in values]
    args = ANGLE_ARGS + DANGLE_ARGS + DDANGLE_ARGS + args_of([
        (v0, "speed V0 of O along the midline", "m/s"), (dv0, "dV0/dt", "m/s^2")]) + tuple(kept)
    return NamedMatrix("reactions_along_track", expr, args,
                       "reactions P0…P5 from θ, dθ/ds, d²θ/ds², V0, V̇0 (the chain fused)", "N",
                       "(11) with ω = V0 A dθ/ds")


def module_specs() -> list[ModuleSpec]:
    lam = rotation_matrix()
    frame = [NamedMatrix("Lambda", lam, ANGLE_ARGS, "rotation matrix Λ (fixed -> moving)", "1", "Λ")]
    frame += [NamedMatrix(f"dLambda_dth{i + 1}", lam.diff(t), ANGLE_ARGS,
                          f"∂Λ/∂θ{i + 1}", "1/rad", "(13)") for i, t in enumerate(THETA)]
    frame += [NamedMatrix("A", angular_velocity_matrix(), ANGLE_ARGS, "A with ω = A θ̇", "1", "ω = A θ̇")]
    frame += omega_functions()
    frame += [angles_from_tangent(), chord_coefficients(), lambda_bar_linear(), rodrigues(), chord_rotation()]
    dynamics = [point_coefficients(), reactions(True), reactions(False), newton_euler(), reactions_along_track()]
    return [
        ModuleSpec("trolley_frame", "Frames, angles and angular velocity of the trolley along the track.",
                   SOURCE, frame),
        ModuleSpec("trolley_dynamics", "Body-point kinematics and the reactions P0…P5 of the rigid trolley.",
                   SOURCE, dynamics),
    ]
