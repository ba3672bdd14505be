"""The scene's impact law at the lowest point, in numba (``ImpactLaw.apply`` for one grain): the
Chatterjee-Ruina law, and the printed law by its exact reduction (the trigonometric equation of
``mu_equation``, the roots of its quartic, the companion matrix's eigenvalues, by Durand-Kerner, polished by
Newton), for the law itself or for its verdict in the log (an impact row, layout :data:`layouts.IMPACT_ROW`)."""
from __future__ import annotations

import math

import numpy as np

from symmech.numerics import kernels
from symmech.numerics.jit import inline, jit
from symmech.grain.motion_engine.kinematics import (
    EPS, contact_offset_xyz, cross_xyz, dot3, inertia_solve, inverse_effective_mass, kinetic, rotation, turn,
    turn_back)
from symmech.grain.motion_engine.layouts import (
    I_AT, IMPACT_WIDTH, LAW_PRINTED, P_AT, W_ENERGY, W_PRINTED_ENERGY, W_PRINTED_PULLS, W_PRINTED_RESIDUAL, X_AT)
from symmech.grain.motion_engine.rows import warn

gi = kernels.load("grain_impact")


@jit
def _coulomb_impulse(K, u, e_n, e_t, mu):
    """Chatterjee-Ruina impulse (P_x, P_y, P_z) [N s] (``coulomb_law.coulomb_impulse`` for one grain) of the
    symmetric K's 6 entries (:func:`kinematics.inverse_effective_mass`) [1/kg] and u (3 floats) [m/s]: K u' = u by
    the generated Cramer formulas, no LAPACK."""
    pi_z = -u[2] / K[5]
    s = _solve_symmetric(K, u)
    return _bounded_impulse(pi_z, -s[0] - 0.0, -s[1] - 0.0, -s[2] - pi_z, e_n, e_t, mu)


@jit
def _solve_symmetric(K, b):
    """x of K x = b, K symmetric given by (K_xx, K_xy, K_xz, K_yy, K_yz, K_zz): the generated Cramer formulas
    (``cramer_solution``, written for the Euler rates, a general 3 x 3 system)."""
    x = gi.cramer_solution_scalar(K[0], K[1], K[2], K[1], K[3], K[4], K[2], K[4], K[5], b[0], b[1], b[2])
    return x[0], x[1], x[2]


@jit
def _point_impulse(u, k, e_n, e_t, mu):
    """``_coulomb_impulse`` of a point mass (K = k times the identity, k = 1/m [1/kg]) in scalars, the same
    operations element by element: (P_x, P_y, P_z) [N s]."""
    pi_z = -u[2] / k
    return _bounded_impulse(pi_z, -u[0] / k - 0.0, -u[1] / k - 0.0, -u[2] / k - pi_z, e_n, e_t, mu)


@jit
def _bounded_impulse(pi_z, d_x, d_y, d_z, e_n, e_t, mu):
    """The law from the frictionless plastic normal impulse pi_z and D = sticking plastic minus it [N s]:
    (1 + e_n) P_I + (1 + e_t) D, pulled back onto the friction cone (mu) if outside; 3 floats [N s]."""
    p_x, p_y = (1.0 + e_n) * 0.0 + (1.0 + e_t) * d_x, (1.0 + e_n) * 0.0 + (1.0 + e_t) * d_y
    p_z = (1.0 + e_n) * pi_z + (1.0 + e_t) * d_z
    p_t = math.hypot(p_x, p_y)
    outside = p_t / mu > p_z if mu > 0 else p_t > 0
    if outside:
        kappa = (1.0 + e_n) * pi_z / (math.hypot(d_x, d_y) / mu - d_z)
        return (1.0 + e_n) * 0.0 + kappa * d_x, (1.0 + e_n) * 0.0 + kappa * d_y, (1.0 + e_n) * pi_z + kappa * d_z
    return p_x, p_y, p_z


