"""Accurate mode compiled: the whole per-grain event loop of :mod:`symmech.grain.motion` in numba.

The loop, its regimes and its rules are those of ``motion.simulate`` (the Python
loop stays the reference; the tests compare the two), with the physics taken from
the generated scalar kernels (``grain_motion_nb``, ``grain_impact_nb``):

- flight: exact translation of the centre in the local time since the last event
  (generated ``flight_translation_into``); torque-free rotation by DOP853
  (scipy's, ported: the same steps as the Python loop's ``solve_ivp``, error per
  step held to ``tolerance`` relative, ``tolerance * 1e-3`` absolute); the
  orientation inside an accepted step is its 7th-order dense interpolant, smooth
  in time, so the root finders see a smooth gap; with ``Numerics.flight = "exact"``
  the rotation in closed form instead and the contact search of the Python loop's
  exact flight (:mod:`symmech.grain.free_flight_nb`: samples certified by the gap's
  curvature bound, Brent), no integration;
- contact: the gap is scanned at ``scan_step`` in windows of 32 points exactly as
  :func:`symmech.grain.contact.first_root`; a sign change is refined by Brent's
  method (scipy's ``brentq``, ported) to ``tolerance * scan_step`` on the time;
  a scan minimum is searched by the bounded Brent minimiser (scipy's, ported)
  for a grazing contact; the scan evaluates the gap only up to the first point
  at or below zero, which is all the Python scan uses of its window;
- impact: the Chatterjee-Ruina law, and the printed law by the exact reduction
  (the trigonometric equation of ``mu_equation``, its quartic's roots by the
  Durand-Kerner iteration, polished by Newton) for the law itself or for its
  verdict in the log;
- sliding: the ODE of :mod:`symmech.grain.sliding` (stick, slip, spin about the
  normal, work and loss as quadratures) by the same DOP853 with
  terminal events located by Brent on the step; stiff slips (anisotropic, below
  the stiff slip speed) by Radau IIA of order 5 (scipy's ``Radau``, ported:
  step control, simplified Newton on the real / complex split of the collocation
  system, embedded error estimate, dense output; unlike scipy, no step growth
  right after a Newton failure, RADAU5's rule, so its steps differ from the
  Python loop's within the tolerance) with the analytic Jacobian of
  the slip, switching as ``sliding.slide`` does; lift-off from the root of n(t).

The loop is :mod:`symmech.grain.motion_engine.loop` and the modules beside it, a phase or a concept each
(docs/ARCHITECTURE.md); this module is its Python side and imports no numba. The generic integrators and root
finders (DOP853, Radau IIA with dense output, Brent) are those of :mod:`symmech.numerics.ode`, compiled for the
rotation and sliding right-hand sides (:mod:`.steppers`) and the functions of time (:mod:`.roots`); the loop
keeps the physics and the event logic.

Parameters travel in one float64 vector (layout :data:`layouts.PARAMS`), the state as
(t, r (3), v (3), q (4), w body (3)) (``STATE``); results come back as growing arrays
(trajectory rows, impact rows, warning codes) and are turned into a
``motion.Motion`` with the same structure as the Python loop's (its impact log
built on first read: ``motion.ImpactLog``). The compiled loop returns to Python every ``PHASES_PER_CALL`` regime phases so that
``on_step`` is called; this does not change the result. ``simulate_many`` runs
grains on threads (the loop releases the GIL). Once ``symmech warm`` or the background builder has built the
loop ahead of time (:mod:`symmech.numerics.aot`), a run on the main thread calls that build: nothing of numba is
loaded; threads call numba's, which releases the GIL.
"""
from __future__ import annotations

import os
import threading
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from symmech.core import layout
from symmech.numerics import aot, artifacts, build
from symmech.core.scene import SymmechError
from symmech.grain import motion, outcome, sliding
from symmech.grain.motion_engine import layouts
from symmech.grain.motion_engine.layouts import (  # noqa: F401 (LAYOUTS: the engine protocol reads it here)
    LAYOUTS, PARAMS, STATE, CARRY, IMPACT_ROW, C_AT, X_AT, LAW_COULOMB, LAW_PRINTED, INT, DONE, MORE, STALLED,
    SLIDE_STALLED, SLIDE_RHS, SLIDE_FAIL, W_MAX_IMPACTS, W_CHATTER, W_PRINTED_ENERGY, W_PRINTED_PULLS,
    W_PRINTED_RESIDUAL, IMPACT_WIDTH, TRAJECTORY_WIDTH, WARNING_WIDTH, PHASES_PER_CALL, COLD_COMPILE_SECONDS,
    ZENO_IMPACTS, ZENO_INTERVAL, MAX_IDLE_STEPS, MAX_STALLED_EVENTS)


