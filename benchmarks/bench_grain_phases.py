"""Where the default grain scene's CPU goes, per phase of the compiled loop.

The scene (``scenes/grain_default.toml``, 2 s) is run once phase by phase (``loop.run`` with one phase per call),
which records each phase's start (state and carry). Each phase is then replayed from its start, alone, in CPU
time (``time.process_time_ns``; medians of ``--repeats`` rounds per phase, summed over the phases), with
parameter variants that leave the phase's path unchanged and drop one part of its work:

- flights: the whole phase (flight, impact or landing); no trajectory rows (``sample_interval`` 1e9 s); no
  check of the printed law (``check_printed`` 0: the log's two flags only); the flight alone (``max_impacts`` 0:
  the phase stops at the contact);
- slides: the whole phase; no trajectory rows.

The difference of two variants is that part's cost. A call from Python costs a few us more than the phase inside the
whole run (argument unboxing, cold caches), measured alone (a call doing nothing) and subtracted; the sum is therefore
compared with the whole run timed in one call (``loop.run`` for all phases), reported beside it.

``--impact-alone``: instead, the impact law alone (``impact_law.impact``) on the run's pre-impact states (the first
of each pair of IMPACT trajectory rows), in one compiled loop, CPU per impact with and without the printed law's check.

Run: python benchmarks/bench_grain_phases.py [--repeats 7] [--impact-alone] (numba's cache built: ``symmech warm
--engine grain``)
"""
from __future__ import annotations

import argparse
import os
import time

import numba
import numpy as np

from timing import machine

from symmech.core import pipeline
from symmech.grain.motion_engine import driver, loop
from symmech.grain.motion_engine.impact_law import impact
from symmech.grain.motion_engine.layouts import (
    C_AT, CARRY, FLIGHT, IMPACT, IMPACT_WIDTH, INT, MORE, P_AT, STATE, T_AT, TRAJECTORY_WIDTH, WARNING_WIDTH)


def buffers():
    return np.empty((4096, TRAJECTORY_WIDTH)), np.empty((1024, IMPACT_WIDTH)), np.empty((64, WARNING_WIDTH))


def record_phases(p, y0, t_end):
    """[(regime, state before, carry before)] of every phase of the run from y0, and the run's final carry."""
    rows, imps, warns = buffers()
    carry, y = CARRY.zeros(), y0.copy()
    y, rows, imps, warns, status = loop.run(p, y, t_end, rows, imps, warns, carry, INT(0))  # the start only
    phases = []
    while status == MORE:
        before = (int(carry[C_AT.regime]), y.copy(), carry.copy())
        y, rows, imps, warns, status = loop.run(p, y, t_end, rows, imps, warns, carry, INT(1))
        phases.append(before)
    return phases, carry


def replay(phases, p, t_end, repeats):
    """CPU us of each phase replayed from its start with parameters p: medians of ``repeats`` rounds (phases,)."""
    rows, imps, warns = buffers()
    times = np.empty((repeats, len(phases)))
    for r in range(repeats):
        for k, (_, y, carry) in enumerate(phases):
            c, yy = carry.copy(), y.copy()
            c[C_AT.rows] = c[C_AT.nimp] = c[C_AT.nwarn] = 0.0  # the phase's rows into the buffers' start
            start = time.process_time_ns()
            loop.run(p, yy, t_end, rows, imps, warns, c, INT(1))
            times[r, k] = time.process_time_ns() - start
    return np.median(times, axis=0) / 1e3


def call_cost(p, y0, t_end, repeats=2000):
    """CPU us of a call that runs no phase (a started carry, max_phases 0): what each replayed phase pays more."""
    rows, imps, warns = buffers()
    carry, times = CARRY.zeros(), []
    for _ in range(repeats):
        carry[C_AT.rows] = 1.0
        start = time.process_time_ns()
        loop.run(p, y0.copy(), t_end, rows, imps, warns, carry, INT(0))
        times.append(time.process_time_ns() - start)
    return float(np.median(times)) / 1e3


def whole_run(p, y0, t_end, repeats):
    """CPU ms of the whole run in one call of ``loop.run``: median and min of ``repeats``."""
    times = []
    for _ in range(repeats):
        rows, imps, warns = buffers()
        start = time.process_time_ns()
        loop.run(p, y0.copy(), t_end, rows, imps, warns, CARRY.zeros(), INT(1 << 30))
        times.append(time.process_time_ns() - start)
    return float(np.median(times)) / 1e6, min(times) / 1e6


