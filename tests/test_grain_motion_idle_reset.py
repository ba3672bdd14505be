"""The Python grain loop's stagnation guard counts the phases in a row that leave t where it was, and only those:
a phase that advances time starts the count again. A sliding phase is replaced by one that advances 1 ms every
MAX_IDLE_STEPS + 1 calls and otherwise returns its start state (as in test_grain_motion_stall.py)."""
from dataclasses import replace

import pytest

from symmech.core.scene import SymmechError
from symmech.grain import motion
from test_grain_motion_closed_forms import A, frictionless, numerics, sphere, state

STEP = 1e-3  # [s] advanced by an advancing phase


def sliding_phases(advancing, calls):
    """A stand-in for motion._slide: call k advances STEP when advancing(k), else returns its start state."""
    def phase(model, num, st, t_end, rec, budget, progress):
        calls.append(st.t)
        assert len(calls) <= 4 * motion.MAX_IDLE_STEPS, "the guard let the run spin on"
        return (replace(st, t=st.t + STEP) if advancing(len(calls) - 1) else st), False
    return phase


def test_idle_phases_between_advancing_ones_are_allowed_up_to_the_limit(monkeypatch):
    """Three advancing phases, each followed by MAX_IDLE_STEPS idle ones: 3 (MAX_IDLE_STEPS + 1) - MAX_IDLE_STEPS
    phases in all up to t_end = 3 ms, no error."""
    calls, n = [], motion.MAX_IDLE_STEPS
    monkeypatch.setattr(motion, "_slide", sliding_phases(lambda k: k % (n + 1) == 0, calls))
    res = motion.simulate(sphere(frictionless(0.5)), numerics(), state(z=A), 3 * STEP)  # at rest: slides
    assert len(calls) == 2 * (n + 1) + 1
    assert res.final.t == pytest.approx(3 * STEP, abs=1e-18)
    assert res.time_in == {"flight": 0.0, "sliding": pytest.approx(3 * STEP, abs=1e-18)}


def test_after_an_advancing_phase_the_run_fails_at_the_limit_plus_one_idle_phases(monkeypatch):
    calls = []
    monkeypatch.setattr(motion, "_slide", sliding_phases(lambda k: k == 0, calls))
    with pytest.raises(SymmechError) as err:
        motion.simulate(sphere(frictionless(0.5)), numerics(), state(z=A), 10 * STEP)
    assert len(calls) == 1 + motion.MAX_IDLE_STEPS + 1 and set(calls[1:]) == {STEP}
    assert "stopped advancing at t = 0.001 s (1000 regime changes without advancing time" in str(err.value)
