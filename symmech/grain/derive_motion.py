"""Layer 1: derivations for the grain's motion between and along impacts (paper 1, eqs (61)-(64)).

Frames. KXYZ is the surface frame: X the longitudinal axis of the working surface,
Y the transverse axis, Z the outward normal. The frame translates with the surface
(harmonic vibration) and does not rotate, so relative motion obeys
r'' = g_K - a_s(t) (+ contact forces).

Inclination, defined unambiguously: alpha is the angle by which the X axis rises
above the horizontal plane, beta the angle by which the Y axis rises above it
(positive: the axis points uphill). The unit vertical u (upwards) therefore has
u.e_X = sin(alpha), u.e_Y = sin(beta), and, being a unit vector with u.e_Z > 0,
u.e_Z = sqrt(1 - sin^2 alpha - sin^2 beta) = cos(delta), delta the angle of
steepest slope. Gravity in KXYZ is g_K = -g u.

Orientation: unit quaternion (q0, q1, q2, q3) with body axes as the columns of
Q(q) in KXYZ (no Euler-angle singularity); the paper's z-x-z Euler angles
Q = Rz(psi) Rx(theta) Rz(phi) are derived here too, for paper mode.
"""
from __future__ import annotations

import sympy as sp

from symmech.core import kinematics as kin
from symmech.core.derivation import Arg, Dynamics, Event, ModuleSpec, NamedMatrix, args_of

ROLE = "derivation"  # found by symmech.core.discovery

g = sp.Symbol("g", positive=True)
alpha, beta = sp.symbols("alpha beta", real=True)
A, phase, t, t0 = sp.symbols("A phase t t0", real=True)
omega = sp.Symbol("omega", positive=True)
dX, dY, dZ = sp.symbols("dX dY dZ", real=True)
a, b, c = sp.symbols("a b c", positive=True)
q0, q1, q2, q3 = sp.symbols("q0 q1 q2 q3", real=True)
I1, I2, I3 = sp.symbols("I1 I2 I3", positive=True)
w1, w2, w3 = sp.symbols("w1 w2 w3", real=True)
psi, theta, phi = sp.symbols("psi theta phi", real=True)
psi_d, theta_d, phi_d = sp.symbols("psi_d theta_d phi_d", real=True)
x0, y0, z0, vx0, vy0, vz0 = sp.symbols("rx0 ry0 rz0 vx0 vy0 vz0", real=True)
rx, ry, rz, vx, vy, vz = sp.symbols("rx ry rz vx vy vz", real=True)
gX, gY, gZ = sp.symbols("gX gY gZ", real=True)
n1, n2, n3 = sp.symbols("n1 n2 n3", real=True)

_G = [(g, "gravitational acceleration", "m/s^2")]
_INCL = [(alpha, "rise of the surface X axis above the horizontal", "rad"),
         (beta, "rise of the surface Y axis above the horizontal", "rad")]
VIBRATION_ARGS = [(A, "vibration amplitude", "m"), (omega, "vibration angular frequency", "rad/s"),
        (phase, "vibration phase at t = 0", "rad"),
        (dX, "vibration direction, X component (unit vector)", "1"),
        (dY, "vibration direction, Y component (unit vector)", "1"),
        (dZ, "vibration direction, Z component (unit vector)", "1")]
AXES_ARGS = [(a, "semi-axis along body axis 1", "m"), (b, "semi-axis along body axis 2", "m"),
         (c, "semi-axis along body axis 3", "m")]
_QUAT = [(q0, "orientation quaternion, scalar part", "1"),
         (q1, "orientation quaternion, x part", "1"),
         (q2, "orientation quaternion, y part", "1"),
         (q3, "orientation quaternion, z part", "1")]
_NORMAL = [(n1, "plane normal in body axes, component 1 (third row of Q)", "1"),
           (n2, "plane normal in body axes, component 2", "1"),
           (n3, "plane normal in body axes, component 3", "1")]
INERTIA_ARGS = [(I1, "principal moment of inertia, body axis 1", "kg*m^2"),
            (I2, "principal moment of inertia, body axis 2", "kg*m^2"),
            (I3, "principal moment of inertia, body axis 3", "kg*m^2")]
_RATES = [(w1, "angular velocity, body axis 1", "rad/s"), (w2, "angular velocity, body axis 2", "rad/s"),
          (w3, "angular velocity, body axis 3", "rad/s")]
