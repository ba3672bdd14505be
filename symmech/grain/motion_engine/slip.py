"""The sliding contact in numba (:mod:`symmech.grain.sliding`): the ODE of a grain on the plane, stick or slip,
its analytic slip Jacobian, the settling impulse at a regime change and the terminal events of a chunk.

The sliding vector z (layout :data:`layouts.SLIDE_STATE`) is (r (2), v (2), w (3) KXYZ, q (4), work, loss):
tangential position and velocity, spin, orientation, the surface's work and the friction's loss per unit mass;
``sp`` the phase's parameters (layout :data:`layouts.SLIDE`)."""
from __future__ import annotations

import math

import numpy as np

from symmech.numerics.jit import inline, jit
from symmech.grain.motion_engine.kinematics import cross, is_sphere, rotation
from symmech.grain.motion_engine.layouts import N_SLIDE, N_SLIDING, N_STATE, P_AT, S_AT, X_AT, Z_AT


# Events: none; the slip stops; the stick ends; an anisotropic slip stops or falls below the stiff slip speed
# (explicit); the slip speed rises through 2 s_stiff (implicit).
EV_NONE, EV_SLIP, EV_STICK, EV_SLIP_STIFF, EV_FAST = 0.0, 1.0, 2.0, 3.0, 4.0


@inline
def planar_length(x, y):
    """|(x, y)| as sqrt(x^2 + y^2), within 2 ulp: glibc's correctly rounded ``hypot`` cost ~6 % of a sliding run
    (the slip's right-hand side, Jacobian and events call it every stage); ``hypot`` where a square would under- or
    overflow (|(x, y)| outside ~1e-145 ... 1e145)."""
    ss = x * x + y * y
    return math.sqrt(ss) if 1e-290 < ss < 1e290 else math.hypot(x, y)


@jit
def slide_surface(sp, t):
    ph = sp[S_AT.omega] * t + sp[S_AT.phase]
    d = sp[S_AT.direction:S_AT.direction + 3]
    amp, om = sp[S_AT.amplitude], sp[S_AT.omega]
    return amp * om * math.cos(ph) * d, -amp * om ** 2 * math.sin(ph) * d


@inline
def _offset_now(z, sp):
    """Contact offset R (3 floats) of the sliding grain: fixed for a sphere, turned with q otherwise."""
    if sp[S_AT.sphere] != 0.0:
        return sp[S_AT.r0], sp[S_AT.r0 + 1], sp[S_AT.r0 + 2]
    q0, u0, u1, u2 = z[Z_AT.q], z[Z_AT.q + 1], z[Z_AT.q + 2], z[Z_AT.q + 3]
    v0, v1, v2 = sp[S_AT.rb], sp[S_AT.rb + 1], sp[S_AT.rb + 2]
    t0, t1, t2 = 2.0 * (u1 * v2 - u2 * v1), 2.0 * (u2 * v0 - u0 * v2), 2.0 * (u0 * v1 - u1 * v0)
    qq = q0 * q0 + u0 * u0 + u1 * u1 + u2 * u2
    return (v0 + (q0 * t0 + u1 * t2 - u2 * t1) / qq, v1 + (q0 * t1 + u2 * t0 - u0 * t2) / qq,
            v2 + (q0 * t2 + u0 * t1 - u1 * t0) / qq)


@jit
def geometry(z, sp):
    """Contact offset R (3,), slip s (2,), slip acceleration c (2,) of the carried contact point."""
    R0, R1, R2 = _offset_now(z, sp)
    w0, w1, w2 = z[Z_AT.w], z[Z_AT.w + 1], z[Z_AT.w + 2]
    s = np.array([z[Z_AT.v] + w1 * R2 - w2 * R1, z[Z_AT.v + 1] + w2 * R0 - w0 * R2])
    # The contact point turns with the spin about the normal: R' = w_z e_z x R; c = (w x R')_t.
    c = np.array([-w2 * (w2 * R0), w2 * (-w2 * R1)])
    return np.array([R0, R1, R2]), s, c


@jit
def _mobility(sp):
    return sp[S_AT.m:S_AT.m + 9].copy().reshape(3, 3)


