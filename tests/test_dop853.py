"""symmech's DOP853 tableau (``numerics.dop853``) is the one scipy's ``solve_ivp(method="DOP853")`` steps with.

The compiled grain engine must take the Python loop's steps exactly, so every coefficient is compared
with scipy's transcription of Hairer's ``dop853.f`` bit for bit (the runtime never imports that
private scipy module; this test may). The classical order conditions are checked independently.
"""
import numpy as np
import pytest
from scipy.integrate._ivp import dop853_coefficients as scipy_dop

from symmech.numerics import dop853_tableau as dop853


@pytest.mark.parametrize("name", ["A", "B", "C", "E3", "E5", "D"])
def test_every_coefficient_equals_scipys_bit_for_bit(name):
    ours, theirs = getattr(dop853, name), getattr(scipy_dop, name)
    assert ours.dtype == theirs.dtype and ours.shape == theirs.shape
    assert np.array_equal(ours.view(np.int64), theirs.view(np.int64))  # also tells 0.0 from -0.0


def test_sizes_equal_scipys():
    for name in ("N_STAGES", "N_STAGES_EXTENDED", "INTERPOLATOR_POWER"):
        assert getattr(dop853, name) == getattr(scipy_dop, name)


def test_order_conditions_of_the_8th_order_weights():
    """Row sums of A equal C (consistency), and sum_i b_i c_i^(k-1) = 1/k for k = 1..8 (the bushy-tree
    conditions of order 8), each to 1e-15."""
    A, B, C, n = dop853.A, dop853.B, dop853.C, dop853.N_STAGES
    assert np.allclose(A.sum(axis=1), C, rtol=0, atol=1e-15)
    for k in range(1, 9):
        assert abs(B @ C[:n] ** (k - 1) - 1 / k) < 1e-15
    # The error estimators weigh differences of two consistent formulas: their weights sum to zero.
    assert abs(dop853.E5.sum()) < 1e-15 and abs(dop853.E3.sum()) < 1e-15
