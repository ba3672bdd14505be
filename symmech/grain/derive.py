"""Derivations for the impact of an ellipsoidal grain on a plane (seed 000, eqs (1)-(60)).

Conventions (stated once, used everywhere):

* Surface frame KXYZ: X, Y in the plane, Z the outward normal. Body frame
  CX'Y'Z': principal axes of the ellipsoid with semi-axes a, b, c along X', Y', Z'.
* Orientation: z-x-z Euler angles of the paper, psi (precession), theta
  (nutation), phi (spin); ``Q = Rz(psi) Rx(theta) Rz(phi)`` has the body axes as
  columns, expressed in the surface frame, so ``x_surface = Q x_body``.
* R: vector from the centre of mass C to the contact point K (the lowest point
  of the ellipsoid), surface frame.
* Impact: impulse T on the body at K; ``m (u_K - u_K(0)) = H T`` (1).

Everything here is sympy only; :func:`module_specs` hands the results to the
emitter.
"""
from __future__ import annotations

import functools

import sympy
from sympy import Matrix, cos, sin, sqrt

from symmech.core import kinematics as kin
from symmech.core.derivation import ModuleSpec, NamedMatrix, args_of
from symmech.grain import SEED

ROLE = "derivation"  # found by symmech.core.discovery

a, b, c = sympy.symbols("a b c", positive=True)
psi, theta, phi = sympy.symbols("psi theta phi", real=True)
m = sympy.Symbol("m", positive=True)
e, lam = sympy.symbols("e lambda", nonnegative=True)
# Pre-impact contact-point velocity (surface frame) and post-impact tangential speed.
ux0, uy0, uz0 = sympy.symbols("u_x0 u_y0 u_z0", real=True)
Tx, Ty, Tz, mu = sympy.symbols("T_x T_y T_z mu", real=True)
# Entries of the symmetric reduction tensor H.
hxx, hxy, hxz, hyy, hyz, hzz = sympy.symbols("h_xx h_xy h_xz h_yy h_yz h_zz", real=True)
# Principal moments of inertia and Euler-angle rates.
Jx, Jy, Jz = sympy.symbols("J_x J_y J_z", positive=True)
dtheta, dpsi, dphi = sympy.symbols("dtheta dpsi dphi", real=True)
Rb = Matrix(sympy.symbols("R_x' R_y' R_z'", real=True))  # R in body axes
Tb = Matrix(sympy.symbols("T_x' T_y' T_z'", real=True))  # T in body axes

GEOMETRY = ((a, "semi-axis along body X'", "m"), (b, "semi-axis along body Y'", "m"),
            (c, "semi-axis along body Z'", "m"), (psi, "Euler precession angle", "rad"),
            (theta, "Euler nutation angle", "rad"), (phi, "Euler spin angle", "rad"))
H_ENTRIES = tuple((h, f"reduction tensor entry {h.name[2:]}", "1")
                  for h in (hxx, hxy, hxz, hyy, hyz, hzz))
IMPACT_STATE = ((m, "mass", "kg"), (lam, "tangential reduction factor lambda", "1"),
                (e, "normal restitution coefficient", "1"),
                (ux0, "pre-impact contact-point velocity, X", "m/s"),
                (uy0, "pre-impact contact-point velocity, Y", "m/s"),
                (uz0, "pre-impact contact-point velocity, Z", "m/s"))
UNKNOWNS = ((Tx, "impulse, X", "N*s"), (Tz, "impulse, Z", "N*s"),
            (mu, "angle of the tangential impulse and velocity from X", "rad"))
R_surface = Matrix(sympy.symbols("R_x R_y R_z", real=True))  # contact offset, surface frame
v0 = Matrix(sympy.symbols("v_x0 v_y0 v_z0", real=True))  # centre velocity before the impact
A_sym = Matrix(3, 3, sympy.symbols("a11 a12 a13 a21 a22 a23 a31 a32 a33", real=True))  # (43)
b_sym = Matrix(sympy.symbols("b1 b2 b3", real=True))
R_ARGS = tuple((s, f"contact offset R, {s.name[2]}", "m") for s in R_surface)
VELOCITY_ARGS = (tuple((s, f"pre-impact centre velocity, {s.name[2]}", "m/s") for s in v0)
                 + tuple((s, f"impulse, {s.name[2]}", "N*s") for s in (Tx, Ty, Tz)) + ((m, "mass", "kg"),))
