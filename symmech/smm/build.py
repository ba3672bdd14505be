"""The mechanism of a validated scene, checked for admissibility before any work.

:func:`model` turns the resolved scene (``symmech.smm.schema.SCHEMA``) into a
:class:`~symmech.smm.model.Mechanism`. Every expression is evaluated at the
parameter values here, and every structural or physical defect — an unknown or
duplicate name, a dangling reference, a spring or torsion spring on a single
element, a non-unit axis or gravity direction, masses, moments, stiffnesses and
viscosities out of range, inertia violating the triangle inequalities, a
coordinate listed twice, one that moves nothing — is a SceneError naming the
dotted scene field.
"""
from __future__ import annotations

import difflib
from pathlib import Path

import numpy as np

from symmech.core.scene import SceneError, SymmechError, read_toml
from symmech.core.schema import validate
from symmech.smm import schema as S
from symmech.smm.chain import build_chain, chain_spec
from symmech.smm.model import (EQUILIBRIUM, GROUND, Body, Coordinate, Effects, Link, Mechanism, Parameter, Point,
                               Torsion, evaluate, expression_names)

UNIT_TOL = 1e-9  # |norm - 1| allowed for axes and directions


def model(resolved: dict) -> Mechanism:
    """The scene's mechanism: a generated ``[chain]`` or the explicit vector model."""
    if resolved["chain"] is not None:
        return build_chain(chain_spec(resolved["chain"], resolved["name"]))
    return _Builder(resolved).mechanism()


