"""Layer 2: print derived matrices as code through jinja2 templates.

``render`` returns the text of one generated module for a :class:`Target` and
``write`` writes it atomically (:mod:`symmech.core.codegen` decides what to
regenerate). Both targets print the same common-subexpression split
(:func:`cse_chunks`), which ``symmech latex --cse`` shows too: a target is a
printer (numpy, math or C99 calls), a template, the way a chunk line addresses
an output element, and whether a dynamics module's rates are printed on floats
too (the numpy module's one-state path), nothing more. The C99 target
(``<name>.c``) prints the same chunks as C statements into a flat row-major
``out`` (:func:`_c_context`), for code that leaves Python (``symmech export``).
The MathML target (``<name>_mathml.py``) holds what ``symmech report`` shows of
each function, its whole matrix typeset by :mod:`symmech.core.typeset`.

Determinism: elements are split into chunks in matrix order, each chunk is
CSE'd with ``order="canonical"`` and a fixed symbol stream, and the header
hash covers the template text, the generator version and ``srepr`` of every
expression with its argument list.
"""
from __future__ import annotations

import functools
import hashlib
import importlib
import importlib.resources
import math
import re
from dataclasses import dataclass
from pathlib import Path

import jinja2
import sympy
from sympy.printing.c import C99CodePrinter
from sympy.printing.mathml import MathMLPresentationPrinter
from sympy.printing.numpy import NumPyPrinter
from sympy.printing.pycode import PythonCodePrinter

from symmech import __version__
from symmech.core import integrity, typeset
from symmech.core.derivation import Dynamics, ModuleSpec, NamedMatrix

# Elements per chunk: each chunk is CSE'd on its own and, when a function has
# more than one, emitted as a private helper so no function body grows huge.
CHUNK_ELEMENTS = 64


@dataclass(frozen=True)
class Chunk:
    """CSE of a run of matrix elements: ``replacements`` then ``elements``."""

    replacements: tuple[tuple[sympy.Symbol, sympy.Expr], ...]
    elements: tuple[tuple[tuple[int, ...], sympy.Expr], ...]  # (index, expr)


def cse_chunks(nm: NamedMatrix) -> list[Chunk]:
    """Split ``nm`` (arguments under their code names) into chunks of CHUNK_ELEMENTS (one chunk when ``nm.whole``)
    and CSE each chunk."""
    clash = {a.name for a in nm.args if re.fullmatch(r"x\d+", a.name)}
    if clash:
        raise ValueError(f"{nm.name}: argument names {sorted(clash)} clash with CSE names x0, x1, ...")
    matrix = nm.code_matrix
    return list(_cse_chunks(matrix, nm.shape, len(matrix) if nm.whole else CHUNK_ELEMENTS))


@functools.lru_cache(maxsize=64)  # every target prints the same chunks: CSE once per matrix
def _cse_chunks(matrix: sympy.ImmutableMatrix, shape: tuple[int, ...], chunk_elements: int) -> tuple[Chunk, ...]:
    rows, cols = matrix.shape
    indexed = []
    for i in range(rows):
        for j in range(cols):
            index = {(): (), (rows,): (i,)}.get(shape, (i, j))
            indexed.append((index, matrix[i, j]))
    chunks = []
    counter = 0
    for start in range(0, len(indexed), chunk_elements):
        part = indexed[start:start + chunk_elements]
        symbols = sympy.numbered_symbols("x", start=counter)
        replacements, reduced = sympy.cse([e for _, e in part], symbols=symbols, order="canonical")
        counter += len(replacements)
        chunks.append(Chunk(tuple(replacements), tuple((idx, e) for (idx, _), e in zip(part, reduced))))
    return tuple(chunks)


class _ExactDivision:
    """x**(-1) printed as a division: exact and faster than a power call (both targets)."""

    def _print_Pow(self, expr, rational=False):
        if expr.exp == -1:
            return f"1/{self.parenthesize(expr.base, sympy.printing.precedence.PRECEDENCE['Pow'])}"
        return super()._print_Pow(expr, rational=rational)


