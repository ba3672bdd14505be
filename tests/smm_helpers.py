"""Small mechanisms for the SMM tests, written as scene dictionaries."""
from __future__ import annotations

import numpy as np
import scipy.linalg

from symmech.core import pipeline
from symmech.core.context import Context
from symmech.core.schema import validate
from symmech.smm import numeric, scene
from symmech.smm.build import model
from symmech.smm.schema import SCHEMA


def param(value, unit="1"):
    return {"value": value, "unit": unit}


def mech(d: dict):
    """The mechanism of a scene dict (without ``kind``), validated as `symmech run` does."""
    return model(validate(SCHEMA, {"kind": "mechanism", **d}))


def run_scene(d: dict) -> dict:
    """Summary (with the warnings) of running a scene dict through the pipeline (nothing written)."""
    result = pipeline.load({"kind": "mechanism", **d}).run(Context(quiet=True))
    return {**result.summary, "warnings": result.warnings, "result": result}


def run_model(m) -> dict:
    """Summary (with the warnings) of the run of a model built in Python (no responses, no plots)."""
    resolved = {"equilibrium": {"solve": False}, "initial": None, "forcing": None, "output": {"plots": []}}
    result = scene.run(scene.Setup(m, len(m.coordinates), resolved), Context(quiet=True))
    return {**result.summary, "warnings": result.warnings}


def chain(**spec):
    """A generated ``[chain]`` mechanism (fields as in the scene's ``[chain]`` table)."""
    return model(validate(SCHEMA, {"kind": "mechanism", "chain": spec}))


def omega2(m, effects=None):
    n = numeric.assemble(m, effects)
    return scipy.linalg.eigh(n.c.toarray(), n.a.toarray(), eigvals_only=True)


def hanging_mass(k=500.0, mass=2.0, length=0.8, g=9.81, preload=True, effects=None):
    """A point mass on a vertical spring, free to move in x and y; preload = weight."""
    d = {
        "parameters": {"m": param(mass, "kg"), "k": param(k, "N/m"), "l": param(length, "m"),
                       "g": param(g, "m/s^2")},
        "coordinates": [{"name": "x", "type": "slide", "axis": [1, 0]},
                        {"name": "y", "type": "slide", "axis": [0, 1]}],
        "points": [{"name": "O", "at": [0, 0]},
                   {"name": "P", "from": "O", "vector": [0, "-l"], "slides": ["x", "y"]}],
        "bodies": [{"name": "bob", "mass": "m", "com": "P"}],
        "springs": [{"name": "hanger", "ends": ["O", "P"], "stiffness": "k",
                     **({"preload": "m*g"} if preload else {})}],
        "gravity": {"g": "g"},
    }
    if effects:
        d["effects"] = effects
    return mech(d)


def bar_on_springs(m=40.0, J=6.0, k1=2000.0, k2=2000.0, l1=0.5, l2=0.5):
    """A rigid bar (centre of mass C) on two vertical springs at distances l1 (left), l2 (right)."""
    return mech({
        "parameters": {"m": param(m, "kg"), "J": param(J, "kg m^2"), "k1": param(k1, "N/m"),
                       "k2": param(k2, "N/m"), "l1": param(l1, "m"), "l2": param(l2, "m"),
                       "h": param(1.0, "m")},
        "coordinates": [{"name": "y", "type": "slide", "axis": [0, 1]},
                        {"name": "theta", "type": "angle"}],
        "points": [{"name": "O", "at": [0, 0]},
                   {"name": "C", "from": "O", "vector": [0, "h"], "slides": ["y"]},
                   {"name": "L", "from": "C", "vector": ["-l1", 0], "turns": ["theta"]},
                   {"name": "R", "from": "C", "vector": ["l2", 0], "turns": ["theta"]},
                   {"name": "GL", "at": ["-l1", 0]}, {"name": "GR", "at": ["l2", 0]}],
        "bodies": [{"name": "bar", "mass": "m", "inertia": "J", "com": "C", "turns": ["theta"]}],
        "springs": [{"name": "left", "ends": ["GL", "L"], "stiffness": "k1"},
                    {"name": "right", "ends": ["GR", "R"], "stiffness": "k2"}],
    })


def spring_chain(masses, stiffnesses, end_stiffness=None, tension=0.0):
    """Masses along x on absolute slides; springs k_0 (wall-m1), k_1 (m1-m2), ...;
    ``end_stiffness`` adds a spring from the last mass to a far wall."""
    n = len(masses)
    params = {f"m{i + 1}": param(v, "kg") for i, v in enumerate(masses)}
    params.update({f"k{i}": param(v, "N/m") for i, v in enumerate(stiffnesses)})
    points = [{"name": "O", "at": [0, 0]}]
    points += [{"name": f"P{i}", "from": "O", "vector": [float(i), 0], "slides": [f"s{i}"]}
               for i in range(1, n + 1)]
    springs = [{"name": "k0", "ends": ["O", "P1"], "stiffness": "k0"}]
    springs += [{"name": f"k{i}", "ends": [f"P{i}", f"P{i + 1}"], "stiffness": f"k{i}"} for i in range(1, n)]
    if end_stiffness is not None:
        params["K"] = param(end_stiffness, "N/m")
        points.append({"name": "W", "at": [float(n + 1), 0]})
        springs.append({"name": "K", "ends": [f"P{n}", "W"], "stiffness": "K"})
    return mech({
        "parameters": params,
        "coordinates": [{"name": f"s{i}", "type": "slide", "axis": [1, 0]} for i in range(1, n + 1)],
        "points": points,
        "bodies": [{"name": f"b{i}", "mass": f"m{i}", "com": f"P{i}"} for i in range(1, n + 1)],
        "springs": springs,
    })


def sorted_sqrt(w2):
    return np.sqrt(np.sort(np.asarray(w2)))


def fd_hessian(f, n: int, h: float = 1e-4) -> np.ndarray:
    """(n, n) Hessian of the scalar ``f`` at 0 by central differences of step ``h`` (error O(h^2))."""
    H = np.empty((n, n))
    for i in range(n):
        for j in range(n):
            ei, ej = np.eye(n)[i] * h, np.eye(n)[j] * h
            H[i, j] = (f(ei + ej) - f(ei - ej) - f(-ei + ej) + f(-ei - ej)) / (4 * h * h)
    return H
