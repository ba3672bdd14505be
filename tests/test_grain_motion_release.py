"""How the Python grain loop starts a grain released on the plane: a grain at rest on a plane that pushes slides from
the start (no landing, no impact, no flight), whatever its spin about the normal and however the plate vibrates;
and a contact point approaching slowly, above the round-off of a spinning grain, is an impact."""
import math

import numpy as np
import pytest

from symmech.grain import flight, motion
from symmech.grain.coulomb_law import ImpactLaw
from test_grain_motion_closed_forms import A, M, numerics, sphere, state

LAW = ImpactLaw("coulomb", e_n=0.5, e_t=0.0, mu=0.0, check_printed=False)


def assert_slides_from_the_start(res, t_end, v_release=0.0):
    assert res.impacts == [] and res.extra["landings"] == 0
    assert res.time_in == {"flight": 0.0, "sliding": pytest.approx(t_end, abs=1e-15)}
    assert res.extra["energy_budget"]["lost_at_landings_J"] == pytest.approx(0.5 * M * v_release**2, rel=1e-12, abs=0)
    assert set(res.trajectory[1:, -1]) == {motion.REGIMES.index("sliding")}  # the first row is the start's
    # then a sliding row at every sample time (1 ms apart) from t = 0 on, so the file says it slides at t = 0, up to
    # the end; a sample time within round-off (1e-9 of the interval) before the end is the end's rows, not one more
    samples = np.arange(round(t_end / 1e-3)) * 1e-3
    np.testing.assert_array_equal(res.trajectory[1:len(samples) + 1, 0], samples)
    assert (res.trajectory[len(samples) + 1:, 0] == t_end).all()


def test_released_at_rest_spinning_about_the_normal_slides_from_the_start_and_keeps_its_spin():
    """A sphere at rest on a still plane, spinning at 30 rad/s about the normal: its contact point does not move,
    so it slides (rests) from the start, in place, its spin about the normal kept. The run ends 0.1 ns past its
    sample time 2 ms."""
    res = motion.simulate(sphere(LAW), numerics(), state(z=A, w=(0.0, 0.0, 30.0)), 0.002 + 1e-13)
    assert_slides_from_the_start(res, 0.002 + 1e-13)
    np.testing.assert_allclose(res.final.r, [0.0, 0.0, A], atol=1e-15)
    np.testing.assert_allclose(res.final.v, 0.0, atol=1e-15)
    np.testing.assert_allclose(flight.rotation_matrix(res.final.q) @ res.final.w, [0.0, 0.0, 30.0], rtol=1e-9)


@pytest.mark.parametrize("vz", [0.0, 1e-16])
def test_released_at_rest_on_a_vibrating_plate_rides_it_from_the_start(vz):
    """A sphere at rest on a plate vibrating at Γ = A ω²/g = 0.16 (never lifting it), or leaving it at 1e-16 m/s,
    below the round-off of a contact velocity on that plate (1e3 eps A ω = 2.8e-15 m/s): it rides the plate from
    the start, at rest relative to it."""
    model = sphere(LAW, amplitude=1e-4, freq=20.0)
    assert 1e-4 * (2 * math.pi * 20.0) ** 2 / 9.81 < 0.2
    res = motion.simulate(model, numerics(), state(z=A, v=(0.0, 0.0, vz)), 0.01)
    assert_slides_from_the_start(res, 0.01, vz)
    np.testing.assert_allclose(res.final.r, [0.0, 0.0, A], atol=1e-15)
    np.testing.assert_allclose(res.final.v, 0.0, atol=1e-15)


@pytest.mark.parametrize("spin", [0.0, 30.0])
def test_a_slow_approach_above_round_off_is_an_impact(spin):
    """A sphere (spinning about the normal or not) let go 1e-13 m above the plate at 1e-10 m/s downwards under a
    weak gravity g = 1e-6 m/s²: it arrives at u = sqrt(v0² + 2 g h) = 4.6e-10 m/s, far above the round-off of its
    contact velocity (1e3 eps (|v| + |ω| a) ~ 1e-14 m/s), so it bounces (u⁺ = -e u) and then lands (below
    rest_velocity)."""
    g, h, v0, e = 1e-6, 1e-13, 1e-10, 0.5
    model = motion.Model((A,) * 3, M, (0.0, 0.0, -g), flight.Vibration(0.0, 1.0, 0.0, (0.0, 0.0, 1.0)), LAW, 0.5)
    res = motion.simulate(model, numerics(), state(z=A + h, v=(0.0, 0.0, -v0), w=(0.0, 0.0, spin)), 2e-3)
    u = math.sqrt(v0**2 + 2 * g * h)
    assert len(res.impacts) == 1 and res.extra["landings"] == 1
    imp = res.impacts[0]
    assert imp["t"] == pytest.approx((u - v0) / g, rel=1e-6)
    assert imp["u_before"][2] == pytest.approx(-u, rel=1e-6)
    assert imp["u_after"][2] == pytest.approx(e * u, rel=1e-6)
