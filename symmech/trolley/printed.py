"""Layer 1: the trolley paper's formulas as printed (seed 002), typed in by hand.

Each matrix is transcribed element by element from the paper (equation or
paragraph named in ``equations``); ``symmech errata`` compares them with the
derivations in :mod:`symmech.trolley.derive`. The paper numbers only some
formulas; unnumbered ones are named after the symbol they define.
"""
from __future__ import annotations

import sympy as sp

from symmech.core import kinematics as kin
from symmech.core.derivation import ModuleSpec, NamedMatrix, args_of
from symmech.trolley.derive import ANGLE_ARGS, SOURCE, rigid_body_args, th1, th2, th3

ROLE = "printed"  # found by symmech.core.discovery

s1, s2, s3 = sp.sin(th1), sp.sin(th2), sp.sin(th3)
c1, c2, c3 = sp.cos(th1), sp.cos(th2), sp.cos(th3)

# Λ, paragraph "Матрица Λ записывается в виде".
LAMBDA = sp.Matrix([
    [c2 * c3, s3, -s2 * c3],
    [s1 * s2 - c1 * c2 * s3, c1 * c3, s1 * c2 + c1 * s2 * s3],
    [c1 * s2 + s1 * c2 * s3, -s1 * c3, c1 * c2 - s1 * s2 * s3],
])

# ∂Λ/∂θ1, ∂Λ/∂θ2, ∂Λ/∂θ3 after (13).
DLAMBDA = [
    sp.Matrix([
        [0, 0, 0],
        [c1 * s2 + s1 * c2 * s3, -s1 * c3, c1 * c2 - s1 * s2 * s3],
        [-s1 * s2 + c1 * c2 * s3, -c1 * c3, -s1 * c2 - c1 * s2 * s3],
    ]),
    sp.Matrix([
        [-s2 * c3, 0, -c2 * c3],
        [s1 * c2 + c1 * s2 * s3, 0, -s1 * s2 + c1 * c2 * s3],
        [c1 * c2 - s1 * s2 * s3, 0, -c1 * s2 - s1 * c2 * s3],
    ]),
    sp.Matrix([
        [-c2 * s3, c3, s2 * s3],
        [-c1 * c2 * c3, -c1 * s3, c1 * s2 * c3],
        [s1 * c2 * c3, s1 * s3, -s1 * s2 * c3],
    ]),
]

# A, "ω = A θ̇".
A = sp.Matrix([[1, s3, 0], [0, c1 * c3, s1], [0, -s1 * c3, c1]])

dX1, dX2, dX3 = sp.symbols("dX1 dX2 dX3", real=True)
# l_ij after (14); columns l_i0, l_i1, l_i2, l_i3.
CHORD = sp.Matrix([
    [c2 * c3 * dX1 + s3 * dX2 - s2 * c3 * dX3,
     0,
     -s2 * c3 * dX1 - c2 * c3 * dX3,
     -c2 * s3 * dX1 + c3 * dX2 + s2 * s3 * dX3],
    [(s1 * s2 - c1 * c2 * s3) * dX1 + c1 * c3 * dX2 + (s1 * c2 + c1 * s2 * s3) * dX3,
     (c1 * s2 + s1 * c2 * s3) * dX1 - s1 * c3 * dX2 + (c1 * c2 - s1 * s2 * s3) * dX3,
     (s1 * c2 + c1 * s2 * s3) * dX1 - (s1 * s2 - c1 * c2 * s3) * dX3,
     -c1 * c2 * c3 * dX1 - c1 * s3 * dX2 + c1 * s2 * c3 * dX3],
    [(c1 * s2 + s1 * c2 * s3) * dX1 - s1 * c3 * dX2 + (c1 * c2 - s1 * s2 * s3) * dX3,
     (-s1 * s2 + c1 * c2 * s3) * dX1 - c1 * c3 * dX2 - (s1 * c2 + c1 * s2 * s3) * dX3,
     (c1 * c2 - s1 * s2 * s3) * dX1 - (c1 * s2 + s1 * c2 * s3) * dX3,
     s1 * c2 * c3 * dX1 + s1 * s3 * dX2 - s1 * s2 * c3 * dX3],
])

