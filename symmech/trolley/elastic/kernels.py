"""The elastic trolley's assembly in numba: the right-hand side and Jacobian the toolkit's Radau IIA
(:mod:`symmech.numerics.ode`) integrates, the cached whole solve and the per-row output terms (:func:`rows`); driven by
:mod:`symmech.trolley.elastic.compiled` (a module of its own: numba's cache is keyed on the file, so the
driver changes without a recompile).

The physics is that of ``System.evaluate`` / ``resultants`` (the Python engine stays the reference; the
tests compare the two): per state the coefficient vectors over the fields (rr, and v = q̇ A, the
ψ part of A held as a sparse list of entries), two passes over the Gram tensor G (X_k = Σ_l G_kl rr_l,
Y_k = Σ_l G_kl v_l) give the residual R, the resultants F, M_O (track power) and the mass matrix; the
Jacobian forms G:B and G:W explicitly. The frame enters as 12 channels (load a0 + g0 ν, ω, ω̇, v0) of a
spline table in t; with traction (s, V0 states) as 15 geometry channels of a spline table in s, from which
the kernels form those 12 at each stage's V0, V̇0 (:func:`_motion`). The model comes as one record
(:data:`symmech.trolley.elastic.layout.MODEL`, packed once per model by ``System.record``); the vectors whose
length follows the model's size (the state, the field coefficients, the traction unknowns) are indexed
through the edges it carries (``mdl.state_at[Y_AT.qd]``: where q̇ starts).

The generic steppers are compiled per right-hand side as closures (:func:`ode.steppers` at module level)
and inlined into the cached entry :func:`solve`, so a second process loads the whole solve from numba's
cache (see :mod:`symmech.numerics.ode`).
"""
from __future__ import annotations

import math

import numba
import numpy as np

from symmech.numerics import ode, radau
from symmech.numerics.jit import jit, with_gil
from symmech.trolley.elastic import layout  # noqa: F401 (a module global: numerics.artifacts then records its file as a source of this build, so a changed declaration rebuilds)
from symmech.trolley.elastic.layout import (CH_AT, CO_AT, F_AT, FC_AT, G_AT, N_CHANNELS, N_GEOMETRY, N_ROLLER_DOFS,
                                            RL_AT, U_AT, Y_AT)

MAX_STEPS = 50_000_000


# --------------------------------------------------------------------------- small pieces

@jit
def _channels(tab, t, out):
    """The 12 frame channels at t [s] from the spline table tab = (nodes (n,), coefficients (4, n - 1, 12))."""
    tk, c = tab
    i = np.searchsorted(tk, t, side="right") - 1
    i = min(max(i, 0), tk.size - 2)
    x = t - tk[i]
    for j in range(N_CHANNELS):
        out[j] = ((c[0, i, j] * x + c[1, i, j]) * x + c[2, i, j]) * x + c[3, i, j]


@jit
def _frame_mats(ch):
    """B = skew(ω̇) + skew(ω)² and W = skew(ω) (3, 3) from the channels ch (12,)."""
    w, dw = ch[CH_AT.omega:CH_AT.omega + 3], ch[CH_AT.domega:CH_AT.domega + 3]
    W = np.zeros((3, 3))
    W[0, 1], W[0, 2], W[1, 2] = -w[2], w[1], -w[0]
    W[1, 0], W[2, 0], W[2, 1] = w[2], -w[1], w[0]
    B = W @ W
    B[0, 1] -= dw[2]
    B[0, 2] += dw[1]
    B[1, 2] -= dw[0]
    B[1, 0] += dw[2]
    B[2, 0] -= dw[1]
    B[2, 1] += dw[0]
    return B, W


@jit
def _times_a(mdl, y, x):
    """y A(x) (F,): the coefficient vector of Σ_b y_b φ̃_b with φ̃_b = φ_b + Σ_c x_c ψ_bc, y and x (N,)."""
    n, f = int(mdl.flags[F_AT.n]), int(mdl.flags[F_AT.f])
    ptr, col, qi, phi = mdl.ptr, mdl.col, mdl.qi, mdl.fields_at[FC_AT.phi]
    out = np.zeros(f)
    for b in range(n):
        out[phi + b] = y[b]
        for e in range(ptr[b], ptr[b + 1]):
            out[col[e]] += y[b] * x[qi[e]]
    return out


