"""Free and forced response of a q'' + b q' + c q = Q against the damped oscillator in closed form:
grids of one and two points, a grid that does not start at t = 0, and the phase of the forced
amplitude (the convention Q e^{i omega t}: q'' -> -omega^2 q, q' -> i omega q)."""
import math

import numpy as np
import pytest

from symmech.smm import numeric

M, K, C = 2.0, 800.0, 4.0            # [kg], [N/m], [N s/m]
W0 = math.sqrt(K / M)
Z = C / (2 * math.sqrt(K * M))
WD = W0 * math.sqrt(1 - Z * Z)
A, B, CC = np.array([[M]]), np.array([[C]]), np.array([[K]])


def oscillator(q0, v0, tau):
    """q(tau) of the damped oscillator from q(0) = q0, q'(0) = v0."""
    return np.exp(-Z * W0 * tau) * (q0 * np.cos(WD * tau) + (v0 + Z * W0 * q0) / WD * np.sin(WD * tau))


def test_one_time_point_is_the_initial_state():
    q = numeric.free_response(A, B, CC, np.array([0.01]), np.array([0.3]), np.array([0.0]))
    np.testing.assert_array_equal(q, [[0.01]])


@pytest.mark.parametrize("t", [np.array([0.0, 0.05]), np.linspace(0.3, 1.3, 201)])
def test_grid_from_its_first_time(t):
    """The state at t[0] is (q0, v0); two points take one step, a grid from t0 = 0.3 s runs tau = t - t0."""
    q = numeric.free_response(A, B, CC, np.array([0.01]), np.array([0.3]), t)[:, 0]
    np.testing.assert_allclose(q, oscillator(0.01, 0.3, t - t[0]), rtol=0, atol=1e-12)


def test_forced_amplitude_and_phase():
    """q = Q / (k - m w^2 + i c w): the response lags the force by atan2(c w, k - m w^2) in [0, pi]."""
    w = np.array([0.0, 5.0, W0, 40.0])
    H = numeric.frequency_response(A, B, CC, np.array([1.0]), w)[:, 0]
    np.testing.assert_allclose(H, 1 / (K - M * w**2 + 1j * C * w), rtol=1e-13)
    assert H[2] == pytest.approx(-1j / (C * W0), rel=1e-13)  # at resonance a quarter period behind
