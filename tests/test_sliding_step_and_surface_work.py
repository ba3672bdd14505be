"""Sliding, by hand: paper mode's explicit step per grain, and the work the surface does on a sliding grain when it
vibrates sideways (a Y component of its direction, which no scene of the other tests uses).

Expected values are written out here: the step v + (f - mu n v/|v|) dt grain by grain with `math` (stick when the
step would reverse the slip and |f| <= mu n), and the work as the change of the kinetic energy in the ground frame
plus the friction loss (a point mass on a level plate that vibrates in its own plane: gravity does no work).
"""
import math

import numpy as np
import pytest

from symmech.grain import flight, sliding

G = 9.81
MASS = 2e-3  # kg


def step_by_hand(v, f, mu_n, dt):
    """One grain's paper-mode step (2,) written out: the friction of a slip along v, or of a start along f."""
    speed = math.hypot(*v)
    fn = math.hypot(*f)
    d = (v[0] / speed, v[1] / speed) if speed > 0 else (f[0] / fn, f[1] / fn)
    new = (v[0] + (f[0] - mu_n * d[0]) * dt, v[1] + (f[1] - mu_n * d[1]) * dt)
    reverses = new[0] * d[0] + new[1] * d[1] <= 0
    return (0.0, 0.0) if reverses and fn <= mu_n else new


@pytest.mark.parametrize("mu", [0.5, 0.05])
def test_paper_slide_step_is_each_grains_own_coulomb_step(mu):
    """A batch of grains on a still incline (f = (1, 0) m/s^2, n = g): slow slips (|v| < 1 m/s) brake along
    their own unit direction, a fast one too, a slow slip that would reverse sticks at zero when |f| <= mu n
    (mu = 0.5) and carries on through zero when not (mu = 0.05), a grain at rest starts along f or stays."""
    model = sliding.Sliding((1.0, 0.0, -G), flight.Vibration(0.0, 1.0, 0.0, (0.0, 0.0, 1.0)), mu)
    v = np.array([[0.3, 0.4], [3.0, -4.0], [0.01, 0.0], [0.0, 0.0], [-0.001, 0.0], [0.0, 0.02]])
    dt = 0.01
    got = sliding.slide_step(model, 0.0, v.copy(), dt)
    expected = np.array([step_by_hand(row, (1.0, 0.0), mu * G, dt) for row in v])
    np.testing.assert_allclose(got, expected, rtol=1e-14, atol=1e-17)
    if mu == 0.5:  # the cases the step must tell apart, stated as numbers
        np.testing.assert_allclose(got[0], [0.3 - 0.6 * (mu * G) * dt + dt, 0.4 - 0.8 * (mu * G) * dt], rtol=1e-14)
        assert np.all(got[2:5] == 0.0)  # stuck: nothing left of the slip
    else:
        assert got[4, 0] == pytest.approx(-0.001 + (1.0 + mu * G) * dt, rel=1e-14)  # through zero, |f| > mu n


def point_mass(mu, direction, amplitude=1e-3, omega=50.0):
    vib = flight.Vibration(amplitude, omega, 0.0, direction)
    model = sliding.Sliding((0.0, 0.0, -G), vib, mu)
    body = sliding.Body((1e-3,) * 3, MASS, (2e-10,) * 3, False)
    return model, body, vib


def slide(model, body, v0, t_end, sample_times=()):
    return sliding.slide(model, body, 0.0, np.zeros(2), np.asarray(v0, float), np.array([1.0, 0, 0, 0]),
                         np.zeros(3), t_end, list(sample_times), t_end / 20, 1e-11)


def surface_velocity(vib, t):
    return vib.amplitude * vib.omega * math.cos(vib.omega * t + vib.phase) * np.asarray(vib.direction)[:2]


