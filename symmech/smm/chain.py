"""Uniform chains of point masses generated from a ``[chain]`` scene table.

n equal masses m [kg] joined by n - 1 (+ end) springs of stiffness k [N/m] and
equilibrium length L [m] along x, with tension T [N] in equilibrium. Each mass
has one absolute slide coordinate (``axial``: along x; ``transverse``: along y,
a pretensioned string whose stiffness comes from T alone). Absolute coordinates
keep L_a and L_c sparse, so 10,000 DOF assemble in well under a second.
"""
from __future__ import annotations

import math

from symmech.core.scene import SceneError
from symmech.smm.model import Body, Coordinate, Link, Mechanism, Parameter, Point


def chain_spec(chain: dict, scene_name: str | None = None) -> dict:
    """The resolved ``[chain]`` table (see ``symmech.smm.schema``) with its name filled in:
    n, ends, motion, mass [kg], stiffness [N/m], spacing [m], tension [N], name."""
    spec = dict(chain)
    if spec["name"] is None:
        spec["name"] = scene_name or f"chain_{spec['n']}_{spec['ends']}_{spec['motion']}"
    if spec["ends"] == "free-free" and spec["n"] == 1:
        raise SceneError("chain.n", "a free-free chain needs at least two masses")
    return spec


def exact_omega2(spec: dict) -> list[float]:
    """Closed-form omega^2 [1/s^2], ascending: 2 s/m (1 - cos theta_j) with s = k (axial)
    or T/L (transverse) and theta_j = j pi/(n+1) (fixed-fixed), (2j-1) pi/(2n+1)
    (fixed-free), j pi/n, j = 0..n-1 (free-free)."""
    n = spec["n"]
    s = spec["stiffness"] if spec["motion"] == "axial" else spec["tension"] / spec["spacing"]
    theta = {"fixed-fixed": [j * math.pi / (n + 1) for j in range(1, n + 1)],
             "fixed-free": [(2 * j - 1) * math.pi / (2 * n + 1) for j in range(1, n + 1)],
             "free-free": [j * math.pi / n for j in range(n)]}[spec["ends"]]
    return [2 * s / spec["mass"] * (1 - math.cos(t)) for t in theta]


def build_chain(spec: dict) -> Mechanism:
    """The vector model of the chain ``spec`` (see :func:`chain_spec`)."""
    n, ends, motion = spec["n"], spec["ends"], spec["motion"]
    params = {
        "m": Parameter("m", spec["mass"], "kg", "mass of each particle"),
        "k": Parameter("k", spec["stiffness"], "N/m", "stiffness of each spring"),
        "L": Parameter("L", spec["spacing"], "m", "spring length in equilibrium"),
        "T": Parameter("T", spec["tension"], "N", "spring tension in equilibrium"),
    }
    axis = ("1", "0", "0") if motion == "axial" else ("0", "1", "0")
    coords = [Coordinate(f"s{i}", "slide", axis) for i in range(1, n + 1)]
    points = {"O": Point("O", None, ("0", "0", "0"))}
    for i in range(1, n + 1):
        points[f"P{i}"] = Point(f"P{i}", "O", (f"{i}*L", "0", "0"), (), (f"s{i}",))
    points["E"] = Point("E", None, (f"{n + 1}*L", "0", "0"))
    bodies = [Body(f"mass{i}", "m", ("0", "0", "0"), f"P{i}", ()) for i in range(1, n + 1)]
    springs = [Link(f"k{i}", f"P{i}", f"P{i + 1}", "k", "T") for i in range(1, n)]
    if ends in ("fixed-fixed", "fixed-free"):
        springs.insert(0, Link("k0", "O", "P1", "k", "T"))
    if ends == "fixed-fixed":
        springs.append(Link(f"k{n}", f"P{n}", "E", "k", "T"))
    return Mechanism(spec["name"], params, coords, points, bodies, springs)
