"""The grain-impact formulas exactly as printed in seed 000 (hand transcription).

Each function types one group of the paper's equations, misprints included, so
that ``symmech errata`` can compare two independent sources: this file and
:mod:`symmech.grain.derive`. Where the printed text is ambiguous the reading is
stated. Direction cosines cos(alpha_ir) of (12) and l_i, m_i, n_i of (56)-(57)
are the entries of the derived rotation Q (body axis r as column r).
"""
from __future__ import annotations

import sympy
from sympy import Matrix, cos, sin, sqrt, tan

from symmech.core.derivation import ModuleSpec, NamedMatrix, args_of
from symmech.grain import derive as d

ROLE = "printed"  # found by symmech.core.discovery

Rx, Ry, Rz = d.R_surface
p_xx, p_xy, p_xz, p_yy, p_yz, p_zz = sympy.symbols("P_xx P_xy P_xz P_yy P_yz P_zz", real=True)
theta0, phi0 = d.theta, d.phi  # the angles at the impact, theta(0) and phi(0) of (44)-(55)


def inertia_ratio():
    """(11)-(12) as printed: rho_ij = sum_r rho_r cos(a_ir) cos(a_jr), P_ij = +-rho_ij^2.

    The printed (12) sums radii of gyration (not their squares), and (11) puts a
    minus sign on every off-diagonal entry.
    """
    Q = d.rotation()
    rho = [sqrt(g) for g in d.gyration_squared()]
    rho_ij = Matrix(3, 3, lambda i, j: sum(rho[r] * Q[i, r] * Q[j, r] for r in range(3)))
    return Matrix(3, 3, lambda i, j: rho_ij[i, j]**2 if i == j else -rho_ij[i, j]**2)


def reduction_tensor():
    """(3)-(10): H from R and the cofactors P_ij and determinant |P| of P."""
    P = Matrix([[p_xx, p_xy, p_xz], [p_xy, p_yy, p_yz], [p_xz, p_yz, p_zz]])
    det = P.det()
    R = (Rx, Ry, Rz)

    def z(k, s, i, j):  # (10): (zeta_k zeta_s)_ij = R_k R_s P_ij / |P|, P_ij the cofactor
        return R[k] * R[s] * P.cofactor(i, j) / det

    X, Y, Z = 0, 1, 2
    h_xx = 1 + z(Z, Z, Y, Y) + z(Y, Y, Z, Z) - 2 * z(Y, Z, Y, Z)  # (3)
    h_yy = 1 + z(X, X, Z, Z) + z(Z, Z, X, X) - 2 * z(Z, X, Z, X)  # (4)
    h_zz = 1 + z(Y, Y, X, X) + z(X, X, Y, Y) - 2 * z(X, Y, X, Y)  # (5)
    h_xy = -z(X, Y, Z, Z) - z(Z, Z, X, Y) + z(Z, X, Y, Z) + z(Y, Z, Z, X)  # (6)
    h_yz = -z(Y, Z, X, X) - z(X, X, Y, Z) + z(X, Y, Z, X) + z(Z, X, X, Y)  # (7)
    h_zx = -z(Z, X, Y, Y) - z(Y, Y, Z, X) + z(Y, Z, X, Y) + z(X, Y, Y, Z)  # (8)
    return Matrix([[h_xx, h_xy, h_zx], [h_xy, h_yy, h_yz], [h_zx, h_yz, h_zz]])  # (9)


def _lhs_19(k):
    """Left-hand sides of (19) with |V_K(0)| from (20)."""
    V0 = sqrt(d.ux0**2 + d.uy0**2)  # (20)
    return [d.m * ((1 - d.lam) * V0 * cos(d.mu) - d.ux0),
            d.m * ((1 - d.lam) * V0 * sin(d.mu) - d.uy0),
            -d.m * (1 + d.e) * d.uz0][k]


def system_19_residual():
    """(19): left-hand side minus right-hand side, one row per equation."""
    h = {"xx": d.hxx, "xy": d.hxy, "xz": d.hxz, "yy": d.hyy, "yz": d.hyz, "zz": d.hzz,
         "yx": d.hxy, "zx": d.hxz, "zy": d.hyz}
    t = tan(d.mu)
    rows = [(h["xx"] + h["xy"] * t) * d.Tx + h["xz"] * d.Tz,
            (h["yx"] + h["yy"] * t) * d.Tx + h["yz"] * d.Tz,
            (h["zx"] + h["zy"] * t) * d.Tx + h["zz"] * d.Tz]
    return Matrix([rows[k] - _lhs_19(k) for k in range(3)])


def functional():
    """(24): Phi as printed, the plain sum of the three residuals of (19)."""
    return Matrix([-sum(system_19_residual())])


def functional_gradient():
    """The gradient of the printed (24) itself in (T_x, T_z, mu): what (25)-(27) should print."""
    phi = functional()[0]
    return Matrix([sympy.diff(phi, v) for v in (d.Tx, d.Tz, d.mu)])


def gradient():
    """(25)-(27) as printed; (27) omits h_xy from the tan(mu) term."""
    V0 = sqrt(d.ux0**2 + d.uy0**2)
    t = tan(d.mu)
    g_tx = -(d.hxx + d.hxy * t) - (d.hxy + d.hyy * t) - (d.hxz + d.hyz * t)  # (25)
    g_tz = -d.hxz - d.hyz - d.hzz  # (26)
    g_mu = (-d.m * (1 - d.lam) * V0 * sin(d.mu) + d.m * (1 - d.lam) * V0 * cos(d.mu)
            - (d.hyy + d.hyz) / cos(d.mu)**2 * d.Tx)  # (27)
    return Matrix([g_tx, g_tz, g_mu])


