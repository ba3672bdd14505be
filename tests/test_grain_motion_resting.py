"""The Python grain loop: a grain on a still plate whose contact point moves away slower than it can rise (1e-12 m/s
up: a height of at most v^2 / 2g = 5e-26 m, far below the round-off of the gap, ~3e-17 m) is resting: its flight
ends at once, it lands (the landing loss 1/2 m v^2) and slides for the whole run, without a rocking contact and
without stalling, whatever rest_velocity (even zero, through the API; scenes ask for a positive one)."""
import pytest

from symmech.grain import motion
from test_grain_motion_closed_forms import A, M, frictionless, numerics, sphere, state


@pytest.mark.parametrize("rest_velocity", [1e-5, 0.0])
def test_a_grain_resting_on_a_pushing_plate_lands_and_slides(rest_velocity):
    v_up, v_x, t_end = 1e-12, 0.01, 0.003
    model = sphere(frictionless(0.5), mu=0.0)
    res = motion.simulate(model, numerics(rest_velocity=rest_velocity), state(z=A, v=(v_x, 0.0, v_up)), t_end)
    assert res.impacts == [] and res.warnings == []
    assert res.extra["landings"] == 1 and res.extra["rocking_contacts"] == 0
    assert res.time_in == {"flight": 0.0, "sliding": pytest.approx(t_end, abs=1e-15)}
    assert res.final.t == t_end
    assert res.final.r.tolist() == [pytest.approx(v_x * t_end, rel=1e-12), 0.0, pytest.approx(A, abs=1e-18)]
    assert res.final.v.tolist() == [pytest.approx(v_x, rel=1e-12), 0.0, 0.0]
    budget = res.extra["energy_budget"]
    assert budget["lost_at_landings_J"] == pytest.approx(0.5 * M * v_up**2, rel=1e-6)
    assert budget["lost_in_sliding_J"] == 0.0
