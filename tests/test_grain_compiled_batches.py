"""The compiled engine's ``simulate`` between its loop's batches, without compiling the loop: a stand-in loop
(``compiled.entry`` replaced) returns chosen times and statuses call by call, as the loop returns a batch of
``PHASES_PER_CALL`` regime phases; progress is reported with each batch's time and a failure status becomes the
Python loop's error at the loop's time and regime. A population (a stand-in ``run_many``) through the registry
gets each grain's own results, the main thread calls the ahead-of-time build, and ``pack`` and ``simulate_many``
refuse what the loop cannot run. Expected values are written here by hand."""
import math
from dataclasses import replace

import numpy as np
import pytest

from symmech.core.scene import SymmechError
from symmech.grain import flight, motion
from symmech.grain.motion_engine import driver as compiled, layouts as compiled_layout
from symmech.grain.coulomb_law import ImpactLaw

MODEL = motion.Model((1e-3, 1e-3, 1e-3), 2e-6, (0.0, 0.0, -9.81), flight.Vibration(0.0, 1.0, 0.0, (0.0, 0.0, 1.0)),
                     ImpactLaw("printed", e=0.5, lam=0.5), 0.3)
NUM = motion.Numerics()
START = motion.State(0.25, np.array([0.0, 0.0, 0.01]), np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(3))


def stand_in(monkeypatch, batches):
    """Replace the loop: its k-th call moves the time to ``batches[k] = (t, status, regime)``; the arguments of
    each call (its state copied) are returned (a list, filled as it runs)."""
    seen = []

    def run(p, y, t_end, rows, imps, warns, carry, phases):
        t, status, regime = batches[len(seen)]
        seen.append((p, y.copy(), t_end, rows, imps, warns, carry, phases))
        y = y.copy()
        y[0], carry[compiled_layout.C_AT.regime] = t, regime
        return y, rows, imps, warns, status

    monkeypatch.setattr(compiled, "entry", lambda: run)
    return seen


def test_progress_is_reported_at_each_batch_time_and_once_at_the_end(monkeypatch):
    """A run through the registry's ``run`` (the engine's ``Runner``): progress at each batch's time, the reason
    given in its ``extra``."""
    from symmech.core import engines

    monkeypatch.setattr(motion, "PROGRESS_INTERVAL", 0.0)  # every call reports
    calls = stand_in(monkeypatch, [(0.5, compiled.MORE, 0), (0.75, compiled.MORE, 2), (1.0, compiled.DONE, 0)])
    times = []
    result = engines.get("grain").run(compiled.Run(MODEL, NUM, START, 1.0, times.append, "chosen here"))
    assert times == [0.25, 0.5, 0.75, 1.0]  # before each batch, then the final time
    assert [args[1][0] for args in calls] == [0.25, 0.5, 0.75] and result.final.t == 1.0
    assert result.extra["engine_reason"] == "chosen here"


@pytest.mark.parametrize("status, regime, text", [
    (compiled.STALLED, 2, "grain: the simulation stopped advancing at t = 0.75 s (1000 regime changes without "
                          "advancing time, sliding regime)"),
    (compiled.STALLED, 0, "grain: the simulation stopped advancing at t = 0.75 s (1000 regime changes without "
                          "advancing time, flight regime)"),
    (compiled.SLIDE_FAIL, 2, "sliding integration failed at t = 0.75 s: required step size is less than spacing "
                             "between numbers"),
])
def test_a_failed_batch_raises_the_python_loops_error_at_its_time_and_regime(monkeypatch, status, regime, text):
    stand_in(monkeypatch, [(0.5, compiled.MORE, 0), (0.75, status, regime)])
    with pytest.raises(SymmechError) as err:
        compiled.simulate(MODEL, NUM, START, 1.0)
    assert str(err.value) == text


def test_the_signature_built_ahead_is_the_one_simulate_calls_the_loop_with(monkeypatch):
    """The engine is compiled (and built ahead of time) for ``entry_signature``: a run with other argument
    types would compile again, or find no ahead-of-time export."""
    import numba

    calls = stand_in(monkeypatch, [(1.0, compiled.DONE, 0)])
    compiled.simulate(MODEL, NUM, START, 1.0)
    assert tuple(numba.typeof(a) for a in calls[0]) == compiled.entry_signature()


