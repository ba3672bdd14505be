"""The compiled engine's loop in numba: the per-grain event loop of :mod:`symmech.grain.motion`.

The Python side (parameters, results, errors, the entry it calls) is :mod:`symmech.grain.compiled`,
which imports no numba: a warm run whose loop was built ahead of time loads that build instead of
this module. The physics, the event logic and their contract are described there."""
from __future__ import annotations

import math

import numpy as np

from symmech.numerics import kernels, ode
from symmech.numerics.jit import inline, jit
from symmech.grain import sliding
from symmech.grain.compiled_layout import (
    P_AT, C_AT, S_AT, I_AT, N_SLIDE, IMPACT_WIDTH, LAW_PRINTED, INT, FLIGHT, IMPACT, SLIDING, DONE, MORE, STALLED,
    SLIDE_STALLED, SLIDE_RHS, SLIDE_FAIL, ROT_FAIL, W_MAX_IMPACTS, W_CHATTER, W_PRINTED_ENERGY, W_PRINTED_PULLS,
    W_PRINTED_RESIDUAL, W_ENERGY, ZENO_IMPACTS, ZENO_INTERVAL, MAX_IDLE_STEPS, MAX_STALLED_EVENTS)

gm = kernels.load("grain_motion")
gi = kernels.load("grain_impact")

EPS = float(np.finfo(float).eps)
SCAN_WINDOW = 32
MAX_STEPS_PER_CHUNK = sliding.MAX_RHS_PER_PHASE // 12  # DOP853 steps (12 evaluations) per sliding chunk
ROT, SLIP, STICK = INT(0), INT(1), INT(2)  # right-hand sides of the Dormand-Prince stepper

DOP_STAGES, DOP_EXTENDED, DOP_POWER, DOP_EXPONENT = ode.DOP_STAGES, ode.DOP_EXTENDED, ode.DOP_POWER, ode.DOP_EXPONENT
ROT_WIDTH = 3 + 7 + 7 * 7  # rotation step table row: t_old, t_new, (unused), y_old (7), F (7 x 7)


# --------------------------------------------------------------------------- small algebra


@jit
def _cross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


@jit
def _rot(q):
    """Q (3, 3) of a quaternion, normalised here (generated ``rotation_matrix``)."""
    s = math.sqrt(q[0] ** 2 + q[1] ** 2 + q[2] ** 2 + q[3] ** 2)
    return gm.rotation_matrix_scalar(q[0] / s, q[1] / s, q[2] / s, q[3] / s)


@jit
def _offset(p, Q):
    """Contact offset R (3,) [m] of the lowest point, KXYZ (generated ``contact_offset_body``)."""
    body = gm.contact_offset_body_scalar(p[P_AT.axes], p[P_AT.axes + 1], p[P_AT.axes + 2], Q[2, 0], Q[2, 1], Q[2, 2])
    return Q @ body


@jit
def _support(p, Q):
    return gm.support_distance_scalar(p[P_AT.axes], p[P_AT.axes + 1], p[P_AT.axes + 2], Q[2, 0], Q[2, 1], Q[2, 2])


@jit
def _surface(p, t):
    """Rows displacement, velocity, acceleration (3, 3) of the surface at t."""
    d = P_AT.direction
    return gm.surface_kinematics_scalar(p[P_AT.amplitude], p[P_AT.omega], p[P_AT.phase], p[d], p[d + 1], p[d + 2], t)


@jit
def _normal(p, t):
    """Normal force per unit mass n(t) [m/s^2] of a grain on the plane."""
    return _surface(p, t)[2, 2] - p[P_AT.g + 2]


@jit
def _world_inv_inertia(p, Q):
    return Q @ np.diag(1.0 / p[P_AT.inertia:P_AT.inertia + 3]) @ Q.T


@jit
def _inverse_effective_mass(p, Q, R):
    """K (3, 3) [1/kg], as ``coulomb_law.inverse_effective_mass``; a point mass without rotation."""
    K = np.eye(3) / p[P_AT.mass]
    if p[P_AT.rotation] != 0.0:
        Rx = np.array([[0.0, -R[2], R[1]], [R[2], 0.0, -R[0]], [-R[1], R[0], 0.0]])
        K = K - Rx @ _world_inv_inertia(p, Q) @ Rx
    return K


@jit
def _kinetic(p, Q, v, w):
    """Kinetic energy [J]; v, w (3,) in KXYZ."""
    wb = Q.T @ w
    I = p[P_AT.inertia:P_AT.inertia + 3]
    return 0.5 * p[P_AT.mass] * (v @ v) + 0.5 * (I[0] * wb[0] ** 2 + I[1] * wb[1] ** 2 + I[2] * wb[2] ** 2)


@jit
def _is_sphere(p):
    a = P_AT.axes
    return max(p[a], p[a + 1], p[a + 2]) == min(p[a], p[a + 1], p[a + 2])


# --------------------------------------------------------------------------- right-hand sides (core.ode steppers)


@jit
def _rhs(t, y, args, out):
    """Right-hand side of the toolkit's steppers, args = (kind, data): ``ROT`` torque-free rotation y = (q, w
    body), data = the principal inertia (3,); ``SLIP``/``STICK`` sliding, data the sliding parameters (SLIDE)."""
    kind, data = args
    if kind == ROT:
        qd = gm.quaternion_rate_scalar(y[0], y[1], y[2], y[3], y[4], y[5], y[6])
        wd = gm.euler_equations_scalar(data[0], data[1], data[2], y[4], y[5], y[6])
        out[:4] = qd
        out[4:7] = wd
    else:
        _slide_rhs(t, y, data, kind == STICK, out)


@jit
def _jac(t, y, args, J):
    """Jacobian d rhs / d y (13, 13) into J of the slip (analytic), args = (kind, sp): the only stiff one."""
    _slip_jac(t, y, args[1], J)


# The generic DOP853, Radau IIA and Brent code of core.ode, compiled for these right-hand sides.
_steps = ode.steppers(_rhs, _jac)
_first_step, _dop_advance, _dop_dense = _steps.first_step, _steps.dop_advance, _steps.dop_dense
_radau_start, _radau_step = _steps.radau_start, _steps.radau_step
_dense, _radau_dense = ode.dop_dense_at, ode.radau_dense_at


# --------------------------------------------------------------------------- functions of time

GAP, NORMAL, EVENT = INT(0), INT(1), INT(2)  # what _h evaluates


@jit
def _orient(t, ctx, tab, ntab):
    """(q normalised (4,), w body (3,)) of the flight at t from the rotation step table ``tab`` (rows
    t_old, t_new, -, y_old (7), F (7 x 7)): the interpolant of the first step ending at or after t."""
    if ntab == 0:
        y = ctx[7:14].copy()
    else:
        lo, hi = 0, ntab - 1
        while lo < hi:
            mid = (lo + hi) // 2
            if tab[mid, 1] >= t:
                hi = mid
            else:
                lo = mid + 1
        row = tab[lo]
        y = _dense(t, row[0], row[1] - row[0], row[3:10], tab[lo, 10:])
    s = math.sqrt(y[0] ** 2 + y[1] ** 2 + y[2] ** 2 + y[3] ** 2)
    y[:4] /= s
    return y[:4], y[4:7]


@inline  # no call in the scan loop
def _translate_into(p, ctx, t, out):
    """Centre position and velocity rows out[0] (2, 3) at t of the flight from ctx = (t0, r0, v0, ...)."""
    tau = t - ctx[0]
    if p[P_AT.amplitude] == 0.0:
        gm.flight_translation_rigid_into(ctx[1], ctx[2], ctx[3], ctx[4], ctx[5], ctx[6],
                                       p[P_AT.g], p[P_AT.g + 1], p[P_AT.g + 2], 0.0, tau, out)
    else:
        d = P_AT.direction
        gm.flight_translation_into(ctx[1], ctx[2], ctx[3], ctx[4], ctx[5], ctx[6], p[P_AT.g], p[P_AT.g + 1],
                                   p[P_AT.g + 2], p[P_AT.amplitude], p[P_AT.omega], ctx[17], p[d], p[d + 1], p[d + 2],
                                   0.0, tau, out)


