"""The sweep's statistics at their edges, by hand: failed grains (NaN rows) are counted per point and left out of
the means, and identical normal populations overlap completely, silently (their crossing points are 0/0, which the
overlap's closed form resolves, not a warning for the user to read)."""
import warnings

import numpy as np
import pytest
from scipy.stats import norm

from symmech.grain import sweep


def test_failed_grains_are_counted_per_point_and_left_out_of_the_means():
    """Two points of three grains (vx, vy, flight fraction); the second grain of point 0 failed (NaN)."""
    nan = float("nan")
    grid = np.array([[[0.1, 0.0, 0.9], [nan, nan, nan], [0.3, 0.2, 0.1]],
                     [[0.2, 0.0, 0.0], [0.4, 0.0, 0.6], [0.6, 0.3, 0.8]]])
    out = sweep.statistics(grid)
    assert out["failed"].tolist() == [1.0, 0.0]
    np.testing.assert_allclose(out["mean_vx"], [0.2, 0.4], rtol=1e-15)
    np.testing.assert_allclose(out["hop_fraction"], [1 / 2, 2 / 3], rtol=1e-15)  # flight > 1/2: 0.9; 0.6, 0.8


def test_identical_normal_populations_overlap_completely_and_silently():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ovl = sweep.overlap_normal(np.array([0.1, 0.1]), np.array([0.02, 0.02]), np.array([0.1, 0.3]),
                                   np.array([0.02, 0.02]))
    assert ovl[0] == 1.0
    # equal spreads 0.02, means 0.2 apart: the densities cross at the midpoint, overlap 2 Phi(-0.1 / 0.02)
    assert ovl[1] == pytest.approx(2 * norm.cdf(-5.0), rel=1e-9)
