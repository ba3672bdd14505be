"""Impact laws for the grain at its contact point K, vectorised over grains.

Notation: ``u`` (..., 3) velocity of the body point at K relative to the surface
[m/s], normal e_z; ``P`` (..., 3) impulse on the body [N s]; ``K`` (..., 3, 3)
inverse effective mass [1/kg], ``u+ = u- + K P`` with
``K = (E - m [R]x I_K^-1 [R]x)/m = H/m`` (H the paper's reduction tensor, (2)-(10)).

Energy-consistent law (Chatterjee & Ruina 1998, "A new algebraic rigid-body
collision law based on impulse space considerations", J. Appl. Mech. 65):
``P_I = -(u_n / K_nn) n`` (frictionless, perfectly plastic), ``P_II = -K^-1 u``
(perfectly plastic, sticking), ``D = P_II - P_I``, ``P^ = (1 + e_n) P_I + (1 + e_t) D``;
if ``|P^_t| <= mu P^_n`` then ``P = P^``, else ``P = (1 + e_n) P_I + kappa D`` with
kappa putting P on the friction cone.
It never creates energy for 0 <= e_n <= 1, -1 <= e_t <= e_n (tested). For a
sphere, ``e_n = e``, ``e_t = lambda - 1``, ``mu = inf`` is the printed law
(normal restitution e, tangential speed times 1 - lambda, same direction).

With the rotation effect off, the grain is a point mass: ``K = E/m`` and the
printed law is this law with ``e_n = e, e_t = lambda - 1, mu = inf``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from symmech.core import kinematics as kin
from symmech.grain import contact, outcome
from symmech.grain.impact import solve_robust_batch

PRINTED_RESIDUAL = 1e-8  # relative residual of (19) below which the printed law counts as solved


def inverse_effective_mass(mass, inertia, Q, R):
    """K (..., 3, 3) [1/kg]: mass (...,) kg, inertia (..., 3) principal kg m^2, Q (..., 3, 3), R (..., 3) m."""
    mass = np.asarray(mass, dtype=float)
    inv_i = kin.rotate_tensor(Q, np.eye(3) / np.asarray(inertia, dtype=float)[..., None, :])
    Rx = kin.skew(R)
    return np.eye(3) / mass[..., None, None] - Rx @ inv_i @ Rx


def coulomb_impulse(K, u, e_n, e_t, mu):
    """Impulse P (..., 3) [N s] of the Chatterjee-Ruina law; e_n, e_t, mu broadcast over grains."""
    e_n, e_t, mu = (np.asarray(x, dtype=float)[..., None] for x in (e_n, e_t, mu))
    k_nn = K[..., 2, 2][..., None]
    P_I = np.zeros_like(u)
    P_I[..., 2] = -u[..., 2] / k_nn[..., 0]  # frictionless, perfectly plastic
    D = -np.linalg.solve(K, u[..., None])[..., 0] - P_I  # sticking plastic minus frictionless plastic
    P = (1.0 + e_n) * P_I + (1.0 + e_t) * D
    d_t = np.linalg.norm(D[..., :2], axis=-1, keepdims=True)
    p_t = np.linalg.norm(P[..., :2], axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        # Written with 1/mu so that mu = inf (half-space) and mu = 0 (frictionless) are exact limits.
        outside = np.where(mu > 0, p_t / mu > P[..., 2:3], p_t > 0)
        kappa = (1.0 + e_n) * P_I[..., 2:3] / (d_t / mu - D[..., 2:3])
    return np.where(outside, (1.0 + e_n) * P_I + np.where(outside, kappa, 0.0) * D, P)


def kinetic_energy(mass, inertia, Q, v, w):
    """Kinetic energy (...,) [J]; v (..., 3) m/s, w (..., 3) rad/s in KXYZ."""
    wb = np.einsum("...ji,...j->...i", Q, w)
    return 0.5 * np.asarray(mass) * np.einsum("...i,...i->...", v, v) + 0.5 * np.einsum(
        "...i,...i->...", np.asarray(inertia) * wb, wb)


def principal_inertia(axes, mass):
    """Principal moments (..., 3) [kg m^2] of solid ellipsoids: m/5 (b^2+c^2, a^2+c^2, a^2+b^2)."""
    a2 = np.asarray(axes, dtype=float) ** 2
    return np.asarray(mass, dtype=float)[..., None] / 5.0 * (a2.sum(axis=-1, keepdims=True) - a2)


@dataclass(frozen=True)
class ImpactLaw:
    """``kind`` "printed" (e, lam; eqs (14)-(20)) or "coulomb" (e_n, e_t, mu; Chatterjee-Ruina).

    With the Coulomb law and ``check_printed``, the printed law (e = e_n,
    lam = 1 + e_t) is evaluated too, so the log says whether it would have created energy.
    """

    kind: str
    e: float = 0.0
    lam: float = 0.0
    e_n: float = 0.0
    e_t: float = 0.0
    mu: float = np.inf
    check_printed: bool = True

    def apply(self, axes, mass, Q, v, w, rotation: bool) -> dict:
        """Post-impact states and log fields for n grains at their lowest points.

        axes (n, 3) m, mass (n,) kg, Q (n, 3, 3), v (n, 3) m/s, w (n, 3) rad/s in KXYZ.
        A contact point that is not approaching the plane gets no impulse. The printed
        law is solved exactly (impact.py's robust solver, vectorised). Returns arrays:
        ``v``, ``w`` (n, 3) after, ``impulse`` (n, 3) N s, ``u_before``,
        ``u_after`` (n, 3) contact velocities, ``ke_before``, ``ke_after`` (n,) J,
        ``admissible`` (n,) (no energy created), ``printed_admissible`` (n,) (the printed
        law's verdict: a root that neither creates energy nor pulls the grain into the
        plane; None when not evaluated), ``printed_creates_energy`` (n,) (True/False/None), ``converged`` (n,), and ``warnings`` (list of str).
        """
        n = len(mass)
        R = contact.contact_offset(axes, Q)
        inertia = principal_inertia(axes, mass)
        w = np.asarray(w, dtype=float) if rotation else np.zeros((n, 3))
        u = v + np.cross(w, R)
        warnings: list[str] = []
        converged = np.ones(n, dtype=bool)
        printed_admissible = [None] * n
        printed_creates = [None] * n
        if not rotation:
            K = np.eye(3) / np.asarray(mass, dtype=float)[:, None, None]
        else:
            K = inverse_effective_mass(mass, inertia, Q, R)
        approaching = u[:, 2] < 0.0
        if rotation and (self.kind == "printed" or self.check_printed) and approaching.any():
            e, lam = (self.e, self.lam) if self.kind == "printed" else (self.e_n, 1.0 + self.e_t)
            idx = np.flatnonzero(approaching)
            m = np.asarray(mass, dtype=float)[idx]
            printed = solve_robust_batch(m[:, None, None] * K[idx], m, e, lam, u[idx])
            for j, i in enumerate(idx):
                printed_admissible[i] = bool(printed.admissible[j])
                printed_creates[i] = bool(printed.energy_created[j])
            if self.kind == "printed":
                for j in np.flatnonzero(~printed.admissible):
                    warnings.append(outcome.printed_inadmissible_warning(bool(printed.energy_created[j])))
            if self.kind == "printed":
                converged[idx] = printed.residual < PRINTED_RESIDUAL
                for j in np.flatnonzero(~converged[idx]):
                    warnings.append(outcome.printed_residual_warning(printed.residual[j]))
        if rotation and self.kind == "printed":
            P = np.zeros((n, 3))
            if approaching.any():
                P[idx] = printed.T
        else:
            e_n, e_t, mu = ((self.e, self.lam - 1.0, np.inf) if self.kind == "printed"
                            else (self.e_n, self.e_t, self.mu))
            P = np.where(approaching[:, None], coulomb_impulse(K, u, e_n, e_t, mu), 0.0)
        v_after = v + P / np.asarray(mass, dtype=float)[:, None]
        if rotation:
            I_k = kin.rotate_tensor(Q, inertia[..., None, :] * np.eye(3))
            w_after = w + np.linalg.solve(I_k, np.cross(R, P)[..., None])[..., 0]
        else:
            w_after = np.zeros((n, 3))
        ke_before = kinetic_energy(mass, inertia, Q, v, w)
        ke_after = kinetic_energy(mass, inertia, Q, v_after, w_after)
        admissible = ke_after <= ke_before * (1.0 + 1e-9)
        for i in np.flatnonzero(~admissible):
            warnings.append(outcome.energy_created_warning(self.kind, ke_before[i], ke_after[i]))
        return {"v": v_after, "w": w_after, "impulse": P, "u_before": u,
                "u_after": v_after + np.cross(w_after, R), "ke_before": ke_before, "ke_after": ke_after,
                "admissible": admissible, "printed_admissible": printed_admissible,
                "printed_creates_energy": printed_creates,
                "converged": converged, "warnings": warnings}
