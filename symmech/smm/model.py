"""Mechanism description for the structural model method (pure Python, no sympy).

A :class:`Mechanism` is the paper's *vector model* (section 2): every
characteristic point is reached from a fixed root by a chain of vectors drawn
in the equilibrium configuration. Each chain vector ``v`` names the angle
coordinates that turn it (``turns``, outermost first) and the slide coordinates
that lengthen it (``slides``); its value at the generalized coordinates q is

    v(q) = R_turns[0](q) ... R_turns[-1](q) (v0 + sum_s q_s u_s),

with R_a a rotation by q_a about the coordinate's axis e_a (given in the
equilibrium configuration) and u_s the slide's unit direction. The position of
a point is its root position plus the sum of its chain vectors. Absolute angles
("main bodies") list one angle per vector; relative angles ("attached bodies")
list the angles of every body from the root outwards.

All quantities are expression strings of the parameters (SI units): the same
model is evaluated with floats (:func:`numeric`) or sympy (``symmech.smm.forms``).
:func:`from_scene` reads a scene through :class:`~symmech.core.scene.Section`
accessors and validates the structure; errors name the element.
"""
from __future__ import annotations

import ast
import functools
import math
import operator
from dataclasses import dataclass, field, replace

from symmech.core.scene import SceneError, Section, SymmechError

GROUND = "ground"
EQUILIBRIUM = "equilibrium"  # a spring preload left to the equilibrium conditions (5)


@dataclass(frozen=True)
class Parameter:
    """A named scene parameter: numeric value, SI unit, meaning."""

    name: str
    value: float
    unit: str
    meaning: str


@dataclass(frozen=True)
class Coordinate:
    """A generalized coordinate: ``angle`` [rad] about ``axis`` or ``slide`` [m] along ``axis``."""

    name: str
    kind: str
    axis: tuple[str, str, str]

    @property
    def unit(self) -> str:
        return "rad" if self.kind == "angle" else "m"


@dataclass(frozen=True)
class Point:
    """A characteristic point: a root (``parent`` None, ``vector`` = position) or a chain vector."""

    name: str
    parent: str | None
    vector: tuple[str, str, str]
    turns: tuple[str, ...] = ()
    slides: tuple[str, ...] = ()


@dataclass(frozen=True)
class Body:
    """A rigid body: mass [kg] at point ``com``, principal central moments ``inertia``
    [kg m^2] about its principal axes in equilibrium, turned by the angle coordinates
    ``turns``. ``axes`` are the three principal axes (orthonormal 3-vectors, global
    components); None means the global x, y, z."""

    name: str
    mass: str
    inertia: tuple[str, str, str]
    com: str
    turns: tuple[str, ...]
    axes: tuple[tuple[str, str, str], tuple[str, str, str], tuple[str, str, str]] | None = None


@dataclass(frozen=True)
class Link:
    """A spring or damper between points ``a`` and ``b`` along the line joining them.

    ``coef`` is the stiffness [N/m] or viscosity [N s/m]; ``preload`` the tension
    [N] in the equilibrium configuration (springs only; None with ``free_length``).
    """

    name: str
    a: str
    b: str
    coef: str
    preload: str | None = None
    free_length: str | None = None


@dataclass(frozen=True)
class Torsion:
    """A torsion spring [N m/rad] or damper [N m s/rad] acting on the rotation of body
    ``b`` relative to body ``a`` (``ground`` for the fixed frame) about ``axis``.

    ``preload`` (springs only) is the moment [N m] in the equilibrium configuration,
    acting on the twist axis . vee(R_a^T R_b) (see ``symmech.smm.lagrange._twist``),
    or ``"equilibrium"`` (solved from eq. (5) with the springs' tensions)."""

    name: str
    a: str
    b: str
    coef: str
    axis: tuple[str, str, str]
    preload: str | None = None


@dataclass(frozen=True)
class Effects:
    """Which second-order and dissipative effects enter the matrices."""

    damping: bool = True
    preload: bool = True
    gravity: bool = True