class _NumPyPrinter(_ExactDivision, NumPyPrinter):
    """numpy.* calls that broadcast over a batch; refuses anything it cannot translate."""

    def __init__(self):
        super().__init__({"fully_qualified_modules": True, "strict": True})


class _MathPrinter(_ExactDivision, PythonCodePrinter):
    """math.* calls on floats, which numba compiles to plain libm calls."""

    def __init__(self):
        super().__init__({"fully_qualified_modules": True, "strict": True})


class _CPrinter(C99CodePrinter):
    """C99 <math.h> calls on doubles; refuses anything it cannot translate."""

    def __init__(self):
        super().__init__({"strict": True})


# C99 keywords and the names the C template declares: never an argument name
_C_RESERVED = frozenset("""auto break case char const continue default do double else enum extern float for goto if
inline int long register restrict return short signed sizeof static struct switch typedef union unsigned void volatile
while _Bool _Complex _Imaginary out sm_arg sm_t sm_y sm_p sm_i""".split())


@dataclass(frozen=True)
class Target:
    """An emission target: the same CSE'd chunks through another printer and template.

    ``element`` addresses one output element in a chunk line: ``...`` (numpy: the
    whole batch at once) or ``k`` (numba: the k-th configuration of a loop).
    """

    suffix: str  # module name = spec name + suffix
    template: str
    printer: type
    element: str
    reserved: frozenset[str]  # names the template uses beside the arguments
    float_rates: bool  # a dynamics module's rate functions also on floats with math (rhs/jac at one state)
    extension: str = ".py"
    comment: str = "#"  # line comment that starts the integrity header

    def file(self, name: str) -> str:
        """File name of the module of spec ``name`` in this target."""
        return f"{name}{self.suffix}{self.extension}"


NUMPY = Target("", "module.py.j2", _NumPyPrinter, "...", frozenset({"out", "batch", "math", "numpy"}), True)
NUMBA = Target("_nb", "numba.py.j2", _MathPrinter, "_k",
               frozenset({"out", "_k", "_steps", "_arrays", "_batch", "math", "numba", "numpy"}), False)
C99 = Target("", "c99.c.j2", _CPrinter, "", _C_RESERVED, False, ".c", "//")
# what `symmech report` shows of each function, typeset at codegen so that a report needs no sympy
MATHML = Target("_mathml", "mathml.py.j2", MathMLPresentationPrinter, "", frozenset(), False)
TARGETS = (NUMPY, NUMBA, C99, MATHML)
# functions of a dynamics module that take (t, y, p) in C, the layout of Dynamics.args
DYNAMICS_FUNCTIONS = ("rate", "rate_jacobian", "rate_mass", "event_values", "rate_and_mass_block")


def _chunk_lines(chunk: Chunk, printer, element: str) -> list[str]:
    lines = [f"{s} = {printer.doprint(e)}" for s, e in chunk.replacements]
    lines += [f"out[{', '.join([element, *map(str, idx)])}] = {printer.doprint(e)}"
              for idx, e in chunk.elements]
    return lines


def _float_lines(chunk: Chunk, printer, shape: tuple[int, ...]) -> list[str]:
    """Chunk lines on floats into a flat list ``out`` (row-major), zero elements left to its 0.0 fill."""
    lines = [f"{s} = {printer.doprint(e)}" for s, e in chunk.replacements]
    lines += [f"out[{_flat_index(idx, shape)}] = {printer.doprint(e)}" for idx, e in chunk.elements if e != 0]
    return lines


def _flat_index(index: tuple[int, ...], shape: tuple[int, ...]) -> int:
    flat = 0
    for i, n in zip(index, shape):
        flat = flat * n + i
    return flat


def _float_context(nm: NamedMatrix) -> dict:
    """``nm`` on floats with ``math`` (a dynamics module's one-state path): name, arguments, flat size, lines."""
    printer = _MathPrinter()
    lines = [line for c in cse_chunks(nm) for line in _float_lines(c, printer, nm.shape)]
    return {"name": nm.name, "arglist": ", ".join(a.name for a in nm.args), "size": math.prod(nm.shape),
            "lines": lines}


