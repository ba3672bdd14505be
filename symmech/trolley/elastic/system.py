"""The elastic trolley (seed 002, eqs. (6)-(10) and the roller section): assembly and integration.

Coordinates q = [q0 (the five roller DOFs u2, u3, θ1, θ2, θ3, when the rollers are
elastic), beam Ritz coordinates]. Every material point r of the body (trolley, beams,
tip masses) moves in the track frame Ox1x2x3 to
    r̃ = r + Σ_a q_a φ_a(r) + ½ Σ_ab q_a q_b ψ_ab(r),
with φ0, ψ0 of the roller DOFs from :mod:`symmech.generated.trolley_elastic`, the beam
modes φ_k and their axial shortening ψ_kl, and the cross terms ψ_(θa, k) = e_a × φ_k of
the small rotations carrying the beams (second order, consistent). The body is sampled
once per scene by weighted points (Gauss points of the beams, a six-point cloud with
the mass, centre and inertia of the rigid trolley); the Gram tensors of the fields over
these samples are the inertia invariants (9), so each step is a few small contractions.

Equations, per coordinate a (the third of (8), virtual work of the d'Alembert forces):
    ∫ φ̃_aᵀ (a - g) dm + ∂Π/∂q_a + (D q̇)_a = 0,   φ̃_a = ∂r̃/∂q_a,
    a = a0 + ω̇ × r̃ + ω × (ω × r̃) + 2 ω × u̇ + ü,
with the frame's a0, ω, ω̇ from Λ(s) and the prescribed V0(t) as in the rigid model
(:mod:`symmech.trolley.model`); gravity g = -g0 ν (10). The roller forces P1…P5 act at
the trolley's contact points along x2 (B, C, A) and x3 (O, A); P0 closes the balance
along x1 (first of (8)).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from symmech.core import context, kinematics as kin
from symmech.core.scene import SymmechError
from symmech.generated import trolley_elastic as gen
from symmech.trolley import model
from symmech.trolley.elastic import membrane

ROLLER_NAMES = ("u2", "u3", "th1", "th2", "th3")
# (i, j) of the ψ0 columns of the generated rigid_fields: 44, 45, 46, 55, 56, 66
ROTATION_PAIRS = ((2, 2), (2, 3), (2, 4), (3, 3), (3, 4), (4, 4))
# Gauss points per beam: exact for the products of two shortening fields of degree 2 NMAX + 1.
BEAM_GAUSS = 2 * 8 + 4
# Frequencies that load the body periodically (name, meaning), in the columns of the scene's forcing_frequencies.
FORCING = (("axle", "axle passing |V0|/l"), ("rotation", "frame rotation |ω|/2π"),
           ("curvature", "curvature change |V0| |Ω'|/(2π max|Ω|)"))


@dataclass(frozen=True)
class Beam:
    """Euler–Bernoulli beam fixed to the trolley: root [m] and unit axis (trolley frame),
    first bending direction ``plane`` (⟂ axis; the second is axis × plane), length [m],
    mass per length ``rho_a`` [kg/m], bending stiffness ``ei`` (EI in the two planes)
    [N m²], ``support`` "cantilever" (clamped at the root) or "pinned" (both ends),
    ``modes`` Ritz functions per plane, ``tip_mass`` [kg] at the free end; a pinned beam's
    far end slides along the axis (``axial`` "free", inextensible) or is ``"held"`` (immovable
    supports: the beam stretches, axial stiffness ``ea`` [N], :mod:`symmech.trolley.elastic.membrane`)."""

    root: tuple
    axis: tuple
    plane: tuple
    length: float
    rho_a: float
    ei: tuple
    support: str = "cantilever"
    modes: int = 4
    tip_mass: float = 0.0
    damping_ratio: float = 0.0
    axial: str = "free"
    ea: float = 0.0


@dataclass(frozen=True)
class Rollers:
    """Roller stiffness [N/m] and damping [N s/m] of P1…P5, law "linear" or "clamped_pair"
    (two rollers clamping the rail, each preloaded by ``preload`` [m]; negative: a gap)."""

    stiffness: tuple
    damping: tuple
    law: str = "linear"
    preload: tuple = (0.0,) * 5


@dataclass(frozen=True)
class Effects:
    rollers: bool = True
    body: bool = True
    stiffening: bool = True
    damping: bool = True
    membrane: bool = True


@dataclass(frozen=True)
class ElasticModel:
    """Trolley (mass [kg], centre of mass [m], central inertia [I11, I22, I33, I12, I23, I13]
    [kg m²]), beams, rollers, axle distance l and half gauge ah [m], g0 [m/s²] (0: none)."""

    mass: float
    com: tuple
    inertia: tuple
    l: float
    ah: float
    g0: float
    rollers: Rollers | None = None
    beams: tuple = ()
    effects: Effects = field(default_factory=Effects)


# ---------------------------------------------------------------- body samples and fields

def rigid_cloud(mass: float, com, inertia6) -> tuple[np.ndarray, np.ndarray]:
    """Six points of mass m/6 with the mass, centre and central inertia of a rigid body:
    c ± sqrt(3 λ_i/m) e_i for the eigenpairs of the central second moment J = ½ tr(I) E - I."""
    J = kin.second_moment(kin.inertia_matrix(inertia6))
    lam, vec = np.linalg.eigh(J)
    if lam[0] < -1e-12 * max(lam[-1], 1e-300):
        raise SymmechError(f"trolley inertia {list(inertia6)} kg m^2 violates the triangle inequality "
                           "(I11 + I22 >= I33 and permutations)")
    arm = np.sqrt(3 * np.maximum(lam, 0.0) / mass)
    pts = [np.asarray(com, float) + sgn * arm[i] * vec[:, i] for i in range(3) for sgn in (1, -1)]
    return np.array(pts), np.full(6, mass / 6)


def _frame_of(beam: Beam):
    e = np.asarray(beam.axis, float)
    e = e / np.linalg.norm(e)
    b1 = np.asarray(beam.plane, float)
    b1 = b1 - (b1 @ e) * e
    b1 = b1 / np.linalg.norm(b1)
    return e, b1, np.cross(e, b1)


def beam_basis(support: str, xi, axial: str = "free"):
    """[N; N'; N''] (P, 3, NMAX) at ξ (P,) and the axial field -L ψ_kl (P, NMAX, NMAX): the
    shortening S_kl(ξ) with a free far end, S_kl(ξ) - ξ H_kl with held ends."""
    if support == "cantilever":
        return gen.cantilever_basis(xi), gen.cantilever_shortening(xi)
    return gen.pinned_basis(xi), (-gen.pinned_held_axial(xi) if axial == "held" else gen.pinned_shortening(xi))


@dataclass
class Invariants:
    """Fields over the body samples and their Gram tensors (the inertia invariants (9)).

    Field index 0 is r itself, 1…N the φ_a, then the ψ of ``pairs`` (a <= b). ``G`` (F, F, 3, 3)
    = Σ w f_k f_lᵀ [kg m^k], ``S1`` (F, 3) = Σ w f_k; ``dA`` (N, N) maps (a, b) to the field
    index of ψ_ab (or -1); ``K``, ``D`` (N, N) the constant stiffness and damping of the beams;
    ``membrane`` the :class:`~symmech.trolley.elastic.membrane.Block` of each beam with held ends."""

    names: list
    pairs: list
    G: np.ndarray
    S1: np.ndarray
    dA: np.ndarray
    K: np.ndarray
    D: np.ndarray
    mass: float
    n_roll: int
    probe_fields: np.ndarray  # (F, n_probes, 3) field values at the report points
    probe_points: np.ndarray  # (n_probes, 3) undeformed report points [m]
    membrane: tuple = ()


def _beam_samples(beam: Beam, probes=()):
    xg, wg = np.polynomial.legendre.leggauss(BEAM_GAUSS)
    xi = np.concatenate([(xg + 1) / 2, [1.0], probes])
    w = np.concatenate([beam.rho_a * beam.length * wg / 2, [beam.tip_mass], np.zeros(len(probes))])
    e, _, _ = _frame_of(beam)
    pts = np.asarray(beam.root, float) + np.outer(xi * beam.length, e)
    return pts, w, xi


def _beam_stiffness(beam: Beam, n: int) -> np.ndarray:
    """EI/L³ ∫ N_k'' N_l'' dξ (exact by Gauss for the polynomial bases), per plane (n, n)."""
    xg, wg = np.polynomial.legendre.leggauss(BEAM_GAUSS)
    basis, _ = beam_basis(beam.support, (xg + 1) / 2)
    d2 = basis[:, 2, :n]
    return np.einsum("p,pk,pl->kl", wg / 2, d2, d2) / beam.length ** 3


def invariants(mdl: ElasticModel, probes=()) -> Invariants:
    """Fields, pairs and Gram tensors of ``mdl`` (computed once per scene).

    ``probes``: report points, each ``(None, (x1, x2, x3))`` on the trolley [m] or
    ``(i, ξ)`` on beam i at x/L = ξ; they are massless samples whose field values are kept."""
    cloud, cw = rigid_cloud(mdl.mass, mdl.com, mdl.inertia)
    mine = [j for j, (b, _) in enumerate(probes) if b is None]
    pts0 = np.array([*cloud, *(np.asarray(probes[j][1], float) for j in mine)])
    parts = [(pts0, np.r_[cw, np.zeros(len(mine))], None, None)]
    probe_index = {j: 6 + n for n, j in enumerate(mine)}
    offset = len(pts0)
    for i, beam in enumerate(mdl.beams):
        mine = [j for j, (b, _) in enumerate(probes) if b == i]
        pts, w, xi = _beam_samples(beam, [float(probes[j][1]) for j in mine])
        probe_index.update({j: offset + len(w) - len(mine) + n for n, j in enumerate(mine)})
        parts.append((pts, w, beam, xi))
        offset += len(w)
    pts = np.concatenate([p[0] for p in parts])
    w = np.concatenate([p[1] for p in parts])
    n_pts = len(w)
    fields: list[np.ndarray] = [pts]
    names: list[str] = []
    psi: dict[tuple, np.ndarray] = {}
    eff = mdl.effects
    rigid = gen.rigid_fields(pts[:, 0], pts[:, 1], pts[:, 2])  # (P, 3, 11)
    if eff.rollers and mdl.rollers is not None:
        names += list(ROLLER_NAMES)
        fields += [rigid[:, :, i] for i in range(5)]
        for col, pair in enumerate(ROTATION_PAIRS):
            psi[pair] = rigid[:, :, 5 + col]
    n_roll = len(names)
    K_blocks, held = [], []
    start = 0
    for index, (_pts_b, w_b, beam, xi) in enumerate(parts):
        if beam is None or not eff.body:
            start += len(w_b)
            continue
        e, b1, b2 = _frame_of(beam)
        basis, short = beam_basis(beam.support, xi, beam.axial)
        n = beam.modes
        k1 = _beam_stiffness(beam, n)
        sl = slice(start, start + len(w_b))
        first = len(names)
        for plane, (b, ei) in enumerate(zip((b1, b2), beam.ei)):
            base = len(names)
            for k in range(n):
                f = np.zeros((n_pts, 3))
                f[sl] = np.outer(basis[:, 0, k], b)
                fields.append(f)
                names.append(f"beam{index - 1}_p{plane + 1}_m{k + 1}")  # parts[0] is the trolley
            if eff.stiffening:
                for k in range(n):
                    for m in range(k, n):
                        f = np.zeros((n_pts, 3))
                        f[sl] = np.outer(-short[:, k, m] / beam.length, e)
                        psi[(base + k, base + m)] = f
            K_blocks.append((base, ei * k1, beam.damping_ratio))
        if beam.axial == "held" and eff.membrane:
            held.append(membrane.block(first, n, beam.ea, beam.length))
        for a in (range(n_roll - 3, n_roll) if n_roll else ()):
            axis = np.eye(3)[a - (n_roll - 3)]
            for c in range(first, len(names)):
                psi[(a, c)] = np.cross(axis, fields[1 + c])
        start += len(w_b)
    N = len(names)
    pairs = sorted(psi)
    fields += [psi[p] for p in pairs]
    F = np.array(fields)  # (F, P, 3)
    G = np.einsum("kpi,p,lpj->klij", F, w, F)
    S1 = np.einsum("kpi,p->ki", F, w)
    dA = -np.ones((N, N), dtype=int)
    for idx, (a, b) in enumerate(pairs):
        dA[a, b] = dA[b, a] = 1 + N + idx
    K = np.zeros((N, N))
    D = np.zeros((N, N))
    for base, kb, _zeta in K_blocks:
        n = kb.shape[0]
        sl = slice(base, base + n)
        K[sl, sl] = kb
    at = [probe_index[j] for j in range(len(probes))]
    inv = Invariants(names, pairs, G, S1, dA, K, D, float(w.sum()), n_roll, F[:, at, :], pts[at], tuple(held))
    if eff.damping:
        _beam_damping(inv, K_blocks)
    return inv


def _beam_damping(inv: Invariants, blocks) -> None:
    """Stiffness-proportional damping per beam plane: ζ at the plane's first mode."""
    gtr = np.einsum("klii->kl", inv.G)
    for base, kb, zeta in blocks:
        if zeta <= 0:
            continue
        n = kb.shape[0]
        idx = np.arange(1 + base, 1 + base + n)
        mb = gtr[np.ix_(idx, idx)]
        w1 = math.sqrt(max(np.min(np.real(np.linalg.eigvals(np.linalg.solve(mb, kb)))), 0.0))
        sl = slice(base, base + n)
        inv.D[sl, sl] = 2 * zeta / w1 * kb


# ---------------------------------------------------------------- rollers

def roller_forces(rollers: Rollers, d, dd, damping: bool):
    """Forces P1…P5 on the trolley [N] and tangent stiffness dP/dd [N/m] at deflections d [m],
    rates dd [m/s]. "clamped_pair": P = k [(δ - d)₊ - (δ + d)₊] (δ the preload; δ < 0 a gap)."""
    k = np.asarray(rollers.stiffness, float)
    c = np.asarray(rollers.damping, float) if damping else np.zeros(5)
    if rollers.law == "linear":
        return -k * d - c * dd, -k
    pre = np.asarray(rollers.preload, float)
    up, down = pre - d, pre + d
    force = k * (np.maximum(up, 0.0) - np.maximum(down, 0.0)) - c * dd
    # a roller just touching counts half (the mean of the slopes beside the kink): with no preload
    # the pair is exactly -k d, stiffness k at d = 0, not 0
    return force, -k * (1.0 + (np.sign(up) + np.sign(down)) / 2)


def roller_energy(rollers: Rollers, d):
    """Π^P [J] of the roller law at deflections d (..., 5), shape (...)."""
    k = np.asarray(rollers.stiffness, float)
    if rollers.law == "linear":
        return 0.5 * (k * d * d).sum(-1)
    pre = np.asarray(rollers.preload, float)
    return 0.5 * (k * (np.maximum(pre - d, 0) ** 2 + np.maximum(pre + d, 0) ** 2 - 2 * np.maximum(pre, 0) ** 2)).sum(-1)


# ---------------------------------------------------------------- frame along the track

@dataclass(frozen=True)
class Drive:
    """The motion of the frame: track, frame mode ("twist", "frenet"), case 2
    (``local_curvature``) or 1, speed(t) -> (V0 [m/s], dV0 [m/s²]), start s0 [m], the
    case-2 difference order and step [m], and the rigid setup's frame plan. With
    ``traction`` (t, V0) -> P0 [N] instead of a speed, s and V0 are coordinates (from
    ``v_initial`` [m/s]) and the x1 balance of the whole body, F1 = P0, is their equation."""

    track: object
    frame: str
    local_curvature: bool
    speed: object
    s0: float = 0.0
    fd_order: int = 4
    fd_step: float = 1e-3
    plan: object = None  # model.FramePlan keeping the frame continuous (from the trolley setup)
    traction: object = None
    v_initial: float = 0.0


@dataclass(frozen=True)
class FrameState:
    """Track frame at one instant, body-frame components: velocity v0 [m/s] and acceleration
    a0 [m/s²] of O, ω [rad/s], ω̇ [rad/s²], upward unit vector ν."""

    v0: np.ndarray
    a0: np.ndarray
    w: np.ndarray
    dw: np.ndarray
    nu: np.ndarray


def frames(drive: Drive, s, l: float) -> model.Frame:
    s = np.atleast_1d(np.asarray(s, dtype=float))
    if drive.local_curvature:
        return model.local_curvature_frame(drive.track, s, l, drive.frame, drive.fd_order, drive.fd_step,
                                           plan=drive.plan)
    return model.moving_frame(drive.track, s, drive.frame, drive.plan)


def frame_motion(fr: model.Frame, V0, dV0) -> tuple:
    """v0, a0, ω, ω̇ (k, 3) of the frame fr (k rows) at speeds V0 [m/s] and rates dV0 [m/s²] (k,): the
    vectorised :func:`frame_state` without ν."""
    V, dV = V0[:, None], dV0[:, None]
    return V * fr.e, dV * fr.e + V ** 2 * (fr.de + np.cross(fr.W, fr.e)), V * fr.W, dV * fr.W + V ** 2 * fr.dW


def frame_state(fr: model.Frame, i: int, V0: float, dV0: float) -> FrameState:
    e, W = fr.e[i], fr.W[i]
    return FrameState(V0 * e, dV0 * e + V0 ** 2 * (fr.de[i] + np.cross(W, e)), V0 * W,
                      dV0 * W + V0 ** 2 * fr.dW[i], fr.lam[i, :, 1])


# ---------------------------------------------------------------- equations of motion

# Absolute floor of a converged Newton step [m or rad]: a femtometre (femtoradian) is no deflection.
Q_FLOOR = 1e-15


class System:
    """Residual R(q, q̇, q̈) = M(q) q̈ + f(q, q̇) of the relative motion, its Jacobians,
    reactions and energies, from the invariants of ``mdl``."""

    def __init__(self, mdl: ElasticModel, probes=()):
        self.mdl = mdl
        self.inv = invariants(mdl, probes)
        inv = self.inv
        self.N = len(inv.names)
        self.F = inv.G.shape[0]
        self.Gtr = np.einsum("klii->kl", inv.G)
        self.C = gen.roller_matrix(mdl.l, mdl.ah)
        self.pair_i = np.array([p[0] for p in inv.pairs], dtype=int)
        self.pair_j = np.array([p[1] for p in inv.pairs], dtype=int)
        self.diag = self.pair_i == self.pair_j
        pts = np.array([(0, 0, -mdl.ah), (0, 0, mdl.ah), (mdl.l, 0, 0), (0, 0, 0), (mdl.l, 0, 0)], float)
        self.contacts = pts
        self.directions = np.eye(3)[[1, 1, 1, 2, 2]]
        # columns: unit P0…P5 as force and moment about O (the rigid model's reaction system)
        cols = [np.r_[1.0, 0, 0, 0, 0, 0]] + [np.r_[n, np.cross(p, n)] for p, n in zip(pts, self.directions)]
        self.reaction_system = np.array(cols).T
        self.rollers_on = inv.n_roll == 5

    # coefficient vectors over the fields
    def coefficients(self, q):
        N, F = self.N, self.F
        rr = np.zeros(F)
        rr[0] = 1.0
        rr[1:1 + N] = q
        qi, qj = q[self.pair_i], q[self.pair_j]
        rr[1 + N:] = np.where(self.diag, 0.5, 1.0) * qi * qj
        A = self._dv(q)
        A[np.arange(N), 1 + np.arange(N)] = 1.0
        return rr, A

    def _dv(self, rate):
        """(N, F): ∂(Σ_c rate_c φ̃_c)/∂q_b = Σ_c rate_c ψ_cb (with rate = q: the ψ part of φ̃_b)."""
        out = np.zeros((self.N, self.F))
        cols = 1 + self.N + np.arange(len(self.pair_i))
        np.add.at(out, (self.pair_i, cols), rate[self.pair_j])
        off = ~self.diag
        np.add.at(out, (self.pair_j[off], cols[off]), rate[self.pair_i[off]])
        return out

    def _p2(self, qd):
        out = np.zeros(self.F)
        out[1 + self.N:] = np.where(self.diag, 1.0, 2.0) * qd[self.pair_i] * qd[self.pair_j]
        return out

    def roller_state(self, q, qd):
        """Deflections d, rates, forces P1…P5 and tangent stiffness (zeros without rollers)."""
        if not self.rollers_on:
            z = np.zeros(5)
            return z, z, z, z
        d, dd = self.C @ q[:5], self.C @ qd[:5]
        force, kt = roller_forces(self.mdl.rollers, d, dd, self.mdl.effects.damping)
        return d, dd, force, kt

    def _frame_mats(self, fs: FrameState):
        B = kin.skew(fs.dw) + kin.skew(fs.w) @ kin.skew(fs.w)
        W = kin.skew(fs.w)
        G = self.inv.G
        return B, W, np.einsum("klij,ij->kl", G, B), np.einsum("klij,ij->kl", G, W)

    def evaluate(self, fs: FrameState, q, qd, qdd, jacobian: bool = False):
        """R (N,) and, with ``jacobian``, M, ∂R/∂q, ∂R/∂q̇ (N, N) at the state."""
        inv, g0 = self.inv, self.mdl.g0
        rr, A = self.coefficients(q)
        v = qd @ A
        acc = qdd @ A + self._p2(qd)
        B, W, GB, GW = self._frame_mats(fs)
        load = fs.a0 + g0 * fs.nu
        z = inv.S1 @ load + GB @ rr + 2 * GW @ v + self.Gtr @ acc
        R = A @ z + inv.K @ q + inv.D @ qd + membrane.force(inv.membrane, q)
        d, dd, force, kt = self.roller_state(q, qd)
        if self.rollers_on:
            R[:5] -= self.C.T @ force
        if not jacobian:
            return R
        M = A @ self.Gtr @ A.T
        zpad = np.append(z, 0.0)
        DV, DQ = self._dv(qd), self._dv(qdd)
        Rq = zpad[self.inv.dA] + A @ (GB @ A.T + 2 * GW @ DV.T + self.Gtr @ DQ.T) + inv.K + \
            membrane.stiffness(inv.membrane, q)
        Rqd = A @ (2 * GW @ A.T + 2 * self.Gtr @ DV.T) + inv.D
        if self.rollers_on:
            Rq[:5, :5] -= self.C.T @ (kt[:, None] * self.C)
            if self.mdl.effects.damping:
                Rqd[:5, :5] += self.C.T @ (np.asarray(self.mdl.rollers.damping)[:, None] * self.C)
        return R, M, Rq, Rqd

    def mass(self, q):
        _, A = self.coefficients(q)
        return A @ self.Gtr @ A.T

    def accelerations(self, fs: FrameState, q, qd):
        M = self.mass(q)
        try:
            return -np.linalg.solve(M, self.evaluate(fs, q, qd, np.zeros(self.N)))
        except np.linalg.LinAlgError:
            raise SymmechError("the mass matrix of the elastic model is singular: give the trolley a positive "
                               "inertia about every axis (trolley.inertia)") from None

    def resultants(self, fs: FrameState, q, qd, qdd):
        """Force F and moment M about O (3, 3) of ∫ (a - g) dm: the left sides of (8)."""
        inv = self.inv
        rr, A = self.coefficients(q)
        v = qd @ A
        acc = qdd @ A + self._p2(qd)
        B, W, _, _ = self._frame_mats(fs)
        load = fs.a0 + self.mdl.g0 * fs.nu
        first = inv.S1.T
        F = inv.mass * load + B @ (first @ rr) + 2 * W @ (first @ v) + first @ acc
        X = (rr @ inv.G.reshape(self.F, -1)).reshape(inv.G.shape[1:])  # ∫ r̃ f_lᵀ dm per field l
        J = lambda y: np.tensordot(y, X, 1)  # noqa: E731  ∫ r̃ yᵀ dm
        H = J(rr) @ B.T + 2 * J(v) @ W.T + J(acc)
        moment = np.cross(first @ rr, load) - 2 * kin.vee(H)
        return F, moment

    def reactions(self, fs: FrameState, q, qd, qdd):
        """P0…P5 [N]: roller forces (elastic rollers) or, with rigid rollers, the rigid
        model's reaction system solved for the resultants."""
        F, moment = self.resultants(fs, q, qd, qdd)
        if self.rollers_on:
            return np.r_[F[0], self.roller_state(q, qd)[2]]
        return np.linalg.solve(self.reaction_system, np.r_[F, moment])

    def contact_moment(self, q, forces):
        """Moment about O of the roller forces at the displaced contact points [N m] (..., 3), for
        coordinates q (..., N) and forces P1…P5 (..., 5)."""
        p = self.contacts
        f = gen.rigid_fields(p[:, 0], p[:, 1], p[:, 2])
        q = np.asarray(q, float)
        u = np.einsum("pik,...k->...pi", f[:, :, :5], q[..., :5])
        for col, (i, j) in enumerate(ROTATION_PAIRS):
            u = u + (0.5 if i == j else 1.0) * (q[..., i] * q[..., j])[..., None, None] * f[:, :, 5 + col]
        return np.cross(p + u, forces[..., :, None] * self.directions).sum(-2)

    def jacobi_energy(self, fs: FrameState, q, qd):
        """h = T2 - T0 + Π + V_g [J]: constant when the frame's motion is steady (ω, v0, ν
        constant in the frame), decreasing by the dissipated energy with damping."""
        inv = self.inv
        rr, A = self.coefficients(q)
        M = A @ self.Gtr @ A.T
        W = kin.skew(fs.w)
        first = inv.S1.T @ rr
        J = np.einsum("k,klij,l->ij", rr, inv.G, rr)
        t0 = 0.5 * (inv.mass * fs.v0 @ fs.v0 + 2 * fs.v0 @ np.cross(fs.w, first) + np.sum((W.T @ W) * J))
        return 0.5 * qd @ M @ qd - t0 + self.potential(q) + self.mdl.g0 * fs.nu @ first

    def potential(self, q):
        """Π [J]: beam bending (and membrane) energy and the rollers' potential at q (..., N), shape (...)."""
        pi = 0.5 * np.einsum("...i,ij,...j->...", q, self.inv.K, q) + membrane.energy(self.inv.membrane, q)
        if self.rollers_on:
            pi = pi + roller_energy(self.mdl.rollers, q[..., :5] @ self.C.T)
        return pi

    def total_energy(self, fs: FrameState, q, qd, height: float) -> float:
        """E = T + Π + V_g [J] in the fixed frame, O at ``height`` [m] (X2 up): kinetic energy of
        the absolute velocity v0 + ω × r̃ + u̇, roller and beam potential, gravity."""
        inv = self.inv
        rr, A = self.coefficients(q)
        v = qd @ A
        Wt = kin.skew(fs.w).T
        first = inv.S1.T @ rr
        twice_t = inv.mass * fs.v0 @ fs.v0 + 2 * fs.v0 @ (np.cross(fs.w, first) + inv.S1.T @ v) + \
            rr @ np.einsum("klij,ij->kl", inv.G, Wt @ Wt.T) @ rr + 2 * rr @ np.einsum("klij,ij->kl", inv.G, Wt) @ v + \
            v @ self.Gtr @ v
        return 0.5 * twice_t + self.potential(q) + self.mdl.g0 * (inv.mass * height + fs.nu @ first)

    def track_power(self, fs: FrameState, q, qd, qdd) -> float:
        """Power [W] of the forces of the track on the body, F·v0 + M_O·ω: they act at points of
        the rails, which move with the frame, and their resultants are those of (8)."""
        F, moment = self.resultants(fs, q, qd, qdd)
        return float(F @ fs.v0 + moment @ fs.w)

    def quasi_static(self, fs: FrameState, q0=None, tol: float = 1e-12, max_iter: int = 50):
        """q with R(q, 0, 0) = 0 by Newton's method (the quasi-static state): converged when a
        step is below ``tol`` relative to q or below :data:`Q_FLOOR` (the state q = 0 of an
        unloaded body is reached only to rounding, where no relative test can pass)."""
        q = np.zeros(self.N) if q0 is None else np.array(q0, float)
        zero = np.zeros(self.N)
        for _ in range(max_iter):
            R, _, Rq, _ = self.evaluate(fs, q, zero, zero, jacobian=True)
            try:
                step = np.linalg.solve(Rq, -R)
            except np.linalg.LinAlgError:
                raise SymmechError("no quasi-static state of the elastic model: its stiffness is singular (a "
                                   "free play of the rollers, elastic.rollers.preload < 0, carries no load)") from None
            q = q + step
            if np.abs(step).max() <= tol * np.abs(q).max() + Q_FLOOR or not np.any(R):
                return q
        raise SymmechError("no quasi-static state of the elastic model (Newton did not converge in "
                           f"{max_iter} steps; residual {np.abs(R).max():.3g})")

    def linear_modes(self, fs: FrameState, q, shapes: bool = False):
        """Natural frequencies [rad/s] and damping ratios of the linearisation at q (q̇ = 0):
        the state-space eigenvalues λ of M x'' + ∂R/∂q̇ x' + ∂R/∂q x = 0 with Im λ >= 0,
        ω = |λ|, ζ = -Re λ / |λ| (gyroscopic and circulatory frame terms included), sorted by
        ω; with ``shapes`` also their displacement parts x (N, k) (complex, unit 2-norm)."""
        zero = np.zeros(self.N)
        _, M, Rq, Rqd = self.evaluate(fs, q, zero, zero, jacobian=True)
        Minv = np.linalg.inv(M)
        n = self.N
        state = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ Rq, -Minv @ Rqd]])
        lam, vectors = np.linalg.eig(state)
        keep = np.flatnonzero(lam.imag >= -1e-12 * np.abs(lam).max())
        keep = keep[np.argsort(np.abs(lam[keep]))]
        lam = lam[keep]
        omega = np.abs(lam)
        zeta = np.where(omega > 0, -lam.real / np.where(omega > 0, omega, 1.0), 0.0)
        if not shapes:
            return omega, zeta
        x = vectors[:n, keep]
        return omega, zeta, x / np.linalg.norm(x, axis=0)


