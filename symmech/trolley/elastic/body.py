"""The elastic trolley's body (seed 002, eqs. (9) and the roller section): the model's data (beams, rollers,
effects), the body sampled by weighted points, the fields φ, ψ over the samples and their Gram tensors (the
inertia invariants), the rigid body of the same mass, the beams' stiffness and damping, the rollers' forces
and energy.

The coordinates and fields are those of :mod:`symmech.trolley.elastic.system`."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from symmech.core import kinematics as kin
from symmech.core.scene import SymmechError
from symmech.generated import trolley_elastic as gen
from symmech.trolley import model
from symmech.trolley.elastic import membrane
from symmech.trolley.elastic.layout import FIELDS, RIGID_FIELDS, ROLLER_DOFS, ROTATION_PAIRS

ROLLER_NAMES = ROLLER_DOFS.names  # the roller coordinates, declared with their units
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
    rigid = RIGID_FIELDS.split(gen.rigid_fields(pts[:, 0], pts[:, 1], pts[:, 2]))  # phi, psi: (P, 3, 5), (P, 3, 6)
    if eff.rollers and mdl.rollers is not None:
        names += list(ROLLER_NAMES)
        fields += list(np.moveaxis(rigid["phi"], -1, 0))
        psi.update(zip(ROTATION_PAIRS, np.moveaxis(rigid["psi"], -1, 0)))
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
    psi_at = FIELDS.sized(N=N, P=len(pairs)).offset("psi")
    for idx, (a, b) in enumerate(pairs):
        dA[a, b] = dA[b, a] = psi_at + idx
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


def rigid_body(mdl: ElasticModel) -> model.Body:
    """The rigid model's body with the total mass, centre of mass and central inertia of
    trolley, beams and tip masses (undeformed)."""
    inv = invariants(mdl)
    m = inv.mass
    com = inv.S1[0] / m
    J = inv.G[0, 0] - m * np.outer(com, com)  # central second moment
    I = kin.inertia_from_second_moment(J)
    return model.Body(m, tuple(com), (I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[1, 2], I[0, 2]), mdl.l, mdl.ah, mdl.g0)