@inline
def _b_entry(i, j, R0, R1, R2, sp):
    """Entry (i, j) of B = (E - [R]x M [R]x)_tt: the tangential slip response to a tangential impulse per unit mass."""
    Rx = ((0.0, -R2, R1), (R2, 0.0, -R0), (-R1, R0, 0.0))
    acc = 0.0
    for k in range(3):
        for m in range(3):
            acc += Rx[i][k] * sp[S_AT.m + 3 * k + m] * Rx[m][j]
    return (1.0 if i == j else 0.0) - acc


@inline
def _B(R0, R1, R2, sp):
    """B (2, 2) as its entries (B00, B01, B10, B11), in scalars: the stick force's solve makes no array per call."""
    return (_b_entry(0, 0, R0, R1, R2, sp), _b_entry(0, 1, R0, R1, R2, sp), _b_entry(1, 0, R0, R1, R2, sp),
            _b_entry(1, 1, R0, R1, R2, sp))


@inline
def _solve_B(R0, R1, R2, sp, b0, b1):
    """B^-1 b (Cramer's rule)."""
    B00, B01, B10, B11 = _B(R0, R1, R2, sp)
    det = B00 * B11 - B01 * B10
    return (B11 * b0 - B01 * b1) / det, (B00 * b1 - B10 * b0) / det


@jit
def _anisotropic(sp):
    """``_Contact.stiff_slip`` of :mod:`symmech.grain.sliding`: the eigenvalues of the symmetric B at R0 differ by
    more than 1e-12 relative (turning about the normal keeps them for the whole phase)."""
    B00, _, B10, B11 = _B(sp[S_AT.r0], sp[S_AT.r0 + 1], sp[S_AT.r0 + 2], sp)
    gap = planar_length(B00 - B11, 2.0 * B10)
    return gap > 1e-12 * (0.5 * (B00 + B11 + gap))


@inline
def _stick_force(t, z, sp):
    """(phi0, phi1, n): the friction force per unit mass holding the slip at zero and the normal force, in scalars
    (``slide_surface`` and ``geometry`` written out: no arrays in a stick phase's event, evaluated every step)."""
    d0, d1, d2 = sp[S_AT.direction], sp[S_AT.direction + 1], sp[S_AT.direction + 2]
    a = -sp[S_AT.amplitude] * sp[S_AT.omega] ** 2 * math.sin(sp[S_AT.omega] * t + sp[S_AT.phase])
    R0, R1, R2 = _offset_now(z, sp)
    w2 = z[Z_AT.w + 2]
    c0, c1 = -w2 * (w2 * R0), w2 * (-w2 * R1)
    p0, p1 = _solve_B(R0, R1, R2, sp, sp[S_AT.g] - a * d0 + c0, sp[S_AT.g + 1] - a * d1 + c1)
    return -p0, -p1, a * d2 - sp[S_AT.g + 2]


@inline
def slide_rhs(t, z, sp, stick, out):
    """Sliding ODE of z (layout ``SLIDE_STATE``) into out (``_Contact.rhs`` of the Python loop), in scalars."""
    ph = sp[S_AT.omega] * t + sp[S_AT.phase]
    sv = sp[S_AT.amplitude] * sp[S_AT.omega] * math.cos(ph)
    sa = -sp[S_AT.amplitude] * sp[S_AT.omega] ** 2 * math.sin(ph)
    d0, d1, d2 = sp[S_AT.direction], sp[S_AT.direction + 1], sp[S_AT.direction + 2]
    R0, R1, R2 = _offset_now(z, sp)
    w0, w1, w2 = z[Z_AT.w], z[Z_AT.w + 1], z[Z_AT.w + 2]
    s0, s1 = z[Z_AT.v] + w1 * R2 - w2 * R1, z[Z_AT.v + 1] + w2 * R0 - w0 * R2
    n = sa * d2 - sp[S_AT.g + 2]
    f0, f1 = sp[S_AT.g] - sa * d0, sp[S_AT.g + 1] - sa * d1
    if stick:
        p0, p1 = _solve_B(R0, R1, R2, sp, f0 - w2 * w2 * R0, f1 - w2 * w2 * R1)
        phi0, phi1 = -p0, -p1
    else:
        speed = planar_length(s0, s1)
        phi0, phi1 = (-sp[S_AT.mu] * n / speed * s0, -sp[S_AT.mu] * n / speed * s1) if speed > 0.0 else (0.0, 0.0)
    tx, ty, tz = R1 * n - R2 * phi1, R2 * phi0 - R0 * n, R0 * phi1 - R1 * phi0
    q0, q1, q2, q3 = z[Z_AT.q], z[Z_AT.q + 1], z[Z_AT.q + 2], z[Z_AT.q + 3]
    out[Z_AT.r], out[Z_AT.r + 1] = z[Z_AT.v], z[Z_AT.v + 1]
    out[Z_AT.v], out[Z_AT.v + 1] = f0 + phi0, f1 + phi1
    for i in range(3):
        out[Z_AT.w + i] = sp[S_AT.m + 3 * i] * tx + sp[S_AT.m + 3 * i + 1] * ty + sp[S_AT.m + 3 * i + 2] * tz
    out[Z_AT.q] = 0.5 * (-w0 * q1 - w1 * q2 - w2 * q3)
    out[Z_AT.q + 1] = 0.5 * (w0 * q0 + w1 * q3 - w2 * q2)
    out[Z_AT.q + 2] = 0.5 * (w1 * q0 + w2 * q1 - w0 * q3)
    out[Z_AT.q + 3] = 0.5 * (w2 * q0 + w0 * q2 - w1 * q1)
    out[Z_AT.work] = sv * (phi0 * d0 + phi1 * d1 + n * d2)
    out[Z_AT.loss] = -(phi0 * s0 + phi1 * s1)