def beam_mode(system: System, beam: int, plane: int, mode: int) -> np.ndarray:
    """Coordinates (N,) of mode ``mode`` (1 = lowest) of beam ``beam`` alone, bending in
    ``plane`` (1: along its ``plane`` direction, 2: axis × plane), on a fixed trolley: the
    eigenvector of its own Ritz block of M and K (tip mass included), scaled to a largest
    deflection along the beam of +1 m. Raises KeyError when the model has no such coordinate."""
    import scipy.linalg

    b = system.mdl.beams[beam]
    idx = [system.inv.names.index(f"beam{beam}_p{plane}_m{k + 1}") for k in range(b.modes)]
    block = np.ix_(idx, idx)
    _, vectors = scipy.linalg.eigh(system.inv.K[block], system.mass(np.zeros(system.N))[block])
    shape = beam_basis(b.support, np.linspace(0.0, 1.0, MODE_SAMPLES))[0][:, 0, :b.modes] @ vectors[:, mode - 1]
    out = np.zeros(system.N)
    out[idx] = vectors[:, mode - 1] / shape[np.argmax(np.abs(shape))]
    return out


MODE_SAMPLES = 2001  # points along a beam at which a mode's largest deflection is found


# ---------------------------------------------------------------- integration along the track

def rigid_body(mdl: ElasticModel) -> model.Body:
    """The rigid model's body with the total mass, centre of mass and central inertia of
    trolley, beams and tip masses (undeformed)."""
    inv = invariants(mdl)
    m = inv.mass
    com = inv.S1[0] / m
    J = inv.G[0, 0] - m * np.outer(com, com)  # central second moment
    I = kin.inertia_from_second_moment(J)
    return model.Body(m, tuple(com), (I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[1, 2], I[0, 2]), mdl.l, mdl.ah, mdl.g0)


