"""Layer 1: the elastic trolley's assembled equations for one model, as a module the C target prints.

Not a ``derive*`` producer of `symmech codegen`: nothing here is fixed, every module it makes is a scene's.

The elastic model's equations M(q) q̈ + R(t, q, q̇) = 0 are sums over its invariants (the Gram tensor G, the
first moments S1, the sparse ψ part of A(q), K, D, the roller map and the held beams' membrane blocks,
docs/trolley-elastic.md; the compiled engine's ``_terms`` and ``_resultants``). Their sizes and sparsity
depend on the scene, so the module is derived per model at export time (``symmech export``), with the
invariants as numbers: a term whose coefficient is zero is never formed (nine tenths of G on the bundled
helix), and the emitter's CSE shares the rest. Its text carries the usual hash header.

Functions (C99 via :mod:`symmech.core.emit`), the two the exported model calls: ``rate_and_mass_block``, F =
(q̇, -R) of M y' = F with M = diag(1, A Gtr Aᵀ) over the state y = (q, q̇) with parameters p = (the rollers'
stiffnesses, dampings and preloads, the 12 frame channels at t: load a0 + g0 ν, ω, ω̇, v0), then the block of M
below its identity rows alone (at a prescribed speed its lower triangle: M(q) is symmetric), from (t, y, p) with
one CSE over both, what the model's solve reads at each rate evaluation; ``outputs`` (P0…P5, the roller
deflections, and per probe its displacement, elastic deflection and overload) from (q, q̇, q̈, p). F and M alone
(``rate``, ``rate_mass``) are not printed: the module has its dynamics' layout, not its rate functions.

Its symbols carry no assumptions and are named as the printed code's arguments, so the emitter prints the
expressions as derived (renaming real symbols rebuilt every tree, and sympy's assumptions made each product
cost more to build: together about half the derivation's time).

With traction (:func:`traction_spec`) s and V0 are states, y = (q, s, q̇, V0): the 12 channels follow from the
15 geometry channels at s (parameters) and V0, V̇0 (the compiled engine's ``_motion``), and q̈, V̇0 solve
M q̈ + R = 0 together with F1 = P0(t, V0) (the x1 resultant against the traction law, the engine's
``_traction_terms``), both affine in (q̈, V̇0): M = diag(1, L) with L their coefficients, F = (q̇, V0, -R, P0 - F1)
at q̈ = V̇0 = 0. ``outputs`` then read (y, q̈, V̇0, p).
"""
from __future__ import annotations

import sympy as sp

from symmech.core.derivation import Dynamics, ModuleSpec, NamedMatrix, args_of
from symmech.trolley.derive import SOURCE
from symmech.trolley.elastic.layout import CHANNELS as CHANNEL_LAYOUT, FIELDS, GEOMETRY as GEOMETRY_LAYOUT, N_ROLLER_DOFS

NAME = "elastic_assembly"
ROLLERS = 5


def _symbols(layout) -> tuple:
    """One symbol per slot of ``layout``, in its order (``load1``, ``load2``, ... for a field ``load`` of
    3), and their arguments (symbol, meaning with the component, unit)."""
    symbols = tuple(sp.Symbol(f"{f.name}{i + 1}") for f in layout.fields for i in range(f.size))
    rows = [(f.meaning, f.unit, i) for f in layout.fields for i in range(f.size)]
    return symbols, args_of([(x, f"{meaning}, x{i + 1} component", unit)
                             for x, (meaning, unit, i) in zip(symbols, rows)])


def _by_field(layout, values) -> dict:
    """{field name: its slots of ``values``} of a sequence in the order of ``layout``."""
    return {f.name: tuple(values[layout.slice(f.name)]) for f in layout.fields}


# the frame channels of the table in t and the geometry channels of the traction table in s, as declared
CHANNELS, CHANNEL_ARGS = _symbols(CHANNEL_LAYOUT)
GEOMETRY, GEOMETRY_ARGS = _symbols(GEOMETRY_LAYOUT)
STIFFNESS = sp.symbols(f"roller_k1:{ROLLERS + 1}")
DAMPING = sp.symbols(f"roller_c1:{ROLLERS + 1}")
PRELOAD = sp.symbols(f"roller_pre1:{ROLLERS + 1}")
ROLLER_ARGS = args_of([(k, f"stiffness of the roller of P{r + 1}", "N/m") for r, k in enumerate(STIFFNESS)]
                      + [(c, f"damping of the roller of P{r + 1}", "N s/m") for r, c in enumerate(DAMPING)]
                      + [(x, f"preload of the roller of P{r + 1} (clamped pair law)", "m")
                         for r, x in enumerate(PRELOAD)])


