"""One sliding phase of the compiled loop, in numba (the Python loop's ``_slide`` with ``sliding.slide``): chunks of
DOP853, or of Radau IIA for stiff slips, until lift-off or the end, with the terminal events located on each
step's interpolant, the regime switched at each event, and the trajectory rows at the sample times."""
from __future__ import annotations

import math

import numpy as np

from symmech.numerics.dop853 import dop_dense_at
from symmech.numerics.jit import inline, jit
from symmech.numerics.radau import radau_buffers, radau_dense_at
from symmech.grain import sliding
from symmech.grain.motion_engine.kinematics import EPS, contact_offset, normal_force, rotation
from symmech.grain.motion_engine.layouts import (
    C_AT, DONE, INT, MAX_STALLED_EVENTS, N_FLIGHT, N_SAMPLER, N_SLIDE_STEP, N_SLIDING, P_AT, ROT_WIDTH, S_AT,
    SLIDE_FAIL, SLIDE_RHS, SLIDE_STALLED, SLIDING, SM_AT, SS_AT, X_AT, Z_AT)
from symmech.grain.motion_engine.roots import EVENT, NORMAL, brentq, first_root, interp, locate, step_ctx
from symmech.grain.motion_engine.rows import record
from symmech.grain.motion_engine.slip import (
    EV_FAST, EV_NONE, EV_SLIP, choose_event, event_at, goes_implicit, settle, slide_params, slide_state, slip_events,
    switched)
from symmech.grain.motion_engine.steppers import (
    DOP_EXPONENT, DOP_EXTENDED, DOP_POWER, DOP_STAGES, SLIP, STICK, dop_advance, dop_dense, first_step, radau_start,
    radau_step, rhs)


MAX_STEPS_PER_CHUNK = sliding.MAX_RHS_PER_PHASE // 12  # DOP853 steps (12 evaluations) per sliding chunk
MAX_RADAU_STEPS = sliding.MAX_RHS_PER_PHASE // 4  # Radau steps (at least 4 evaluations) per sliding chunk
# A landing may stick: a numpy bool, typed as bool and not as the literal True, which would compile settle twice.
MAY_STICK = np.bool_(True)
NO_EVENT, REGIME, SWITCH = 0, 1, 2  # how a chunk ends: its end time, a regime event, the integrator switch


@jit
def _sample_rows(rows, carry, rec, t_last, ctx, coef):
    """Trajectory rows at the sample times before t_last from the step of ctx (coefficients coef); rec the
    sampler (layout ``SAMPLER``), its next index advanced."""
    while rec[SM_AT.next] * rec[SM_AT.interval] < t_last:
        ts = rec[SM_AT.next] * rec[SM_AT.interval]
        if ts >= rec[SM_AT.t_start]:
            rows = record(rows, carry, slide_state(ts, interp(ts, ctx, coef), rec[SM_AT.height]), SLIDING)
        rec[SM_AT.next] += 1.0
    return rows


@inline
def _dop_chunk(p, kind, t, z, t_chunk, sp, atol, ctx, rows, carry, rec):
    """One integration chunk by DOP853 (a fresh ``solve_ivp`` of the Python loop) until t_chunk or the
    terminal event of sp: (t, z, event NO_EVENT / REGIME / SWITCH, rows, status)."""
    tol = p[P_AT.tolerance]
    g_old = event_at(t, z, sp) if sp[S_AT.event] != EV_NONE else 0.0
    f = np.empty(N_SLIDING)
    rhs(t, z, (kind, sp), f)
    h_abs = first_step(t, z, f, t_chunk, (kind, sp), tol, atol, -DOP_EXPONENT)
    K = np.empty((DOP_EXTENDED, N_SLIDING))
    F = np.empty((1, DOP_POWER * N_SLIDING))
    ctx[SS_AT.sp:] = sp
    for _ in range(MAX_STEPS_PER_CHUNK):
        if not t < t_chunk:
            return t, z, NO_EVENT, rows, DONE
        t_new, z_new, h_abs, ok = dop_advance(t, z, f, h_abs, t_chunk, (kind, sp), tol, atol, K)
        if not ok:
            return t, z, NO_EVENT, rows, SLIDE_FAIL
        g_new = event_at(t_new, z_new, sp) if sp[S_AT.event] != EV_NONE else 0.0
        fired = sp[S_AT.event] != EV_NONE and g_old >= 0.0 and g_new <= 0.0
        t_last = t_new
        if fired or rec[SM_AT.next] * rec[SM_AT.interval] < t_new:
            F[0] = dop_dense(t, t_new - t, z, z_new, (kind, sp), K).reshape(DOP_POWER * N_SLIDING)
            step_ctx(ctx, t, t_new - t, z, 0.0)
        if fired:
            t_last = brentq(t, t_new, 4 * EPS, (EVENT, ctx, F, INT(0), p, np.empty((1, 2, 3))))
            z_new = dop_dense_at(t_last, t, t_new - t, z, F[0])
        rows = _sample_rows(rows, carry, rec, t_last, ctx, F)
        if fired:
            return t_last, z_new, SWITCH if switched(z_new, sp) else REGIME, rows, DONE
        t, z, f, g_old = t_new, z_new, K[DOP_STAGES].copy(), g_new
    return t, z, NO_EVENT, rows, DONE if t >= t_chunk else SLIDE_RHS


