"""The structural model method: a, b, c from conjugate vectors (eqs. (1)-(10)).

Works in any arithmetic ``ar`` (floats via :class:`symmech.smm.model.NumericArith`,
sympy via ``symmech.smm.derive.SymbolicArith``): ``ar(text)`` evaluates a model
expression, ``ar.sqrt``, ``ar.is_zero``, ``ar.sum`` and ``ar.prod`` do the rest. No energies,
no differentiation: for a chain vector v turned by angle q_a about e_a,
dv/dq_a = e_a x v (the conjugate vector, Table 1 / Table 2), a slide q_s adds
its unit vector u_s, and second derivatives are e_a x (e_b x v) and e_a x u_s.

Equation contract of the result: a q'' + b q' + c q = Q with
  a = L_a m L_a^T                                   (3)
  c = L_c c_d L_c^T + sum_i T_i d2l_i + sum_j P_j d2y_j   (7), (9)
      + sum_t M_t d2(twist_t)   (preloaded torsion springs, moment M_t [N m])
  b = L_b mu L_b^T                                  (10)
where T_i = c_i Delta_i is the spring tension in equilibrium. The principal central
moments of a body enter L_a through its principal axes p_k: column entries p_k . e_a.
"""
from __future__ import annotations

from dataclasses import dataclass, field

from symmech.core.scene import SymmechError
from symmech.smm.model import EQUILIBRIUM, GROUND, Effects, Mechanism


def turn(e, v, ez: bool):
    """e x v; ``ez`` marks e = (0, 0, 1), where e x v = (-v_y, v_x, 0) needs no products."""
    return (-v[1], v[0], 0 * v[2]) if ez else cross(e, v)


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    terms = [x * y for x, y in zip(a, b) if not (x == 0 or y == 0)]
    return sum(terms[1:], terms[0]) if terms else 0 * a[0]


def _vsum(ar, vectors):
    return tuple(ar.sum([v[i] for v in vectors]) for i in range(3))


def _nonzero(ar, v) -> bool:
    return not all(ar.is_zero(x) for x in v)


@dataclass
class PointKinematics:
    """Position r [m] of a point in equilibrium, first derivatives D[a] = dr/dq_a and
    second derivatives H[(a, b)] = d2r/dq_a dq_b (a <= b by coordinate index), all 3-vectors."""

    r: tuple
    D: dict
    H: dict


class Geometry:
    """The model's vectors and axes evaluated in arithmetic ``ar``."""

    def __init__(self, m: Mechanism, ar):
        self.m = m
        self.ar = ar
        self.index = {name: i for i, name in enumerate(m.coordinate_names)}
        self.axis = {c.name: tuple(ar(t, f"coordinate '{c.name}'") for t in c.axis) for c in m.coordinates}
        self.ez = {c.name: tuple(c.axis) == ("0", "0", "1") for c in m.coordinates}
        self.vector = {p.name: tuple(ar(t, f"point '{p.name}'") for t in p.vector) for p in m.points.values()}

    def pair(self, a: str, b: str) -> tuple[str, str]:
        return (a, b) if self.index[a] <= self.index[b] else (b, a)


def chain_kinematics(g: Geometry, point: str, second: bool) -> PointKinematics:
    """Vector-chain form: walk the chain root -> point, summing conjugate vectors."""
    ar, m = g.ar, g.m
    chain = m.chain(point)
    r = _vsum(ar, [g.vector[p.name] for p in chain])
    turned: dict[str, list] = {}       # a -> vectors turned by q_a
    slid: dict[str, int] = {}          # s -> number of chain vectors it lengthens
    pair_v: dict[tuple, list] = {}     # (a, b) in turn order -> names of vectors turned by both
    pair_s: dict[tuple, int] = {}      # (a, s) -> count
    for p in chain[1:]:
        v = g.vector[p.name]
        for i, a in enumerate(p.turns):
            turned.setdefault(a, []).append(v)
            if second:
                for b in p.turns[i:]:
                    pair_v.setdefault((a, b), []).append(p.name)
                for s in p.slides:
                    pair_s[(a, s)] = pair_s.get((a, s), 0) + 1
        for s in p.slides:
            slid[s] = slid.get(s, 0) + 1
    D = {}
    for a, vs in turned.items():
        D[a] = turn(g.axis[a], _vsum(ar, vs), g.ez[a])
    for s, n in slid.items():
        u = tuple(n * x for x in g.axis[s])
        D[s] = _vsum(ar, [D[s], u]) if s in D else u
    parts: dict[tuple, list] = {}
    # with relative angles many pairs turn the same vectors: sum and turn each set once
    planar = {}
    for (a, b), vs in pair_v.items():
        key = tuple(vs)
        if g.ez[a] and g.ez[b] and key in planar:
            h = planar[key]
        else:
            h = turn(g.axis[a], turn(g.axis[b], _vsum(ar, [g.vector[n] for n in vs]), g.ez[b]), g.ez[a])
            if g.ez[a] and g.ez[b]:
                planar[key] = h
        parts.setdefault(g.pair(a, b), []).append(h)
    for (a, s), n in pair_s.items():
        parts.setdefault(g.pair(a, s), []).append(turn(g.axis[a], tuple(n * x for x in g.axis[s]), g.ez[a]))
    H = {k: vs[0] if len(vs) == 1 else _vsum(ar, vs) for k, vs in parts.items()}
    D = {k: v for k, v in D.items() if _nonzero(ar, v)}
    H = {k: v for k, v in H.items() if _nonzero(ar, v)}
    return PointKinematics(r, D, H)


