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

from functools import cached_property

import numpy as np

from symmech.core import kinematics as kin
from symmech.core.scene import SymmechError
from symmech.generated import trolley_elastic as gen
from symmech.trolley.elastic import membrane
from symmech.trolley.elastic.body import (ElasticModel, beam_basis, invariants, rigid_body, roller_energy,
                                          roller_forces)
from symmech.trolley.elastic.frame import FrameState
from symmech.trolley.elastic.layout import (FIELDS, FLAGS, MODEL, N_ROLLER_DOFS, RIGID_FIELDS, RL_AT, ROLLER,
                                           ROTATION_PAIRS, edges)

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
        self.fields = FIELDS.sized(N=self.N, P=len(inv.pairs))  # the coefficient vectors over the F fields
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

    @cached_property
    def beam_fields(self) -> np.ndarray:
        """(F,) bool: the fields of the beams' deflection, their φ and ψ (not the roller coordinates')."""
        fields, n_roll = self.fields, self.inv.n_roll
        mask = np.zeros(fields.size, bool)
        mask[fields.slice("phi")] = np.arange(self.N) >= n_roll
        mask[fields.slice("psi")] = [i >= n_roll for i, _ in self.inv.pairs]
        return mask

    @cached_property
    def rigid(self):
        """The rigid model's body (``symmech.trolley.model.Body``) of the same total mass, centre of mass and
        central inertia (:func:`~symmech.trolley.elastic.body.rigid_body`), made once: a traction run finds its
        span with it, and every run's outputs set the rigid reactions beside the elastic ones."""
        return rigid_body(self.mdl)

    @cached_property
    def record(self):
        """The model as the compiled kernels take it (:data:`symmech.trolley.elastic.layout.MODEL`), packed once:
        the compiled run, its output rows and the export read this one record."""
        inv, mdl = self.inv, self.mdl
        n, f = self.N, self.F
        rows = [[] for _ in range(n)]  # the ψ entries of A: (column, index of the coordinate multiplying it)
        for p, (i, j) in enumerate(inv.pairs):
            rows[i].append((self.fields.offset("psi") + p, j))
            if i != j:
                rows[j].append((self.fields.offset("psi") + p, i))
        ptr = np.cumsum([0] + [len(r) for r in rows]).astype(np.int64)
        col = np.array([c for r in rows for c, _ in r], dtype=np.int64)
        qi = np.array([x for r in rows for _, x in r], dtype=np.int64)
        roll = np.zeros((ROLLER.size, 5))
        law = 0.0
        if self.rollers_on:
            rl = mdl.rollers
            roll[RL_AT.stiffness] = rl.stiffness
            roll[RL_AT.damping] = rl.damping if mdl.effects.damping else 0.0
            roll[RL_AT.preload] = rl.preload
            law = 0.0 if rl.law == "linear" else 1.0
        blocks = inv.membrane
        width = max([len(b.index) for b in blocks], default=1)
        idx = np.zeros((len(blocks), width), dtype=np.int64)
        H = np.zeros((len(blocks), width, width))
        for b, blk in enumerate(blocks):
            m = len(blk.index)
            idx[b, :m], H[b, :m, :m] = blk.index, blk.H
        flags = FLAGS.pack(n=n, f=f, mass=inv.mass, g0=mdl.g0, rollers=1.0 if self.rollers_on else 0.0, law=law)
        return MODEL.pack(
            **edges(n, len(inv.pairs)), flags=flags, ptr=ptr, col=col, qi=qi, pair_i=self.pair_i, pair_j=self.pair_j,
            gram_x=inv.G.transpose(0, 2, 3, 1).reshape(9 * f, f), gram_trace=self.Gtr, rollers_map=self.C, roll=roll,
            block_index=idx, block_size=[len(b.index) for b in blocks], block_h=H, block_c=[b.c for b in blocks],
            s1=inv.S1, stiffness=inv.K, damping=inv.D, pair_field=inv.dA, gram_9=inv.G.reshape(f * f, 9))

    # coefficient vectors over the fields
    def coefficients(self, q):
        N, fields = self.N, self.fields
        rr = np.zeros(fields.size)
        rr[fields.offset("r")] = 1.0
        rr[fields.slice("phi")] = q
        qi, qj = q[self.pair_i], q[self.pair_j]
        rr[fields.slice("psi")] = np.where(self.diag, 0.5, 1.0) * qi * qj
        A = self._dv(q)
        A[np.arange(N), fields.offset("phi") + np.arange(N)] = 1.0
        return rr, A

    def _dv(self, rate):
        """(N, F): ∂(Σ_c rate_c φ̃_c)/∂q_b = Σ_c rate_c ψ_cb (with rate = q: the ψ part of φ̃_b)."""
        out = np.zeros((self.N, self.F))
        cols = self.fields.offset("psi") + np.arange(len(self.pair_i))
        np.add.at(out, (self.pair_i, cols), rate[self.pair_j])
        off = ~self.diag
        np.add.at(out, (self.pair_j[off], cols[off]), rate[self.pair_i[off]])
        return out

    def quadratic_rates(self, qd):
        """(F,) the coefficients over the fields of the acceleration's terms quadratic in the rates q̇ (N,):
        Σ_ab q̇_a q̇_b ψ_ab, on the ψ fields only."""
        out = np.zeros(self.F)
        out[self.fields.slice("psi")] = np.where(self.diag, 1.0, 2.0) * qd[self.pair_i] * qd[self.pair_j]
        return out

    def roller_state(self, q, qd):
        """Deflections d, rates, forces P1…P5 and tangent stiffness (zeros without rollers)."""
        if not self.rollers_on:
            z = np.zeros(5)
            return z, z, z, z
        d, dd = self.C @ q[:N_ROLLER_DOFS], self.C @ qd[:N_ROLLER_DOFS]
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
        acc = qdd @ A + self.quadratic_rates(qd)
        B, W, GB, GW = self._frame_mats(fs)
        load = fs.a0 + g0 * fs.nu
        z = inv.S1 @ load + GB @ rr + 2 * GW @ v + self.Gtr @ acc
        R = A @ z + inv.K @ q + inv.D @ qd + membrane.force(inv.membrane, q)
        d, dd, force, kt = self.roller_state(q, qd)
        if self.rollers_on:
            R[:N_ROLLER_DOFS] -= self.C.T @ force
        if not jacobian:
            return R
        M = A @ self.Gtr @ A.T
        zpad = np.append(z, 0.0)
        DV, DQ = self._dv(qd), self._dv(qdd)
        Rq = zpad[self.inv.dA] + A @ (GB @ A.T + 2 * GW @ DV.T + self.Gtr @ DQ.T) + inv.K + \
            membrane.stiffness(inv.membrane, q)
        Rqd = A @ (2 * GW @ A.T + 2 * self.Gtr @ DV.T) + inv.D
        if self.rollers_on:
            rollers = slice(N_ROLLER_DOFS)
            Rq[rollers, rollers] -= self.C.T @ (kt[:, None] * self.C)
            if self.mdl.effects.damping:
                Rqd[rollers, rollers] += self.C.T @ (np.asarray(self.mdl.rollers.damping)[:, None] * self.C)
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
        acc = qdd @ A + self.quadratic_rates(qd)
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
        f = RIGID_FIELDS.split(gen.rigid_fields(p[:, 0], p[:, 1], p[:, 2]))
        q = np.asarray(q, float)
        u = np.einsum("pik,...k->...pi", f["phi"], q[..., :N_ROLLER_DOFS])
        for (i, j), psi in zip(ROTATION_PAIRS, np.moveaxis(f["psi"], -1, 0)):
            u = u + (0.5 if i == j else 1.0) * (q[..., i] * q[..., j])[..., None, None] * psi
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
            pi = pi + roller_energy(self.mdl.rollers, q[..., :N_ROLLER_DOFS] @ self.C.T)
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
