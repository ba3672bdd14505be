"""Kinematics and reactions of the rigid trolley's body (symmech.trolley.model.point_coefficients,
body_motion, the reactions) against independent references (mutation testing).

The body frame is written by hand: the Frenet frame of a circular helix (radius R, rise λ per radian,
r² = R² + λ²: κ = R / r², τ = λ / r²) turned about x3 by φ(s) = φ0 + φ1 s + φ2 s², so the direction
e of V0 in body components, its rate e' and Ω' are all non-zero: e = [cos φ, -sin φ, 0],
Ω = [τ cos φ, -τ sin φ, κ + φ'], Ω' = [-τ φ' sin φ, -τ φ' cos φ, φ''].
References: the centre of mass's fixed-frame path X0(s(t)) + Λᵀ r differenced in time (its
velocity and acceleration in body components), ω and ω̇ from differences of Λ (ω̃ = -Λ̇ Λᵀ), and the
reactions from Newton-Euler's six equations for the six contact forces, assembled and solved here;
a body at constant speed on a level circle against P4 = m V²/R, P1 = P2 = m g / 2.
"""
from __future__ import annotations

import numpy as np
import pytest

from symmech.trolley import model

R, RISE = 2.0, 0.5
ROOT = np.hypot(R, RISE)
KAPPA, TAU = R / ROOT**2, RISE / ROOT**2
PHI = (0.3, 0.4, -0.15)  # φ0 [rad], φ1 [rad/m], φ2 [rad/m²]
UP = np.array([0.0, 1.0, 0.0])  # X2 is up


def _helix(s):
    p = np.asarray(s, float) / ROOT
    x = np.stack([R * np.cos(p), R * np.sin(p), RISE * p], -1)
    t = np.stack([-R * np.sin(p), R * np.cos(p), np.full_like(p, RISE)], -1) / ROOT
    normal = np.stack([-np.cos(p), -np.sin(p), np.zeros_like(p)], -1)
    return x, np.stack([t, normal, np.cross(t, normal)], -2)


def _phi(s):
    return PHI[0] + PHI[1] * s + PHI[2] * s**2, PHI[1] + 2 * PHI[2] * s, 2 * PHI[2] + 0 * s


def _lam(s):
    """Body frame (n, 3, 3), fixed -> body: the Frenet frame turned (passively) by φ about x3."""
    _, frenet = _helix(s)
    phi = _phi(s)[0]
    c, n, z, o = np.cos(phi), np.sin(phi), np.zeros_like(phi), np.ones_like(phi)
    turn = np.stack([np.stack([c, n, z], -1), np.stack([-n, c, z], -1), np.stack([z, z, o], -1)], -2)
    return turn @ frenet


def _frame(s):
    phi, dphi, ddphi = _phi(s)
    c, n, z = np.cos(phi), np.sin(phi), np.zeros_like(phi)
    return model.Frame(_lam(s), np.stack([c, -n, z], -1), dphi[:, None] * np.stack([-n, -c, z], -1),
                       np.stack([TAU * c, -TAU * n, KAPPA + dphi], -1),
                       np.stack([-TAU * dphi * n, -TAU * dphi * c, ddphi], -1))


def _d(f, t, h, k):
    """k-th derivative (k = 1, 2) of f at t by 4th-order central differences with step h."""
    w = {1: (1 / 12, -2 / 3, 0, 2 / 3, -1 / 12), 2: (-1 / 12, 4 / 3, -5 / 2, 4 / 3, -1 / 12)}[k]
    return sum(wj * f(t + j * h) for wj, j in zip(w, range(-2, 3))) / h**k


def _vee_rate(lam_of_t, t, h=1e-4):
    """ω (body components) from ω̃ = -Λ̇ Λᵀ."""
    w = -_d(lam_of_t, t, h, 1) @ np.swapaxes(lam_of_t(t), -1, -2)
    return np.stack([w[..., 2, 1], w[..., 0, 2], w[..., 1, 0]], -1)


def _reference_reactions(m, r, inertia, a, w, dw, nu, g0, l, ah):
    """P0…P5: Newton-Euler for the body with the six contact forces of the trolley (body frame):
    P0 at O along x1, P1 at (0, 0, -ah) and P2 at (0, 0, ah) along x2, P3 at A = (l, 0, 0) along x2,
    P4 at O along x3, P5 at A along x3; gravity -m g0 ν."""
    i11, i22, i33, i12, i23, i13 = inertia
    tensor = np.array([[i11, i12, i13], [i12, i22, i23], [i13, i23, i33]])
    points = np.array([[0, 0, 0], [0, 0, -ah], [0, 0, ah], [l, 0, 0], [0, 0, 0], [l, 0, 0]], float)
    axes = np.eye(3)[[0, 1, 1, 1, 2, 2]]
    system = np.vstack([axes.T, np.cross(points, axes).T])
    out = []
    for ak, wk, dwk, nuk in zip(a, w, dw, nu):
        force = m * (ak + g0 * nuk)
        moment = np.cross(r, force) + tensor @ dwk + np.cross(wk, tensor @ wk)
        out.append(np.linalg.solve(system, np.concatenate([force, moment])))
    return np.array(out)