@jit
def _translate(p, ctx, t):
    """Centre position and velocity rows (2, 3) at t of the flight from ctx = (t0, r0, v0, ...)."""
    out = np.empty((1, 2, 3))
    _translate_into(p, ctx, t, out)
    return out[0]


@jit
def _still_gap(p, ctx, t, out):
    """The gap [m] of a flight without rotation (the support height is the one at its start); out (1, 2, 3)
    scratch: the scan reuses one, which halves the time of a sphere's scan."""
    _translate_into(p, ctx, t, out)
    return out[0, 0, 2] - ctx[28]


@jit
def _h(what, t, ctx, steps, nsteps, p, out):
    """GAP: height [m] of the lowest point in flight (out (1, 2, 3) scratch); NORMAL: n(t); EVENT: sliding
    event function."""
    if what == GAP:
        if ctx[18] == 0.0:
            return _still_gap(p, ctx, t, out)
        q, _ = _orient(t, ctx, steps, nsteps)
        _translate_into(p, ctx, t, out)
        return out[0, 0, 2] - _support(p, _rot(q))
    if what == NORMAL:
        return _normal(p, t)
    return _event(t, ctx, steps, p)


@jit
def _h_args(t, args):
    """``_h`` at t with args = (what, ctx, steps, nsteps, p, out): the function of the root finders."""
    what, ctx, steps, nsteps, p, out = args
    return _h(what, t, ctx, steps, nsteps, p, out)


_roots = ode.roots(_h_args)  # core.ode's Brent root finder and bounded minimiser of _h
_brentq, _bounded_min = _roots.brentq, _roots.bounded_min


@jit
def _first_root(what, t0, t1, step, xtol, ctx, steps, nsteps, p):
    """First time in (t0, t1] where h reaches zero from above, or NaN (``contact.first_root``, same scan)."""
    start = t0
    hs = np.empty(SCAN_WINDOW + 1)
    ts = np.empty(SCAN_WINDOW + 1)
    out = np.empty((1, 2, 3))
    # Without rotation the scan skips _extend (nothing to do) and calls the gap directly: 2/3 of a sphere's scan.
    rotating, still = what == GAP and ctx[18] != 0.0, what == GAP and ctx[18] == 0.0
    while True:
        n = 0
        for i in range(SCAN_WINDOW + 1):
            ti = min(start + step * i, t1)
            if n == 0 or ti > ts[n - 1]:
                ts[n] = ti
                n += 1
        stop = n
        for i in range(n):
            if rotating:  # the Python scan asks for the whole window at once
                steps, nsteps = _extend(ts[i], ts[n - 1], ctx, steps, nsteps, p)
            hs[i] = _still_gap(p, ctx, ts[i], out) if still else _h(what, ts[i], ctx, steps, nsteps, p, out)
            if i > 0 and hs[i] <= 0.0:
                stop = i
                break
        for j in range(1, min(stop, n - 1)):
            if hs[j] < hs[j - 1] and hs[j] <= hs[j + 1]:  # as contact.first_root: a minimum between equal samples
                x, fx = _bounded_min(ts[j - 1], ts[j + 1], xtol, (what, ctx, steps, nsteps, p, out))
                if fx < 0.0 and hs[j - 1] > 0.0:
                    return _brentq(ts[j - 1], x, xtol, (what, ctx, steps, nsteps, p, out)), steps, nsteps
        if stop < n:
            return _brentq(ts[stop - 1], ts[stop], xtol, (what, ctx, steps, nsteps, p, out)), steps, nsteps
        if ts[n - 1] >= t1:
            return np.nan, steps, nsteps
        start = ts[n - 2]


# --------------------------------------------------------------------------- flight


@jit
def _extend(t, t_request, ctx, tab, ntab, p):
    """Integrate the rotation of the flight ctx until it covers t; returns the grown step table and its length.

    ``flight.RotationFlight`` integrates in chunks, each a fresh DOP853 solve from its start to
    max(t_request, start + period), t_request being the latest time the Python loop asks for at once.
    The same chunks are solved here, but only as many of their steps as t needs: the step sequence, hence
    every value, is the Python one. Solver state in ctx: 29 chunk end, 30 step length, 31-37 f, 38 active;
    ctx[27] = 1 on failure."""
    if ctx[18] == 0.0:
        return tab, ntab
    tol = p[P_AT.tolerance]
    atol = np.full(7, tol * 1e-3)
    K = np.empty((DOP_EXTENDED, 7))
    inertia = ctx[14:17].copy()
    while ctx[19] < t:
        if ctx[38] == 0.0:  # a new chunk
            ctx[29] = max(t_request, ctx[19] + p[P_AT.period])
            f = np.empty(7)
            _rhs(ctx[19], ctx[20:27].copy(), (ROT, inertia), f)
            ctx[31:38] = f
            ctx[30] = _first_step(ctx[19], ctx[20:27].copy(), f, ctx[29], (ROT, inertia), tol, atol, -DOP_EXPONENT)
            ctx[38] = 1.0
        tt, y, f = ctx[19], ctx[20:27].copy(), ctx[31:38].copy()
        t_new, y_new, h_abs, ok = _dop_advance(tt, y, f, ctx[30], ctx[29], (ROT, inertia), tol, atol, K)
        if not ok:
            ctx[27] = 1.0
            return tab, ntab
        if ntab == tab.shape[0]:
            grown = np.empty((2 * ntab, ROT_WIDTH))
            grown[:ntab] = tab
            tab = grown
        tab[ntab, 0], tab[ntab, 1], tab[ntab, 2] = tt, t_new, 0.0
        tab[ntab, 3:10] = y
        tab[ntab, 10:] = _dop_dense(tt, t_new - tt, y, y_new, (ROT, inertia), K).reshape(DOP_POWER * 7)
        ntab += 1
        ctx[19], ctx[30] = t_new, h_abs
        ctx[20:27] = y_new
        ctx[31:38] = K[DOP_STAGES]
        if t_new >= ctx[29]:
            ctx[38] = 0.0
    return tab, ntab


@jit
def _flight_ctx(p, y):
    """Flight record: t0, r0 (3), v0 (3), q0, w0 (7), inertia (3), phase at t0, rotating, end of the rotation
    integration and its state (7), failure flag, support height at the start, rotation solver state (10)."""
    ctx = np.zeros(39)
    ctx[:14] = y
    ctx[19] = y[0]
    ctx[20:27] = y[7:14]
    ctx[14:17] = p[P_AT.inertia:P_AT.inertia + 3]
    ctx[17] = (p[P_AT.omega] * y[0] + p[P_AT.phase]) % (2 * math.pi)
    rotating = p[P_AT.rotation] != 0.0 and (y[11] != 0.0 or y[12] != 0.0 or y[13] != 0.0)
    ctx[18] = 1.0 if rotating else 0.0
    ctx[28] = _support(p, _rot(y[7:11]))
    return ctx


@jit
def _state_at(t, ctx, steps, nsteps, p):
    rv = _translate(p, ctx, t)
    q, w = _orient(t, ctx, steps, nsteps)
    y = np.empty(14)
    y[0] = t
    y[1:4] = rv[0]
    y[4:7] = rv[1]
    y[7:11] = q
    y[11:14] = w
    return y


