"""``symmech codegen``: regenerate ``generated/`` only where its inputs changed.

A *producer* is a paper module declaring ``ROLE = "derivation"`` or ``"printed"``
(:mod:`symmech.core.discovery`) with ``module_specs()``; every spec becomes four files, ``<name>.py`` (numpy, the
reference), ``<name>_nb.py`` (numba), ``<name>.c`` (C99) and ``<name>_mathml.py`` (what ``symmech report`` typesets),
see :mod:`symmech.core.emit`.

Cache: each module's header records the *source key* of its producer, a
sha256 of the symmech and sympy versions, every template, the source text of
the producer and of the emitter and of every symmech module they import
(transitively, read with ``ast``, nothing imported), and the package data
(bundled scenes, files in ``symmech/``) the derivation read (recorded while it
ran, listed in the package index ``generated/__init__.py``; nothing else it
opens counts, so the output never depends on the environment). When the key and the body hash of every
module of a producer match, the producer is up to date without running sympy;
otherwise it is derived and rendered, and a module counts as stale only when
its text (source-key line aside) differs, so a refactor that does not change
the output costs one slow check, not a failure.
"""
from __future__ import annotations

import ast
import functools
import hashlib
import importlib
import importlib.metadata
import importlib.util
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import symmech
from symmech import __version__
from symmech.core import discovery, integrity
from symmech.core.scene import scenes_folder

INDEX = "__init__.py"
# emit.TARGETS' file names after the spec name, repeated: the fast path needs no sympy
TAILS = (".py", "_nb.py", ".c", "_mathml.py")
# The emitter's own files feed every key (not their imports: the error class's module does not shape output).
EMITTER = ("symmech.core.emit", "symmech.core.integrity", "symmech.core.derivation", "symmech.core.typeset")
_PACKAGE_DIR = Path(symmech.__file__).resolve().parent
ROOT = _PACKAGE_DIR.parent  # the repository in a checkout (where `symmech codegen` writes by default)
_INDEX_DOC = '''"""Numeric modules emitted by `symmech codegen` (never edit by hand).

Installed as ``symmech.generated``: ``<name>.py`` needs numpy only (the
reference), ``<name>_nb.py`` is its numba twin (load it through
``symmech.numerics.kernels``), ``<name>.c`` its C99 twin (``symmech export``
reads it through ``integrity.verify_file``), ``<name>_mathml.py`` what
``symmech report`` typesets of it (no sympy at report time). Regenerate with ``make codegen``; check with
``symmech codegen --check``. This index is written by codegen too; importing
it checks the body hash of every module of the package as it is imported.
"""
from symmech.core import integrity as _integrity

_integrity.guard(__file__)
'''


def producers() -> list[str]:
    """Names of the producer modules (``ROLE = "derivation"`` or ``"printed"``), in name order; nothing imported."""
    return discovery.modules("derivation", "printed")


# -- source key ---------------------------------------------------------------

def _source_file(module: str) -> Path | None:
    """File of a symmech module or package, found without importing it."""
    folder = _PACKAGE_DIR.joinpath(*module.split(".")[1:])
    for path in (folder / "__init__.py", folder.with_suffix(".py")):
        if path.is_file():
            return path
    return None


def _imported(module: str, path: Path) -> set[str]:
    """symmech modules (and their parent packages) that ``path`` imports anywhere in its text."""
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    return {n for n in _symmech_names(package, path.read_text(encoding="utf-8")) if _source_file(n) is not None}


@functools.cache  # by the text itself: every producer's closure parses the shared core modules again otherwise
def _symmech_names(package: str, text: str) -> frozenset[str]:
    """The symmech names (and their parents) that ``text``, a module of ``package``, imports anywhere."""
    names = set()
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = importlib.util.resolve_name("." * node.level + (node.module or ""), package)
            names.add(base)
            names.update(f"{base}.{a.name}" for a in node.names)
    found = set()
    for name in names:
        parts = name.split(".")
        if parts[0] == "symmech":
            found.update(".".join(parts[:i]) for i in range(1, len(parts) + 1))
    return frozenset(found)


def closure(module: str) -> list[str]:
    """``module`` and every symmech module it imports, transitively, sorted."""
    seen, todo = set(), [module]
    while todo:
        name = todo.pop()
        if name not in seen:
            seen.add(name)
            todo.extend(_imported(name, _source_file(name)) - seen)
    return sorted(seen)


def _templates() -> list[Path]:
    import symmech.templates

    return sorted(Path(symmech.templates.__path__[0]).glob("*.j2"))