@dataclass
class Mechanism:
    """The vector model of a linear(ized) mechanism: a q'' + b q' + c q = Q."""

    name: str
    parameters: dict[str, Parameter]
    coordinates: list[Coordinate]
    points: dict[str, Point]
    bodies: list[Body]
    springs: list[Link] = field(default_factory=list)
    dampers: list[Link] = field(default_factory=list)
    torsion_springs: list[Torsion] = field(default_factory=list)
    torsion_dampers: list[Torsion] = field(default_factory=list)
    gravity: str = "0"
    gravity_direction: tuple[str, str, str] = ("0", "-1", "0")
    effects: Effects = field(default_factory=Effects)

    @property
    def coordinate_names(self) -> list[str]:
        return [c.name for c in self.coordinates]

    def coordinate(self, name: str) -> Coordinate:
        for c in self.coordinates:
            if c.name == name:
                return c
        raise KeyError(name)

    def chain(self, point: str) -> list[Point]:
        """Chain of ``point`` from its root: [root, ..., point]."""
        out = []
        seen = set()
        name = point
        while name is not None:
            if name in seen:
                raise SymmechError(f"point '{point}' is not reachable from a fixed root: its chain of vectors "
                                   f"loops through '{name}'")
            seen.add(name)
            if name not in self.points:
                if not out:
                    raise SymmechError(f"point '{name}' is not defined")
                raise SymmechError(f"point '{point}' is not reachable from a fixed root: parent point '{name}' "
                                   f"of '{out[-1].name}' is not defined")
            p = self.points[name]
            out.append(p)
            name = p.parent
        return out[::-1]

    def body_turns(self, name: str) -> tuple[str, ...]:
        if name == GROUND:
            return ()
        for b in self.bodies:
            if b.name == name:
                return b.turns
        raise KeyError(name)

    def characteristic_points(self) -> list[str]:
        """Points that carry a mass or an end of a spring or damper, in first-use order."""
        names = [b.com for b in self.bodies]
        for link in self.springs + self.dampers:
            names += [link.a, link.b]
        return list(dict.fromkeys(names))

    def values(self) -> dict[str, float]:
        return {p.name: p.value for p in self.parameters.values()}


# ---------------------------------------------------------------- expressions

_FUNCS = {"sin": math.sin, "cos": math.cos, "tan": math.tan, "sqrt": math.sqrt,
          "asin": math.asin, "acos": math.acos, "atan": math.atan, "atan2": math.atan2,
          "exp": math.exp, "log": math.log}
_CONSTS = {"pi": math.pi}
_BINOPS = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul,
           ast.Div: operator.truediv, ast.Pow: operator.pow}


@functools.lru_cache(maxsize=4096)
def expression_names(text: str) -> frozenset[str]:
    """Parameter names used by an expression (function names excluded)."""
    tree = _parse(text, "<expression>")
    called = {n.func.id for n in ast.walk(tree) if isinstance(n, ast.Call) and isinstance(n.func, ast.Name)}
    return frozenset({n.id for n in ast.walk(tree) if isinstance(n, ast.Name)} - called - set(_CONSTS))


@functools.lru_cache(maxsize=4096)
def _parse(text: str, where: str):
    try:
        return ast.parse(text, mode="eval")
    except SyntaxError:
        raise SymmechError(f"{where}: cannot read expression {text!r}") from None


def evaluate(text: str, values: dict[str, float], where: str = "<expression>") -> float:
    """Value of an arithmetic expression of parameters (+ - * / **, sin, cos, sqrt, pi ...)."""
    try:
        return float(interpret(text, values, where))
    except (ZeroDivisionError, ValueError, OverflowError) as exc:
        raise SymmechError(f"{where}: expression {text!r} cannot be evaluated ({exc})") from None


def interpret(text: str, values: dict, where: str = "<expression>", funcs=None, consts=None, number=float):
    """Walk the expression's syntax tree with the given values, functions, constants and number
    type (floats by default; ``symmech.smm.derive`` passes sympy's)."""
    funcs = _FUNCS if funcs is None else funcs
    consts = _CONSTS if consts is None else consts

    def ev(node):
        if isinstance(node, ast.Expression):
            return ev(node.body)
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) \
                and not isinstance(node.value, bool):
            return number(node.value)
        if isinstance(node, ast.Name):
            if node.id in values:
                return values[node.id]
            if node.id in consts:
                return consts[node.id]
            raise SymmechError(f"{where}: unknown parameter '{node.id}' in {text!r}")
        if isinstance(node, ast.BinOp) and type(node.op) in _BINOPS:
            return _BINOPS[type(node.op)](ev(node.left), ev(node.right))
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            v = ev(node.operand)
            return -v if isinstance(node.op, ast.USub) else v
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in funcs:
            return funcs[node.func.id](*(ev(a) for a in node.args))
        raise SymmechError(f"{where}: unsupported expression {text!r}")

    return ev(_parse(text, where))