@jit
def _a_times(mdl, q, z):
    """A(q) z (N,) for z (F,)."""
    n = int(mdl.flags[F_AT.n])
    ptr, col, qi, phi = mdl.ptr, mdl.col, mdl.qi, mdl.fields_at[FC_AT.phi]
    out = np.empty(n)
    for b in range(n):
        acc = z[phi + b]
        for e in range(ptr[b], ptr[b + 1]):
            acc += q[qi[e]] * z[col[e]]
        out[b] = acc
    return out


@jit
def _a_rows(mdl, q, Z):
    """A(q) Z (N, k) for Z (F, k): row b gathers Z's row of φ_b and the ψ rows of row b."""
    n = int(mdl.flags[F_AT.n])
    ptr, col, qi, phi = mdl.ptr, mdl.col, mdl.qi, mdl.fields_at[FC_AT.phi]
    out = np.empty((n, Z.shape[1]))
    for b in range(n):
        out[b] = Z[phi + b]
        for e in range(ptr[b], ptr[b + 1]):
            x = q[qi[e]]
            for j in range(Z.shape[1]):
                out[b, j] += x * Z[col[e], j]
    return out


@jit
def _rr(mdl, q):
    """Coefficients (F,) of r̃ = r + Σ q_a φ_a + ½ Σ q_a q_b ψ_ab over the fields."""
    n, f = int(mdl.flags[F_AT.n]), int(mdl.flags[F_AT.f])
    pi, pj, at = mdl.pair_i, mdl.pair_j, mdl.fields_at
    phi, psi = at[FC_AT.phi], at[FC_AT.psi]
    out = np.zeros(f)
    out[at[FC_AT.r]] = 1.0
    out[phi:phi + n] = q
    for p in range(pi.size):
        out[psi + p] = (0.5 if pi[p] == pj[p] else 1.0) * q[pi[p]] * q[pj[p]]
    return out


@jit
def _gram_pass(Gx, x):
    """X (F, 9) with X_k = Σ_l G_kl x_l (row-major 3 x 3), from Gx (F 9, F) the Gram tensor laid out for it."""
    return (Gx @ x).reshape(x.size, 9)


@jit
def _contract(G9, M):
    """G:M (F, F), (G:M)_kl = Σ_ij G_klij M_ij, from G9 (F F, 9)."""
    f = int(math.sqrt(G9.shape[0]) + 0.5)
    return (G9 @ M.copy().reshape(9)).reshape(f, f)


@jit
def _rollers(mdl, q, qd):
    """Roller deflections d, forces P1…P5 [N] and tangent stiffness dP/dd [N/m] (elastic.roller_forces)."""
    C, roll, law = mdl.rollers_map, mdl.roll, mdl.flags[F_AT.law]
    d, dd = C @ q[:N_ROLLER_DOFS], C @ qd[:N_ROLLER_DOFS]
    k, c, pre = roll[RL_AT.stiffness], roll[RL_AT.damping], roll[RL_AT.preload]
    if law == 0.0:
        return d, -k * d - c * dd, -k
    up, down = pre - d, pre + d
    force = k * (np.maximum(up, 0.0) - np.maximum(down, 0.0)) - c * dd
    return d, force, -k * (1.0 + (np.sign(up) + np.sign(down)) / 2)


@jit
def _membrane(mdl, q, R, Rq, stiffness):
    """Adds the held beams' membrane force to R (N,) and, with ``stiffness``, its Hessian to Rq (N, N)."""
    idx, size, H, cm = mdl.block_index, mdl.block_size, mdl.block_h, mdl.block_c
    for b in range(size.size):
        m = size[b]
        x = np.empty(m)
        for i in range(m):
            x[i] = q[idx[b, i]]
        Hb = H[b, :m, :m]
        hx = Hb @ x
        quad = x @ hx
        for i in range(m):
            R[idx[b, i]] += 4 * cm[b] * quad * hx[i]
            if stiffness:
                for j in range(m):
                    Rq[idx[b, i], idx[b, j]] += 4 * cm[b] * (quad * Hb[i, j] + 2 * hx[i] * hx[j])


# --------------------------------------------------------------------------- the state's terms

