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