def numeric(m: Mechanism) -> "NumericArith":
    """Float arithmetic over ``m``'s parameter values."""
    return NumericArith(m.values())


class NumericArith:
    """Evaluates model expressions to floats (for numeric assembly)."""

    zero = 0.0

    def __init__(self, values: dict[str, float]):
        self.values = values
        self._cache: dict[str, float] = {}

    def __call__(self, text: str, where: str = "<expression>") -> float:
        if text not in self._cache:
            self._cache[text] = evaluate(text, self.values, where)
        return self._cache[text]

    @staticmethod
    def sqrt(x):
        return math.sqrt(x)

    @staticmethod
    def sum(terms):
        return math.fsum(terms)

    @staticmethod
    def prod(factors):
        return math.prod(factors)

    @staticmethod
    def is_zero(x) -> bool:
        return x == 0.0


# ---------------------------------------------------------------- scenes

def _expr(sec: Section, key: str, *, default=None, where: str) -> str:
    """An expression field: a number or a string expression of parameters."""
    value = sec.raw(key, default=default)
    if value is None:
        raise SceneError(where, "missing (required)")
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        raise SceneError(where, f"expected a number or an expression string, got {value!r}")
    return value if isinstance(value, str) else number_text(value)


def number_text(value: float) -> str:
    """A number as expression text; integral values print as integers (exact in sympy)."""
    value = float(value)
    return str(int(value)) if value.is_integer() and abs(value) < 1e15 else repr(value)


def _vector(sec: Section, key: str, where: str, default=None) -> tuple[str, str, str]:
    value = sec.raw(key, default=default)
    if value is None:
        raise SceneError(where, "missing (required)")
    if not isinstance(value, list) or len(value) not in (2, 3):
        raise SceneError(where, f"expected a list of 2 or 3 components, got {value!r}")
    comps = []
    for i, v in enumerate(value):
        if isinstance(v, bool) or not isinstance(v, (int, float, str)):
            raise SceneError(f"{where}[{i}]", f"expected a number or an expression string, got {v!r}")
        comps.append(v if isinstance(v, str) else number_text(v))
    return tuple(comps + ["0"] * (3 - len(comps)))


def _names(sec: Section, key: str, where: str) -> tuple[str, ...]:
    value = sec.raw(key, default=[])
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise SceneError(where, f"expected a list of names, got {value!r}")
    return tuple(value)


def _items(scene: Section, key: str) -> list[Section]:
    raw = scene.raw(key, default=[])
    if not isinstance(raw, list):
        raise SceneError(key, "expected an array of tables ([[" + key + "]])")
    return [Section(item, f"{key}[{i}]") for i, item in enumerate(raw)]


def _unique(kind: str, names: list[str]) -> None:
    seen = set()
    for n in names:
        if n in seen:
            raise SymmechError(f"{kind} '{n}' is defined twice")
        seen.add(n)