# --------------------------------------------------------------------------- Python side


def pack(model: motion.Model, num: motion.Numerics) -> np.ndarray:
    """The parameter vector (PARAMS.size,) of a model and its numerics (layout :data:`PARAMS`); a ValueError naming
    the parameters that are NaN."""
    vib, law = model.vibration, model.law
    p = PARAMS.pack(
        axes=model.axes, mass=model.mass, inertia=model.inertia, g=model.g_k, amplitude=vib.amplitude,
        omega=vib.omega, phase=vib.phase, direction=vib.direction,
        law=LAW_PRINTED if law.kind == "printed" else LAW_COULOMB, e_n=law.e_n, e_t=law.e_t, mu_impact=law.mu,
        e=law.e, lam=law.lam, check_printed=law.check_printed, mu=model.mu, rotation=model.effects.rotation,
        tolerance=num.tolerance, scan_step=num.scan_step, rest_velocity=num.rest_velocity,
        max_impacts=num.max_impacts, sample_interval=num.sample_interval, period=model.period,
        exact_flight=closed_form_flight(model, num))
    if np.isnan(p).any():  # a NaN (a NaN e_t, say) sends the compiled loop on without end: refused here, by name
        nan = [name for name, value in PARAMS.unpack(p).items() if np.isnan(value).any()]
        raise ValueError(f"grain engine: parameter {', '.join(nan)} is NaN")
    return p


def packs(models: list, num: motion.Numerics) -> np.ndarray:
    """:func:`pack` of each grain's model (grains, PARAMS.size), equal models packed once: a model equal to the one
    before it (the usual population: one model) is found by one comparison, others through a dict (a hash and a
    comparison: twice the time of the comparison, on a frozen dataclass ~1.5 us)."""
    distinct, which, last, row = {}, [], None, -1  # model -> its row; each grain's row
    for model in models:
        if model is not last and model != last:
            last, row = model, distinct.setdefault(model, len(distinct))
        which.append(row)
    return np.array([pack(model, num) for model in distinct]).reshape(len(distinct), PARAMS.size)[which]


def closed_form_flight(model: motion.Model, num: motion.Numerics) -> bool:
    """Whether the loop flies in closed form (:mod:`symmech.grain.free_flight_nb`): when asked (``flight =
    "exact"``), and by default (``"auto"``) where that is exact at no cost: a grain whose gap does not depend on
    its attitude (a sphere, or any grain with rotation off), whose rotation is one at a constant rate (or none)."""
    if num.flight == "auto":
        return not model.effects.rotation or min(model.axes) == max(model.axes)
    return num.flight == "exact"


def warning_text(code: int, a: float, b: float, model: motion.Model, num: motion.Numerics) -> str:
    """The text of a warning row (code, a, b), as the Python loop words it (:mod:`symmech.grain.outcome`)."""
    if code == W_MAX_IMPACTS:
        return outcome.max_impacts_warning(a, num.max_impacts)
    if code == W_CHATTER:
        return outcome.chatter_warning(ZENO_IMPACTS, ZENO_INTERVAL)
    if code in (W_PRINTED_ENERGY, W_PRINTED_PULLS):
        return outcome.printed_inadmissible_warning(code == W_PRINTED_ENERGY)
    if code == W_PRINTED_RESIDUAL:
        return outcome.printed_residual_warning(a)
    return outcome.energy_created_warning(model.law.kind, a, b)


FLAGS = (None, False, True)  # a flag column + 1: not checked, no, yes
FLAG_FIELDS = ("admissible", "printed_admissible", "printed_creates_energy", "converged")
# Where each value of an impact row is: a slot for a scalar, a slice for a vector (read from a row as a list).
IMPACT_VALUES = {f.name: IMPACT_ROW.slice(f.name) if f.shape else IMPACT_ROW.offset(f.name)
                 for f in IMPACT_ROW.fields if f.name not in FLAG_FIELDS}


IMPACT_KEYS = (*IMPACT_VALUES, *FLAG_FIELDS)
T_COLUMN = IMPACT_ROW.offset("t")