def _state_at(system: System, drive: Drive, t: float, s: float) -> FrameState:
    V0, dV0 = drive.speed(t)
    return frame_state(frames(drive, s, system.mdl.l), 0, float(V0), float(dV0))


class Timeline:
    """Arc length s(t) = s0 + ∫ V0 dt (8-point Gauss-Legendre per interval of the grid t, as the
    rigid scene computes it, and from the last node) and the frame state at t, cached:
    implicit steps revisit their stage times."""

    NODES = np.polynomial.legendre.leggauss(8)

    def __init__(self, system: System, drive: Drive, t):
        self.system, self.drive, self.t = system, drive, np.asarray(t, dtype=float)
        self.s_nodes = arc_length(drive, self.t) if drive.traction is None else None
        self.cache: dict = {}

    def _integral(self, a, b):
        x, w = self.NODES
        mid, half = (a + b) / 2, (b - a) / 2
        return float(sum(wi * float(self.drive.speed(mid + half * xi)[0]) for xi, wi in zip(x, w)) * half)

    def s(self, time: float) -> float:
        k = max(int(np.searchsorted(self.t, time, side="right")) - 1, 0)
        return self.s_nodes[k] + self._integral(self.t[k], time)

    def state(self, time: float) -> FrameState:
        if time not in self.cache:
            if len(self.cache) > 64:
                self.cache.clear()
            self.cache[time] = _state_at(self.system, self.drive, time, self.s(time))
        return self.cache[time]

    def traction_states(self, s: float, V0: float) -> tuple[FrameState, FrameState]:
        """Frame states at arc length s [m], speed V0 [m/s] with V̇0 = 0 and 1 m/s² (the
        equations are affine in V̇0), cached by s."""
        if s not in self.cache:
            if len(self.cache) > 64:
                self.cache.clear()
            self.cache[s] = frames(self.drive, s, self.system.mdl.l)
        fr = self.cache[s]
        return frame_state(fr, 0, V0, 0.0), frame_state(fr, 0, V0, 1.0)

    def traction_step(self, time: float, y):
        """(frame state, q̈, V̇0) with traction: M q̈ + b V̇0 = -R0 and F1 = P0(t, V0) solved together
        (b = ∂R/∂V̇0, F1 the x1 resultant of (8), affine in q̈ and V̇0)."""
        system, N = self.system, self.system.N
        q, qd, s, V0 = y[:N], y[N:2 * N], y[-2], y[-1]
        fs0, fs1 = self.traction_states(float(s), float(V0))
        zero = np.zeros(N)
        R0 = system.evaluate(fs0, q, qd, zero)
        F0 = system.resultants(fs0, q, qd, zero)[0][0]
        _, A = system.coefficients(q)
        lhs = np.zeros((N + 1, N + 1))
        lhs[:N, :N] = system.mass(q)
        lhs[:N, N] = system.evaluate(fs1, q, qd, zero) - R0
        lhs[N, :N] = A @ system.inv.S1[:, 0]
        lhs[N, N] = system.resultants(fs1, q, qd, zero)[0][0] - F0
        x = np.linalg.solve(lhs, np.r_[-R0, float(self.drive.traction(time, V0)) - F0])
        return frame_state(self.cache[float(s)], 0, V0, x[N]), x[:N], x[N]