@dataclass
class Assembly:
    """Factors of a, b, c (eqs. (3), (7), (9), (10)) over coordinates ``coords``.

    Column lists hold (label, {coordinate index: value}); ``*_diag`` the matching
    diagonal entries (masses and moments [kg, kg m^2], stiffnesses [N/m, N m/rad],
    viscosities). ``preload`` and ``gravity`` map (i, j), i <= j, to the second-order
    stiffness terms; ``residual`` is dPi/dq in the given configuration (eq. (5)).
    """

    coords: list[str]
    La: list = field(default_factory=list)
    ma: list = field(default_factory=list)
    Lc: list = field(default_factory=list)
    kc: list = field(default_factory=list)
    Lb: list = field(default_factory=list)
    mb: list = field(default_factory=list)
    preload: dict = field(default_factory=dict)
    gravity: dict = field(default_factory=dict)
    residual: dict = field(default_factory=dict)
    lengths: dict = field(default_factory=dict)
    tensions: dict = field(default_factory=dict)


def assemble(m: Mechanism, ar, kinematics=chain_kinematics, effects: Effects | None = None,
             tensions: dict | None = None) -> Assembly:
    """The SMM factors of a, b, c for ``m`` in arithmetic ``ar``.

    ``kinematics(geometry, point, second)`` supplies conjugate vectors (the
    vector-chain form by default; ``symmech.smm.derive.graph_kinematics`` is the
    graph form (11)). ``effects`` defaults to the model's own. ``tensions`` gives
    the tension [N] of springs (moment [N m] of torsion springs) whose preload is
    ``"equilibrium"`` (see :func:`tension_system`).
    """
    eff = effects or m.effects
    tensions = tensions or {}
    g = Geometry(m, ar)
    idx = g.index
    out = Assembly(list(m.coordinate_names))
    grav = ar(m.gravity, "gravity.g")
    gdir = tuple(ar(t, "gravity.direction") for t in m.gravity_direction)
    has_gravity = not ar.is_zero(grav)
    need_second = set()
    for s in m.springs:
        need_second |= {s.a, s.b}
    if has_gravity:
        need_second |= {b.com for b in m.bodies}
    cache: dict[str, PointKinematics] = {}

    def kin(p):
        if p not in cache:
            cache[p] = kinematics(g, p, p in need_second and (eff.preload or eff.gravity))
        return cache[p]

    def add(target, key, value):
        target.setdefault(key, []).append(value)

    # inertia, eq. (3): translational columns per body and axis, then rotational ones
    for b in m.bodies:
        mass = ar(b.mass, f"body '{b.name}'")
        k = kin(b.com)
        for axis, label in enumerate("xyz"):
            col = {idx[a]: d[axis] for a, d in k.D.items() if not ar.is_zero(d[axis])}
            if col and not ar.is_zero(mass):
                out.La.append((f"{b.name}.{label}", col))
                out.ma.append(mass)
        J = [ar(t, f"body '{b.name}'") for t in b.inertia]
        # rotational columns: principal axis k . e_a (the paper's J_x, J_y, J_z rows), so m stays diagonal
        P = None if b.axes is None else [tuple(ar(t, f"body '{b.name}'") for t in ax) for ax in b.axes]
        for axis, label in enumerate("xyz"):
            comp = {a: g.axis[a][axis] if P is None else dot(P[axis], g.axis[a]) for a in b.turns}
            col = {idx[a]: v for a, v in comp.items() if not ar.is_zero(v)}
            if col and not ar.is_zero(J[axis]):
                out.La.append((f"{b.name}.J{label}", col))
                out.ma.append(J[axis])
        if has_gravity:
            weight = tuple(mass * grav * x for x in gdir)  # force of gravity [N]
            for a, d in k.D.items():
                add(out.residual, idx[a], -dot(weight, d))
            if eff.gravity:
                seen: dict[int, object] = {}  # identical H vectors (shared by many pairs) dotted once
                for (a, bb), h in k.H.items():
                    if id(h) not in seen:
                        seen[id(h)] = -dot(weight, h)
                    add(out.gravity, (idx[a], idx[bb]), seen[id(h)])

    # springs, eqs. (5), (7), (9)
    for s in m.springs:
        ka, kb = kin(s.a), kin(s.b)
        d = tuple(x - y for x, y in zip(kb.r, ka.r))
        length = ar.sqrt(dot(d, d))
        if ar.is_zero(length) or (isinstance(length, float) and length < 1e-12):
            raise SymmechError(f"spring '{s.name}': its ends '{s.a}' and '{s.b}' coincide (zero length); "
                               "a spring needs a direction")
        e = tuple(x / length for x in d)
        k = ar(s.coef, f"spring '{s.name}'")
        if s.preload == EQUILIBRIUM:
            if s.name not in tensions:
                raise ValueError(f"spring '{s.name}': tension from equilibrium not supplied")
            tension = tensions[s.name]
        elif s.preload is not None:
            tension = ar(s.preload, f"spring '{s.name}'")
        elif s.free_length is not None:
            tension = k * (length - ar(s.free_length, f"spring '{s.name}'"))
        else:
            tension = 0 * k
        out.lengths[s.name] = length
        out.tensions[s.name] = tension
        dd = _diff(ar, ka.D, kb.D)
        col = {idx[a]: dot(e, v) for a, v in dd.items()}
        col = {i: v for i, v in col.items() if not ar.is_zero(v)}
        out.Lc.append((s.name, col))
        out.kc.append(k)
        for i, v in col.items():
            add(out.residual, i, tension * v)
        if eff.preload and not ar.is_zero(tension):
            hh = _diff(ar, ka.H, kb.H)
            names = sorted(dd, key=idx.get)
            along = {a: dot(e, dd[a]) for a in names}
            t_l = tension / length
            # T/l (dd_a . dd_b - (e . dd_a)(e . dd_b)): the turn of the spring axis, eq. (7)
            for ii, a in enumerate(names):
                for bb in names[ii:]:
                    terms = [ar.prod((t_l, x, y)) for x, y in zip(dd[a], dd[bb])
                             if not (ar.is_zero(x) or ar.is_zero(y))]
                    if not (ar.is_zero(along[a]) or ar.is_zero(along[bb])):
                        terms.append(-ar.prod((t_l, along[a], along[bb])))
                    if terms:
                        out.preload.setdefault((idx[a], idx[bb]), []).extend(terms)
            seen = {}
            for (a, bb), h in hh.items():
                if id(h) not in seen:
                    seen[id(h)] = dot(e, h)
                v = seen[id(h)]
                if not ar.is_zero(v):
                    add(out.preload, (idx[a], idx[bb]), tension * v)

    for t in m.torsion_springs:
        col = torsion_column(m, g, t)
        out.Lc.append((t.name, col))
        out.kc.append(ar(t.coef, f"torsion spring '{t.name}'"))
        if t.preload is None:
            continue
        if t.preload == EQUILIBRIUM:
            if t.name not in tensions:
                raise ValueError(f"torsion spring '{t.name}': moment from equilibrium not supplied")
            moment = tensions[t.name]
        else:
            moment = ar(t.preload, f"torsion spring '{t.name}'")
        for i, v in col.items():
            add(out.residual, i, moment * v)
        if eff.preload and not ar.is_zero(moment):
            for key, v in _twist_hessian(m, g, t).items():
                add(out.preload, key, moment * v)
    if eff.damping:
        for dmp in m.dampers:
            ka, kb = kin(dmp.a), kin(dmp.b)
            d = tuple(x - y for x, y in zip(kb.r, ka.r))
            length = ar.sqrt(dot(d, d))
            if ar.is_zero(length) or (isinstance(length, float) and length < 1e-12):
                raise SymmechError(f"damper '{dmp.name}': its ends '{dmp.a}' and '{dmp.b}' coincide (zero length)")
            e = tuple(x / length for x in d)
            col = {idx[a]: dot(e, v) for a, v in _diff(ar, ka.D, kb.D).items()}
            out.Lb.append((dmp.name, {i: v for i, v in col.items() if not ar.is_zero(v)}))
            out.mb.append(ar(dmp.coef, f"damper '{dmp.name}'"))
        for t in m.torsion_dampers:
            out.Lb.append((t.name, torsion_column(m, g, t)))
            out.mb.append(ar(t.coef, f"torsion damper '{t.name}'"))
    return out


