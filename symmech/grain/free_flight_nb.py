"""The exact free flight in numba: the compiled twin of :mod:`symmech.grain.free_flight` (the reference).

What a compiled event loop calls, per flight (records laid out by ``free_flight.FLIGHT`` and ``ROTATION``,
float64 vectors the caller owns; ``state`` laid out as the engine's ``STATE``: t, r (3), v (3), q (4), w (3)):

- :func:`flight_setup` ``(state, g, amplitude, omega, phase, direction, axes, inertia, fl, rot)``: the records
  of the flight that starts at ``state`` (``phase`` the surface phase at t = 0);
- :func:`flight_state` ``(t, fl, rot, out)``: the state at ``t`` into ``out`` (14,), no integration;
- :func:`gap` ``(t, fl, rot, buf) -> (h [m], h' [m/s])``: the gap and its rate (``buf``: float64 (1, 2, 3)
  scratch);
- :func:`gap_curvature_bound` ``(fl, rot) -> m/s^2``: a bound on ``|h''|`` over the whole flight;
- :func:`next_contact` ``(fl, rot, t_from, t_end, step, xtol, buf) -> t`` or nan: the first root of the gap
  (``gap(t_from) > 0``): samples as far apart as the lower parabola of the curvature bound proves clear, at
  most ``step`` apart near the plane, pieces between them certified by the same bound (as
  :func:`symmech.grain.contact.first_contact`), the root by Newton's method on the gap and its rate, safeguarded by
  the bracket, to ``xtol`` (the reference's function, :mod:`symmech.numerics.newton`, compiled).

Jacobi's elliptic functions by the descending Landen (AGM) transformation, Carlson's R_F and R_J by duplication
(the two in one pass where the third-kind integral needs both), R_C in closed form: generic numerics, no scipy.
"""
from __future__ import annotations

import math

import numpy as np

from symmech.generated import grain_motion_nb as gm_nb
from symmech.grain import free_flight  # module globals: the builds of a compiled caller record their files
from symmech.grain.motion_engine import layouts
from symmech.numerics.brent import newton
from symmech.numerics.jit import EPS, inline, jit

F_AT, R_AT = free_flight.FLIGHT.slots, free_flight.ROTATION.slots
X_AT = layouts.X_AT
FLIGHT_SIZE, ROTATION_SIZE = free_flight.FLIGHT.size, free_flight.ROTATION.size  # constants of compiled callers
LADDER_SIZE = free_flight.LADDER
TWO_PI = 2.0 * math.pi


# --------------------------------------------------------------------------- special functions

@jit
def landen_ladder(m, out):
    """The descending Landen (AGM) ladder of ``m`` into ``out`` (``free_flight.LADDER``,): the steps N, the scale
    2^N a_N and c_i / a_i for i = 1..N (N <= 15, as Cephes caps it): what :func:`ellipj_on` walks back, the same
    for every ``u``, so a flight builds it once."""
    a, b, c = 1.0, math.sqrt(1.0 - m), math.sqrt(m)
    twon, i = 1.0, 0
    while abs(c / a) > EPS and i < 15:
        ai = a
        i += 1
        c = 0.5 * (ai - b)
        t = math.sqrt(ai * b)
        a = 0.5 * (ai + b)
        b = t
        twon *= 2.0
        out[1 + i] = c / a
    out[0], out[1] = i, twon * a


@jit
def ellipj_on(u, m, ladder):
    """Jacobi sn, cn, dn and am(u | m) for 0 <= m < 1 (Abramowitz-Stegun 16.4, as in Cephes), ``ladder`` m's
    (:func:`landen_ladder`; not read for m < 1e-9 or m >= 1 - 1e-10, where the series serve)."""
    if m < 1e-9:
        t, b = math.sin(u), math.cos(u)
        ai = 0.25 * m * (u - t * b)
        return t - ai * b, b + ai * t, 1.0 - 0.5 * m * t * t, u - ai
    if m >= 0.9999999999:
        ai = 0.25 * (1.0 - m)
        b = math.cosh(u)
        t = math.tanh(u)
        phi = 1.0 / b
        twon = b * math.sinh(u)
        sn = t + ai * (twon - u) / (b * b)
        ph = 2.0 * math.atan(math.exp(u)) - 0.5 * math.pi + ai * (twon - u) / b
        ai *= t * phi
        return sn, phi - ai * (twon - u), phi + ai * (twon + u), ph
    phi = ladder[1] * u
    b = phi
    for i in range(int(ladder[0]), 0, -1):
        b = phi
        phi = 0.5 * (math.asin(ladder[1 + i] * math.sin(phi)) + phi)
    cn = math.cos(phi)
    return math.sin(phi), cn, cn / math.cos(phi - b), phi