def traction_start(line: Timeline, t0: float) -> np.ndarray:
    """The quasi-static q (N,) at t0 [s] with traction: under the acceleration of the whole body by P0 along a
    level x1, at s0 and the initial speed."""
    system, drive = line.system, line.drive
    fs, _ = line.traction_states(drive.s0, drive.v_initial)
    dv = float(drive.traction(t0, drive.v_initial)) / system.inv.mass - system.mdl.g0 * fs.nu[0]
    return system.quasi_static(frame_state(line.cache[drive.s0], 0, drive.v_initial, dv))


def arc_length(drive: Drive, t) -> np.ndarray:
    """s on the grid t (n,): s0 + ∫ V0 dt, 8-point Gauss-Legendre per step [m]."""
    nodes, weights = Timeline.NODES
    mid, half = (t[1:] + t[:-1]) / 2, (t[1:] - t[:-1]) / 2
    x = mid[:, None] + half[:, None] * nodes
    v = np.broadcast_to(np.asarray(drive.speed(x)[0], dtype=float), x.shape)
    return drive.s0 + np.concatenate([[0.0], np.cumsum((v * weights).sum(axis=1) * half)])


def _dissipation(system: System, qd) -> float:
    """Power of the damping forces [W] (beam d_ij and roller dampers)."""
    power = qd @ system.inv.D @ qd
    if system.rollers_on and system.mdl.effects.damping:
        dd = system.C @ qd[:5]
        power += float(np.asarray(system.mdl.rollers.damping) @ (dd * dd))
    return float(power)