def tension_system(m: Mechanism, ar, kinematics=chain_kinematics):
    """Eq. (5) for the unknown tensions T_u [N] (torsion springs: moments [N m]) of springs with
    preload ``"equilibrium"``: G T_u = -r0, with G (k x u) their L_c columns {row: value} and r0
    {row: value} the generalized forces of gravity and of the given preloads. Returns (names, G, r0)."""
    names = [s.name for s in m.springs + m.torsion_springs if s.preload == EQUILIBRIUM]
    asm = assemble(m, ar, kinematics, Effects(False, False, False), {n: 0 * ar("1") for n in names})
    columns = dict(zip([c[0] for c in asm.Lc], [c[1] for c in asm.Lc]))
    r0 = {i: ar.sum(t) for i, t in asm.residual.items()}
    return names, [columns[n] for n in names], r0


def _diff(ar, A: dict, B: dict) -> dict:
    """B - A for dicts of 3-vectors (missing keys are zero)."""
    out = {}
    for key in set(A) | set(B):
        if key in A and key in B:
            out[key] = tuple(y - x for x, y in zip(A[key], B[key]))
        elif key in B:
            out[key] = B[key]
        else:
            out[key] = tuple(-x for x in A[key])
    return {k: v for k, v in out.items() if _nonzero(ar, v)}


