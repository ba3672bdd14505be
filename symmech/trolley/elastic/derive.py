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
carries geometric stiffening); a pinned beam with held ends stretches instead (uniform
mid-plane strain, :func:`held_membrane`: the quartic membrane energy).
"""
from __future__ import annotations

import functools

import sympy as sp

from symmech.core import kinematics as kin
from symmech.core.derivation import Dynamics, ModuleSpec, NamedMatrix, args_of
from symmech.trolley.derive import SOURCE

ROLE = "derivation"  # found by symmech.core.discovery

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


@functools.cache
def _fields_at_x() -> tuple[sp.Matrix, sp.Matrix]:
    """φ0 (3 x 5) and ψ0 (3 x 6) at the symbolic point X [m], once per process."""
    u = rigid_displacement()
    zero = {q: 0 for q in Q0}
    phi = sp.Matrix.hstack(*[u.diff(q).subs(zero) for q in Q0])
    psi = sp.Matrix.hstack(*[u.diff(Q0[i], Q0[j]).subs(zero) for i, j in ROTATION_PAIRS])
    return phi, psi


def rigid_fields(point=X) -> tuple[sp.Matrix, sp.Matrix]:
    """φ0 (3 x 5) and ψ0 (3 x 6, columns ROTATION_PAIRS): first and second derivatives
    of the exact rigid displacement at q0 = 0. Both are linear in r: derived once at r = X
    and evaluated at ``point`` (the rotation sequence is the costly part)."""
    at = dict(zip(X, point))
    return tuple(m.xreplace(at) for m in _fields_at_x())


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
U = sp.Symbol("u", real=True)  # 2ξ - 1: the Ritz polynomials' own variable (see beam_functions)


def beam_functions(support: str) -> list[sp.Expr]:
    """Polynomial Ritz functions N_k, k = 1…NMAX, admissible for ``support``: the shifted Legendre
    polynomials P_(k-1)(u) times ξ² for "cantilever" (clamped at ξ = 0) or ξ (1 - ξ) for "pinned"
    (pinned at both ends), as polynomials in u = 2ξ - 1 (symbol ``U``).

    Expanded in u the coefficients stay small (|u| <= 1 on the beam); expanded in ξ they grow to
    ~1e7 with alternating signs, and the degree-17 shortening integrals lost up to 1e-4 of their
    value near ξ = 1 to cancellation."""
    xi = (1 + U) / 2
    factor = xi ** 2 if support == "cantilever" else xi * (1 - xi)
    return [sp.expand(factor * sp.legendre(k, U)) for k in range(NMAX)]


def _d_dxi(f: sp.Expr) -> sp.Expr:
    return sp.expand(2 * f.diff(U))  # du/dξ = 2


def _integral_from_0(f: sp.Expr) -> sp.Expr:
    """∫0^ξ f dξ' of a polynomial in u: ½ ∫_-1^u f du'."""
    antiderivative = sp.Poly(f, U).integrate().as_expr()
    return sp.expand((antiderivative - antiderivative.subs(U, -1)) / 2)


def _in_xi(m: sp.Matrix) -> sp.Matrix:
    """A polynomial matrix in u evaluated at u = 2ξ - 1 (kept in u: the generated code forms u once)."""
    return m.subs(U, 2 * XI - 1)


def beam_basis(support: str) -> list[NamedMatrix]:
    """N, dN/dξ, d²N/dξ² (3 x NMAX) and the shortening integrals S_kl(ξ) = ∫0^ξ N_k' N_l' dξ."""
    n = beam_functions(support)
    slopes = [_d_dxi(f) for f in n]
    rows = sp.Matrix([n, slopes, [_d_dxi(f) for f in slopes]])
    short = sp.Matrix(NMAX, NMAX, lambda i, j: _integral_from_0(slopes[i] * slopes[j]))
    return [NamedMatrix(f"{support}_basis", _in_xi(rows), XI_ARGS,
                        f"[N; N'; N''] of the {support} Ritz functions at ξ (derivatives in ξ)", "1",
                        "u = Σ q_i φ_i"),
            NamedMatrix(f"{support}_shortening", _in_xi(short), XI_ARGS,
                        f"S_kl(ξ) = ∫0^ξ N_k' N_l' dξ of the {support} functions (axial ψ_kl = -S_kl/L)", "1",
                        "ψ_ij (quadratic strain ε11 = u1' + ½ w'²)")]


def _poly_hessian(expr: sp.Expr, q) -> sp.Matrix:
    """sympy.hessian of an expression polynomial in q, differentiated as a Poly in q (sympy's diff walks the
    expanded sum once per entry)."""
    poly = sp.Poly(expr, *q)
    return sp.Matrix(len(q), len(q), lambda k, l: poly.diff(q[k]).diff(q[l]).as_expr())


def held_membrane(support: str = "pinned") -> list[NamedMatrix]:
    """Mid-plane stretching of a beam whose ends are held (immovable axial supports at ξ = 0, 1).

    The quadratic strain ε11 = u1'/L + ½ (w'/L)² (primes: d/dξ, w' = Σ q_k N_k' per plane; the
    two planes add) carries the axial force N = EA ε11. Without axial inertia or load N' = 0:
    ε11 = ε̄ is uniform, u1(ξ) = L ∫0^ξ (ε̄ - ½ (w'/L)²) dξ, and u1(1) = 0 fixes ε̄. Solved here
    symbolically for the Ritz functions: ε̄ = Σ q_k q_l H_kl / (2 L²) with the mode-slope
    integrals H_kl = ∫0^1 N_k' N_l' dξ, the held axial field ψ_kl = ∂²u1/∂q_k∂q_l =
    (ξ H_kl - S_kl(ξ))/L, and the strain energy ½ EA L ε̄² = EA/(8 L³) Σ Γ_ijkl q_i q_j q_k q_l,
    Γ_ijkl = H_ij H_kl (the Duffing term of N = EA/(2L) ∫ w'² dx)."""
    n = beam_functions(support)
    q = sp.symbols(f"q1:{NMAX + 1}", real=True)
    length, eps = sp.symbols("L eps", positive=True)
    slope = sum(qk * _d_dxi(f) for qk, f in zip(q, n))
    u1 = length * _integral_from_0(sp.expand(eps - slope ** 2 / (2 * length ** 2)))
    eps_held = sp.solve(u1.subs(U, 1), eps)[0]
    u1 = sp.expand(u1.subs(eps, eps_held))
    gram = (_poly_hessian(eps_held, q) * length ** 2).applyfunc(sp.simplify)
    held = (_poly_hessian(u1, q) * length).applyfunc(sp.expand)
    if gram.free_symbols or held.free_symbols - {U}:
        raise ValueError("the held-end membrane fields depend on more than ξ")
    return [NamedMatrix(f"{support}_slope_gram", gram, (),
                        f"mode-slope integrals H_kl = ∫0^1 N_k' N_l' dξ of the {support} functions "
                        "(Γ_ijkl = H_ij H_kl)", "1", "membrane strain energy EA/(8L³) Σ Γ_ijkl q_i q_j q_k q_l"),
            NamedMatrix(f"{support}_held_axial", _in_xi(held), XI_ARGS,
                        f"L ∂²u1/∂q_k∂q_l = ξ H_kl - S_kl(ξ) of the {support} functions with held ends "
                        "(axial ψ_kl = (ξ H_kl - S_kl)/L)", "1", "ψ_ij with held ends (uniform ε11)")]


def module_specs() -> list[ModuleSpec]:
    functions = [rigid_fields_matrix(), roller_matrix(), *beam_basis("cantilever"), *beam_basis("pinned"),
                 *held_membrane("pinned")]
    return [ModuleSpec("trolley_elastic", "Rigid fields of the roller DOFs, roller deflections and beam Ritz bases "
                       "of the elastic trolley.", SOURCE, functions),
            ModuleSpec("trolley_elastic_lagrange", "Small elastic trolley by Lagrange's equations (test route).",
                       SOURCE, [residual := lagrange_model()], lagrange_dynamics(residual))]


def directional(expr: sp.Expr, seeds: dict, memo: dict | None = None) -> sp.Expr:
    """Σ_a ∂expr/∂a · seeds[a] (e.g. d/dt by the chain rule with seeds {q: q̇, q̇: q̈}) by the sum, product and
    integer power rules on expr's tree, each distinct subtree once; ``memo`` ({subtree: its derivative}) carries
    that over calls with the same seeds. sympy's diff walks the whole tree once per variable instead."""
    memo = {} if memo is None else memo
    if expr in memo:
        return memo[expr]
    if expr in seeds:
        out = sp.sympify(seeds[expr])
    elif not expr.args:
        out = sp.S.Zero
    elif expr.is_Add:
        out = sp.Add(*[directional(a, seeds, memo) for a in expr.args])
    elif expr.is_Mul:
        parts = [(k, directional(a, seeds, memo)) for k, a in enumerate(expr.args)]
        out = sp.Add(*[sp.Mul(*expr.args[:k], d, *expr.args[k + 1:]) for k, d in parts if d != 0])
    elif expr.is_Pow and expr.exp.is_Integer:
        d = directional(expr.base, seeds, memo)
        out = expr.exp * expr.base ** (expr.exp - 1) * d if d != 0 else sp.S.Zero
    else:
        raise ValueError(f"no chain rule for {type(expr).__name__}")
    memo[expr] = out
    return out


def lagrange_dynamics(residual: NamedMatrix) -> Dynamics:
    """The small model's motion for solve_ivp: y = (q, q̇), M(q) = diag(E, ∂R/∂q̈), F = (q̇, -R at q̈ = 0),
    R the residual (linear in q̈), with the frame's motion (V, ω, their rates, ν) held at the values
    of p. M depends on q: rhs only, no Jacobian."""
    q, qd, qdd, rest = (residual.args[i:j] for i, j in ((0, 7), (7, 14), (14, 21), (21, None)))
    accelerations = sp.Matrix([a.symbol for a in qdd])
    memos = [{} for _ in accelerations]  # one per column: the rows share subtrees
    mass = sp.Matrix(len(residual.matrix), len(accelerations),
                     lambda i, j: directional(residual.matrix[i], {accelerations[j]: 1}, memos[j]))
    if mass.free_symbols & set(accelerations):
        raise ValueError("the Lagrange residual is not linear in the accelerations")
    rate = sp.Matrix.vstack(sp.Matrix([a.symbol for a in qd]), -residual.matrix.xreplace({s: 0 for s in accelerations}))
    return Dynamics(q + qd, rest, rate, sp.diag(sp.eye(7), mass), jacobian=False,
                    meaning="the small elastic trolley of Lagrange's equations in a frame of constant motion")


def lagrange_model() -> NamedMatrix:
    """Second, independent route: the residual of Lagrange's equations of a small model — the
    five roller DOFs and one mode per plane of a cantilever (N = ξ²) along x2, rooted at
    (b1, 0, b3), with a tip mass — from its kinetic energy differentiated symbolically.

    The displacement field is the model's own (quadratic rigid fields, beam modes, their axial
    shortening, rotation-times-mode cross terms), but the equations come from
    d/dt ∂T/∂q̇ - ∂T/∂q + ∂V/∂q + ∂F/∂q̇ (the total time derivative by the chain rule through
    q, q̇, the frame velocity v and ω) instead of the invariants and d'Alembert's form. The
    beam's kinetic energy is integrated by 4-point Gauss (exact: |V|² has degree 6 in ξ)."""
    names = ["u2", "u3", "th1", "th2", "th3", "w1", "w3"]
    q = sp.symbols(" ".join(f"q_{n}" for n in names), real=True)
    qd = sp.symbols(" ".join(f"qd_{n}" for n in names), real=True)
    qdd = sp.symbols(" ".join(f"qdd_{n}" for n in names), real=True)
    v, dv = sp.Matrix(sp.symbols("V1:4", real=True)), sp.symbols("dV1:4", real=True)
    w, dw = sp.Matrix(sp.symbols("om1:4", real=True)), sp.symbols("dom1:4", real=True)
    m0, rho_a, length, tip = sp.symbols("m0 rho_a L_b m_tip", positive=True)
    com = sp.Matrix(sp.symbols("c1 c2 c3", real=True))
    inertia = sp.symbols("I11 I22 I33", positive=True)
    b1, b3, g0 = sp.symbols("b1 b3 g0", real=True)
    ei = sp.symbols("EI1 EI3", positive=True)
    k = sp.symbols("k1:6", positive=True)
    c = sp.symbols("d1:6", nonnegative=True)
    nu = sp.Matrix(sp.symbols("nu1:4", real=True))
    qv, qdv = sp.Matrix(q), sp.Matrix(qd)
    q0 = dict(zip(Q0, q[:5]))

    def velocity(r):
        return v + w.cross(r) + r.jacobian(qv) * qdv

    # trolley: r̃ = P ρ + p is affine in ρ, so ∫|V|² dm needs only m, m c and J = ∫ ρ ρᵀ dm
    r_trolley = (sp.Matrix(X) + quadratic_displacement()).xreplace(q0)
    vel = velocity(r_trolley)
    P = vel.jacobian(sp.Matrix(X))
    p = vel.xreplace({x: 0 for x in X})
    J = kin.second_moment(sp.diag(*inertia), kin.SYMPY) + m0 * com * com.T
    T = ((P * J * P.T).trace() + 2 * (p.T * P * com)[0] * m0 + m0 * (p.T * p)[0]) / 2
    # beam along x2: modes along x1 and x3, axial shortening ½∫ w'² dx, cross terms θ × w
    e1, e2, e3 = sp.eye(3)[:, 0], sp.eye(3)[:, 1], sp.eye(3)[:, 2]
    theta = sp.Matrix(q[2:5])

    def beam_point(xi):
        rho = sp.Matrix([b1, xi * length, b3])
        wv = (q[5] * e1 + q[6] * e3) * xi ** 2
        axial = -(q[5] ** 2 + q[6] ** 2) * sp.Rational(4, 3) * xi ** 3 / (2 * length) * e2
        return rho + quadratic_displacement(rho).xreplace(q0) + wv + theta.cross(wv) + axial

    z = sp.Symbol("z")
    roots = sp.Poly(sp.legendre(4, z), z).nroots(n=20)
    dleg = sp.legendre(4, z).diff(z)
    gauss = [((1 + r) / 2, 1 / ((1 - r ** 2) * dleg.subs(z, r) ** 2)) for r in roots] + [(1, None)]
    Vg = g0 * (nu.T * (m0 * (r_trolley.jacobian(sp.Matrix(X)) * com + r_trolley.xreplace({x: 0 for x in X}))))[0]
    for xi, wgt in gauss:
        mass = tip if wgt is None else rho_a * length * wgt
        r = beam_point(xi)
        vb = velocity(r)
        T += mass * (vb.T * vb)[0] / 2
        Vg += g0 * mass * (nu.T * r)[0]
    d = sp.Matrix([quadratic_displacement(point)[axis] for point, axis in ROLLERS]).xreplace(q0)
    V = sum(ki * di ** 2 for ki, di in zip(k, d)) / 2 + Vg
    V += (ei[0] * q[5] ** 2 + ei[1] * q[6] ** 2) * 4 / (2 * length ** 3)  # ∫ (N'')² dξ = 4
    dd = d.jacobian(qv) * qdv
    rayleigh = sum(ci * x ** 2 for ci, x in zip(c, dd)) / 2
    rates = dict(zip(q + qd + tuple(v) + tuple(w), qd + qdd + dv + dw))  # the total time derivative
    rows, memo = [], {}  # memo: subtrees shared by the rows are differentiated once
    for i in range(7):
        total = directional(directional(T, {qd[i]: 1}), rates, memo)
        rows.append(total - directional(T, {q[i]: 1}) + V.diff(q[i]) + rayleigh.diff(qd[i]))
    args = args_of([(s, f"coordinate {n}", "m or rad") for s, n in zip(q, names)]
                   + [(s, f"rate of {n}", "m/s or rad/s") for s, n in zip(qd, names)]
                   + [(s, f"acceleration of {n}", "m/s^2 or rad/s^2") for s, n in zip(qdd, names)]
                   + [(s, f"velocity of O, component {i + 1} (frame)", "m/s") for i, s in enumerate(v)]
                   + [(s, f"d/dt of that component {i + 1}", "m/s^2") for i, s in enumerate(dv)]
                   + [(s, f"ω component {i + 1}", "rad/s") for i, s in enumerate(w)]
                   + [(s, f"d/dt of ω component {i + 1}", "rad/s^2") for i, s in enumerate(dw)]
                   + [(s, f"upward unit vector ν, component {i + 1}", "1") for i, s in enumerate(nu)]
                   + [(m0, "trolley mass", "kg")] + [(s, f"trolley centre of mass {s}", "m") for s in com]
                   + [(s, f"trolley central inertia {s}", "kg m^2") for s in inertia]
                   + [(rho_a, "beam mass per length", "kg/m"), (length, "beam length", "m"),
                      (tip, "tip mass", "kg"), (b1, "beam root x1", "m"), (b3, "beam root x3", "m")]
                   + [(s, f"beam bending stiffness {s}", "N m^2") for s in ei]
                   + [(s, f"roller stiffness {s}", "N/m") for s in k] + [(s, f"roller damping {s}", "N s/m") for s in c]
                   + [(g0, "gravitational acceleration", "m/s^2")]) + GEOMETRY_ARGS
    return NamedMatrix("lagrange_residual", sp.Matrix(rows), args,
                       "d/dt ∂T/∂q̇ - ∂T/∂q + ∂V/∂q + ∂F/∂q̇ of the small elastic trolley (7 coordinates)",
                       "N or N m", "(1)-(8) by Lagrange's equations")
