"""The Python grain loop on a plate vibrating along the normal a little above the throw threshold (Gamma = 1.05):
a point mass slides with the plate, lifts off where the plate accelerates down at g, hops and lands plastically
(e = 0), once a period. The hop, about 10 ms, is shorter than the 10 ms scan step: the flight after a lift-off has
to rise above round-off first, then find the landing inside that step. Lift-off time, hop duration and approach
speed come from the closed-form flight relative to the plate (solved here with scipy's brentq); the time spent
sliding sums the three sliding phases."""
import itertools
import math

import pytest
from scipy.optimize import brentq

from symmech.grain import motion
from test_grain_motion_closed_forms import A, G, frictionless, sphere, state

GAMMA, FREQ = 1.05, 20.0  # plate acceleration amplitude / g; frequency [Hz]
OMEGA = 2 * math.pi * FREQ
AMP = GAMMA * G / OMEGA**2  # plate z = AMP sin(OMEGA t) [m]


def relative_flight(tau: float, phi: float, amp: float = AMP):
    """Height [m] and velocity [m/s] of a point mass above the plate, tau [s] after leaving it with the plate's
    velocity at the plate phase phi [rad]: the double integral of g (Gamma sin(phi + OMEGA s) - 1)."""
    x = OMEGA * tau
    height = amp * (math.sin(phi) * 2 * math.sin(x / 2) ** 2 + math.cos(phi) * (x - math.sin(x))) - G * tau**2 / 2
    speed = amp * OMEGA * (math.cos(phi) - math.cos(phi + x)) - G * tau
    return height, speed


def test_hops_shorter_than_the_scan_step_land_at_the_closed_form_times():
    phi = math.asin(1 / GAMMA)  # normal force g (1 - GAMMA sin(OMEGA t)) reaches zero
    t_lift = phi / OMEGA
    hop = brentq(lambda tau: relative_flight(tau, phi)[0], 0.05 / FREQ, 1 / FREQ, xtol=1e-15)
    approach = relative_flight(hop, phi)[1]
    assert 9e-3 < hop < 1e-2  # shorter than the scan step below
    t_end = 0.1  # two periods: lift-offs at t_lift and t_lift + 1/FREQ, both landed before t_end
    num = motion.Numerics(tolerance=1e-11, scan_step=1e-2, sample_interval=1e-3)
    res = motion.simulate(sphere(frictionless(0.0), amplitude=AMP, freq=FREQ), num, state(z=A), t_end)
    landings = [t_lift + hop, t_lift + 1 / FREQ + hop]
    assert [i["t"] for i in res.impacts] == [pytest.approx(t, abs=1e-10) for t in landings]
    for imp in res.impacts:
        assert imp["u_before"][2] == pytest.approx(approach, rel=1e-8)
        assert imp["v_after"][2] == pytest.approx(0.0, abs=1e-12)
    assert res.extra["landings"] == 2 and res.extra["rocking_contacts"] == 0
    # sliding: [0, t_lift], [t_lift + hop, t_lift + 1/FREQ], [t_lift + 1/FREQ + hop, t_end]
    assert res.time_in["flight"] == pytest.approx(2 * hop, abs=1e-10)
    assert res.time_in["sliding"] == pytest.approx(t_end - 2 * hop, abs=1e-10)
    assert res.time_in["flight"] + res.time_in["sliding"] == pytest.approx(t_end, abs=1e-15)
    assert res.final.t == t_end


def test_a_lift_off_whose_dip_lies_midway_between_two_scan_points_is_found():
    """At Gamma = 1.001 the normal force g (1 - Gamma sin(OMEGA t)) dips below zero only between 12.14 and 12.86
    ms, its minimum at T/4 = 12.5 ms, midway between the 1 ms scan points 12 and 13 ms, where it is equal (to the
    bit: sin(OMEGA t) is symmetric about T/4) and positive. The grain lifts off at asin(1/Gamma)/OMEGA."""
    midway_dip(motion.simulate)


def test_a_run_that_ends_just_after_a_lift_off_ends_in_flight():
    """Lifting off less than a scan step before the end, the flight cannot rise above round-off before t_end: the
    run ends in flight at t_end (it used to take that for a resting grain, land it and lift it off again, 1000 times,
    and stop with an error)."""
    lift_off_at_the_end(motion.simulate)


def lift_off_at_the_end(simulate):
    """The run above by ``simulate`` (the Python or the compiled loop's), each way of flying: a point mass on a plate
    at Gamma = 2 lifts off at asin(1/Gamma)/OMEGA, d before t_end."""
    gamma = 2.0
    t_lift = math.asin(1 / gamma) / OMEGA
    for flight, d in itertools.product(motion.FLIGHTS, (1e-9, 1e-7, 3e-7, 2e-3)):
        num = motion.Numerics(tolerance=1e-11, scan_step=1e-2, sample_interval=1e-3, flight=flight)
        res = simulate(sphere(frictionless(0.0), amplitude=gamma * G / OMEGA**2, freq=FREQ), num, state(z=A),
                       t_lift + d)
        assert res.final.t == t_lift + d and not res.impacts and res.extra["landings"] == 0
        assert res.time_in["sliding"] == pytest.approx(t_lift, abs=1e-13)
        assert res.time_in["flight"] == pytest.approx(d, abs=1e-13)
        height, speed = relative_flight(d, math.pi / 6, gamma * G / OMEGA**2)  # pi/6: the lift-off's phase
        assert res.final.r[2] - A == pytest.approx(height, abs=1e-14)
        assert res.final.v[2] == pytest.approx(speed, abs=1e-12)


def midway_dip(simulate):
    """The lift-off of the test above by ``simulate`` (the Python or the compiled loop's)."""
    gamma = 1.001
    amp = gamma * G / OMEGA**2
    phi = math.asin(1 / gamma)
    hop = brentq(lambda tau: relative_flight(tau, phi, amp)[0], 1e-5, 0.5 / FREQ, xtol=1e-15)
    num = motion.Numerics(tolerance=1e-11, scan_step=1e-3, sample_interval=1e-3)
    res = simulate(sphere(frictionless(0.0), amplitude=amp, freq=FREQ), num, state(z=A), 0.02)
    assert [i["t"] for i in res.impacts] == [pytest.approx(phi / OMEGA + hop, abs=1e-10)]
    assert res.time_in["flight"] == pytest.approx(hop, abs=1e-10)