@jit
def _offset_jac(z, sp):
    """dR/dq (3, 4) of the contact offset of :func:`_offset_now` (zero for a sphere), in scalars:
    R = v + N / |q|^2, N = q0 t + u x t, t = 2 u x v (u the vector part of q, v the body-frame offset)."""
    dR = np.zeros((3, 4))
    if sp[S_AT.sphere] != 0.0:
        return dR
    q0, u0, u1, u2 = z[Z_AT.q], z[Z_AT.q + 1], z[Z_AT.q + 2], z[Z_AT.q + 3]
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


@inline
def slip_jac(t, z, sp, J):
    """Jacobian d rhs / d z (N_SLIDING, N_SLIDING) of the slip (``slide_rhs``, not stuck), analytic, column by column: the
    stiff part is the friction's turning rate mu n / |s| (I - s s^T / |s|^2) through s = v + (w x R)_t, the
    contact offset R turning with q."""
    J[:] = 0.0
    amp, om, ph = sp[S_AT.amplitude], sp[S_AT.omega], sp[S_AT.phase]
    n = -amp * om ** 2 * math.sin(om * t + ph) * sp[S_AT.direction + 2] - sp[S_AT.g + 2]
    sv = amp * om * math.cos(om * t + ph)
    R0, R1, R2 = _offset_now(z, sp)
    w0, w1, w2 = z[Z_AT.w], z[Z_AT.w + 1], z[Z_AT.w + 2]
    s0, s1 = z[Z_AT.v] + w1 * R2 - w2 * R1, z[Z_AT.v + 1] + w2 * R0 - w0 * R2
    speed = planar_length(s0, s1)
    k, u0, u1 = 0.0, 0.0, 0.0  # no friction force at zero slip
    if speed > 0.0:
        k, u0, u1 = -sp[S_AT.mu] * n / speed, s0 / speed, s1 / speed
    phi0, phi1 = k * s0, k * s1
    ds = np.zeros((2, N_SLIDING))  # ds/dz at fixed R
    ds[0, Z_AT.v], ds[0, Z_AT.w + 1], ds[0, Z_AT.w + 2] = 1.0, R2, -R1
    ds[1, Z_AT.v + 1], ds[1, Z_AT.w], ds[1, Z_AT.w + 2] = 1.0, -R2, R0
    dR = np.zeros((3, N_SLIDING))
    dR[:, Z_AT.q:Z_AT.q + 4] = _offset_jac(z, sp)
    for j in range(N_SLIDING):
        a0, a1, a2 = dR[0, j], dR[1, j], dR[2, j]
        ds0, ds1 = ds[0, j] + w1 * a2 - w2 * a1, ds[1, j] + w2 * a0 - w0 * a2
        dp0, dp1 = k * ((1.0 - u0 * u0) * ds0 - u0 * u1 * ds1), k * ((1.0 - u1 * u1) * ds1 - u0 * u1 * ds0)
        tau = (a1 * n - a2 * phi1 - R2 * dp1, a2 * phi0 + R2 * dp0 - a0 * n,  # d(R x (phi, n))
               a0 * phi1 + R0 * dp1 - a1 * phi0 - R1 * dp0)
        J[Z_AT.v, j], J[Z_AT.v + 1, j] = dp0, dp1
        for i in range(3):
            row = S_AT.m + 3 * i
            J[Z_AT.w + i, j] = sp[row] * tau[0] + sp[row + 1] * tau[1] + sp[row + 2] * tau[2]
        J[Z_AT.work, j] = sv * (sp[S_AT.direction] * dp0 + sp[S_AT.direction + 1] * dp1)
        J[Z_AT.loss, j] = -(dp0 * s0 + phi0 * ds0 + dp1 * s1 + phi1 * ds1)
    J[Z_AT.r, Z_AT.v] = J[Z_AT.r + 1, Z_AT.v + 1] = 1.0
    q0, q1, q2, q3 = z[Z_AT.q], z[Z_AT.q + 1], z[Z_AT.q + 2], z[Z_AT.q + 3]
    dq_dw = ((-q1, -q2, -q3), (q0, q3, -q2), (-q3, q0, q1), (q2, -q1, q0))  # q' = (0, w) (x) q / 2
    dq_dq = ((0.0, -w0, -w1, -w2), (w0, 0.0, -w2, w1), (w1, w2, 0.0, -w0), (w2, -w1, w0, 0.0))
    for i in range(4):
        for j in range(3):
            J[Z_AT.q + i, Z_AT.w + j] = 0.5 * dq_dw[i][j]
        for j in range(4):
            J[Z_AT.q + i, Z_AT.q + j] = 0.5 * dq_dq[i][j]