@jit
def _terms(mdl, ch, q, qd):
    """(R0 (N,) the residual at q̈ = 0, M (N, N), rr, v, p2 (F,), X (F, 9), B, W, z (F,)) at one state."""
    flags, Gx, Gtr, S1, K, D = mdl.flags, mdl.gram_x, mdl.gram_trace, mdl.s1, mdl.stiffness, mdl.damping
    rr = _rr(mdl, q)
    v = _times_a(mdl, qd, q)
    p2 = _times_a(mdl, qd, qd)
    p2[:mdl.fields_at[FC_AT.psi]] = 0.0  # its r and φ parts
    B, W = _frame_mats(ch)
    X = _gram_pass(Gx, rr)
    Y = _gram_pass(Gx, v)
    load = ch[CH_AT.load:CH_AT.load + 3].copy()
    z = S1 @ load + Gtr @ p2 + X @ B.copy().reshape(9) + 2.0 * (Y @ W.copy().reshape(9))
    R = _a_times(mdl, q, z) + K @ q + D @ qd
    _membrane(mdl, q, R, R.reshape(1, -1), False)
    if flags[F_AT.rollers] != 0.0:
        _, force, _ = _rollers(mdl, q, qd)
        R[:N_ROLLER_DOFS] -= force @ mdl.rollers_map
    AG = _a_rows(mdl, q, Gtr)  # A Gtr (N, F)
    M = _a_rows(mdl, q, AG.T.copy())  # A Gtr Aᵀ
    return R, M, rr, v, p2, X, B, W, z


@jit
def _resultants(mdl, ch, rr, v, acc, X, B, W):
    """Force F and moment M_O (3,) of ∫ (a - g) dm (System.resultants); acc (F,) the coefficients of ü."""
    flags, S1 = mdl.flags, mdl.s1
    load = ch[CH_AT.load:CH_AT.load + 3].copy()
    first, fv, fa = rr @ S1, v @ S1, acc @ S1
    F = flags[F_AT.mass] * load + B @ first + 2.0 * W @ fv + fa
    # J(y) = Σ_kl rr_k y_l G_kl = Σ_l y_l X_lᵀ (G_kl = G_lkᵀ)
    Jr, Jv, Ja = (rr @ X).reshape(3, 3).T, (v @ X).reshape(3, 3).T, (acc @ X).reshape(3, 3).T
    H = Jr @ B.T + 2.0 * Jv @ W.T + Ja
    moment = np.cross(first, load) - np.array([H[2, 1] - H[1, 2], H[0, 2] - H[2, 0], H[1, 0] - H[0, 1]])
    return F, moment


@jit
def _accelerations(mdl, ch, q, qd):
    """q̈ (N,) and the terms of :func:`_terms` at the state."""
    R, M, rr, v, p2, X, B, W, z = _terms(mdl, ch, q, qd)
    qdd = -np.linalg.solve(M, R)
    return qdd, M, rr, v, p2, X, B, W, z


@jit
def _rhs(t, y, args, out):
    """y' of the state y (layout.STATE); args = (model record (layout.MODEL), spline table, calls (1,))."""
    mdl, tab, calls = args
    calls[0] += 1.0
    at = mdl.state_at
    iq, iqd, n = at[Y_AT.q], at[Y_AT.qd], int(mdl.flags[F_AT.n])
    ch = np.empty(N_CHANNELS)
    _channels(tab, t, ch)
    q, qd = y[iq:iq + n], y[iqd:iqd + n]
    qdd, M, rr, v, p2, X, B, W, z = _accelerations(mdl, ch, q, qd)
    acc = _times_a(mdl, qdd, q) + p2
    F, moment = _resultants(mdl, ch, rr, v, acc, X, B, W)
    out[iq:iq + n] = qd
    out[iqd:iqd + n] = qdd
    out[at[Y_AT.dissipated]] = _dissipation(mdl, qd)
    out[at[Y_AT.work]] = F @ ch[CH_AT.v0:CH_AT.v0 + 3] + moment @ ch[CH_AT.omega:CH_AT.omega + 3]


