"""Mid-plane stretching of pinned beams with held ends: the quartic (Duffing) membrane energy.

A pinned beam whose supports are axially immovable stretches as it bends: the axial force is
uniform, N = EA/(2L) ∫ w'² dx (both bending planes), and the strain energy gains
    Π_m = EA/(8L) (∫ w'² dx)² = EA/(8L³) Σ Γ_ijkl q_i q_j q_k q_l,   Γ_ijkl = H_ij H_kl,
with the mode-slope integrals H_kl = ∫0^1 N_k' N_l' dξ derived in
:func:`symmech.trolley.elastic.derive.held_membrane` (generated ``pinned_slope_gram``). H is
block-diagonal over the two planes, so Γ is kept in this product form: per beam the energy,
force and tangent stiffness are a few products of a (2n, 2n) matrix, evaluated at every step.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from symmech.generated import trolley_elastic as gen


@dataclass(frozen=True)
class Block:
    """One held beam: its coordinates ``index`` (2n,) in q (plane 1 then plane 2), the slope
    Gram ``H`` (2n, 2n) [1] and the coefficient c = EA/(8L³) [N/m³] of Π_m = c (qᵀ H q)²."""

    index: np.ndarray
    H: np.ndarray
    c: float


def block(first: int, modes: int, ea: float, length: float) -> Block:
    """The block of a beam whose 2·modes coordinates start at ``first``; EA [N], L [m]."""
    h = gen.pinned_slope_gram()[:modes, :modes]
    H = np.zeros((2 * modes, 2 * modes))
    H[:modes, :modes] = H[modes:, modes:] = h
    return Block(np.arange(first, first + 2 * modes), H, ea / (8 * length ** 3))


def energy(blocks, q):
    """Π_m [J] of all held beams at the coordinates q (..., N), shape (...)."""
    out = 0.0
    for b in blocks:
        x = q[..., b.index]
        out = out + b.c * np.einsum("...i,ij,...j->...", x, b.H, x) ** 2
    return out


def force(blocks, q) -> np.ndarray:
    """∂Π_m/∂q (N,) [N or N m]: 4 c (qᵀHq) H q per beam (the uniform axial force times the slopes)."""
    out = np.zeros(len(q))
    for b in blocks:
        x = q[b.index]
        hx = b.H @ x
        out[b.index] += 4 * b.c * float(x @ hx) * hx
    return out


def stiffness(blocks, q) -> np.ndarray:
    """∂²Π_m/∂q² (N, N): 4 c [(qᵀHq) H + 2 (Hq)(Hq)ᵀ] per beam (zero at q = 0)."""
    out = np.zeros((len(q), len(q)))
    for b in blocks:
        x = q[b.index]
        hx = b.H @ x
        out[np.ix_(b.index, b.index)] += 4 * b.c * (float(x @ hx) * b.H + 2 * np.outer(hx, hx))
    return out