_EULER = [(psi, "precession angle", "rad"), (theta, "nutation angle", "rad"), (phi, "spin angle", "rad")]
_STATE0 = [(x0, "relative centre position X at t0", "m"), (y0, "relative centre position Y at t0", "m"),
           (z0, "relative centre position Z at t0", "m"), (vx0, "relative centre velocity X at t0", "m/s"),
           (vy0, "relative centre velocity Y at t0", "m/s"), (vz0, "relative centre velocity Z at t0", "m/s")]
GRAVITY_ARGS = [(gX, "gravity in KXYZ, X component", "m/s^2"), (gY, "gravity in KXYZ, Y component", "m/s^2"),
       (gZ, "gravity in KXYZ, Z component", "m/s^2")]
_TIMES = [(t0, "start time of the flight", "s"), (t, "time", "s")]
STATE_ARGS = [(rx, "relative centre position X", "m"), (ry, "relative centre position Y", "m"),
          (rz, "relative centre position Z", "m"), (vx, "relative centre velocity X", "m/s"),
          (vy, "relative centre velocity Y", "m/s"), (vz, "relative centre velocity Z", "m/s")] + _QUAT + _RATES


def gravity_surface_frame() -> sp.Matrix:
    """g_K (3,) from the definition of alpha, beta: -g times the unit upward vertical in KXYZ."""
    ux, uy = sp.sin(alpha), sp.sin(beta)
    uz = sp.Symbol("uz", positive=True)
    # The vertical is a unit vector with positive normal component: solve |u| = 1 for uz.
    (uz_value,) = sp.solve(sp.Eq(ux**2 + uy**2 + uz**2, 1), uz)
    return -g * sp.Matrix([ux, uy, uz_value])


def surface_displacement() -> sp.Matrix:
    """Surface displacement s(t) = A d sin(omega t + phase), (3,) m."""
    return A * sp.Matrix([dX, dY, dZ]) * sp.sin(omega * t + phase)


def surface_kinematics() -> sp.Matrix:
    """Rows: displacement, velocity, acceleration of the surface frame, (3, 3)."""
    s = surface_displacement()
    return sp.Matrix.vstack(s.T, s.diff(t).T, s.diff(t, 2).T)


def flight_translation(vibration: bool) -> sp.Matrix:
    """Exact relative flight of the centre: solve r'' = g_K - s''(t) from (r0, v0) at t0.

    Rows: relative position, relative velocity at time t, (2, 3).
    """
    r0 = sp.Matrix([x0, y0, z0])
    v0 = sp.Matrix([vx0, vy0, vz0])
    gk = sp.Matrix([gX, gY, gZ])
    tau = sp.Symbol("tau", real=True)
    s = surface_displacement() if vibration else sp.zeros(3, 1)
    acc = gk - s.diff(t, 2)
    # Integrate twice in closed form (the forcing is a polynomial plus a harmonic).
    vel = v0 + (acc.subs(t, tau)).applyfunc(lambda e: sp.integrate(e, (tau, t0, t)))
    pos = r0 + (vel.subs(t, tau)).applyfunc(lambda e: sp.integrate(e, (tau, t0, t)))
    return sp.Matrix.vstack(pos.T, vel.T)


def quaternion_matrix() -> sp.Matrix:
    """Rotation matrix Q(q) of a unit quaternion, body axes as columns, (3, 3)."""
    return sp.Matrix([
        [1 - 2 * (q2**2 + q3**2), 2 * (q1 * q2 - q0 * q3), 2 * (q1 * q3 + q0 * q2)],
        [2 * (q1 * q2 + q0 * q3), 1 - 2 * (q1**2 + q3**2), 2 * (q2 * q3 - q0 * q1)],
        [2 * (q1 * q3 - q0 * q2), 2 * (q2 * q3 + q0 * q1), 1 - 2 * (q1**2 + q2**2)],
    ])


def support_distance() -> sp.Matrix:
    """Height of the centre above the plane at contact, |D n'|, (1,) m.

    n' = Q^T e_z is the plane normal in body axes (the third row of Q); the support
    function of the ellipsoid x^T D^-2 x = 1 in direction n' is |D n'|.
    """
    d = sp.diag(a, b, c) * sp.Matrix([n1, n2, n3])
    return sp.Matrix([sp.sqrt((d.T * d)[0, 0])])


def contact_offset_body() -> sp.Matrix:
    """Offset of the lowest point from the centre in body axes, R' = -D^2 n' / |D n'|, (3,) m.

    The lowest point maximises -n'.x on the ellipsoid: the gradient D^-2 x is parallel to -n'.
    """
    return -sp.diag(a**2, b**2, c**2) * sp.Matrix([n1, n2, n3]) / support_distance()[0]