@jit
def _dissipation(mdl, qd):
    """Power of the damping forces [W] (beam D and roller dampers)."""
    power = qd @ mdl.damping @ qd
    if mdl.flags[F_AT.rollers] != 0.0:
        dd = mdl.rollers_map @ qd[:N_ROLLER_DOFS]
        power += mdl.roll[RL_AT.damping] @ (dd * dd)
    return power


@jit
def _jacobians(mdl, ch, q, qd):
    """M, ∂R/∂q, ∂R/∂q̇ (N, N) at the state, q̈ from the equations (System.evaluate with ``jacobian``)."""
    flags, G9, Gtr, K, D = mdl.flags, mdl.gram_9, mdl.gram_trace, mdl.stiffness, mdl.damping
    C, dA = mdl.rollers_map, mdl.pair_field
    n = q.size
    qdd, M, rr, v, p2, X, B, W, z = _accelerations(mdl, ch, q, qd)
    z = z + Gtr @ _times_a(mdl, qdd, q)  # z at the state's q̈
    GW = _contract(G9, W)
    # Rq = A (GB Aᵀ + 2 GW DVᵀ + Gtr DQᵀ), Rqd = A (2 GW Aᵀ + 2 Gtr DVᵀ), DV, DQ the ψ parts of A at q̇, q̈;
    # by the symmetries (G:B)ᵀ = G:Bᵀ, (G:W)ᵀ = -G:W (W skew), Gtrᵀ = Gtr, each Z Aᵀ is (A Zᵀ)ᵀ
    phi = mdl.fields_at[FC_AT.phi]
    psi = lambda x, Zt: _a_rows(mdl, x, Zt) - Zt[phi:phi + n]  # noqa: E731  DV(x) Zt
    T = _a_rows(mdl, q, _contract(G9, B.T.copy())) - 2.0 * psi(qd, GW) + psi(qdd, Gtr)
    S = -2.0 * _a_rows(mdl, q, GW) + 2.0 * psi(qd, Gtr)
    Rq = _a_rows(mdl, q, T.T.copy()) + K
    Rqd = _a_rows(mdl, q, S.T.copy()) + D
    for a in range(n):
        for b in range(n):
            if dA[a, b] >= 0:
                Rq[a, b] += z[dA[a, b]]
    R0 = np.zeros(n)
    _membrane(mdl, q, R0, Rq, True)
    if flags[F_AT.rollers] != 0.0:
        _, _, kt = _rollers(mdl, q, qd)
        c = mdl.roll[RL_AT.damping]
        for i in range(N_ROLLER_DOFS):
            for j in range(N_ROLLER_DOFS):
                for r in range(c.size):
                    Rq[i, j] -= C[r, i] * kt[r] * C[r, j]
                    Rqd[i, j] += C[r, i] * c[r] * C[r, j]
    return M, Rq, Rqd


@jit
def _jac(t, y, args, J):
    """dy'/dy of the state (layout.STATE) by the state: the rows of q and q̇ (those of E_d and W zero, as the
    Python engine's)."""
    mdl, tab, _ = args
    at = mdl.state_at
    iq, iqd, n = at[Y_AT.q], at[Y_AT.qd], int(mdl.flags[F_AT.n])
    ch = np.empty(N_CHANNELS)
    _channels(tab, t, ch)
    M, Rq, Rqd = _jacobians(mdl, ch, y[iq:iq + n], y[iqd:iqd + n])
    J[:] = 0.0
    for i in range(n):
        J[iq + i, iqd + i] = 1.0
    J[iqd:iqd + n, iq:iq + n] = -np.linalg.solve(M, Rq)
    J[iqd:iqd + n, iqd:iqd + n] = -np.linalg.solve(M, Rqd)


_steps = ode.steppers(_rhs, _jac)
_radau_start, _radau_step = _steps.radau_start, _steps.radau_step  # globals numba types (not the namespace)