def assembly_spec(model: dict, names: list[str], units: list[str]) -> ModuleSpec:
    """The module ``elastic_assembly`` of one elastic model. ``model``: the engine's record
    (``symmech.trolley.elastic.layout.MODEL``) as nested lists by field name (``gram_x`` as (F, 9, F)), with
    ``mass`` [kg], ``rollers`` and ``clamped`` (0/1), ``probe_fields`` (F, probes, 3) [m],
    ``probe_points`` (probes, 3) [m], ``elastic`` (F,) 1 on the elastic fields, ``g_ref`` [m/s²]; ``names``,
    ``units`` the N coordinates'."""
    n = len(names)
    q, qd, qdd = _coordinates(n)
    state = _state_args(q, qd, names, units)
    params = ROLLER_ARGS + CHANNEL_ARGS
    terms = _Terms(model, q, qd, CHANNELS)
    R = terms.residual()
    M = terms.mass_matrix()
    mass = sp.diag(sp.eye(n), M)
    dynamics = Dynamics(state, params, sp.Matrix(list(qd) + [-r for r in R]), mass=mass,
                        meaning="the elastic trolley in its track frame", jacobian=False)
    outputs = NamedMatrix("outputs", sp.Matrix(terms.outputs(qdd)), state + _acceleration_args(qdd, names, units)
                          + params, "P0…P5, roller deflections d1…d5, per probe u (3), e (3), n (3)", "N, m, g")
    block = M.lower_triangular()
    return ModuleSpec(NAME, "The elastic trolley's equations M(q) q'' + R = 0 and outputs, assembled from one "
                      "model's invariants", SOURCE, (outputs, rate_and_mass_block(dynamics, block)),
                      dynamics, rates=False)


def rate_and_mass_block(dynamics: Dynamics, block: sp.Matrix) -> NamedMatrix:
    """F (y's size), then the block of M below its identity rows row by row, from
    (t, y, p) as ``rate``: the exported model's solve needs both at each rate evaluation, and one CSE over both
    forms their common subexpressions (the frame's channels combined with q) once."""
    args = ((dynamics.time,) if dynamics.time else ()) + dynamics.state + dynamics.params
    return NamedMatrix("rate_and_mass_block", sp.Matrix([*dynamics.rate, *block]), args,
                       "F, then the block of M below its identity rows", "F's, then kg, kg m, kg m^2", whole=True)


# the traction law's variables: time and the speed of O along the track
TIME = sp.Symbol("t")
SPEED = sp.Symbol("V0")
ARC_LENGTH = sp.Symbol("s")
SPEED_RATE = sp.Symbol("dV0")


def traction_spec(model: dict, names: list[str], units: list[str], law: sp.Expr) -> ModuleSpec:
    """The module ``elastic_assembly`` of one elastic model under traction: state y = (q, s, q̇, V0), parameters
    the rollers' and the 15 geometry channels at s (GEOMETRY); ``law`` P0 [N] in TIME [s] and SPEED [m/s];
    ``model`` as :func:`assembly_spec` reads it, with ``g0`` [m/s²] (0 without gravity). F's last row is
    P0 - F1: an input force added there adds to the law."""
    n = len(names)
    q, qd, qdd = _coordinates(n)
    V, dV = SPEED, SPEED_RATE
    state = args_of([(q[i], f"coordinate {names[i]}", units[i]) for i in range(n)]
                    + [(ARC_LENGTH, "arc length of O along the track", "m")]
                    + [(qd[i], f"rate of {names[i]}", f"{units[i]}/s") for i in range(n)]
                    + [(V, "speed of O along the track", "m/s")])
    params = ROLLER_ARGS + GEOMETRY_ARGS
    terms = _Terms(model, q, qd, motion(V, dV, _number(model["g0"])))
    R = terms.residual()  # at q̈ = 0, affine in V̇0
    F1 = terms.resultant_x1(qdd)  # affine in q̈ and V̇0
    at_rest = {dV: 0, **{x: 0 for x in qdd}}
    L = sp.zeros(n + 1, n + 1)
    L[:n, :n] = terms.mass_matrix()
    L[:n, n] = sp.Matrix([sp.diff(r, dV) for r in R])
    L[n, :n] = sp.Matrix([[sp.diff(F1, x) for x in qdd]])
    L[n, n] = sp.diff(F1, dV)
    rate = [*qd, V, *[-r.xreplace(at_rest) for r in R], law - F1.xreplace(at_rest)]
    dynamics = Dynamics(state, params, sp.Matrix(rate), mass=sp.diag(sp.eye(n + 1), L),
                        time=args_of([(TIME, "time", "s")])[0], jacobian=False,
                        meaning="the elastic trolley in its track frame under traction")
    accelerations = _acceleration_args(qdd, names, units) + args_of([(dV, "rate of V0", "m/s^2")])
    outputs = NamedMatrix("outputs", sp.Matrix(terms.outputs(qdd)), state + accelerations + params,
                          "P0…P5, roller deflections d1…d5, per probe u (3), e (3), n (3)", "N, m, g")
    return ModuleSpec(NAME, "The elastic trolley's equations M(q) q'' + R = 0 with F1 = P0(t, V0) and outputs, "
                      "assembled from one model's invariants", SOURCE, (outputs, rate_and_mass_block(dynamics, L)),
                      dynamics, rates=False)


