"""The grain's body: the solid ellipsoid's inertia against its closed form, its field checks, and the z-x-z Euler
angles against rotation matrices written out here (Rz(psi) Rx(theta) Rz(phi)), generic and at gimbal lock."""
import math

import numpy as np
import pytest

from symmech.grain.body import Ellipsoid, euler_from_matrix, rotation


def rz(a):
    return np.array([[math.cos(a), -math.sin(a), 0.0], [math.sin(a), math.cos(a), 0.0], [0.0, 0.0, 1.0]])


def rx(a):
    return np.array([[1.0, 0.0, 0.0], [0.0, math.cos(a), -math.sin(a)], [0.0, math.sin(a), math.cos(a)]])


def zxz(psi, theta, phi):
    return rz(psi) @ rx(theta) @ rz(phi)


def test_inertia_of_a_solid_ellipsoid_is_m_over_5_times_the_other_two_axes_squared():
    body = Ellipsoid(3.0, 2.0, 1.0, 10.0)  # J'_x = m (b^2 + c^2) / 5 = 10, J'_y = 10 * 10 / 5, J'_z = 10 * 13 / 5
    np.testing.assert_allclose(body.inertia, [10.0, 20.0, 26.0], rtol=1e-15)
    np.testing.assert_allclose(Ellipsoid(0.5, 0.5, 0.5, 2.0).inertia, [0.2, 0.2, 0.2], rtol=1e-15)  # 2/5 m r^2


@pytest.mark.parametrize("field", ["a", "b", "c", "mass"])
@pytest.mark.parametrize("bad", [0.0, -1.0, math.nan, math.inf, "1"])
def test_an_ellipsoid_refuses_a_bad_field_by_name_and_value(field, bad):
    values = {**dict(a=3.0, b=2.0, c=1.0, mass=10.0), field: bad}
    with pytest.raises(ValueError, match=rf"^Ellipsoid\.{field} must be a finite number > 0, got {bad!r}$"):
        Ellipsoid(**values)


def test_euler_angles_of_generic_rotations_are_the_angles_they_were_built_from():
    rng = np.random.default_rng(34)
    angles = np.column_stack([rng.uniform(-3.1, 3.1, 20), rng.uniform(1e-9, math.pi - 1e-3, 20),
                              rng.uniform(-3.1, 3.1, 20)])
    angles[0, 1] = 1e-9  # near gimbal lock, still resolved: sin(theta) is far above the 1e-12 lock threshold
    Q = np.array([zxz(*a) for a in angles])
    np.testing.assert_allclose(euler_from_matrix(Q), angles, rtol=0, atol=1e-12)
    # batch shapes (..., 3, 3) -> (..., 3), and rotation() is the inverse map
    np.testing.assert_allclose(euler_from_matrix(Q.reshape(4, 5, 3, 3)), angles.reshape(4, 5, 3), atol=1e-12)
    np.testing.assert_allclose(rotation(angles.reshape(4, 5, 3)), Q.reshape(4, 5, 3, 3), rtol=0, atol=1e-15)
    with pytest.raises(TypeError, match="not 'complex'"):  # a complex angle is refused, not cut to its real part
        rotation([0.3 + 0.1j, 0.7, 1.1])
    # a single-precision matrix (an input the API takes) is read in double: the angle of its stored values, to
    # round-off, not to float32's 1e-8
    turn = rx(0.3).astype(np.float32)  # about x: psi = phi = 0, theta the angle of the stored cosine and sine
    theta = math.atan2(float(turn[2, 1]), float(turn[1, 1]))
    np.testing.assert_allclose(euler_from_matrix(turn), [0.0, theta, 0.0], rtol=0, atol=1e-16)


@pytest.mark.parametrize("psi, phi", [(0.3, 0.5), (-2.0, 1.2), (2.5, 2.0)])
def test_at_gimbal_lock_psi_is_zero_and_phi_carries_the_whole_turn(psi, phi):
    # theta = 0: Rz(psi) Rz(phi) = Rz(psi + phi); theta = pi: Rz(psi) Rx(pi) Rz(phi) = Rx(pi) Rz(phi - psi)
    for theta, turn in [(0.0, psi + phi), (math.pi, phi - psi)]:
        wrapped = math.atan2(math.sin(turn), math.cos(turn))
        np.testing.assert_allclose(euler_from_matrix(zxz(psi, theta, phi)), [0.0, theta, wrapped], rtol=0,
                                   atol=1e-12)