@jit
def quartic_roots(c1, c2, c3, c4):
    """The four complex roots of t^4 + c1 t^3 + c2 t^2 + c3 t + c4 by the Durand-Kerner (Weierstrass) iteration in
    complex scalars: the eigenvalues of the quartic's companion matrix (what ``impact._trig_roots`` takes from
    LAPACK) at a tenth of the cost and with no arrays. Corrections below 8 eps relative end it; a multiple root
    converges linearly, to ~sqrt(eps) as an eigensolver's, within the 100 sweeps. Returns a tuple of 4 complex."""
    bound = 1.0 + max(abs(c1), abs(c2), abs(c3), abs(c4))  # Cauchy's: every root inside
    seed = complex(0.4, 0.9)  # neither real nor a root of unity: no symmetric stall
    z0, z1, z2, z3 = bound * seed, bound * seed ** 2, bound * seed ** 3, bound * seed ** 4
    for _ in range(100):
        d0 = _quartic(z0, c1, c2, c3, c4) / ((z0 - z1) * (z0 - z2) * (z0 - z3))
        z0 -= d0
        d1 = _quartic(z1, c1, c2, c3, c4) / ((z1 - z0) * (z1 - z2) * (z1 - z3))
        z1 -= d1
        d2 = _quartic(z2, c1, c2, c3, c4) / ((z2 - z0) * (z2 - z1) * (z2 - z3))
        z2 -= d2
        d3 = _quartic(z3, c1, c2, c3, c4) / ((z3 - z0) * (z3 - z1) * (z3 - z2))
        z3 -= d3
        if (abs(d0) <= 8 * EPS * abs(z0) and abs(d1) <= 8 * EPS * abs(z1) and abs(d2) <= 8 * EPS * abs(z2)
                and abs(d3) <= 8 * EPS * abs(z3)):
            break
    return z0, z1, z2, z3


@jit
def _quartic(z, c1, c2, c3, c4):
    return (((z + c1) * z + c2) * z + c3) * z + c4


@jit
def _trig_roots(k, tol, max_iter):
    """Real roots (4,) (NaN unused) of k0 + k1c cos + k1s sin + k2c cos2 + k2s sin2 (``_trig_roots`` of
    :mod:`symmech.grain.impact`)."""
    k0, k1c, k1s, k2c, k2s = k[0], k[1], k[2], k[3], k[4]
    best, delta = -1.0, 0.0
    for i in range(5):
        s = i * (2 * math.pi / 5)
        m = s + math.pi
        val = abs(k0 + k1c * math.cos(m) + k1s * math.sin(m) + k2c * math.cos(2 * m) + k2s * math.sin(2 * m))
        if val > best:
            best, delta = val, s
    c1, s1, c2, s2 = math.cos(delta), math.sin(delta), math.cos(2 * delta), math.sin(2 * delta)
    a1c, a1s = k1c * c1 + k1s * s1, -k1c * s1 + k1s * c1
    a2c, a2s = k2c * c2 + k2s * s2, -k2c * s2 + k2s * c2
    lead = k0 - a1c + a2c
    roots = np.full(4, np.nan)
    if abs(lead) > 0:
        t = quartic_roots((2 * a1s - 4 * a2s) / lead, (2 * k0 - 6 * a2c) / lead, (2 * a1s + 4 * a2s) / lead,
                          (k0 + a1c + a2c) / lead)
        for j in range(4):
            if abs(t[j].imag) <= 1e-6 * (1.0 + abs(t[j].real)):
                roots[j] = delta + 2 * math.atan(t[j].real)
    for _ in range(max_iter):
        big = False
        for j in range(4):
            r = roots[j]
            if math.isnan(r):
                continue
            f = k0 + k1c * math.cos(r) + k1s * math.sin(r) + k2c * math.cos(2 * r) + k2s * math.sin(2 * r)
            d = (-k1c * math.sin(r) + k1s * math.cos(r) - 2 * k2c * math.sin(2 * r) + 2 * k2s * math.cos(2 * r))
            step = 0.0 if d == 0 else f / d
            roots[j] = r - min(0.5, max(-0.5, step))
            big = big or abs(step) > tol
        if not big:
            break
    scale = abs(k0) + abs(k1c) + abs(k1s) + abs(k2c) + abs(k2s)
    for j in range(4):
        r = roots[j]
        f = k0 + k1c * math.cos(r) + k1s * math.sin(r) + k2c * math.cos(2 * r) + k2s * math.sin(2 * r)
        if abs(f) > 1e-9 * scale:
            roots[j] = np.nan
        else:
            roots[j] = (r + math.pi) % (2 * math.pi) - math.pi
    roots = np.sort(roots)  # NaN last
    keep = roots.copy()
    for j in range(1, 4):
        if roots[j] - roots[j - 1] < 1e-7:  # a double root: two nearly equal eigenvalues
            keep[j] = np.nan
    count = 0
    for j in range(4):
        count += 0 if math.isnan(keep[j]) else 1
    if count > 1:
        last = keep[count - 1]
        if abs((last - keep[0] + math.pi) % (2 * math.pi) - math.pi) < 1e-7:
            keep[count - 1] = np.nan
    return keep