class _Builder:
    def __init__(self, scene: dict):
        self.scene = scene
        self.values = {name: p["value"] for name, p in scene["parameters"].items()}

    def value(self, path: str, text: str) -> float:
        """``text`` evaluated at the parameter values; SceneError naming ``path`` otherwise."""
        unknown = sorted(expression_names(text) - set(self.values))
        if unknown:
            close = difflib.get_close_matches(unknown[0], list(self.values), n=1)
            hint = f" (did you mean '{close[0]}'?)" if close else ""
            raise SceneError(path, f"unknown parameter '{unknown[0]}' in {text!r}{hint}")
        try:
            return evaluate(text, self.values, path)
        except SymmechError as exc:
            raise SceneError(path, str(exc).removeprefix(f"{path}: ")) from None

    def ranged(self, path, text, lo, hi, unit, zero_ok=False) -> float:
        v = self.value(path, text)
        if not (lo <= v <= hi or (zero_ok and v == 0.0)):
            zero = "0 or " if zero_ok else ""
            raise SceneError(path, f"{text} = {v:g} {unit} is outside {zero}[{lo:g}, {hi:g}] {unit}")
        return v

    def vector(self, path, comps, bound=S.LENGTH_MAX) -> np.ndarray:
        v = np.array([self.value(f"{path}[{i}]", t) for i, t in enumerate(comps)])
        if np.abs(v).max() > bound:
            raise SceneError(path, f"{v.tolist()} has a component beyond {bound:g}")
        return v

    def unit(self, path, comps) -> np.ndarray:
        v = self.vector(path, comps)
        norm = float(np.linalg.norm(v))
        if abs(norm - 1.0) > UNIT_TOL:
            raise SceneError(path, f"{v.tolist()} must be a unit vector (length {norm:.6g}, admissible 1 +- {UNIT_TOL:g})")
        return v

    def mechanism(self) -> Mechanism:
        sc = self.scene
        params = {n: Parameter(n, p["value"], p["unit"], p["meaning"] or n) for n, p in sc["parameters"].items()}
        coords = self.coordinates()
        points = self.points(coords)
        bodies = self.bodies(coords, points)
        springs = [self.link("springs", i, s, points) for i, s in enumerate(sc["springs"])]
        dampers = [self.link("dampers", i, d, points) for i, d in enumerate(sc["dampers"])]
        torsion = {key: [self.torsion(key, i, t, bodies) for i, t in enumerate(sc[key])]
                   for key in ("torsion_springs", "torsion_dampers")}
        _unique([(f"{key}[{i}].name", e["name"]) for key in ("springs", "dampers", "torsion_springs",
                                                               "torsion_dampers") for i, e in enumerate(sc[key])])
        grav = sc["gravity"]
        self.ranged("gravity.g", grav["g"], 0.0, 1e4, "m/s^2")
        self.unit("gravity.direction", grav["direction"])
        self.moves_something(coords, points, bodies)
        eff = sc["effects"]
        return Mechanism(sc["name"] or "mechanism", params, coords, points, bodies, springs, dampers,
                         torsion["torsion_springs"], torsion["torsion_dampers"], grav["g"], grav["direction"],
                         Effects(eff["damping"], eff["preload"], eff["gravity"]))

    def coordinates(self) -> list[Coordinate]:
        items = self.scene["coordinates"]
        _unique([(f"coordinates[{i}].name", c["name"]) for i, c in enumerate(items)])
        for i, c in enumerate(items):
            self.unit(f"coordinates[{i}].axis", c["axis"])
        return [Coordinate(c["name"], c["type"], c["axis"]) for c in items]

    def points(self, coords) -> dict[str, Point]:
        items = self.scene["points"]
        _unique([(f"points[{i}].name", p["name"]) for i, p in enumerate(items)])
        kinds = {c.name: c.kind for c in coords}
        index = {p["name"]: i for i, p in enumerate(items)}
        out = {}
        for i, p in enumerate(items):
            where = f"points[{i}]"
            if p["at"] is not None:
                self.vector(f"{where}.at", p["at"])
                out[p["name"]] = Point(p["name"], None, p["at"])
                continue
            self.vector(f"{where}.vector", p["vector"])
            _listed(f"{where}.turns", p["turns"], kinds, "angle")
            _listed(f"{where}.slides", p["slides"], kinds, "slide")
            seen, parent = {p["name"]}, p["from"]
            while parent is not None:
                if parent not in index:
                    raise SceneError(f"{where}.from", f"point '{parent}' is not defined{_close(parent, index)}")
                if parent in seen:
                    raise SceneError(f"{where}.from", f"the chain of vectors of '{p['name']}' loops through "
                                                      f"'{parent}': not reachable from a fixed root")
                seen.add(parent)
                parent = items[index[parent]]["from"]
            out[p["name"]] = Point(p["name"], p["from"], p["vector"], p["turns"], p["slides"])
        return out

    def bodies(self, coords, points) -> list[Body]:
        items = self.scene["bodies"]
        _unique([(f"bodies[{i}].name", b["name"]) for i, b in enumerate(items)])
        kinds = {c.name: c.kind for c in coords}
        out = []
        for i, b in enumerate(items):
            where = f"bodies[{i}]"
            if b["name"] == GROUND:
                raise SceneError(f"{where}.name", f"'{GROUND}' names the fixed frame; choose another name")
            if b["com"] not in points:
                raise SceneError(f"{where}.com", f"point '{b['com']}' is not defined{_close(b['com'], points)}")
            self.ranged(f"{where}.mass", b["mass"], *S.MASS_RANGE, "kg", zero_ok=True)
            J = [self.ranged(f"{where}.inertia[{k}]", t, *S.INERTIA_RANGE, "kg m^2", zero_ok=True)
                 for k, t in enumerate(b["inertia"])]
            # a zero moment is "not modelled" (planar bodies give only J_z): the triangle
            # inequalities bind a full tensor, all three moments given
            for k in range(3):
                if all(J) and J[k] > (J[(k + 1) % 3] + J[(k + 2) % 3]) * (1 + 1e-12):
                    raise SceneError(f"{where}.inertia[{k}]", f"{J[k]:g} kg m^2 exceeds the sum of the other two "
                                                              f"principal moments {J[(k + 1) % 3] + J[(k + 2) % 3]:g} "
                                                              "(triangle inequality of an inertia tensor)")
            if b["principal_axes"] is not None:
                P = [self.vector(f"{where}.principal_axes[{k}]", ax) for k, ax in enumerate(b["principal_axes"])]
                gram = np.array(P) @ np.array(P).T
                bad = np.argwhere(np.abs(gram - np.eye(3)) > UNIT_TOL)
                if len(bad):
                    i, j = sorted(bad[0])
                    raise SceneError(f"{where}.principal_axes", f"must be orthonormal; axis {i + 1} . axis {j + 1} "
                                                                f"= {gram[i, j]:.6g} (expected {int(i == j)})")
            turns = points[b["com"]].turns if b["turns"] is None else b["turns"]
            _listed(f"{where}.turns", turns, kinds, "angle")
            out.append(Body(b["name"], b["mass"], b["inertia"], b["com"], turns, b["principal_axes"]))
        return out

    def link(self, key, i, e, points) -> Link:
        where = f"{key}[{i}]"
        a, b = e["ends"]
        for end in (a, b):
            if end not in points:
                raise SceneError(f"{where}.ends", f"point '{end}' is not defined{_close(end, points)}")
        if a == b:
            raise SceneError(f"{where}.ends", f"both ends are '{a}': an element must join two points")
        d = self.position(b, points) - self.position(a, points)
        if np.linalg.norm(d) <= 1e-12 * max(1.0, np.abs(self.position(a, points)).max()):
            raise SceneError(f"{where}.ends", f"ends '{a}' and '{b}' coincide in equilibrium (zero length); "
                                              "an element needs a direction")
        if key == "dampers":
            self.ranged(f"{where}.viscosity", e["viscosity"], 0.0, S.COEF_MAX, "N s/m")
            return Link(e["name"], a, b, e["viscosity"])
        self.ranged(f"{where}.stiffness", e["stiffness"], 0.0, S.COEF_MAX, "N/m")
        self.preload(f"{where}.preload", e["preload"], "N")
        if e["free_length"] is not None:
            self.ranged(f"{where}.free_length", e["free_length"], 0.0, S.LENGTH_MAX, "m")
        return Link(e["name"], a, b, e["stiffness"], e["preload"], e["free_length"])

    def preload(self, path, text, unit):
        if text is None:
            return
        if text == EQUILIBRIUM:
            if self.scene["equilibrium"]["solve"]:
                raise SceneError(path, "equilibrium.solve needs a preload value (or a free length), "
                                       "not \"equilibrium\"")
            return
        self.ranged(path, text, -S.FORCE_MAX, S.FORCE_MAX, unit)

    def torsion(self, key, i, t, bodies) -> Torsion:
        where = f"{key}[{i}]"
        names = {b.name for b in bodies}
        for b in t["bodies"]:
            if b != GROUND and b not in names:
                raise SceneError(f"{where}.bodies", f"body '{b}' is not defined{_close(b, names | {GROUND})}")
        if t["bodies"][0] == t["bodies"][1]:
            raise SceneError(f"{where}.bodies", f"both bodies are '{t['bodies'][0]}': a torsion element acts "
                                                "between two different bodies")
        self.unit(f"{where}.axis", t["axis"])
        coef = "stiffness" if key == "torsion_springs" else "viscosity"
        self.ranged(f"{where}.{coef}", t[coef], 0.0, S.COEF_MAX, "N m/rad" if coef == "stiffness" else "N m s/rad")
        if key == "torsion_springs":
            self.preload(f"{where}.preload", t["preload"], "N m")
        return Torsion(t["name"], *t["bodies"], t[coef], t["axis"], t.get("preload"))

    def position(self, name, points) -> np.ndarray:
        r = np.zeros(3)
        while name is not None:
            p = points[name]
            r += [self.value(f"points.{name}", x) for x in p.vector]
            name = p.parent
        return r

    def moves_something(self, coords, points, bodies) -> None:
        used = set()
        for p in points.values():
            used |= set(p.turns) | set(p.slides)
        for b in bodies:
            used |= set(b.turns)
        for i, c in enumerate(coords):
            if c.name not in used:
                raise SceneError(f"coordinates[{i}].name", f"coordinate '{c.name}' moves nothing: no point or body "
                                                           "lists it in turns/slides")


