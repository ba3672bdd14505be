"""Layer 1: the elastic trolley of seed 002 (roller section after (14), eqs. (1)-(10)).

Generalized coordinates relative to the track frame Ox1x2x3 (see docs/trolley-elastic.md):
q0 = [u2, u3, θ1, θ2, θ3], the translation of O across the track and three small
rotations of the trolley in the aircraft sequence θ2 -> θ3 -> θ1 of Λ; then the
Ritz coordinates of the elastic body. The displacement of a trolley point r is the
expansion of the exact rigid motion to second order,
    ũ(r) = Σ q0_i φ0_i(r) + ½ Σ q0_i q0_j ψ0_ij(r),
derived here (not transcribed) from the rotation sequence of
:mod:`symmech.core.kinematics`. Beams use polynomial Ritz bases, their quadratic
fields ψ_kl are the axial shortening ½∫ w'² of an inextensible beam (the part that
carries geometric stiffening).
"""
from __future__ import annotations

import sympy as sp

from symmech.core import kinematics as kin
from symmech.core.derivation import ModuleSpec, NamedMatrix, args_of
from symmech.trolley.derive import SOURCE

u2, u3, q_th1, q_th2, q_th3 = sp.symbols("u2 u3 q_th1 q_th2 q_th3", real=True)
Q0 = (u2, u3, q_th1, q_th2, q_th3)
Q0_ARGS = args_of([(u2, "roller DOF: displacement of O along x2", "m"),
                   (u3, "roller DOF: displacement of O along x3", "m"),
                   (q_th1, "roller DOF: small roll about x1", "rad"),
                   (q_th2, "roller DOF: small yaw about x2", "rad"),
                   (q_th3, "roller DOF: small pitch about x3", "rad")])
X = sp.symbols("r1 r2 r3", real=True)
X_ARGS = args_of([(x, f"trolley point coordinate r{i + 1} (along x{i + 1})", "m") for i, x in enumerate(X)])
# Pairs (i, j), i <= j, of the rotation coordinates in the order of ψ0 columns: 44, 45, 46, 55, 56, 66.
ROTATION_PAIRS = ((2, 2), (2, 3), (2, 4), (3, 3), (3, 4), (4, 4))
# Largest number of Ritz functions per bending plane of a beam.
NMAX = 8
L_AXLE, A_HALF = sp.symbols("l ah", positive=True)
GEOMETRY_ARGS = args_of([(L_AXLE, "axle distance OA", "m"), (A_HALF, "half track gauge OB = OC", "m")])
# Contact points (trolley frame) and directions of the rollers carrying P1...P5 (as in (11)).
ROLLERS = (((0, 0, -A_HALF), 1), ((0, 0, A_HALF), 1), ((L_AXLE, 0, 0), 1), ((0, 0, 0), 2), ((L_AXLE, 0, 0), 2))


def rigid_displacement(point=X) -> sp.Matrix:
    """Exact displacement (R - E) r + [0, u2, u3] of the trolley point r, R the active turn
    θ2 about x2, then θ3 about x3, then θ1 about x1 (the sequence of Λ)."""
    rot = kin.sequence((1, 2, 0), (q_th2, q_th3, q_th1), kin.SYMPY, passive=False)
    r = sp.Matrix(point)
    return (rot - sp.eye(3)) * r + sp.Matrix([0, u2, u3])


def rigid_fields(point=X) -> tuple[sp.Matrix, sp.Matrix]:
    """φ0 (3 x 5) and ψ0 (3 x 6, columns ROTATION_PAIRS): first and second derivatives
    of the exact rigid displacement at q0 = 0."""
    u = rigid_displacement(point)
    zero = {q: 0 for q in Q0}
    phi = sp.Matrix.hstack(*[u.diff(q).subs(zero) for q in Q0])
    psi = sp.Matrix.hstack(*[u.diff(Q0[i], Q0[j]).subs(zero) for i, j in ROTATION_PAIRS])
    return phi, psi