def euler_equations() -> sp.Matrix:
    """Torque-free Euler equations: body angular acceleration (3,) rad/s^2.

    From dL/dt = 0 in the body frame: I w' + w x (I w) = 0.
    """
    I = sp.diag(I1, I2, I3)
    w = sp.Matrix([w1, w2, w3])
    return -I.inv() * w.cross(I * w)


def quaternion_rate() -> sp.Matrix:
    """q' = q (x) (0, w)/2 for body-frame angular velocity w, (4,) 1/s."""
    qv = sp.Matrix([q1, q2, q3])
    w = sp.Matrix([w1, w2, w3])
    scalar = -qv.dot(w) / 2
    vector = (q0 * w + qv.cross(w)) / 2
    return sp.Matrix([scalar, *vector])


def invariants() -> sp.Matrix:
    """Rotational kinetic energy [J] and angular momentum in KXYZ [kg*m^2/s], (4,)."""
    I = sp.diag(I1, I2, I3)
    w = sp.Matrix([w1, w2, w3])
    energy = (w.T * I * w)[0, 0] / 2
    L = quaternion_matrix() * I * w
    return sp.Matrix([energy, *L])


def euler_matrix() -> sp.Matrix:
    """Q = Rz(psi) Rx(theta) Rz(phi) (active rotations), body axes as columns, (3, 3)."""
    return kin.sequence((2, 0, 2), (psi, theta, phi), kin.SYMPY, passive=False)


def body_rates_from_euler_rates() -> sp.Matrix:
    """Body rates (p, q, r) from Euler-angle rates: the 3x3 matrix B with (p,q,r) = B (psi', theta', phi').

    Derived from Q^T Q' = [w]x, not typed in; the generated function returns B.
    """
    tt = sp.Symbol("tt", real=True)
    fs = [sp.Function(n)(tt) for n in ("psi", "theta", "phi")]
    Qt = euler_matrix().subs({psi: fs[0], theta: fs[1], phi: fs[2]})
    W = Qt.T * Qt.diff(tt)
    w = kin.vee(W, kin.SYMPY)
    rates = [f.diff(tt) for f in fs]
    B = w.jacobian(rates)
    back = {fs[0]: psi, fs[1]: theta, fs[2]: phi}
    return B.subs(back).applyfunc(_pythagoras)


def _pythagoras(expr):
    """Expand and use sin^2 = 1 - cos^2 for the Euler angles (cheap, exact, deterministic)."""
    expr = sp.expand(expr)
    for angle in (psi, theta, phi):
        expr = sp.expand(expr.subs(sp.sin(angle) ** 2, 1 - sp.cos(angle) ** 2))
    return expr


def euler_rates_from_body_rates() -> sp.Matrix:
    """(psi', theta', phi') = B^-1 (p, q, r); B is 3x3 with det B = sin(theta), singular at gimbal lock."""
    B = body_rates_from_euler_rates()
    # Adjugate over determinant: both small after the Pythagorean reduction.
    det = _pythagoras(B.det())
    return ((B.adjugate().applyfunc(_pythagoras) * sp.Matrix([w1, w2, w3])) / det).applyfunc(sp.cancel)


def contact_gap() -> sp.Expr:
    """Height of the ellipsoid's lowest point above the plane Z = 0, rz - |D n'| [m] (eq (63)), n' the third
    row of Q(q / |q|): exact also for a quaternion that drifted off unit length in an integration."""
    norm = sp.sqrt(q0**2 + q1**2 + q2**2 + q3**2)
    n_body = quaternion_matrix().row(2).subs({q: q / norm for q in (q0, q1, q2, q3)}, simultaneous=True)
    return rz - support_distance()[0].subs(dict(zip((n1, n2, n3), n_body)))


m = sp.Symbol("m", positive=True)
e_n, e_t, mu = sp.symbols("e_n e_t mu", real=True)
K_ENTRIES = sp.symbols("k0:9", real=True)
u0, u1, u2 = sp.symbols("u0 u1 u2", real=True)
P0, P1, P2 = sp.symbols("P0 P1 P2", real=True)
P_I, D0, D1, D2 = sp.symbols("P_I D0 D1 D2", real=True)
_MASS = [(m, "grain mass", "kg")]
_LAW = [(e_n, "normal restitution coefficient", "1"), (e_t, "tangential restitution coefficient", "1"),
        (mu, "impact friction coefficient", "1")]
_K = [(k, f"inverse effective mass at the contact, entry {i // 3 + 1}{i % 3 + 1}", "1/kg")
      for i, k in enumerate(K_ENTRIES)]