@jit
def _prescribed(u, e, lam, mu):
    """The printed law's contact velocity after [m/s] at slip angle mu [rad], 3 floats."""
    speed = (1.0 - lam) * math.hypot(u[0], u[1])
    return speed * math.cos(mu), speed * math.sin(mu), -e * u[2]


@inline
def printed_impulse(H, m, e, lam, u):
    """The printed law solved exactly for one impact (``impact.solve_robust_batch``) of H = m K [1] by its upper
    triangle (H_xx, H_xy, H_xz, H_yy, H_yz, H_zz), mass m [kg], u (3 floats or (3,)) [m/s]:
    (T (3 floats) [N s], residual of (19), admissible, creates energy, pulls)."""
    k = gi.mu_equation_scalar(H[0], H[1], H[2], H[3], H[4], H[5], lam, e, u[0], u[1], u[2])
    norm_u = math.sqrt(dot3(u, u))
    stuck = abs(1.0 - lam) * math.hypot(u[0], u[1]) <= 1e-14 * norm_u  # lam > 1 reverses: its size says stuck
    roots = np.full(4, np.nan)
    if stuck:
        roots[0] = 0.0
    else:
        roots = _trig_roots(k, 1e-14, 12)
    ke_scale = 0.5 * m * dot3(u, u)
    Ts = np.zeros((4, 3))
    score = np.full(4, np.inf)
    gains = np.zeros(4, dtype=np.bool_)
    pulls = np.zeros(4, dtype=np.bool_)
    big = 0.0
    for j in range(4):
        if j > 0 and math.isnan(roots[j]):
            continue  # an unused slot: never chosen (slot 0's T, at mu = 0, stands when no root is found)
        mu = 0.0 if math.isnan(roots[j]) else roots[j]
        u_next = _prescribed(u, e, lam, mu)
        du = (u_next[0] - u[0], u_next[1] - u[1], u_next[2] - u[2])
        x = _solve_symmetric(H, du)
        T = (m * x[0], m * x[1], m * x[2])
        Ts[j, 0], Ts[j, 1], Ts[j, 2] = T
        gains[j] = 0.5 * dot3(T, (2 * u[0] + du[0], 2 * u[1] + du[1], 2 * u[2] + du[2])) > 1e-9 * ke_scale
        pulls[j] = T[2] < -1e-12 * math.sqrt(dot3(T, T))
        if not math.isnan(roots[j]):
            big = max(big, math.hypot(T[0], T[1]))
    big = 10.0 * big + 1.0
    choice, found = 0, False
    for j in range(4):
        if not math.isnan(roots[j]):
            found = True
            rank = 2.0 if pulls[j] else (1.0 if gains[j] else 0.0)
            score[j] = rank * big + math.hypot(Ts[j, 0], Ts[j, 1])
            if score[j] < score[choice]:
                choice = j
    T = (Ts[choice, 0], Ts[choice, 1], Ts[choice, 2]) if found else (np.nan, np.nan, np.nan)
    mu = roots[choice]
    if stuck:
        mu = math.atan2(T[1], T[0]) if math.hypot(T[0], T[1]) > 0 else 0.0
    d0, d1 = math.cos(mu), math.sin(mu)
    tau = T[0] * d0 + T[1] * d1
    r = _residual_19(H, (tau * d0, tau * d1, T[2]), m, u, _prescribed(u, e, lam, mu))
    residual = (math.sqrt(dot3(r, r)) + abs(T[1] * d0 - T[0] * d1)) / (m * norm_u)
    bad_gain, bad_pull = gains[choice], pulls[choice]
    return T, residual, found and not (bad_gain or bad_pull), bad_gain, bad_pull


