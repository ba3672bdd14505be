"""The Python side of the compiled grain engine (symmech.grain.motion_engine), without compiling it: the texts of its
warning and error codes (numbers included, worded as the Python loop words them), the impact log and the energy
budget built from the compiled loop's raw rows and carry. Expected values are written here by hand."""
import dataclasses
import math

import numpy as np
import pytest

from symmech.core.scene import SymmechError
from symmech.grain import flight, motion
from symmech.grain.motion_engine import driver as compiled, layouts as compiled_layout
from symmech.grain.coulomb_law import ImpactLaw
from symmech.grain.motion_engine.layouts import C_AT

MODEL = motion.Model((1e-3, 1e-3, 1e-3), 2e-6, (0.0, 0.0, -9.81), flight.Vibration(0.0, 1.0, 0.0, (0.0, 0.0, 1.0)),
                     ImpactLaw("printed", e=0.5, lam=0.5), 0.3)
NUM = motion.Numerics(max_impacts=7)


@pytest.mark.parametrize("code, a, b, text", [
    (compiled.W_MAX_IMPACTS, 0.0123456789, 0.0, "stopped at t = 0.0123457 s after numerics.max_impacts = 7 impacts"),
    (compiled.W_CHATTER, 0.5, 0.0, "100 impacts within 0.0001 periods: chattering summed into sliding"),
    (compiled.W_PRINTED_ENERGY, 0.0, 0.0,
     "printed impact law: no admissible root; the one used creates kinetic energy"),
    (compiled.W_PRINTED_PULLS, 0.0, 0.0,
     "printed impact law: no admissible root; the one used pulls the grain into the plane (T_z < 0)"),
    (compiled.W_PRINTED_RESIDUAL, 3.456789e-7, 0.0,
     "printed impact law: no solution of (19) (relative residual 3.46e-07)"),
    (compiled_layout.W_ENERGY, 1.234567891e-6, 1.3e-6, "impact law 'printed' created energy: 1.23457e-06 J -> 1.3e-06 J"),
])
def test_warning_codes_read_as_the_python_loops_texts(code, a, b, text):
    assert compiled.warning_text(int(code), a, b, MODEL, NUM) == text


@pytest.mark.parametrize("status, regime, text", [
    (compiled.STALLED, 2, "grain: the simulation stopped advancing at t = 0.123456789 s (1000 regime changes without "
                          "advancing time, sliding regime)"),
    (compiled.STALLED, 0, "grain: the simulation stopped advancing at t = 0.123456789 s (1000 regime changes without "
                          "advancing time, flight regime)"),
    (compiled.SLIDE_STALLED, 2, "sliding stagnates at t = 0.123456789 s: 200 regime changes without advancing time"),
    (compiled.SLIDE_RHS, 2, "sliding integration stagnates at t = 0.123456789 s (more than 400000 evaluations in one "
                            "chunk)"),
    (compiled.SLIDE_FAIL, 2, "sliding integration failed at t = 0.123456789 s: required step size is less than "
                             "spacing between numbers"),
    (compiled_layout.ROT_FAIL, 0, "torque-free rotation failed at t = 0.123456789 s: required step size is less than spacing "
                           "between numbers"),
])
def test_failure_codes_are_the_python_loops_errors(status, regime, text):
    err = compiled.failure(status, 0.1234567891, regime)
    assert isinstance(err, SymmechError) and str(err) == text


def impact_rows():
    """Two compiled impact rows: t, r, v before/after, w before/after, impulse, u before/after, ke before/after,
    then the flags admissible, printed admissible, printed creates energy, converged (-1 not checked, 0 no, 1 yes)."""
    rows = np.arange(2 * compiled.IMPACT_WIDTH, dtype=float).reshape(2, compiled.IMPACT_WIDTH) / 8.0
    rows[0, 27:31] = [1.0, -1.0, -1.0, 1.0]
    rows[1, 27:31] = [0.0, 0.0, 1.0, 0.0]
    return rows