@jit
def solve(mdl, tab, y0, t_eval, rtol, atol):
    """Radau IIA from (t_eval[0], y0) over t_eval (k,), steps as long as the error control allows (the outputs
    come from the collocation polynomial, not from steps to each output time); returns (Y (k, n) the dense
    output at t_eval, accepted steps, rhs evaluations, status of :mod:`symmech.numerics.ode`)."""
    n, t_end = y0.size, t_eval[-1]
    Y = np.full((t_eval.size, n), np.nan)
    calls = np.zeros(1)
    args = (mdl, tab, calls)
    t, y, f = t_eval[0], y0.copy(), np.empty(n)
    _rhs(t, y, args, f)
    Y[0] = y
    k = 1
    J, LUr, pr, LUc, pc, Q = radau.radau_buffers(n)
    st = _radau_start(t, y, f, t_end, args, rtol, atol, J)
    for step in range(MAX_STEPS):
        if not t < t_end:
            return Y, step, int(calls[0]), ode.SUCCESS
        t_new, y_new, f_new, ok = _radau_step(t, y, f, t_end, args, rtol, atol, st, J, LUr, pr, LUc, pc, Q)
        if not ok:
            return Y, step, int(calls[0]), ode.STEP_TOO_SMALL
        k = radau.radau_dense_until(Y, k, t_eval, t_new, t, t_new - t, Q)
        t, y, f = t_new, y_new, f_new
    return Y, MAX_STEPS, int(calls[0]), ode.TOO_MANY_STEPS


@jit
def rows(mdl, chs, nu, height, Y):
    """Per output row (channels chs (k, 12) of the exact frame, upward unit vectors nu (k, 3), heights of O
    (k,) [m], states Y (k, layout.STATE)): q̈ (k, N), the resultants F, M_O (k, 3), the coefficient vectors of r̃,
    its rate and acceleration (k, F), and the Jacobi and total energies less the potential Π (k,) [J]
    (System.jacobi_energy, System.total_energy)."""
    flags, S1, Gtr = mdl.flags, mdl.s1, mdl.gram_trace
    n, f, mass, g0 = int(flags[F_AT.n]), int(flags[F_AT.f]), flags[F_AT.mass], flags[F_AT.g0]
    iq, iqd = mdl.state_at[Y_AT.q], mdl.state_at[Y_AT.qd]
    k = Y.shape[0]
    qdd_out, F_out, M_out = np.empty((k, n)), np.empty((k, 3)), np.empty((k, 3))
    rr_out, v_out, acc_out = np.empty((k, f)), np.empty((k, f)), np.empty((k, f))
    h_out, E_out = np.empty(k), np.empty(k)
    for i in range(k):
        ch = chs[i]
        q, qd = Y[i, iq:iq + n], Y[i, iqd:iqd + n]
        qdd, M, rr, v, p2, X, B, W, z = _accelerations(mdl, ch, q, qd)
        acc = _times_a(mdl, qdd, q) + p2
        F_out[i], M_out[i] = _resultants(mdl, ch, rr, v, acc, X, B, W)
        qdd_out[i], rr_out[i], v_out[i], acc_out[i] = qdd, rr, v, acc
        Jr, Jv = (rr @ X).reshape(3, 3).T, (v @ X).reshape(3, 3).T
        w, v0 = ch[CH_AT.omega:CH_AT.omega + 3].copy(), ch[CH_AT.v0:CH_AT.v0 + 3].copy()
        first = rr @ S1
        t2 = v @ Gtr @ v
        t0 = 0.5 * (mass * v0 @ v0 + 2.0 * v0 @ np.cross(w, first) + np.sum((W.T @ W) * Jr))
        h_out[i] = 0.5 * t2 - t0 + g0 * nu[i] @ first
        twice_t = mass * v0 @ v0 + 2.0 * v0 @ (np.cross(w, first) + v @ S1) + np.sum((W.T @ W) * Jr) + \
            2.0 * np.sum(W.T * Jv) + t2
        E_out[i] = 0.5 * twice_t + g0 * (mass * height[i] + nu[i] @ first)
    return qdd_out, F_out, M_out, rr_out, v_out, acc_out, h_out, E_out


# --------------------------------------------------------------------------- traction (s and V0 are states)

TRACTIONS: dict = {}  # key -> P0(t, V0) [N] of the runs under way (compiled.simulate registers them)


def traction_force(key, t, v):
    """P0 [N] and ∂P0/∂V0 [N s/m] of the registered traction ``key`` at t [s], V0 [m/s]: the slope by central
    differences (the user's expression is Python; step 1e-6 (1 + |V0|): ~1e-10 of its scale)."""
    p0 = TRACTIONS[key]
    h = 1e-6 * (1.0 + abs(v))
    return float(p0(t, v)), float(p0(t, v + h) - p0(t, v - h)) / (2.0 * h)