@jit
def _fly(p, y, t_end, on_plane, rows, carry):
    """Fly from y until the first contact or t_end: (state, status 0 contact, 1 end, 2 resting, rows)."""
    ctx = _flight_ctx(p, y)
    steps = np.empty((64, ROT_WIDTH))
    nsteps = INT(0)
    t_from = y[0]
    scan, xtol = p[P_AT.scan_step], p[P_AT.tolerance] * p[P_AT.scan_step]
    if on_plane:
        span = min(scan, t_end - y[0])
        steps, nsteps = _extend(y[0] + span, y[0] + span, ctx, steps, nsteps, p)
        noise = _gap_noise(p, y)
        out = np.empty((1, 2, 3))
        t_from = np.nan
        for kk in range(64):
            t = y[0] + span / 2.0 ** kk
            if t <= y[0]:
                break
            if _h(GAP, t, ctx, steps, nsteps, p, out) > noise:
                t_from = t
                break
        if math.isnan(t_from):
            return y, 2, rows
    tc, steps, nsteps = _first_root(GAP, t_from, t_end, scan, xtol, ctx, steps, nsteps, p)
    t_stop = t_end if math.isnan(tc) else tc
    steps, nsteps = _extend(t_stop, t_stop, ctx, steps, nsteps, p)
    if ctx[27] != 0.0:
        return y, 3, rows
    k0 = math.ceil(y[0] / p[P_AT.sample_interval] - 1e-9)
    k1 = math.floor(t_stop / p[P_AT.sample_interval] - 1e-9)
    for kk in range(int(k0), int(k1) + 1):
        ts = kk * p[P_AT.sample_interval]
        if y[0] < ts < t_stop:
            rows = _record(rows, carry, _state_at(ts, ctx, steps, nsteps, p), FLIGHT)
    return _state_at(t_stop, ctx, steps, nsteps, p), 1 if math.isnan(tc) else 0, rows


# --------------------------------------------------------------------------- records


@jit
def _record(rows, carry, y, regime):
    """Append the trajectory row of state y (t, r, v, q, w in KXYZ, regime)."""
    n = int(carry[C_AT.rows])
    if n == rows.shape[0]:
        grown = np.empty((2 * n, 15))
        grown[:n] = rows
        rows = grown
    rows[n, :11] = y[:11]
    rows[n, 11:14] = _rot(y[7:11]) @ y[11:14]
    rows[n, 14] = regime
    carry[C_AT.rows] = n + 1
    return rows


@jit
def _warn(warns, carry, code, a, b):
    n = int(carry[C_AT.nwarn])
    if n == warns.shape[0]:
        grown = np.empty((2 * n, 3))
        grown[:n] = warns
        warns = grown
    warns[n, 0], warns[n, 1], warns[n, 2] = code, a, b
    carry[C_AT.nwarn] = n + 1
    return warns


# --------------------------------------------------------------------------- impact laws


@jit
def _coulomb_impulse(K, u, e_n, e_t, mu):
    """Chatterjee-Ruina impulse P (3,) [N s] (``coulomb_law.coulomb_impulse`` for one grain)."""
    P_I = np.zeros(3)
    P_I[2] = -u[2] / K[2, 2]
    D = -np.linalg.solve(K, u) - P_I
    P = (1.0 + e_n) * P_I + (1.0 + e_t) * D
    d_t = math.hypot(D[0], D[1])
    p_t = math.hypot(P[0], P[1])
    outside = p_t / mu > P[2] if mu > 0 else p_t > 0
    if outside:
        kappa = (1.0 + e_n) * P_I[2] / (d_t / mu - D[2])
        return (1.0 + e_n) * P_I + kappa * D
    return P


@jit
def _trig_roots(k, tol, max_iter):
    """Real roots (4,) (NaN unused) of k0 + k1c cos + k1s sin + k2c cos2 + k2s sin2 (``impact._trig_roots``)."""
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
    quartic = np.array([k0 - a1c + a2c, 2 * a1s - 4 * a2s, 2 * k0 - 6 * a2c, 2 * a1s + 4 * a2s, k0 + a1c + a2c])
    roots = np.full(4, np.nan)
    if abs(quartic[0]) > 0:
        comp = np.zeros((4, 4), dtype=np.complex128)
        for j in range(4):
            comp[0, j] = -quartic[j + 1] / quartic[0]
        comp[1, 0] = comp[2, 1] = comp[3, 2] = 1.0
        t = np.linalg.eigvals(comp)
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
    speed = (1.0 - lam) * math.hypot(u[0], u[1])
    return np.array([speed * math.cos(mu), speed * math.sin(mu), -e * u[2]])


@jit
def _printed(H, m, e, lam, u):
    """The printed law solved exactly for one impact (``impact.solve_robust_batch``):
    (T (3,), residual of (19), admissible, creates energy, pulls)."""
    k = gi.mu_equation_scalar(H[0, 0], H[0, 1], H[0, 2], H[1, 1], H[1, 2], H[2, 2], lam, e, u[0], u[1], u[2])
    norm_u = math.sqrt(u @ u)
    stuck = abs(1.0 - lam) * math.hypot(u[0], u[1]) <= 1e-14 * norm_u  # lam > 1 reverses: its size says stuck
    roots = np.full(4, np.nan)
    if stuck:
        roots[0] = 0.0
    else:
        roots = _trig_roots(k, 1e-14, 12)
    ke_scale = 0.5 * m * (u @ u)
    Ts = np.zeros((4, 3))
    score = np.full(4, np.inf)
    gains = np.zeros(4, dtype=np.bool_)
    pulls = np.zeros(4, dtype=np.bool_)
    big = 0.0
    for j in range(4):
        mu = 0.0 if math.isnan(roots[j]) else roots[j]
        du = _prescribed(u, e, lam, mu) - u
        T = m * np.linalg.solve(H, du)
        Ts[j] = T
        gains[j] = 0.5 * (T @ (2 * u + du)) > 1e-9 * ke_scale
        pulls[j] = T[2] < -1e-12 * math.sqrt(T @ T)
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
    T = Ts[choice] if found else np.full(3, np.nan)
    mu = roots[choice]
    if stuck:
        mu = math.atan2(T[1], T[0]) if math.hypot(T[0], T[1]) > 0 else 0.0
    d0, d1 = math.cos(mu), math.sin(mu)
    tau = T[0] * d0 + T[1] * d1
    r = H @ np.array([tau * d0, tau * d1, T[2]]) - m * (_prescribed(u, e, lam, mu) - u)
    residual = (math.sqrt(r @ r) + abs(T[1] * d0 - T[0] * d1)) / (m * norm_u)
    bad_gain, bad_pull = gains[choice], pulls[choice]
    return T, residual, found and not (bad_gain or bad_pull), bad_gain, bad_pull


