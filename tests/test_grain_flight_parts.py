"""The grain's flight parts against closed forms written out here: the exact translation relative to a vibrating
surface, the surface phase, and quaternions of rotation matrices (every branch of Shepperd's method)."""
import math
from types import SimpleNamespace

import numpy as np
import pytest
import scipy.integrate

from symmech.grain.flight import RotationFlight, Vibration, bounces, quaternion_from_matrix, rotation_matrix, translate


def matrix_of(q):
    """Rotation matrix of the unit quaternion (w, x, y, z) (Hamilton's convention)."""
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


# a generic turn (trace largest), turns near pi about X, Y and Z (that diagonal entry largest), and two turns with
# no Y part whose Q[2, 1] or Q[1, 2] (0.72) exceeds every diagonal entry: the Y branch would divide by s = 0
@pytest.mark.parametrize("q", [(0.8, 0.2, -0.4, 0.3), (0.01, 1.0, 0.02, -0.03), (0.02, -0.03, 1.0, 0.05),
                               (0.03, 0.05, -0.02, 1.0), (-0.6, 0.3, 0.5, -0.2), (0.6, 0.6, 0.0, math.sqrt(0.28)),
                               (0.6, -0.6, 0.0, math.sqrt(0.28))])
def test_quaternion_of_a_rotation_matrix_is_the_one_it_was_built_from(q):
    q = np.array(q) / np.linalg.norm(q)
    expected = q if q[0] > 0 else -q  # positive scalar part
    np.testing.assert_allclose(quaternion_from_matrix(matrix_of(q)), expected, rtol=0, atol=1e-14)
    np.testing.assert_allclose(rotation_matrix(q), matrix_of(q), rtol=0, atol=1e-15)


def test_phase_is_reduced_to_zero_to_two_pi():
    vib = Vibration(1e-3, 2 * math.pi * 10, -0.5, (0.0, 0.0, 1.0))
    # omega t + phase = 20 pi - 0.5, 1.5 pi - 0.5, -0.5
    np.testing.assert_allclose(vib.phase_at([1.0, 0.075, 0.0]),
                               [2 * math.pi - 0.5, 1.5 * math.pi - 0.5, 2 * math.pi - 0.5], rtol=1e-12)


@pytest.mark.parametrize("amplitude", [0.0, 1e-3])
def test_translation_relative_to_the_surface_is_gravity_less_the_surface_motion(amplitude):
    A, omega, phase, d = amplitude, 2 * math.pi * 50, 0.3, np.array([0.6, 0.0, 0.8])
    r0, v0, g = np.array([0.1, -0.2, 0.005]), np.array([0.3, 0.1, 1.2]), np.array([0.0, 1.0, -9.81])
    t0, t = 2.0, np.array([2.0, 2.004, 2.013])
    tau = (t - t0)[:, None]

    def s(time):
        return A * d * np.sin(omega * time + phase)

    def s_rate(time):
        return A * omega * d * np.cos(omega * time + phase)

    # r'' = g - s''(t): r = r0 + v0 tau + g tau^2 / 2 - (s(t) - s(t0) - s'(t0) tau), v its derivative
    r_exact = r0 + v0 * tau + 0.5 * g * tau**2 - (s(t[:, None]) - s(t0) - s_rate(t0) * tau)
    v_exact = v0 + g * tau - (s_rate(t[:, None]) - s_rate(t0))
    r, v = translate(r0, v0, g, Vibration(A, omega, phase, tuple(d)), t0, t)
    np.testing.assert_allclose(r, r_exact, rtol=0, atol=1e-13)
    np.testing.assert_allclose(v, v_exact, rtol=0, atol=1e-12)
    # positions, velocities and gravity are real: a complex one is refused, not flown with its real part kept
    for k in range(3):
        vectors = [r0.tolist(), v0.tolist(), g.tolist()]
        vectors[k] = [1j, 0.0, 0.0]
        with pytest.raises(TypeError):
            translate(*vectors, Vibration(A, omega, phase, tuple(d)), t0, t)


def test_a_grain_that_does_not_spin_keeps_its_orientation_and_zero_spin():
    q0 = np.array([0.8, 0.2, -0.4, 0.3]) / np.linalg.norm([0.8, 0.2, -0.4, 0.3])
    q, w = RotationFlight([1.0, 2.0, 3.0], q0, np.zeros(3), 0.0, 1e-10, 0.1).state(np.array([0.0, 0.5, 2.0]))
    np.testing.assert_array_equal(q, np.tile(q0, (3, 1)))
    np.testing.assert_array_equal(w, np.zeros((3, 3)))
    with pytest.raises(TypeError):  # times are real: a complex one is refused, as by a spinning grain's rotation
        RotationFlight([1.0, 2.0, 3.0], q0, np.zeros(3), 0.0, 1e-10, 0.1).state([0.5 + 0.5j])