@with_gil  # the callback holds the GIL
def _force(key, t, v):
    with numba.objmode(p="float64", dp="float64"):  # a Python call per stage (~2 µs)
        p, dp = traction_force(key, t, v)
    return p, dp


@jit
def _geometry(tab, s, g, dg):
    """The 15 geometry channels g and their s-derivatives dg at s [m] from the spline table tab."""
    sk, c = tab
    i = np.searchsorted(sk, s, side="right") - 1
    i = min(max(i, 0), sk.size - 2)
    x = s - sk[i]
    for j in range(N_GEOMETRY):
        g[j] = ((c[0, i, j] * x + c[1, i, j]) * x + c[2, i, j]) * x + c[3, i, j]
        dg[j] = (3.0 * c[0, i, j] * x + 2.0 * c[1, i, j]) * x + c[2, i, j]


@jit
def _motion(g, V, dV, g0):
    """The 12 frame channels (load, ω, ω̇, v0) at speed V [m/s] and rate dV [m/s²] from geometry g (15,)."""
    ch = np.empty(N_CHANNELS)
    for i in range(3):
        ch[CH_AT.load + i] = dV * g[G_AT.e + i] + V * V * g[G_AT.k + i] + g0 * g[G_AT.nu + i]
        ch[CH_AT.omega + i] = V * g[G_AT.om + i]
        ch[CH_AT.domega + i] = dV * g[G_AT.om + i] + V * V * g[G_AT.dom + i]
        ch[CH_AT.v0 + i] = V * g[G_AT.e + i]
    return ch


@jit
def _traction_terms(mdl, g, q, qd, V, p0):
    """q̈ (N,), V̇0 and the terms of :func:`_terms` at the frame of that V̇0, from M q̈ + b V̇0 = -R0 and
    c·q̈ + d V̇0 = P0 - F1 (elastic.Timeline.traction_step; b = ∂R/∂V̇0, c, d those of the x1 resultant F1)."""
    flags, S1, at = mdl.flags, mdl.s1, mdl.unknowns_at
    n, iqdd, idv = q.size, at[U_AT.qdd], at[U_AT.dspeed]  # L's rows and columns: the unknowns q̈, V̇0
    ch0 = _motion(g, V, 0.0, flags[F_AT.g0])
    R0, M, rr, v, p2, X, B, W, z = _terms(mdl, ch0, q, qd)
    dch = np.zeros(N_CHANNELS)  # ∂B/∂V̇0 = skew(Ω): the channels with ω̇ = Ω, nothing else
    dch[CH_AT.domega:CH_AT.domega + 3] = g[G_AT.om:G_AT.om + 3]
    dB, _ = _frame_mats(dch)
    e = g[G_AT.e:G_AT.e + 3].copy()
    L = np.empty((at[U_AT.dspeed + 1], at[U_AT.dspeed + 1]))
    L[iqdd:iqdd + n, iqdd:iqdd + n] = M
    L[iqdd:iqdd + n, idv] = _a_times(mdl, q, S1 @ e + X @ dB.copy().reshape(9))
    L[idv, iqdd:iqdd + n] = _a_rows(mdl, q, S1)[:, 0]
    L[idv, idv] = flags[F_AT.mass] * e[0] + (dB @ (rr @ S1))[0]
    F0 = _resultants(mdl, ch0, rr, v, p2, X, B, W)[0][0]
    rhs = np.empty(at[U_AT.dspeed + 1])
    rhs[iqdd:iqdd + n] = -R0
    rhs[idv] = p0 - F0
    x = np.linalg.solve(L, rhs)
    return x[iqdd:iqdd + n], x[idv], L


