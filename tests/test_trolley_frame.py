"""Generated Λ, ∂Λ/∂θ, A, tangent angles and Λ* against independent constructions."""
import numpy as np
import pytest

from symmech.generated import trolley_frame as frm
from symmech.generated import trolley_printed as printed

RNG_SEED = 20261121


def _rot(axis, angle):
    """Passive elementary rotation, written out by hand (independent of derive.py)."""
    c, s = np.cos(angle), np.sin(angle)
    if axis == 1:
        return np.array([[1, 0, 0], [0, c, s], [0, -s, c]])
    if axis == 2:
        return np.array([[c, 0, -s], [0, 1, 0], [s, 0, c]])
    return np.array([[c, s, 0], [-s, c, 0], [0, 0, 1]])


@pytest.fixture
def angles():
    return np.random.default_rng(RNG_SEED).uniform(-np.pi, np.pi, (50, 3))


def test_lambda_is_product_of_elementary_rotations_yaw_pitch_roll(angles):
    for th1, th2, th3 in angles:
        expected = _rot(1, th1) @ _rot(3, th3) @ _rot(2, th2)
        np.testing.assert_allclose(frm.Lambda(th1, th2, th3), expected, atol=1e-14)


def test_lambda_and_derivatives_match_hand_transcription(angles):
    th = angles.T
    for name in ("Lambda", "dLambda_dth1", "dLambda_dth2", "dLambda_dth3", "A"):
        np.testing.assert_allclose(getattr(frm, name)(*th), getattr(printed, name)(*th), atol=1e-14)


def test_lambda_orthogonal_with_unit_determinant(angles):
    lam = frm.Lambda(*angles.T)
    np.testing.assert_allclose(lam @ np.swapaxes(lam, 1, 2), np.broadcast_to(np.eye(3), lam.shape), atol=1e-14)
    np.testing.assert_allclose(np.linalg.det(lam), 1.0, atol=1e-14)


def test_partial_derivatives_against_central_differences(angles):
    h = 1e-6
    for i in range(3):
        step = np.zeros(3)
        step[i] = h
        fd = (frm.Lambda(*(angles + step).T) - frm.Lambda(*(angles - step).T)) / (2 * h)
        np.testing.assert_allclose(getattr(frm, f"dLambda_dth{i + 1}")(*angles.T), fd, atol=1e-9)


def test_A_gives_omega_of_the_rotating_frame(angles):
    """Passive Λ: Λ̇ = -ω̌ Λ, so ω̌ = -Λ̇ Λᵀ with Λ̇ by central differences along θ(t)."""
    rates = np.random.default_rng(RNG_SEED + 1).normal(size=angles.shape)
    h = 1e-6
    dlam = (frm.Lambda(*(angles + h * rates).T) - frm.Lambda(*(angles - h * rates).T)) / (2 * h)
    skew = -dlam @ np.swapaxes(frm.Lambda(*angles.T), 1, 2)
    omega = np.stack([skew[:, 2, 1], skew[:, 0, 2], skew[:, 1, 0]], axis=1)
    np.testing.assert_allclose(np.einsum("nij,nj->ni", frm.A(*angles.T), rates), omega, atol=1e-8)
    np.testing.assert_allclose(skew, -np.swapaxes(skew, 1, 2), atol=1e-8)


def test_omega_rate_against_differences_along_a_path():
    """Ω' = d/ds (A θ') for θ(s) = θ0 + θ1 s + θ2 s²."""
    rng = np.random.default_rng(RNG_SEED + 2)
    c0, c1, c2 = rng.uniform(-1, 1, (3, 20, 3))
    th = lambda s: c0 + c1 * s + c2 * s**2  # noqa: E731
    dth = lambda s: c1 + 2 * c2 * s  # noqa: E731
    h = 1e-5
    w = lambda s: frm.omega_per_length(*th(s).T, *dth(s).T)  # noqa: E731
    fd = (w(h) - w(-h)) / (2 * h)
    np.testing.assert_allclose(frm.omega_per_length_rate(*c0.T, *c1.T, *(2 * c2).T), fd, atol=1e-8)


def test_angles_from_tangent_invert_tangent_relations():
    rng = np.random.default_rng(RNG_SEED + 3)
    th2 = rng.uniform(-3, 3, 40)
    th3 = rng.uniform(-1.4, 1.4, 40)
    d2, d3, dd2, dd3 = rng.normal(size=(4, 40))

    def tangent(s):
        a2, a3 = th2 + d2 * s + dd2 * s**2 / 2, th3 + d3 * s + dd3 * s**2 / 2
        return np.stack([np.cos(a2) * np.cos(a3), np.sin(a3), -np.sin(a2) * np.cos(a3)], axis=1)

    h = 1e-4
    t, tp, tm = tangent(0.0), tangent(h), tangent(-h)
    dt, ddt = (tp - tm) / (2 * h), (tp - 2 * t + tm) / h**2
    out = frm.angles_from_tangent(*t.T, *dt.T, *ddt.T)
    np.testing.assert_allclose(out[:, 0], th2, atol=1e-12)
    np.testing.assert_allclose(out[:, 1], th3, atol=1e-12)
    np.testing.assert_allclose(out[:, 2:4], np.stack([d2, d3], 1), atol=1e-6)
    np.testing.assert_allclose(out[:, 4:6], np.stack([dd2, dd3], 1), atol=1e-3)


def test_chord_rotation_turns_x1_onto_chord_and_is_a_rotation():
    rng = np.random.default_rng(RNG_SEED + 4)
    rho = rng.normal(size=(30, 3))
    rho[:, 0] = np.abs(rho[:, 0]) + 0.1
    rho /= np.linalg.norm(rho, axis=1, keepdims=True)
    ls = frm.chord_rotation(*rho.T)
    np.testing.assert_allclose(ls[:, 0, :], rho, atol=1e-14)
    np.testing.assert_allclose(ls @ np.swapaxes(ls, 1, 2), np.broadcast_to(np.eye(3), ls.shape), atol=1e-13)
    # Equals Rodrigues about the unit axis e1 × ρ by Ψ = acos ρ1.
    axis = np.cross([1.0, 0, 0], rho)
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    np.testing.assert_allclose(ls, frm.rodrigues(np.arccos(rho[:, 0]), *axis.T), atol=1e-13)
    np.testing.assert_allclose(frm.chord_rotation(1.0, 0.0, 0.0), np.eye(3), atol=0)


def test_lambda_bar_linear_is_first_order(angles):
    d = np.random.default_rng(RNG_SEED + 5).normal(size=angles.shape) * 1e-4
    exact = frm.Lambda(*(angles + d).T)
    err = np.abs(frm.Lambda_bar_linear(*angles.T, *d.T) - exact).max()
    assert 1e-10 < err < 1e-7  # O(Δθ²) with |Δθ| ~ 1e-4