@jit
def _impact(p, y, warns, carry):
    """The scene's impact law at the lowest point (``ImpactLaw.apply`` for one grain):
    (state after, log row (IMPACT_WIDTH,) without t and r, warns)."""
    Q = _rot(y[7:11])
    R = _offset(p, Q)
    m = p[P_AT.mass]
    rotating = p[P_AT.rotation] != 0.0
    v = y[4:7].copy()
    w = Q @ y[11:14] if rotating else np.zeros(3)
    u = v + _cross(w, R)
    K = _inverse_effective_mass(p, Q, R)
    printed = p[P_AT.law] == LAW_PRINTED
    p_adm = p_gain = -1.0
    converged = 1.0
    P = np.zeros(3)
    if u[2] < 0.0:
        if rotating and (printed or p[P_AT.check_printed] != 0.0):
            e, lam = (p[P_AT.e], p[P_AT.lam]) if printed else (p[P_AT.e_n], 1.0 + p[P_AT.e_t])
            T, residual, adm, gain, pull = _printed(m * K, m, e, lam, u)
            p_adm, p_gain = (1.0 if adm else 0.0), (1.0 if gain else 0.0)
            if printed:
                if not adm:
                    warns = _warn(warns, carry, W_PRINTED_ENERGY if gain else W_PRINTED_PULLS, 0.0, 0.0)
                converged = 1.0 if residual < 1e-8 else 0.0
                if not residual < 1e-8:
                    warns = _warn(warns, carry, W_PRINTED_RESIDUAL, residual, 0.0)
                P = T
        if not (rotating and printed):
            if printed:
                P = _coulomb_impulse(K, u, p[P_AT.e], p[P_AT.lam] - 1.0, np.inf)
            else:
                P = _coulomb_impulse(K, u, p[P_AT.e_n], p[P_AT.e_t], p[P_AT.mu_impact])
    v_after = v + P / m
    w_after = w + _world_inv_inertia(p, Q) @ _cross(R, P) if rotating else np.zeros(3)
    ke_before, ke_after = _kinetic(p, Q, v, w), _kinetic(p, Q, v_after, w_after)
    admissible = ke_after <= ke_before * (1.0 + 1e-9)
    if not admissible:
        warns = _warn(warns, carry, W_ENERGY, ke_before, ke_after)
    after = y.copy()
    after[4:7] = v_after
    after[11:14] = Q.T @ w_after
    log = np.empty(IMPACT_WIDTH)
    log[I_AT.v_before:I_AT.v_before + 3] = v
    log[I_AT.v_after:I_AT.v_after + 3] = v_after
    log[I_AT.w_before:I_AT.w_before + 3] = y[11:14]
    log[I_AT.w_after:I_AT.w_after + 3] = after[11:14]
    log[I_AT.impulse:I_AT.impulse + 3] = P
    log[I_AT.u_before:I_AT.u_before + 3] = u
    log[I_AT.u_after:I_AT.u_after + 3] = v_after + _cross(w_after, R)
    log[I_AT.ke_before], log[I_AT.ke_after], log[I_AT.admissible] = ke_before, ke_after, 1.0 if admissible else 0.0
    log[I_AT.printed_admissible], log[I_AT.printed_creates_energy], log[I_AT.converged] = p_adm, p_gain, converged
    return after, log, warns


@jit
def _bounce(p, y, rows, imps, warns, carry):
    """An impact at y, logged and booked: (state after, normal contact velocity after, rows, imps, warns)."""
    after, log, warns = _impact(p, y, warns, carry)
    carry[C_AT.work] += log[I_AT.impulse:I_AT.impulse + 3] @ _surface(p, y[0])[1]
    carry[C_AT.impacts] += log[I_AT.ke_before] - log[I_AT.ke_after]
    rows = _record(rows, carry, y, IMPACT)
    rows = _record(rows, carry, after, IMPACT)
    n = int(carry[C_AT.nimp])
    if n == imps.shape[0]:
        grown = np.empty((2 * n, IMPACT_WIDTH))
        grown[:n] = imps
        imps = grown
    log[I_AT.t] = y[0]
    log[I_AT.r:I_AT.r + 3] = y[1:4]
    imps[n] = log
    carry[C_AT.nimp] = n + 1
    if n + 1 >= ZENO_IMPACTS and imps[n, I_AT.t] - imps[n + 1 - ZENO_IMPACTS, I_AT.t] < ZENO_INTERVAL * p[P_AT.period]:
        warns = _warn(warns, carry, W_CHATTER, 0.0, 0.0)
        return after, 0.0, rows, imps, warns
    return after, log[I_AT.u_after + 2], rows, imps, warns


# --------------------------------------------------------------------------- contact tests and landing


@jit
def _contact_velocity(p, y):
    Q = _rot(y[7:11])
    return y[6] + _cross(Q @ y[11:14], _offset(p, Q))[2]


@jit
def _gap(p, y):
    return y[3] - _support(p, _rot(y[7:11]))


@jit
def _gap_noise(p, y):
    return 64 * EPS * (max(p[P_AT.axes], p[P_AT.axes + 1], p[P_AT.axes + 2]) + abs(y[3]) + p[P_AT.amplitude])


@jit
def _velocity_noise(p, y):
    a = P_AT.axes
    scale = (math.sqrt(y[4:7] @ y[4:7]) + math.sqrt(y[11:14] @ y[11:14]) * max(p[a], p[a + 1], p[a + 2])
             + p[P_AT.amplitude] * p[P_AT.omega])
    return 1e3 * EPS * scale


@jit
def _energy(p, y):
    """Absolute energy [J]: kinetic in the inertial frame plus the potential of gravity (``motion._Budget``)."""
    s = _surface(p, y[0])
    v = y[4:7] + s[1]
    I = p[P_AT.inertia:P_AT.inertia + 3]
    w = y[11:14]
    return (p[P_AT.mass] * (0.5 * (v @ v) - p[P_AT.g:P_AT.g + 3] @ (y[1:4] + s[0]))
            + 0.5 * (I[0] * w[0] ** 2 + I[1] * w[1] ** 2 + I[2] * w[2] ** 2))


@jit
def _land(p, y, carry):
    """Start sliding (``motion._land``): plastic normal impulse at the lowest point, tilting spin dropped."""
    Q = _rot(y[7:11])
    R = _offset(p, Q)
    w0 = Q @ y[11:14]
    rotating = p[P_AT.rotation] != 0.0
    K = _inverse_effective_mass(p, Q, R)
    P = np.array([0.0, 0.0, -_contact_velocity(p, y) / K[2, 2]])
    v0 = y[4:7].copy()
    v = v0 + P / p[P_AT.mass]
    w = w0.copy()
    if rotating:
        w = w0 + Q @ ((Q.T @ _cross(R, P)) / p[P_AT.inertia:P_AT.inertia + 3])
        if not _is_sphere(p):
            v[2], w[0], w[1] = 0.0, 0.0, 0.0
    v[2] = 0.0
    carry[C_AT.work] += (p[P_AT.mass] * (v - v0)) @ _surface(p, y[0])[1]
    carry[C_AT.land_loss] += _kinetic(p, Q, v0, w0) - _kinetic(p, Q, v, w)
    out = y.copy()
    out[3] = _support(p, Q)
    out[4:7] = v
    out[11:14] = Q.T @ w
    return out


MAX_RADAU_STEPS = sliding.MAX_RHS_PER_PHASE // 4  # Radau steps (at least 4 evaluations) per sliding chunk
NO_EVENT, REGIME, SWITCH = 0, 1, 2  # how a chunk ends: its end time, a regime event, the integrator switch


# --------------------------------------------------------------------------- sliding

# Events: none; the slip stops; the stick ends; an anisotropic slip stops or falls below the stiff slip speed
# (explicit); the slip speed rises through 2 s_stiff (implicit).
EV_NONE, EV_SLIP, EV_STICK, EV_SLIP_STIFF, EV_FAST = 0.0, 1.0, 2.0, 3.0, 4.0


@jit
def _slide_surface(sp, t):
    ph = sp[S_AT.omega] * t + sp[S_AT.phase]
    d = sp[S_AT.direction:S_AT.direction + 3]
    amp, om = sp[S_AT.amplitude], sp[S_AT.omega]
    return amp * om * math.cos(ph) * d, -amp * om ** 2 * math.sin(ph) * d


@jit
def _offset_now(y, sp):
    """Contact offset R (3 floats) of the sliding grain: fixed for a sphere, turned with q otherwise."""
    if sp[S_AT.sphere] != 0.0:
        return sp[S_AT.r0], sp[S_AT.r0 + 1], sp[S_AT.r0 + 2]
    q0, u0, u1, u2 = y[7], y[8], y[9], y[10]
    v0, v1, v2 = sp[S_AT.rb], sp[S_AT.rb + 1], sp[S_AT.rb + 2]
    t0, t1, t2 = 2.0 * (u1 * v2 - u2 * v1), 2.0 * (u2 * v0 - u0 * v2), 2.0 * (u0 * v1 - u1 * v0)
    qq = q0 * q0 + u0 * u0 + u1 * u1 + u2 * u2
    return (v0 + (q0 * t0 + u1 * t2 - u2 * t1) / qq, v1 + (q0 * t1 + u2 * t0 - u0 * t2) / qq,
            v2 + (q0 * t2 + u0 * t1 - u1 * t0) / qq)