_U = [(u, f"contact point velocity before the impact, {x}", "m/s") for u, x in zip((u0, u1, u2), "XYZ")]
_P = [(P, f"impulse on the grain at the contact, {x}", "N*s") for P, x in zip((P0, P1, P2), "XYZ")]
_PLASTIC = [(P_I, "plastic normal impulse", "N*s")] + [
    (d, f"plastic sticking impulse beyond it, {x}", "N*s") for d, x in zip((D0, D1, D2), "XYZ")]


def _skew(r: sp.Matrix) -> sp.Matrix:
    return sp.Matrix([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])


def _contact_frame() -> tuple[sp.Matrix, sp.Matrix, sp.Matrix, sp.Matrix]:
    """At the state (q, w): Q of q / |q| (3, 3), the offset R (3,) [m] of the lowest point from the centre in
    KXYZ, the inverse inertia in KXYZ (3, 3) [1/(kg m^2)] and w in KXYZ (3,) [rad/s]."""
    norm = sp.sqrt(q0**2 + q1**2 + q2**2 + q3**2)
    Q = quaternion_matrix().subs({q: q / norm for q in (q0, q1, q2, q3)}, simultaneous=True)
    R = Q * contact_offset_body().subs(dict(zip((n1, n2, n3), Q.row(2))))
    return Q, R, Q * sp.diag(1 / I1, 1 / I2, 1 / I3) * Q.T, Q * sp.Matrix([w1, w2, w3])


def impact_contact() -> sp.Matrix:
    """The lowest point's inverse effective mass K = 1/m - [R]x I_w^-1 [R]x (row by row, 9 entries) [1/kg] and
    its velocity u = v + w x R (3) [m/s], (12,): what the impact law reads."""
    _, R, inv_inertia, w = _contact_frame()
    K = sp.eye(3) / m - _skew(R) * inv_inertia * _skew(R)
    return sp.Matrix([*K, *(sp.Matrix([vx, vy, vz]) + w.cross(R))])


def plastic_impulse() -> sp.Matrix:
    """The impulses (4,) [N s] of a perfectly plastic impact at a contact of inverse effective mass K (3, 3)
    [1/kg] hit at the velocity u (3,) [m/s]: the normal one P_I = -u_z / K_zz (along e_z) and the sticking
    remainder D = -K^-1 u - P_I e_z (3) that stops the point."""
    K, u = sp.Matrix(3, 3, K_ENTRIES), sp.Matrix([u0, u1, u2])
    normal = -u2 / K[2, 2]
    return sp.Matrix([normal, *(-(K.adjugate() * u) / K.det() - sp.Matrix([0, 0, normal]))])


def coulomb_impulse() -> sp.Matrix:
    """Chatterjee and Ruina's impulse P (3,) [N s] from the plastic impulses (:func:`plastic_impulse`):
    P = (1 + e_n) P_I e_z + s D, s = 1 + e_t inside the friction cone and, outside it, the s that puts P on the
    cone |P_t| = mu P_z. No impulse where the point does not approach the plane (u_z >= 0)."""
    D = sp.Matrix([D0, D1, D2])
    normal = (1 + e_n) * P_I
    slope = sp.sqrt(D0**2 + D1**2) - mu * D2
    s = sp.Piecewise((mu * normal / slope, (1 + e_t) * slope > mu * normal), (1 + e_t, True))
    return (sp.Matrix([0, 0, normal]) + s * D).applyfunc(lambda x: sp.Piecewise((x, u2 < 0), (0, True)))


def impact_state() -> sp.Matrix:
    """The state (13,) just after the impulse P (3,) [N s] at the lowest point: position and orientation kept,
    v + P / m, w + I^-1 (R x P) in body axes."""
    Q, R, inv_inertia, w = _contact_frame()
    P = sp.Matrix([P0, P1, P2])
    v_after = sp.Matrix([vx, vy, vz]) + P / m
    return sp.Matrix([rx, ry, rz, *v_after, q0, q1, q2, q3, *(Q.T * (w + inv_inertia * R.cross(P)))])


def flight_dynamics() -> Dynamics:
    """Flight of the rigid grain as an ODE in KXYZ: r' = v, v' = g_K - s''(t), q' = q (x) (0, w)/2,
    I w' = -w x I w, ending where the ellipsoid touches the plane (the terminal event ``contact``: the gap
    falls through zero). The run integrates the same equations (translation in closed form). The semi-axes
    enter the event only."""
    acceleration = sp.Matrix([gX, gY, gZ]) - surface_displacement().diff(t, 2)
    rate = sp.Matrix.vstack(sp.Matrix([vx, vy, vz]), acceleration, quaternion_rate(), euler_equations())
    contact = Event("contact", contact_gap(), "gap between the ellipsoid's lowest point and the plane", "m",
                    direction=-1, terminal=True)
    return Dynamics(args_of(STATE_ARGS), args_of(GRAVITY_ARGS + VIBRATION_ARGS + INERTIA_ARGS + AXES_ARGS), rate, time=Arg(t, "time", "s"),
                    meaning="the grain in flight over the vibrating surface (eqs (61)-(62))", events=(contact,))


