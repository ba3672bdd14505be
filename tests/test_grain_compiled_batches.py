"""The compiled engine's ``simulate`` between its loop's batches, without compiling the loop: a stand-in loop
(``compiled.entry`` replaced) returns chosen times and statuses call by call, as the loop returns a batch of
``PHASES_PER_CALL`` regime phases; progress is reported with each batch's time and a failure status becomes the
Python loop's error at the loop's time and regime. Expected values are written here by hand."""
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
    monkeypatch.setattr(motion, "PROGRESS_INTERVAL", 0.0)  # every call reports
    calls = stand_in(monkeypatch, [(0.5, compiled.MORE, 0), (0.75, compiled.MORE, 2), (1.0, compiled.DONE, 0)])
    times = []
    result = compiled.simulate(MODEL, NUM, START, 1.0, on_step=times.append)
    assert times == [0.25, 0.5, 0.75, 1.0]  # before each batch, then the final time
    assert [args[1][0] for args in calls] == [0.25, 0.5, 0.75] and result.final.t == 1.0


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
