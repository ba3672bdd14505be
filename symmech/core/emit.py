"""Layer 2: print derived matrices as numpy code through jinja2 templates.

``render`` returns the text of one generated module, ``write`` writes it and
``stale`` compares what is on disk with what would be written. The same
common-subexpression split (:func:`cse_chunks`) feeds the generated code and
``symmech latex --cse``, so the two visibly match.

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
import pkgutil
import re
from dataclasses import dataclass
from pathlib import Path

import jinja2
import sympy
from sympy.printing.numpy import NumPyPrinter

from symmech import __version__
from symmech.core.derivation import ModuleSpec, NamedMatrix

TEMPLATE = "module.py.j2"
# Elements per chunk: each chunk is CSE'd on its own and, when a function has
# more than one, emitted as a private helper so no function body grows huge.
CHUNK_ELEMENTS = 64


@dataclass(frozen=True)
class Chunk:
    """CSE of a run of matrix elements: ``replacements`` then ``elements``."""

    replacements: tuple[tuple[sympy.Symbol, sympy.Expr], ...]
    elements: tuple[tuple[tuple[int, ...], sympy.Expr], ...]  # (index, expr)


def cse_chunks(nm: NamedMatrix, chunk_elements: int = CHUNK_ELEMENTS) -> list[Chunk]:
    """Split ``nm`` (arguments under their code names) into chunks and CSE each chunk."""
    matrix = nm.code_matrix()
    rows, cols = matrix.shape
    shape = nm.shape
    clash = {a.name for a in nm.args if re.fullmatch(r"x\d+", a.name)}
    if clash:
        raise ValueError(f"{nm.name}: argument names {sorted(clash)} clash with CSE names x0, x1, ...")
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
    return chunks


class _Printer(NumPyPrinter):
    """NumPy printer that refuses to print anything it cannot translate."""

    def __init__(self):
        super().__init__({"fully_qualified_modules": True, "strict": True})

    def _print_Pow(self, expr, rational=False):
        # x**(-1.0) goes through numpy.power; a division is exact and faster.
        if expr.exp == -1:
            return f"1/{self.parenthesize(expr.base, sympy.printing.precedence.PRECEDENCE['Pow'])}"
        return super()._print_Pow(expr, rational=rational)


def _index_text(index: tuple[int, ...]) -> str:
    return "[...]" if not index else "[..., " + ", ".join(str(i) for i in index) + "]"


def _chunk_lines(chunk: Chunk, printer: _Printer) -> list[str]:
    lines = [f"{s} = {printer.doprint(e)}" for s, e in chunk.replacements]
    lines += [f"out{_index_text(idx)} = {printer.doprint(e)}" for idx, e in chunk.elements]
    return lines


def _function_context(nm: NamedMatrix) -> dict:
    printer = _Printer()
    chunks = [_chunk_lines(c, printer) for c in cse_chunks(nm)]
    return {
        "name": nm.name,
        "meaning": nm.meaning,
        "unit": nm.unit,
        "equations": nm.equations,
        "args": nm.args,
        "arglist": ", ".join(a.name for a in nm.args),
        "chunk_args": ", ".join([a.name for a in nm.args] + ["out"]),
        "shape": nm.shape,
        "shape_text": "(...)" if not nm.shape else "(..., " + ", ".join(map(str, nm.shape)) + ")",
        "chunks": chunks,
    }


def _template_text() -> str:
    return importlib.resources.files("symmech.templates").joinpath(TEMPLATE).read_text()


def inputs_hash(spec: ModuleSpec) -> str:
    """sha256 of everything the module text is made from."""
    h = hashlib.sha256()
    for part in (__version__, _template_text(), spec.name, spec.doc, spec.source):
        h.update(part.encode())
    for f in spec.functions:
        h.update(f"{f.name}|{f.meaning}|{f.unit}|{f.equations}".encode())
        for a in f.args:
            h.update(f"{a.name}|{a.meaning}|{a.unit}".encode())
        h.update(sympy.srepr(f.matrix).encode())
    return h.hexdigest()


def render(spec: ModuleSpec) -> str:
    """Text of the generated module for ``spec``."""
    env = jinja2.Environment(
        loader=jinja2.FunctionLoader(lambda _name: _template_text()),
        keep_trailing_newline=True,
        trim_blocks=True,
        lstrip_blocks=True,
        undefined=jinja2.StrictUndefined,
    )
    return env.get_template(TEMPLATE).render(
        version=__version__,
        hash=inputs_hash(spec),
        spec=spec,
        functions=[_function_context(f) for f in spec.functions],
    )


def write(spec: ModuleSpec, directory: Path) -> Path:
    Path(directory).mkdir(parents=True, exist_ok=True)
    path = Path(directory) / f"{spec.name}.py"
    path.write_text(render(spec))
    return path


def default_directory() -> Path:
    """The folder behind ``symmech.generated`` (the repository's ``generated/``)."""
    return Path(importlib.import_module("symmech.generated").__path__[0])


@functools.cache
def _all_specs() -> tuple[ModuleSpec, ...]:
    specs = []
    for module in paper_modules(("derive", "printed")):
        specs.extend(module.module_specs())
    names = [s.name for s in specs]
    if len(set(names)) != len(names):
        raise ValueError(f"duplicate generated module names: {names}")
    return tuple(sorted(specs, key=lambda s: s.name))


def module_specs() -> list[ModuleSpec]:
    """Every ModuleSpec the paper packages declare, sorted by name.

    A paper package ``symmech.<paper>`` declares specs in its ``derive*`` and
    ``printed*`` modules through a ``module_specs()`` function. Derivations run
    once per process.
    """
    return list(_all_specs())


def paper_modules(prefixes: tuple[str, ...]) -> list:
    """Modules ``symmech.<paper>.<prefix>*`` of every paper package, in name order."""
    import symmech

    found = []
    papers = (m.name for m in pkgutil.iter_modules(symmech.__path__) if m.ispkg and m.name != "core")
    for pkg in sorted(papers):
        package = importlib.import_module(f"symmech.{pkg}")
        for m in sorted(pkgutil.iter_modules(package.__path__), key=lambda m: m.name):
            if m.name.startswith(prefixes):
                found.append(importlib.import_module(f"symmech.{pkg}.{m.name}"))
    return found


def stale(directory: Path, specs: list[ModuleSpec]) -> list[str]:
    """Files in ``directory`` that differ from what ``specs`` render, or should not be there."""
    directory = Path(directory)
    out = []
    expected = {f"{s.name}.py" for s in specs} | {"__init__.py"}
    for spec in specs:
        path = directory / f"{spec.name}.py"
        if not path.exists() or path.read_text() != render(spec):
            out.append(str(path))
    out += sorted(str(p) for p in directory.glob("*.py") if p.name not in expected)
    return out
