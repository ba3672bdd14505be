"""Hand transcriptions of the matrices printed in section 5 of the paper (seed 003).

Only what the OCR leaves legible is transcribed; each function says which
entries. Conjugate vectors printed as symbols (e.g. the L_a entries of 5.2)
are written out with the paper's rule (Table 1): the conjugate of (x, y) is
(-y, x), the chain vector turned by 90 degrees counter-clockwise.
"""
from __future__ import annotations

import sympy

from symmech.core.derivation import ModuleSpec, NamedMatrix, args_of
from symmech.smm import EX52_LC_ENTRIES
from symmech.smm.derive import SOURCE

ROLE = "printed"  # found by symmech.core.discovery

I1, I2, m2, r1, z2, alpha = sympy.symbols("I1 I2 m2 r1 z2 alpha", real=True)
xM, yM, l4, l5, beta, l3, l6, delta3, delta4 = sympy.symbols("xM yM l4 l5 beta l3 l6 delta3 delta4", real=True)
L1, delta = sympy.symbols("L1 delta", real=True)

ARGS = {
    I1: ("moment of inertia of the boom about its pivot", "kg m^2"),
    I2: ("central moment of inertia of the drive with the wheel", "kg m^2"),
    m2: ("mass of the drive with the wheel", "kg"),
    r1: ("boom pivot to drive hinge", "m"),
    z2: ("drive hinge to drive centre of mass", "m"),
    alpha: ("angle (5.1: rope to boom; 5.2: boom inclination)", "rad"),
    xM: ("boom foot from A, horizontal", "m"), yM: ("boom foot from A, vertical", "m"),
    l4: ("boom length", "m"), l5: ("suspension bar length", "m"),
    beta: ("angle (5.2: suspension bar inclination; 5.3: rope to the boom axis in the boom's plane)", "rad"),
    l3: ("A to front support", "m"), l6: ("A to rear support", "m"),
    delta3: ("front support angle", "rad"), delta4: ("rear support angle", "rad"),
    L1: ("5.3: boom pivot O1 to the centre of mass and the rope attachment", "m"),
    delta: ("5.3: rope angle out of the boom's plane", "rad"),
}


def _args(*symbols):
    return args_of([(s, *ARGS[s]) for s in symbols])


def ex51_a() -> NamedMatrix:
    """5.1, printed (a) — fully legible."""
    a = sympy.Matrix([[I1 + m2 * r1**2, -m2 * r1 * z2], [-m2 * r1 * z2, I2 + m2 * z2**2]])
    return NamedMatrix("ex51_a", a, _args(I1, I2, m2, r1, z2), "example 5.1: inertia matrix (a) as printed",
                       "kg m^2", "5.1 (a)")


def ex51_Lc_rope() -> NamedMatrix:
    """5.1, printed (L_c), column c_1 (rope): (-r1 sin alpha, 0). The other columns are illegible."""
    return NamedMatrix("ex51_Lc_rope", sympy.Matrix([-r1 * sympy.sin(alpha), 0]), _args(r1, alpha),
                       "example 5.1: (L_c) column of the rope c_1 as printed", "m", "5.1 (L_c)")


def _conj(x, y):
    return (-y, x)


def ex52_La() -> NamedMatrix:
    """5.2, printed (L_a) in coordinate form: columns m1.x, m1.y, m2.x, m2.y, m3.x, m3.y, I3;
    rows s1, s2, phi3, phi4, phi5. Entries: s-bar (unit vectors), conjugates of e5 = AM,
    e1 = MB, e2 = BD, and the 1 of I3."""
    e5 = _conj(xM, yM)
    e1 = _conj(l4 * sympy.cos(alpha), l4 * sympy.sin(alpha))
    e2 = _conj(l5 * sympy.cos(beta), l5 * sympy.sin(beta))
    L = sympy.Matrix([
        [1, 0, 1, 0, 1, 0, 0],
        [0, 1, 0, 1, 0, 1, 0],
        [e5[0], e5[1], e5[0], e5[1], 0, 0, 1],
        [e1[0], e1[1], e1[0], e1[1], 0, 0, 0],
        [0, 0, e2[0], e2[1], 0, 0, 0],
    ])
    return NamedMatrix("ex52_La", L, _args(xM, yM, l4, alpha, l5, beta),
                       "example 5.2: (L_a) as printed (conjugate vectors written out)", "m or 1", "5.2 (L_a)")


