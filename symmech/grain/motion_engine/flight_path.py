"""Where a flying grain is, in numba: the exact translation of its centre (generated ``flight_translation_into``)
and its torque-free rotation, integrated by DOP853 step by step as far as asked and read back from the steps'
dense interpolants (``flight.RotationFlight``'s chunks, the same steps).

A flight is a record ``ctx`` (layout :data:`layouts.FLIGHT_RECORD`) set up at its start (:func:`flight_ctx`)
and a table ``tab`` of rotation steps (rows: layout ``ROTATION_STEP``) that grows as the root finders ask for later
times."""
from __future__ import annotations

import math

import numpy as np

from symmech.numerics.dop853 import dop_dense_at
from symmech.numerics.jit import inline, jit
from symmech.grain.motion_engine.kinematics import gm, rotation, support
from symmech.grain.motion_engine.layouts import FL_AT, N_FLIGHT, N_ROTATION, N_STATE, P_AT, RO_AT, ROT_WIDTH, RS_AT, X_AT
from symmech.grain.motion_engine.steppers import (
    DOP_EXPONENT, DOP_EXTENDED, DOP_POWER, DOP_STAGES, ROT, dop_advance, dop_dense, first_step, rhs)

@jit
def orient(t, ctx, tab, ntab):
    """(q normalised (4,), w body (3,)) of the flight at t from the rotation step table ``tab`` (rows: layout
    ``ROTATION_STEP``): the interpolant of the first step ending at or after t."""
    if ntab == 0:
        y = ctx[FL_AT.q0:FL_AT.q0 + N_ROTATION].copy()  # q0 and w0: a rotation state
    else:
        lo, hi = 0, ntab - 1
        while lo < hi:
            mid = (lo + hi) // 2
            if tab[mid, RS_AT.t_new] >= t:
                hi = mid
            else:
                lo = mid + 1
        row = tab[lo]
        y = dop_dense_at(t, row[RS_AT.t_old], row[RS_AT.t_new] - row[RS_AT.t_old], row[RS_AT.y_old:RS_AT.y_old + N_ROTATION],
                         tab[lo, RS_AT.dense:])
    q = y[RO_AT.q:RO_AT.q + 4]
    q /= math.sqrt(q[0] ** 2 + q[1] ** 2 + q[2] ** 2 + q[3] ** 2)
    return q, y[RO_AT.w:RO_AT.w + 3]


@inline  # no call in the scan loop
def translate_into(p, ctx, t, out):
    """Centre position and velocity rows out[0] (2, 3) at t of the flight ctx."""
    tau = t - ctx[FL_AT.t0]
    r = FL_AT.r0
    v = FL_AT.v0
    if p[P_AT.amplitude] == 0.0:
        gm.flight_translation_rigid_into(ctx[r], ctx[r + 1], ctx[r + 2], ctx[v], ctx[v + 1], ctx[v + 2],
                                         p[P_AT.g], p[P_AT.g + 1], p[P_AT.g + 2], 0.0, tau, out)
    else:
        d = P_AT.direction
        gm.flight_translation_into(ctx[r], ctx[r + 1], ctx[r + 2], ctx[v], ctx[v + 1], ctx[v + 2], p[P_AT.g],
                                   p[P_AT.g + 1], p[P_AT.g + 2], p[P_AT.amplitude], p[P_AT.omega], ctx[FL_AT.phase],
                                   p[d], p[d + 1], p[d + 2], 0.0, tau, out)


@jit
def _translate(p, ctx, t):
    """Centre position and velocity rows (2, 3) at t of the flight ctx."""
    out = np.empty((1, 2, 3))
    translate_into(p, ctx, t, out)
    return out[0]


@jit
def still_gap(p, ctx, t, out):
    """The gap [m] of a flight without rotation (the support height is the one at its start); out (1, 2, 3)
    scratch: the scan reuses one, which halves the time of a sphere's scan."""
    translate_into(p, ctx, t, out)
    return out[0, 0, 2] - ctx[FL_AT.support]


