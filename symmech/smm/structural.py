"""Numeric a, b, c from sparse structural matrices: the graph form (11), vectorised.

Vertices are the points, edges the chain vectors (one into every non-root point).
With the path matrix P (points x edges, 1 where the edge lies on the point's chain),
the turn matrix T (edges x coordinates, 1 where an angle turns the edge), the slide
matrix S (edges x coordinates, how often a slide lengthens it) and the edge vectors
V (edges x 3), the conjugate vectors of eq. (11) are sparse products:

    W_c = P diag(V_c) T                (sum of the vectors turned by q_a, component c)
    D   = e_a x W + (P S) u_s          (dr_p/dq: points x coordinates, per component)

and a = sum_c D_c^T m D_c + R^T J R (3), c = L_c^T k L_c (9) with L_c = sum_c diag(e_c)(D_c[b] - D_c[a]),
b likewise (10). The second-order terms of (7) are forces on points F (gravity -m g,
spring tensions +-T e) carried to the edges, F_e = P^T F, and contracted with
h_e[a, b] = e_a x (e_b x v_e), F.h = (F.e_b)(e_a.v) - (F.v)(e_a.e_b), and with
h_e[a, s] = e_a x u_s. Each unordered pair enters once, as in :mod:`symmech.smm.forms`;
that pairing is order-free only when all angle axes are parallel, so this form serves
planar mechanisms (:func:`applies`) and :func:`symmech.smm.numeric.assemble` keeps the
term-list form for spatial ones. Cost: O(nonzeros of P T) in sparse products plus one
Python pass over the elements (measured in ``benchmarks/bench_smm.py``).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from symmech.core.scene import SymmechError
from symmech.smm.model import EQUILIBRIUM, Effects, Mechanism, NumericArith


def applies(m: Mechanism, ar: NumericArith) -> bool:
    """True when every angle axis is parallel to the first (the pair terms are symmetric)."""
    axes = [np.array([ar(t) for t in c.axis]) for c in m.coordinates if c.kind == "angle"]
    return all(np.linalg.norm(np.cross(axes[0], e)) <= 1e-12 for e in axes[1:])


def values(ar: NumericArith, texts: list[str], what: str) -> np.ndarray:
    """Expressions as floats, each distinct text evaluated once."""
    known = {t: ar(t, what) for t in set(texts)}
    return np.array([known[t] for t in texts], dtype=float)


def vectors(ar: NumericArith, vecs: list, what: str) -> np.ndarray:
    """3-vectors of expressions as a (len, 3) array."""
    return values(ar, [t for v in vecs for t in v], what).reshape(len(vecs), 3)


class Graph:
    """The structural matrices of ``m`` evaluated in floats (see the module docstring)."""

    def __init__(self, m: Mechanism, ar: NumericArith):
        self.m, self.ar = m, ar
        self.names = list(m.points)
        self.pindex = {p: i for i, p in enumerate(self.names)}
        self.cindex = {c.name: i for i, c in enumerate(m.coordinates)}
        k = len(m.coordinates)
        self.k = k
        self.axes = vectors(ar, [c.axis for c in m.coordinates], "coordinate axes")
        edges = [p for p in self.names if m.points[p].parent is not None]
        eindex = {p: i for i, p in enumerate(edges)}
        V = vectors(ar, [m.points[p].vector for p in edges], "point vectors")
        roots = {p: [ar(t, f"point '{p}'") for t in m.points[p].vector]
                 for p in self.names if m.points[p].parent is None}
        rows, cols, root_of = [], [], {}
        for p in self.names:
            chain = m.chain(p)
            root_of[p] = chain[0].name
            rows += [self.pindex[p]] * (len(chain) - 1)
            cols += [eindex[q.name] for q in chain[1:]]
        npts, ne = len(self.names), len(edges)
        self.P = sp.csr_matrix((np.ones(len(rows)), (rows, cols)), shape=(npts, ne))
        t_r, t_c, s_r, s_c = [], [], [], []
        for p in edges:
            for a in m.points[p].turns:
                t_r.append(eindex[p])
                t_c.append(self.cindex[a])
            for s in m.points[p].slides:
                s_r.append(eindex[p])
                s_c.append(self.cindex[s])
        self.T = sp.csr_matrix((np.ones(len(t_r)), (t_r, t_c)), shape=(ne, k))
        self.S = sp.csr_matrix((np.ones(len(s_r)), (s_r, s_c)), shape=(ne, k))  # duplicates sum: counts
        self.V = V
        self.r = (np.array([roots[root_of[p]] for p in self.names]).reshape(npts, 3) + self.P @ V)
        PS = self.P @ self.S
        self.D = []
        for c in range(3):
            c1, c2 = (c + 1) % 3, (c + 2) % 3
            W1, W2 = (self.P @ sp.diags(V[:, j]) @ self.T for j in (c1, c2))
            # (e_a x W)_c = e_a,c1 W_c2 - e_a,c2 W_c1, column a scaled by the axis components
            self.D.append((W2 @ sp.diags(self.axes[:, c1]) - W1 @ sp.diags(self.axes[:, c2])
                           + PS @ sp.diags(self.axes[:, c])).tocsr())

    def rows(self, points: list[str]) -> list[sp.csr_matrix]:
        """D_x, D_y, D_z restricted to ``points`` (len(points) x k each)."""
        idx = [self.pindex[p] for p in points]
        return [d[idx] for d in self.D]

    def directions(self, links, what: str):
        """Unit vectors e (links x 3), lengths [m] and L rows (links x k) of springs or dampers."""
        ia = [self.pindex[x.a] for x in links]
        ib = [self.pindex[x.b] for x in links]
        d = self.r[ib] - self.r[ia]
        length = np.linalg.norm(d, axis=1)
        bad = np.flatnonzero(length < 1e-12)
        if len(bad):
            x = links[bad[0]]
            raise SymmechError(f"{what} '{x.name}': its ends '{x.a}' and '{x.b}' coincide (zero length); "
                               "a spring needs a direction")
        e = d / length[:, None] if len(links) else np.zeros((0, 3))
        dd = [(Dc[ib] - Dc[ia]).tocsr() for Dc in self.D]
        L = sum((sp.diags(e[:, c]) @ dd[c] for c in range(3)), sp.csr_matrix((len(links), self.k)))
        return e, length, L.tocsr(), dd, ia, ib

    def body_turns(self, body_names: list[str]) -> sp.csr_matrix:
        """Incidence (len x k) of the angles turning each body ('ground': none)."""
        turns = {b.name: b.turns for b in self.m.bodies}
        r, c = [], []
        for i, b in enumerate(body_names):
            for a in turns.get(b, ()):
                r.append(i)
                c.append(self.cindex[a])
        return sp.csr_matrix((np.ones(len(r)), (r, c)), shape=(len(body_names), self.k))

    def torsion_rows(self, elements) -> sp.csr_matrix:
        """d twist/dq of torsion elements: axis . (sum e over body b's turns - over body a's)."""
        if not elements:
            return sp.csr_matrix((0, self.k))
        rel = (self.body_turns([t.b for t in elements]) - self.body_turns([t.a for t in elements])).tocoo()
        n = np.array([[self.ar(x, f"torsion element '{t.name}'") for x in t.axis] for t in elements])
        vals = rel.data * np.einsum("ij,ij->i", n[rel.row], self.axes[rel.col])
        return sp.csr_matrix((vals, (rel.row, rel.col)), shape=rel.shape)

    def second_order(self, forces: np.ndarray) -> sp.csr_matrix:
        """sum_e F_e . h_e over every unordered pair (k x k, symmetric) for point forces (points x 3)."""
        F = self.P.T @ forces                      # edges x 3: force carried by each edge
        T = self.T.tocoo()
        x = np.einsum("ij,ij->i", self.V[T.row], self.axes[T.col])       # e_a . v_e
        y = np.einsum("ij,ij->i", F[T.row], self.axes[T.col])            # F_e . e_b
        X = sp.csr_matrix((x, (T.row, T.col)), shape=T.shape)
        Y = sp.csr_matrix((y, (T.row, T.col)), shape=T.shape)
        fv = np.einsum("ij,ij->i", F, self.V)
        gram = (self.T.T @ sp.diags(fv) @ self.T).tocoo()
        gram.data *= np.einsum("ij,ij->i", self.axes[gram.row], self.axes[gram.col])
        out = (X.T @ Y - gram.tocsr())
        Z = sp.csr_matrix((self.k, self.k))
        for c in range(3):
            c1, c2 = (c + 1) % 3, (c + 2) % 3
            # F . (e_a x u_s) = sum_c e_a,c (u_c1 F_c2 - u_c2 F_c1)
            Z = Z + sp.diags(self.axes[:, c]) @ (self.T.T @ sp.diags(F[:, c2]) @ self.S @ sp.diags(self.axes[:, c1])
                                                  - self.T.T @ sp.diags(F[:, c1]) @ self.S @ sp.diags(self.axes[:, c2]))
        return (out + Z + Z.T).tocsr()


def assemble(m: Mechanism, ar: NumericArith, effects: Effects, tensions: dict):
    """(a, b, c, c_preload, c_gravity, residual, lengths, tensions) of a planar ``m`` (see module doc)."""
    g = Graph(m, ar)
    k = g.k
    npts = len(g.names)
    empty = sp.csr_matrix((k, k))
    # inertia (3): translation of the mass centres, rotation about the principal axes
    masses = values(ar, [b.mass for b in m.bodies], "masses")
    Dm = g.rows([b.com for b in m.bodies]) if m.bodies else [sp.csr_matrix((0, k))] * 3
    a = sum((Dc.T @ sp.diags(masses) @ Dc for Dc in Dm), empty)
    turns = g.body_turns([b.name for b in m.bodies]).tocoo()
    for axis in range(3):
        J = values(ar, [b.inertia[axis] for b in m.bodies], "moments of inertia")
        P = np.tile(np.eye(3)[axis], (len(m.bodies), 1))
        turned = [i for i, b in enumerate(m.bodies) if b.axes is not None]
        P[turned] = vectors(ar, [m.bodies[i].axes[axis] for i in turned], "principal axes")
        vals = np.einsum("ij,ij->i", P[turns.row], g.axes[turns.col]) if turns.nnz else np.zeros(0)
        R = sp.csr_matrix((vals, (turns.row, turns.col)), shape=turns.shape)
        a = a + R.T @ sp.diags(J) @ R
    # springs (5), (7), (9)
    e, length, Lc, dd, ia, ib = g.directions(m.springs, "spring")
    kk = values(ar, [s.coef for s in m.springs], "spring stiffnesses")
    T = np.array([_tension(ar, s, kk[i], length[i], tensions) for i, s in enumerate(m.springs)])
    Lt = g.torsion_rows(m.torsion_springs)
    kt = np.array([ar(t.coef, f"torsion spring '{t.name}'") for t in m.torsion_springs])
    Mt = np.array([_moment(ar, t, tensions) for t in m.torsion_springs])
    stiff = Lc.T @ sp.diags(kk) @ Lc + Lt.T @ sp.diags(kt) @ Lt
    grav = ar(m.gravity, "gravity.g")
    gdir = np.array([ar(t, "gravity.direction") for t in m.gravity_direction])
    weights = np.zeros((npts, 3))
    np.add.at(weights, [g.pindex[b.com] for b in m.bodies], masses[:, None] * grav * gdir[None, :])
    residual = (-sum(Dc.T @ weights[[g.pindex[b.com] for b in m.bodies], c] for c, Dc in enumerate(Dm))
                + Lc.T @ T + Lt.T @ Mt) if k else np.zeros(0)
    residual = np.asarray(residual, float).reshape(k)
    c_grav = g.second_order(-weights) if effects.gravity and grav != 0 else empty
    c_pre = empty
    if effects.preload and np.any(T != 0):
        tl = T / length
        c_pre = sum((ddc.T @ sp.diags(tl) @ ddc for ddc in dd), empty) - Lc.T @ sp.diags(tl) @ Lc
        forces = np.zeros((npts, 3))
        np.add.at(forces, ib, T[:, None] * e)
        np.add.at(forces, ia, -T[:, None] * e)
        c_pre = c_pre + g.second_order(forces)
    b = empty
    if effects.damping and (m.dampers or m.torsion_dampers):
        _, _, Lb, *_ = g.directions(m.dampers, "damper")
        mu = values(ar, [d.coef for d in m.dampers], "damper viscosities")
        Ltd = g.torsion_rows(m.torsion_dampers)
        mut = np.array([ar(t.coef, f"torsion damper '{t.name}'") for t in m.torsion_dampers])
        b = Lb.T @ sp.diags(mu) @ Lb + Ltd.T @ sp.diags(mut) @ Ltd
    names = [s.name for s in m.springs]
    return (a.tocsr(), sp.csr_matrix(b), (stiff + c_pre + c_grav).tocsr(), sp.csr_matrix(c_pre),
            sp.csr_matrix(c_grav), residual, dict(zip(names, length.tolist())), dict(zip(names, T.tolist())),
            sp.vstack([Lc, Lt]).tocsr())


def _tension(ar, s, k, length, tensions) -> float:
    if s.preload == EQUILIBRIUM:
        if s.name not in tensions:
            raise ValueError(f"spring '{s.name}': tension from equilibrium not supplied")
        return tensions[s.name]
    if s.preload is not None:
        return ar(s.preload, f"spring '{s.name}'")
    if s.free_length is not None:
        return k * (length - ar(s.free_length, f"spring '{s.name}'"))
    return 0.0


def _moment(ar, t, tensions) -> float:
    if t.preload == EQUILIBRIUM:
        if t.name not in tensions:
            raise ValueError(f"torsion spring '{t.name}': moment from equilibrium not supplied")
        return tensions[t.name]
    return 0.0 if t.preload is None else ar(t.preload, f"torsion spring '{t.name}'")