psi = sp.Symbol("psi", real=True)
xi1, xi2, xi3 = sp.symbols("xi1 xi2 xi3", real=True)
_c, _s = sp.cos(psi), sp.sin(psi)
# Λ* of the helix example (Rodrigues), printed over two lines.
RODRIGUES = sp.Matrix([
    [_c + (1 - _c) * xi1**2, (1 - _c) * xi1 * xi2 + _s * xi3, (1 - _c) * xi1 * xi3 - _s * xi2],
    [(1 - _c) * xi2 * xi1 - _s * xi3, _c + (1 - _c) * xi2**2, (1 - _c) * xi2 * xi3 + _s * xi1],
    [(1 - _c) * xi3 * xi1 + _s * xi2, (1 - _c) * xi3 * xi2 - _s * xi1, _c + (1 - _c) * xi3**2],
])

phi, R, lam = sp.symbols("phi R lam", positive=True)
_Rb, _lb = R / sp.sqrt(R**2 + lam**2), lam / sp.sqrt(R**2 + lam**2)
# Helix example: Λ with rows t, n, b (Frenet trihedron).
HELIX_LAMBDA = sp.Matrix([
    [-_Rb * sp.sin(phi), _Rb * sp.cos(phi), _lb],
    [-sp.cos(phi), -sp.sin(phi), 0],
    [_lb * sp.sin(phi), -_lb * sp.cos(phi), _Rb],
])
# Helix example: "ω = ϰ t + κ b", moving-frame components (no speed factor as printed).
HELIX_OMEGA = sp.Matrix([lam / (R**2 + lam**2), 0, R / (R**2 + lam**2)])

HELIX_ARGS = args_of([(phi, "helix angle φ = s / sqrt(R² + λ²)", "rad"),
                      (R, "helix radius R", "m"), (lam, "helix rise per radian λ", "m")])
CHORD_ARGS = ANGLE_ARGS + args_of([(d, f"chord ΔX̄{i + 1} (fixed frame)", "m")
                                   for i, d in enumerate((dX1, dX2, dX3))])
RODRIGUES_ARGS = args_of([(psi, "rotation angle Ψ", "rad")]) + args_of(
    [(x, f"rotation axis ξ{i + 1} (as used: ξ = t × ρ)", "1") for i, x in enumerate((xi1, xi2, xi3))])


def rigid_body_equations() -> NamedMatrix:
    """(11): m a0 - Ľ0 ω̇ - ω̌ Ľ0 ω = P; -Ľ0ᵀ a0 + I00 ω̇ + ω̌ I00 ω = M, with Ľ the cross-product
    matrix, L0 = m r the static moment and I00 = I_c + m(|r|² E - r rᵀ) the inertia about O."""
    m, r, icm, a0, w, dw, args = rigid_body_args()
    L0 = kin.skew(m * r, kin.SYMPY)
    i00 = icm + m * (r.dot(r) * sp.eye(3) - r * r.T)
    force = m * a0 - L0 * dw - kin.skew(w, kin.SYMPY) * L0 * w
    moment = -L0.T * a0 + i00 * dw + kin.skew(w, kin.SYMPY) * i00 * w
    return NamedMatrix("rigid_body_equations", sp.Matrix.vstack(force, moment), args,
                       "(11) as printed: [P; M] of the rigid body", "N, N m", "(11)")


def module_specs() -> list[ModuleSpec]:
    fns = [NamedMatrix("Lambda", LAMBDA, ANGLE_ARGS, "Λ as printed", "1", "Λ")]
    fns += [NamedMatrix(f"dLambda_dth{i + 1}", d, ANGLE_ARGS, f"∂Λ/∂θ{i + 1} as printed", "1/rad", "(13)")
            for i, d in enumerate(DLAMBDA)]
    fns += [
        NamedMatrix("A", A, ANGLE_ARGS, "A as printed", "1", "ω = A θ̇"),
        NamedMatrix("chord_coefficients", CHORD, CHORD_ARGS, "l_ij as printed", "m", "(14)"),
        NamedMatrix("rodrigues", RODRIGUES, RODRIGUES_ARGS, "Λ* as printed", "1", "Λ* (helix example)"),
        NamedMatrix("helix_Lambda", HELIX_LAMBDA, HELIX_ARGS, "helix Λ = [t n b]ᵀ as printed", "1",
                    "Λ (helix example)"),
        NamedMatrix("helix_omega", HELIX_OMEGA, HELIX_ARGS[1:], "helix ω = ϰ t + κ b as printed",
                    "rad/m (printed as rad/s)", "ω (helix example)"),
        rigid_body_equations(),
    ]
    return [ModuleSpec("trolley_printed", "The trolley paper's formulas as printed (hand transcription).",
                       SOURCE, fns)]