def quadratic_displacement(point=X) -> sp.Matrix:
    """ũ = Σ q0_i φ0_i + ½ Σ_ij q0_i q0_j ψ0_ij (the paper's quadratic approximation)."""
    phi, psi = rigid_fields(point)
    q = sp.Matrix(Q0)
    u = phi * q
    for col, (i, j) in enumerate(ROTATION_PAIRS):
        weight = sp.Rational(1, 2) if i == j else 1  # ψ_ij = ψ_ji: the pair appears twice
        u += weight * Q0[i] * Q0[j] * psi[:, col]
    return u


def rigid_fields_matrix() -> NamedMatrix:
    phi, psi = rigid_fields()
    return NamedMatrix("rigid_fields", sp.Matrix.hstack(phi, psi), X_ARGS,
                       "[φ0_2 … φ0_6 | ψ0_44, ψ0_45, ψ0_46, ψ0_55, ψ0_56, ψ0_66] at the trolley point r",
                       "1 (translations), m (rotations)", "ũ (roller section)")


def roller_matrix() -> NamedMatrix:
    """C with the roller deflections d = C q0, d_i = n_i · ũ(r_i) (positive along x2 at B, C, A,
    along x3 at O, A). The contact points lie on the axes x1, x3, where every ψ0 term along
    the roller's direction vanishes: d is exactly linear in the quadratic approximation."""
    d = sp.Matrix([quadratic_displacement(point)[axis] for point, axis in ROLLERS])
    c = d.jacobian(sp.Matrix(Q0))
    if c.free_symbols & set(Q0):
        raise ValueError("roller deflections are not linear in q0")
    return NamedMatrix("roller_matrix", c, GEOMETRY_ARGS, "C of the roller deflections d = C q0",
                       "1 (translations), m (rotations)", "Π^P = ½ dᵀ diag(k) d, K0 = Cᵀ diag(k) C")


XI = sp.Symbol("xi", real=True)
XI_ARGS = args_of([(XI, "coordinate along the beam x / L", "1")])


def beam_functions(support: str) -> list[sp.Expr]:
    """Polynomial Ritz functions N_k(ξ), k = 1…NMAX, admissible for ``support``: the shifted
    Legendre polynomials P_(k-1)(2ξ - 1) (well conditioned, unlike monomials) times ξ² for
    "cantilever" (clamped at ξ = 0) or ξ (1 - ξ) for "pinned" (pinned at both ends)."""
    factor = XI ** 2 if support == "cantilever" else XI * (1 - XI)
    return [sp.expand(factor * sp.legendre(k, 2 * XI - 1)) for k in range(NMAX)]


def beam_basis(support: str) -> list[NamedMatrix]:
    """N, dN/dξ, d²N/dξ² (3 x NMAX) and the shortening integrals S_kl(ξ) = ∫0^ξ N_k' N_l' dξ."""
    n = beam_functions(support)
    rows = sp.Matrix([n, [f.diff(XI) for f in n], [f.diff(XI, 2) for f in n]])
    t = sp.Symbol("t", real=True)
    short = sp.Matrix(NMAX, NMAX, lambda i, j: sp.integrate((n[i].diff(XI) * n[j].diff(XI)).subs(XI, t), (t, 0, XI)))
    return [NamedMatrix(f"{support}_basis", rows, XI_ARGS,
                        f"[N; N'; N''] of the {support} Ritz functions at ξ (derivatives in ξ)", "1",
                        "u = Σ q_i φ_i"),
            NamedMatrix(f"{support}_shortening", short, XI_ARGS,
                        f"S_kl(ξ) = ∫0^ξ N_k' N_l' dξ of the {support} functions (axial ψ_kl = -S_kl/L)", "1",
                        "ψ_ij (quadratic strain ε11 = u1' + ½ w'²)")]


def module_specs() -> list[ModuleSpec]:
    functions = [rigid_fields_matrix(), roller_matrix(), *beam_basis("cantilever"), *beam_basis("pinned")]
    return [ModuleSpec("trolley_elastic", "Rigid fields of the roller DOFs, roller deflections and beam Ritz bases "
                       "of the elastic trolley.", SOURCE, functions)]
