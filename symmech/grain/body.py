"""The grain: a homogeneous solid ellipsoid, and its orientation in the surface frame."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from symmech.generated import grain_impact as gen


@dataclass(frozen=True)
class Ellipsoid:
    """Solid homogeneous ellipsoid: semi-axes a, b, c [m] along body X', Y', Z'; mass [kg]."""

    a: float
    b: float
    c: float
    mass: float

    def __post_init__(self):
        for name in ("a", "b", "c", "mass"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"Ellipsoid.{name} must be a finite number > 0, got {value!r}")

    @property
    def gyration_squared(self) -> np.ndarray:
        """Principal radii of gyration squared, shape (3,) [m^2]."""
        a2, b2, c2 = self.a**2, self.b**2, self.c**2
        return np.array([b2 + c2, a2 + c2, a2 + b2]) / 5.0

    @property
    def inertia(self) -> np.ndarray:
        """Principal moments of inertia J'_x, J'_y, J'_z, shape (3,) [kg m^2]."""
        return self.mass * self.gyration_squared


def euler_from_matrix(Q) -> np.ndarray:
    """z-x-z Euler angles (psi, theta, phi) of rotation(s) Q, shape (..., 3, 3) -> (..., 3) [rad].

    theta comes from atan2, accurate near 0 and pi; at gimbal lock (sin theta = 0)
    psi is set to 0 and phi carries the whole rotation about Z.
    """
    Q = np.asarray(Q, dtype=float)
    s_theta = np.hypot(Q[..., 0, 2], Q[..., 1, 2])
    theta = np.arctan2(s_theta, Q[..., 2, 2])
    locked = s_theta < 1e-12
    psi = np.where(locked, 0.0, np.arctan2(Q[..., 0, 2], -Q[..., 1, 2]))
    phi = np.where(locked, np.arctan2(Q[..., 1, 0] * np.sign(Q[..., 2, 2] + 0.5), Q[..., 0, 0]),
                   np.arctan2(Q[..., 2, 0], Q[..., 2, 1]))
    return np.stack([psi, theta, phi], axis=-1)


def rotation(angles) -> np.ndarray:
    """Q from z-x-z Euler angles (..., 3) -> (..., 3, 3); body axes as columns."""
    angles = np.asarray(angles, dtype=float)
    return gen.rotation(angles[..., 0], angles[..., 1], angles[..., 2])
