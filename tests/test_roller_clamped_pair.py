"""The clamped roller pair at its kinks: with zero preload (the scene default) the law
P = k [(δ - d)₊ - (δ + d)₊] is P = -k d for every d, so it must behave as the linear law at rest too."""
import numpy as np
import pytest

from symmech.trolley.elastic import system as el, body as el_body, frame as el_frame

K = (1e6, 1e6, 2e6, 1.5e6, 1e6)
AT_REST = el_frame.FrameState(np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3), np.array([0.0, 1.0, 0.0]))


def system(law, preload=(0.0,) * 5):
    rollers = el_body.Rollers(K, (0.0,) * 5, law, preload)
    return el.System(el_body.ElasticModel(100.0, (0.8, 0.5, 0.0), (20.0, 30.0, 25.0, 0, 0, 0), 2.0, 1.0, 9.81, rollers,
                                      effects=el_body.Effects(damping=False)))


def test_zero_preload_pair_is_the_linear_law():
    pair, linear = system("clamped_pair"), system("linear")
    for d in (np.zeros(5), np.array([1e-4, -2e-4, 0.0, 3e-5, -1e-6])):
        force, kt = el_body.roller_forces(pair.mdl.rollers, d, np.zeros(5), False)
        np.testing.assert_allclose(force, -np.array(K) * d, rtol=1e-15, atol=0)
        np.testing.assert_array_equal(kt, -np.array(K))  # one roller engaged on either side of d = 0
    # the weight settles on the rollers as on linear springs; the frequencies at rest are the linear ones
    q = pair.quasi_static(AT_REST)
    np.testing.assert_allclose(q, linear.quasi_static(AT_REST), rtol=1e-12)
    assert np.abs(q).max() > 1e-5
    np.testing.assert_allclose(pair.linear_modes(AT_REST, np.zeros(5))[0],
                               linear.linear_modes(AT_REST, np.zeros(5))[0], rtol=1e-12)


@pytest.mark.parametrize("preload", [2e-4, -2e-4])
def test_tangent_at_a_kink_is_the_mean_of_its_sides(preload):
    """At d = ±δ one roller of the pair just touches: the tangent stiffness is the mean of the one-sided slopes."""
    rollers = el_body.Rollers(K, (0.0,) * 5, "clamped_pair", (preload,) * 5)
    h = 1e-9
    for d in (np.full(5, preload), np.full(5, -preload)):
        left = (el_body.roller_forces(rollers, d, np.zeros(5), False)[0]
                - el_body.roller_forces(rollers, d - h, np.zeros(5), False)[0]) / h
        right = (el_body.roller_forces(rollers, d + h, np.zeros(5), False)[0]
                 - el_body.roller_forces(rollers, d, np.zeros(5), False)[0]) / h
        kt = el_body.roller_forces(rollers, d, np.zeros(5), False)[1]
        np.testing.assert_allclose(kt, (left + right) / 2, rtol=1e-6)


def test_linear_law_ignores_the_preload():
    """The preload belongs to the clamped pair: the linear law is P = -k d - c ḋ whatever it says."""
    c = (100.0, 200.0, 300.0, 400.0, 500.0)
    rollers = el_body.Rollers(K, c, "linear", (1e-3,) * 5)
    d, dd = np.array([1e-4, -2e-4, 0.0, 3e-5, -1e-6]), np.array([0.1, -0.2, 0.3, 0.0, 0.05])
    force, kt = el_body.roller_forces(rollers, d, dd, True)
    np.testing.assert_allclose(force, -np.array(K) * d - np.array(c) * dd, rtol=1e-15, atol=0)
    np.testing.assert_array_equal(kt, -np.array(K))
    assert el_body.roller_energy(rollers, d) == pytest.approx(0.5 * np.sum(np.array(K) * d * d), rel=1e-15)