def ex52_Lc() -> NamedMatrix:
    """5.2, printed (L_c): the legible entries EX52_LC_ENTRIES as a column (the phi3 entries
    of c1 and c2 are illegible)."""
    values = {
        (1, 2): 1, (1, 3): 1,
        (2, 2): l3 * sympy.sin(delta3), (2, 3): -l6 * sympy.cos(delta4),
        (3, 0): l4 * sympy.sin(alpha), (3, 1): l4 * sympy.cos(alpha),
        (4, 0): l5 * sympy.sin(beta), (4, 1): l5 * sympy.cos(beta),
    }
    col = sympy.Matrix([values.get(e, 0) for e in EX52_LC_ENTRIES])
    return NamedMatrix("ex52_Lc", col, _args(l4, alpha, l5, beta, l3, l6, delta3, delta4),
                       "example 5.2: legible entries of (L_c) as printed", "m or 1", "5.2 (L_c)")


def ex53_Lc() -> NamedMatrix:
    """5.3, printed (L_c): the three rows whose entries are legible, columns c1, c1', c_K, c2.
    Their row labels are lost; by the physics they are beta1 (pitch: both ropes alike), psi1
    (yaw: the ropes opposite) and phi1 (roll about the boom axis: c_K alone). The phi2 row is
    illegible."""
    pitch = -L1 * sympy.cos(delta) * sympy.sin(beta)
    L = sympy.Matrix([
        [pitch, pitch, 0, 0],
        [L1 * sympy.sin(delta), -L1 * sympy.sin(delta), 0, 0],
        [0, 0, 1, 0],
    ])
    return NamedMatrix("ex53_Lc", L, _args(L1, beta, delta),
                       "example 5.3: legible rows (beta1, psi1, phi1) of (L_c) as printed", "m or 1", "5.3 (L_c)")


# ---- general formulas of sections 2-3, as printed (vectors by their components) ----

ex, ey, ez, px, py, pz, ux, uy, uz, ell = sympy.symbols("e_x e_y e_z p_x p_y p_z u_x u_y u_z ell", real=True)
fx, fy, fz, sx, sy, sz = sympy.symbols("f_x f_y f_z s_x s_y s_z", real=True)
E, F, P, U, S = (sympy.Matrix(v) for v in ((ex, ey, ez), (fx, fy, fz), (px, py, pz), (ux, uy, uz), (sx, sy, sz)))
VECTOR_ARGS = {
    ex: "axis e of the turn q_kappa (unit), x", ey: "axis e, y", ez: "axis e, z",
    fx: "axis f of a second turn q_lambda (unit), x", fy: "axis f, y", fz: "axis f, z",
    px: "chain vector p turned by the axes, x", py: "p, y", pz: "p, z",
    ux: "unit vector l° along the spring, pointing to its moving end, x", uy: "l°, y", uz: "l°, z",
    sx: "unit vector s of a slide, x", sy: "s, y", sz: "s, z",
    ell: "spring length l",
}


def _vargs(*symbols):
    return args_of([(x, VECTOR_ARGS[x], "m" if x in (px, py, pz, ell) else "1") for x in symbols])


def table2_conjugates() -> NamedMatrix:
    """Table 2: projections on i, j, k of the conjugate vector p~ = dp/dq for a turn about e = i, j, k
    (rows e = i, j, k)."""
    T = sympy.Matrix([[0, -pz, py], [pz, 0, -px], [-py, px, 0]])
    return NamedMatrix("table2_conjugates", T, _vargs(px, py, pz),
                       "Table 2: conjugate vector projections for e = i, j, k as printed", "m", "Table 2")


def spatial_conjugate() -> NamedMatrix:
    """Section 3, the braced formula after Table 2: (e_y p_z - e_z p_y, e_z p_x - e_x p_z, e_x p_y - e_y p_x)."""
    v = sympy.Matrix([ey * pz - ez * py, ez * px - ex * pz, ex * py - ey * px])
    return NamedMatrix("spatial_conjugate", v, _vargs(ex, ey, ez, px, py, pz),
                       "section 3: the conjugate vector dp/dq for an axis e, as printed", "m", "sec. 3")