EULER_SYSTEM_ARGS = ((Jx, "principal moment of inertia about X'", "kg*m^2"),
                     (Jy, "principal moment of inertia about Y'", "kg*m^2"),
                     (Jz, "principal moment of inertia about Z'", "kg*m^2"),
                     (theta, "Euler nutation angle at the impact", "rad"),
                     (phi, "Euler spin angle at the impact", "rad"))
EULER_RHS_ARGS = (EULER_SYSTEM_ARGS
                  + tuple((s, f"contact offset R in body axes, {s.name[2]}'", "m") for s in Rb)
                  + tuple((s, f"impulse T in body axes, {s.name[2]}'", "N*s") for s in Tb)
                  + ((dtheta, "pre-impact nutation rate", "rad/s"), (dpsi, "pre-impact precession rate", "rad/s"),
                     (dphi, "pre-impact spin rate", "rad/s")))
CRAMER_ARGS = (tuple((s, f"coefficient {s.name} of (43)", "kg*m^2") for s in A_sym)
               + tuple((s, f"right-hand side {s.name} of (43)", "kg*m^2/s") for s in b_sym))


def rotation():
    """Q(psi, theta, phi): body axes as columns in the surface frame."""
    return kin.sequence((2, 0, 2), (psi, theta, phi), kin.SYMPY, passive=False)


@functools.cache
def euler_rate_matrix():
    """W(theta, phi) with body angular velocity omega' = W (theta', psi', phi').

    The rotation Q = Rz(psi) Rx(theta) Rz(phi) turns at psi' about the surface Z,
    at theta' about the line of nodes Rz(psi) e_x and at phi' about the body z';
    expressed in body axes these are Rz(phi)^T Rx(theta)^T e_z, Rz(phi)^T e_x and
    e_z. (The test suite checks W against Q^T dQ/dt by finite differences.)
    """
    e_x, e_z = Matrix([1, 0, 0]), Matrix([0, 0, 1])
    # the passive matrices are the transposes: Rz(phi)^T Rx(theta)^T = Λz(phi) Λx(theta)
    about_psi = kin.sequence((0, 2), (theta, phi), kin.SYMPY) * e_z
    about_theta = kin.elementary(2, phi, kin.SYMPY) * e_x
    return Matrix.hstack(about_theta, about_psi, e_z)


def gyration_squared():
    """Principal radii of gyration squared of a solid ellipsoid, rho_r^2 = J_r / m."""
    return Matrix([(b**2 + c**2) / 5, (a**2 + c**2) / 5, (a**2 + b**2) / 5])


def inertia_ratio():
    """P = I/m in the surface frame (11) from the principal radii: Q diag(rho^2) Q^T."""
    return kin.rotate_tensor(rotation(), sympy.diag(*gyration_squared()), kin.SYMPY)


def contact_offset():
    """R = K - C for the lowest point K of the ellipsoid (support point along -Z)."""
    Q = rotation()
    n_body = Q.T * Matrix([0, 0, 1])
    D2 = sympy.diag(a**2, b**2, c**2)
    height = sqrt((D2 * n_body.applyfunc(lambda x: x**2)).dot(Matrix([1, 1, 1])))
    return -Q * D2 * n_body / height


def contact_height():
    """Height of C above the plane when the ellipsoid touches it: |D n'|."""
    n_body = rotation().T * Matrix([0, 0, 1])
    return sqrt(a**2 * n_body[0]**2 + b**2 * n_body[1]**2 + c**2 * n_body[2]**2)