@inline
def _radau_chunk(p, t, z, t_chunk, sp, atol, ctx, rows, carry, rec):
    """One chunk of a stiff slip by Radau (a fresh ``solve_ivp(method="Radau")`` of the Python loop) until
    t_chunk or the first terminal event: the slip stops (along sp's reference direction) or its speed rises
    through 2 s_stiff (back to DOP853). Returns (t, z, event, rows, status, accepted steps)."""
    tol = p[P_AT.tolerance]
    f = np.empty(N_SLIDING)
    rhs(t, z, (SLIP, sp), f)
    J, LUr, pr, LUc, pc, Q = radau_buffers(N_SLIDING)
    st = radau_start(t, z, f, t_chunk, (SLIP, sp), tol, atol, J)
    ctx[SS_AT.sp:] = sp
    stops, speed = slip_events(z, sp)
    for k in range(MAX_RADAU_STEPS):
        if not t < t_chunk:
            return t, z, NO_EVENT, rows, DONE, k
        t_new, z_new, f, ok = radau_step(t, z, f, t_chunk, (SLIP, sp), tol, atol, st, J, LUr, pr, LUc, pc, Q)
        if not ok:
            return t, z, NO_EVENT, rows, SLIDE_FAIL, k
        stops_new, speed_new = slip_events(z_new, sp)
        step_ctx(ctx, t, t_new - t, z, 1.0)
        fast, fast_new = speed - 2.0 * sp[S_AT.v_stiff], speed_new - 2.0 * sp[S_AT.v_stiff]
        t_stops = locate(EV_SLIP, t, t_new, ctx, Q, p) if stops >= 0.0 and stops_new <= 0.0 else np.inf
        t_fast = locate(EV_FAST, t, t_new, ctx, Q, p) if fast <= 0.0 and fast_new >= 0.0 else np.inf
        t_last = min(t_stops, t_fast, t_new)
        rows = _sample_rows(rows, carry, rec, t_last, ctx, Q)
        if min(t_stops, t_fast) < np.inf:
            z_last = radau_dense_at(t_last, t, t_new - t, Q[0])
            return t_last, z_last, REGIME if t_stops <= t_fast else SWITCH, rows, DONE, k + 1
        t, z, stops, speed = t_new, z_new, stops_new, speed_new
    return t, z, NO_EVENT, rows, DONE if t >= t_chunk else SLIDE_RHS, MAX_RADAU_STEPS


@inline
def slide(p, y, t_end, rows, carry):
    """One sliding phase from state y (the Python loop's ``_slide`` with ``sliding.slide``): (state, lifted, rows,
    status)."""
    t0 = y[X_AT.t]
    step, tol = p[P_AT.scan_step], p[P_AT.tolerance]
    if normal_force(p, t0) > 0:
        no_flight, no_steps = np.empty(N_FLIGHT), np.empty((1, ROT_WIDTH))  # n(t) reads neither
        t_lift = first_root(NORMAL, t0, t_end, step, tol * step, no_flight, no_steps, INT(0), p)[0]
    else:
        t_lift = t0
    t_stop = t_end if math.isnan(t_lift) else t_lift
    Q0 = rotation(y[X_AT.q:X_AT.q + 4])
    sp = slide_params(p, Q0, contact_offset(p, Q0), p[P_AT.mu])
    z = np.empty(N_SLIDING)
    z[Z_AT.r:Z_AT.r + 2] = y[X_AT.r:X_AT.r + 2]
    z[Z_AT.v:Z_AT.v + 2] = y[X_AT.v:X_AT.v + 2]
    z[Z_AT.w:Z_AT.w + 3] = Q0 @ y[X_AT.w:X_AT.w + 3]
    z[Z_AT.q:Z_AT.q + 4] = y[X_AT.q:X_AT.q + 4]
    z[Z_AT.work] = z[Z_AT.loss] = 0.0
    g = math.sqrt(p[P_AT.g:P_AT.g + 3] @ p[P_AT.g:P_AT.g + 3])
    v_scale = (g + abs(normal_force(p, t0))) * step
    sp[S_AT.v_stop] = tol * v_scale
    sp[S_AT.v_stiff] = tol**sliding.SLIP_STIFF_POWER * v_scale
    a_min = min(p[P_AT.axes], p[P_AT.axes + 1], p[P_AT.axes + 2])
    scale = np.empty(N_SLIDING)  # of each component, times tol v_scale: its absolute tolerance
    scale[Z_AT.r:Z_AT.r + 2], scale[Z_AT.v:Z_AT.v + 2], scale[Z_AT.w:Z_AT.w + 3] = step, 1.0, 1 / a_min
    scale[Z_AT.q:Z_AT.q + 4], scale[Z_AT.work], scale[Z_AT.loss] = 1 / v_scale, v_scale, v_scale
    atol = tol * v_scale * scale
    stick, z = settle(t0, z, sp, MAY_STICK)
    t, stalled, status, implicit = t0, 0, DONE, False
    ctx = np.empty(N_SLIDE_STEP)
    rec = np.empty(N_SAMPLER)
    rec[SM_AT.next] = float(math.ceil(t0 / p[P_AT.sample_interval] - 1e-9))
    rec[SM_AT.interval], rec[SM_AT.t_start], rec[SM_AT.height] = p[P_AT.sample_interval], t0, y[X_AT.r + 2]
    while t < t_stop and status == DONE:
        implicit = goes_implicit(z, sp, stick, 2.0 if implicit else 1.0)
        choose_event(z, sp, stick)
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
            stick, z = settle(t, z, sp, not stick)
    carry[C_AT.work] += p[P_AT.mass] * z[Z_AT.work]
    carry[C_AT.slide_loss] += p[P_AT.mass] * z[Z_AT.loss]
    end = slide_state(t, z, y[X_AT.r + 2])
    rows = record(rows, carry, end, SLIDING)
    return end, (not math.isnan(t_lift)) and t >= t_lift, rows, status

