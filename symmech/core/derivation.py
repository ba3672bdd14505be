"""Layer 1 vocabulary: named symbolic matrices with declared arguments.

A derivation is a pure function of sympy that returns :class:`NamedMatrix`
objects; a :class:`ModuleSpec` groups them into one generated module. Nothing
here knows about files, numpy or templates.
"""
from __future__ import annotations

import functools
import keyword
import re
from dataclasses import dataclass, field

import sympy


@dataclass(frozen=True)
class Arg:
    """One argument of a generated function: its symbol, meaning and SI unit."""

    symbol: sympy.Symbol
    meaning: str
    unit: str

    @property
    def name(self) -> str:
        """Python identifier used in generated code: primes become 'p', keywords get '_'."""
        name = re.sub(r"\W", "_", self.symbol.name.replace("'", "p"))
        return name + "_" if keyword.iskeyword(name) else name


@dataclass(frozen=True)
class NamedMatrix:
    """A symbolic matrix that becomes one generated function.

    ``args`` fixes the argument order of the generated function; every free
    symbol of ``matrix`` must be one of them (checked by :meth:`check`).
    ``equations`` names the paper's equations the matrix stands for. ``whole``:
    one CSE over all its elements instead of chunks (a function whose parts share
    much, e.g. a rate with its mass matrix; slower to derive when large).
    """

    name: str
    matrix: sympy.Matrix
    args: tuple[Arg, ...]
    meaning: str
    unit: str
    equations: str = ""
    whole: bool = False

    def __post_init__(self):
        object.__setattr__(self, "matrix", sympy.Matrix(self.matrix))
        object.__setattr__(self, "args", tuple(self.args))
        self.check()

    def check(self) -> None:
        names = [a.name for a in self.args]
        if len(set(names)) != len(names):
            raise ValueError(f"{self.name}: duplicate argument names in {names}")
        declared = {a.symbol for a in self.args}
        missing = sorted(s.name for s in self.matrix.free_symbols - declared)
        if missing:
            raise ValueError(
                f"{self.name}: free symbols not declared as arguments: {', '.join(missing)}"
            )

    @functools.cached_property
    def code_matrix(self) -> sympy.ImmutableMatrix:
        """The matrix with every argument symbol renamed to its code name; a symbol that already is one is left out,
        since a rule x -> x rebuilds every tree it reaches too. Renamed once per instance (the renaming rebuilds every
        expression tree, and every target of a module prints it); immutable, so no caller can change what the next
        one reads. Kept in the instance's ``__dict__``, outside the fields, so equality is unchanged."""
        renamed = {a.symbol: sympy.Symbol(a.name) for a in self.args if a.symbol != sympy.Symbol(a.name)}
        return sympy.ImmutableMatrix(self.matrix.xreplace(renamed) if renamed else self.matrix)

    @property
    def shape(self) -> tuple[int, ...]:
        """Trailing shape of the numeric result: () scalar, (n,) column, (n, m)."""
        rows, cols = self.matrix.shape
        if rows == cols == 1:
            return ()
        if cols == 1:
            return (rows,)
        return (rows, cols)


@dataclass(frozen=True)
class ModuleSpec:
    """A generated module: its name under ``symmech.generated`` and its functions.

    With ``dynamics`` the module also holds that ODE's ``rate`` functions (appended to
    ``functions``) and the solve_ivp-style ``rhs``/``jac`` over the declared layout. With ``rates``
    False it holds the layout alone: a C module whose own functions read (t, y, p) and combine what the
    rate functions would give (the elastic trolley's F with its mass block under one CSE): no Python rhs.
    """

    name: str
    doc: str
    source: str
    functions: tuple[NamedMatrix, ...] = field(default_factory=tuple)
    dynamics: Dynamics | None = None  # emitted as rhs(t, y, p), jac(t, y, p), STATE, PARAMS
    rates: bool = True

    def __post_init__(self):
        object.__setattr__(self, "functions", tuple(self.functions)
                           + (self.dynamics.functions() if self.dynamics and self.rates else ()))
        names = [f.name for f in self.functions]
        if len(set(names)) != len(names):
            raise ValueError(f"module {self.name}: duplicate function names")

    def function(self, name: str) -> NamedMatrix:
        for f in self.functions:
            if f.name == name:
                return f
        raise KeyError(f"module {self.name} has no function {name!r}")


def args_of(table) -> tuple[Arg, ...]:
    """Build arguments from ``(symbol, meaning, unit)`` triples."""
    return tuple(Arg(s, meaning, unit) for s, meaning, unit in table)