@functools.cache
def reduction_tensor():
    """H = m d(u_K)/dT from the impulse-momentum balance of a rigid body.

    m du_C = T, I dw = R x T, du_K = du_C + dw x R with I = m P; writing the
    impulse per unit mass, t = T/m, the mass drops out exactly:
    du_K = t + (P^-1 (R x t)) x R and H = d(du_K)/dt. The balance is written in
    body axes, where P = diag(rho^2) (nothing to invert) and R' = -D^2 n'/|D n'|,
    then turned to the surface frame: H = Q H' Q^T.
    """
    Q = rotation()
    n_body = Q.T * Matrix([0, 0, 1])
    D2 = sympy.diag(a**2, b**2, c**2)
    R_body = -D2 * n_body / contact_height()
    t = Matrix(sympy.symbols("t_x t_y t_z", real=True))
    inv_P = sympy.diag(*[1 / r for r in gyration_squared()])
    du_K = t + (inv_P * R_body.cross(t)).cross(R_body)
    return kin.rotate_tensor(Q, du_K.jacobian(t), kin.SYMPY)


def _h_matrix():
    return Matrix([[hxx, hxy, hxz], [hxy, hyy, hyz], [hxz, hyz, hzz]])


def _delta_uK(angle):
    """m-free velocity jump at K imposed by the impact law (14)-(17) for angle mu."""
    speed = (1 - lam) * sqrt(ux0**2 + uy0**2)
    return Matrix([speed * cos(angle) - ux0, speed * sin(angle) - uy0, -(1 + e) * uz0])


def mu_equation():
    """Fourier coefficients (k0, k1c, k1s, k2c, k2s) of the exact scalar equation F(mu) = 0.

    Eliminating T from (13)-(18): H (tau d + T_z e_z) = m du_K(mu) with
    d = (cos mu, sin mu, 0) is solvable iff det[H d, H e_z, du_K(mu)] = 0, a
    trigonometric polynomial of degree 2:
    F = k0 + k1c cos mu + k1s sin mu + k2c cos 2mu + k2s sin 2mu.
    """
    cm, sm = sympy.symbols("c_mu s_mu", real=True)
    H = _h_matrix()
    speed = (1 - lam) * sqrt(ux0**2 + uy0**2)
    du = Matrix([speed * cm - ux0, speed * sm - uy0, -(1 + e) * uz0])
    F = sympy.expand(Matrix.hstack(H * Matrix([cm, sm, 0]), H * Matrix([0, 0, 1]), du).det())
    poly = sympy.Poly(F, cm, sm)
    coeff = {k: poly.coeff_monomial(cm**k[0] * sm**k[1]) for k in
             ((0, 0), (1, 0), (0, 1), (2, 0), (0, 2), (1, 1))}
    # c^2 = (1 + cos 2mu)/2, s^2 = (1 - cos 2mu)/2, cs = sin(2mu)/2
    k0 = coeff[(0, 0)] + (coeff[(2, 0)] + coeff[(0, 2)]) / 2
    k2c = (coeff[(2, 0)] - coeff[(0, 2)]) / 2
    k2s = coeff[(1, 1)] / 2
    return Matrix([k0, coeff[(1, 0)], coeff[(0, 1)], k2c, k2s])


def system_19_residual():
    """Residuals of (19): H (T_x, T_x tan mu, T_z) - m du_K(mu), as derived from (13)-(18)."""
    T = Matrix([Tx, Tx * sympy.tan(mu), Tz])
    return _h_matrix() * T - m * _delta_uK(mu)


def descent_functional():
    """Consistent functional for the paper's descent: the sum of squared residuals of (19).

    The printed (24) sums the residuals themselves, which is unbounded below.
    """
    r = system_19_residual()
    return Matrix([r.dot(r)])


def descent_gradient():
    """Gradient of :func:`descent_functional` with respect to (T_x, T_z, mu)."""
    return descent_functional().jacobian([Tx, Tz, mu]).T


def euler_rate_system():
    """Matrix of (43): J' W(theta, phi), so that J' W x' = J' W x'(0) + R' x T' (42)."""
    return sympy.diag(Jx, Jy, Jz) * euler_rate_matrix()


def euler_rate_rhs():
    """Right-hand side b of (43): R' x T' + J' W(theta0, phi0) (theta0', psi0', phi0')."""
    rates0 = Matrix([dtheta, dpsi, dphi])
    return Rb.cross(Tb) + euler_rate_system() * rates0


