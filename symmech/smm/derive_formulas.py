"""Layer 1: the general formulas of the SMM paper (seed 003) derived from their definitions.

Each function differentiates the geometric definition it stands for — a chain
vector turned by Rodrigues' rotation, a spring length |anchor - moving end|, a
pendulum's potential energy — and returns a NamedMatrix with the same arguments
as its printed twin in :mod:`symmech.smm.printed`, so ``symmech errata`` can
compare the two numerically. Nothing here uses the SMM's own conjugate-vector rules.
"""
from __future__ import annotations

import sympy
from sympy.core.exprtools import factor_terms
from sympy.simplify.simplify import signsimp

from symmech.core.derivation import ModuleSpec, NamedMatrix
from symmech.core.kinematics import SYMPY, rodrigues
from symmech.smm import printed as pr
from symmech.smm.derive import SOURCE

ROLE = "derivation"  # found by symmech.core.discovery

phi, phi2, s = sympy.symbols("phi phi2 s", real=True)


def _turn(axis, angle) -> sympy.Matrix:
    """Active rotation by ``angle`` about the unit ``axis`` (Rodrigues)."""
    return rodrigues(axis, angle, SYMPY)


def _at_zero(expr, *symbols):
    return expr.subs({x: 0 for x in symbols})


def _second_at_zero(expr, x, y, *symbols) -> sympy.Expr:
    """∂²expr/∂x∂y at ``symbols`` = 0, one variable at a time, tidied by factor_terms(signsimp()) at zero:
    sympy's diff(expr, x, y) tidies the whole expression before differentiating, most of the cost."""
    return factor_terms(signsimp(_at_zero(expr.diff(x).diff(y), *symbols)))


def _like(printed: NamedMatrix, matrix, meaning: str) -> NamedMatrix:
    return NamedMatrix(printed.name, sympy.Matrix(matrix), printed.args, meaning, printed.unit, printed.equations)


def table2_conjugates() -> NamedMatrix:
    rows = [sympy.diff(_turn(sympy.Matrix(e), phi) * pr.P, phi).T
            for e in ((1, 0, 0), (0, 1, 0), (0, 0, 1))]
    return _like(pr.table2_conjugates(), _at_zero(sympy.Matrix.vstack(*rows), phi),
                 "d(R(e, q) p)/dq at q = 0 for e = i, j, k (rows)")


def spatial_conjugate() -> NamedMatrix:
    return _like(pr.spatial_conjugate(), _at_zero(sympy.diff(_turn(pr.E, phi) * pr.P, phi), phi),
                 "d(R(e, q) p)/dq at q = 0")


def _length(moving: sympy.Matrix) -> sympy.Expr:
    """|moving - anchor| with the anchor at p - l l°: in the drawn configuration the moving end
    is p and l° points from the anchor to it."""
    d = moving - (pr.P - pr.ell * pr.U)
    return sympy.sqrt(d.dot(d))


def length_d2_turn() -> NamedMatrix:
    l_ = _length(_turn(pr.E, phi) * pr.P)
    return _like(pr.length_d2_turn(), [_second_at_zero(l_, phi, phi, phi)], "d2|anchor - R(e, q) p|/dq2 at 0")


def length_d2_two_turns() -> NamedMatrix:
    l_ = _length(_turn(pr.E, phi) * _turn(pr.F, phi2) * pr.P)
    return _like(pr.length_d2_two_turns(), [_second_at_zero(l_, phi, phi2, phi, phi2)],
                 "d2|anchor - R(e, q1) R(f, q2) p|/dq1 dq2 at 0")


def length_d2_slide() -> NamedMatrix:
    l_ = _length(pr.P + s * pr.S)
    return _like(pr.length_d2_slide(), [_second_at_zero(l_, s, s, s)], "d2|anchor - (p + s s)|/ds2 at 0")


def _planar_point():
    """r(phi, s) = R_k(phi) (p + s s): a chain vector and a slide, both turned by phi."""
    p = sympy.Matrix([pr.px, pr.py, 0])
    sv = sympy.Matrix([pr.sx, pr.sy, 0])
    return _turn(sympy.Matrix([0, 0, 1]), phi) * (p + s * sv)