@jit
def _rf_series(x, y, z):
    """R_F(x, y, z) by its fifth-order series, for x, y, z within 2e-4 of their mean (error below 1e-22)."""
    mean = (x + y + z) / 3.0
    dx, dy, dz = 1.0 - x / mean, 1.0 - y / mean, 1.0 - z / mean
    e2, e3 = dx * dy - dz * dz, dx * dy * dz
    return (1.0 - e2 / 10.0 + e3 / 14.0 + e2 * e2 / 24.0 - 3.0 * e2 * e3 / 44.0) / math.sqrt(mean)


@jit
def carlson_rf(x, y, z):
    """Carlson's R_F(x, y, z), x, y, z >= 0, at most one zero (duplication, Carlson 1995)."""
    for _ in range(64):
        lam = math.sqrt(x * y) + math.sqrt(y * z) + math.sqrt(z * x)
        x, y, z = 0.25 * (x + lam), 0.25 * (y + lam), 0.25 * (z + lam)
        mean = (x + y + z) / 3.0
        if max(abs(x - mean), abs(y - mean), abs(z - mean)) < 1e-4 * mean:
            return _rf_series(x, y, z)
    return math.nan


@jit
def carlson_rc(x, y):
    """Carlson's R_C(x, y), x >= 0, y > 0, in closed form (DLMF 19.2.17-19.2.18): arctan below the diagonal,
    a logarithm above it written with ``log1p`` so that neither side cancels near ``x = y``."""
    if x < y:
        return math.atan(math.sqrt((y - x) / x)) / math.sqrt(y - x) if x > 0.0 else 0.5 * math.pi / math.sqrt(y)
    if x == y:
        return 1.0 / math.sqrt(x)
    d = math.sqrt(x - y)
    return math.log1p((d + (x - y) / (math.sqrt(x) + math.sqrt(y))) / math.sqrt(y)) / d


@jit
def carlson_rf_rj(x, y, z, p):
    """Carlson's (R_F(x, y, z), R_J(x, y, z, p)), x, y, z >= 0 (at most one zero), p > 0, by one duplication
    (Carlson 1995): the two share x, y and z's steps, and R_F is invariant under them, so its series is taken
    where R_J's converged."""
    total, scale = 0.0, 1.0
    for _ in range(64):
        sx, sy, sz = math.sqrt(x), math.sqrt(y), math.sqrt(z)
        lam = sx * sy + sy * sz + sz * sx
        alpha = (p * (sx + sy + sz) + sx * sy * sz) ** 2
        beta = p * (p + lam) ** 2
        total += scale * carlson_rc(alpha, beta)
        scale *= 0.25
        x, y, z, p = 0.25 * (x + lam), 0.25 * (y + lam), 0.25 * (z + lam), 0.25 * (p + lam)
        mean = 0.2 * (x + y + z + 2.0 * p)
        dx, dy, dz, dp = (mean - x) / mean, (mean - y) / mean, (mean - z) / mean, (mean - p) / mean
        if max(abs(dx), abs(dy), abs(dz), abs(dp)) < 1e-4:
            ea = dx * (dy + dz) + dy * dz
            eb = dx * dy * dz
            ec = dp * dp
            ed = ea - 3.0 * ec
            ee = eb + 2.0 * dp * (ea - ec)
            series = (1.0 + ed * (-3.0 / 14.0 + 9.0 / 88.0 * ed - 9.0 / 52.0 * ee)
                      + eb * (1.0 / 6.0 + dp * (-6.0 / 22.0 + dp * 3.0 / 26.0))
                      + dp * ea * (1.0 / 3.0 - dp * 3.0 / 22.0) - 1.0 / 3.0 * dp * ec)
            return _rf_series(x, y, z), 3.0 * total + scale * series / (mean * math.sqrt(mean))
    return math.nan, math.nan