@numba.njit(cache=True, error_model="numpy")
def _impacts(p, states, carry, rounds):
    """impact_law.impact on every state (n, STATE.size), ``rounds`` times; the warning count reset each call."""
    warns = np.empty((64, WARNING_WIDTH))
    after = states.copy()
    for _ in range(rounds):
        for i in range(states.shape[0]):
            carry[C_AT.nwarn] = 0.0
            after[i], _, warns = impact(p, states[i], warns, carry)
    return after


def impact_alone(p, y0, t_end, repeats, rounds=100):
    """CPU us per impact of the impact law alone on the run's pre-impact states: (median, min) of ``repeats``, and
    the number of impacts."""
    rows, imps, warns = buffers()
    carry = CARRY.zeros()
    _, rows, _, _, _ = loop.run(p, y0.copy(), t_end, rows, imps, warns, carry, INT(1 << 30))
    rows = rows[:int(carry[C_AT.rows])]
    at_impact = rows[rows[:, T_AT.regime] == IMPACT]  # pairs (before, after); a row starts with the state
    states = np.ascontiguousarray(at_impact[0::2, :STATE.size])
    _impacts(p, states, CARRY.zeros(), 1)
    times = []
    for _ in range(repeats):
        start = time.process_time_ns()
        _impacts(p, states, CARRY.zeros(), rounds)
        times.append((time.process_time_ns() - start) / 1e3 / rounds / len(states))
    return float(np.median(times)), min(times), len(states)


def variant(p, **fields):
    q = p.copy()
    for name, value in fields.items():
        q[getattr(P_AT, name)] = value
    return q


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--impact-alone", action="store_true", help="the impact law alone on the run's impact states")
    ns = ap.parse_args()
    print(f"machine: {machine()}; load average {os.getloadavg()[0]:.1f}")
    sc = pipeline.load("scenes/grain_default.toml").setup
    p, y0 = driver.pack(sc.model, sc.numerics), driver.start_vector(sc.model, sc.start)
    t_end = sc.start.t + sc.duration
    if ns.impact_alone:
        for label, q in (("with the printed law's check", p), ("Coulomb law alone", variant(p, check_printed=0.0))):
            median, least, n = impact_alone(q, y0, t_end, ns.repeats)
            print(f"impact law alone, {label:<28} {median:6.3f} us per impact (min {least:.3f}; {n} impacts)")
        return
    phases, carry = record_phases(p, y0, t_end)
    flights = [ph for ph in phases if ph[0] == FLIGHT]
    slides = [ph for ph in phases if ph[0] != FLIGHT]
    nimp = int(carry[C_AT.nimp])
    print(f"default scene, {t_end - sc.start.t} s: {nimp} impacts, {int(carry[C_AT.landings])} landings, "
          f"{len(flights)} flight and {len(slides)} sliding phases, {int(carry[C_AT.implicit])} Radau steps; "
          f"time in flight {carry[C_AT.t_flight]:.3f} s, sliding {carry[C_AT.t_sliding]:.3f} s")
    cost = call_cost(p, y0, t_end)
    median, least = whole_run(p, y0, t_end, ns.repeats)
    print(f"whole run in one call: {median:.2f} ms CPU (min {least:.2f}) = {nimp / median * 1e3:,.0f} impacts per "
          f"CPU-second; a replayed phase's call costs {cost:.2f} us more (subtracted below)")
    cases = [("flights", flights, "whole phase (flight + impact or landing)", p),
             ("flights", flights, "no trajectory rows", variant(p, sample_interval=1e9)),
             ("flights", flights, "no check of the printed law", variant(p, check_printed=0.0)),
             ("flights", flights, "flight alone (stops at the contact)", variant(p, max_impacts=0.0)),
             ("flights", flights, "flight alone, no rows", variant(p, max_impacts=0.0, sample_interval=1e9)),
             ("slides", slides, "whole phase", p),
             ("slides", slides, "no trajectory rows", variant(p, sample_interval=1e9))]
    for what, phs, label, q in cases:
        us = replay(phs, q, t_end, ns.repeats) - cost
        print(f"{what:<8} {label:<44} {us.sum() / 1e3:7.2f} ms  ({us.sum() / nimp:6.2f} us per impact; median "
              f"phase {np.median(us):.2f} us)")


if __name__ == "__main__":
    main()