@jit
def _rhs_traction(t, y, args, out):
    """y' of the state y (layout.TRACTION_STATE); args = (model record, geometry table, calls (1,), traction key)."""
    mdl, tab, calls, key = args
    calls[0] += 1.0
    at = mdl.state_at
    iq, iqd, n = at[Y_AT.q], at[Y_AT.qd], int(mdl.flags[F_AT.n])
    g, dg = np.empty(N_GEOMETRY), np.empty(N_GEOMETRY)
    _geometry(tab, y[at[Y_AT.s]], g, dg)
    q, qd, V = y[iq:iq + n], y[iqd:iqd + n], y[at[Y_AT.speed]]
    qdd, dV, _ = _traction_terms(mdl, g, q, qd, V, _force(key, t, V)[0])
    ch = _motion(g, V, dV, mdl.flags[F_AT.g0])
    _, _, rr, v, p2, X, B, W, _ = _terms(mdl, ch, q, qd)
    F, moment = _resultants(mdl, ch, rr, v, _times_a(mdl, qdd, q) + p2, X, B, W)
    out[iq:iq + n] = qd
    out[iqd:iqd + n] = qdd
    out[at[Y_AT.dissipated]] = _dissipation(mdl, qd)
    out[at[Y_AT.work]] = F @ ch[CH_AT.v0:CH_AT.v0 + 3] + moment @ ch[CH_AT.omega:CH_AT.omega + 3]
    out[at[Y_AT.s]] = V
    out[at[Y_AT.speed]] = dV


@jit
def _frame_rates(g, dg, V, dV, g0, W, theta):
    """∂(load, B, W)/∂θ at q̈, V̇0 fixed (W = skew(ω) of the state), θ = 0 the arc length s, 1 the speed V0:
    (3,), (3, 3), (3, 3)."""
    Om, dOm = g[G_AT.om:G_AT.om + 3].copy(), g[G_AT.dom:G_AT.dom + 3].copy()
    if theta == 0:
        dload = dV * dg[G_AT.e:G_AT.e + 3] + V * V * dg[G_AT.k:G_AT.k + 3] + g0 * dg[G_AT.nu:G_AT.nu + 3]
        dw, ddw = V * dOm, dV * dOm + V * V * dg[G_AT.dom:G_AT.dom + 3]
    else:
        dload, dw, ddw = 2.0 * V * g[G_AT.k:G_AT.k + 3], Om, 2.0 * V * dOm
    rates = np.zeros(N_CHANNELS)
    rates[CH_AT.omega:CH_AT.omega + 3], rates[CH_AT.domega:CH_AT.domega + 3] = dw, ddw
    dB, dW = _frame_mats(rates)
    return dload, dB - dW @ dW + dW @ W + W @ dW, dW  # ∂B = skew(∂ω̇) + ∂(skew(ω)²)


