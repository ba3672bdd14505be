"""Integrity of generated modules, checked without sympy.

Every module ``symmech codegen`` writes starts with :data:`HEADER_LINES` lines::

    # symmech VERSION generated module; inputs sha256 I
    # source key K
    # body sha256 B

(``//`` instead of ``#`` in a C file). ``B`` is the sha256 of the text after the header, so a hand-edited, truncated
or half-written module is detected by reading the file alone; ``VERSION``
detects a module left from another symmech release; ``I`` (everything the text
is made from, needs sympy) and ``K`` (the codegen cache key, see
:mod:`symmech.core.codegen`) are for ``symmech codegen``. Files are written
through :func:`write_atomic`, so a reader never sees a partial module.

Every import of a generated module is checked, by any path (``import
symmech.generated.X``, ``from symmech.generated import X``,
``importlib.import_module``, :func:`symmech.numerics.kernels.load`): the package's
``__init__.py`` (written by codegen) calls :func:`guard`, which checks the index
itself and puts a finder first on ``sys.meta_path`` whose loader hashes each
``symmech.generated.*`` module before executing it. A damaged module raises
:class:`SymmechError` (the CLI: one line naming the module and ``symmech
codegen``, exit 2). Each file version (path, mtime, size) is hashed once per
process.
"""
from __future__ import annotations

import ast
import hashlib
import importlib.abc
import importlib.machinery
import os
import re
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path

from symmech import __version__
from symmech.core.scene import SymmechError

PACKAGE = "symmech.generated"
HEADER_LINES = 3
_HEADER = re.compile(
    r"(?P<comment>#|//) symmech (?P<version>\S+) generated module; inputs sha256 (?P<inputs>[0-9a-f]{64})\n"
    r"(?P=comment) source key (?P<key>[0-9a-f]{64})\n"
    r"(?P=comment) body sha256 (?P<body>[0-9a-f]{64})\n"
)


@dataclass(frozen=True)
class Header:
    version: str
    inputs: str
    key: str
    body: str
    comment: str = "#"  # "//" in a C file

    def text(self) -> str:
        c = self.comment
        return (f"{c} symmech {self.version} generated module; inputs sha256 {self.inputs}\n"
                f"{c} source key {self.key}\n"
                f"{c} body sha256 {self.body}\n")


def sha256(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()


def with_header(body: str, inputs: str, key: str, comment: str = "#") -> str:
    """The full module text: header (recording ``sha256(body)``, lines starting with ``comment``) then ``body``."""
    return Header(__version__, inputs, key, sha256(body), comment).text() + body


def split(text: str) -> tuple[Header | None, str]:
    """(header, body) of a module text; header None when the first lines are not one."""
    match = _HEADER.match(text)
    if not match:
        return None, text
    return Header(**match.groupdict()), text[match.end():]


def _inspect(path: Path) -> tuple[str | None, str | None]:
    """(recorded body sha256, None) of an intact module; (None, why it cannot be used) otherwise."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except FileNotFoundError:
        return None, "missing"
    except (OSError, UnicodeDecodeError) as exc:
        return None, f"unreadable ({exc.__class__.__name__})"
    header, body = split(text)
    if header is None:
        return None, "edited (no symmech header)"
    if sha256(body) != header.body:
        return None, "edited or truncated (body sha256 differs from its header)"
    if header.version != __version__:
        return None, f"stale (written by symmech {header.version}, this is {__version__})"
    return header.body, None


def problem(path: Path) -> str | None:
    """Why the generated module at ``path`` cannot be used, or None when it is intact."""
    return _inspect(path)[1]


def literals(path: Path) -> tuple[Header, dict] | None:
    """(header, {name: value}) of the top-level ``NAME = literal`` assignments of the generated file at ``path``,
    parsed, never executed; None unless it is intact (:func:`problem`)."""
    if problem(path) is not None:
        return None
    header, body = split(Path(path).read_text(encoding="utf-8"))
    return header, {node.targets[0].id: ast.literal_eval(node.value) for node in ast.parse(body).body
                    if isinstance(node, ast.Assign) and isinstance(node.targets[0], ast.Name)}


_verified: dict[tuple[str, int, int], str] = {}  # (path, mtime ns, size) -> body sha256 of an intact file


def verify_file(name: str, path: Path) -> str:
    """Recorded body sha256 of the intact module ``name`` at ``path``; SymmechError otherwise.

    A file is hashed once per process unless it changes (a new mtime or size)."""
    try:
        stat = os.stat(path)
        stamp = (os.fspath(path), stat.st_mtime_ns, stat.st_size)
    except OSError:
        stamp = None
    if stamp in _verified:
        return _verified[stamp]
    body, why = _inspect(path)
    if why is not None:
        raise SymmechError(f"generated module {name} is {why}: regenerate with `symmech codegen`")
    if stamp is not None:
        _verified[stamp] = body
    return body


class _VerifyingLoader(importlib.machinery.SourceFileLoader):
    """Executes a generated module only after :func:`verify_file` accepted its file."""

    def exec_module(self, module):
        verify_file(self.name.removeprefix(PACKAGE + "."), Path(self.path))
        super().exec_module(module)


class _GeneratedFinder(importlib.abc.MetaPathFinder):
    """Finds ``symmech.generated.*`` as the path finder does, with a verifying loader."""

    def find_spec(self, fullname, path, target=None):
        if not fullname.startswith(PACKAGE + "."):
            return None
        spec = importlib.machinery.PathFinder.find_spec(fullname, path)
        if spec is not None and spec.origin is not None:  # any file here must be an intact generated module
            spec.loader = _VerifyingLoader(fullname, spec.origin)
        return spec


def guard(index_file: str) -> None:
    """Called by ``symmech.generated``'s ``__init__``: refuse a damaged index, then verify every module
    of the package as it is imported (the finder is installed once per process)."""
    verify_file("__init__", Path(index_file))
    if not any(isinstance(finder, _GeneratedFinder) for finder in sys.meta_path):
        sys.meta_path.insert(0, _GeneratedFinder())


_built_from: dict[str, str] = {}  # name -> body sha256 of the generated modules in a loaded ahead-of-time build


def verify_built_from(files) -> None:
    """Verify the generated modules among ``files`` (those an ahead-of-time build about to run was compiled
    from, :mod:`symmech.numerics.aot`) as importing them would, and count them as used (:func:`used_modules`)."""
    import symmech.generated as package

    folder = Path(package.__file__).parent
    for path in map(Path, files):
        if path.parent == folder and path.name != "__init__.py":
            _built_from[path.stem] = verify_file(path.stem, path)


def used_modules() -> dict[str, str]:
    """{module name: recorded body sha256} of every generated module imported so far, or compiled into an
    ahead-of-time build that was loaded."""
    used = dict(_built_from)
    for name, module in sorted(sys.modules.items()):
        path = getattr(module, "__file__", None)
        if name.startswith(PACKAGE + ".") and path:
            with open(path, encoding="utf-8") as f:
                header, _ = split("".join(f.readline() for _ in range(HEADER_LINES)))
            used[name.removeprefix(PACKAGE + ".")] = header.body if header else "no header"
    return dict(sorted(used.items()))


def write_atomic(path: Path, text: str) -> None:
    """Write ``text`` to a temporary file beside ``path``, then rename it into place."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        os.fchmod(fd, 0o644)  # mkstemp's 0600 would hide the module from other users
        with os.fdopen(fd, "w", encoding="utf-8", newline="\n") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