def from_scene(scene: Section) -> Mechanism:
    """Read and validate the mechanism part of a scene (see docs/scenes-mechanism.md)."""
    name = scene.str("name", default="mechanism")
    params = {}
    psec = scene.section("parameters", default={})
    for pname in psec.keys():
        entry = psec.raw(pname)
        where = psec.name(pname)
        if not pname.isidentifier():
            raise SceneError(where, "a parameter name must be an identifier")
        if isinstance(entry, (int, float)) and not isinstance(entry, bool):
            entry = {"value": entry}
        p = Section(entry, where)
        unit = p.str("unit", default="1")
        params[pname] = Parameter(pname, p.float("value", unit=unit), unit, p.str("meaning", default=pname))
        p.finish()

    coords = []
    for c in _items(scene, "coordinates"):
        kind = c.choice("type", ("angle", "slide"))
        axis = _vector(c, "axis", c.name("axis"), default=[0, 0, 1] if kind == "angle" else None)
        coords.append(Coordinate(c.str("name"), kind, axis))
        c.finish()
    _unique("coordinate", [c.name for c in coords])
    if not coords:
        raise SceneError("coordinates", "a mechanism needs at least one generalized coordinate")

    points = {}
    for p in _items(scene, "points"):
        pname = p.str("name")
        if p.has("at"):
            points[pname] = Point(pname, None, _vector(p, "at", p.name("at")))
        else:
            points[pname] = Point(pname, p.str("from"), _vector(p, "vector", p.name("vector")),
                                  _names(p, "turns", p.name("turns")), _names(p, "slides", p.name("slides")))
        p.finish()
    _unique("point", [p for p in points])

    bodies = []
    for b in _items(scene, "bodies"):
        where = b.name("inertia")
        raw = b.raw("inertia", default=0.0)
        if isinstance(raw, list):
            inertia = _vector(b, "inertia", where)
        else:
            inertia = ("0", "0", _expr(b, "inertia", default=0.0, where=where))
        com = b.str("com")
        turns = b.raw("turns", default=None)
        axes = None
        if b.has("principal_axes"):
            raw = b.raw("principal_axes")
            where = b.name("principal_axes")
            if not isinstance(raw, list) or len(raw) != 3 or not all(isinstance(v, list) and len(v) == 3
                                                                     for v in raw):
                raise SceneError(where, f"expected three axes of 3 components, got {raw!r}")
            axes = tuple(_vector(Section({"v": v}, where), "v", f"{where}[{i}]") for i, v in enumerate(raw))
        bodies.append(Body(b.str("name"), _expr(b, "mass", where=b.name("mass")), inertia, com,
                           _names(b, "turns", b.name("turns")) if turns is not None else None, axes))
        b.finish()
    _unique("body", [b.name for b in bodies])

    springs = []
    for s in _items(scene, "springs"):
        ends = _names(s, "ends", s.name("ends"))
        if len(ends) != 2:
            raise SceneError(s.name("ends"), f"expected two point names, got {list(ends)!r}")
        pre = _expr(s, "preload", where=s.name("preload")) if s.has("preload") else None
        free = _expr(s, "free_length", where=s.name("free_length")) if s.has("free_length") else None
        if pre is not None and free is not None:
            raise SceneError(s.name("free_length"), "give either preload or free_length, not both")
        springs.append(Link(s.str("name"), ends[0], ends[1], _expr(s, "stiffness", where=s.name("stiffness")),
                            pre, free))
        s.finish()
    dampers = []
    for d in _items(scene, "dampers"):
        ends = _names(d, "ends", d.name("ends"))
        if len(ends) != 2:
            raise SceneError(d.name("ends"), f"expected two point names, got {list(ends)!r}")
        dampers.append(Link(d.str("name"), ends[0], ends[1], _expr(d, "viscosity", where=d.name("viscosity"))))
        d.finish()
    torsion = {}
    for key, coef in (("torsion_springs", "stiffness"), ("torsion_dampers", "viscosity")):
        torsion[key] = []
        for t in _items(scene, key):
            bs = _names(t, "bodies", t.name("bodies"))
            if len(bs) != 2:
                raise SceneError(t.name("bodies"), f"expected two body names (or 'ground'), got {list(bs)!r}")
            pre = None
            if key == "torsion_springs" and t.has("preload"):
                pre = _expr(t, "preload", where=t.name("preload"))
            torsion[key].append(Torsion(t.str("name"), bs[0], bs[1], _expr(t, coef, where=t.name(coef)),
                                        _vector(t, "axis", t.name("axis"), default=[0, 0, 1]), pre))
            t.finish()
    _unique("spring", [s.name for s in springs + dampers + torsion["torsion_springs"] + torsion["torsion_dampers"]])

    g = scene.section("gravity", default={})
    gravity = _expr(g, "g", default=0.0, where=g.name("g"))
    gdir = _vector(g, "direction", g.name("direction"), default=[0, -1, 0])
    g.finish()
    e = scene.section("effects", default={})
    effects = Effects(e.bool("damping", default=True), e.bool("preload", default=True),
                      e.bool("gravity", default=True))
    e.finish()

    m = Mechanism(name, params, coords, points, bodies, springs, dampers,
                  torsion["torsion_springs"], torsion["torsion_dampers"], gravity, gdir, effects)
    validate(m)
    return m