def length_d2_turn() -> NamedMatrix:
    """Section 3: d2 l/dq2 = (1/l)((e x p)^2 - ((e x p) . l°)^2) + (e x (e x p)) . l° (the last printed form)."""
    ep = E.cross(P)
    v = (ep.dot(ep) - ep.dot(U) ** 2) / ell + E.cross(ep).dot(U)
    return NamedMatrix("length_d2_turn", sympy.Matrix([v]), _vargs(ex, ey, ez, px, py, pz, ux, uy, uz, ell),
                       "section 3: second derivative of a spring length by one turn, as printed", "m", "sec. 3")


def length_d2_two_turns() -> NamedMatrix:
    """Section 3, mixed second derivative by two turns (axes e outer, f inner) of a chain vector p,
    read literally: (p~2 / l)(p~2 - l°(p~2 . l°)) + l° . ((e x f) x p + f x (e x p)), with p~2 = f x p
    in both places of the first term (the printed indices)."""
    p2 = F.cross(P)
    v = p2.dot(p2 - U * p2.dot(U)) / ell + U.dot(E.cross(F).cross(P) + F.cross(E.cross(P)))
    return NamedMatrix("length_d2_two_turns", sympy.Matrix([v]),
                       _vargs(ex, ey, ez, fx, fy, fz, px, py, pz, ux, uy, uz, ell),
                       "section 3: mixed second derivative of a spring length by two turns, as printed", "m",
                       "sec. 3")


def length_d2_two_turns_read() -> NamedMatrix:
    """The same with the first conjugate read as p~1 = e x p (the outer turn)."""
    p1, p2 = E.cross(P), F.cross(P)
    v = p1.dot(p2 - U * p2.dot(U)) / ell + U.dot(E.cross(F).cross(P) + F.cross(E.cross(P)))
    return NamedMatrix("length_d2_two_turns_read", sympy.Matrix([v]),
                       _vargs(ex, ey, ez, fx, fy, fz, px, py, pz, ux, uy, uz, ell),
                       "section 3: mixed second derivative by two turns, first factor read as p~1", "m", "sec. 3")


def length_d2_slide() -> NamedMatrix:
    """Section 3: d2 l/ds2 = (1/l)(1 - s~^2), read as (1 - (s . l°)^2)/l."""
    v = (1 - S.dot(U) ** 2) / ell
    return NamedMatrix("length_d2_slide", sympy.Matrix([v]), _vargs(sx, sy, sz, ux, uy, uz, ell),
                       "section 3: second derivative of a spring length by a slide, as printed", "1/m", "sec. 3")


def table1_planar() -> NamedMatrix:
    """Table 1, first block, set (p~, s): for a planar chain vector p turned by phi (axis k) and a slide s
    turned by phi: [dr/dphi . dr/dphi, dr/dphi . dr/ds, dr/ds . dr/ds, j . dr/dphi, j . dr/ds,
    j . d2r/dphi2, j . d2r/dphi ds, j . d2r/ds2] as printed: p~.p~, p~.s, s.s, i.p, i.s~, -j.p, -j.s~, 0,
    where p~ = p turned 90 deg counter-clockwise and s~ = s turned 90 deg clockwise."""
    pt = sympy.Matrix([-py, px, 0])
    st = sympy.Matrix([sy, -sx, 0])
    i, j = sympy.Matrix([1, 0, 0]), sympy.Matrix([0, 1, 0])
    p, s = sympy.Matrix([px, py, 0]), sympy.Matrix([sx, sy, 0])
    row = [pt.dot(pt), pt.dot(s), s.dot(s), i.dot(p), i.dot(st), -j.dot(p), -j.dot(st), 0]
    return NamedMatrix("table1_planar", sympy.Matrix(row), _vargs(px, py, sx, sy),
                       "Table 1, set (p~, s): inertia and gravity entries of a planar chain, as printed",
                       "m^2, m or 1", "Table 1")


def table1_length() -> NamedMatrix:
    """Table 1, second block (spring length l, l° pointing to the moving end, planar), legible entries
    with the printed +- signs taken for the moving end: [dl/dphi, dl/ds, d2l/dphi2, d2l/ds2] =
    [p~ . l°, s . l°, (p~ across l°)^2 / l - p . l°, (s across l°)^2 / l] (p, s turned by phi)."""
    pt = sympy.Matrix([-py, px, 0])
    p, s, u = sympy.Matrix([px, py, 0]), sympy.Matrix([sx, sy, 0]), sympy.Matrix([ux, uy, 0])
    row = [pt.dot(u), s.dot(u), (pt.dot(pt) - pt.dot(u) ** 2) / ell - p.dot(u), (s.dot(s) - s.dot(u) ** 2) / ell]
    return NamedMatrix("table1_length", sympy.Matrix(row), _vargs(px, py, sx, sy, ux, uy, ell),
                       "Table 1, spring-length block: first and second derivatives, as printed (legible entries)",
                       "m or 1", "Table 1")


