"""One flight of the compiled loop, in numba: from a state until the first contact or the end, its
trajectory rows on the way. The rotation integrated by DOP853 step by step (:mod:`.flight_path`, the scan of
:mod:`.roots`), or, when the parameters ask for the exact flight, in closed form (:mod:`symmech.grain.free_flight_nb`:
the contact certified by the gap's curvature bound, as the Python loop's flight with ``Numerics.flight = "exact"``)."""
from __future__ import annotations

import math

import numpy as np

from symmech.numerics.jit import inline, jit
from symmech.grain import free_flight_nb as ff
from symmech.grain.motion_engine.flight_path import extend_rotation, flight_ctx, state_at
from symmech.grain.motion_engine.kinematics import gap_noise
from symmech.grain.motion_engine.layouts import FL_AT, FLIGHT, INT, N_STATE, P_AT, ROT_WIDTH, X_AT
from symmech.grain.motion_engine.roots import GAP, first_root, h_at
from symmech.grain.motion_engine.rows import record


@jit
def _samples(p, t0, t_stop):
    """The range (k0, k1) of k whose sample times k * sample_interval may lie in (t0, t_stop)."""
    k0 = math.ceil(t0 / p[P_AT.sample_interval] - 1e-9)
    return int(k0), int(math.floor(t_stop / p[P_AT.sample_interval] - 1e-9)) + 1


@jit
def scratch():
    """The closed-form flight's work arrays, made once per call of the loop and reused by every flight: its records
    (free_flight.FLIGHT, ROTATION), the translation's buffer (1, 2, 3) and a state (STATE.size,)."""
    return np.empty(ff.FLIGHT_SIZE), np.empty(ff.ROTATION_SIZE), np.empty((1, 2, 3)), np.empty(N_STATE)


@inline
def _rise(p, y, t_end, gap, args):
    """Where a grain on the plane starts its flight: the first ``t = t0 + span / 2**k`` (k = 0 … 63, span the scan
    step or less at the run's end) where ``gap(t, args)`` [m] exceeds the gap's round-off; t_end if the run ends
    before the rise is over (in flight, not resting); NaN if it stays within round-off for a whole scan step
    (resting)."""
    span, noise = min(p[P_AT.scan_step], t_end - y[X_AT.t]), gap_noise(p, y)
    for kk in range(64):
        t = y[X_AT.t] + span / 2.0 ** kk
        if t <= y[X_AT.t]:
            break
        if gap(t, args) > noise:
            return t
    return np.nan if span >= p[P_AT.scan_step] else t_end


# The gaps take their arguments as one tuple: numba inlines no call with *args.
@inline
def _path_gap(t, args):
    """The gap [m] at t of the DOP853 flight; args (ctx, steps, nsteps, p, out): its rotation's steps so far."""
    ctx, steps, nsteps, p, out = args
    return h_at(GAP, t, ctx, steps, nsteps, p, out)


@inline
def _exact_gap(t, args):
    """The gap [m] at t of the closed-form flight; args (fl, rot, buf): its records and buffer."""
    fl, rot, buf = args
    return ff.gap(t, fl, rot, buf)[0]


@inline
def fly(p, y, t_end, on_plane, rows, carry, work):
    """Fly from y until the first contact or t_end: (state, status 0 contact, 1 end, 2 resting, 3 the rotation's
    integration failed, rows); ``work``: :func:`scratch`."""
    if p[P_AT.exact_flight] != 0.0:
        return _fly_exact(p, y, t_end, on_plane, rows, carry, work)
    ctx = flight_ctx(p, y)
    steps = np.empty((64, ROT_WIDTH))
    nsteps = INT(0)
    t_from = y[X_AT.t]
    scan, xtol = p[P_AT.scan_step], p[P_AT.tolerance] * p[P_AT.scan_step]
    if on_plane:
        span = min(scan, t_end - y[X_AT.t])
        steps, nsteps = extend_rotation(y[X_AT.t] + span, y[X_AT.t] + span, ctx, steps, nsteps, p)
        t_from = _rise(p, y, t_end, _path_gap, (ctx, steps, nsteps, p, np.empty((1, 2, 3))))
        if math.isnan(t_from):
            return y, 2, rows
    tc, steps, nsteps = first_root(GAP, t_from, t_end, scan, xtol, ctx, steps, nsteps, p)
    t_stop = t_end if math.isnan(tc) else tc
    steps, nsteps = extend_rotation(t_stop, t_stop, ctx, steps, nsteps, p)
    if ctx[FL_AT.failed] != 0.0:
        return y, 3, rows
    k0, k1 = _samples(p, y[X_AT.t], t_stop)
    for kk in range(k0, k1):
        ts = kk * p[P_AT.sample_interval]
        if y[X_AT.t] < ts < t_stop:
            rows = record(rows, carry, state_at(ts, ctx, steps, nsteps, p), FLIGHT)
    return state_at(t_stop, ctx, steps, nsteps, p), 1 if math.isnan(tc) else 0, rows


@inline
def _exact_records(p, y, fl, rot, start):
    """Fill the exact flight's records ``fl``, ``rot`` (free_flight.FLIGHT, ROTATION) from the state y; a grain that
    does not rotate keeps its attitude (its rate, kept in y, is not applied: ``start``, a state, holds y without it)."""
    source = y
    if p[P_AT.rotation] == 0.0:
        start[:] = y
        start[X_AT.w:X_AT.w + 3] = 0.0
        source = start
    ff.flight_setup(source, p[P_AT.g:P_AT.g + 3], p[P_AT.amplitude], p[P_AT.omega], p[P_AT.phase],
                    p[P_AT.direction:P_AT.direction + 3], p[P_AT.axes:P_AT.axes + 3],
                    p[P_AT.inertia:P_AT.inertia + 3], fl, rot)


@inline
def _exact_state(t, y, fl, rot, p, out):
    """The state (STATE.size,) at t of the exact flight from y, into ``out`` (returned)."""
    ff.flight_state(t, fl, rot, out)
    if p[P_AT.rotation] == 0.0:
        out[X_AT.w:X_AT.w + 3] = y[X_AT.w:X_AT.w + 3]
    return out


@inline
def _fly_exact(p, y, t_end, on_plane, rows, carry, work):
    """``fly`` on the closed-form flight: the rise off the plane, ``next_contact`` (no grazing contact missed),
    the trajectory rows; status 0 contact, 1 end, 2 resting. ``work``: :func:`scratch` (the returned state is new)."""
    fl, rot, buf, state = work
    _exact_records(p, y, fl, rot, state)
    scan = p[P_AT.scan_step]
    t_from = y[X_AT.t]
    if on_plane:
        t_from = _rise(p, y, t_end, _exact_gap, (fl, rot, buf))
        if math.isnan(t_from):
            return y, 2, rows
    tc = ff.next_contact(fl, rot, t_from, t_end, scan, p[P_AT.tolerance] * scan, buf)
    t_stop = t_end if math.isnan(tc) else tc
    k0, k1 = _samples(p, y[X_AT.t], t_stop)
    for kk in range(k0, k1):
        ts = kk * p[P_AT.sample_interval]
        if y[X_AT.t] < ts < t_stop:
            rows = record(rows, carry, _exact_state(ts, y, fl, rot, p, state), FLIGHT)
    return _exact_state(t_stop, y, fl, rot, p, np.empty(N_STATE)), 1 if math.isnan(tc) else 0, rows