def test_impact_log_from_the_compiled_rows_has_the_python_loops_fields():
    rows = impact_rows()
    log = compiled.impact_log(rows)
    assert len(log) == 2
    for k, entry in enumerate(log):
        x = list(np.arange(31 * k, 31 * k + 31) / 8.0)
        assert entry == {"t": x[0], "r": x[1:4], "v_before": x[4:7], "v_after": x[7:10], "w_before": x[10:13],
                         "w_after": x[13:16], "impulse": x[16:19], "u_before": x[19:22], "u_after": x[22:25],
                         "ke_before": x[25], "ke_after": x[26],
                         "admissible": k == 0, "printed_admissible": [None, False][k],
                         "printed_creates_energy": [None, True][k], "converged": k == 0}
        assert type(entry["t"]) is float and type(entry["admissible"]) is bool
    lazy = motion.Motion(np.zeros((1, 15)), compiled.deferred_log(rows), {}, [], None, None)
    assert type(lazy) is motion.Motion and "impacts" not in vars(lazy)  # the public type, no log built yet
    assert lazy.impact_times().tolist() == [0.0, 31 / 8.0] and "impacts" not in vars(lazy)  # read from the rows
    assert lazy.impacts == log and lazy.impacts is lazy.impacts  # built once, on first read


def test_energy_budget_of_a_finished_run_from_its_carry():
    """Start 2.0 J, end 1.25 J, work 0.5 J, losses 0.75, 0.25, 0.125 J: residual = end - start - (work - losses)."""
    carry = compiled.CARRY.zeros()
    carry[[C_AT.e_start, C_AT.e_end, C_AT.work]] = 2.0, 1.25, 0.5
    carry[[C_AT.impacts, C_AT.land_loss, C_AT.slide_loss]] = 0.75, 0.25, 0.125
    report = compiled.energy_budget(carry)
    residual = 1.25 - 2.0 - (0.5 - 0.75 - 0.25 - 0.125)
    assert report == {"start_J": 2.0, "end_J": 1.25, "input_by_surface_J": 0.5, "lost_in_impacts_J": 0.75,
                      "lost_at_landings_J": 0.25, "lost_in_sliding_J": 0.125, "residual_J": residual,
                      "relative_residual": abs(residual) / 2.0, "tolerance": 1e-6}
    assert list(report) == ["start_J", "end_J", "input_by_surface_J", "lost_in_impacts_J", "lost_at_landings_J",
                            "lost_in_sliding_J", "residual_J", "relative_residual", "tolerance"]  # the summary's order
    assert {type(v) for v in report.values()} == {float}
    bulk = compiled.energy_budgets(np.array([carry]))[0]
    assert list(bulk.items()) == list(report.items()) and {type(v) for v in bulk.values()} == {float}


def test_state_of_a_result_vector_is_made_of_its_views():
    y = np.arange(14, dtype=float) / 4.0
    st = compiled.state_view(y)
    assert type(st.t) is float and st.t == 0.0
    for got, part in ((st.r, y[1:4]), (st.v, y[4:7]), (st.q, y[7:11]), (st.w, y[11:14])):
        assert np.shares_memory(got, y) and np.array_equal(got, part)
    assert math.isclose(st.w[-1], 13 / 4.0)