@jit
def _slide_kinetic(sp, q, v2, w):
    """Kinetic energy per unit mass [J/kg] of tangential velocity v2 (2,) and spin w (3,) KXYZ."""
    Q = rotation(q)
    wb = Q.T @ w
    I = sp[S_AT.inertia:S_AT.inertia + 3]
    return 0.5 * (v2 @ v2) + 0.5 * (I[0] * wb[0] ** 2 + I[1] * wb[1] ** 2 + I[2] * wb[2] ** 2) / sp[S_AT.mass]


@jit
def settle(t, z, sp, may_stick):
    """``_settle`` of :mod:`symmech.grain.sliding`: remove a slip within v_stop by a friction impulse; (stick, z)."""
    R, s, _ = geometry(z, sp)
    v_stop = sp[S_AT.v_stop]
    if sp[S_AT.mu] == 0.0 or planar_length(s[0], s[1]) > 1.5 * v_stop:
        return False, z
    phi0, phi1, n = _stick_force(t, z, sp)
    stick = may_stick and planar_length(phi0, phi1) <= sp[S_AT.mu] * n
    target = np.zeros(2)
    if not stick:  # against the stick force: along B^-1 (f + c) (``_Contact.slip_direction``)
        _, acc = slide_surface(sp, t)
        c = geometry(z, sp)[2]
        d0, d1 = _solve_B(R[0], R[1], R[2], sp, sp[S_AT.g] - acc[0] + c[0], sp[S_AT.g + 1] - acc[1] + c[1])
        target = 2.0 * v_stop * np.array([d0, d1]) / max(planar_length(d0, d1), 1e-300)
    z = z.copy()
    q, v, w = Z_AT.q, Z_AT.v, Z_AT.w
    before = _slide_kinetic(sp, z[q:q + 4], z[v:v + 2], z[w:w + 3])
    dphi = np.array(_solve_B(R[0], R[1], R[2], sp, target[0] - s[0], target[1] - s[1]))
    z[v:v + 2] += dphi
    z[w:w + 3] += _mobility(sp) @ cross(R, np.array([dphi[0], dphi[1], 0.0]))
    z[Z_AT.loss] += before - _slide_kinetic(sp, z[q:q + 4], z[v:v + 2], z[w:w + 3])
    return stick, z


