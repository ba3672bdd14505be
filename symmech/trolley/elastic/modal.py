"""What each natural frequency of the elastic model is, and which mode is which along the track.

A mode's displacement part x (N,) (complex: gyroscopic, circulatory and damping terms) is
written in *components*: each roller DOF (u2, u3, θ1, θ2, θ3) and each beam's own modes per
bending plane (the eigenvectors of the beam's Ritz block of M and K on a fixed trolley, as
:func:`symmech.trolley.elastic.system.beam_mode`). Its participation in component j is the share
|y_j|² M_jj / Σ |y_i|² M_ii of the kinetic norm, y = T⁻¹ x the component coordinates and
M_jj the mass of component j at the quasi-static state (non-negative, summing to one).

Tracking: consecutive samples are matched by the mass-weighted modal assurance criterion
MAC_ab = |x_aᴴ M x_b|² / (x_aᴴ M x_a · x_bᴴ M x_b) and an optimal assignment
(``scipy.optimize.linear_sum_assignment``), so a mode keeps its identity (``mode_id``, numbered
by frequency at the first sample) through a crossing.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
from scipy.optimize import linear_sum_assignment

from symmech.trolley.elastic import system as el, body as el_body


@dataclass(frozen=True)
class Components:
    """Component basis T (N, N) (block diagonal: identity on the roller DOFs, each beam plane's
    own modes) and per component its beam (-1: rollers), plane (0: rollers), mode number (0:
    rollers), roller DOF (1…5 for u2, u3, θ1, θ2, θ3; 0: beams) and its group (0: the roller DOFs
    together; 2 b + p: beam b's plane p)."""

    T: np.ndarray
    beam: np.ndarray
    plane: np.ndarray
    mode_number: np.ndarray
    dof: np.ndarray
    group: np.ndarray
    labels: tuple


def components(system: el.System) -> Components:
    N, names = system.N, system.inv.names
    T = np.eye(N)
    beam, plane, number, dof = (np.zeros(N, int) for _ in range(4))
    beam[:] = -1
    labels = [""] * N
    for a in range(system.inv.n_roll):
        dof[a] = a + 1
        labels[a] = f"roller_{el_body.ROLLER_NAMES[a]}"
    M0 = system.mass(np.zeros(N))
    for b, _spec in enumerate(system.mdl.beams):
        for p in (1, 2):
            idx = [i for i, name in enumerate(names) if name.startswith(f"beam{b}_p{p}_m")]
            if not idx:
                continue
            block = np.ix_(idx, idx)
            _, vectors = scipy.linalg.eigh(system.inv.K[block], M0[block])
            T[block] = vectors
            for k, i in enumerate(idx):
                beam[i], plane[i], number[i] = b, p, k + 1
                labels[i] = f"beam{b}_plane{p}_mode{k + 1}"
    group = np.where(beam < 0, 0, 1 + 2 * beam + plane - 1)
    return Components(T, beam, plane, number, dof, group, tuple(labels))


def participation(comp: Components, M: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Shares (N, k) of the kinetic norm of the modes X (N, k) per component, M (N, N) the mass."""
    Y = np.linalg.solve(comp.T, X)
    weight = np.abs(Y) ** 2 * np.einsum("ij,ik,kj->j", comp.T, M, comp.T)[:, None]
    return weight / weight.sum(axis=0)


def mac(M: np.ndarray, A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Mass-weighted MAC (k, l) between the columns of A (N, k) and B (N, l), in [0, 1]."""
    cross = A.conj().T @ M @ B
    na = np.real(np.einsum("ik,ij,jk->k", A.conj(), M, A))
    nb = np.real(np.einsum("ik,ij,jk->k", B.conj(), M, B))
    return np.abs(cross) ** 2 / np.outer(na, nb)


def align(M: np.ndarray, previous: np.ndarray, X: np.ndarray) -> np.ndarray:
    """X (N, k) with each column turned by the complex phase that makes xᴴ_prev M x real and
    positive (the shapes and their signs then continue along the track)."""
    cross = np.einsum("ik,ij,jk->k", previous.conj(), M, X)
    return X * np.where(np.abs(cross) > 0, np.abs(cross) / np.where(cross == 0, 1, cross), 1.0)


def start_phase(M: np.ndarray, X: np.ndarray) -> np.ndarray:
    """X with each column turned so that its largest component (in the kinetic norm) is real
    and positive: a reproducible sign at the first sample."""
    weight = np.abs(X) ** 2 * np.diag(M)[:, None]
    top = X[np.argmax(weight, axis=0), np.arange(X.shape[1])]
    return X * (np.abs(top) / top)


def track(samples) -> tuple[list, list, np.ndarray]:
    """Modes followed along the samples, a list of (M (N, N), X (N, k)) each in frequency order.
    Returns per sample the column of X holding mode_id 0…k-1 (at the first sample the frequency
    order), the modes X in mode_id order turned to continue the previous sample's
    (:func:`align`), and the smallest matched MAC between each sample and the next (n - 1,)."""
    M, X = samples[0]
    order, shapes, worst = [np.arange(X.shape[1])], [start_phase(M, X)], []
    for M, X in samples[1:]:
        score = mac(M, shapes[-1], X)
        rows, cols = linear_sum_assignment(-score)
        order.append(cols[np.argsort(rows)])
        shapes.append(align(M, shapes[-1], X[:, order[-1]]))
        worst.append(score[rows, cols].min())
    return order, shapes, np.array(worst)


def curvature_hessian(system: el.System, q: np.ndarray) -> np.ndarray:
    """Hessian (N, N) at q of the bending energy the model leaves out, of the same order as its
    quadratic axial fields [N/m]: Π_c = ½ ∫ g² dx, g = Σ_p √EI_p w_p' w_p'' over the two planes
    (primes d/dx). For bending in one plane it is the quartic part of ½ EI ∫ κ² of an
    inextensible beam, κ² = w''²/(1 - w'²) = w''² + w'² w''² + O(w⁶); across the planes it is
    exact for equal stiffness (κ² = |r''|²) and an estimate otherwise (torsion left out)."""
    H = np.zeros((system.N, system.N))
    if not system.mdl.effects.body:
        return H
    xg, wg = np.polynomial.legendre.leggauss(el_body.BEAM_GAUSS)
    xi, wg = (xg + 1) / 2, wg / 2
    names = system.inv.names
    for b, beam in enumerate(system.mdl.beams):
        n = beam.modes
        basis = el_body.beam_basis(beam.support, xi)[0][:, :, :n]
        d1, d2 = basis[:, 1] / beam.length, basis[:, 2] / beam.length ** 2  # (P, n) d/dx, d²/dx²
        idx = [[names.index(f"beam{b}_p{p}_m{k + 1}") for k in range(n)] for p in (1, 2)]
        root = np.sqrt(beam.ei)
        g = sum(c * (d1 @ q[i]) * (d2 @ q[i]) for c, i in zip(root, idx))
        grad = np.concatenate([c * (d1 * (d2 @ q[i])[:, None] + d2 * (d1 @ q[i])[:, None])
                               for c, i in zip(root, idx)], axis=1)
        block = np.einsum("p,pk,pl->kl", wg, grad, grad)
        curl = np.einsum("p,pk,pl->kl", wg * g, d1, d2)
        for plane, c in enumerate(root):
            sl = slice(plane * n, (plane + 1) * n)
            block[sl, sl] += c * (curl + curl.T)
        flat = idx[0] + idx[1]
        H[np.ix_(flat, flat)] += beam.length * block
    return H


def curvature_shift(system: el.System, q: np.ndarray, omega: np.ndarray, X: np.ndarray) -> np.ndarray:
    """Relative change (k,) of the frequencies ω (k,) [rad/s] of the modes X (N, k) at the
    quasi-static state q that the left-out curvature energy would cause, to first order:
    δω/ω = Re(xᴴ H_c x) / (2 ω² xᴴ M x) (Rayleigh; :func:`curvature_hessian`)."""
    H, M = curvature_hessian(system, q), system.mass(q)
    num = np.real(np.einsum("ik,ij,jk->k", X.conj(), H, X))
    den = np.real(np.einsum("ik,ij,jk->k", X.conj(), M, X))
    return np.where(omega > 0, num / (2 * np.where(omega > 0, omega, 1.0) ** 2 * den), 0.0)


def beam_slope(system: el.System, q: np.ndarray) -> float:
    """Largest slope |w'| (both planes together) of the beams at q [1] (0 without beams)."""
    if not system.mdl.effects.body:
        return 0.0
    xi = np.linspace(0.0, 1.0, el.MODE_SAMPLES)
    slope = 0.0
    for b, beam in enumerate(system.mdl.beams):
        d1 = el_body.beam_basis(beam.support, xi)[0][:, 1, :beam.modes] / beam.length
        w = [d1 @ q[[system.inv.names.index(f"beam{b}_p{p}_m{k + 1}") for k in range(beam.modes)]] for p in (1, 2)]
        slope = max(slope, float(np.hypot(*w).max()))
    return slope