@pytest.mark.parametrize("start, end, work, impacts, landings, sliding, scale", [
    (0.5, 2.0, 0.25, 0.125, 0.0625, 0.03125, 2.0),   # the end energy is the largest
    (0.5, -0.25, 1.5, 0.125, 0.0625, 0.03125, 1.5),  # the input
    (0.5, -0.25, 0.25, 0.5, 0.375, 0.25, 1.125),     # the losses together (each smaller than the start)
    (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, None),            # nothing at all: relative residual 0
])
def test_relative_residual_of_the_budget_is_over_its_largest_entry(start, end, work, impacts, landings, sliding, scale):
    carry = compiled.CARRY.zeros()
    carry[[C_AT.e_start, C_AT.e_end, C_AT.work]] = start, end, work
    carry[[C_AT.impacts, C_AT.land_loss, C_AT.slide_loss]] = impacts, landings, sliding
    report = compiled.energy_budget(carry)
    residual = end - start - (work - impacts - landings - sliding)
    assert report["residual_J"] == residual
    assert report["relative_residual"] == (abs(residual) / scale if scale else 0.0)
    assert compiled.energy_budgets(np.array([carry, carry])) == [report, report]  # a population's, in bulk


def test_budgets_in_bulk_choose_the_largest_part_as_one_run_does_with_nan():
    """Python's max keeps a NaN that comes first (relative residual 0) and passes over a later one: the bulk budget
    of a population gives each run exactly its own report."""
    carries = np.zeros((2, compiled.CARRY.size))
    carries[:, [C_AT.e_start, C_AT.e_end, C_AT.work]] = [[np.nan, 1.0, 0.5], [1.0, np.nan, 0.5]]
    bulk = compiled.energy_budgets(carries)
    for carry, report in zip(carries, bulk):
        one = compiled.energy_budget(carry)
        assert report["relative_residual"] == one["relative_residual"] or math.isnan(one["relative_residual"])
        assert math.isnan(report["relative_residual"]) == math.isnan(one["relative_residual"])
    assert bulk[0]["relative_residual"] == 0.0


def test_start_states_in_bulk_equal_each_grains_own():
    """q normalised (a quaternion of norm 3 here), spin zeroed where the model does not rotate: bit for bit."""
    vib = flight.Vibration(1e-3, 2 * math.pi * 20.0, 0.3, (0.0, 0.0, 1.0))
    law = ImpactLaw("coulomb", e_n=0.5, e_t=0.0, mu=0.5, check_printed=False)
    models = [motion.Model((3e-3, 2e-3, 1e-3), 2e-5, (0.0, 0.0, -9.81), vib, law, 0.4, motion.Effects(rotation=r))
              for r in (True, False)]
    start = motion.State(0.1, np.array([0.0, 0.0, 4e-3]), np.array([0.1, 0.0, 0.2]),
                         np.array([1.0, 2.0, 2.0, 0.3]) / 1.01, np.array([3.0, -4.0, 5.0]))
    ys = compiled.start_vectors(models, [start, start])
    for y, model in zip(ys, models):
        assert y.tobytes() == compiled.start_vector(model, start).tobytes()
    assert ys[1, 11:].tolist() == [0.0, 0.0, 0.0] and ys[0, 11:].tolist() == [3.0, -4.0, 5.0]
    # the norms of many quaternions at once (one matmul) are each one's np.linalg.norm, bit for bit
    qs = np.random.default_rng(7).normal(size=(300, 4)) * np.logspace(-3, 3, 300)[:, None]
    starts = [dataclasses.replace(start, q=q) for q in qs]
    bulk = compiled.start_vectors([models[0]] * len(starts), starts)
    assert bulk.tobytes() == np.array([compiled.start_vector(models[0], st) for st in starts]).tobytes()


def test_equal_models_are_packed_once_and_each_grain_gets_its_models_row(monkeypatch):
    """Grains of friction 0.3, 0.3 (an equal copy), 0.7, 0.3, 0.7 (a copy): two packings, and each grain's row holds
    its own friction coefficient."""
    packed = []
    monkeypatch.setattr(compiled, "pack", lambda model, num: packed.append(model) or np.full(compiled.PARAMS.size,
                                                                                             model.mu))
    other = dataclasses.replace(MODEL, mu=0.7)
    models = [MODEL, dataclasses.replace(MODEL), other, MODEL, dataclasses.replace(other)]
    ps = compiled.packs(models, NUM)
    assert packed == [MODEL, other] and packed[1] is other
    assert ps.shape == (5, compiled.PARAMS.size) and ps[:, 0].tolist() == [0.3, 0.3, 0.7, 0.3, 0.7]
    assert np.array_equal(ps, np.repeat(ps[:, :1], compiled.PARAMS.size, axis=1)) and ps.flags.c_contiguous