def impact_log(imps: np.ndarray) -> list:
    """The impact log (the keys of ``motion.impact_record``) from the compiled impact rows (n, IMPACT_WIDTH), built
    column by column (half the time of building each dict from its row)."""
    columns = [imps[:, at].tolist() for at in IMPACT_VALUES.values()]
    flags = (imps[:, [IMPACT_ROW.offset(name) for name in FLAG_FIELDS]] + 1.0).astype(INT)
    columns += [[FLAGS[code] for code in column] for column in flags.T.tolist()]
    return [dict(zip(IMPACT_KEYS, values)) for values in zip(*columns)]


STATE_VECTORS = tuple(STATE.slice(name) for name in ("r", "v", "q", "w"))  # motion.State's order


def state_view(y: np.ndarray) -> motion.State:
    """The state (STATE.size,) y as a ``motion.State`` of views of y (y belongs to one result); not
    ``STATE.unpack``, which takes 3 us more of a 0.2 ms run."""
    return motion.State(float(y[X_AT.t]), *[y[at] for at in STATE_VECTORS])


def deferred_log(imps: np.ndarray) -> motion.ImpactLog:
    """The impact log of the compiled impact rows (n, IMPACT_WIDTH), built by :func:`impact_log` on first read."""
    return motion.ImpactLog(imps, impact_log, T_COLUMN)


def energy_budget(carry: np.ndarray) -> dict:
    """The energy budget of a finished run from its carry (CARRY.size,): the energies at the start and the end come
    from the compiled entry (no compiled function of their own to load, no 30 us of numpy kinematics in Python)."""
    budget = outcome.EnergyBudget(float(carry[C_AT.e_start]), carry[C_AT.work], carry[C_AT.impacts],
                                  carry[C_AT.land_loss], carry[C_AT.slide_loss])
    return budget.report(float(carry[C_AT.e_end]), motion.ENERGY_TOLERANCE)


def energy_budgets(carries: np.ndarray) -> list:
    """:func:`energy_budget` of each of the finished runs' carries (n, CARRY.size), built in bulk (equal, bit for
    bit, to each run's own)."""
    c = carries.T
    return outcome.budget_reports(c[C_AT.e_start], c[C_AT.e_end], c[C_AT.work], c[C_AT.impacts], c[C_AT.land_loss],
                                  c[C_AT.slide_loss], motion.ENERGY_TOLERANCE)


def failure(status: int, t: float, regime: int) -> SymmechError:
    """The Python loop's error for a compiled loop's failure code."""
    if status == STALLED:
        return SymmechError(outcome.stalled_error(t, MAX_IDLE_STEPS, motion.REGIMES[regime]))
    if status == SLIDE_STALLED:
        return SymmechError(outcome.sliding_stalled_error(t, MAX_STALLED_EVENTS))
    if status == SLIDE_RHS:
        return SymmechError(outcome.sliding_evaluations_error(t, sliding.MAX_RHS_PER_PHASE))
    what = "sliding integration" if status == SLIDE_FAIL else "torque-free rotation"
    return SymmechError(outcome.integration_failed_error(
        what, t, "required step size is less than spacing between numbers"))


def start_vector(model: motion.Model, start: motion.State) -> np.ndarray:
    """The loop's start state (STATE.size,): q normalised, no spin when the model does not rotate."""
    q = np.asarray(start.q, float)
    w = start.w if model.effects.rotation else (0.0, 0.0, 0.0)
    return STATE.pack(t=start.t, r=start.r, v=start.v, q=q / np.linalg.norm(q), w=w)


def start_vectors(models: list, starts: list) -> np.ndarray:
    """:func:`start_vector` of each grain (grains, STATE.size), built in bulk (equal to each, bit for bit)."""
    ys = np.empty((len(starts), STATE.size))
    ys[:, X_AT.t] = [st.t for st in starts]
    for at, name in zip(STATE_VECTORS, ("r", "v", "q", "w")):
        ys[:, at] = np.array([getattr(st, name) for st in starts], float)  # one conversion, not one per row
    q = ys[:, X_AT.q:X_AT.q + 4]
    # row @ column is numpy's 1-D dot (BLAS ddot), as np.linalg.norm's: the same bits, one call for all rows
    q /= np.sqrt(q[:, None, :] @ q[:, :, None])[:, 0]
    ys[[not model.effects.rotation for model in models], X_AT.w:X_AT.w + 3] = 0.0
    return ys


