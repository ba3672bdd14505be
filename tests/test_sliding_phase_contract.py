"""A sliding phase's contract, by hand: a tilted ellipsoid spinning on a rough plate starts to slip at the speed of
its contact point, |w x R|, with R the ellipsoid's support point written out here; a grain spinning about the normal
on a still frictionless plate keeps its spin and turns at that rate (its orientation a closed-form quaternion, of
unit norm), the phase advancing chunk by chunk to its end.

Expected values are computed here from the geometry: the support point of x^T (Q A^-2 Q^T) x = 1 below the centre is
R = -E e_z / sqrt(e_z . E e_z), E = Q A^2 Q^T; the friction then pulls the centre against the slip at mu g.
"""
import math

import numpy as np
import pytest

from symmech.grain import flight, sliding

G = 9.81
MASS = 2e-3  # kg
AXES = (3e-3, 2e-3, 1e-3)  # m
Q0 = np.array([0.9, 0.3, -0.2, 0.25]) / math.sqrt(0.9**2 + 0.3**2 + 0.2**2 + 0.25**2)


def ellipsoid():
    a, b, c = AXES
    inertia = (MASS * (b * b + c * c) / 5, MASS * (a * a + c * c) / 5, MASS * (a * a + b * b) / 5)
    return sliding.Body(AXES, MASS, inertia, True)


def still_plate(mu):
    return sliding.Sliding((0.0, 0.0, -G), flight.Vibration(0.0, 1.0, 0.0, (0.0, 0.0, 1.0)), mu)


def turned_about_z(angle, q):
    """The quaternion product (cos a/2, 0, 0, sin a/2) q, written out."""
    c, s = math.cos(angle / 2), math.sin(angle / 2)
    w, x, y, z = q
    return np.array([c * w - s * z, c * x - s * y, c * y + s * x, c * z + s * w])


def support_point(axes, Q):
    """R (3,) [m] from the centre to the lowest point of the ellipsoid of semi-axes `axes` turned by Q."""
    E = Q @ np.diag(np.square(axes)) @ Q.T
    return -E[:, 2] / math.sqrt(E[2, 2])


def test_a_tilted_ellipsoid_spinning_on_a_rough_plate_slips_at_its_contact_points_speed():
    """A short phase from rest with spin W about the normal: the contact point moves at s = (w x R)_t, so friction
    pushes the centre: it gains mu g tau against s and the friction loss is m mu g |s| tau (the slip changes by
    ~mu g tau / |s| ~ 1e-4 over tau, its direction turns by W tau = 1e-3 rad)."""
    mu, spin, tau = 0.3, 100.0, 1e-5
    R = support_point(AXES, flight.rotation_matrix(Q0))
    slip = spin * np.array([-R[1], R[0]])  # (W e_z x R)_t
    assert np.hypot(*slip) > 0.05  # tilted: the contact point is well off the vertical through the centre
    res = sliding.slide(still_plate(mu), ellipsoid(), 0.0, np.zeros(2), np.zeros(2), Q0.copy(),
                        np.array([0.0, 0.0, spin]), tau, [], tau / 20, 1e-10)
    expected_v = -mu * G * tau * slip / np.hypot(*slip)
    np.testing.assert_allclose(res.v, expected_v, rtol=2e-3, atol=0.0)
    assert res.dissipated == pytest.approx(MASS * mu * G * np.hypot(*slip) * tau, rel=2e-3)


def test_a_spin_about_the_normal_on_a_frictionless_plate_turns_the_grain_at_that_rate_chunk_by_chunk():
    """mu = 0: no torque about the normal, so w = (0, 0, W) stays and q(t) = q_z(W t) q0, |q| = 1 to round-off;
    progress is told each chunk's end, increasing, within (t0, t_end]."""
    spin, t_end, step = 40.0, 0.2, 1e-3  # five chunks of 40 steps
    seen = [0.0]

    def progress(t):
        assert seen[-1] < t <= t_end, (seen[-1], t)
        seen.append(t)
    res = sliding.slide(still_plate(0.0), ellipsoid(), 0.0, np.zeros(2), np.zeros(2), Q0.copy(),
                        np.array([0.0, 0.0, spin]), t_end, [0.1], step, 1e-10, progress)
    assert res.t == t_end and not res.lifted
    assert len(seen) >= 6 and seen[-1] == t_end
    np.testing.assert_allclose(res.w, [0.0, 0.0, spin], rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(res.q, turned_about_z(spin * t_end, Q0), atol=1e-8)
    assert abs(float(np.linalg.norm(res.q)) - 1.0) < 4e-16
    np.testing.assert_allclose(res.samples[3][0], turned_about_z(spin * 0.1, Q0), atol=1e-8)
    np.testing.assert_allclose(res.v, 0.0, atol=1e-15)