def euler_rate_system():
    """(44)-(52) as printed; a_32 reads J'_z cos(phi(0))."""
    Jx, Jy, Jz = d.Jx, d.Jy, d.Jz
    return Matrix([
        [Jx * cos(phi0), Jx * sin(theta0) * sin(phi0), 0],
        [-Jy * sin(phi0), Jy * sin(theta0) * cos(phi0), 0],
        [0, Jz * cos(phi0), Jz],
    ])


def euler_rate_rhs():
    """(53)-(55) as printed; b_3 reads J'_z [phi'(0) + theta'(0) cos theta(0)]."""
    (Rx_, Ry_, Rz_), (Tx_, Ty_, Tz_) = d.Rb, d.Tb
    return Matrix([
        Ry_ * Tz_ - Rz_ * Ty_ + d.Jx * (d.dpsi * sin(theta0) * sin(phi0) + d.dtheta * cos(phi0)),
        Rz_ * Tx_ - Rx_ * Tz_ + d.Jy * (d.dpsi * sin(theta0) * cos(phi0) - d.dtheta * sin(phi0)),
        Rx_ * Ty_ - Ry_ * Tx_ + d.Jz * (d.dphi + d.dtheta * cos(theta0)),
    ])


def cramer_solution():
    """(58)-(60) as printed."""
    (a11, a12, a13), (a21, a22, a23), (a31, a32, a33) = (d.A_sym.row(i) for i in range(3))
    b1, b2, b3 = d.b_sym
    den = a11 * (a22 * a33 - a23 * a32) - a21 * (a12 * a33 - a13 * a32) + a31 * (a12 * a23 - a13 * a22)
    return Matrix([
        (b1 * (a22 * a33 - a23 * a32) - b2 * (a12 * a33 - a13 * a32) + b3 * (a12 * a23 - a13 * a22)) / den,
        (-b1 * (a21 * a33 - a23 * a31) + b2 * (a11 * a33 - a13 * a31) - b3 * (a11 * a23 - a13 * a21)) / den,
        (b1 * (a21 * a32 - a22 * a31) - b2 * (a11 * a32 - a12 * a31) + b3 * (a11 * a22 - a12 * a21)) / den,
    ])


def body_components():
    """(56): R'_i = R_x l_i + R_y m_i + R_z n_i with l_i, m_i, n_i the cosines of body axis i."""
    Q = d.rotation()
    return Matrix([Rx * Q[0, i] + Ry * Q[1, i] + Rz * Q[2, i] for i in range(3)])


def centre_velocity_after():
    """(41): u_C = T/m + u_C(0)."""
    T = (d.Tx, d.Ty, d.Tz)
    return Matrix([T[k] / d.m + d.v0[k] for k in range(3)])


def module_specs() -> list[ModuleSpec]:
    descent_args = args_of(d.UNKNOWNS + d.H_ENTRIES + d.IMPACT_STATE)
    P_args = tuple((s, f"P = I/m entry {s.name[2:]}", "m^2") for s in (p_xx, p_xy, p_xz, p_yy, p_yz, p_zz))
    functions = [
        NamedMatrix("inertia_ratio", inertia_ratio(), args_of(d.GEOMETRY),
                    "P as printed", "m^2", "(11)-(12)"),
        NamedMatrix("H", reduction_tensor(), args_of(d.R_ARGS + P_args),
                    "reduction tensor H as printed, from R and P", "1", "(3)-(10)"),
        NamedMatrix("system_19_residual", system_19_residual(), descent_args,
                    "residuals of (19) as printed", "N*s", "(19)"),
        NamedMatrix("functional", functional(), descent_args,
                    "Phi as printed (sum of residuals)", "N*s", "(24)"),
        NamedMatrix("gradient", gradient(), descent_args,
                    "grad Phi as printed", "1, 1, N*s/rad", "(25)-(27)"),
        NamedMatrix("functional_gradient", functional_gradient(), descent_args,
                    "grad Phi derived from the printed (24)", "1, 1, N*s/rad", "(24)"),
        NamedMatrix("euler_rate_system", euler_rate_system(), args_of(d.EULER_SYSTEM_ARGS),
                    "matrix a as printed", "kg*m^2", "(44)-(52)"),
        NamedMatrix("euler_rate_rhs", euler_rate_rhs(), args_of(d.EULER_RHS_ARGS),
                    "right-hand side b as printed", "kg*m^2/s", "(53)-(55)"),
        NamedMatrix("cramer_solution", cramer_solution(), args_of(d.CRAMER_ARGS),
                    "Euler rates by Cramer's rule as printed", "rad/s", "(58)-(60)"),
        NamedMatrix("body_components", body_components(), args_of(d.R_ARGS + d.GEOMETRY[3:]),
                    "R in body axes as printed", "m", "(56)"),
        NamedMatrix("centre_velocity_after", centre_velocity_after(), args_of(d.VELOCITY_ARGS),
                    "centre-of-mass velocity after the impact as printed", "m/s", "(41)"),
    ]
    return [ModuleSpec("grain_impact_printed",
                       "Impact of an ellipsoidal grain on a plane: formulas as printed (misprints kept).",
                       f"seed {d.SEED}, eqs (3)-(60), transcribed in symmech.grain.printed", functions)]