@jit
def _geometry(y, sp):
    """Contact offset R (3,), slip s (2,), slip acceleration c (2,) of the carried contact point."""
    R0, R1, R2 = _offset_now(y, sp)
    w0, w1, w2 = y[4], y[5], y[6]
    s = np.array([y[2] + w1 * R2 - w2 * R1, y[3] + w2 * R0 - w0 * R2])
    # The contact point turns with the spin about the normal: R' = w_z e_z x R; c = (w x R')_t.
    c = np.array([-w2 * (w2 * R0), w2 * (-w2 * R1)])
    return np.array([R0, R1, R2]), s, c


@jit
def _mobility(sp):
    return sp[S_AT.m:S_AT.m + 9].copy().reshape(3, 3)


@jit
def _B(R0, R1, R2, sp):
    """B = (E - [R]x M [R]x)_tt (2, 2): the tangential slip response to a tangential impulse per unit mass."""
    Rx = ((0.0, -R2, R1), (R2, 0.0, -R0), (-R1, R0, 0.0))
    B = np.zeros((2, 2))
    for i in range(2):
        for j in range(2):
            acc = 0.0
            for k in range(3):
                for m in range(3):
                    acc += Rx[i][k] * sp[S_AT.m + 3 * k + m] * Rx[m][j]
            B[i, j] = (1.0 if i == j else 0.0) - acc
    return B


@jit
def _solve_B(R0, R1, R2, sp, b0, b1):
    """B^-1 b (Cramer's rule)."""
    B = _B(R0, R1, R2, sp)
    det = B[0, 0] * B[1, 1] - B[0, 1] * B[1, 0]
    return (B[1, 1] * b0 - B[0, 1] * b1) / det, (B[0, 0] * b1 - B[1, 0] * b0) / det


@jit
def _anisotropic(sp):
    """``sliding._Contact.stiff_slip``: the eigenvalues of the symmetric B at R0 differ by more than 1e-12
    relative (turning about the normal keeps them for the whole phase)."""
    B = _B(sp[S_AT.r0], sp[S_AT.r0 + 1], sp[S_AT.r0 + 2], sp)
    gap = math.hypot(B[0, 0] - B[1, 1], 2.0 * B[1, 0])
    return gap > 1e-12 * (0.5 * (B[0, 0] + B[1, 1] + gap))


@jit
def _stick_force(t, y, sp):
    _, acc = _slide_surface(sp, t)
    R, _, c = _geometry(y, sp)
    p0, p1 = _solve_B(R[0], R[1], R[2], sp, sp[S_AT.g] - acc[0] + c[0], sp[S_AT.g + 1] - acc[1] + c[1])
    return np.array([-p0, -p1]), acc[2] - sp[S_AT.g + 2]


@jit
def _slide_rhs(t, y, sp, stick, out):
    """Sliding ODE y = (r (2), v (2), w (3) KXYZ, q (4), W, D) (``sliding._Contact.rhs``), in scalars."""
    ph = sp[S_AT.omega] * t + sp[S_AT.phase]
    sv = sp[S_AT.amplitude] * sp[S_AT.omega] * math.cos(ph)
    sa = -sp[S_AT.amplitude] * sp[S_AT.omega] ** 2 * math.sin(ph)
    d0, d1, d2 = sp[S_AT.direction], sp[S_AT.direction + 1], sp[S_AT.direction + 2]
    R0, R1, R2 = _offset_now(y, sp)
    w0, w1, w2 = y[4], y[5], y[6]
    s0, s1 = y[2] + w1 * R2 - w2 * R1, y[3] + w2 * R0 - w0 * R2
    n = sa * d2 - sp[S_AT.g + 2]
    f0, f1 = sp[S_AT.g] - sa * d0, sp[S_AT.g + 1] - sa * d1
    if stick:
        p0, p1 = _solve_B(R0, R1, R2, sp, f0 - w2 * w2 * R0, f1 - w2 * w2 * R1)
        phi0, phi1 = -p0, -p1
    else:
        speed = math.hypot(s0, s1)
        phi0, phi1 = (-sp[S_AT.mu] * n / speed * s0, -sp[S_AT.mu] * n / speed * s1) if speed > 0.0 else (0.0, 0.0)
    tx, ty, tz = R1 * n - R2 * phi1, R2 * phi0 - R0 * n, R0 * phi1 - R1 * phi0
    q0, q1, q2, q3 = y[7], y[8], y[9], y[10]
    out[0], out[1] = y[2], y[3]
    out[2], out[3] = f0 + phi0, f1 + phi1
    for i in range(3):
        out[4 + i] = sp[S_AT.m + 3 * i] * tx + sp[S_AT.m + 3 * i + 1] * ty + sp[S_AT.m + 3 * i + 2] * tz
    out[7] = 0.5 * (-w0 * q1 - w1 * q2 - w2 * q3)
    out[8] = 0.5 * (w0 * q0 + w1 * q3 - w2 * q2)
    out[9] = 0.5 * (w1 * q0 + w2 * q1 - w0 * q3)
    out[10] = 0.5 * (w2 * q0 + w0 * q2 - w1 * q1)
    out[11] = sv * (phi0 * d0 + phi1 * d1 + n * d2)
    out[12] = -(phi0 * s0 + phi1 * s1)


@jit
def _offset_jac(y, sp):
    """dR/dq (3, 4) of the contact offset of :func:`_offset_now` (zero for a sphere), in scalars:
    R = v + N / |q|^2, N = q0 t + u x t, t = 2 u x v (u the vector part of q, v the body-frame offset)."""
    dR = np.zeros((3, 4))
    if sp[S_AT.sphere] != 0.0:
        return dR
    q0, u0, u1, u2 = y[7], y[8], y[9], y[10]
    v0, v1, v2 = sp[S_AT.rb], sp[S_AT.rb + 1], sp[S_AT.rb + 2]
    qq = q0 * q0 + u0 * u0 + u1 * u1 + u2 * u2
    t0, t1, t2 = 2.0 * (u1 * v2 - u2 * v1), 2.0 * (u2 * v0 - u0 * v2), 2.0 * (u0 * v1 - u1 * v0)
    N = (q0 * t0 + u1 * t2 - u2 * t1, q0 * t1 + u2 * t0 - u0 * t2, q0 * t2 + u0 * t1 - u1 * t0)
    T = (t0, t1, t2)
    u = (u0, u1, u2)
    for i in range(3):
        dR[i, 0] = T[i] / qq - N[i] * 2.0 * q0 / qq ** 2
    for k in range(3):  # dN/du_k = q0 dt + e_k x t + u x dt, dt = 2 e_k x v
        e = (1.0 if k == 0 else 0.0, 1.0 if k == 1 else 0.0, 1.0 if k == 2 else 0.0)
        d0, d1, d2 = 2.0 * (e[1] * v2 - e[2] * v1), 2.0 * (e[2] * v0 - e[0] * v2), 2.0 * (e[0] * v1 - e[1] * v0)
        dN = (q0 * d0 + e[1] * t2 - e[2] * t1 + u1 * d2 - u2 * d1,
              q0 * d1 + e[2] * t0 - e[0] * t2 + u2 * d0 - u0 * d2,
              q0 * d2 + e[0] * t1 - e[1] * t0 + u0 * d1 - u1 * d0)
        for i in range(3):
            dR[i, 1 + k] = dN[i] / qq - N[i] * 2.0 * u[k] / qq ** 2
    return dR