def motions(models: list, num: motion.Numerics, starts: list, ys: np.ndarray, carries: np.ndarray, tables: tuple,
            statuses: np.ndarray, reason: str = "", strict: bool = True) -> list:
    """The ``motion.Motion`` of each finished run, built in bulk: final states ys (grains, STATE.size), carries
    (grains, CARRY.size), the trajectory, impact and warning rows of all grains one after another (``tables``;
    a grain's counts in its carry), the statuses (grains,); ``extra`` names this engine, "compiled", and
    ``reason``, why the caller chose it. A failed grain raises its error (``strict``) or is its SymmechError (no
    result built for it). Every number a grain's result needs is read out of the arrays by one ``tolist`` per
    kind, as columns zipped (no list per grain); in the loop over grains only the views of its rows and the
    result's objects are made."""
    failed = np.flatnonzero(statuses != DONE).tolist()
    if strict and failed:
        raise grain_failure(failed[0], ys, carries, statuses)
    errors = iter([grain_failure(k, ys, carries, statuses) for k in failed])  # taken in grain order below
    counts = carries[:, GRAIN_COUNTS].astype(INT)  # (grains, 6): rows, impacts, warnings, landings, rocking, implicit
    bounds = np.zeros((len(counts) + 1, 3), INT)  # where each grain's rows begin in each table, then the end
    np.cumsum(counts[:, :3], axis=0, out=bounds[1:])
    bounds, columns = bounds.tolist(), counts[:, 3:].T.tolist()
    times = carries[:, C_AT.t_flight].tolist(), carries[:, C_AT.t_sliding].tolist()
    rows, imps, warns = tables
    finals = (ys[:, X_AT.t].tolist(), *(ys[:, at] for at in STATE_VECTORS))  # t; r, v, q, w: views of ys's rows
    Motion, State, ImpactLog = motion.Motion, motion.State, motion.ImpactLog  # looked up once, not per grain
    done = int(DONE)  # a Python int: a numpy scalar's comparison costs ~0.1 us a grain
    return [Motion(rows[row0:row1], ImpactLog(imps[imp0:imp1], impact_log, T_COLUMN),
                   {"flight": flight, "sliding": slide},
                   run_warnings(warns[warn0:warn1], rocking, model, num) if warn1 > warn0 or rocking else [],
                   start, State(t, r, v, q, w), run_extra(landings, rocking, budget, implicit, reason))
            if status == done else next(errors)
            for status, model, start, (row0, imp0, warn0), (row1, imp1, warn1), landings, rocking, implicit, flight,
            slide, budget, t, r, v, q, w in zip(statuses.tolist(), models, starts, bounds, bounds[1:], *columns,
                                                *times, energy_budgets(carries), *finals)]


def grain_failure(k: int, ys: np.ndarray, carries: np.ndarray, statuses: np.ndarray) -> SymmechError:
    """:func:`failure` of grain k of a population: its status, the time of its state in ys, the regime in its
    carry."""
    return failure(int(statuses[k]), float(ys[k, X_AT.t]), int(carries[k, C_AT.regime]))


def run_warnings(warns, rocking: int, model: motion.Model, num: motion.Numerics) -> list:
    """The warnings of a run: its warning rows (n, WARNING_WIDTH) worded, then its ``rocking`` contacts, each once."""
    texts = [warning_text(int(c), a, b, model, num) for c, a, b in (warns.tolist() if len(warns) else ())]
    if rocking:
        texts.append(outcome.rocking_warning(rocking))
    return outcome.distinct(texts) if texts else texts


def run_extra(landings: int, rocking: int, budget: dict, implicit: int, reason: str) -> dict:
    """A compiled run's ``extra``: its counts, energy budget, this engine and why the caller chose it."""
    return {"landings": landings, "rocking_contacts": rocking, "energy_budget": budget, "engine": "compiled",
            "implicit_slip_steps": implicit, "engine_reason": reason}


def motion_of(model: motion.Model, num: motion.Numerics, start: motion.State, y: np.ndarray, carry: np.ndarray,
              rows: np.ndarray, imps: np.ndarray, warns: np.ndarray, reason: str = "") -> motion.Motion:
    """:func:`motions` of one finished run (no bulk arrays: a single grain's results in a few us): its final state y
    (STATE.size,), carry (CARRY.size,), trajectory, impact and warning rows (its counts)."""
    rocking = int(carry[C_AT.rocking])
    extra = run_extra(int(carry[C_AT.landings]), rocking, energy_budget(carry), int(carry[C_AT.implicit]), reason)
    time_in = {"flight": float(carry[C_AT.t_flight]), "sliding": float(carry[C_AT.t_sliding])}
    return motion.Motion(rows, deferred_log(imps), time_in, run_warnings(warns, rocking, model, num), start,
                         state_view(y), extra)