def _function_context(nm: NamedMatrix, target: Target) -> dict:
    clash = {a.name for a in nm.args} & target.reserved
    if clash:
        raise ValueError(f"{nm.name}: argument names {sorted(clash)} are reserved by the templates")
    printer = target.printer()
    arglist = ", ".join(a.name for a in nm.args)
    return {
        "name": nm.name,
        "meaning": nm.meaning,
        "unit": nm.unit,
        "equations": nm.equations,
        "args": nm.args,
        "arglist": arglist,
        "shape": nm.shape,
        "shape_text": "(...)" if not nm.shape else "(..., " + ", ".join(map(str, nm.shape)) + ")",
        "chunks": [_chunk_lines(c, printer, target.element) for c in cse_chunks(nm)],
    }


def _c_context(spec: ModuleSpec, nm: NamedMatrix) -> dict:
    """``nm`` as C statements: per chunk the arguments it reads (unpacked from ``sm_arg``, or from ``sm_t``, ``sm_y``,
    ``sm_p`` for a dynamics function), its CSE temporaries and its nonzero elements at flat row-major offsets."""
    clash = {a.name for a in nm.args} & C99.reserved
    if clash:
        raise ValueError(f"{nm.name}: argument names {sorted(clash)} are reserved in C")
    printer = _CPrinter()
    by_layout = spec.dynamics is not None and nm.name in DYNAMICS_FUNCTIONS
    if by_layout:
        dyn = spec.dynamics
        source = ([("sm_t", dyn.time.name)] if dyn.time else []) \
            + [(f"sm_y[{i}]", a.name) for i, a in enumerate(dyn.state)] \
            + [(f"sm_p[{i}]", a.name) for i, a in enumerate(dyn.params)]
        where = {name: place for place, name in source}
    else:
        where = {a.name: f"sm_arg[{i}]" for i, a in enumerate(nm.args)}
    chunks = []
    for chunk in cse_chunks(nm):
        used = set().union(*(e.free_symbols for _, e in chunk.replacements),
                           *(e.free_symbols for _, e in chunk.elements))
        chunks.append({
            "unpack": [(a.name, where[a.name]) for a in nm.args if sympy.Symbol(a.name) in used],
            "temps": [(str(s), printer.doprint(e)) for s, e in chunk.replacements],
            "elements": [(_flat_index(idx, nm.shape), printer.doprint(e)) for idx, e in chunk.elements if e != 0],
        })
    return {"name": nm.name, "meaning": nm.meaning, "unit": nm.unit, "equations": nm.equations, "args": nm.args,
            "size": math.prod(nm.shape), "shape": nm.shape, "by_layout": by_layout, "chunks": chunks}


def _mathml_context(nm: NamedMatrix) -> dict:
    """What the report shows of ``nm``: name, meaning, unit, equations, and its MathML (None when too long)."""
    return {"name": nm.name, "meaning": nm.meaning, "unit": nm.unit, "equations": nm.equations,
            "mathml": typeset.block(nm)}


def _context(spec: ModuleSpec, nm: NamedMatrix, target: Target) -> dict:
    if target is C99:
        return _c_context(spec, nm)
    return _mathml_context(nm) if target is MATHML else _function_context(nm, target)


def _dynamics_context(dyn: Dynamics) -> dict:
    """Layout constants and the call of the rate functions from ``(t, y, p)``."""
    def layout(args):
        return [repr((a.name, a.unit, a.meaning)) for a in args]

    call = (["t"] if dyn.time else []) + [f"y[{i}]" for i in range(len(dyn.state))] \
        + [f"p[{i}]" for i in range(len(dyn.params))]
    return {"state": layout(dyn.state), "params": layout(dyn.params), "state_args": dyn.state,
            "param_args": dyn.params, "n": len(dyn.state),
            "m": len(dyn.params), "call": ", ".join(call), "mass": dyn.mass is not None,
            "jacobian": dyn.jacobian,
            "time": f"{dyn.time.meaning} [{dyn.time.unit}]" if dyn.time else None, "meaning": dyn.meaning,
            "events": [repr((e.name, e.direction, e.terminal, e.unit, e.meaning)) for e in dyn.events],
            "event_args": dyn.events}


