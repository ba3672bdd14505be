"""Uniform chains of point masses generated from a ``[chain]`` scene table.

n equal masses m [kg] joined by n - 1 (+ end) springs of stiffness k [N/m] and
equilibrium length L [m] along x, with tension T [N] in equilibrium. Each mass
has one absolute slide coordinate (``axial``: along x; ``transverse``: along y,
a pretensioned string whose stiffness comes from T alone). Absolute coordinates
keep L_a and L_c sparse, so 10,000 DOF assemble in well under a second.
"""
from __future__ import annotations

from symmech.core.scene import SceneError, Section
from symmech.smm.model import Body, Coordinate, Link, Mechanism, Parameter, Point, validate

ENDS = ("fixed-fixed", "fixed-free", "free-free")


def chain_mechanism(sec: Section) -> Mechanism:
    n = sec.int("n", lo=1, hi=10**6)
    ends = sec.choice("ends", ENDS, default="fixed-fixed")
    motion = sec.choice("motion", ("axial", "transverse"), default="axial")
    params = {
        "m": Parameter("m", sec.float("mass", unit="kg", lo=0, lo_open=True), "kg", "mass of each particle"),
        "k": Parameter("k", sec.float("stiffness", unit="N/m", lo=0), "N/m", "stiffness of each spring"),
        "L": Parameter("L", sec.float("spacing", unit="m", lo=0, lo_open=True), "m", "spring length in equilibrium"),
        "T": Parameter("T", sec.float("tension", unit="N", default=0.0), "N", "spring tension in equilibrium"),
    }
    name = sec.str("name", default=f"chain_{n}_{ends}_{motion}")
    sec.finish()
    if motion == "transverse" and ends == "free-free" and n == 1:
        raise SceneError(sec.field("n"), "a free-free chain needs at least two masses")
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
    m = Mechanism(name, params, coords, points, bodies, springs)
    validate(m)
    return m