def motion(V, dV, g0) -> tuple:
    """The 12 frame channels (load, ω, ω̇, v0) at speed V [m/s] and its rate dV [m/s²] from the GEOMETRY channels
    (the compiled engine's ``_motion``)."""
    geo = _by_field(GEOMETRY_LAYOUT, GEOMETRY)
    e, k, nu, om, dom = (geo[name] for name in ("e", "k", "nu", "om", "dom"))
    frame = {"load": tuple(dV * e[i] + V ** 2 * k[i] + g0 * nu[i] for i in range(3)),
             "omega": tuple(V * om[i] for i in range(3)),
             "domega": tuple(dV * om[i] + V ** 2 * dom[i] for i in range(3)), "v0": tuple(V * e[i] for i in range(3))}
    return tuple(x for name in CHANNEL_LAYOUT.names for x in frame[name])


def _coordinates(n: int) -> tuple:
    """Symbols of q, q̇, q̈ (n each)."""
    return (sp.symbols(f"q0:{n}"), sp.symbols(f"qd0:{n}"), sp.symbols(f"qdd0:{n}"))


def _state_args(q, qd, names, units) -> tuple:
    return args_of([(q[i], f"coordinate {names[i]}", units[i]) for i in range(len(q))]
                   + [(qd[i], f"rate of {names[i]}", f"{units[i]}/s") for i in range(len(q))])


def _acceleration_args(qdd, names, units) -> tuple:
    return args_of([(qdd[i], f"acceleration of {names[i]}", f"{units[i]}/s^2") for i in range(len(qdd))])


def _number(x) -> sp.Expr:
    """An invariant's value as an exact binary float (printed with every digit)."""
    return sp.Float(float(x), 17)


def _dot(coefficients, values) -> sp.Expr:
    """Σ c_i v_i over the nonzero coefficients."""
    return sp.Add(*[_number(c) * v for c, v in zip(coefficients, values) if c != 0])


