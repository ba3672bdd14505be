"""One flight of the compiled loop, in numba: from a state until the first contact or the end, its
trajectory rows on the way."""
from __future__ import annotations

import math

import numpy as np

from symmech.numerics.jit import jit
from symmech.grain.motion_engine.flight_path import extend_rotation, flight_ctx, state_at
from symmech.grain.motion_engine.kinematics import gap_noise
from symmech.grain.motion_engine.layouts import FL_AT, FLIGHT, INT, P_AT, ROT_WIDTH, X_AT
from symmech.grain.motion_engine.roots import GAP, first_root, h_at
from symmech.grain.motion_engine.rows import record


@jit
def fly(p, y, t_end, on_plane, rows, carry):
    """Fly from y until the first contact or t_end: (state, status 0 contact, 1 end, 2 resting, rows)."""
    ctx = flight_ctx(p, y)
    steps = np.empty((64, ROT_WIDTH))
    nsteps = INT(0)
    t_from = y[X_AT.t]
    scan, xtol = p[P_AT.scan_step], p[P_AT.tolerance] * p[P_AT.scan_step]
    if on_plane:
        span = min(scan, t_end - y[X_AT.t])
        steps, nsteps = extend_rotation(y[X_AT.t] + span, y[X_AT.t] + span, ctx, steps, nsteps, p)
        noise = gap_noise(p, y)
        out = np.empty((1, 2, 3))
        t_from = np.nan
        for kk in range(64):
            t = y[X_AT.t] + span / 2.0 ** kk
            if t <= y[X_AT.t]:
                break
            if h_at(GAP, t, ctx, steps, nsteps, p, out) > noise:
                t_from = t
                break
        if math.isnan(t_from):
            return y, 2, rows
    tc, steps, nsteps = first_root(GAP, t_from, t_end, scan, xtol, ctx, steps, nsteps, p)
    t_stop = t_end if math.isnan(tc) else tc
    steps, nsteps = extend_rotation(t_stop, t_stop, ctx, steps, nsteps, p)
    if ctx[FL_AT.failed] != 0.0:
        return y, 3, rows
    k0 = math.ceil(y[X_AT.t] / p[P_AT.sample_interval] - 1e-9)
    k1 = math.floor(t_stop / p[P_AT.sample_interval] - 1e-9)
    for kk in range(int(k0), int(k1) + 1):
        ts = kk * p[P_AT.sample_interval]
        if y[X_AT.t] < ts < t_stop:
            rows = record(rows, carry, state_at(ts, ctx, steps, nsteps, p), FLIGHT)
    return state_at(t_stop, ctx, steps, nsteps, p), 1 if math.isnan(tc) else 0, rows