@jit
def third_kind(n, phi, m):
    """Legendre's Pi(n; phi | m), |phi| <= pi/2, n <= 0."""
    s, c = math.sin(phi), math.cos(phi)
    rf, rj = carlson_rf_rj(c * c, 1.0 - m * s * s, 1.0, 1.0 - n * s * s)
    return s * rf + n / 3.0 * s**3 * rj


# --------------------------------------------------------------------------- quaternions


@jit
def _qmul(p0, p1, p2, p3, q0, q1, q2, q3):
    return (p0 * q0 - p1 * q1 - p2 * q2 - p3 * q3, p0 * q1 + p1 * q0 + p2 * q3 - p3 * q2,
            p0 * q2 - p1 * q3 + p2 * q0 + p3 * q1, p0 * q3 + p1 * q2 - p2 * q1 + p3 * q0)


@jit
def _tilt(ma, mb, mc, M):
    """Quaternion of Rx(theta) Rz(psi), the z-x-z angles of the momentum (ma, mb, mc) in the Euler frame."""
    rho = math.hypot(ma, mb)
    big = math.sqrt((M + abs(mc)) / (2.0 * M))
    small = rho / (2.0 * M * big)
    ct2, st2 = (big, small) if mc >= 0.0 else (small, big)
    half = 0.5 * math.atan2(ma, mb)
    cp2, sp2 = math.cos(half), math.sin(half)
    return ct2 * cp2, st2 * cp2, -st2 * sp2, ct2 * sp2


@jit
def _permutation_quaternion(a, b, c):
    """Quaternion of the even permutation taking body axes (a, b, c) to (x, y, z): identity or +-120 deg."""
    if c == 2:
        return 1.0, 0.0, 0.0, 0.0
    if c == 0:  # (1, 2, 0): x <- body y, y <- body z, z <- body x
        return 0.5, -0.5, -0.5, -0.5
    return 0.5, 0.5, 0.5, 0.5


# --------------------------------------------------------------------------- the rotation


@jit
def _argument(sn0, cn0, k2, K):
    """u0 with sn(u0) = sn0, cn(u0) = cn0: F(am | k2), continued past +-pi/2."""
    am = math.atan2(sn0, cn0)
    folded = math.copysign(math.pi, am) - am if abs(am) > 0.5 * math.pi else am
    s, c = math.sin(folded), math.cos(folded)
    f = s * carlson_rf(c * c, 1.0 - k2 * s * s, 1.0)
    return math.copysign(2.0 * K, am) - f if abs(am) > 0.5 * math.pi else f


@jit
def _circled_axis(I, m):
    lo = 0
    hi = 0
    for i in range(3):
        if I[i] < I[lo]:
            lo = i
        if I[i] > I[hi]:
            hi = i
    if lo == hi:
        return lo
    mid = 3 - lo - hi
    if I[lo] == I[mid]:
        return hi
    if I[mid] == I[hi]:
        return lo
    excess = 0.0
    for i in range(3):
        excess += m[i] * m[i] * (I[i] - I[mid]) / I[i]
    return hi if excess > 0.0 else lo


