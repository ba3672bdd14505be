"""A sliding phase's contract, by hand: a tilted ellipsoid spinning on a rough plate starts to slip at the speed of
its contact point, |w x R|, with R the ellipsoid's support point written out here; a grain spinning about the normal
on a still frictionless plate keeps its spin and turns at that rate (its orientation a closed-form quaternion, of
unit norm), the phase advancing chunk by chunk to its end.

Expected values are computed here from the geometry: the support point of x^T (Q A^-2 Q^T) x = 1 below the centre is
R = -E e_z / sqrt(e_z . E e_z), E = Q A^2 Q^T; the friction then pulls the centre against the slip at mu g.
"""
import math
from types import SimpleNamespace

import numpy as np
import pytest
import scipy.integrate

from symmech.core.scene import SymmechError
from symmech.grain import flight, sliding
from symmech.grain.vectors import SLIDE_STATE

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


@pytest.fixture
def integrations(monkeypatch):
    """Every solve_ivp call of the phase: (method, (t0, t1), y0, stick, status, [event sizes], y at its end)."""
    import scipy.integrate

    calls, solve_ivp = [], scipy.integrate.solve_ivp

    def recorded(fun, span, y0, method, args, **options):
        sol = solve_ivp(fun, span, y0, method=method, args=args, **options)
        calls.append((method, span, np.array(y0), args[0], sol.status, [e.size for e in sol.t_events or []],
                      sol.y[:, -1].copy()))
        return sol
    monkeypatch.setattr(scipy.integrate, "solve_ivp", recorded)
    return calls


def slip_speed(y):
    """|v + (w x R)_t| [m/s] of the ellipsoid of AXES in state y = (r, v, w, q, W, D)."""
    R = support_point(AXES, flight.rotation_matrix(y[7:11]))
    return float(np.hypot(*(y[2:4] + np.cross(y[4:7], R)[:2])))


def s_stiff(tol, step, n0):
    """The documented switch speed tol^(1/2) v_scale, v_scale = (|g| + |n(t0)|) step [m/s]."""
    return math.sqrt(tol) * (G + abs(n0)) * step


def test_a_sphere_sliding_to_rolling_reaches_five_sevenths_of_its_speed_by_dop853_alone(integrations):
    """A sphere launched without spin slips until v = 5/7 v0 at t = 2 v0 / (7 mu g), then rolls (w_y = v / a);
    the friction loss is m v0^2 / 7. Its B is isotropic (the identity times 7/2), so no slip is stiff: every chunk,
    the slip's last ~s_stiff included, runs with DOP853."""
    a, mu, v0 = 2e-3, 0.3, 0.1
    sphere = sliding.Body((a, a, a), MASS, (0.4 * MASS * a * a,) * 3, True)
    res = sliding.slide(still_plate(mu), sphere, 0.0, np.zeros(2), np.array([v0, 0.0]), np.array([1.0, 0, 0, 0]),
                        np.zeros(3), 0.02, [], 1e-3, 1e-9)
    assert 2 * v0 / (7 * mu * G) < 0.02
    np.testing.assert_allclose(res.v, [5 / 7 * v0, 0.0], rtol=1e-7, atol=1e-12)
    np.testing.assert_allclose(res.w, [0.0, 5 / 7 * v0 / a, 0.0], rtol=1e-7, atol=1e-9)
    assert res.dissipated == pytest.approx(MASS * v0 * v0 / 7, rel=1e-7)
    assert {c[0] for c in integrations} == {"DOP853"}
    assert [c[3] for c in integrations][:2] == [False, True]  # the slip, then the rolling (a stick)


def test_a_tilted_ellipsoids_slip_coming_to_rest_goes_implicit_at_s_stiff(integrations):
    """Anisotropic B: a slip from 0.02 m/s decelerates with DOP853 until its speed falls through s_stiff (an
    event), the rest of the slip runs with Radau down to v_stop, and the stick that follows with DOP853."""
    tol, step = 1e-9, 1e-3
    sliding.slide(still_plate(0.3), ellipsoid(), 0.0, np.zeros(2), np.array([0.02, 0.0]), Q0.copy(), np.zeros(3),
                  0.02, [], step, tol)
    switch = s_stiff(tol, step, G)
    assert [(c[0], c[3]) for c in integrations] == [("DOP853", False), ("Radau", False), ("DOP853", True)]
    explicit, implicit, _ = integrations
    assert explicit[5] == [0, 1]  # ended on the switch event
    assert slip_speed(explicit[6]) == pytest.approx(switch, rel=1e-6)
    assert slip_speed(implicit[2]) == pytest.approx(switch, rel=1e-6)
    assert implicit[5] == [1, 0]  # ended on the slip's stop


def test_a_slip_in_the_hysteresis_band_stays_implicit_across_a_chunk_and_leaves_it_at_twice_s_stiff(integrations):
    """On a 0.3 rad incline (mu below the stick limit of the tilted ellipsoid's B) the stick ends near 0.0166 s
    and a slip starts at 2 v_stop with Radau; a chunk (40 steps) ends while its speed is inside the band
    [s_stiff, 2 s_stiff): the next chunk stays implicit, and the switch to DOP853 comes at 2 s_stiff."""
    tol, step, incline = 1e-4, 1e-5, 0.3
    plate = sliding.Sliding((G * math.sin(incline), 0.0, -G * math.cos(incline)),
                            flight.Vibration(0.0, 1.0, 0.0, (0.0, 0.0, 1.0)), 0.2784)
    sliding.slide(plate, ellipsoid(), 0.0, np.zeros(2), np.zeros(2), Q0.copy(), np.zeros(3), 0.0175, [], step, tol)
    switch = s_stiff(tol, step, G * math.cos(incline))
    slips = [c for c in integrations if not c[3]]
    assert [c[0] for c in slips] == ["Radau", "Radau", "DOP853", "DOP853"]
    first, second, third = slips[:3]
    assert first[4] == 0 and first[1][1] == pytest.approx(first[1][0] + 40 * step, rel=1e-12)  # a chunk's end
    assert switch < slip_speed(first[6]) < 2 * switch
    assert second[5] == [0, 1] and slip_speed(second[6]) == pytest.approx(2 * switch, rel=1e-6)
    assert slip_speed(third[2]) == pytest.approx(2 * switch, rel=1e-6)