def torsion_column(m: Mechanism, g: Geometry, t) -> dict:
    """d(relative rotation of body b w.r.t. a about the axis)/dq: axis . (sum e_b - sum e_a)."""
    ar = g.ar
    axis = tuple(ar(x, f"torsion element '{t.name}'") for x in t.axis)
    col = {}
    for sign, body in ((1, t.b), (-1, t.a)):
        for a in m.body_turns(body) if body != GROUND else ():
            col.setdefault(g.index[a], []).append(sign * dot(axis, g.axis[a]))
    col = {i: ar.sum(v) for i, v in col.items()}
    return {i: v for i, v in col.items() if not ar.is_zero(v)}


def _twist_hessian(m: Mechanism, g: Geometry, t) -> dict:
    """d2 twist/dq_i dq_j {(i, j), i < j: value} at q = 0, twist = n . vee(R_a^T R_b).

    R_a^T R_b is the product of rotations R_f(s_f q_f): body a's turns reversed with
    s = -1, then body b's with s = +1. To second order a product of rotations is
    I + sum_f s_f q_f [e_f] + sum_f (s_f q_f)^2 [e_f]^2 / 2 + sum_{f<g} s_f s_g q_f q_g [e_f][e_g];
    [e]^2 is symmetric and the skew part of [e_f][e_g] is [e_f x e_g] / 2, so the q_i q_j
    coefficient of the twist is sum over factor pairs f < g on (i, j) of s_f s_g n . (e_f x e_g) / 2.
    A coordinate shared by both bodies pairs with itself only through e x e = 0 (no diagonal)."""
    ar = g.ar
    n = tuple(ar(x, f"torsion element '{t.name}'") for x in t.axis)
    factors = [(-1, a) for a in reversed(m.body_turns(t.a))] + [(1, a) for a in m.body_turns(t.b)]
    parts: dict = {}
    for f, (sf, a) in enumerate(factors):
        for sg, b in factors[f + 1:]:
            if a == b or (g.ez[a] and g.ez[b]):
                continue
            v = dot(n, cross(g.axis[a], g.axis[b]))
            if not ar.is_zero(v):
                parts.setdefault(g.pair(a, b), []).append(sf * sg * v / 2)
    out = {(g.index[a], g.index[b]): ar.sum(v) for (a, b), v in parts.items()}
    return {k: v for k, v in out.items() if not ar.is_zero(v)}


def triple_product(ar, columns, diag, n):
    """Upper-triangle entries {(i, j): [terms]} of L diag L^T for sparse columns."""
    out: dict = {}
    for (_, col), w in zip(columns, diag):
        items = sorted(col.items())
        for ii, (i, vi) in enumerate(items):
            for j, vj in items[ii:]:
                out.setdefault((i, j), []).append(ar.prod((w, vi, vj)))
    return out