@pytest.mark.parametrize("direction", [(0.6, 0.8, 0.0), (0.0, 1.0, 0.0)])
def test_a_grain_held_by_a_sideways_vibrating_plate_takes_the_plates_kinetic_energy(direction):
    """Stuck (mu n = 19.6 m/s^2 above the plate's 2.5 m/s^2), the grain moves with the plate: the surface's work is
    m (|v_s(t)|^2 - |v_s(0)|^2) / 2 = m (A w)^2 (cos^2 w t - 1) / 2, and nothing is lost."""
    model, body, vib = point_mass(2.0, direction)
    t_end = 0.05
    res = slide(model, body, (0.0, 0.0), t_end, sample_times=[-0.01, 0.0, 0.02, 0.05, 0.07])
    assert not res.lifted and res.t == t_end
    times, r, v = res.samples[:3]  # only the sample times within the phase [0, t_end), where it stays stuck
    np.testing.assert_array_equal(times, [0.0, 0.02])
    np.testing.assert_allclose(np.hstack([r, v]), 0.0, atol=1e-12)
    np.testing.assert_allclose(res.v, [0.0, 0.0], atol=1e-12)
    expected = 0.5 * MASS * (vib.amplitude * vib.omega) ** 2 * (math.cos(vib.omega * t_end) ** 2 - 1.0)
    assert res.work == pytest.approx(expected, rel=1e-9)
    assert abs(res.dissipated) < 1e-9 * abs(expected)


@pytest.mark.parametrize("direction", [(0.6, 0.8, 0.0), (0.0, 1.0, 0.0)])
def test_a_grain_slipping_on_a_sideways_vibrating_plate_closes_its_energy_budget(direction):
    """Slipping (mu n = 0.49 m/s^2 below the plate's 2.5 m/s^2): the surface's work equals the change of the
    ground-frame kinetic energy m |v + v_s|^2 / 2 plus the friction loss (which is positive)."""
    model, body, vib = point_mass(0.05, direction)
    t_end, v0 = 0.05, np.array([0.01, -0.005])
    res = slide(model, body, v0, t_end)
    assert not res.lifted and res.t == t_end
    kinetic = [0.5 * MASS * float(np.sum((v + surface_velocity(vib, t)) ** 2)) for t, v in ((0.0, v0), (t_end, res.v))]
    assert res.dissipated > 0
    assert res.work == pytest.approx(kinetic[1] - kinetic[0] + res.dissipated, rel=1e-7)


@pytest.mark.parametrize("g_k, v", [((1.0, 0.0, -2.0), (-0.005, 0.0)), ((0.5, 0.5, -3.0), (0.01, 0.0))])
def test_paper_slide_step_sticks_on_the_edges_it_documents(g_k, v):
    """mu = 0.5, dt = 0.01 s, both exact in binary: |f| = mu n = 1 m/s^2 exactly (the cone's edge still holds the
    grain), and a slip the step brings to exactly zero along its direction, v_new = (0, 0.005) m/s (it sticks)."""
    model = sliding.Sliding(g_k, flight.Vibration(0.0, 1.0, 0.0, (0.0, 0.0, 1.0)), 0.5)
    got = sliding.slide_step(model, 0.0, np.array([v]), 0.01)
    assert step_by_hand(v, g_k[:2], 0.5 * -g_k[2], 0.01) == (0.0, 0.0)
    np.testing.assert_array_equal(got, [[0.0, 0.0]])


def test_a_sphere_rolls_down_an_incline_at_five_sevenths_of_the_drive():
    """A solid sphere (I = 2/5 m r^2) at rest on a still 0.2 rad incline, mu = 1 (the stick force f/3.5 is inside the
    cone): it rolls without slipping, x = (5/7) g sin(0.2) t^2 / 2, v = (5/7) g sin(0.2) t, spin v / r about Y."""
    radius, alpha, t_end = 0.01, 0.2, 0.1
    model = sliding.Sliding((G * math.sin(alpha), 0.0, -G * math.cos(alpha)),
                            flight.Vibration(0.0, 1.0, 0.0, (0.0, 0.0, 1.0)), 1.0)
    body = sliding.Body((radius,) * 3, MASS, (0.4 * MASS * radius**2,) * 3, True)
    res = sliding.slide(model, body, 0.0, np.zeros(2), np.zeros(2), np.array([1.0, 0, 0, 0]), np.zeros(3), t_end,
                        [], t_end / 20, 1e-11)
    a = 5 / 7 * G * math.sin(alpha)
    np.testing.assert_allclose(res.r, [a * t_end**2 / 2, 0.0], rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(res.v, [a * t_end, 0.0], rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(res.w, [0.0, a * t_end / radius, 0.0], rtol=1e-9, atol=1e-12)
    assert abs(res.dissipated) < 1e-12
