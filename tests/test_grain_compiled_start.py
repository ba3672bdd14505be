"""How the compiled grain engine (symmech.grain.motion_engine) takes its start state: a point mass (rotation off) drops
without spin whatever spin it was given, and a start quaternion that is not a unit one is normalised; against the
closed form of the drop (first contact at sqrt(2h/g)) and its energy m g z."""
import math

import numpy as np
import pytest

from symmech.grain import motion
from symmech.grain.motion_engine import driver as compiled
from test_grain_motion_closed_forms import A, G, H, M, T_C, frictionless, numerics, sphere, state

pytestmark = [pytest.mark.slow, pytest.mark.compiled_engine]  # the engine's build: slow tier (conftest.py)


def test_a_point_mass_drops_without_the_spin_it_was_given_from_a_normalised_orientation():
    start = state(w=(30.0, -20.0, 10.0), q=(2.0, 0.0, 0.0, 0.0))
    res = compiled.simulate(sphere(frictionless(0.5), rotation=False), numerics(), start, 1.5 * T_C)
    assert res.impacts[0]["t"] == pytest.approx(T_C, abs=1e-9)
    assert res.impacts[0]["v_before"] == pytest.approx([0.0, 0.0, -G * T_C], rel=1e-9)
    assert not res.trajectory[:, 11:14].any() and not res.final.w.any()
    np.testing.assert_array_equal(res.trajectory[:, 7:11], np.tile([1.0, 0.0, 0.0, 0.0], (len(res.trajectory), 1)))
    assert res.extra["energy_budget"]["start_J"] == pytest.approx(M * G * (A + H), rel=1e-12)
    assert math.isclose(res.final.t, 1.5 * T_C)


def test_max_impacts_stops_the_compiled_run_at_the_next_contact_with_its_warning():
    """A point mass dropped from h with e = 0.5 and max_impacts = 2: contacts at t_c, t_c (1 + 2e), and the third,
    t_c (1 + 2e + 2e²), stops the run with the warning that names it."""
    e = 0.5
    num = motion.Numerics(tolerance=1e-11, scan_step=1e-3, sample_interval=1e-3, max_impacts=2)
    res = compiled.simulate(sphere(frictionless(e), rotation=False), num, state(), 1.0)
    t3 = T_C * (1 + 2 * e + 2 * e * e)
    assert [i["t"] for i in res.impacts] == pytest.approx([T_C, T_C * (1 + 2 * e)], abs=1e-9)
    assert res.final.t == pytest.approx(t3, abs=1e-9)
    assert res.warnings == [f"stopped at t = {t3:.6g} s after numerics.max_impacts = 2 impacts"]