class Counted:
    """A stand-in model that counts its hashes and comparisons (equal to any other of its kind)."""

    calls = []

    def __hash__(self):
        Counted.calls.append("hash")
        return 0

    def __eq__(self, other):
        Counted.calls.append("eq")
        return isinstance(other, Counted)


def test_a_model_equal_to_the_one_before_is_compared_not_hashed(monkeypatch):
    """Five equal models, each its own object, as a scene's grains bring them: the first compared with none before
    it and hashed into the dict of distinct models, then one comparison a grain with the one before; one packing."""
    monkeypatch.setattr(compiled, "pack", lambda model, num: np.zeros(compiled.PARAMS.size))
    Counted.calls.clear()
    ps = compiled.packs([Counted() for _ in range(5)], NUM)
    assert Counted.calls == ["eq", "hash", "eq", "eq", "eq", "eq"] and ps.shape == (5, compiled.PARAMS.size)


def population_run():
    """Three finished grains as the compiled population loop leaves them: carries with their counts (2, 0, 3
    trajectory rows; 1, 0, 2 impacts; grain 0 one warning, grain 2 4 rocking contacts), the tables of all grains one
    after another, the final states; grain 1 failed (stalled)."""
    carries = np.zeros((3, compiled.CARRY.size))
    carries[:, [C_AT.rows, C_AT.nimp, C_AT.nwarn, C_AT.rocking, C_AT.landings, C_AT.implicit]] = [
        [2, 1, 1, 0, 1, 5], [0, 0, 0, 0, 0, 0], [3, 2, 0, 4, 0, 0]]
    carries[:, [C_AT.t_flight, C_AT.t_sliding, C_AT.e_start, C_AT.e_end]] = np.arange(12.0).reshape(3, 4) / 8
    carries[:, C_AT.regime] = 2
    rows = np.arange(5 * compiled.TRAJECTORY_WIDTH, dtype=float).reshape(5, -1)
    imps = np.vstack((impact_rows()[1:], impact_rows()))
    warns = np.array([[compiled.W_MAX_IMPACTS, 0.25, 0.0]])
    ys = np.arange(3 * compiled.STATE.size, dtype=float).reshape(3, -1) / 16
    statuses = np.array([compiled.DONE, compiled.STALLED, compiled.DONE])
    return carries, (rows, imps, warns), ys, statuses