def source_key(producer: str, data: tuple[str, ...]) -> str:
    """Cache key of ``producer``'s modules (see the module docstring)."""
    h = hashlib.sha256()
    h.update(f"symmech {__version__} sympy {importlib.metadata.version('sympy')}\n".encode())
    for path in _templates():
        h.update(f"template {path.name}\n".encode() + path.read_bytes())
    for name in sorted(set(closure(producer)) | set(EMITTER)):
        h.update(f"module {name}\n".encode() + _source_file(name).read_bytes())
    for rel in data:
        path = _data_path(rel)
        # a folder is keyed by its entries, not by the bytecode Python writes when it imports the scenes package
        content = ("\n".join(sorted(p.name for p in path.iterdir() if p.name != "__pycache__")).encode()
                   if path.is_dir()
                   else path.read_bytes() if path.is_file() else b"<missing>")
        h.update(f"data {rel}\n".encode() + content)
    return h.hexdigest()


# -- recording the data a derivation reads ------------------------------------

_recorded: list | None = None
_hooked = False


def _audit(event: str, args: tuple) -> None:
    if _recorded is not None and event in ("open", "os.scandir") and isinstance(args[0], (str, Path)):
        _recorded.append(args[0])


@functools.cache
def derive(producer: str) -> tuple[tuple, tuple[str, ...]]:
    """(module specs, data files and folders read) of ``producer``: runs sympy, once per process."""
    global _recorded, _hooked
    if not _hooked:
        sys.addaudithook(_audit)  # audit hooks cannot be removed: installed once, gated by _recorded
        _hooked = True
    module = importlib.import_module(producer)
    _recorded = []
    try:
        specs = tuple(module.module_specs())
    finally:
        opened, _recorded = _recorded, None
    data = set()
    for p in opened:
        path = Path(p).resolve()
        if path.suffix not in (".py", ".pyc") and "__pycache__" not in path.parts:
            name = _data_name(path)
            if name is not None:
                data.add(name)
    return specs, tuple(sorted(data))


def module_specs() -> list:
    """Every ModuleSpec the paper packages declare (their ``derive*`` and ``printed*`` modules'
    ``module_specs()``), sorted by name; derivations run once per process (:func:`derive`)."""
    specs = [s for producer in producers() for s in derive(producer)[0]]
    names = [s.name for s in specs]
    if len(set(names)) != len(names):
        raise ValueError(f"duplicate generated module names: {names}")
    return sorted(specs, key=lambda s: s.name)


def named_matrices() -> dict:
    """Every derived function (a FunctionSpec) by its name ``module.function``; derives every producer."""
    return {f"{s.name}.{f.name}": f for s in module_specs() for f in s.functions}


def _data_name(path: Path) -> str | None:
    """Name of a data file or folder a derivation read; None when it is not the package's own data.

    Only the package's data counts: the bundled scenes (``scenes/...``; they install as package
    data in ``symmech/scenes``, so the name is the same in a checkout and an installed package) and
    files inside the ``symmech`` package (``symmech/...``). Whatever else a derivation happens to
    open (a library's metadata in a virtual environment inside the checkout, say) is the
    environment, not an input: generated code never depends on where or with what symmech is installed."""
    scenes = scenes_folder().resolve()
    if path == scenes or scenes in path.parents:
        return Path("scenes", path.relative_to(scenes)).as_posix()
    if _PACKAGE_DIR in path.parents:
        return Path("symmech", path.relative_to(_PACKAGE_DIR)).as_posix()
    return None


def _data_path(name: str) -> Path:
    """The file or folder behind a name of :func:`_data_name`."""
    head, _, rest = name.partition("/")
    return (scenes_folder() if head == "scenes" else _PACKAGE_DIR) / rest


# -- the package index ----------------------------------------------------------

@dataclass
class Index:
    """``generated/__init__.py``: which producer declares each module, the data each producer reads, and each
    generated function's meaning and equations (``symmech latex --list`` reads them without deriving)."""

    # spec name -> producer, producers in name order, each one's modules in the order it declares them (the report's)
    modules: dict[str, str] = field(default_factory=dict)
    inputs: dict[str, tuple[str, ...]] = field(default_factory=dict)  # producer -> data
    # "module.function" -> (meaning, equations), each module's functions in their declared order
    matrices: dict[str, tuple[str, str]] = field(default_factory=dict)

    def text(self) -> str:
        lines = [_INDEX_DOC, "# spec name -> the derivation module that declares it (numpy module, _nb, C and MathML twins);",
                 "# derivation modules by name, each one's modules in the order it declares them (the report's)",
                 "MODULES = {"]
        lines += [f"    {n!r}: {p!r}," for n, p in self.modules.items()]
        lines += ["}", "# derivation module -> data files and folders its derivation reads (scenes/..., symmech/...)",
                  "INPUTS = {"]
        lines += [f"    {p!r}: {tuple(d)!r}," for p, d in sorted(self.inputs.items())]
        lines += ["}", "# module.function -> (meaning, the paper's equations) of every generated function",
                  "MATRICES = {"]
        lines += [f"    {k!r}: {tuple(v)!r}," for n in sorted(self.modules) for k, v in self.listing(n).items()]
        body = "\n".join(lines + ["}", ""])
        return integrity.with_header(body, integrity.sha256(body), "0" * 64)  # no source key: always rebuilt

    @classmethod
    def read(cls, directory: Path) -> Index | None:
        """The index in ``directory``, or None when it is missing, edited or unreadable."""
        read = integrity.literals(Path(directory) / INDEX)
        if read is None:
            return None
        values = read[1]
        return cls(values.get("MODULES", {}), values.get("INPUTS", {}), values.get("MATRICES", {}))

    def names(self, producer: str) -> list[str]:
        """The modules of ``producer`` in the order it declares them."""
        return [n for n, p in self.modules.items() if p == producer]

    def listing(self, name: str) -> dict[str, tuple[str, str]]:
        """The entries of :attr:`matrices` of module ``name``."""
        return {k: v for k, v in self.matrices.items() if k.partition(".")[0] == name}

    def declare(self, producer: str, spec) -> None:
        """Record ``spec`` (a ModuleSpec) as declared by ``producer``, with its functions' listing."""
        if spec.name in self.modules:
            raise ValueError(f"generated module {spec.name} declared by {self.modules[spec.name]} and {producer}")
        self.modules[spec.name] = producer
        self.matrices.update((f"{spec.name}.{f.name}", (f.meaning, f.equations)) for f in spec.functions)