@jit
def slide_params(p, Q0, R0, mu):
    sp = np.zeros(N_SLIDE)
    sp[S_AT.g:S_AT.g + 3] = p[P_AT.g:P_AT.g + 3]
    sp[S_AT.amplitude], sp[S_AT.omega], sp[S_AT.phase] = p[P_AT.amplitude], p[P_AT.omega], p[P_AT.phase]
    sp[S_AT.direction:S_AT.direction + 3] = p[P_AT.direction:P_AT.direction + 3]
    sp[S_AT.mu] = mu
    sp[S_AT.r0:S_AT.r0 + 3] = R0
    sp[S_AT.rb:S_AT.rb + 3] = Q0.T @ R0
    sp[S_AT.sphere] = 1.0 if is_sphere(p) else 0.0
    M = np.zeros((3, 3))
    if p[P_AT.rotation] != 0.0:
        if is_sphere(p):
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
def slip_events(z, sp):
    """(The slip projected on the reference direction minus v_stop, the slip speed)."""
    s = geometry(z, sp)[1]
    return s[0] * sp[S_AT.ref] + s[1] * sp[S_AT.ref + 1] - sp[S_AT.v_stop], planar_length(s[0], s[1])


@jit
def event_at(t, z, sp):
    if sp[S_AT.event] == EV_STICK:
        phi0, phi1, n = _stick_force(t, z, sp)
        return sp[S_AT.mu] * n - planar_length(phi0, phi1)
    stops, speed = slip_events(z, sp)
    if sp[S_AT.event] == EV_SLIP:
        return stops
    if sp[S_AT.event] == EV_FAST:
        return speed - 2.0 * sp[S_AT.v_stiff]
    # The earlier of the two falling events of an explicit anisotropic slip (slip stops, turns stiff).
    return min(stops, speed - sp[S_AT.v_stiff])


@jit
def choose_event(z, sp, stick):
    """The terminal event of the next chunk (``_events`` of :mod:`symmech.grain.sliding`) into sp: kind and reference
    slip direction."""
    if sp[S_AT.mu] == 0.0:  # without friction there is no stick or slip regime to change
        sp[S_AT.event] = EV_NONE
    elif stick:
        sp[S_AT.event] = EV_STICK
    else:
        s0 = geometry(z, sp)[1]
        nrm = max(planar_length(s0[0], s0[1]), 1e-300)
        sp[S_AT.event] = EV_SLIP_STIFF if sp[S_AT.aniso] != 0.0 else EV_SLIP
        sp[S_AT.ref], sp[S_AT.ref + 1] = s0[0] / nrm, s0[1] / nrm


@jit
def goes_implicit(z, sp, stick, band):
    """Whether the next chunk goes implicit (``sliding.slide``): an anisotropic slip below ``band`` s_stiff
    (1; 2 when the last chunk was implicit: the hysteresis band)."""
    if stick or sp[S_AT.aniso] == 0.0:
        return False
    s = geometry(z, sp)[1]
    return planar_length(s[0], s[1]) < band * sp[S_AT.v_stiff]


@jit
def switched(z, sp):
    """At a located ``EV_SLIP_STIFF`` event: the slip speed fell through s_stiff (not the slip stopping)."""
    if sp[S_AT.event] != EV_SLIP_STIFF:
        return False
    s = geometry(z, sp)[1]
    stiff_gap = planar_length(s[0], s[1]) - sp[S_AT.v_stiff]
    return stiff_gap <= s[0] * sp[S_AT.ref] + s[1] * sp[S_AT.ref + 1] - sp[S_AT.v_stop]


@jit
def slide_state(t, z, height):
    """Full state (layout ``STATE``) from the sliding vector z at t on the plane at centre height ``height`` [m]
    (q normalised, w into body axes)."""
    y = np.empty(N_STATE)
    q = z[Z_AT.q:Z_AT.q + 4] / math.sqrt(z[Z_AT.q:Z_AT.q + 4] @ z[Z_AT.q:Z_AT.q + 4])
    y[X_AT.t], y[X_AT.r], y[X_AT.r + 1], y[X_AT.r + 2] = t, z[Z_AT.r], z[Z_AT.r + 1], height
    y[X_AT.v], y[X_AT.v + 1], y[X_AT.v + 2] = z[Z_AT.v], z[Z_AT.v + 1], 0.0
    y[X_AT.q:X_AT.q + 4] = q
    y[X_AT.w:X_AT.w + 3] = rotation(q).T @ z[Z_AT.w:Z_AT.w + 3]
    return y