def template_names() -> list[str]:
    """Every template file, in name order (all of them feed every module's hashes)."""
    folder = importlib.resources.files("symmech.templates")
    return sorted(p.name for p in folder.iterdir() if p.name.endswith(".j2"))


def _template_text(name: str) -> str:
    return importlib.resources.files("symmech.templates").joinpath(name).read_text()


def inputs_hash(spec: ModuleSpec, target: Target = NUMPY) -> str:
    """sha256 of everything the module text is made from."""
    h = hashlib.sha256()
    for part in (__version__, target.file(""), *map(_template_text, template_names()),
                 spec.name, spec.doc, spec.source):
        h.update(part.encode())
    for f in spec.functions:
        h.update(f"{f.name}|{f.meaning}|{f.unit}|{f.equations}{'|whole' if f.whole else ''}".encode())
        for a in f.args:
            h.update(f"{a.name}|{a.meaning}|{a.unit}".encode())
        h.update(_matrix_digest(sympy.ImmutableMatrix(f.matrix)))
    if spec.dynamics:  # the split of the arguments into t, y and p
        h.update(repr(_dynamics_context(spec.dynamics)).encode())
    return h.hexdigest()


@functools.lru_cache(maxsize=256)  # the same for every target
def _matrix_digest(matrix: sympy.ImmutableMatrix) -> bytes:
    """sha256 over the expression tree, each shared subexpression digested once: ``srepr`` of the whole matrix
    writes a shared subtree out at every use (5 s for the grain's stick force alone)."""
    memo: dict = {}
    return b"".join(_tree_digest(e, memo) for e in (sympy.Integer(matrix.rows), sympy.Integer(matrix.cols), *matrix))


def _tree_digest(expr: sympy.Basic, memo: dict) -> bytes:
    """An atom by its ``srepr`` (name, assumptions, value), a node by its class and its arguments' digests in
    sympy's canonical order (sorted on construction, independent of the hash seed)."""
    key = (type(expr), expr)  # 2 and 2.0 are equal in sympy, and hash alike
    digest = memo.get(key)
    if digest is None:
        h = hashlib.sha256(type(expr).__name__.encode() if expr.args else sympy.srepr(expr).encode())
        for arg in expr.args:
            h.update(_tree_digest(arg, memo))
        digest = memo[key] = h.digest()
    return digest


# Source key of modules written outside `symmech codegen` (no cache entry).
NO_KEY = "0" * 64


def render(spec: ModuleSpec, target: Target = NUMPY, key: str = NO_KEY) -> str:
    """Text of the generated module for ``spec`` in ``target``, header included."""
    if spec.dynamics and not spec.rates and target in (NUMPY, NUMBA):  # their rhs calls rate
        raise ValueError(f"module {spec.name}: dynamics without its rate functions have no Python rhs")
    env = jinja2.Environment(
        loader=jinja2.FunctionLoader(_template_text),
        keep_trailing_newline=True,
        trim_blocks=True,
        lstrip_blocks=True,
        undefined=jinja2.StrictUndefined,
    )
    env.filters["c_comment"] = lambda text: str(text).replace("*/", "* /")
    env.filters["pyrepr"] = repr
    body = env.get_template(target.template).render(
        spec=spec, limit=typeset.MATHML_LIMIT,
        functions=[_context(spec, f, target) for f in spec.functions],
        dynamics=_dynamics_context(spec.dynamics) if spec.dynamics else None,
        floats={f.name: _float_context(f) for f in spec.functions
                if target.float_rates and spec.dynamics and f.name in ("rate", "rate_jacobian", "rate_mass")},
    )
    return integrity.with_header(body, inputs_hash(spec, target), key, target.comment)


def write(spec: ModuleSpec, directory: Path, target: Target = NUMPY, key: str = NO_KEY) -> Path:
    """Write the module atomically into ``directory`` (created if needed); its path."""
    Path(directory).mkdir(parents=True, exist_ok=True)
    path = Path(directory) / target.file(spec.name)
    integrity.write_atomic(path, render(spec, target, key))
    return path


def default_directory() -> Path:
    """The folder behind ``symmech.generated`` (the repository's ``generated/``)."""
    return Path(importlib.import_module("symmech.generated").__path__[0])