c1, L, g, mass = sympy.symbols("c1 L g m", positive=True)
FIG_ARGS = {c1: ("spring stiffness C1", "N/m"), L: ("pendulum length L (pivot to the mass)", "m"),
            alpha: ("pendulum angle above the horizontal", "rad"),
            beta: ("spring angle above the horizontal, pointing back over the pivot", "rad"),
            ell: ("spring length l in equilibrium", "m"), mass: ("mass m at the pendulum's end", "kg"),
            g: ("gravitational acceleration", "m/s^2")}


def _fig8(inner_weight: bool):
    gam = alpha + beta
    D = mass * g * sympy.cos(alpha) / (c1 * sympy.sin(gam))
    bracket = L**2 / ell * sympy.cos(gam) ** 2 - L * sympy.cos(gam)
    if inner_weight:
        bracket -= mass * g * L * sympy.sin(alpha)
    return c1 * L**2 * sympy.sin(gam) ** 2 + c1 * D * bracket - mass * g * L * sympy.sin(alpha)


def fig8_c() -> NamedMatrix:
    """Fig. 8 (table of examples, row 8): C = C1 L^2 sin^2(a+b) + C2 D (L^2/l cos^2(a+b) - L cos(a+b)
    - m g L sin a) - m g L sin a, D = m g cos a / (C1 sin(a+b)). The model has one spring, so C2 is
    read as C1; the term - m g L sin a inside the bracket is kept as printed."""
    return NamedMatrix("fig8_c", sympy.Matrix([_fig8(True)]), _fig_args(c1, L, alpha, beta, ell, mass, g),
                       "Fig. 8: stiffness of the pendulum on a preloaded spring, as printed (C2 read as C1)",
                       "N m", "Fig. 8")


def fig8_c_read() -> NamedMatrix:
    """Fig. 8 with the bracket's - m g L sin a (a repeat of the last term) dropped."""
    return NamedMatrix("fig8_c_read", sympy.Matrix([_fig8(False)]), _fig_args(c1, L, alpha, beta, ell, mass, g),
                       "Fig. 8 without the repeated gravity term inside the bracket", "N m", "Fig. 8")


def _fig_args(*symbols):
    return args_of([(x, *FIG_ARGS[x]) for x in symbols])


def fig9_c() -> NamedMatrix:
    """Fig. 9 (table of examples, row 9): C = C1 D / l, a mass moving across a spring preloaded by C1 D."""
    D = sympy.Symbol("Delta", positive=True)
    return NamedMatrix("fig9_c", sympy.Matrix([c1 * D / ell]),
                       args_of([(c1, *FIG_ARGS[c1]), (D, "static elongation of the spring", "m"),
                                (ell, *FIG_ARGS[ell])]),
                       "Fig. 9: lateral stiffness of a mass on a preloaded spring, as printed", "N/m", "Fig. 9")


def omega_c_rates() -> NamedMatrix:
    """Section 3: d omega_C / d(alpha', beta', gamma') = (sin beta, 0, 1), the legible row (Euler-Krylov angles)."""
    return NamedMatrix("omega_c_rates", sympy.Matrix([sympy.sin(beta), 0, 1]),
                       args_of([(beta, "second Euler-Krylov angle", "rad")]),
                       "section 3: partial derivatives of omega_C by the angle rates, as printed", "1", "sec. 3")


def module_specs() -> list[ModuleSpec]:
    functions = (ex51_a(), ex51_Lc_rope(), ex52_La(), ex52_Lc(), ex53_Lc(), table2_conjugates(),
                 spatial_conjugate(), length_d2_turn(), length_d2_two_turns(), length_d2_two_turns_read(),
                 length_d2_slide(), table1_planar(), table1_length(), fig8_c(), fig8_c_read(), fig9_c(), omega_c_rates())
    return [ModuleSpec("smm_printed", "Formulas and matrices of the SMM paper (seed 003) as printed: "
                       "sections 2-3 (general formulas, Tables 1-2, Fig. 8) and section 5 (legible entries).",
                       SOURCE, functions)]