WORK_ATOL = 1e-5  # J, absolute tolerance of the work of the track forces
# Wall time per output step of this (Python) engine [s] (bundled trolley_elastic_helix on 2 shared cores: ~0.1 s;
# stiff rollers and undamped beams take more): the estimates of a run, of a sweep, of a fallback to it
SECONDS_PER_STEP = 0.1


def simulate(system: System, drive: Drive, t, method: str = "Radau", rtol: float = 1e-8,
             atol_q: float = 1e-12, dq0=None, dqd0=None, analytic_jacobian: bool = True, fallback: str = "") -> dict:
    """Integrate the relative motion on the grid t [s] (n,) from the quasi-static state at t[0]
    (plus the offsets ``dq0``, ``dqd0`` of coordinates and rates, when given).

    y = [q, q̇, E_d, W]: the coordinates, their rates, the dissipated energy and the work of the
    track forces [J]; with ``drive.traction`` also [s, V0]. The prescribed frame follows s(t) of
    :class:`Timeline`. Implicit methods ("Radau", "BDF") use the analytic Jacobian (prescribed
    speed; with traction scipy differences the right-hand side, as without ``analytic_jacobian``).
    Returns a dict of arrays with a leading axis n (see :func:`outputs`).

    The run's context (:func:`symmech.core.context.active`), when there is one, is ticked at every
    right-hand side: ``--max-time`` holds here too. ``fallback`` (why this engine runs in place of the compiled
    one) re-estimates against what is left of it and says so (:meth:`~symmech.core.context.Context.fallback`)."""
    from scipy.integrate import solve_ivp

    t = np.asarray(t, dtype=float)
    ctx = context.active()
    if ctx is not None and fallback:
        ctx.fallback(f"elastic model on the Python engine: {fallback}", SECONDS_PER_STEP * (t.size - 1))
    N = system.N
    line = Timeline(system, drive, t)
    traction = drive.traction is not None
    zero = np.zeros(N)
    if traction:
        q0 = traction_start(line, t[0])
    else:
        q0 = system.quasi_static(line.state(t[0]))

    def rhs(time, y):
        if ctx is not None:
            ctx.tick(f"elastic model, Python engine at t = {time:.6g} s")
        q, qd = y[:N], y[N:2 * N]
        if traction:
            fs, qdd, dv = line.traction_step(time, y)
            tail = [y[-1], dv]
        else:
            fs = line.state(time)
            qdd, tail = system.accelerations(fs, q, qd), []
        return np.r_[qd, qdd, _dissipation(system, qd), system.track_power(fs, q, qd, qdd), tail]

    def jac(time, y):
        fs = line.state(time)
        q, qd = y[:N], y[N:2 * N]
        qdd = system.accelerations(fs, q, qd)
        _, M, Rq, Rqd = system.evaluate(fs, q, qd, qdd, jacobian=True)
        out = np.zeros((2 * N + 2, 2 * N + 2))
        out[:N, N:2 * N] = np.eye(N)
        out[N:2 * N, :N] = -np.linalg.solve(M, Rq)
        out[N:2 * N, N:2 * N] = -np.linalg.solve(M, Rqd)
        return out

    y0 = np.r_[q0 + (zero if dq0 is None else dq0), zero if dqd0 is None else dqd0, 0.0, 0.0,
               [drive.s0, drive.v_initial] if traction else []]
    # the work of the track forces is under step control too (left out, the stiff start transient
    # goes unresolved and the reactions lose two digits), at 1e-5 J: tighter costs steps on stiff
    # rollers (10 kg on 1e8 N/m: 1761 evaluations at 1e-5 J, 2175 at 1e-9 J) for no gain in P
    atol = np.r_[np.full(N, atol_q), np.full(N, atol_q * 1e3), 1e-9, WORK_ATOL, [1e-10, 1e-10] if traction else []]
    kw = {"jac": jac} if analytic_jacobian and not traction and method in ("Radau", "BDF", "LSODA") else {}
    # Steps no longer than the output spacing: the outputs come from the dense output, whose
    # interpolation error the step control does not see (Radau's steps grow to ~0.3 s here).
    step = float(np.min(np.diff(t))) if len(t) > 1 else np.inf
    sol = solve_ivp(rhs, (t[0], t[-1]), y0, method=method, t_eval=t, rtol=rtol, atol=atol, max_step=step, **kw)
    if sol.status != 0 or not np.all(np.isfinite(sol.y)):
        raise SymmechError(f"elastic trolley: integration failed at t = {sol.t[-1]:.6g} s ({sol.message})")
    Y = sol.y.T
    if traction:
        s, V0 = Y[:, -2], Y[:, -1]
        dV0 = np.array([line.traction_step(ti, yi)[2] for ti, yi in zip(t, Y)])
        Y = Y[:, :-2]
    else:
        s = line.s_nodes
        speed = [drive.speed(ti) for ti in t]
        V0, dV0 = (np.array([float(v[k]) for v in speed]) for k in (0, 1))
    out = outputs(system, drive, t, s, V0, dV0, Y)
    out["nfev"], out["njev"] = sol.nfev, sol.njev
    return out