@dataclass(frozen=True)
class Run:
    """One grain's run on this engine, its inputs by name (the engine protocol's run, ``engines.Engine.run``): those
    of :func:`simulate`."""

    model: motion.Model
    numerics: motion.Numerics
    start: motion.State
    t_end: float  # [s]
    on_step: Callable[[float], None] | None = None
    reason: str = ""


@dataclass(frozen=True)
class Population:
    """Grains run together on this engine, their inputs by name (the engine protocol's population,
    ``engines.Engine.run_many``): those of :func:`simulate_many` (``models`` and ``starts`` a list each, one per
    grain)."""

    models: list
    numerics: motion.Numerics
    starts: list
    t_end: float  # [s]
    workers: int | None = None
    reason: str = ""
    strict: bool = True


class Runner:
    """This engine's side of the protocol's run and population (:class:`symmech.core.engines.PopulationRunner`)."""

    def simulate(self, inputs: Run) -> motion.Motion:
        """:func:`simulate` of the inputs."""
        return simulate(inputs.model, inputs.numerics, inputs.start, inputs.t_end, inputs.on_step, inputs.reason)

    def simulate_many(self, inputs: Population) -> list:
        """:func:`simulate_many` of the inputs."""
        return simulate_many(inputs.models, inputs.numerics, inputs.starts, inputs.t_end, inputs.workers,
                             inputs.reason, inputs.strict)


RUNNER = Runner()


def simulate(model: motion.Model, num: motion.Numerics, start: motion.State, t_end: float,
             on_step=None, reason: str = "") -> motion.Motion:
    """Accurate mode compiled: the contract and the result structure of :func:`symmech.grain.motion.simulate`
    (``extra`` names this engine, "compiled", and ``reason``, why the caller chose it).

    ``on_step(t_now)`` is called between batches of ``PHASES_PER_CALL`` regime phases, at most every 0.2 s
    of wall time, and once at the end. ``extra["implicit_slip_steps"]`` counts the Radau steps of stiff slips.
    The impact log is built on first read (:func:`deferred_log`).
    """
    run = entry()
    progress = motion.Progress(on_step)
    p = pack(model, num)
    y = start_vector(model, start)
    rows = np.empty((row_hint(t_end - start.t, num), TRAJECTORY_WIDTH))
    imps, warns, carry = np.empty((64, IMPACT_WIDTH)), np.empty((8, WARNING_WIDTH)), CARRY.zeros()
    status = MORE
    while status == MORE:
        progress(y[X_AT.t])
        y, rows, imps, warns, status = run(p, y, t_end, rows, imps, warns, carry, PHASES_PER_CALL)
    if status != DONE:
        raise failure(status, float(y[X_AT.t]), int(carry[C_AT.regime]))
    progress(y[X_AT.t], final=True)
    return motion_of(model, num, start, y, carry, rows[:int(carry[C_AT.rows])], imps[:int(carry[C_AT.nimp])],
                     warns[:int(carry[C_AT.nwarn])], reason)


def row_hint(duration: float, num: motion.Numerics) -> int:
    """Trajectory rows a run of ``duration`` [s] starts its buffer with: its samples and some events."""
    return int(max(duration, 0.0) / num.sample_interval) + 64


# --------------------------------------------------------------------------- building the cache once


def _loop():
    from symmech.grain.motion_engine import loop  # imports numba

    artifacts.guard_numba_cache()
    return loop


def entry_signature() -> tuple:
    """The argument types :func:`simulate` calls ``run`` with: the parameters, the state, t_end, the trajectory,
    impact and warning rows, the carry and the phases per call (the vectors' types from their layouts)."""
    from numba import types

    rows = types.Array(types.float64, 2, "C")
    return (PARAMS.numba_type(), STATE.numba_type(), types.float64, rows, rows, rows, CARRY.numba_type(),
            types.int64)