@jit
def _slip_jac(t, y, sp, J):
    """Jacobian d rhs / d y (13, 13) of the slip (``_slide_rhs``, not stuck), analytic, column by column: the
    stiff part is the friction's turning rate mu n / |s| (I - s s^T / |s|^2) through s = v + (w x R)_t, the
    contact offset R turning with q."""
    J[:] = 0.0
    amp, om, ph = sp[S_AT.amplitude], sp[S_AT.omega], sp[S_AT.phase]
    n = -amp * om ** 2 * math.sin(om * t + ph) * sp[S_AT.direction + 2] - sp[S_AT.g + 2]
    sv = amp * om * math.cos(om * t + ph)
    R0, R1, R2 = _offset_now(y, sp)
    w0, w1, w2 = y[4], y[5], y[6]
    s0, s1 = y[2] + w1 * R2 - w2 * R1, y[3] + w2 * R0 - w0 * R2
    speed = math.hypot(s0, s1)
    k, u0, u1 = 0.0, 0.0, 0.0  # no friction force at zero slip
    if speed > 0.0:
        k, u0, u1 = -sp[S_AT.mu] * n / speed, s0 / speed, s1 / speed
    phi0, phi1 = k * s0, k * s1
    ds = np.zeros((2, 13))  # ds/dy at fixed R
    ds[0, 2], ds[0, 5], ds[0, 6] = 1.0, R2, -R1
    ds[1, 3], ds[1, 4], ds[1, 6] = 1.0, -R2, R0
    dR = np.zeros((3, 13))
    dR[:, 7:11] = _offset_jac(y, sp)
    for j in range(13):
        a0, a1, a2 = dR[0, j], dR[1, j], dR[2, j]
        ds0, ds1 = ds[0, j] + w1 * a2 - w2 * a1, ds[1, j] + w2 * a0 - w0 * a2
        dp0, dp1 = k * ((1.0 - u0 * u0) * ds0 - u0 * u1 * ds1), k * ((1.0 - u1 * u1) * ds1 - u0 * u1 * ds0)
        tau = (a1 * n - a2 * phi1 - R2 * dp1, a2 * phi0 + R2 * dp0 - a0 * n,  # d(R x (phi, n))
               a0 * phi1 + R0 * dp1 - a1 * phi0 - R1 * dp0)
        J[2, j], J[3, j] = dp0, dp1
        for i in range(3):
            row = S_AT.m + 3 * i
            J[4 + i, j] = sp[row] * tau[0] + sp[row + 1] * tau[1] + sp[row + 2] * tau[2]
        J[11, j] = sv * (sp[S_AT.direction] * dp0 + sp[S_AT.direction + 1] * dp1)
        J[12, j] = -(dp0 * s0 + phi0 * ds0 + dp1 * s1 + phi1 * ds1)
    J[0, 2] = J[1, 3] = 1.0
    q0, q1, q2, q3 = y[7], y[8], y[9], y[10]
    dq_dw = ((-q1, -q2, -q3), (q0, q3, -q2), (-q3, q0, q1), (q2, -q1, q0))  # q' = (0, w) (x) q / 2
    dq_dq = ((0.0, -w0, -w1, -w2), (w0, 0.0, -w2, w1), (w1, w2, 0.0, -w0), (w2, -w1, w0, 0.0))
    for i in range(4):
        for j in range(3):
            J[7 + i, 4 + j] = 0.5 * dq_dw[i][j]
        for j in range(4):
            J[7 + i, 7 + j] = 0.5 * dq_dq[i][j]


@jit
def _slide_kinetic(sp, q, v2, w):
    """Kinetic energy per unit mass [J/kg] of tangential velocity v2 (2,) and spin w (3,) KXYZ."""
    Q = _rot(q)
    wb = Q.T @ w
    I = sp[S_AT.inertia:S_AT.inertia + 3]
    return 0.5 * (v2 @ v2) + 0.5 * (I[0] * wb[0] ** 2 + I[1] * wb[1] ** 2 + I[2] * wb[2] ** 2) / sp[S_AT.mass]


@jit
def _settle(t, y, sp, may_stick):
    """``sliding._settle``: remove a slip within v_stop by a friction impulse; (stick, y)."""
    R, s, _ = _geometry(y, sp)
    v_stop = sp[S_AT.v_stop]
    if sp[S_AT.mu] == 0.0 or math.hypot(s[0], s[1]) > 1.5 * v_stop:
        return False, y
    phi, n = _stick_force(t, y, sp)
    stick = may_stick and math.hypot(phi[0], phi[1]) <= sp[S_AT.mu] * n
    target = np.zeros(2)
    if not stick:  # against the stick force: along B^-1 (f + c) (``sliding._Contact.slip_direction``)
        _, acc = _slide_surface(sp, t)
        c = _geometry(y, sp)[2]
        d0, d1 = _solve_B(R[0], R[1], R[2], sp, sp[S_AT.g] - acc[0] + c[0], sp[S_AT.g + 1] - acc[1] + c[1])
        target = 2.0 * v_stop * np.array([d0, d1]) / max(math.hypot(d0, d1), 1e-300)
    y = y.copy()
    before = _slide_kinetic(sp, y[7:11], y[2:4], y[4:7])
    dphi = np.array(_solve_B(R[0], R[1], R[2], sp, target[0] - s[0], target[1] - s[1]))
    y[2:4] += dphi
    y[4:7] += _mobility(sp) @ _cross(R, np.array([dphi[0], dphi[1], 0.0]))
    y[12] += before - _slide_kinetic(sp, y[7:11], y[2:4], y[4:7])
    return stick, y


@jit
def _slide_params(p, Q0, R0, mu):
    sp = np.zeros(N_SLIDE)
    sp[S_AT.g:S_AT.g + 3] = p[P_AT.g:P_AT.g + 3]
    sp[S_AT.amplitude], sp[S_AT.omega], sp[S_AT.phase] = p[P_AT.amplitude], p[P_AT.omega], p[P_AT.phase]
    sp[S_AT.direction:S_AT.direction + 3] = p[P_AT.direction:P_AT.direction + 3]
    sp[S_AT.mu] = mu
    sp[S_AT.r0:S_AT.r0 + 3] = R0
    sp[S_AT.rb:S_AT.rb + 3] = Q0.T @ R0
    sp[S_AT.sphere] = 1.0 if _is_sphere(p) else 0.0
    M = np.zeros((3, 3))
    if p[P_AT.rotation] != 0.0:
        if _is_sphere(p):
            M = p[P_AT.mass] / p[P_AT.inertia] * np.eye(3)
        else:
            I = p[P_AT.inertia:P_AT.inertia + 3]
            M[2, 2] = p[P_AT.mass] / (I[0] * Q0[2, 0] ** 2 + I[1] * Q0[2, 1] ** 2 + I[2] * Q0[2, 2] ** 2)
    sp[S_AT.m:S_AT.m + 9] = M.reshape(9)
    sp[S_AT.mass] = p[P_AT.mass]
    sp[S_AT.inertia:S_AT.inertia + 3] = p[P_AT.inertia:P_AT.inertia + 3]
    sp[S_AT.aniso] = 1.0 if mu > 0.0 and _anisotropic(sp) else 0.0
    return sp


@jit
def _interp(t, ctx, tab):
    """The interpolant at t of the step in ctx = (t_old, h, y_old (13), Radau, sp), coefficients tab[0]."""
    if ctx[15] != 0.0:
        return _radau_dense(t, ctx[0], ctx[1], tab[0])
    return _dense(t, ctx[0], ctx[1], ctx[2:15], tab[0])


@jit
def _step_ctx(ctx, t, h, z, radau):
    ctx[0], ctx[1], ctx[15] = t, h, radau
    ctx[2:15] = z


@jit
def _event(t, ctx, tab, p):
    """Sliding event at t inside the step of ctx (see :func:`_interp`)."""
    return _event_at(t, _interp(t, ctx, tab), ctx[16:16 + N_SLIDE])


@jit
def _slip_events(y, sp):
    """(The slip projected on the reference direction minus v_stop, the slip speed)."""
    s = _geometry(y, sp)[1]
    return s[0] * sp[S_AT.ref] + s[1] * sp[S_AT.ref + 1] - sp[S_AT.v_stop], math.hypot(s[0], s[1])


