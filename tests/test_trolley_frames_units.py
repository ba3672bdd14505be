"""The rotation-minimising frame and the turn angle of symmech.trolley.model against closed forms on
a circular helix (mutation testing). On a helix of radius R and rise λ per radian
(r² = R² + λ²) the curvature is κ = R / r², the torsion τ = λ / r², and the rotation-minimising
normal turns against the Frenet normal N at the rate -τ: n = cos ψ N + sin ψ B with ψ' = -τ, so
Ω = [0, κ sin ψ, κ cos ψ] and Ω' = [0, -κτ cos ψ, κτ sin ψ]."""
from __future__ import annotations

import numpy as np
import pytest

from symmech.trolley import model

R, RISE = 2.0, 0.5
ROOT = np.hypot(R, RISE)
KAPPA, TAU = R / ROOT**2, RISE / ROOT**2


class Helix:
    """The helix and its arc-length derivatives written by hand (the reference, not symmech's track)."""

    def derivatives(self, s, order):
        p = np.asarray(s, float) / ROOT
        c, n, z = np.cos(p), np.sin(p), np.zeros_like(p)
        rows = [(R * c, R * n, RISE * p), (-R * n / ROOT, R * c / ROOT, z + RISE / ROOT),
                (-R * c / ROOT**2, -R * n / ROOT**2, z), (R * n / ROOT**3, -R * c / ROOT**3, z)]
        return [np.stack(row, axis=-1) for row in rows[:order + 1]]


class FastHelix(Helix):
    """The helix with X0' 1.001 times its unit tangent: a table track's X0' is unit only to its fit error."""

    def derivatives(self, s, order):
        rows = super().derivatives(s, order)
        return [rows[0], 1.001 * rows[1], *rows[2:]]


def _frenet(s):
    p = s / ROOT
    t = np.stack([-R * np.sin(p), R * np.cos(p), np.full_like(p, RISE)], -1) / ROOT
    normal = np.stack([-np.cos(p), -np.sin(p), np.zeros_like(p)], -1)
    return t, normal, np.cross(t, normal)


@pytest.mark.parametrize("min_curvature, s0", [(1e-6, 0.3), (1.0, 0.3), (1.0, 2.0)])
def test_rotation_minimising_frame_on_a_helix_matches_the_closed_form(min_curvature, s0):
    rmf = model.RotationMinimising(Helix(), np.array([s0, 6.0]), min_curvature)
    s = np.linspace(s0, 6.0, 9)
    frame = rmf.frame(Helix(), s)
    t, normal, binormal = _frenet(s)
    if min_curvature < KAPPA:  # starts from the principal normal
        psi0 = 0.0
        assert rmf.start == f"the principal normal at s = {s0:g} m"
    else:  # starts from the world's y axis made normal to the tangent, x when the tangent is nearly y
        axis = 1 if abs(t[0, 1]) < 0.9 else 0
        assert axis == (1 if s0 == 2.0 else 0)
        up = np.eye(3)[axis] - t[0, axis] * t[0]
        up /= np.linalg.norm(up)
        psi0 = np.arctan2(up @ binormal[0], up @ normal[0])
        assert rmf.start == f"the upward normal at s = {s0:g} m"
    psi = psi0 - TAU * (s - s0)
    n = np.cos(psi)[:, None] * normal + np.sin(psi)[:, None] * binormal
    lam = np.stack([t, n, np.cross(t, n)], axis=-2)
    np.testing.assert_allclose(frame.lam, lam, atol=1e-9)
    zero = np.zeros_like(s)
    np.testing.assert_allclose(frame.W, np.stack([zero, KAPPA * np.sin(psi), KAPPA * np.cos(psi)], -1), atol=1e-9)
    np.testing.assert_allclose(frame.dW, np.stack([zero, -KAPPA * TAU * np.cos(psi), KAPPA * TAU * np.sin(psi)], -1),
                               atol=1e-9)
    np.testing.assert_array_equal(frame.e, np.tile([1.0, 0.0, 0.0], (9, 1)))
    # x1 is the unit tangent whatever the track's speed: the same frame on a track whose X0' is not of unit length
    np.testing.assert_allclose(rmf.frame(FastHelix(), s).lam, frame.lam, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(frame.de, np.zeros((9, 3)))


def _rotation(axis, angle):
    k = np.asarray(axis, float) / np.linalg.norm(axis)
    cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * cross + (1 - np.cos(angle)) * cross @ cross


@pytest.mark.parametrize("angle", [0.0, 0.3, 2.0, np.pi])
def test_angle_of_a_rotation_is_its_rotation_angle_even_with_rounding(angle):
    rotation = _rotation([1.0, -2.0, 0.5], angle)
    assert model._angle(rotation) == pytest.approx(angle, abs=1e-7)
    # a product of rotations carries rounding: its trace may pass 3 (angle 0) or -1 (angle π) by a few ulps
    assert model._angle(rotation * (1 + 1e-15)) == pytest.approx(angle, abs=1e-7)