@dataclass(frozen=True)
class Event:
    """A physical event of a :class:`Dynamics`: where the scalar ``g(t, y, p)`` [``unit``] crosses zero, located
    by the integration (``solve_ivp``'s event attributes): ``direction`` +1 only where g rises through zero, -1
    only where it falls, 0 both; ``terminal``: the motion the equations describe ends there (e.g. a flight at
    contact). ``name`` is a Python identifier."""

    name: str
    g: sympy.Expr
    meaning: str
    unit: str
    direction: int = 0
    terminal: bool = False

    def __post_init__(self):
        if not self.name.isidentifier() or self.direction not in (-1, 0, 1):
            raise ValueError(f"event {self.name!r}: a Python identifier and a direction -1, 0 or 1")


@dataclass(frozen=True)
class Dynamics:
    """A first-order ODE ``M(t, y, p) y' = F(t, y, p)`` that a module emits as ``rhs(t, y, p)``.

    ``state`` and ``params`` declare the layout of the vectors ``y`` and ``p`` (order,
    meanings, units); ``time`` is the time symbol when the equations depend on it.
    ``mass`` is the matrix M (None: the identity, ``y' = F``). With ``jacobian`` the
    Jacobian ``d(y')/dy = M^-1 dF/dy`` is derived symbolically from ``F`` alone
    (:meth:`functions`), which needs M free of the state; ``jacobian=False`` emits
    ``rhs`` only and admits a state-dependent M. Nothing is inverted symbolically: the
    generated ``rhs`` and ``jac`` solve with M numerically.
    """

    state: tuple[Arg, ...]
    params: tuple[Arg, ...]
    rate: sympy.Matrix
    mass: sympy.Matrix | None = None
    time: Arg | None = None
    meaning: str = ""
    jacobian: bool = True
    events: tuple[Event, ...] = ()

    def __post_init__(self):
        object.__setattr__(self, "events", tuple(self.events))
        object.__setattr__(self, "state", tuple(self.state))
        object.__setattr__(self, "params", tuple(self.params))
        object.__setattr__(self, "rate", sympy.Matrix(self.rate))
        n = len(self.state)
        if self.rate.shape != (n, 1):
            raise ValueError(f"rate has shape {self.rate.shape}, the state has {n} entries")
        if self.mass is not None:
            object.__setattr__(self, "mass", sympy.Matrix(self.mass))
            if self.mass.shape != (n, n):
                raise ValueError(f"mass matrix has shape {self.mass.shape}, expected ({n}, {n})")
            depends = self.mass.free_symbols & {a.symbol for a in self.state}
            if depends and self.jacobian:
                raise ValueError(f"mass matrix depends on the state: {sorted(s.name for s in depends)}")

    @property
    def args(self) -> tuple[Arg, ...]:
        """Arguments of the emitted functions: time (if any), state, parameters."""
        return ((self.time,) if self.time else ()) + self.state + self.params

    def functions(self) -> tuple[NamedMatrix, ...]:
        """``rate`` F (n,), ``rate_jacobian`` dF/dy (n, n) if derived, with a mass matrix ``rate_mass`` M, with
        events ``event_values`` g (k,)."""
        y = sympy.Matrix([a.symbol for a in self.state])
        what = self.meaning or "the state"
        out = [NamedMatrix("rate", self.rate, self.args, f"F of M y' = F: rates of {what}",
                           "state unit / s (times M)")]
        if self.jacobian:
            out.append(NamedMatrix("rate_jacobian", jacobian(self.rate, y), self.args, "dF/dy, rows F, columns y",
                                   "unit of F / unit of y"))
        if self.mass is not None:
            out.append(NamedMatrix("rate_mass", self.mass, self.args, "M of M y' = F", "unit of F / unit of y'"))
        if self.events:
            out.append(NamedMatrix("event_values", sympy.Matrix([e.g for e in self.events]), self.args,
                                   "event functions g, one row per event: " + ", ".join(e.name for e in self.events),
                                   ", ".join(e.unit for e in self.events)))
        return tuple(out)


def jacobian(rate: sympy.Matrix, y: sympy.Matrix) -> sympy.Matrix:
    """``rate.jacobian(y)``, entry for entry the same expressions, differentiated with every largest subtree free
    of ``y`` held as a placeholder symbol: sympy's ``diff`` collects an expression's free symbols at every node it
    passes, so a rate whose coefficients are large expressions of the parameters (a mechanism's a, b, c) cost
    seconds to differentiate as it stands."""
    wrt = set(y)
    depends: dict[sympy.Basic, bool] = {}

    def on_y(e: sympy.Basic) -> bool:
        if e not in depends:
            depends[e] = e in wrt or any([on_y(a) for a in e.args])
        return depends[e]

    held: dict[sympy.Basic, sympy.Dummy] = {}

    def skeleton(e: sympy.Basic) -> sympy.Basic:
        if not on_y(e):
            return e if e.is_Atom else held.setdefault(e, sympy.Dummy())
        return e if e.is_Atom else e.func(*[skeleton(a) for a in e.args])

    rows = [skeleton(e) for e in rate]
    back = {v: k for k, v in held.items()}
    return sympy.Matrix([[r.diff(v).xreplace(back) for v in y] for r in rows])