def test_population_results_are_each_grains_own_motion():
    """Each grain's result of a population, built in bulk, is the motion.Motion that motion_of builds of that grain's
    own rows: every field set, equal value for value and type for type; the failed grain stands as its error, or is
    raised (strict)."""
    carries, (rows, imps, warns), ys, statuses = population_run()
    starts = [motion.State(k, np.zeros(3), np.zeros(3), np.array([1.0, 0, 0, 0]), np.zeros(3)) for k in range(3)]
    got = compiled.motions([MODEL] * 3, NUM, starts, ys, carries, (rows, imps, warns), statuses, "why", strict=False)
    assert isinstance(got[1], SymmechError) and str(got[1]) == (
        "grain: the simulation stopped advancing at t = 0.875 s (1000 regime changes without advancing time, "
        "sliding regime)")  # ys[1, 0] = 14 / 16
    with pytest.raises(SymmechError, match=r"^grain: the simulation stopped advancing at t = 0.875 s "):
        compiled.motions([MODEL] * 3, NUM, starts, ys, carries, (rows, imps, warns), statuses, "why")
    own = {0: compiled.motion_of(MODEL, NUM, starts[0], ys[0], carries[0], rows[:2], imps[:1], warns, "why"),
           2: compiled.motion_of(MODEL, NUM, starts[2], ys[2], carries[2], rows[2:], imps[1:], warns[:0], "why")}
    assert own[0].warnings == ["stopped at t = 0.25 s after numerics.max_impacts = 7 impacts"]
    assert own[2].warnings == [compiled.outcome.rocking_warning(4)] and own[0].extra["implicit_slip_steps"] == 5
    assert own[0].impact_times().tolist() == [31 / 8] and own[2].impact_times().tolist() == [0.0, 31 / 8]
    for k, one in own.items():
        m = got[k]
        assert type(m) is motion.Motion and set(vars(m)) == {f.name for f in dataclasses.fields(m)}  # all built
        assert m.trajectory.tobytes() == one.trajectory.tobytes() and m.impacts == one.impacts
        assert (m.time_in, m.warnings, m.extra) == (one.time_in, one.warnings, one.extra)
        assert m.time_in == {"flight": carries[k, C_AT.t_flight], "sliding": carries[k, C_AT.t_sliding]}
        assert [type(v) for v in m.extra.values()] == [type(v) for v in one.extra.values()]
        assert [type(v) for v in m.time_in.values()] == [float, float] and type(m.final.t) is float
        assert m.start is starts[k] and m.final.t == ys[k, 0] == k * 14 / 16
        assert np.array_equal(np.concatenate(dataclasses.astuple(m.final)[1:]), ys[k, 1:])
        assert np.shares_memory(m.final.r, ys) and np.shares_memory(m.trajectory, rows)


def test_a_failed_grain_stands_as_its_own_error_and_no_result_is_built_for_it(monkeypatch):
    """Grains 0 and 1 of three failed (a slip that stalled at t = 0 s, the torque-free rotation at 0.875 s), grain 2
    finished: each failure stands at its own place as its own error, and only grain 2's extra and warnings are
    built (grain 0's warning row and rocking contacts are not worded)."""
    carries, (rows, imps, warns), ys, statuses = population_run()
    statuses = np.array([compiled.SLIDE_STALLED, compiled_layout.ROT_FAIL, compiled.DONE])
    built, worded = [], []
    monkeypatch.setattr(compiled, "run_extra", lambda *args: built.append(args) or {})
    monkeypatch.setattr(compiled, "run_warnings", lambda *args: worded.append(args) or [])
    starts = [motion.State(k, np.zeros(3), np.zeros(3), np.array([1.0, 0, 0, 0]), np.zeros(3)) for k in range(3)]
    got = compiled.motions([MODEL] * 3, NUM, starts, ys, carries, (rows, imps, warns), statuses, "why", strict=False)
    assert [type(m) for m in got] == [SymmechError, SymmechError, motion.Motion]
    assert str(got[0]) == "sliding stagnates at t = 0 s: 200 regime changes without advancing time"
    assert str(got[1]) == ("torque-free rotation failed at t = 0.875 s: required step size is less than spacing "
                           "between numbers")
    assert len(built) == 1 and built[0][:2] == (0, 4)
    assert len(worded) == 1 and worded[0][0].shape == (0, compiled.WARNING_WIDTH) and worded[0][1] == 4
    assert got[2].trajectory.tobytes() == rows[2:].tobytes() and got[2].impact_times().tolist() == [0.0, 31 / 8]


@pytest.mark.parametrize("duration, interval, rows", [(0.5, 1e-3, 564), (2.0, 0.25, 72), (-1.0, 0.25, 64)])
def test_a_runs_trajectory_buffer_starts_with_its_samples_and_64_rows_more(duration, interval, rows):
    """The rows a run's trajectory buffer starts with: one per sample interval of its duration (none for a
    duration below zero) and 64 for events; the loop grows it past that."""
    assert compiled.row_hint(duration, motion.Numerics(sample_interval=interval)) == rows