@jit
def _jac_traction(t, y, args, J):
    """dy'/dy of the state (layout.TRACTION_STATE) by the state: q̈ and V̇0 are x = L⁻¹ r
    (:func:`_traction_terms`; rows of layout.TRACTION_UNKNOWNS), so ∂x/∂y = -L⁻¹ ∂G/∂y with G = [R; F1 - P0] at
    the state's q̈, V̇0 (columns of layout.TRACTION_COLUMNS: q, q̇ as :func:`_jacobians`; s, V0 through the
    frame's channels, ∂/∂s by the spline's derivative); the rows of E_d and W zero, as :func:`_jac`'s."""
    mdl, tab, _, key = args
    flags, S1, Gx, at, un, co = mdl.flags, mdl.s1, mdl.gram_x, mdl.state_at, mdl.unknowns_at, mdl.columns_at
    n, mass, g0 = int(flags[F_AT.n]), flags[F_AT.mass], flags[F_AT.g0]
    iq, iqd, i_s, iv = at[Y_AT.q], at[Y_AT.qd], at[Y_AT.s], at[Y_AT.speed]
    uqdd, udv = un[U_AT.qdd], un[U_AT.dspeed]
    cq, cqd, cs, cv = co[CO_AT.q], co[CO_AT.qd], co[CO_AT.s], co[CO_AT.speed]
    g, dg = np.empty(N_GEOMETRY), np.empty(N_GEOMETRY)
    _geometry(tab, y[i_s], g, dg)
    q, qd, V = y[iq:iq + n], y[iqd:iqd + n], y[iv]
    p0, dp0 = _force(key, t, V)
    qdd, dV, L = _traction_terms(mdl, g, q, qd, V, p0)
    ch = _motion(g, V, dV, g0)
    _, Rq, Rqd = _jacobians(mdl, ch, q, qd)
    _, _, rr, v, _, X, B, W, _ = _terms(mdl, ch, q, qd)
    Yv = _gram_pass(Gx, v)
    AS, first, fv = _a_rows(mdl, q, S1), rr @ S1, v @ S1
    phi = mdl.fields_at[FC_AT.phi]
    psi = lambda x: _a_rows(mdl, x, S1) - S1[phi:phi + n]  # noqa: E731  DV(x) S1
    G = np.zeros((un[U_AT.dspeed + 1], co[CO_AT.speed + 1]))
    G[uqdd:uqdd + n, cq:cq + n], G[uqdd:uqdd + n, cqd:cqd + n] = Rq, Rqd
    G[udv, cq:cq + n] = (AS @ B.T + 2.0 * psi(qd) @ W.T + psi(qdd))[:, 0]
    G[udv, cqd:cqd + n] = (2.0 * AS @ W.T + 2.0 * psi(qd))[:, 0]
    for theta, column in ((0, cs), (1, cv)):
        dload, dB, dW = _frame_rates(g, dg, V, dV, g0, W, theta)
        z = S1 @ dload + X @ dB.copy().reshape(9) + 2.0 * (Yv @ dW.copy().reshape(9))
        G[uqdd:uqdd + n, column] = _a_times(mdl, q, z)
        G[udv, column] = (mass * dload + dB @ first + 2.0 * dW @ fv)[0]
    G[udv, cv] -= dp0
    dx = -np.linalg.solve(L, G)
    J[:] = 0.0
    for i in range(n):
        J[iq + i, iqd + i] = 1.0
    J[i_s, iv] = 1.0
    # the rows of q̇ and V0 are those of q̈ and V̇0 in dx
    J[iqd:iqd + n, iq:iq + n] = dx[uqdd:uqdd + n, cq:cq + n]
    J[iqd:iqd + n, iqd:iqd + n] = dx[uqdd:uqdd + n, cqd:cqd + n]
    J[iv, iq:iq + n], J[iv, iqd:iqd + n] = dx[udv, cq:cq + n], dx[udv, cqd:cqd + n]
    J[iqd:iqd + n, i_s], J[iqd:iqd + n, iv] = dx[uqdd:uqdd + n, cs], dx[uqdd:uqdd + n, cv]
    J[iv, i_s], J[iv, iv] = dx[udv, cs], dx[udv, cv]


_tsteps = ode.steppers(_rhs_traction, _jac_traction)
_traction_start, _traction_step = _tsteps.radau_start, _tsteps.radau_step


@jit
def solve_traction(mdl, tab, key, y0, t_eval, rtol, atol, max_step):
    """:func:`solve` with traction (y = [q, q̇, E_d, W, s, V0], geometry table in s, traction ``key``); returns
    also V̇0 (k,) at t_eval [m/s²]."""
    n, t_end = y0.size, t_eval[-1]
    Y = np.full((t_eval.size, n), np.nan)
    calls = np.zeros(1)
    args = (mdl, tab, calls, key)
    t, y, f = t_eval[0], y0.copy(), np.empty(n)
    _rhs_traction(t, y, args, f)
    Y[0] = y
    k = 1
    J, LUr, pr, LUc, pc, Q = radau.radau_buffers(n)
    st = _traction_start(t, y, f, t_end, args, rtol, atol, J)
    status, steps = ode.TOO_MANY_STEPS, MAX_STEPS
    for step in range(MAX_STEPS):
        if not t < t_end:
            status, steps = ode.SUCCESS, step
            break
        if st[radau.ST_AT.h] > max_step:
            st[radau.ST_AT.h], st[radau.ST_AT.h_old], st[radau.ST_AT.err_old] = max_step, -1.0, -1.0
        t_new, y_new, f_new, ok = _traction_step(t, y, f, t_end, args, rtol, atol, st, J, LUr, pr, LUc, pc, Q)
        if not ok:
            status, steps = ode.STEP_TOO_SMALL, step
            break
        k = radau.radau_dense_until(Y, k, t_eval, t_new, t, t_new - t, Q)
        t, y, f = t_new, y_new, f_new
    nfev = int(calls[0])
    dV = np.full(t_eval.size, np.nan)
    for i in range(k):
        _rhs_traction(t_eval[i], Y[i], args, f)
        dV[i] = f[mdl.state_at[Y_AT.speed]]
    return Y, dV, steps, nfev, status
