"""Layer 1 vocabulary: named symbolic matrices with declared arguments.

A derivation is a pure function of sympy that returns :class:`NamedMatrix`
objects; a :class:`ModuleSpec` groups them into one generated module. Nothing
here knows about files, numpy or templates.
"""
from __future__ import annotations

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
    ``equations`` names the paper's equations the matrix stands for.
    """

    name: str
    matrix: sympy.Matrix
    args: tuple[Arg, ...]
    meaning: str
    unit: str
    equations: str = ""

    def __post_init__(self):
        object.__setattr__(self, "matrix", sympy.Matrix(self.matrix))
        object.__setattr__(self, "args", tuple(self.args))
        self.check()

    def check(self) -> None:
        names = [a.name for a in self.args]
        if len(set(names)) != len(names):
            raise ValueError(f"{self.name}: duplicate argument names in {names}")
        declared = {a.symbol for a in self.args}
        missing = sorted((s.name for s in self.matrix.free_symbols - declared))
        if missing:
            raise ValueError(
                f"{self.name}: free symbols not declared as arguments: {', '.join(missing)}"
            )

    def code_matrix(self) -> sympy.Matrix:
        """The matrix with every argument symbol renamed to its code name."""
        return self.matrix.xreplace({a.symbol: sympy.Symbol(a.name) for a in self.args})

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
    """A generated module: its name under ``symmech.generated`` and its functions."""

    name: str
    doc: str
    source: str
    functions: tuple[NamedMatrix, ...] = field(default_factory=tuple)

    def __post_init__(self):
        object.__setattr__(self, "functions", tuple(self.functions))
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