@jit
def rotation_setup(inertia, q, w, t0, rot):
    """Fill ``rot`` (ROTATION) for the free rotation from quaternion ``q`` (4,), body rate ``w`` (3,) at ``t0``."""
    rot[:] = 0.0
    norm = math.sqrt(q[0] ** 2 + q[1] ** 2 + q[2] ** 2 + q[3] ** 2)
    rot[R_AT.t0] = t0
    m = np.empty(3)
    energy2 = 0.0
    for i in range(3):
        rot[R_AT.q0 + i] = q[i] / norm
        rot[R_AT.w0 + i] = w[i]
        rot[R_AT.inertia + i] = inertia[i]
        m[i] = inertia[i] * w[i]
        energy2 += m[i] * w[i]
    rot[R_AT.q0 + 3] = q[3] / norm
    M = math.sqrt(m[0] ** 2 + m[1] ** 2 + m[2] ** 2)
    i_min = min(inertia[0], inertia[1], inertia[2])
    rot[R_AT.max_rate] = min(math.sqrt(energy2 / i_min), M / i_min)
    cross_zero = (w[1] * m[2] == w[2] * m[1]) and (w[2] * m[0] == w[0] * m[2]) and (w[0] * m[1] == w[1] * m[0])
    if cross_zero or (inertia[0] == inertia[1] and inertia[1] == inertia[2]):
        rot[R_AT.fixed_axis] = 1.0
        return
    c = _circled_axis(inertia, m)
    a, b = (c + 1) % 3, (c + 2) % 3
    o_first = abs(inertia[a] - inertia[c]) > abs(inertia[b] - inertia[c]) if inertia[a] != inertia[b] else True
    o, mid = (a, b) if o_first else (b, a)
    Io, Imid, Ic = inertia[o], inertia[mid], inertia[c]
    d_c = 0.0  # 2 E I_c - M^2, summed without cancellation
    d_o = 0.0  # M^2 - 2 E I_o
    for i in range(3):
        if i != c:
            d_c += m[i] * m[i] * (Ic - inertia[i]) / inertia[i]
        if i != o:
            d_o += m[i] * m[i] * (inertia[i] - Io) / inertia[i]
    lam = math.sqrt((Ic - Imid) * d_o / (Io * Imid * Ic))
    k2 = min((Imid - Io) * d_c / ((Ic - Imid) * d_o), 1.0 - EPS) if Imid != Io else 0.0
    sign_c = 1.0 if m[c] >= 0.0 else -1.0
    parity = 1.0 if o_first else -1.0
    mo = math.sqrt(Io * d_c / (Ic - Io))
    mmid = parity * math.copysign(1.0, Ic - Io) * sign_c * math.sqrt(Imid * d_c / (Ic - Imid))
    K = carlson_rf(0.0, 1.0 - k2, 1.0)
    n = Ic * (Io - Imid) / (Io * (Ic - Imid))
    u0 = _argument(m[mid] / mmid if mmid != 0.0 else 0.0, m[o] / mo if mo != 0.0 else 1.0, k2, K)
    rot[R_AT.frame], rot[R_AT.frame + 1], rot[R_AT.frame + 2] = a, b, c
    rot[R_AT.o_first] = 1.0 if o_first else 0.0
    rot[R_AT.mo], rot[R_AT.mmid] = mo, mmid
    rot[R_AT.mc] = sign_c * math.sqrt(Ic * d_o / (Ic - Io))
    rot[R_AT.lam], rot[R_AT.k2], rot[R_AT.K], rot[R_AT.n], rot[R_AT.u0] = lam, k2, K, n, u0
    landen_ladder(k2, rot[R_AT.landen:R_AT.landen + LADDER_SIZE])
    rot[R_AT.momentum] = M
    rot[R_AT.precession] = M * (Ic - Io) / (Ic * Io)
    rot[R_AT.pi_complete] = third_kind(n, 0.5 * math.pi, k2)
    ma, mb, mcv, phi0, pi0 = _euler(rot, 0.0)
    rot[R_AT.pi0] = pi0
    f0, f1, f2, f3 = _permutation_quaternion(a, b, c)
    rot[R_AT.q_frame], rot[R_AT.q_frame + 1], rot[R_AT.q_frame + 2], rot[R_AT.q_frame + 3] = f0, f1, f2, f3
    t0_, t1_, t2_, t3_ = _tilt(ma, mb, mcv, M)
    p = _qmul(q[0] / norm, q[1] / norm, q[2] / norm, q[3] / norm, f0, -f1, -f2, -f3)
    u = _qmul(p[0], p[1], p[2], p[3], t0_, -t1_, -t2_, -t3_)
    for i in range(4):
        rot[R_AT.q_fixed + i] = u[i]