def _unique(named: list[tuple[str, str]]) -> None:
    seen = set()
    for path, name in named:
        if name in seen:
            raise SceneError(path, f"'{name}' is defined twice (names must be unique)")
        seen.add(name)


def _listed(path, names, kinds, kind) -> None:
    for name in names:
        if kinds.get(name) != kind:
            raise SceneError(path, f"'{name}' is not {'an' if kind == 'angle' else 'a'} {kind} coordinate"
                                   f"{_close(name, [k for k, v in kinds.items() if v == kind])}")
    if len(set(names)) != len(names):
        twice = next(n for n in names if names.count(n) > 1)
        raise SceneError(path, f"coordinate '{twice}' is listed twice")


def _close(word, options) -> str:
    close = difflib.get_close_matches(word, list(options), n=1)
    return f" (did you mean '{close[0]}'?)" if close else ""


def coordinate_count(resolved: dict) -> int:
    """Number of generalized coordinates of the scene (without building the model)."""
    return resolved["chain"]["n"] if resolved["chain"] is not None else len(resolved["coordinates"])


def load_mechanism(path: Path) -> Mechanism:
    """The :class:`~symmech.smm.model.Mechanism` of a scene file (explicit vector model or a generated
    ``[chain]``), its parameters evaluated in floats; no sympy (the errata sample around its values)."""
    data = read_toml(path)
    if data.get("kind") != "mechanism":
        raise SymmechError(f"{path}: not a mechanism scene")
    return model(validate(S.SCHEMA, data))
