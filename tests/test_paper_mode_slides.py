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
