"""Hand transcriptions of the matrices printed in section 5 of the paper (seed 003).

Only what the OCR leaves legible is transcribed; each function says which
entries. Conjugate vectors printed as symbols (e.g. the L_a entries of 5.2)
are written out with the paper's rule (Table 1): the conjugate of (x, y) is
(-y, x), the chain vector turned by 90 degrees counter-clockwise.
"""
from __future__ import annotations

import sympy

from symmech.core.derivation import ModuleSpec, NamedMatrix, args_of
from symmech.smm.derive import SOURCE

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


# legible entries of the printed 5.2 (L_c): (row, column) with rows s1 s2 phi3 phi4 phi5, columns c1..c4
EX52_LC_ENTRIES = ((0, 0), (0, 1), (0, 2), (0, 3), (1, 0), (1, 1), (1, 2), (1, 3), (2, 2), (2, 3),
                   (3, 0), (3, 1), (3, 2), (3, 3), (4, 0), (4, 1), (4, 2), (4, 3))


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


def module_specs() -> list[ModuleSpec]:
    return [ModuleSpec("smm_printed", "Matrices of the SMM paper's section 5 as printed (legible entries).",
                       SOURCE, (ex51_a(), ex51_Lc_rope(), ex52_La(), ex52_Lc(), ex53_Lc()))]
