"""The functions of time whose zeros end a phase, and their roots, in numba: the gap of a flight, the normal
force of a sliding grain, a sliding chunk's terminal event on its step's interpolant; the scan of
``contact.first_root`` with Brent's root finder and bounded minimiser (:mod:`symmech.numerics.ode`)."""
from __future__ import annotations

import numpy as np

from symmech.numerics import ode
from symmech.numerics.dop853 import dop_dense_at
from symmech.numerics.jit import jit
from symmech.numerics.radau import radau_dense_at
from symmech.grain.motion_engine.flight_path import extend_rotation, orient, still_gap, translate_into
from symmech.grain.motion_engine.kinematics import EPS, normal_force, rotation, support
from symmech.grain.motion_engine.layouts import FL_AT, INT, N_SLIDE, N_SLIDING, S_AT, SS_AT
from symmech.grain.motion_engine.slip import event_at

SCAN_WINDOW = 32
GAP, NORMAL, EVENT = INT(0), INT(1), INT(2)  # what h_at evaluates


@jit
def h_at(what, t, ctx, steps, nsteps, p, out):
    """GAP: height [m] of the lowest point in flight (out (1, 2, 3) scratch); NORMAL: n(t); EVENT: sliding
    event function."""
    if what == GAP:
        if ctx[FL_AT.rotating] == 0.0:
            return still_gap(p, ctx, t, out)
        q, _ = orient(t, ctx, steps, nsteps)
        translate_into(p, ctx, t, out)
        return out[0, 0, 2] - support(p, rotation(q))
    if what == NORMAL:
        return normal_force(p, t)
    return _event(t, ctx, steps, p)


@jit
def _h_args(t, args):
    """``h_at`` at t with args = (what, ctx, steps, nsteps, p, out): the function of the root finders."""
    what, ctx, steps, nsteps, p, out = args
    return h_at(what, t, ctx, steps, nsteps, p, out)


_roots = ode.roots(_h_args)  # numerics.ode's Brent root finder and bounded minimiser of h_at
brentq, _bounded_min = _roots.brentq, _roots.bounded_min


@jit
def first_root(what, t0, t1, step, xtol, ctx, steps, nsteps, p):
    """First time in (t0, t1] where h reaches zero from above, or NaN (``contact.first_root``, same scan)."""
    start = t0
    hs = np.empty(SCAN_WINDOW + 1)
    ts = np.empty(SCAN_WINDOW + 1)
    out = np.empty((1, 2, 3))
    # Without rotation the scan skips extend_rotation (nothing to do) and calls the gap directly: 2/3 of a
    # sphere's scan.
    rotating, still = what == GAP and ctx[FL_AT.rotating] != 0.0, what == GAP and ctx[FL_AT.rotating] == 0.0
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
                steps, nsteps = extend_rotation(ts[i], ts[n - 1], ctx, steps, nsteps, p)
            hs[i] = still_gap(p, ctx, ts[i], out) if still else h_at(what, ts[i], ctx, steps, nsteps, p, out)
            if i > 0 and hs[i] <= 0.0:
                stop = i
                break
        for j in range(1, min(stop, n - 1)):
            if hs[j] < hs[j - 1] and hs[j] <= hs[j + 1]:  # as contact.first_root: a minimum between equal samples
                x, fx = _bounded_min(ts[j - 1], ts[j + 1], xtol, (what, ctx, steps, nsteps, p, out))
                if fx < 0.0 and hs[j - 1] > 0.0:
                    return brentq(ts[j - 1], x, xtol, (what, ctx, steps, nsteps, p, out)), steps, nsteps
        if stop < n:
            return brentq(ts[stop - 1], ts[stop], xtol, (what, ctx, steps, nsteps, p, out)), steps, nsteps
        if ts[n - 1] >= t1:
            return np.nan, steps, nsteps
        start = ts[n - 2]


@jit
def interp(t, ctx, coef):
    """The interpolant at t of the sliding step ctx (layout ``SLIDE_STEP``), its coefficients coef[0]."""
    if ctx[SS_AT.radau] != 0.0:
        return radau_dense_at(t, ctx[SS_AT.t_old], ctx[SS_AT.h], coef[0])
    return dop_dense_at(t, ctx[SS_AT.t_old], ctx[SS_AT.h], ctx[SS_AT.z_old:SS_AT.z_old + N_SLIDING], coef[0])


@jit
def step_ctx(ctx, t, h, z, radau):
    """Set the sliding step ctx (layout ``SLIDE_STEP``) to the step of length h from (t, z)."""
    ctx[SS_AT.t_old], ctx[SS_AT.h], ctx[SS_AT.radau] = t, h, radau
    ctx[SS_AT.z_old:SS_AT.z_old + N_SLIDING] = z


@jit
def _event(t, ctx, coef, p):
    """Sliding event at t inside the step of ctx (see :func:`interp`)."""
    return event_at(t, interp(t, ctx, coef), ctx[SS_AT.sp:SS_AT.sp + N_SLIDE])


@jit
def locate(event, t, t_new, ctx, coef, p):
    """Time of ``event`` in the step of ctx: Brent on the interpolant to 4 eps (as ``solve_ivp``)."""
    ctx[SS_AT.sp + S_AT.event] = event
    return brentq(t, t_new, 4 * EPS, (EVENT, ctx, coef, INT(0), p, np.empty((1, 2, 3))))