@jit
def _euler(rot, tau):
    """Momentum (ma, mb, mc) in the Euler frame, the angle phi about L and Pi(n; am u) at ``tau = t - t0``."""
    K = rot[R_AT.K]
    u = rot[R_AT.u0] + rot[R_AT.lam] * tau
    j = math.floor((u + K) / (2.0 * K))
    sn, cn, dn, am = ellipj_on(u - 2.0 * K * j, rot[R_AT.k2], rot[R_AT.landen:R_AT.landen + LADDER_SIZE])
    flip = 1.0 - 2.0 * (j - 2.0 * math.floor(0.5 * j))
    m_o, m_mid = rot[R_AT.mo] * cn * flip, rot[R_AT.mmid] * sn * flip
    o_first = rot[R_AT.o_first] == 1.0
    ma, mb = (m_o, m_mid) if o_first else (m_mid, m_o)
    c = int(rot[R_AT.frame + 2])
    o = int(rot[R_AT.frame + (0 if o_first else 1)])
    M, n = rot[R_AT.momentum], rot[R_AT.n]
    if n == 0.0:
        return ma, mb, rot[R_AT.mc] * dn, M * tau / rot[R_AT.inertia + o], 0.0
    third = 2.0 * j * rot[R_AT.pi_complete] + third_kind(n, am, rot[R_AT.k2])
    phi = M * tau / rot[R_AT.inertia + c] + rot[R_AT.precession] / rot[R_AT.lam] * (third - rot[R_AT.pi0])
    return ma, mb, rot[R_AT.mc] * dn, phi, third


@jit
def rotation_tuple(rot, t):
    """(q0, q1, q2, q3, wx, wy, wz): quaternion and body angular velocity [rad/s] at ``t``, no allocation."""
    tau = t - rot[R_AT.t0]
    if rot[R_AT.fixed_axis] == 1.0:
        wx, wy, wz = rot[R_AT.w0], rot[R_AT.w0 + 1], rot[R_AT.w0 + 2]
        rate = math.sqrt(wx * wx + wy * wy + wz * wz)
        s = math.sin(0.5 * rate * tau) / rate if rate > 0.0 else 0.0
        q = _qmul(rot[R_AT.q0], rot[R_AT.q0 + 1], rot[R_AT.q0 + 2], rot[R_AT.q0 + 3],
                  math.cos(0.5 * rate * tau), s * wx, s * wy, s * wz)
        return q[0], q[1], q[2], q[3], wx, wy, wz
    ma, mb, mc, phi, _ = _euler(rot, tau)
    p = _qmul(rot[R_AT.q_fixed], rot[R_AT.q_fixed + 1], rot[R_AT.q_fixed + 2], rot[R_AT.q_fixed + 3],
              math.cos(0.5 * phi), 0.0, 0.0, math.sin(0.5 * phi))
    t0_, t1_, t2_, t3_ = _tilt(ma, mb, mc, rot[R_AT.momentum])
    p = _qmul(p[0], p[1], p[2], p[3], t0_, t1_, t2_, t3_)
    q = _qmul(p[0], p[1], p[2], p[3], rot[R_AT.q_frame], rot[R_AT.q_frame + 1], rot[R_AT.q_frame + 2],
              rot[R_AT.q_frame + 3])
    a, b, c = int(rot[R_AT.frame]), int(rot[R_AT.frame + 1]), int(rot[R_AT.frame + 2])
    wa, wb, wc = ma / rot[R_AT.inertia + a], mb / rot[R_AT.inertia + b], mc / rot[R_AT.inertia + c]
    w = (wc, wa, wb) if c == 0 else (wb, wc, wa) if c == 1 else (wa, wb, wc)  # (a, b, c) = (c+1, c+2, c) mod 3
    return q[0], q[1], q[2], q[3], w[0], w[1], w[2]


@jit
def rotation_at(rot, t, out):
    """Quaternion and body angular velocity at ``t`` into ``out[0:4]``, ``out[4:7]``."""
    values = rotation_tuple(rot, t)
    for i in range(7):
        out[i] = values[i]


# --------------------------------------------------------------------------- the flight and its gap


