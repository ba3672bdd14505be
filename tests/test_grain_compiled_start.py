"""How the compiled grain engine (symmech.grain.compiled) takes its start state: a point mass (rotation off) drops
without spin whatever spin it was given, and a start quaternion that is not a unit one is normalised; against the
closed form of the drop (first contact at sqrt(2h/g)) and its energy m g z."""
import math

import numpy as np
import pytest

from symmech.grain import compiled
from test_grain_motion_closed_forms import A, G, H, M, T_C, frictionless, numerics, sphere, state

pytestmark = pytest.mark.compiled_engine  # ordered last, after the session's background build (conftest.py)


def test_a_point_mass_drops_without_the_spin_it_was_given_from_a_normalised_orientation():
    start = state(w=(30.0, -20.0, 10.0), q=(2.0, 0.0, 0.0, 0.0))
    res = compiled.simulate(sphere(frictionless(0.5), rotation=False), numerics(), start, 1.5 * T_C)
    assert res.impacts[0]["t"] == pytest.approx(T_C, abs=1e-9)
    assert res.impacts[0]["v_before"] == pytest.approx([0.0, 0.0, -G * T_C], rel=1e-9)
    assert not res.trajectory[:, 11:14].any() and not res.final.w.any()
    np.testing.assert_array_equal(res.trajectory[:, 7:11], np.tile([1.0, 0.0, 0.0, 0.0], (len(res.trajectory), 1)))
    assert res.extra["energy_budget"]["start_J"] == pytest.approx(M * G * (A + H), rel=1e-12)
    assert math.isclose(res.final.t, 1.5 * T_C)