@jit
def _event_at(t, y, sp):
    if sp[S_AT.event] == EV_STICK:
        phi, n = _stick_force(t, y, sp)
        return sp[S_AT.mu] * n - math.hypot(phi[0], phi[1])
    stops, speed = _slip_events(y, sp)
    if sp[S_AT.event] == EV_SLIP:
        return stops
    if sp[S_AT.event] == EV_FAST:
        return speed - 2.0 * sp[S_AT.v_stiff]
    # The earlier of the two falling events of an explicit anisotropic slip (slip stops, turns stiff).
    return min(stops, speed - sp[S_AT.v_stiff])


@jit
def _locate(event, t, t_new, ctx, tab, p):
    """Time of ``event`` in the step of ctx: Brent on the interpolant to 4 eps (as ``solve_ivp``)."""
    ctx[16 + S_AT.event] = event
    return _brentq(t, t_new, 4 * EPS, (EVENT, ctx, tab, INT(0), p, np.empty((1, 2, 3))))


@jit
def _sample_rows(rows, carry, rec, t_last, ctx, tab):
    """Trajectory rows at the sample times before t_last from the step of ctx; rec = (next sample index,
    sample interval [s], start of the phase [s], height [m]), its index advanced."""
    while rec[0] * rec[1] < t_last:
        ts = rec[0] * rec[1]
        if ts >= rec[2]:
            rows = _record(rows, carry, _slide_state(ts, _interp(ts, ctx, tab), rec[3]), SLIDING)
        rec[0] += 1.0
    return rows


@jit
def _dop_chunk(p, kind, t, z, t_chunk, sp, atol, ctx, rows, carry, rec):
    """One integration chunk by DOP853 (a fresh ``solve_ivp`` of the Python loop) until t_chunk or the
    terminal event of sp: (t, z, event NO_EVENT / REGIME / SWITCH, rows, status)."""
    tol = p[P_AT.tolerance]
    g_old = _event_at(t, z, sp) if sp[S_AT.event] != EV_NONE else 0.0
    f = np.empty(13)
    _rhs(t, z, (kind, sp), f)
    h_abs = _first_step(t, z, f, t_chunk, (kind, sp), tol, atol, -DOP_EXPONENT)
    K = np.empty((DOP_EXTENDED, 13))
    F = np.empty((1, DOP_POWER * 13))
    ctx[16:] = sp
    for _ in range(MAX_STEPS_PER_CHUNK):
        if not t < t_chunk:
            return t, z, NO_EVENT, rows, DONE
        t_new, z_new, h_abs, ok = _dop_advance(t, z, f, h_abs, t_chunk, (kind, sp), tol, atol, K)
        if not ok:
            return t, z, NO_EVENT, rows, SLIDE_FAIL
        g_new = _event_at(t_new, z_new, sp) if sp[S_AT.event] != EV_NONE else 0.0
        fired = sp[S_AT.event] != EV_NONE and g_old >= 0.0 and g_new <= 0.0
        t_last = t_new
        if fired or rec[0] * rec[1] < t_new:
            F[0] = _dop_dense(t, t_new - t, z, z_new, (kind, sp), K).reshape(DOP_POWER * 13)
            _step_ctx(ctx, t, t_new - t, z, 0.0)
        if fired:
            t_last = _brentq(t, t_new, 4 * EPS, (EVENT, ctx, F, INT(0), p, np.empty((1, 2, 3))))
            z_new = _dense(t_last, t, t_new - t, z, F[0])
        rows = _sample_rows(rows, carry, rec, t_last, ctx, F)
        if fired:
            return t_last, z_new, SWITCH if _switched(z_new, sp) else REGIME, rows, DONE
        t, z, f, g_old = t_new, z_new, K[DOP_STAGES].copy(), g_new
    return t, z, NO_EVENT, rows, DONE if t >= t_chunk else SLIDE_RHS


@jit
def _radau_chunk(p, t, z, t_chunk, sp, atol, ctx, rows, carry, rec):
    """One chunk of a stiff slip by Radau (a fresh ``solve_ivp(method="Radau")`` of the Python loop) until
    t_chunk or the first terminal event: the slip stops (along sp's reference direction) or its speed rises
    through 2 s_stiff (back to DOP853). Returns (t, z, event, rows, status, accepted steps)."""
    tol = p[P_AT.tolerance]
    f = np.empty(13)
    _rhs(t, z, (SLIP, sp), f)
    J, LUr, LUc = np.empty((13, 13)), np.empty((13, 13)), np.empty((13, 13), dtype=np.complex128)
    pr, pc = np.empty(13, dtype=np.int64), np.empty(13, dtype=np.int64)
    Q = np.empty((1, 4 * 13))
    st = _radau_start(t, z, f, t_chunk, (SLIP, sp), tol, atol, J)
    ctx[16:] = sp
    stops, speed = _slip_events(z, sp)
    for k in range(MAX_RADAU_STEPS):
        if not t < t_chunk:
            return t, z, NO_EVENT, rows, DONE, k
        t_new, z_new, f, ok = _radau_step(t, z, f, t_chunk, (SLIP, sp), tol, atol, st, J, LUr, pr, LUc, pc, Q)
        if not ok:
            return t, z, NO_EVENT, rows, SLIDE_FAIL, k
        stops_new, speed_new = _slip_events(z_new, sp)
        _step_ctx(ctx, t, t_new - t, z, 1.0)
        fast, fast_new = speed - 2.0 * sp[S_AT.v_stiff], speed_new - 2.0 * sp[S_AT.v_stiff]
        t_stops = _locate(EV_SLIP, t, t_new, ctx, Q, p) if stops >= 0.0 and stops_new <= 0.0 else np.inf
        t_fast = _locate(EV_FAST, t, t_new, ctx, Q, p) if fast <= 0.0 and fast_new >= 0.0 else np.inf
        t_last = min(t_stops, t_fast, t_new)
        rows = _sample_rows(rows, carry, rec, t_last, ctx, Q)
        if min(t_stops, t_fast) < np.inf:
            z_last = _radau_dense(t_last, t, t_new - t, Q[0])
            return t_last, z_last, REGIME if t_stops <= t_fast else SWITCH, rows, DONE, k + 1
        t, z, stops, speed = t_new, z_new, stops_new, speed_new
    return t, z, NO_EVENT, rows, DONE if t >= t_chunk else SLIDE_RHS, MAX_RADAU_STEPS