def table1_planar() -> NamedMatrix:
    r = _planar_point()
    j = sympy.Matrix([0, 1, 0])
    rp, rs = r.diff(phi), r.diff(s)
    row = [rp.dot(rp), rp.dot(rs), rs.dot(rs), j.dot(rp), j.dot(rs),
           j.dot(r.diff(phi, 2)), j.dot(r.diff(phi, s)), j.dot(r.diff(s, 2))]
    return _like(pr.table1_planar(), [_at_zero(x, phi, s) for x in row], "derivatives of R_k(phi)(p + s s) at 0")


def table1_length() -> NamedMatrix:
    r = _planar_point()
    u = sympy.Matrix([pr.ux, pr.uy, 0])
    anchor = sympy.Matrix([pr.px, pr.py, 0]) - pr.ell * u
    d = r - anchor
    l_ = sympy.sqrt(d.dot(d))
    row = [_at_zero(l_.diff(phi), phi, s), _at_zero(l_.diff(s), phi, s), _second_at_zero(l_, phi, phi, phi, s),
           _second_at_zero(l_, s, s, phi, s)]
    return _like(pr.table1_length(), row, "derivatives of |R_k(phi)(p + s s) - anchor|")


def fig8_c() -> NamedMatrix:
    """Pendulum (length L at alpha above the horizontal, mass m at its end A) held by a spring of
    stiffness c1 from A to an anchor at l (-cos beta, sin beta) from A, its preload from equilibrium:
    C = d2 Pi/dphi2 at phi = 0 with Pi = c1 (l(phi) - l0)^2 / 2 + m g y_A(phi)."""
    A = pr.L * sympy.Matrix([sympy.cos(pr.alpha + phi), sympy.sin(pr.alpha + phi)])
    anchor = pr.L * sympy.Matrix([sympy.cos(pr.alpha), sympy.sin(pr.alpha)]) + pr.ell * sympy.Matrix(
        [-sympy.cos(pr.beta), sympy.sin(pr.beta)])
    length = sympy.sqrt((anchor - A).dot(anchor - A))
    weight = pr.mass * pr.g
    dl = _at_zero(length.diff(phi), phi)
    tension = -weight * pr.L * sympy.cos(pr.alpha) / dl  # dPi/dphi = T dl/dphi + m g dy/dphi = 0
    C = pr.c1 * dl**2 + tension * _second_at_zero(length, phi, phi, phi) + weight * _at_zero(A[1].diff(phi, 2), phi)
    return _like(pr.fig8_c(), [C], "d2 Pi/dphi2 of the pendulum on a spring preloaded to equilibrium")


def fig9_c() -> NamedMatrix:
    printed = pr.fig9_c()
    delta = printed.args[1].symbol
    potential = pr.c1 * (sympy.sqrt(pr.ell**2 + s**2) - (pr.ell - delta)) ** 2 / 2
    return _like(printed, [_second_at_zero(potential, s, s, s)], "d2 Pi/ds2 across a spring of tension c1 Delta")


def omega_c_rates() -> NamedMatrix:
    """Body angular velocity of R = R_x(alpha) R_y(beta) R_z(gamma); d omega_z / d(rates)."""
    a, b, c = sympy.symbols("alpha beta gamma", real=True)
    da, db, dc = sympy.symbols("alpha_dot beta_dot gamma_dot", real=True)
    ex, ey, ez = (sympy.Matrix(v) for v in ((1, 0, 0), (0, 1, 0), (0, 0, 1)))
    Ry, Rz = _turn(ey, b), _turn(ez, c)
    w = (Ry * Rz).T * ex * da + Rz.T * ey * db + ez * dc
    row = [sympy.diff(w[2], x) for x in (da, db, dc)]
    return _like(pr.omega_c_rates(), [sympy.simplify(x).subs(b, pr.beta) for x in row],
                 "d omega_C / d(alpha', beta', gamma') of the Euler-Krylov sequence x-y-z")


def module_specs() -> list[ModuleSpec]:
    functions = (table2_conjugates(), spatial_conjugate(), length_d2_turn(), length_d2_two_turns(),
                 length_d2_slide(), table1_planar(), table1_length(), fig8_c(), fig9_c(), omega_c_rates())
    return [ModuleSpec("smm_formulas", "The SMM paper's general formulas derived from their definitions "
                       "(twins of the printed ones in smm_printed).", SOURCE, functions)]