def module_specs() -> list[ModuleSpec]:
    t_args = args_of(VIBRATION_ARGS + [(t, "time", "s")])
    flight_args = args_of(_STATE0 + GRAVITY_ARGS + VIBRATION_ARGS + _TIMES)
    rigid_args = args_of(_STATE0 + GRAVITY_ARGS + _TIMES)
    functions = [
        NamedMatrix("gravity", gravity_surface_frame(), args_of(_G + _INCL),
                    "gravity components in the surface frame KXYZ", "m/s^2", "61"),
        NamedMatrix("surface_kinematics", surface_kinematics(), t_args,
                    "surface displacement, velocity and acceleration (rows)", "m, m/s, m/s^2", "61"),
        NamedMatrix("flight_translation", flight_translation(True), flight_args,
                    "exact relative flight of the centre in the vibrating frame: position, velocity (rows)",
                    "m, m/s", "61"),
        NamedMatrix("flight_translation_rigid", flight_translation(False), rigid_args,
                    "exact relative flight of the centre over a still surface: position, velocity (rows)",
                    "m, m/s", "61"),
        NamedMatrix("rotation_matrix", quaternion_matrix(), args_of(_QUAT),
                    "rotation matrix of a unit quaternion, body axes as columns in KXYZ", "1"),
        NamedMatrix("support_distance", support_distance(), args_of(AXES_ARGS + _NORMAL),
                    "centre height above the plane when the ellipsoid touches it", "m", "63"),
        NamedMatrix("contact_offset_body", contact_offset_body(), args_of(AXES_ARGS + _NORMAL),
                    "offset of the lowest point of the ellipsoid from its centre, in body axes", "m", "63"),
        NamedMatrix("euler_equations", euler_equations(), args_of(INERTIA_ARGS + _RATES),
                    "torque-free Euler equations: body angular acceleration", "rad/s^2", "62"),
        NamedMatrix("quaternion_rate", quaternion_rate(), args_of(_QUAT + _RATES),
                    "quaternion rate for body-frame angular velocity", "1/s", "62"),
        NamedMatrix("rotation_invariants", invariants(), args_of(INERTIA_ARGS + _RATES + _QUAT),
                    "rotational kinetic energy and angular momentum in KXYZ", "J, kg*m^2/s"),
        NamedMatrix("body_rates", body_rates_from_euler_rates() * sp.Matrix([psi_d, theta_d, phi_d]),
                    args_of(_EULER + [(psi_d, "precession rate", "rad/s"), (theta_d, "nutation rate", "rad/s"),
                                      (phi_d, "spin rate", "rad/s")]),
                    "body angular velocity (p, q, r) from Euler-angle rates", "rad/s", "43"),
        NamedMatrix("euler_rates", euler_rates_from_body_rates(), args_of(_EULER + _RATES),
                    "Euler-angle rates (psi', theta', phi') from body rates", "rad/s", "62"),
        NamedMatrix("impact_contact", impact_contact(), args_of(STATE_ARGS + INERTIA_ARGS + AXES_ARGS + _MASS),
                    "inverse effective mass K (row by row) and velocity u of the lowest point, KXYZ", "1/kg, m/s"),
        NamedMatrix("plastic_impulse", plastic_impulse(), args_of(_K + _U),
                    "plastic normal impulse and the sticking impulse beyond it at the contact, KXYZ", "N*s"),
        NamedMatrix("coulomb_impulse", coulomb_impulse(), args_of(_PLASTIC + [_U[2]] + _LAW),
                    "energy-consistent Coulomb impulse (Chatterjee-Ruina) at the contact, KXYZ", "N*s"),
        NamedMatrix("impact_state", impact_state(), args_of(STATE_ARGS + INERTIA_ARGS + AXES_ARGS + _MASS + _P),
                    "state just after an impulse at the lowest point", "m, m/s, 1, rad/s"),
    ]
    return [ModuleSpec("grain_motion", "Grain motion: gravity, surface vibration, exact flight, "
                       "ellipsoid support distance, torque-free rotation.",
                       "symmech.grain.derive_motion (paper 1, seed 000, eqs (61)-(64))", functions,
                       flight_dynamics())]