def row_terms(system: System, fr: model.Frame, V0, dV0, Y, height) -> dict:
    """Per output row (frame fr, speeds V0, dV0, heights of O (n,) [m], states Y (n, 2N + 2)): q̈ (n, N), the
    resultants F, M (n, 3), the coefficient vectors of r̃, its rate and acceleration (n, F), the Jacobi
    energy h and the total energy E (n,) [J]. The compiled engine computes the same in numba
    (:func:`symmech.trolley.elastic.compiled.row_terms`)."""
    N, n = system.N, len(V0)
    q, qd = Y[:, :N], Y[:, N:2 * N]
    res = {k: np.zeros((n,) + shape) for k, shape in (("qdd", (N,)), ("F", (3,)), ("M", (3,)), ("rr", (system.F,)),
                                                     ("v", (system.F,)), ("acc", (system.F,)), ("h", ()), ("E", ()))}
    for i in range(n):
        fs = frame_state(fr, i, V0[i], dV0[i])
        qdd = system.accelerations(fs, q[i], qd[i])
        res["qdd"][i] = qdd
        res["F"][i], res["M"][i] = system.resultants(fs, q[i], qd[i], qdd)
        rr, A = system.coefficients(q[i])
        res["rr"][i], res["v"][i], res["acc"][i] = rr, qd[i] @ A, qdd @ A + system._p2(qd[i])
        res["h"][i] = system.jacobi_energy(fs, q[i], qd[i])
        res["E"][i] = system.total_energy(fs, q[i], qd[i], height[i])
    return res