@jit
def extend_rotation(t, t_request, ctx, tab, ntab, p):
    """Integrate the rotation of the flight ctx until it covers t; returns the grown step table and its length.

    ``flight.RotationFlight`` integrates in chunks, each a fresh DOP853 solve from its start to
    max(t_request, start + period), t_request being the latest time the Python loop asks for at once.
    The same chunks are solved here, but only as many of their steps as t needs: the step sequence, hence
    every value, is the Python one. The solver's state is in ctx (t_rot, y_rot, chunk_end, step, f, in_chunk);
    ``failed`` is set on failure."""
    if ctx[FL_AT.rotating] == 0.0:
        return tab, ntab
    tol = p[P_AT.tolerance]
    atol = np.full(N_ROTATION, tol * 1e-3)
    K = np.empty((DOP_EXTENDED, N_ROTATION))
    inertia = ctx[FL_AT.inertia:FL_AT.inertia + 3].copy()
    while ctx[FL_AT.t_rot] < t:
        if ctx[FL_AT.in_chunk] == 0.0:  # a new chunk
            ctx[FL_AT.chunk_end] = max(t_request, ctx[FL_AT.t_rot] + p[P_AT.period])
            f = np.empty(N_ROTATION)
            rhs(ctx[FL_AT.t_rot], ctx[FL_AT.y_rot:FL_AT.y_rot + N_ROTATION].copy(), (ROT, inertia), f)
            ctx[FL_AT.f:FL_AT.f + N_ROTATION] = f
            ctx[FL_AT.step] = first_step(ctx[FL_AT.t_rot], ctx[FL_AT.y_rot:FL_AT.y_rot + N_ROTATION].copy(), f,
                                         ctx[FL_AT.chunk_end], (ROT, inertia), tol, atol, -DOP_EXPONENT)
            ctx[FL_AT.in_chunk] = 1.0
        tt, y, f = ctx[FL_AT.t_rot], ctx[FL_AT.y_rot:FL_AT.y_rot + N_ROTATION].copy(), ctx[FL_AT.f:FL_AT.f + N_ROTATION].copy()
        t_new, y_new, h_abs, ok = dop_advance(tt, y, f, ctx[FL_AT.step], ctx[FL_AT.chunk_end], (ROT, inertia), tol,
                                              atol, K)
        if not ok:
            ctx[FL_AT.failed] = 1.0
            return tab, ntab
        if ntab == tab.shape[0]:
            grown = np.empty((2 * ntab, ROT_WIDTH))
            grown[:ntab] = tab
            tab = grown
        tab[ntab, RS_AT.t_old], tab[ntab, RS_AT.t_new] = tt, t_new
        tab[ntab, RS_AT.y_old:RS_AT.y_old + N_ROTATION] = y
        tab[ntab, RS_AT.dense:] = dop_dense(tt, t_new - tt, y, y_new, (ROT, inertia), K).reshape(DOP_POWER * N_ROTATION)
        ntab += 1
        ctx[FL_AT.t_rot], ctx[FL_AT.step] = t_new, h_abs
        ctx[FL_AT.y_rot:FL_AT.y_rot + N_ROTATION] = y_new
        ctx[FL_AT.f:FL_AT.f + N_ROTATION] = K[DOP_STAGES]
        if t_new >= ctx[FL_AT.chunk_end]:
            ctx[FL_AT.in_chunk] = 0.0
    return tab, ntab


@jit
def flight_ctx(p, y):
    """The flight record (layout ``FLIGHT_RECORD``) of a flight from the state y (STATE.size,)."""
    ctx = np.zeros(N_FLIGHT)
    ctx[FL_AT.t0:FL_AT.w0 + 3] = y
    ctx[FL_AT.t_rot] = y[X_AT.t]
    ctx[FL_AT.y_rot:FL_AT.y_rot + N_ROTATION] = y[X_AT.q:X_AT.w + 3]
    ctx[FL_AT.inertia:FL_AT.inertia + 3] = p[P_AT.inertia:P_AT.inertia + 3]
    ctx[FL_AT.phase] = (p[P_AT.omega] * y[X_AT.t] + p[P_AT.phase]) % (2 * math.pi)
    w = X_AT.w
    rotating = p[P_AT.rotation] != 0.0 and (y[w] != 0.0 or y[w + 1] != 0.0 or y[w + 2] != 0.0)
    ctx[FL_AT.rotating] = 1.0 if rotating else 0.0
    ctx[FL_AT.support] = support(p, rotation(y[X_AT.q:X_AT.q + 4]))
    return ctx


@jit
def state_at(t, ctx, steps, nsteps, p):
    """The state (STATE.size,) at t of the flight ctx with its rotation step table."""
    rv = _translate(p, ctx, t)
    q, w = orient(t, ctx, steps, nsteps)
    y = np.empty(N_STATE)
    y[X_AT.t] = t
    y[X_AT.r:X_AT.r + 3] = rv[0]
    y[X_AT.v:X_AT.v + 3] = rv[1]
    y[X_AT.q:X_AT.q + 4] = q
    y[X_AT.w:X_AT.w + 3] = w
    return y