def test_a_population_takes_a_thread_per_16_grains_and_raises_its_first_failure(monkeypatch):
    """48 grains: three threads of 16 when three workers are asked, two (one a core, two cores) by default; with the
    grains starting at t = k / 100 s, grains 20 and 30 stalled at t + 1/2 (a stand-in ``run_many``), the run
    raises grain 20's error, the first in the population's order. BLAS runs one thread inside each."""
    from threadpoolctl import threadpool_info

    parts, blas_threads = [], []
    np.linalg.solve(np.eye(2), np.ones(2))  # numpy's BLAS loaded (the impact law's 3 x 3 solves load it)

    def run_many(ps, ys, t_ends, hint, carries, statuses):
        parts.append(len(ps))
        blas_threads.extend(i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas")
        statuses[:] = compiled.DONE
        for k in np.flatnonzero(np.isin(np.round(ys[:, 0] * 100), (20, 30))):
            statuses[k], ys[k, 0], carries[k, compiled_layout.C_AT.regime] = compiled.STALLED, ys[k, 0] + 0.5, 2
        empty = np.empty((0, 1))
        return empty, empty, empty

    monkeypatch.setattr(compiled, "entry_many", lambda: run_many)
    monkeypatch.setattr(compiled.os, "cpu_count", lambda: 2)
    starts = [motion.State(k / 100, START.r, START.v, START.q, START.w) for k in range(48)]
    for workers, cut in [(3, [16, 16, 16]), (None, [24, 24])]:
        parts.clear()
        with pytest.raises(SymmechError) as err:
            compiled.simulate_many([MODEL] * 48, NUM, starts, 1.0, workers=workers)
        assert sorted(parts) == cut
        assert blas_threads and set(blas_threads) == {1}  # BLAS's own threads would spin beside the grains'
        blas_threads.clear()
        assert str(err.value).startswith("grain: the simulation stopped advancing at t = 0.7 s ")


def test_a_population_through_the_registry_is_each_grains_own_rows_times_and_counts(monkeypatch):
    """Three grains through the registry's ``run_many`` (the engine's ``Runner``): a stand-in ``run_many`` gives
    grain k k + 1 trajectory rows (each row's first value k), k landings, k / 10 s of flight and k / 100 s of
    sliding; each result holds its own rows, times, counts and start, the population's reason, no warnings. Models
    and start states of different lengths are refused: the loop would read past the shorter."""
    from symmech.core import engines

    def run_many(ps, ys, t_ends, hint, carries, statuses):
        statuses[:] = compiled.DONE
        for k, carry in enumerate(carries):
            carry[[C.rows, C.landings, C.t_flight, C.t_sliding]] = k + 1, k, k / 10, k / 100
        ys[:, 0] = t_ends
        rows = np.repeat(np.arange(3.0), [1, 2, 3])[:, None] * np.ones((1, compiled.TRAJECTORY_WIDTH))
        return rows, np.empty((0, compiled.IMPACT_WIDTH)), np.empty((0, compiled.WARNING_WIDTH))

    C = compiled_layout.C_AT
    monkeypatch.setattr(compiled, "entry_many", lambda: run_many)
    starts = [motion.State(k / 10, START.r, START.v, START.q, START.w) for k in range(3)]
    population = compiled.Population([MODEL] * 3, NUM, starts, 1.0, workers=1, reason="chosen here")
    runs = engines.get("grain").run_many(population)
    for k, run in enumerate(runs):
        assert run.trajectory.shape == (k + 1, compiled.TRAJECTORY_WIDTH) and set(run.trajectory.ravel()) == {k}
        assert run.time_in == {"flight": k / 10, "sliding": k / 100} and run.start is starts[k]
        assert {key: value for key, value in run.extra.items() if key != "energy_budget"} == {
            "landings": k, "rocking_contacts": 0, "engine": "compiled", "implicit_slip_steps": 0,
            "engine_reason": "chosen here"}
        assert run.extra["energy_budget"]["end_J"] == 0.0 and run.warnings == []
        assert run.final.t == 1.0 and run.impacts == []
    with pytest.raises(ValueError, match=r"^simulate_many: 3 models but 2 start states; one of each per grain$"):
        compiled.simulate_many([MODEL] * 3, NUM, starts[:2], 1.0)


def test_the_main_thread_runs_the_build_made_ahead_and_other_threads_numbas_loop(monkeypatch):
    """The ahead-of-time build holds the GIL: only the main thread calls it; another thread, or any thread when
    there is no current build, calls numba's entries (stand-ins here: nothing compiles)."""
    import threading
    from types import SimpleNamespace

    built, numbas = SimpleNamespace(run="built run", run_many="built run_many"), SimpleNamespace(
        run="numba's run", run_many="numba's run_many")
    monkeypatch.setattr(compiled, "_loop", lambda: numbas)
    monkeypatch.setattr(compiled.ENGINE, "ahead_of_time", lambda: built)
    assert (compiled.entry(), compiled.entry_many()) == ("built run", "built run_many")
    seen = []
    thread = threading.Thread(target=lambda: seen.append((compiled.entry(), compiled.entry_many())))
    thread.start()
    thread.join()
    assert seen == [("numba's run", "numba's run_many")]
    monkeypatch.setattr(compiled.ENGINE, "ahead_of_time", lambda: None)
    assert (compiled.entry(), compiled.entry_many()) == ("numba's run", "numba's run_many")


def test_a_nan_parameter_is_refused_by_name_before_the_loop_runs():
    """A NaN in the parameter vector would send the loop's event search on without end (a NaN restitution, say):
    pack names it. An infinite friction coefficient (the impact law's default) is a number and passes."""
    law = ImpactLaw("coulomb", e_n=0.5, e_t=float("nan"), mu=float("inf"))
    with pytest.raises(ValueError, match=r"^grain engine: parameter e_t is NaN$"):
        compiled.pack(replace(MODEL, law=law), NUM)
    with pytest.raises(ValueError, match=r"^grain engine: parameter e_n, tolerance is NaN$"):
        compiled.pack(replace(MODEL, law=replace(law, e_n=float("nan"), e_t=0.0)), replace(NUM, tolerance=math.nan))
    assert compiled_layout.PARAMS.unpack(compiled.pack(replace(MODEL, law=replace(law, e_t=0.0)), NUM))["mu_impact"] \
        == float("inf")
