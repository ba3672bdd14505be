"""The compiled engine's loop in numba: the per-grain event loop of :mod:`symmech.grain.motion`, its phases
(:mod:`.flight_phase`, :mod:`.landing`, :mod:`.sliding_phase`) strung together, and ``run``, the entry from Python.

The Python side (parameters, results, errors, the entry it calls) is :mod:`symmech.grain.motion_engine.driver`,
which imports no numba: a warm run whose loop was built ahead of time loads that build instead of
this module. The physics, the event logic and their contract are described there. ``run_many`` runs a population
in one call (the driver's ``simulate_many``): each grain exactly as ``run``, the results one grain after another."""
from __future__ import annotations

import numpy as np

from symmech.numerics.jit import inline, jit
from symmech.grain.motion_engine.flight_phase import fly, scratch
from symmech.grain.motion_engine.kinematics import (
    contact_velocity, energy, gap, gap_noise, normal_force, velocity_noise)
from symmech.grain.motion_engine.landing import bounce, land
from symmech.grain.motion_engine.layouts import (
    C_AT, DONE, FLIGHT, IMPACT_WIDTH, MAX_IDLE_STEPS, MORE, P_AT, PHASES_PER_CALL, ROT_FAIL, SLIDING, STALLED,
    TRAJECTORY_WIDTH, W_MAX_IMPACTS, WARNING_WIDTH, X_AT)
from symmech.grain.motion_engine.rows import record, warn
from symmech.grain.motion_engine.sliding_phase import slide


@inline
def _start(p, y, rows, carry):
    """First row and the release rule of ``motion.simulate``; sets the regime and on_plane in carry."""
    carry[C_AT.regime], carry[C_AT.on_plane] = FLIGHT, 1.0 if gap(p, y) <= gap_noise(p, y) else 0.0
    rows = record(rows, carry, y, FLIGHT)
    if (carry[C_AT.on_plane] != 0.0 and contact_velocity(p, y) <= velocity_noise(p, y)
            and normal_force(p, y[X_AT.t]) > 0):
        carry[C_AT.regime], carry[C_AT.on_plane] = SLIDING, 0.0
        y = land(p, y, carry)
    return y, rows


@inline
def run_phases(p, y, t_end, rows, imps, warns, carry, max_phases):
    """At most ``max_phases`` regime phases of the loop of ``motion.simulate`` from state y (14,);
    returns (y, rows, imps, warns, status)."""
    work = scratch()
    for _ in range(max_phases):
        if not y[X_AT.t] < t_end:
            return y, rows, imps, warns, DONE
        t_before = y[X_AT.t]
        if carry[C_AT.regime] == FLIGHT:
            y, fly_status, rows = fly(p, y, t_end, carry[C_AT.on_plane] != 0.0, rows, carry, work)
            carry[C_AT.t_flight] += y[X_AT.t] - t_before
            if fly_status == 1:
                return y, rows, imps, warns, DONE
            if fly_status == 3:
                return y, rows, imps, warns, ROT_FAIL
            u_n = 0.0
            if fly_status == 0 and contact_velocity(p, y) < -velocity_noise(p, y):
                if carry[C_AT.nimp] >= p[P_AT.max_impacts]:
                    warns = warn(warns, carry, W_MAX_IMPACTS, y[X_AT.t], p[P_AT.max_impacts])
                    return y, rows, imps, warns, DONE
                y, u_n, rows, imps, warns = bounce(p, y, rows, imps, warns, carry)
            carry[C_AT.on_plane] = 1.0
            if u_n <= p[P_AT.rest_velocity] and normal_force(p, y[X_AT.t]) > 0:
                carry[C_AT.regime], carry[C_AT.on_plane] = SLIDING, 0.0
                carry[C_AT.landings] += 1
                y = land(p, y, carry)
            elif fly_status == 2:  # held on a plane that pulls away: a rocking contact (not modelled)
                carry[C_AT.rocking] += 1
                y = land(p, y, carry)
        else:
            y, lifted, rows, status = slide(p, y, t_end, rows, carry)
            carry[C_AT.t_sliding] += y[X_AT.t] - t_before
            if status != DONE:
                return y, rows, imps, warns, status
            if lifted:
                carry[C_AT.regime], carry[C_AT.on_plane] = FLIGHT, 1.0
        carry[C_AT.idle] = carry[C_AT.idle] + 1 if y[X_AT.t] == t_before else 0
        if carry[C_AT.idle] > MAX_IDLE_STEPS:
            return y, rows, imps, warns, STALLED
    return y, rows, imps, warns, MORE if y[X_AT.t] < t_end else DONE


@jit
def run(p, y, t_end, rows, imps, warns, carry, max_phases):
    """The entry from Python: ``_start`` on a fresh carry (no rows yet), ``run_phases``, and the last row
    once done, in one call, with the energies of the budget at the start and the end (in the carry);
    returns (y, rows, imps, warns, status)."""
    if carry[C_AT.rows] == 0:
        carry[C_AT.e_start] = energy(p, y)
        y, rows = _start(p, y, rows, carry)
    y, rows, imps, warns, status = run_phases(p, y, t_end, rows, imps, warns, carry, max_phases)
    if status == DONE:
        rows = record(rows, carry, y, int(carry[C_AT.regime]))
        carry[C_AT.e_end] = energy(p, y)
    return y, rows, imps, warns, status


@jit
def _append(into, n, rows, count):
    """rows[:count] appended to into[:n] (doubled when full); returns (into, n + count)."""
    if n + count > into.shape[0]:
        grown = np.empty((max(2 * into.shape[0], n + count), into.shape[1]))
        grown[:n] = into[:n]
        into = grown
    into[n:n + count] = rows[:count]
    return into, n + count


@jit
def run_many(ps, ys, t_ends, row_hint, carries, statuses):
    """A population, grain k = 0..n-1 after grain, each as ``run`` called until it is done or fails (no return to
    Python between its phases): parameters ps (n, PARAMS.size), start states ys (n, STATE.size) replaced by the
    final ones, ends t_ends (n,) [s], ``row_hint`` trajectory rows a grain's buffer starts with, carries
    (n, CARRY.size) zeros filled as ``run``'s, statuses (n,) filled. Returns the trajectory, impact and warning rows
    of every grain one after another (a grain's counts: its carry's rows, nimp, nwarn)."""
    n = ys.shape[0]
    rows, imps, warns = np.empty((row_hint, TRAJECTORY_WIDTH)), np.empty((64, IMPACT_WIDTH)), np.empty((8, WARNING_WIDTH))
    all_rows, all_imps, all_warns = np.empty((n * row_hint, TRAJECTORY_WIDTH)), np.empty((64, IMPACT_WIDTH)), np.empty(
        (8, WARNING_WIDTH))
    nr, ni, nw = 0, 0, 0
    for k in range(n):
        y, status, carry = ys[k].copy(), MORE, carries[k]
        while status == MORE:
            y, rows, imps, warns, status = run(ps[k], y, t_ends[k], rows, imps, warns, carry, PHASES_PER_CALL)
        ys[k], statuses[k] = y, status
        all_rows, nr = _append(all_rows, nr, rows, int(carry[C_AT.rows]))
        all_imps, ni = _append(all_imps, ni, imps, int(carry[C_AT.nimp]))
        all_warns, nw = _append(all_warns, nw, warns, int(carry[C_AT.nwarn]))
    return all_rows[:nr], all_imps[:ni], all_warns[:nw]