class _Terms:
    """The sums of the compiled engine's ``_terms``, ``_rollers``, ``_membrane`` and ``_resultants`` over one
    model's invariants."""

    def __init__(self, model: dict, q, qd, channels):
        """``channels``: the 12 frame channels (symbols or expressions) in the order of CHANNELS."""
        self.m, self.q, self.qd, self.channels = model, q, qd, channels
        self.n, self.f = len(q), len(model["gram_trace"])
        self.at = FIELDS.sized(N=self.n, P=self.f - 1 - self.n)  # the fields: r, the φ_a, the ψ_ab
        frame = _by_field(CHANNEL_LAYOUT, channels)
        load, w, dw = frame["load"], frame["omega"], frame["domega"]
        W = sp.Matrix([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
        dW = sp.Matrix([[0, -dw[2], dw[1]], [dw[2], 0, -dw[0]], [-dw[1], dw[0], 0]])
        self.load, self.W, self.B = sp.Matrix(load), W, W * W + dW
        self.rr = self.field_position()
        self.v = self.times_a(qd, q)
        psi = self.at.offset("psi")
        self.p2 = [0] * psi + self.times_a(qd, qd)[psi:]

    def field_position(self) -> list:
        """Coefficients of r + Σ q_a φ_a + ½ Σ q_a q_b ψ_ab over the fields (F)."""
        m, q = self.m, self.q
        pairs = [(sp.Rational(1, 2) if i == j else 1) * q[i] * q[j] for i, j in zip(m["pair_i"], m["pair_j"])]
        return [sp.Integer(1), *q, *pairs]

    def times_a(self, y, x) -> list:
        """y A(x) (F): Σ_b y_b (φ_b + Σ_c x_c ψ_bc)."""
        m = self.m
        out = [sp.Integer(0)] * self.f
        phi = self.at.offset("phi")
        for b in range(self.n):
            out[phi + b] += y[b]
            for e in range(m["ptr"][b], m["ptr"][b + 1]):
                out[m["col"][e]] += y[b] * x[m["qi"][e]]
        return out

    def a_times(self, z) -> list:
        """A(q) z (N) for z (F)."""
        m, q, phi = self.m, self.q, self.at.offset("phi")
        return [z[phi + b] + sp.Add(*[q[m["qi"][e]] * z[m["col"][e]] for e in range(m["ptr"][b], m["ptr"][b + 1])])
                for b in range(self.n)]

    def gram_pass(self, x) -> list:
        """X (F x 9) with X_k = Σ_l G_kl x_l, row-major 3 x 3 blocks."""
        return [[_dot(self.m["gram_x"][k][j], x) for j in range(9)] for k in range(self.f)]

    def rollers(self, q, qd) -> tuple[list, list]:
        """Roller deflections d and forces P1…P5 [m, N] (the linear or the clamped-pair law)."""
        m = self.m
        d = [_dot(m["rollers_map"][r], q[:N_ROLLER_DOFS]) for r in range(ROLLERS)]
        dd = [_dot(m["rollers_map"][r], qd[:N_ROLLER_DOFS]) for r in range(ROLLERS)]
        force = []
        for r in range(ROLLERS):
            k, c, pre = STIFFNESS[r], DAMPING[r], PRELOAD[r]
            spring = k * (sp.Max(pre - d[r], 0) - sp.Max(pre + d[r], 0)) if m["clamped"] else -k * d[r]
            force.append(spring - c * dd[r])
        return d, force

    def residual(self) -> list:
        """R (N) of M q̈ + R = 0 at q̈ = 0."""
        m, q, qd = self.m, self.q, self.qd
        X, Y = self.gram_pass(self.rr), self.gram_pass(self.v)
        B, W = list(self.B), list(self.W)
        z = [_dot(m["s1"][k], self.load) + _dot(m["gram_trace"][k], self.p2)
             + sp.Add(*[X[k][j] * B[j] + 2 * Y[k][j] * W[j] for j in range(9)]) for k in range(self.f)]
        R = [r + _dot(m["stiffness"][b], q) + _dot(m["damping"][b], qd) for b, r in enumerate(self.a_times(z))]
        for blk, size in enumerate(m["block_size"]):  # held beams' membrane force 4 c (xᵀ H x) H x
            idx = m["block_index"][blk][:size]
            H = [row[:size] for row in m["block_h"][blk][:size]]
            hx = [_dot(H[i], [q[j] for j in idx]) for i in range(size)]
            quad = sp.Add(*[q[idx[i]] * hx[i] for i in range(size)])
            for i in range(size):
                R[idx[i]] += 4 * _number(m["block_c"][blk]) * quad * hx[i]
        if m["rollers"]:
            _, force = self.rollers(q, qd)
            for j in range(N_ROLLER_DOFS):
                R[j] -= _dot([m["rollers_map"][r][j] for r in range(ROLLERS)], force)
        return R

    def mass_matrix(self) -> sp.Matrix:
        """M = A Gtr Aᵀ (N x N)."""
        gtr = self.m["gram_trace"]
        AG = [self.a_times([_number(gtr[k][j]) for k in range(self.f)]) for j in range(self.f)]  # (A Gtr)[b, j]
        columns = [self.a_times([AG[k][j] for k in range(self.f)]) for j in range(self.n)]
        return sp.Matrix(self.n, self.n, lambda b, j: columns[j][b])

    def resultant_x1(self, qdd) -> sp.Expr:
        """F1: the x1 resultant of the forces on the body (P0) at q̈ = qdd."""
        m, s1 = self.m, self.m["s1"]
        acc = self.acceleration(qdd)
        first, fv, fa = ([_dot([s1[k][j] for k in range(self.f)], x) for j in range(3)] for x in (self.rr, self.v, acc))
        return _number(m["mass"]) * self.load[0] + fa[0] + sp.Add(
            *[self.B[0, j] * first[j] + 2 * self.W[0, j] * fv[j] for j in range(3)])

    def acceleration(self, qdd) -> list:
        """Coefficients (F) of the field acceleration at q̈ = qdd."""
        return [a + p for a, p in zip(self.times_a(qdd, self.q), self.p2)]

    def outputs(self, qdd) -> list:
        """P0 (the resultant along x1), P1…P5, d1…d5, then per probe u, e [m] and n [g] at q̈ = qdd."""
        m = self.m
        acc = self.acceleration(qdd)
        d, force = self.rollers(self.q, self.qd)
        out = [self.resultant_x1(qdd), *force, *d]
        frame = _by_field(CHANNEL_LAYOUT, self.channels)
        w, dw = sp.Matrix(frame["omega"]), sp.Matrix(frame["domega"])
        for k, point in enumerate(m["probe_points"]):
            field = [[m["probe_fields"][f][k][i] for f in range(self.f)] for i in range(3)]
            pos, vel, ddu = (sp.Matrix([_dot(field[i], x) for i in range(3)]) for x in (self.rr, self.v, acc))
            elastic = [_dot([c * e for c, e in zip(field[i], m["elastic"])], self.rr) for i in range(3)]
            a = self.load + dw.cross(pos) + w.cross(w.cross(pos)) + 2 * w.cross(vel) + ddu
            out += [pos[i] - _number(point[i]) for i in range(3)] + elastic
            out += [a[i] / _number(m["g_ref"]) for i in range(3)]
        return out