def outputs(system: System, drive: Drive, t, s, V0, dV0, Y, rows=row_terms, frame=None) -> dict:
    """Per output time (arrays (n,) of t, s, V0, dV0 and the states Y (n, 2N + 2)): q, q̇, q̈,
    reactions P (n, 6), resultants F, M (n, 3), roller deflections (n, 5), probe displacements
    (total and elastic) and overloads (n, n_probes, 3) [m, g], the Jacobi energy h, the total
    energy E (fixed frame), the dissipated energy and the work of the track forces [J], and the
    rigid model's reactions and overloads of the centre of mass beside them. ``rows`` computes the
    per-row terms (:func:`row_terms` or the compiled engine's); ``frame``: the frame at s when the caller has
    it (:func:`frames`)."""
    N, inv = system.N, system.inv
    q, qd, ed, work = Y[:, :N], Y[:, N:2 * N], Y[:, 2 * N], Y[:, 2 * N + 1]
    fr = frames(drive, s, system.mdl.l) if frame is None else frame
    height = drive.track.derivatives(s, 0)[0][:, 1]
    res = rows(system, fr, V0, dV0, Y, height)
    if system.rollers_on:
        d = q[:, :5] @ system.C.T
        force, _ = roller_forces(system.mdl.rollers, d, qd[:, :5] @ system.C.T, system.mdl.effects.damping)
        res["P"] = np.column_stack([res["F"][:, 0], force])
        res["deflection"] = d
        res["M_contacts"] = system.contact_moment(q, force)
    else:
        res["P"] = np.linalg.solve(system.reaction_system, np.column_stack([res["F"], res["M"]]).T).T
        res["deflection"], res["M_contacts"] = np.zeros((len(t), 5)), np.zeros((len(t), 3))
    g_ref = system.mdl.g0 if system.mdl.g0 > 0 else 9.80665
    elastic = np.zeros(system.F, bool)
    elastic[1 + inv.n_roll:1 + N] = True
    elastic[1 + N:] = [i >= inv.n_roll for i, _ in inv.pairs]
    pos, vel, ddu = (np.einsum("nk,kpi->npi", res[key], inv.probe_fields) for key in ("rr", "v", "acc"))
    _, a0, w, dw = frame_motion(fr, V0, dV0)
    a = a0[:, None] + np.cross(dw[:, None], pos) + np.cross(w[:, None], np.cross(w[:, None], pos)) + \
        2 * np.cross(w[:, None], vel) + ddu
    res["probe_displacement"] = pos - inv.probe_points
    res["probe_elastic"] = np.einsum("nk,kpi->npi", np.where(elastic, res["rr"], 0.0), inv.probe_fields)
    res["probe_overload"] = (a + system.mdl.g0 * fr.lam[:, None, :, 1]) / g_ref
    for key in ("rr", "v", "acc"):
        del res[key]
    rigid = model.body_motion(fr, V0, dV0, rigid_body(system.mdl))
    res.update(t=t, s=s, V0=V0, dV0=dV0, q=q, qd=qd, dissipated=ed, work=work, names=list(inv.names),
               P_rigid=rigid["P"], overload_rigid=rigid["overload"], W=fr.W, dW=fr.dW)
    return res