def test_a_spin_about_a_principal_axis_turns_at_its_rate_across_chunks():
    """w = (0, 0, 10) rad/s about the body's z axis, a principal axis (I w' = -w x I w = 0): w stays, and from
    q0 = 1 the orientation is q(t) = (cos 5t, 0, 0, sin 5t), asked at times that each extend the rotation by a
    chunk of 0.02 s (some steps each), the next chunk starting where the last ended. Asked at t0 first, before any
    chunk, a rotation is its start state as given, bit for bit (no step taken, nothing renormalised; it was memory
    left unwritten)."""
    q_any = np.array([0.8, 0.2, -0.4, 0.3]) / np.linalg.norm([0.8, 0.2, -0.4, 0.3])
    q, w = RotationFlight([1.0, 2.0, 3.0], q_any, np.array([0.3, -2.0, 10.0]), 0.0, 1e-10, 0.02).state(
        np.array([0.0, 0.0]))
    np.testing.assert_array_equal(q, [q_any, q_any])
    np.testing.assert_array_equal(w, [[0.3, -2.0, 10.0]] * 2)
    flight = RotationFlight([1.0, 2.0, 3.0], np.array([1.0, 0.0, 0.0, 0.0]), np.array([0.0, 0.0, 10.0]), 0.0, 1e-10,
                            0.02)
    for t in (0.01, 0.03, 0.05):
        q, w = flight.state(t)
        np.testing.assert_allclose(q, [np.cos(5 * t), 0.0, 0.0, np.sin(5 * t)], rtol=0, atol=1e-8)
        np.testing.assert_allclose(w, [0.0, 0.0, 10.0], rtol=0, atol=1e-12)


def test_a_single_precision_rotation_matrix_gives_the_quaternion_of_its_entries():
    """A turn of 0.3 rad about z stored in float32 (an input the API takes) is read in double precision: from its
    stored entries c = Q[0, 0], s = Q[1, 0], q = (w, 0, 0, s / (2 w)) with w = sqrt(2 + 2c) / 2 (trace 1 + 2c, the
    largest of Shepperd's four), to round-off, not to float32's 1e-8."""
    c, s = math.cos(0.3), math.sin(0.3)
    Q = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]], dtype=np.float32)
    c, s = float(Q[0, 0]), float(Q[1, 0])
    w = math.sqrt(2 + 2 * c) / 2
    np.testing.assert_allclose(quaternion_from_matrix(Q), [w, 0.0, 0.0, s / (2 * w)], rtol=0, atol=1e-15)
    # a quaternion is real: one given as complex numbers is refused, not turned into a matrix of its real parts
    with pytest.raises(TypeError):
        rotation_matrix([w + 0.1j, 0.0, 0.0, s / (2 * w)])


def test_a_failed_rotation_integration_says_why(monkeypatch):
    failed = SimpleNamespace(success=False, message="Required step size is less than spacing between numbers.")
    monkeypatch.setattr(scipy.integrate, "solve_ivp", lambda *args, **kwargs: failed)
    rotation = RotationFlight([1.0, 2.0, 3.0], np.array([1.0, 0.0, 0.0, 0.0]), np.array([0.0, 0.0, 10.0]), 0.0, 1e-10,
                              0.02)
    with pytest.raises(RuntimeError, match=r"^torque-free rotation did not integrate: Required step size is less"):
        rotation.state(0.01)


def test_bounces_of_a_sequence_off_a_still_surface():
    """Rebound speeds v0 e^k and flights 2 v0 e^k / g: with v0 = 2 m/s, e = 1/2, g = 10 m/s^2 the flights last 0.4,
    0.2, 0.1 s, so 0.6 s holds 2 of them (+ the last impact); a rest speed of v0 / 8 ends it after 3 rebounds; an
    elastic bounce lasts 0.4 s; a launch at or below the rest speed, or a plastic one, is one impact."""
    assert bounces(2.0, 0.5, 10.0, 1e-3, 0.6) == pytest.approx(3.0, rel=1e-12)
    assert bounces(2.0, 0.5, 10.0, 0.25, 10.0) == pytest.approx(4.0, rel=1e-12)
    assert bounces(2.0, 1.0, 10.0, 0.25, 1.0) == pytest.approx(3.5, rel=1e-12)
    assert bounces(0.2, 0.5, 10.0, 0.25, 1.0) == 1.0
    assert bounces(2.0, 0.0, 10.0, 0.25, 1.0) == 1.0