@jit
def _residual_19(H, T, m, u, u_next):
    """H T - m (u_next - u) [N s], 3 floats: H by its 6 entries, symmetric; u_next the printed law's velocity after."""
    return (H[0] * T[0] + H[1] * T[1] + H[2] * T[2] - m * (u_next[0] - u[0]),
            H[1] * T[0] + H[3] * T[1] + H[4] * T[2] - m * (u_next[1] - u[1]),
            H[2] * T[0] + H[4] * T[1] + H[5] * T[2] - m * (u_next[2] - u[2]))


@inline
def impact(p, y, warns, carry):
    """The scene's impact law at the lowest point (``ImpactLaw.apply`` for one grain):
    (state after, log row (IMPACT_WIDTH,) without t and r, warns). Vectors as 3 floats, K as its 6 entries: no
    BLAS or LAPACK call; the arrays are Q, the state after and the log (and the printed law's few)."""
    if p[P_AT.rotation] == 0.0:
        return _point_mass_impact(p, y, warns, carry)
    Q = rotation(y[X_AT.q:X_AT.q + 4])
    m = p[P_AT.mass]
    R = contact_offset_xyz(p, Q)
    v = (y[X_AT.v], y[X_AT.v + 1], y[X_AT.v + 2])
    w = turn(Q, y[X_AT.w:X_AT.w + 3])
    u = _plus(v, cross_xyz(w, R))
    K = inverse_effective_mass(p, Q, R)
    printed = p[P_AT.law] == LAW_PRINTED
    p_adm = p_gain = -1.0
    converged = 1.0
    P = (0.0, 0.0, 0.0)
    if u[2] < 0.0:
        if printed or p[P_AT.check_printed] != 0.0:
            e, lam = (p[P_AT.e], p[P_AT.lam]) if printed else (p[P_AT.e_n], 1.0 + p[P_AT.e_t])
            T, residual, adm, gain, pull = printed_impulse((m * K[0], m * K[1], m * K[2], m * K[3], m * K[4], m * K[5]), m, e, lam, u)
            p_adm, p_gain = (1.0 if adm else 0.0), (1.0 if gain else 0.0)
            if printed:
                if not adm:
                    warns = warn(warns, carry, W_PRINTED_ENERGY if gain else W_PRINTED_PULLS, 0.0, 0.0)
                converged = 1.0 if residual < 1e-8 else 0.0
                if not residual < 1e-8:
                    warns = warn(warns, carry, W_PRINTED_RESIDUAL, residual, 0.0)
                P = T
        if not printed:
            P = _coulomb_impulse(K, u, p[P_AT.e_n], p[P_AT.e_t], p[P_AT.mu_impact])
    v_after = (v[0] + P[0] / m, v[1] + P[1] / m, v[2] + P[2] / m)
    w_after = _plus(w, inertia_solve(p, Q, cross_xyz(R, P)))
    ke_before, ke_after = kinetic(p, Q, v, w), kinetic(p, Q, v_after, w_after)
    admissible, warns = _booked(ke_before, ke_after, warns, carry)
    after = y.copy()
    _put(after, X_AT.v, v_after)
    w_body = turn_back(Q, w_after)
    _put(after, X_AT.w, w_body)
    log = np.empty(IMPACT_WIDTH)
    _put(log, I_AT.w_after, w_body)
    _put(log, I_AT.impulse, P)
    _put(log, I_AT.u_before, u)
    _put(log, I_AT.u_after, _plus(v_after, cross_xyz(w_after, R)))
    _log_common(log, y, v, v_after, ke_before, ke_after, admissible, p_adm, p_gain, converged)
    return after, log, warns