# -- plan, check, write -----------------------------------------------------------

def files(name: str) -> list[str]:
    return [f"{name}{tail}" for tail in TAILS]


def _fresh(directory: Path, index: Index | None, producer: str) -> bool:
    """True when every module of ``producer`` is intact and carries the current source key."""
    if index is None or producer not in index.inputs or not index.names(producer):
        return False
    key = source_key(producer, index.inputs[producer])
    for name in index.names(producer):
        if not index.listing(name):  # an index written before the listing: derive once to fill it
            return False
        for file in files(name):
            path = directory / file
            if integrity.problem(path) is not None:
                return False
            with open(path, encoding="utf-8") as f:
                header, _ = integrity.split("".join(f.readline() for _ in range(integrity.HEADER_LINES)))
            if header.key != key:
                return False
    return True


@dataclass
class Report:
    stale: list[str]  # files that differ from what codegen writes, are missing or are stray
    written: list[str]
    derived: list[str]  # producers that had to run
    outdated_keys: list[str]  # files whose text is current but whose source key is not
    seconds: float


def _without_key(text: str) -> str:
    header, body = integrity.split(text)
    return body if header is None else f"{header.inputs}\n{header.body}\n{body}"


def run(directory: Path, check: bool, progress=None) -> Report:
    """Compare ``directory`` with the derivations; unless ``check``, write what differs. ``progress`` (a tqdm bar, or
    None) is advanced by one per producer module, fresh or derived (a full derivation takes minutes)."""
    start = time.perf_counter()
    directory = Path(directory)
    old = Index.read(directory)
    new = Index()
    stale, written, derived, outdated = [], [], [], []
    for producer in producers():
        if progress is not None:
            progress.set_postfix_str(producer.rpartition(".")[2], refresh=False)
            progress.update(1)
        if _fresh(directory, old, producer):
            new.inputs[producer] = old.inputs[producer]
            for n in old.names(producer):
                new.modules[n] = producer
                new.matrices.update(old.listing(n))
            continue
        from symmech.core import emit  # imports sympy: only when something must be derived

        derived.append(producer)
        specs, data = derive(producer)
        new.inputs[producer] = data
        key = source_key(producer, data)
        for spec in specs:
            new.declare(producer, spec)
            for target in emit.TARGETS:
                path = directory / target.file(spec.name)
                text = emit.render(spec, target, key)
                current = path.read_text(encoding="utf-8") if path.is_file() else None
                if current == text:
                    continue
                if current is not None and _without_key(current) == _without_key(text):
                    outdated.append(str(path))
                else:
                    stale.append(str(path))
                if not check:
                    directory.mkdir(parents=True, exist_ok=True)
                    integrity.write_atomic(path, text)
                    written.append(str(path))
    expected = {INDEX} | {f for n in new.modules for f in files(n)}
    index_path = directory / INDEX
    if not index_path.is_file() or index_path.read_text(encoding="utf-8") != new.text():
        stale.append(str(index_path))
        if not check:
            directory.mkdir(parents=True, exist_ok=True)
            integrity.write_atomic(index_path, new.text())
            written.append(str(index_path))
    for path in sorted(p for tail in (".py", ".c") for p in directory.glob(f"*{tail}") if p.name not in expected):
        stale.append(str(path))
        if not check and integrity.split(path.read_text(encoding="utf-8", errors="replace"))[0] is not None:
            path.unlink()  # a module codegen wrote whose spec is gone
            written.append(f"{path} (removed)")
    return Report(stale, written, derived, outdated, time.perf_counter() - start)
