"""Numeric SMM assembly (scipy.sparse), equilibrium search (eq. (6)) and modal analysis.

Equation contract: a q'' + b q' + c q = Q with a, b, c [SI by coordinate kind]
evaluated at the scene's parameter values; q are the generalized coordinates
measured from the equilibrium configuration.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg
import scipy.sparse

from symmech.core import kinematics as kin
from symmech.core.scene import SceneError, SymmechError
from symmech.smm import forms, structural
from symmech.smm.model import EQUILIBRIUM, Effects, Mechanism, NumericArith, number_text


@dataclass
class Numeric:
    """a, b, c (k x k, scipy.sparse CSR) with the parts of c, the equilibrium residual
    dPi/dq [N or N m], spring lengths [m] and tensions [N] in the configuration, and the
    stiffness factor L_c as rows (springs, then torsion springs) x k."""

    coords: list[str]
    a: scipy.sparse.csr_matrix
    b: scipy.sparse.csr_matrix
    c: scipy.sparse.csr_matrix
    c_preload: scipy.sparse.csr_matrix
    c_gravity: scipy.sparse.csr_matrix
    residual: np.ndarray
    lengths: dict
    tensions: dict
    L_c: scipy.sparse.csr_matrix


def _sparse(n: int, entries: dict) -> scipy.sparse.csr_matrix:
    if not entries:
        return scipy.sparse.csr_matrix((n, n))
    ij = np.array(list(entries.keys()), dtype=np.int64)
    v = np.array([math.fsum(t) for t in entries.values()])
    off = ij[:, 0] != ij[:, 1]
    rows = np.concatenate([ij[:, 0], ij[off, 1]])
    cols = np.concatenate([ij[:, 1], ij[off, 0]])
    return scipy.sparse.csr_matrix((np.concatenate([v, v[off]]), (rows, cols)), shape=(n, n))


def equilibrium_tensions(m: Mechanism) -> tuple[dict, list[int]]:
    """Tensions [N] of the springs with ``preload = "equilibrium"`` from eq. (5), and the
    indices of coordinates whose equations determine them (independent rows of G), in the
    row order of Gaussian elimination with partial pivoting at the parameter values."""
    names = [s.name for s in m.springs + m.torsion_springs if s.preload == EQUILIBRIUM]
    if not names:
        return {}, []
    # G: the L_c columns of those springs; r: dPi/dq with their tensions set to zero
    zero = assemble(m, Effects(False, False, False), {n: 0.0 for n in names})
    labels = [s.name for s in m.springs + m.torsion_springs]
    G = zero.L_c[[labels.index(n) for n in names]].toarray().T
    r = zero.residual
    k = len(m.coordinates)
    # G holds dl/dq: [1] for slides, [m] for angles; round-off is judged against 1 and the spring
    # lengths, so springs that move with no coordinate (G zero but for round-off) are indeterminate
    tol = 1e-10 * max(np.abs(G).max(), 1.0, max(zero.lengths.values(), default=0.0))
    rows: list[int] = []
    for i in range(k):
        if np.linalg.matrix_rank(G[rows + [i]], tol=tol) > len(rows):
            rows.append(i)
    # the field to fix: the preload of the first spring whose tension equilibrium should give
    fields = {s.name: f"{table}[{i}].preload" for table, springs in
              (("springs", m.springs), ("torsion_springs", m.torsion_springs)) for i, s in enumerate(springs)}
    field = fields[names[0]]
    if len(rows) < len(names):
        raise SceneError(field, f"springs {', '.join(names)}: equilibrium (5) does not fix their tensions "
                                "(statically indeterminate); give preload values")
    # the elimination order of partial pivoting: the symbolic solve (symmech.smm.derive) takes the
    # rows in this order, so it never divides by an entry that is zero up to round-off
    perm, _, _ = scipy.linalg.lu(G[rows])
    rows = [rows[i] for i in np.argmax(perm, axis=0)]
    T = np.linalg.solve(G[rows], -r[rows])
    miss = G @ T + r
    worst = int(np.argmax(np.abs(miss)))
    if abs(miss[worst]) > 1e-9 * max(np.abs(r).max(), 1.0):
        raise SceneError(field, f"springs {', '.join(names)} cannot balance the loads: dPi/dq = "
                                f"{miss[worst]:.3g} remains on coordinate '{m.coordinate_names[worst]}'")
    return dict(zip(names, T.tolist())), rows


def assemble(m: Mechanism, effects: Effects | None = None, tensions: dict | None = None) -> Numeric:
    """Numeric a, b, c of ``m`` at its parameter values (sparse). Planar mechanisms: the
    vectorised graph form (:mod:`symmech.smm.structural`); spatial ones: the term lists of
    :mod:`symmech.smm.forms`. ``tensions`` defaults to those solved from eq. (5)."""
    ar = NumericArith(m.values())
    eff = effects or m.effects
    if tensions is None:
        tensions = equilibrium_tensions(m)[0]
    if structural.applies(m, ar):
        return Numeric(list(m.coordinate_names), *structural.assemble(m, ar, eff, tensions))
    return assemble_terms(m, ar, eff, tensions)


def assemble_terms(m: Mechanism, ar: NumericArith, eff: Effects, tensions: dict) -> Numeric:
    """:func:`assemble` from the term lists of :mod:`symmech.smm.forms` (any mechanism)."""
    asm = forms.assemble(m, ar, effects=eff, tensions=tensions)
    n = len(asm.coords)
    pre = _sparse(n, asm.preload)
    grav = _sparse(n, asm.gravity)
    stiff = _sparse(n, forms.triple_product(ar, asm.Lc, asm.kc, n))
    res = np.zeros(n)
    for i, terms in asm.residual.items():
        res[i] = math.fsum(terms)
    return Numeric(asm.coords, _sparse(n, forms.triple_product(ar, asm.La, asm.ma, n)),
                   _sparse(n, forms.triple_product(ar, asm.Lb, asm.mb, n)),
                   (stiff + pre + grav).tocsr(), pre, grav, res, asm.lengths, asm.tensions, _columns(n, asm.Lc))


def _columns(n: int, columns: list) -> scipy.sparse.csr_matrix:
    """Rows (one per column label) of a factor given as [(label, {index: value})]."""
    r = [j for j, (_, col) in enumerate(columns) for _ in col]
    c = [i for _, col in columns for i in col]
    v = [float(x) for _, col in columns for x in col.values()]
    return scipy.sparse.csr_matrix((v, (r, c)), shape=(len(columns), n))


def check_mass(m: Mechanism, a: np.ndarray) -> None:
    """SceneError naming the coordinate (``coordinates[i]``) when the inertia matrix is
    (numerically) singular."""
    w, v = np.linalg.eigh(a)
    scale = max(abs(w).max(), 1e-300)
    if w[0] <= 1e-12 * scale:
        i = int(np.argmax(abs(v[:, 0])))
        worst = m.coordinate_names[i]
        raise SceneError(f"coordinates[{i}]", f"inertia matrix is singular (smallest eigenvalue {w[0]:.3g} of {scale:.3g}): "
                           f"coordinate '{worst}' moves no mass or moment of inertia")


# ---------------------------------------------------------------- equilibrium (6)

def _outer_turns(m: Mechanism, spatial: bool) -> dict:
    """For every coordinate, the angle coordinates turned before it (outermost first).

    Angles: the turns preceding it in every turns list of points and bodies; slides: the
    turns of the vectors they lengthen. The redrawn axis of a coordinate is its axis turned
    by these, so they must be the same wherever the coordinate appears; in a planar
    mechanism rotations commute and only the set matters (angles: nothing does)."""
    seen: dict[str, tuple] = {}

    def note(c, outer, where):
        key = tuple(outer) if spatial else frozenset(outer)
        if c in seen and seen[c][0] != key:
            raise SymmechError(f"equilibrium.solve: coordinate '{c}' is preceded by the turns "
                               f"{list(seen[c][2])} in {seen[c][1]} but by {list(outer)} in {where}; the "
                               "equilibrium search needs every coordinate turned by the same outer angles "
                               "wherever it appears")
        seen.setdefault(c, (key, where, tuple(outer)))

    for p in m.points.values():
        for i, a in enumerate(p.turns):
            if spatial:
                note(a, p.turns[:i], f"point '{p.name}'")
        for s in p.slides:
            note(s, p.turns, f"point '{p.name}'")
    for b in m.bodies:
        for i, a in enumerate(b.turns):
            if spatial:
                note(a, b.turns[:i], f"body '{b.name}'")
    return {c: v[2] for c, v in seen.items()}


def _is_spatial(m: Mechanism, ar) -> bool:
    """True unless all angle axes are parallel (planar: the rotations commute)."""
    axes = [np.array([ar(t) for t in c.axis]) for c in m.coordinates if c.kind == "angle"]
    return any(np.linalg.norm(np.cross(axes[0], e)) > 1e-12 for e in axes[1:])


def _twist_axis_only(m: Mechanism, ar, t) -> bool:
    """True when every turn of both bodies of torsion spring ``t`` is about its axis: then the
    twist is sum(+-q) exactly, for any q."""
    n = np.array([ar(x) for x in t.axis])
    return all(np.linalg.norm(np.cross(n, [ar(x) for x in m.coordinate(a).axis])) < 1e-12
               for a in m.body_turns(t.a) + m.body_turns(t.b))


def moved(m: Mechanism, q: np.ndarray) -> Mechanism:
    """The model ``m`` (drawn at q = 0) redrawn in the configuration q (k,) [rad, m].

    For a vector turned by [a, b, c] (outermost first) rotations about fixed axes give
    v(q + dq) = R_a(dq_a) R_b'(dq_b) R_c'(dq_c) (R* v0), R* = R_a(q_a) R_b(q_b) R_c(q_c),
    with the axes conjugated by the outer turns: e_b' = R_a(q_a) e_b, e_c' = R_a(q_a) R_b(q_b) e_c.
    So the redrawn model has the vectors R* v0, the conjugated axes and the same generalized
    coordinates shifted by q; this is exact for any q (not only to first order), provided every
    coordinate has the same outer turns wherever it appears (checked, the error names it).
    Slide directions and principal axes turn with their host's R*; a torsion spring keeps its
    free angle: its moment becomes M0 + k twist(q) (only twists about the spring axis alone)."""
    values = m.values()
    ar = NumericArith(values)
    idx = {c: i for i, c in enumerate(m.coordinate_names)}
    axes = {c.name: np.array([ar(t) for t in c.axis]) for c in m.coordinates}
    spatial = _is_spatial(m, ar)
    outer = _outer_turns(m, spatial)

    def rot(turns):
        R = np.eye(3)
        for a in turns:
            R = R @ kin.rodrigues(axes[a], q[idx[a]])
        return R

    def text(v):
        return tuple(number_text(x) for x in v)

    points = {}
    for p in m.points.values():
        v = np.array([ar(t) for t in p.vector])
        if p.parent is not None:
            for s in p.slides:
                v = v + q[idx[s]] * axes[s]
            v = rot(p.turns) @ v
        points[p.name] = replace(p, vector=text(v))
    coords = []
    for c in m.coordinates:
        if c.kind == "slide" or spatial:
            u = rot(outer.get(c.name, ())) @ axes[c.name]
            coords.append(replace(c, axis=text(u / np.linalg.norm(u))))
        else:
            coords.append(c)
    bodies = []
    for b in m.bodies:
        R = rot(b.turns)
        if b.axes is None and np.array_equal(R, np.eye(3)):
            bodies.append(b)
            continue
        P = np.eye(3) if b.axes is None else np.array([[ar(t) for t in ax] for ax in b.axes])
        bodies.append(replace(b, axes=tuple(text(R @ p) for p in P)))
    torsion = []
    geometry = forms.Geometry(m, ar) if m.torsion_springs else None
    for t in m.torsion_springs:
        if not _twist_axis_only(m, ar, t):
            raise SymmechError(f"equilibrium.solve: torsion spring '{t.name}' turns about axes other than its own "
                               f"axis {[ar(x) for x in t.axis]}; the equilibrium search handles torsion springs "
                               "whose bodies turn about the spring axis only")
        twist = sum(v * q[i] for i, v in forms.torsion_column(m, geometry, t).items())
        moment = (ar(t.preload) if t.preload is not None else 0.0) + ar(t.coef) * twist
        torsion.append(replace(t, preload=number_text(moment) if moment != 0 or t.preload is not None else None))
    return replace(m, points=points, coordinates=coords, bodies=bodies, torsion_springs=torsion)


def solve_equilibrium(m: Mechanism, tol: float = 1e-10, max_iter: int = 60) -> tuple[Mechanism, dict]:
    """Find dPi/dq = 0 (eq. (6)) by Newton's method on the SMM residual and tangent stiffness.

    Springs given by ``preload`` keep their free length l0 = l - T/c, torsion springs their
    free angle. Returns the model redrawn in equilibrium and a report {iterations,
    residual [N or N m], q (k,) [rad, m] from the drawn configuration}.
    """
    full = Effects(True, True, True)
    ar = NumericArith(m.values())
    springs = []
    for t in m.torsion_springs:
        if t.preload == EQUILIBRIUM:
            raise SymmechError(f"torsion spring '{t.name}': equilibrium.solve needs a preload value, "
                               "not preload = \"equilibrium\"")
    moved(m, np.zeros(len(m.coordinates)))  # refuses unsupported models before any work
    start = assemble(m, full)
    for s in m.springs:
        if s.preload == EQUILIBRIUM:
            raise SymmechError(f"spring '{s.name}': equilibrium.solve needs a preload value or a free length, "
                               "not preload = \"equilibrium\"")
        if s.preload is not None:
            k = ar(s.coef)
            if k == 0:
                raise SymmechError(f"spring '{s.name}': a preloaded spring of zero stiffness has no free length")
            s = replace(s, preload=None, free_length=number_text(start.lengths[s.name] - ar(s.preload) / k))
        springs.append(s)
    base = replace(m, springs=springs)
    q = np.zeros(len(m.coordinates))
    cur = base
    num = assemble(cur, full)
    scale = max(1.0, float(np.abs(num.c.toarray()).max()))
    norm = float(np.abs(num.residual).max())
    for it in range(max_iter):
        if norm <= tol * scale:
            return cur, {"iterations": it, "residual": norm, "q": q.tolist()}
        try:
            step = -np.linalg.solve(num.c.toarray(), num.residual)
        except np.linalg.LinAlgError:
            step = -np.linalg.lstsq(num.c.toarray(), num.residual, rcond=None)[0]
        t = 1.0
        while t > 1e-6:
            # Accumulate q and redraw from the base model: the redraw is exact for any q and the
            # redrawn model's coordinates are the base ones shifted by q, so the step (computed in
            # the redrawn model) adds to q; composing redraws would only accumulate round-off.
            trial = moved(base, q + t * step)
            tnum = assemble(trial, full)
            tnorm = float(np.abs(tnum.residual).max())
            if tnorm < norm:
                break
            t /= 2
        q, cur, num, norm = q + t * step, trial, tnum, tnorm
    raise SymmechError(f"equilibrium search did not converge in {max_iter} Newton steps "
                       f"(residual {norm:.3g}); give the equilibrium configuration in the scene")


# ---------------------------------------------------------------- modal analysis

@dataclass
class Modes:
    """Undamped modes of a q'' + c q = 0: omega2 [1/s^2] ascending, mass-normalised
    shapes (columns, phi^T a phi = I), ``kinds`` per mode (``rigid``, ``elastic``,
    ``unstable``; see :func:`classify`), damping ratios from the damped state-space
    eigenvalues (non-proportional damping allowed; None for rigid-body, unstable and
    overdamped modes), the spread max/min of the elastic omega^2 (the lowest lose about
    log10(spread) digits) and the condition number of the Jacobi-scaled stiffness
    (its non-zero eigenvalues)."""

    omega2: np.ndarray
    shapes: np.ndarray
    zeta: list
    kinds: list
    spread: float
    condition: float


def modes(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> Modes:
    w2, phi = scipy.linalg.eigh(c, a)
    kinds, condition = classify(c, w2)
    elastic = np.abs(w2[np.array(kinds) == "elastic"])
    spread = float(elastic.max() / elastic.min()) if len(elastic) else 1.0
    return Modes(w2, phi, damping_ratios(a, b, c, w2, kinds), kinds, spread, condition)


def classify(c: np.ndarray, omega2: np.ndarray) -> tuple[list[str], float]:
    """Kinds of the modes with eigenvalues ``omega2`` (ascending) of (c, a), and the condition
    number of the scaled stiffness.

    The number of rigid-body modes is the nullity of c (Sylvester's law of inertia), measured on
    the Jacobi-scaled D c D (D = diag(c)^-1/2): scaling by each coordinate's own stiffness makes a
    very stiff spring no reason to call a soft but real mode rigid. The null eigenvalues of D c D
    are those within 10 n eps of its largest; the modes with the smallest |omega^2| are rigid."""
    n = len(omega2)
    d = np.abs(np.diag(c))
    if not np.any(c):
        return ["rigid"] * n, 1.0
    scale = 1.0 / np.sqrt(np.maximum(d, np.finfo(float).eps * d.max()))
    lam = np.abs(scipy.linalg.eigvalsh(scale[:, None] * c * scale[None, :]))
    tol = 10 * n * np.finfo(float).eps * lam.max()
    nullity = int(np.sum(lam <= tol))
    nonzero = lam[lam > tol]
    rigid = set(np.argsort(np.abs(omega2))[:nullity].tolist())
    kinds = ["rigid" if i in rigid else "unstable" if x < 0 else "elastic" for i, x in enumerate(omega2)]
    return kinds, float(nonzero.max() / nonzero.min())


def damping_ratios(a, b, c, omega2, kinds) -> list:
    """zeta_r = -Re(lambda)/|lambda| of the state-space eigenvalues, matched to the undamped
    modes by |lambda| ~ omega (first-order state form, valid for non-proportional b)."""
    n = a.shape[0]
    if not np.any(b):
        return [0.0 if k == "elastic" else None for k in kinds]
    ainv = np.linalg.inv(a)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-ainv @ c, -ainv @ b]])
    lam = np.linalg.eigvals(A)
    lam = lam[np.argsort(np.abs(lam))]
    out = []
    used = np.zeros(len(lam), bool)
    for w2, kind in zip(omega2, kinds):
        if kind != "elastic":
            out.append(None)
            continue
        w = math.sqrt(w2)
        cand = np.where(~used & (lam.imag >= 0))[0]
        if len(cand) == 0:
            out.append(None)
            continue
        j = cand[np.argmin(np.abs(np.abs(lam[cand]) - w))]
        used[j] = True
        # an overdamped mode has two real roots that cannot be told apart from those of other
        # overdamped modes in general: no ratio (None), the runner warns
        if abs(lam[j].imag) < 1e-12 * abs(lam[j]):
            out.append(None)
            continue
        out.append(float(-lam[j].real / abs(lam[j])))
    return out


def free_response(a, b, c, q0, v0, t):
    """q(t) [n_t x k] of a q'' + b q' + c q = 0 from q(t[0]) = q0 [m, rad], q'(t[0]) = v0 on a uniform grid t [s]."""
    n = a.shape[0]
    ainv = np.linalg.inv(a)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-ainv @ c, -ainv @ b]])
    step = scipy.linalg.expm(A * (t[1] - t[0])) if len(t) > 1 else np.eye(2 * n)
    x = np.concatenate([q0, v0])
    out = np.empty((len(t), n))
    for i in range(len(t)):
        out[i] = x[:n]
        x = step @ x
    return out


def frequency_response(a, b, c, Q, omegas):
    """Complex amplitudes q(omega) [len x k] of a q'' + b q' + c q = Q e^{i omega t}."""
    out = np.empty((len(omegas), a.shape[0]), complex)
    for i, w in enumerate(omegas):
        out[i] = np.linalg.solve(c - w * w * a + 1j * w * b, Q)
    return out