@jit
def _slide(p, y, t_end, rows, carry):
    """One sliding phase from state y (``motion._slide`` with ``sliding.slide``): (state, lifted, rows, status)."""
    t0 = y[0]
    step, tol = p[P_AT.scan_step], p[P_AT.tolerance]
    dummy = np.empty((1, ROT_WIDTH))
    if _normal(p, t0) > 0:
        t_lift = _first_root(NORMAL, t0, t_end, step, tol * step, np.empty(39), dummy, INT(0), p)[0]
    else:
        t_lift = t0
    t_stop = t_end if math.isnan(t_lift) else t_lift
    Q0 = _rot(y[7:11])
    sp = _slide_params(p, Q0, _offset(p, Q0), p[P_AT.mu])
    z = np.empty(13)
    z[0:2] = y[1:3]
    z[2:4] = y[4:6]
    z[4:7] = Q0 @ y[11:14]
    z[7:11] = y[7:11]
    z[11] = z[12] = 0.0
    g = math.sqrt(p[P_AT.g:P_AT.g + 3] @ p[P_AT.g:P_AT.g + 3])
    v_scale = (g + abs(_normal(p, t0))) * step
    sp[S_AT.v_stop] = tol * v_scale
    sp[S_AT.v_stiff] = tol**sliding.SLIP_STIFF_POWER * v_scale
    a_min = min(p[P_AT.axes], p[P_AT.axes + 1], p[P_AT.axes + 2])
    atol = tol * v_scale * np.array([step, step, 1, 1, 1 / a_min, 1 / a_min, 1 / a_min, 1 / v_scale,
                                     1 / v_scale, 1 / v_scale, 1 / v_scale, v_scale, v_scale])
    stick, z = _settle(t0, z, sp, True)
    t, stalled, status, implicit = t0, 0, DONE, False
    ctx = np.empty(16 + N_SLIDE)
    rec = np.array([float(math.ceil(t0 / p[P_AT.sample_interval] - 1e-9)), p[P_AT.sample_interval], t0, y[3]])
    while t < t_stop and status == DONE:
        implicit = _implicit(z, sp, stick, 2.0 if implicit else 1.0)
        _choose_event(z, sp, stick)
        # One integration chunk of 40 scan steps, a fresh solve as in the Python loop.
        t_phase, t_chunk = t, min(t_stop, t + 40 * step)
        if implicit:
            t, z, event, rows, status, n = _radau_chunk(p, t, z, t_chunk, sp, atol, ctx, rows, carry, rec)
            carry[C_AT.implicit] += n
        else:
            kind = STICK if stick else SLIP
            t, z, event, rows, status = _dop_chunk(p, kind, t, z, t_chunk, sp, atol, ctx, rows, carry, rec)
        stalled = stalled + 1 if t <= t_phase else 0
        if stalled > MAX_STALLED_EVENTS:
            status = SLIDE_STALLED
        if event == SWITCH:  # the slip speed left the hysteresis band [s_stiff, 2 s_stiff]
            implicit = not implicit
        elif event == REGIME:  # the stick force reached the cone (slip starts), or the slip speed v_stop
            stick, z = _settle(t, z, sp, not stick)
    carry[C_AT.work] += p[P_AT.mass] * z[11]
    carry[C_AT.slide_loss] += p[P_AT.mass] * z[12]
    end = _slide_state(t, z, y[3])
    rows = _record(rows, carry, end, SLIDING)
    return end, (not math.isnan(t_lift)) and t >= t_lift, rows, status


@jit
def _choose_event(z, sp, stick):
    """The terminal event of the next chunk (``sliding._events``) into sp: kind and reference slip direction."""
    if sp[S_AT.mu] == 0.0:  # without friction there is no stick or slip regime to change
        sp[S_AT.event] = EV_NONE
    elif stick:
        sp[S_AT.event] = EV_STICK
    else:
        s0 = _geometry(z, sp)[1]
        nrm = max(math.hypot(s0[0], s0[1]), 1e-300)
        sp[S_AT.event] = EV_SLIP_STIFF if sp[S_AT.aniso] != 0.0 else EV_SLIP
        sp[S_AT.ref], sp[S_AT.ref + 1] = s0[0] / nrm, s0[1] / nrm


@jit
def _implicit(z, sp, stick, band):
    """Whether the next chunk goes implicit (``sliding.slide``): an anisotropic slip below ``band`` s_stiff
    (1; 2 when the last chunk was implicit: the hysteresis band)."""
    if stick or sp[S_AT.aniso] == 0.0:
        return False
    s = _geometry(z, sp)[1]
    return math.hypot(s[0], s[1]) < band * sp[S_AT.v_stiff]


@jit
def _switched(z, sp):
    """At a located ``EV_SLIP_STIFF`` event: the slip speed fell through s_stiff (not the slip stopping)."""
    if sp[S_AT.event] != EV_SLIP_STIFF:
        return False
    s = _geometry(z, sp)[1]
    return math.hypot(s[0], s[1]) - sp[S_AT.v_stiff] <= s[0] * sp[S_AT.ref] + s[1] * sp[S_AT.ref + 1] - sp[S_AT.v_stop]


@jit
def _slide_state(t, z, height):
    """Full state (14,) from the sliding vector z at t (q normalised, w into body axes)."""
    y = np.empty(14)
    q = z[7:11] / math.sqrt(z[7:11] @ z[7:11])
    y[0], y[1], y[2], y[3] = t, z[0], z[1], height
    y[4], y[5], y[6] = z[2], z[3], 0.0
    y[7:11] = q
    y[11:14] = _rot(q).T @ z[4:7]
    return y


# --------------------------------------------------------------------------- the loop


@jit
def _start(p, y, rows, carry):
    """First row and the release rule of ``motion.simulate``; sets the regime and on_plane in carry."""
    carry[C_AT.regime], carry[C_AT.on_plane] = FLIGHT, 1.0 if _gap(p, y) <= _gap_noise(p, y) else 0.0
    rows = _record(rows, carry, y, FLIGHT)
    if carry[C_AT.on_plane] != 0.0 and _contact_velocity(p, y) <= _velocity_noise(p, y) and _normal(p, y[0]) > 0:
        carry[C_AT.regime], carry[C_AT.on_plane] = SLIDING, 0.0
        y = _land(p, y, carry)
    return y, rows


@jit
def run_phases(p, y, t_end, rows, imps, warns, carry, max_phases):
    """At most ``max_phases`` regime phases of the loop of ``motion.simulate`` from state y (14,);
    returns (y, rows, imps, warns, status)."""
    for _ in range(max_phases):
        if not y[0] < t_end:
            return y, rows, imps, warns, DONE
        t_before = y[0]
        if carry[C_AT.regime] == FLIGHT:
            y, fly_status, rows = _fly(p, y, t_end, carry[C_AT.on_plane] != 0.0, rows, carry)
            carry[C_AT.t_flight] += y[0] - t_before
            if fly_status == 1:
                return y, rows, imps, warns, DONE
            if fly_status == 3:
                return y, rows, imps, warns, ROT_FAIL
            u_n = 0.0
            if fly_status == 0 and _contact_velocity(p, y) < -_velocity_noise(p, y):
                if carry[C_AT.nimp] >= p[P_AT.max_impacts]:
                    warns = _warn(warns, carry, W_MAX_IMPACTS, y[0], p[P_AT.max_impacts])
                    return y, rows, imps, warns, DONE
                y, u_n, rows, imps, warns = _bounce(p, y, rows, imps, warns, carry)
            carry[C_AT.on_plane] = 1.0
            if u_n <= p[P_AT.rest_velocity] and _normal(p, y[0]) > 0:
                carry[C_AT.regime], carry[C_AT.on_plane] = SLIDING, 0.0
                carry[C_AT.landings] += 1
                y = _land(p, y, carry)
            elif fly_status == 2:  # held on a plane that pulls away: a rocking contact (not modelled)
                carry[C_AT.rocking] += 1
                y = _land(p, y, carry)
        else:
            y, lifted, rows, status = _slide(p, y, t_end, rows, carry)
            carry[C_AT.t_sliding] += y[0] - t_before
            if status != DONE:
                return y, rows, imps, warns, status
            if lifted:
                carry[C_AT.regime], carry[C_AT.on_plane] = FLIGHT, 1.0
        carry[C_AT.idle] = carry[C_AT.idle] + 1 if y[0] == t_before else 0
        if carry[C_AT.idle] > MAX_IDLE_STEPS:
            return y, rows, imps, warns, STALLED
    return y, rows, imps, warns, MORE if y[0] < t_end else DONE


@jit
def run(p, y, t_end, rows, imps, warns, carry, max_phases):
    """The entry from Python: ``_start`` on a fresh carry (no rows yet), ``run_phases``, and the last row
    once done, in one call, with the energies of the budget at the start and the end (in the carry);
    returns (y, rows, imps, warns, status)."""
    if carry[C_AT.rows] == 0:
        carry[C_AT.e_start] = _energy(p, y)
        y, rows = _start(p, y, rows, carry)
    y, rows, imps, warns, status = run_phases(p, y, t_end, rows, imps, warns, carry, max_phases)
    if status == DONE:
        rows = _record(rows, carry, y, int(carry[C_AT.regime]))
        carry[C_AT.e_end] = _energy(p, y)
    return y, rows, imps, warns, status