@pytest.mark.parametrize("g0", [9.81, 0.8, 0.0])  # 0.8: a weak gravity is gravity too
def test_body_motion_matches_differences_of_the_centre_of_mass_path_and_newton_euler(g0):
    s0, v0, acc = np.array([0.2, 1.1, 2.5]), np.array([3.0, -2.0, 5.0]), np.array([0.7, 1.3, -2.0])
    body = model.Body(m=80.0, r=(0.4, 0.9, -0.3), inertia=(30.0, 25.0, 40.0, 2.0, -3.0, 1.5), l=1.6, ah=0.7, g0=g0)
    r = np.array(body.r)

    def s_of(t):
        return s0 + v0 * t + 0.5 * acc * t**2

    def path(t):  # the centre of mass in fixed components
        x, _ = _helix(s_of(t))
        return x + np.einsum("nji,j->ni", _lam(s_of(t)), r)

    def lam_t(t):
        return _lam(s_of(t))

    lam = _lam(s0)
    out = model.body_motion(_frame(s0), v0, acc, body)
    velocity = np.einsum("nij,nj->ni", lam, _d(path, 0.0, 1e-3, 1))
    accel = np.einsum("nij,nj->ni", lam, _d(path, 0.0, 1e-3, 2))
    omega = _vee_rate(lam_t, 0.0)
    omega_dot = _d(lambda t: _vee_rate(lam_t, t), 0.0, 1e-2, 1)
    np.testing.assert_allclose(out["V"], velocity, atol=1e-8)
    np.testing.assert_allclose(out["a"], accel, atol=1e-6)
    np.testing.assert_allclose(out["omega"], omega, atol=1e-8)
    np.testing.assert_allclose(out["omega_dot"], omega_dot, atol=1e-6)
    np.testing.assert_array_equal(out["lam"], lam)
    nu = lam @ UP
    reference = _reference_reactions(body.m, r, body.inertia, accel, omega, omega_dot, nu, g0, body.l, body.ah)
    np.testing.assert_allclose(out["P"], reference, rtol=1e-7, atol=1e-5)
    g_ref = g0 if g0 > 0 else 9.80665
    np.testing.assert_allclose(out["overload"], (accel + g0 * nu) / g_ref, atol=1e-7)


def test_point_coefficients_are_velocity_and_acceleration_per_speed():
    """α = V / V0 at V̇0 = 0 and β = a / V0² there; α again as a's part per V̇0 (two speeds)."""
    s = np.array([0.4, 1.7])
    body = model.Body(m=1.0, r=(-0.5, 0.2, 0.8), inertia=(0.0,) * 6, l=1.0, ah=0.5, g0=0.0)
    alpha, beta = model.point_coefficients(_frame(s), body)
    r = np.array(body.r)

    def path(v):
        def at(t):
            x, _ = _helix(s + v * t)
            return x + np.einsum("nji,j->ni", _lam(s + v * t), r)
        return at

    lam = _lam(s)
    np.testing.assert_allclose(alpha, np.einsum("nij,nj->ni", lam, _d(path(1.0), 0.0, 1e-3, 1)), atol=1e-9)
    np.testing.assert_allclose(beta, np.einsum("nij,nj->ni", lam, _d(path(1.0), 0.0, 1e-3, 2)), atol=1e-7)


def _level_circle(radius, s):
    """Twist-free body frame on a level circle X = (R cos p, 0, R sin p): x1 tangent, x2 up, x3 inward."""
    p = s / radius
    t = np.stack([-np.sin(p), 0 * p, np.cos(p)], -1)
    inward = np.stack([-np.cos(p), 0 * p, -np.sin(p)], -1)
    return np.stack([t, np.tile(UP, (len(s), 1)), inward], -2)


@pytest.mark.parametrize("g0", [9.81, 0.0])
def test_constant_speed_on_a_level_circle_needs_m_v2_over_r_sideways_and_half_the_weight_on_each_rail(g0):
    radius, speed, m = 25.0, 12.0, 500.0
    s = np.array([0.0, 3.0, 40.0])
    lam = _level_circle(radius, s)
    e = np.tile([1.0, 0.0, 0.0], (3, 1))
    # the frame turns about the vertical x2 at 1/R per metre (x1 → x3, towards the centre)
    W = np.tile([0.0, -1.0 / radius, 0.0], (3, 1))
    frame = model.Frame(lam, e, np.zeros_like(e), W, np.zeros_like(W))
    body = model.Body(m=m, r=(0.0, 0.0, 0.0), inertia=(80.0, 120.0, 90.0, 0.0, 0.0, 0.0), l=2.0, ah=0.75, g0=g0)
    out = model.body_motion(frame, np.full(3, speed), np.zeros(3), body)
    centripetal = speed**2 / radius
    np.testing.assert_allclose(out["a"], np.tile([0.0, 0.0, centripetal], (3, 1)), atol=1e-12)
    np.testing.assert_allclose(out["omega"], np.tile([0.0, -speed / radius, 0.0], (3, 1)), atol=1e-12)
    np.testing.assert_allclose(out["omega_dot"], 0.0, atol=1e-12)
    expected = [0.0, m * g0 / 2, m * g0 / 2, 0.0, m * centripetal, 0.0]
    np.testing.assert_allclose(out["P"], np.tile(expected, (3, 1)), atol=1e-9)
    g_ref = g0 if g0 > 0 else 9.80665
    np.testing.assert_allclose(out["overload"], np.tile([0.0, g0, centripetal], (3, 1)) / g_ref, atol=1e-12)
    np.testing.assert_allclose(out["V"], np.tile([speed, 0.0, 0.0], (3, 1)), atol=1e-12)