@jit
def _plus(a, b):
    """a + b of two 3-vectors (floats or (3,)), 3 floats."""
    return a[0] + b[0], a[1] + b[1], a[2] + b[2]


@jit
def _put(vec, at, a):
    """vec[at:at + 3] = a (3 floats or (3,)); at: a layout's offset, from the caller."""
    vec[at], vec[at + 1], vec[at + 2] = a[0], a[1], a[2]


@inline
def _point_mass_impact(p, y, warns, carry):
    """``impact`` of a grain that does not rotate (a point mass: no spin, u = v, K = 1/m), its Coulomb impulse in
    scalars (:func:`_point_impulse`); the printed law of such a grain is its Coulomb reduction (e, lam - 1, no
    bound), as ``ImpactLaw.apply``. No rotation matrix, no LAPACK; the arrays are the state after and the log."""
    m = p[P_AT.mass]
    v = (y[X_AT.v], y[X_AT.v + 1], y[X_AT.v + 2])
    u = (v[0] + 0.0, v[1] + 0.0, v[2] + 0.0)  # v + w x R with w = 0, as the rotating grain's
    P = (0.0, 0.0, 0.0)
    if u[2] < 0.0:
        k = 1.0 / m
        if p[P_AT.law] == LAW_PRINTED:
            P = _point_impulse(u, k, p[P_AT.e], p[P_AT.lam] - 1.0, np.inf)
        else:
            P = _point_impulse(u, k, p[P_AT.e_n], p[P_AT.e_t], p[P_AT.mu_impact])
    v_after = (v[0] + P[0] / m, v[1] + P[1] / m, v[2] + P[2] / m)
    ke_before, ke_after = 0.5 * m * dot3(v, v), 0.5 * m * dot3(v_after, v_after)  # kinetic() without spin
    admissible, warns = _booked(ke_before, ke_after, warns, carry)
    after = y.copy()
    _put(after, X_AT.v, v_after)
    _put(after, X_AT.w, (0.0, 0.0, 0.0))
    log = np.empty(IMPACT_WIDTH)
    _put(log, I_AT.w_after, (0.0, 0.0, 0.0))
    _put(log, I_AT.impulse, P)
    _put(log, I_AT.u_before, u)
    _put(log, I_AT.u_after, (v_after[0] + 0.0, v_after[1] + 0.0, v_after[2] + 0.0))
    _log_common(log, y, v, v_after, ke_before, ke_after, admissible, -1.0, -1.0, 1.0)
    return after, log, warns


@jit
def _booked(ke_before, ke_after, warns, carry):
    """Whether an impact created no energy (to 1e-9 relative), and the warning row if it did: (admissible, warns)."""
    admissible = ke_after <= ke_before * (1.0 + 1e-9)
    if not admissible:
        warns = warn(warns, carry, W_ENERGY, ke_before, ke_after)
    return admissible, warns


@jit
def _log_common(log, y, v, v_after, ke_before, ke_after, admissible, p_adm, p_gain, converged):
    """The parts of an impact row that both grains fill alike: velocities, spin before, energies and flags."""
    _put(log, I_AT.v_before, v)
    _put(log, I_AT.v_after, v_after)
    _put(log, I_AT.w_before, y[X_AT.w:X_AT.w + 3])
    log[I_AT.ke_before], log[I_AT.ke_after], log[I_AT.admissible] = ke_before, ke_after, 1.0 if admissible else 0.0
    log[I_AT.printed_admissible], log[I_AT.printed_creates_energy], log[I_AT.converged] = p_adm, p_gain, converged
