"""Scene fields shared by the grain kinds (``grain`` and ``impact``): the body and the admissible ranges.

The ranges are physical, not numerical conveniences: a grain from a 1 um dust
particle to a 1 m boulder. With semi-axes in [1e-6, 1] m and a mass in
[1e-12, 1e3] kg the principal moments of inertia m (b^2 + c^2) / 5 lie in
[4e-25, 400] kg m^2 — normal floats, so no mass or inertia can underflow (a mass
of 1e-308 kg is refused, not turned into a division by zero in the impact law).
"""
from __future__ import annotations

import math

import numpy as np

from symmech.core.scene import SceneError
from symmech.core.schema import Float, Table, Vector

MASS = (1e-12, 1e3)  # kg
DENSITY = (1.0, 1e5)  # kg/m^3 (air-filled husks to the densest metals)
SEMI_AXIS = (1e-6, 1.0)  # m
MAX_ASPECT = 1e3  # longest / shortest semi-axis: beyond it the support distance loses its digits
SPEED = 100.0  # m/s, bound of each velocity component of the grain and of the surface's peak velocity
SPIN = 1e4  # rad/s, bound of each angular velocity component


def body_mass(body: dict) -> float:
    """Mass [kg] of a resolved body table: ``mass``, or ``density`` times the ellipsoid's volume."""
    if body["mass"] is not None:
        return body["mass"]
    return float(body["density"] * 4.0 / 3.0 * math.pi * np.prod(body["semi_axes"]))


def _admissible_body(body: dict, path: str) -> None:
    if (body["mass"] is None) == (body["density"] is None):
        raise SceneError(f"{path}.mass", "give exactly one of body.mass [kg] or body.density [kg/m^3]")
    mass = body_mass(body)
    if body["density"] is not None and not MASS[0] <= mass <= MASS[1]:
        raise SceneError(f"{path}.density", f"{body['density']:g} kg/m^3 gives a mass of {mass:.3g} kg, "
                                            f"outside [{MASS[0]:g}, {MASS[1]:g}] kg")
    axes = body["semi_axes"]
    if max(axes) / min(axes) > MAX_ASPECT:
        raise SceneError(f"{path}.semi_axes", f"aspect ratio {max(axes) / min(axes):.3g} (longest / shortest) "
                                              f"exceeds {MAX_ASPECT:g}")


BODY = Table("the grain, a homogeneous solid ellipsoid; give exactly one of `mass` and `density`", {
    "semi_axes": Vector("a, b, c along the body axes X', Y', Z' (longest / shortest at most 1000)", n=3, unit="m",
                        lo=SEMI_AXIS[0], hi=SEMI_AXIS[1]),
    "mass": Float("grain mass", unit="kg", lo=MASS[0], hi=MASS[1], default=None),
    "density": Float("mass = density · 4/3 π a b c, which must lie in the mass range", unit="kg/m^3",
                     lo=DENSITY[0], hi=DENSITY[1], default=None),
    "orientation": Vector("z-x-z Euler angles ψ, θ, φ: `Q = Rz(ψ) Rx(θ) Rz(φ)` has the body axes as columns "
                          "in the surface frame", n=3, unit="rad", lo=-2 * math.pi, hi=2 * math.pi,
                          default=[0.0, 0.0, 0.0]),
}, checks=(_admissible_body,))


def velocity(doc: str, **kw) -> Vector:
    """A velocity field (3,) [m/s], each component within ±SPEED."""
    return Vector(doc, n=3, unit="m/s", lo=-SPEED, hi=SPEED, **kw)


def angular_velocity(doc: str, **kw) -> Vector:
    """An angular velocity field (3,) [rad/s], each component within ±SPIN."""
    return Vector(doc, n=3, unit="rad/s", lo=-SPIN, hi=SPIN, **kw)
