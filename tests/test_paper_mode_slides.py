"""Paper mode's sliding grain against Coulomb's closed form: a point mass released on a still plate with a speed
v0 along X falls onto its lowest node (20 nodes: a short drop), lands once, then stops v1^2 / (2 mu g) further on
(v1 its speed after the landing; the explicit step adds O(v0 dt)), its position carried by its velocity."""
import math

import numpy as np

from grain_sliding_reference import on_plane, sphere
from symmech.grain import motion, paper_mode

G = 9.81


def test_a_point_mass_slides_to_a_stop_at_the_coulomb_distance():
    mu, v0, dt = 0.3, 0.5, 1e-4
    model = sphere(mu=mu, rotation=False)
    num = motion.Numerics(mode="paper", dt=dt, nodes=20, sample_interval=0.05)
    res = paper_mode.simulate(model, num, on_plane(v=(v0, 0.0, 0.0)), 0.25)
    [landing] = res.impacts
    assert math.isclose(landing["r"][0], v0 * landing["t"], rel_tol=1e-12)  # the drop keeps the speed along X
    v1 = landing["v_after"][0]
    assert 0.45 < v1 <= v0
    stop = landing["r"][0] + v1**2 / (2 * mu * G)
    assert math.isclose(res.final.r[0], stop, abs_tol=2 * v0 * dt)
    np.testing.assert_array_equal(res.final.v[:2], [0.0, 0.0])
    assert res.final.r[1] == 0.0


def test_a_grain_leaves_a_plate_that_falls_faster_than_gravity():
    """Vertical vibration s = A sin(w t), Gamma = A w^2 / g = 2: the plate falls faster than gravity while
    sin(w t) > 1/2 (w t in (pi/6, 5 pi/6)), a third of each period, and a grain that lands in that window cannot stay
    on it (the normal force would be negative). Released on the plate (a short drop onto its lowest node), it lands
    at 4.3 ms, in that window: it flies on and lands again (measured 32.8 ms), most of 1.2 periods in the air."""
    omega = 2 * math.pi * 25
    model = sphere(mu=0.4, amplitude=2 * G / omega**2, rotation=False)
    num = motion.Numerics(mode="paper", dt=2e-5, nodes=20, sample_interval=0.01)
    res = paper_mode.simulate(model, num, on_plane(), 1.2 * 2 * math.pi / omega)
    first = res.impacts[0]["t"]
    assert math.pi / 6 < omega * first < 5 * math.pi / 6
    assert len(res.impacts) >= 2
    assert res.time_in["flight"] > 0.5 * 2 * math.pi / omega


def test_as_printed_a_plastic_landing_lifts_nothing_off():
    """As printed, (64) lifts a grain off only when z'_c > 0 after the impact. A point mass 0.1 mm above a still
    plate, e_n = 0: the printed contact test first fires at step k = 45 (the explicit fall h - g dt^2 k(k+1)/2 is
    first below 0 there), the impact leaves z'_c = 0 exactly, and the grain slides from that step on, losing mu g dt
    of its 0.5 m/s each of the 56 steps to t = 0.01 s: one impact, no second."""
    mu, v0, dt = 0.3, 0.5, 1e-4
    num = motion.Numerics(mode="paper", dt=dt, nodes=20, sample_interval=0.01, as_printed=True)
    res = paper_mode.simulate(sphere(mu=mu, rotation=False), num, on_plane(v=(v0, 0.0, 0.0), z=1.1e-3), 0.01)
    assert len(res.impacts) == 1
    landing = res.impacts[0]
    assert math.isclose(landing["t"], 45 * dt, rel_tol=1e-12) and landing["v_after"][2] == 0.0
    assert math.isclose(res.final.v[0], v0 - 56 * mu * G * dt, rel_tol=1e-12)
    assert res.final.v[2] == 0.0