def many_signature() -> tuple:
    """The argument types :func:`simulate_many` calls ``run_many`` with: parameters and states (grains, size), the
    ends, the row hint, the carries (grains, CARRY.size) and the statuses."""
    from numba import types

    table = types.Array(types.float64, 2, "C")
    return (table, table, types.Array(types.float64, 1, "C"), types.int64, table, types.Array(types.int64, 1, "C"))


def _exports() -> dict:
    """What the ahead-of-time build exports: ``run`` for the signature of :func:`entry_signature`, loaded from
    numba's cache first (the build then reuses its compiled functions), and ``run_many`` for
    :func:`many_signature`, compiled here: ~8 s of CPU that a scene's first run, which needs ``run`` only
    (the engine's entry), does not wait for; without the build a population compiles it on first use."""
    loop = _loop()
    exports = {}
    for dispatcher, signature in ((loop.run, entry_signature()), (loop.run_many, many_signature())):
        dispatcher.compile(signature)
        exports[dispatcher.__name__] = (dispatcher, dispatcher.nopython_signatures[0])
    return exports


ENGINE = build.Engine("grain", "symmech.grain.motion_engine.loop", lambda: {_loop().run: entry_signature()},
                      COLD_COMPILE_SECONDS,
                      ahead=aot.Build("grain", [__file__, layouts.__file__, layout.__file__], _exports))


def entry_many():
    """``loop.run_many`` for this thread, as :func:`entry` chooses ``run``."""
    built = ENGINE.ahead_of_time() if threading.current_thread() is threading.main_thread() else None
    return built.run_many if built is not None else _loop().run_many


def entry():
    """The loop's entry for this thread: its ahead-of-time build when current and this is the main thread,
    else numba's (which releases the GIL for the grains of :func:`simulate_many`)."""
    built = ENGINE.ahead_of_time() if threading.current_thread() is threading.main_thread() else None
    return built.run if built is not None else _loop().run


GRAINS_PER_THREAD = 16  # a thread's start costs about a sphere's run
# a grain's counts in its carry: its rows in the tables loop.run_many returns (trajectory, impacts, warnings), then
# those its result reports
GRAIN_COUNTS = [C_AT.rows, C_AT.nimp, C_AT.nwarn, C_AT.landings, C_AT.rocking, C_AT.implicit]


def simulate_many(models: list, num: motion.Numerics, starts: list, t_end: float,
                  workers: int | None = None, reason: str = "", strict: bool = True) -> list:
    """Grains with their own models and start states, each as :func:`simulate` (bit for bit; no ``on_step``): a
    population packed once (one parameter vector per distinct model), its grains run one after another inside one
    compiled call (``loop.run_many``) per thread, ``workers`` threads (default: one per core, at most one per
    ``GRAINS_PER_THREAD`` grains; the compiled loop releases the GIL); the results built in bulk (:func:`motions`:
    no loop over impacts; ``reason`` as :func:`simulate`'s). A failed grain raises its error (the first, ``strict``)
    or stands in the list as its SymmechError. ``models`` and ``starts`` of different lengths are a ValueError."""
    n = len(models)
    if len(starts) != n:  # the loop runs a grain per start: extra starts would be dropped, missing ones never run
        raise ValueError(f"simulate_many: {n} models but {len(starts)} start states; one of each per grain")
    ps = packs(models, num)
    ys = start_vectors(models, starts)
    t_ends = np.full(n, float(t_end))
    carries, statuses = np.zeros((n, CARRY.size)), np.empty(n, INT)
    hint = row_hint(t_end - float(np.min(ys[:, X_AT.t], initial=t_end)), num)
    threads = max(1, min(workers or os.cpu_count() or 1, n // GRAINS_PER_THREAD))

    def part(a, b):
        return entry_many()(ps[a:b], ys[a:b], t_ends[a:b], hint, carries[a:b], statuses[a:b])
    if threads == 1:
        parts = [part(0, n)]
    else:
        from threadpoolctl import threadpool_limits
        cuts = np.linspace(0, n, threads + 1).astype(int)
        # the impact law's 3 x 3 solves call OpenBLAS: its own threads spin beside ours, 5x the CPU (measured)
        with threadpool_limits(limits=1, user_api="blas"), ThreadPoolExecutor(threads) as pool:
            parts = list(pool.map(part, cuts[:-1], cuts[1:]))
    tables = parts[0] if threads == 1 else tuple(np.concatenate(column) for column in zip(*parts))
    return motions(models, num, starts, ys, carries, tables, statuses, reason, strict)