def validate(m: Mechanism) -> None:
    """Structural checks; every error names the element."""
    kinds = {c.name: c.kind for c in m.coordinates}
    known = set(m.parameters)

    def exprs_ok(where, *texts):
        for t in texts:
            unknown = expression_names(t) - known
            if unknown:
                raise SymmechError(f"{where}: unknown parameter '{sorted(unknown)[0]}' in {t!r}")

    for c in m.coordinates:
        exprs_ok(f"coordinate '{c.name}'", *c.axis)
    for p in m.points.values():
        m.chain(p.name)
        exprs_ok(f"point '{p.name}'", *p.vector)
        for q in p.turns:
            if kinds.get(q) != "angle":
                raise SymmechError(f"point '{p.name}': turns names '{q}', which is not an angle coordinate")
        for q in p.slides:
            if kinds.get(q) != "slide":
                raise SymmechError(f"point '{p.name}': slides names '{q}', which is not a slide coordinate")
        if len(set(p.turns)) != len(p.turns) or len(set(p.slides)) != len(p.slides):
            raise SymmechError(f"point '{p.name}': a coordinate is listed twice")
    bodies = {b.name for b in m.bodies}
    for i, b in enumerate(m.bodies):
        if b.com not in m.points:
            raise SymmechError(f"body '{b.name}': centre of mass point '{b.com}' is not defined")
        exprs_ok(f"body '{b.name}'", b.mass, *b.inertia, *(x for ax in b.axes or () for x in ax))
        if b.turns is None:
            m.bodies[i] = b = replace(b, turns=m.points[b.com].turns)
        for q in b.turns:
            if kinds.get(q) != "angle":
                raise SymmechError(f"body '{b.name}': turns names '{q}', which is not an angle coordinate")
    for link in m.springs + m.dampers:
        for end in (link.a, link.b):
            if end not in m.points:
                raise SymmechError(f"spring or damper '{link.name}': end point '{end}' is not defined")
        exprs_ok(f"spring or damper '{link.name}'", link.coef,
                 *(t for t in (link.preload, link.free_length) if t and t != EQUILIBRIUM))
    for t in m.torsion_springs + m.torsion_dampers:
        for b in (t.a, t.b):
            if b != GROUND and b not in bodies:
                raise SymmechError(f"torsion element '{t.name}': body '{b}' is not defined")
        exprs_ok(f"torsion element '{t.name}'", t.coef, *t.axis,
                 *((t.preload,) if t.preload and t.preload != EQUILIBRIUM else ()))
    exprs_ok("gravity", m.gravity, *m.gravity_direction)
    used = set()
    for p in m.points.values():
        used |= set(p.turns) | set(p.slides)
    for b in m.bodies:
        used |= set(b.turns)
    for c in m.coordinates:
        if c.name not in used:
            raise SymmechError(f"coordinate '{c.name}' moves nothing: no point or body lists it in turns/slides")
    values = m.values()
    for c in m.coordinates:
        axis = [evaluate(t, values, f"coordinate '{c.name}'") for t in c.axis]
        norm = math.sqrt(sum(a * a for a in axis))
        if abs(norm - 1.0) > 1e-9:
            raise SymmechError(f"coordinate '{c.name}': axis {axis} must be a unit vector (length {norm:.6g})")
    for b in m.bodies:
        if evaluate(b.mass, values, f"body '{b.name}'") < 0:
            raise SymmechError(f"body '{b.name}': mass {b.mass} is negative")
        if b.axes is not None:
            P = [[evaluate(t, values, f"body '{b.name}'") for t in ax] for ax in b.axes]
            for i in range(3):
                for j in range(i, 3):
                    d = sum(x * y for x, y in zip(P[i], P[j]))
                    if abs(d - (i == j)) > 1e-9:
                        raise SymmechError(f"body '{b.name}': principal_axes must be orthonormal; axis {i + 1} "
                                           f". axis {j + 1} = {d:.6g} (expected {int(i == j)})")