@jit
def flight_setup(state, g, amplitude, omega, phase, direction, axes, inertia, fl, rot):
    """Fill ``fl`` (FLIGHT) and ``rot`` (ROTATION) for the flight from ``state`` (layout ``STATE`` of
    :mod:`symmech.grain.motion_engine.layouts`)."""
    t0 = state[X_AT.t]
    fl[F_AT.t0] = t0
    for i in range(3):
        fl[F_AT.r0 + i] = state[X_AT.r + i]
        fl[F_AT.v0 + i] = state[X_AT.v + i]
        fl[F_AT.g + i] = g[i]
        fl[F_AT.direction + i] = direction[i]
        fl[F_AT.axes + i] = axes[i]
    fl[F_AT.amplitude], fl[F_AT.omega] = amplitude, omega
    fl[F_AT.phase] = (omega * t0 + phase) % TWO_PI
    rotation_setup(inertia, state[X_AT.q:X_AT.q + 4], state[X_AT.w:X_AT.w + 3], t0, rot)


@inline
def _translate(fl, t, buf):
    """Relative centre position and velocity at ``t`` into buf[0] (rows)."""
    f = fl
    gm_nb.flight_translation_into(f[F_AT.r0], f[F_AT.r0 + 1], f[F_AT.r0 + 2], f[F_AT.v0], f[F_AT.v0 + 1],
                                  f[F_AT.v0 + 2], f[F_AT.g], f[F_AT.g + 1], f[F_AT.g + 2], f[F_AT.amplitude],
                                  f[F_AT.omega], f[F_AT.phase], f[F_AT.direction], f[F_AT.direction + 1],
                                  f[F_AT.direction + 2], 0.0, t - f[F_AT.t0], buf)


@inline
def flight_state(t, fl, rot, out):
    """The state (layout ``STATE``) at ``t`` into ``out``."""
    buf = np.empty((1, 2, 3))
    _translate(fl, t, buf)
    out[X_AT.t] = t
    for i in range(3):
        out[X_AT.r + i] = buf[0, 0, i]
        out[X_AT.v + i] = buf[0, 1, i]
    rotation_at(rot, t, out[X_AT.q:X_AT.w + 3])  # q, w: adjacent in the state


@inline
def gap(t, fl, rot, buf):
    """(h, h'): height [m] of the lowest point above the plane and its rate [m/s]."""
    _translate(fl, t, buf)
    if fl[F_AT.axes] == fl[F_AT.axes + 1] and fl[F_AT.axes + 1] == fl[F_AT.axes + 2]:
        return buf[0, 0, 2] - fl[F_AT.axes], buf[0, 1, 2]  # a sphere: no attitude in its gap
    q0, q1, q2, q3, wx, wy, wz = rotation_tuple(rot, t)
    n0 = 2.0 * (q1 * q3 - q0 * q2)  # body components of e_z: the third row of Q
    n1 = 2.0 * (q2 * q3 + q0 * q1)
    n2 = q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3
    a = fl[F_AT.axes:F_AT.axes + 3]
    d0, d1, d2 = a[0] ** 2 * n0, a[1] ** 2 * n1, a[2] ** 2 * n2  # D^2 n
    support = math.sqrt(d0 * n0 + d1 * n1 + d2 * n2)
    turn = d0 * (n1 * wz - n2 * wy) + d1 * (n2 * wx - n0 * wz) + d2 * (n0 * wy - n1 * wx)  # (D^2 n).(n x w)
    return buf[0, 0, 2] - support, buf[0, 1, 2] - turn / support


@jit
def gap_curvature_bound(fl, rot):
    """Bound [m/s^2] on |h''| over the flight: |g_z| + A omega^2 |d_z| + (a_max^2/a_min + a_max (1 + I_max/I_min))
    |w|max^2, the last term 0 for a sphere (docs/grain-motion.md)."""
    a_max = max(fl[F_AT.axes], fl[F_AT.axes + 1], fl[F_AT.axes + 2])
    a_min = min(fl[F_AT.axes], fl[F_AT.axes + 1], fl[F_AT.axes + 2])
    i_max = max(rot[R_AT.inertia], rot[R_AT.inertia + 1], rot[R_AT.inertia + 2])
    i_min = min(rot[R_AT.inertia], rot[R_AT.inertia + 1], rot[R_AT.inertia + 2])
    spin = (a_max * a_max / a_min + a_max * (1.0 + i_max / i_min)) * rot[R_AT.max_rate] ** 2 if a_max > a_min else 0.0
    return abs(fl[F_AT.g + 2]) + fl[F_AT.amplitude] * fl[F_AT.omega] ** 2 * abs(fl[F_AT.direction + 2]) + spin


