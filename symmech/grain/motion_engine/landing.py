"""What a contact does to the compiled run, in numba: a bounce (the impact law, logged and booked, chatter
detected) or a landing (plastic normal impulse) that starts sliding."""
from __future__ import annotations

import numpy as np

from symmech.numerics.jit import inline, jit
from symmech.grain.motion_engine.impact_law import impact
from symmech.grain.motion_engine.kinematics import (
    contact_offset, contact_velocity, cross, dot3, inverse_effective_mass, is_sphere, kinetic, rotation, support, surface)
from symmech.grain.motion_engine.layouts import (
    C_AT, I_AT, IMPACT, IMPACT_WIDTH, P_AT, W_CHATTER, X_AT, ZENO_IMPACTS, ZENO_INTERVAL)
from symmech.grain.motion_engine.rows import record, warn


@inline
def bounce(p, y, rows, imps, warns, carry):
    """An impact at y, logged and booked: (state after, normal contact velocity after, rows, imps, warns)."""
    after, log, warns = impact(p, y, warns, carry)
    carry[C_AT.work] += dot3(log[I_AT.impulse:I_AT.impulse + 3], surface(p, y[X_AT.t])[1])
    carry[C_AT.impacts] += log[I_AT.ke_before] - log[I_AT.ke_after]
    rows = record(rows, carry, y, IMPACT)
    rows = record(rows, carry, after, IMPACT)
    n = int(carry[C_AT.nimp])
    if n == imps.shape[0]:
        grown = np.empty((2 * n, IMPACT_WIDTH))
        grown[:n] = imps
        imps = grown
    log[I_AT.t] = y[X_AT.t]
    log[I_AT.r:I_AT.r + 3] = y[X_AT.r:X_AT.r + 3]
    imps[n] = log
    carry[C_AT.nimp] = n + 1
    if n + 1 >= ZENO_IMPACTS and imps[n, I_AT.t] - imps[n + 1 - ZENO_IMPACTS, I_AT.t] < ZENO_INTERVAL * p[P_AT.period]:
        warns = warn(warns, carry, W_CHATTER, 0.0, 0.0)
        return after, 0.0, rows, imps, warns
    return after, log[I_AT.u_after + 2], rows, imps, warns


@jit
def land(p, y, carry):
    """Start sliding (the Python loop's ``_land``): plastic normal impulse at the lowest point, tilting spin dropped."""
    Q = rotation(y[X_AT.q:X_AT.q + 4])
    R = contact_offset(p, Q)
    w0 = Q @ y[X_AT.w:X_AT.w + 3]
    rotating = p[P_AT.rotation] != 0.0
    K = inverse_effective_mass(p, Q, R)
    P = np.array([0.0, 0.0, -contact_velocity(p, y) / K[5]])  # K_zz
    v0 = y[X_AT.v:X_AT.v + 3].copy()
    v = v0 + P / p[P_AT.mass]
    w = w0.copy()
    if rotating:
        w = w0 + Q @ ((Q.T @ cross(R, P)) / p[P_AT.inertia:P_AT.inertia + 3])
        if not is_sphere(p):
            v[2], w[0], w[1] = 0.0, 0.0, 0.0
    v[2] = 0.0
    carry[C_AT.work] += (p[P_AT.mass] * (v - v0)) @ surface(p, y[X_AT.t])[1]
    carry[C_AT.land_loss] += kinetic(p, Q, v0, w0) - kinetic(p, Q, v, w)
    out = y.copy()
    out[X_AT.r + 2] = support(p, Q)
    out[X_AT.v:X_AT.v + 3] = v
    out[X_AT.w:X_AT.w + 3] = Q.T @ w
    return out