def test_a_start_at_zero_normal_force_is_a_lift_off_at_once():
    """The surface accelerates down at exactly g at t0 (A omega^2 = g, phase pi/2): n(t0) = 0, so the phase ends
    at t0, lifted, though n = g (1 - cos t) rises after it."""
    plate = sliding.Sliding((0.0, 0.0, -G), flight.Vibration(G, 1.0, math.pi / 2, (0.0, 0.0, 1.0)), 0.3)
    assert plate.normal(0.0) == 0.0 and plate.normal(0.05) > 0.0
    res = sliding.slide(plate, ellipsoid(), 0.0, np.zeros(2), np.array([0.01, 0.0]), Q0.copy(), np.zeros(3), 0.1,
                        [], 1e-3, 1e-9)
    assert res.lifted and res.t == 0.0
    np.testing.assert_array_equal(res.v, [0.01, 0.0])


def test_a_failed_sliding_integration_says_when_and_why(monkeypatch):
    """The solver's failure reaches the user as one line: what failed, at which time, the solver's own reason."""
    failed = SimpleNamespace(success=False, message="Required step size is less than spacing between numbers.")
    monkeypatch.setattr(scipy.integrate, "solve_ivp", lambda *args, **kwargs: failed)
    with pytest.raises(SymmechError, match=r"^sliding integration failed at t = 0.25 s: Required step size is less"):
        sliding.slide(still_plate(0.3), ellipsoid(), 0.25, np.zeros(2), np.array([0.01, 0.0]), Q0.copy(),
                      np.zeros(3), 0.5, [], 1e-3, 1e-9)


def test_a_gentle_drive_starts_a_rolling_spheres_slip_along_a_unit_direction():
    """A sphere (radius a, I = 2/5 m a^2) at rest on a still plate tilted so that g_t = (0.3, -0.4) m/s^2: the
    contact's B = 1 + m a^2 / I = 7/2 on the tangent plane: the stick force holding it is -B^-1 g_t = (-0.6, 0.8)/7
    with n = g, B^-1 g_t has length 1/7 m/s^2 (below 1, where a direction left unnormalised shows) and the slip
    starts along (0.6, -0.8). Its kinetic energy per unit mass at
    v = (0.3, 0, 0.4) m/s, w = (0, 0, 10) rad/s is |v|^2/2 + (I/m) |w|^2/2 = 0.125 + 20 a^2 J/kg."""
    a, mass = 1e-3, 2.0
    ball = sliding.Body((a,) * 3, mass, (0.4 * mass * a * a,) * 3, True)
    plate = sliding.Sliding((0.3, -0.4, -G), flight.Vibration(0.0, 1.0, 0.0, (0.0, 0.0, 1.0)), 0.1)
    q = np.array([1.0, 0.0, 0.0, 0.0])
    contact = sliding._Contact(plate, ball, q)
    y = SLIDE_STATE.pack(r=(0.0, 0.0), v=(0.0, 0.0), w=(0.0, 0.0, 0.0), q=q, work=0.0, loss=0.0)
    phi, n = contact.stick_force(0.0, y)
    np.testing.assert_allclose(phi, [-0.6 / 7, 0.8 / 7], rtol=0, atol=1e-16)
    assert n == G
    np.testing.assert_allclose(contact.slip_direction(0.0, y), [0.6, -0.8], rtol=0, atol=1e-15)
    assert math.isclose(ball.kinetic(np.eye(3), np.array([0.3, 0.0, 0.4]), np.array([0.0, 0.0, 10.0])),
                        0.125 + 20 * a * a, rel_tol=1e-14)


def test_a_phase_whose_events_do_not_advance_time_stops_at_the_guards_count(monkeypatch):
    """Every chunk ends on an event where it started: the phase stops at the chunk after the 200th in a row
    (MAX_STALLED_EVENTS), with one line naming the time and the count, not one chunk later or never."""
    starts = []

    def stalled(fun, span, y0, **kwargs):
        starts.append(span[0])
        if len(starts) > sliding.MAX_STALLED_EVENTS + 1:
            pytest.fail("the stall guard let a stalled phase run on")
        return SimpleNamespace(success=True, status=1, t=np.array([span[0]]), y=np.asarray(y0)[:, None], sol=None,
                               t_events=[np.array([span[0]])])

    monkeypatch.setattr(scipy.integrate, "solve_ivp", stalled)
    with pytest.raises(SymmechError, match=r"^sliding stagnates at t = 0.25 s: 200 regime changes without advancing"):
        sliding.slide(still_plate(0.3), ellipsoid(), 0.25, np.zeros(2), np.array([0.01, 0.0]), Q0.copy(),
                      np.zeros(3), 0.5, [], 1e-3, 1e-9)
    assert starts == [0.25] * (sliding.MAX_STALLED_EVENTS + 1)
