"""The Python grain loop's stagnation guard: a run whose phases stop advancing time fails after exactly
MAX_IDLE_STEPS + 1 phases in a row that leave t where it was (a sliding phase made to return its start state),
naming the time and the regime."""
import pytest

from symmech.core.scene import SymmechError
from symmech.grain import motion
from test_grain_motion_closed_forms import A, frictionless, numerics, sphere, state


def test_a_run_that_stops_advancing_fails_after_the_allowed_idle_phases(monkeypatch):
    calls = []

    def stuck(model, num, st, t_end, rec, budget, progress):
        calls.append(st.t)
        assert len(calls) <= 2 * motion.MAX_IDLE_STEPS, "the guard let the run spin on"
        return st, False

    monkeypatch.setattr(motion, "_slide", stuck)
    with pytest.raises(SymmechError) as err:
        motion.simulate(sphere(frictionless(0.5)), numerics(), state(z=A), 0.01)  # at rest on the plane: slides
    assert len(calls) == motion.MAX_IDLE_STEPS + 1 and set(calls) == {0.0}
    assert str(err.value) == ("grain: the simulation stopped advancing at t = 0 s (1000 regime changes without "
                              "advancing time, sliding regime)")