@inline
def _gap_and_rate(t, args):
    """The gap [m] and its rate [m/s] at t, as the root finder calls them (``args`` = (fl, rot, buf))."""
    return gap(t, args[0], args[1], args[2])


_bracketed = newton(_gap_and_rate)  # the gap's rate comes with it: Newton, safeguarded (symmech.numerics.brent)


@jit
def clear_span(h, rate, curvature):
    """Time [s] over which the lower parabola h + rate s - curvature s^2 / 2 (h > 0) stays positive."""
    if curvature > 0.0:
        return (rate + math.sqrt(rate * rate + 2.0 * curvature * h)) / curvature
    return h / -rate if rate < 0.0 else math.inf


@jit
def _clear(ha, da, hb, db, span, curvature):
    """h > 0 on a piece of length ``span`` proven by the lower parabola from either end (contact.parabolas_clear)."""
    drop = 0.5 * curvature * span * span
    return min(ha, ha + da * span - drop) > 0.0 or min(hb, hb - db * span - drop) > 0.0


@jit
def _certified_root(fl, rot, a, b, ha, da, hb, db, curvature, xtol, buf, stack):
    """First sign change of the gap in (a, b) with ha, hb > 0, or nan: a piece not cleared by the parabolas
    is halved (as contact.first_contact); ``stack`` (128, 6) scratch."""
    stack[0, 0], stack[0, 1], stack[0, 2], stack[0, 3], stack[0, 4], stack[0, 5] = a, b, ha, da, hb, db
    top = 1
    while top > 0:
        top -= 1
        a, b, ha, da, hb, db = stack[top, 0], stack[top, 1], stack[top, 2], stack[top, 3], stack[top, 4], stack[top, 5]
        if b - a <= xtol or _clear(ha, da, hb, db, b - a, curvature):
            continue
        mid = 0.5 * (a + b)
        hm, dm = gap(mid, fl, rot, buf)
        if hm <= 0.0:
            return _bracketed(a, mid, ha, hm, xtol, (fl, rot, buf))
        stack[top, 0], stack[top, 1], stack[top, 2], stack[top, 3], stack[top, 4], stack[top, 5] = mid, b, hm, dm, hb, db
        top += 1  # the later half below, the earlier on top
        stack[top, 0], stack[top, 1], stack[top, 2], stack[top, 3], stack[top, 4], stack[top, 5] = a, mid, ha, da, hm, dm
        top += 1
    return math.nan


@jit
def next_contact(fl, rot, t_from, t_end, step, xtol, buf):
    """The first time in (t_from, t_end] where the gap reaches zero, or nan; ``t_from`` itself when the gap is not
    positive there."""
    curvature = gap_curvature_bound(fl, rot)
    stack = np.empty((0, 6))  # pieces to clear, allocated on first need (128 rows: one per halving, < 64 levels)
    a = t_from
    ha, da = gap(a, fl, rot, buf)
    if ha <= 0.0:
        return a  # already touching: the caller's rise above round-off did not happen
    while a < t_end:
        span = clear_span(ha, da, curvature)
        b = min(a + max(span, step), t_end)
        hb, db = gap(b, fl, rot, buf)
        if hb <= 0.0:
            return _bracketed(a, b, ha, hb, xtol, (fl, rot, buf))
        if span < b - a:
            if stack.shape[0] == 0:
                stack = np.empty((128, 6))
            root = _certified_root(fl, rot, a, b, ha, da, hb, db, curvature, xtol, buf, stack)
            if not math.isnan(root):
                return root
        a, ha, da = b, hb, db
    return math.nan
