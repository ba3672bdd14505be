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
:func:`symmech.smm.build.mechanism` builds it from a validated scene and checks its
admissibility; errors name the scene field.
"""
from __future__ import annotations

import ast
import functools
import math
import operator
import re
from dataclasses import dataclass, field

from symmech.core import expressions
from symmech.core.scene import SymmechError

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

# The scene expression language is symmech.core.expressions (checked there, in the schema);
# here it is evaluated in floats (and, in symmech.smm.derive, in sympy).
_FUNCS = {name: abs if name == "abs" else getattr(math, name) for name in expressions.FUNCTIONS}
_CONSTS = dict(expressions.CONSTANTS)
_BINOPS = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul,
           ast.Div: operator.truediv, ast.Pow: operator.pow}
# Parameter names the generated modules use themselves (beyond the reserved names of expressions)
GENERATED_NAMES = frozenset({"out", "batch", EQUILIBRIUM})


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
    """Value of an arithmetic expression of parameters (+ - * / **, sin, cos, sqrt, pi ...);
    a division by zero, a domain error, an overflow or a complex value is a SymmechError."""
    try:
        value = interpret(text, values, where)
    except (ZeroDivisionError, ValueError, OverflowError, TypeError) as exc:
        raise SymmechError(f"{where}: expression {text!r} cannot be evaluated ({exc})") from None
    if isinstance(value, complex) or not math.isfinite(value):
        raise SymmechError(f"{where}: expression {text!r} evaluates to {value} (not a finite real number)")
    return float(value)


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


def numeric(m: Mechanism) -> NumericArith:
    """Float arithmetic over ``m``'s parameter values."""
    return NumericArith(m.values())


_MULTIPLE = re.compile(r"([0-9]{1,9})\*([A-Za-z][A-Za-z0-9_]*)")


class NumericArith:
    """Evaluates model expressions to floats (for numeric assembly)."""

    zero = 0.0

    def __init__(self, values: dict[str, float]):
        self.values = values
        self._cache: dict[str, float] = {}

    def __call__(self, text: str, where: str = "<expression>") -> float:
        if text not in self._cache:
            # integer multiples of a parameter (the 10^5 positions of a generated chain) skip the parser
            multiple = _MULTIPLE.fullmatch(text)
            if multiple and multiple[2] in self.values:
                self._cache[text] = int(multiple[1]) * self.values[multiple[2]]
            else:
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


def number_text(value: float) -> str:
    """A number as expression text; integral values print as integers (exact in sympy)."""
    value = float(value)
    return str(int(value)) if value.is_integer() and abs(value) < 1e15 else repr(value)