def body_components(R):
    """Components in body axes of a surface-frame vector: Q^T R."""
    return rotation().T * R


def centre_velocity_after(v0, T):
    """Centre-of-mass velocity after the impact from m (u_C - u_C(0)) = T."""
    return v0 + T / m


def cramer_solution():
    """Solution of a general 3x3 system a x = b by Cramer's rule, as (58)-(60) intend."""
    det = A_sym.det()
    cols = []
    for k in range(3):
        Ak = A_sym.copy()
        Ak[:, k] = b_sym
        cols.append(Ak.det() / det)
    return Matrix(cols)


def module_specs() -> list[ModuleSpec]:
    geometry = args_of(GEOMETRY)
    angles = args_of(((theta, "Euler nutation angle", "rad"), (phi, "Euler spin angle", "rad")))
    impact_args = args_of(H_ENTRIES + IMPACT_STATE[1:])
    descent_args = args_of(UNKNOWNS + H_ENTRIES + IMPACT_STATE)
    functions = [
        NamedMatrix("rotation", rotation(), args_of(GEOMETRY[3:]),
                    "Q: body axes (columns) in the surface frame, z-x-z Euler angles", "1", "(56)-(57)"),
        NamedMatrix("euler_rate_matrix", euler_rate_matrix(), angles,
                    "W: body angular velocity = W (theta', psi', phi')", "1", "(44)-(52)"),
        NamedMatrix("contact_offset", contact_offset(), geometry,
                    "R = K - C, centre of mass to lowest point of the ellipsoid, surface frame", "m"),
        NamedMatrix("contact_height", Matrix([contact_height()]), geometry,
                    "height of the centre above the plane at contact", "m", "(63)"),
        NamedMatrix("inertia_ratio", inertia_ratio(), geometry,
                    "P = I/m, squared radii of gyration in the surface frame", "m^2", "(11)-(12)"),
        NamedMatrix("H", reduction_tensor(), geometry,
                    "reduction tensor H: m (u_K - u_K(0)) = H T", "1", "(1)-(12)"),
        NamedMatrix("mu_equation", mu_equation(), impact_args,
                    "Fourier coefficients (k0, k1c, k1s, k2c, k2s) of the exact scalar equation in mu",
                    "m/s", "(13)-(20)"),
        NamedMatrix("system_19_residual", system_19_residual(), descent_args,
                    "residuals of the impact system (19)", "N*s", "(19)"),
        NamedMatrix("descent_functional", descent_functional(), descent_args,
                    "sum of squared residuals of (19), the consistent form of Phi", "N^2*s^2", "(24)"),
        NamedMatrix("descent_gradient", descent_gradient(), descent_args,
                    "gradient of the consistent Phi with respect to (T_x, T_z, mu)", "N*s, N^2*s^2/rad",
                    "(25)-(27)"),
        NamedMatrix("euler_rate_system", euler_rate_system(), args_of(EULER_SYSTEM_ARGS),
                    "matrix a of the angular-momentum balance in Euler rates", "kg*m^2", "(43)-(52)"),
        NamedMatrix("euler_rate_rhs", euler_rate_rhs(), args_of(EULER_RHS_ARGS),
                    "right-hand side b of the angular-momentum balance", "kg*m^2/s", "(53)-(55)"),
        NamedMatrix("body_components", body_components(R_surface), args_of(R_ARGS + GEOMETRY[3:]),
                    "R in body axes, Q^T R", "m", "(56)"),
        NamedMatrix("centre_velocity_after", centre_velocity_after(v0, Matrix([Tx, Ty, Tz])),
                    args_of(VELOCITY_ARGS),
                    "centre-of-mass velocity after the impact", "m/s", "(41)"),
        NamedMatrix("cramer_solution", cramer_solution(), args_of(CRAMER_ARGS),
                    "solution (theta', psi', phi') of a x = b by Cramer's rule", "rad/s", "(58)-(60)"),
    ]
    return [ModuleSpec("grain_impact",
                       "Impact of an ellipsoidal grain on a plane: derived quantities.",
                       f"seed {SEED}, eqs (1)-(60), derived in symmech.grain.derive", functions)]
