"""Ahead-of-time builds of a compiled engine's entries: an extension module that loads without numba.

A warm run on numba's cache imports numba, sets up its CPU target (its typing and lowering registries, which
numba builds before loading *any* cached function) and links the cached code: about as long as importing
numpy, scipy and matplotlib together. An engine also built ahead of time (``numba.pycc`` and the system C
compiler, by ``symmech warm`` or the background builder right after numba's cache, whose compiled functions it
reuses) loads as a plain extension module instead.

The build lives in :func:`folder` beside its record (:mod:`symmech.numerics.artifacts`: the SHA-256 of the built
module, of every file it was compiled from (the loop, its kernels, the generated modules), the checkout that
built it, the Python ABI and numpy's version). A run loads it only when all of these match this installation,
and hashes the module before loading it; else numba's cache serves, after one warning line naming the refused
file when there was one (which is dropped, and rebuilt by the background builder): an edited generated module is
never run from an old build (numba's path then imports it, and the import refuses it), nor is another
checkout's build, and the generated modules of a current build are verified as their import would be and listed
among the run's ``generated_modules``. Written whole: the module and the record each through a temporary file
renamed into place, the record last, under the engine's build lock and a lock of the build's own that a
reader respects (a pair being replaced is neither loaded nor refused). Never required: without a C compiler
nothing is built and nothing is printed; an unwritable folder is one warning line. The built entries hold the
GIL (pycc's wrappers do not release it), so code that runs an engine on threads calls numba's.
"""
from __future__ import annotations

import contextlib
import hashlib
import importlib.machinery
import importlib.util
import os
import sys
import tempfile
import warnings
from pathlib import Path
from types import ModuleType
from collections.abc import Callable

from symmech.core import integrity
from symmech.numerics import artifacts
from symmech.numerics.build import file_lock

SUFFIX = importlib.machinery.EXTENSION_SUFFIXES[0]


def folder(anchor: str) -> Path:
    """Where the build of the engine defined in file ``anchor`` lives: ``__pycache__`` beside ``anchor``, or,
    under ``NUMBA_CACHE_DIR`` when set (as numba's cache) or ``~/.cache/symmech`` when ``__pycache__`` is
    read-only, a folder of this checkout's own (checkouts sharing a cache never load each other's builds)."""
    own = "symmech-aot-" + hashlib.sha256(artifacts.CHECKOUT.encode()).hexdigest()[:16]
    if os.environ.get("NUMBA_CACHE_DIR"):
        return Path(os.environ["NUMBA_CACHE_DIR"]) / own
    beside = Path(anchor).parent / "__pycache__"
    if os.access(beside if beside.exists() else beside.parent, os.W_OK):
        return beside
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "symmech" / own


class Build:
    """The ahead-of-time build ``<name>_aot`` of an engine: ``exports()`` maps each exported name to a numba
    dispatcher and the signature it is compiled for; ``anchors`` are files of the engine's Python side, sources
    of the build that :func:`symmech.numerics.artifacts.sources` cannot reach (constants imported by name); the
    first sets the folder. ``refused`` tells whether :meth:`load` refused a build it found (to be rebuilt)."""

    def __init__(self, name: str, anchors: list[str], exports: Callable[[], dict]):
        self.module_name, self.anchors, self.exports = f"{name}_aot", list(anchors), exports
        self._module, self._checked, self.refused = None, False, False

    def paths(self) -> tuple[Path, Path]:
        """(extension module, record)."""
        where = folder(self.anchors[0])
        return where / f"{self.module_name}{SUFFIX}", where / f"{self.module_name}.json"

    def load(self) -> ModuleType | None:
        """The built module if it is current (:func:`symmech.numerics.artifacts.check`: the module, its sources,
        the checkout and the platform), else None: a build found but refused is dropped after one warning
        line naming it; one being replaced (its lock held) is left alone. Imports no numba; checked once per
        process."""
        if not self._checked:
            self._checked = True
            so, record = self.paths()
            if not (so.exists() or record.exists()):
                return None
            with file_lock(self.lock_file(), wait=False) as free:
                if not free:  # a builder is replacing it: numba's cache serves this run
                    return None
                data, why = artifacts.check(record, [so])
                if why is not None:
                    self.refused = True
                    artifacts.warn(f"{why}; not loaded (numba's cache serves the engine until it is built again)")
                    artifacts.drop([record, so])
                    return None
            integrity.verify_built_from(data["sources"])  # refuses an edited or stale module, as an import
            spec = importlib.util.spec_from_file_location(self.module_name, so)
            try:
                module = importlib.util.module_from_spec(spec)  # dlopen: an extension is created here
                spec.loader.exec_module(module)
            except ImportError as exc:  # intact but unloadable here (a system library changed under it)
                self.refused = True
                artifacts.warn(f"{so} cannot be loaded ({' '.join(str(exc).split())}); numba's cache serves the "
                               "engine until it is built again")
                artifacts.drop([record, so])
                return None
            _scipy_lapack_alone()
            self._module = module
        return self._module

    def lock_file(self) -> Path:
        """Held while the module and its record are replaced (a reader never judges a half-replaced pair)."""
        return self.paths()[0].parent / f"{self.module_name}.lock"

    def build(self, before: dict[str, str]) -> bool:
        """Compile the exports ahead of time; the caller holds the engine's build lock and took the
        :func:`symmech.numerics.artifacts.digests` ``before`` of the files the exports reach and the anchors
        before its process compiled anything. Returns whether it built: False without a working C compiler (the
        runs keep numba's cache), and False after one warning line when the folder cannot be written."""
        self.refused = False  # tried: a failed build is not started again by every run
        exports = self.exports()
        files = artifacts.sources(sys.modules[next(iter(exports.values()))[0].__module__]) + self.anchors
        so, record = self.paths()
        try:
            so.parent.mkdir(parents=True, exist_ok=True)
            workdir = tempfile.TemporaryDirectory(dir=so.parent)
        except OSError as exc:
            artifacts.warn(f"{so.parent} cannot be written ({exc.strerror or exc}); the engine is not built ahead "
                           "of time (numba's cache serves it)")
            return False
        with workdir as tmp:
            try:
                with warnings.catch_warnings(), _quiet():
                    warnings.simplefilter("ignore")  # numba.pycc is pending deprecation: fine for a cache
                    from numba.pycc import CC  # needs setuptools (a dependency) on Python >= 3.12

                    cc = CC(self.module_name)  # raises without a C compiler
                    cc.output_dir, cc.verbose = tmp, False
                    for name, (dispatcher, signature) in exports.items():
                        cc.export(name, signature)(dispatcher.py_func)
                    cc.compile()
            except Exception:  # no C compiler, no pycc, or a toolchain it cannot drive: numba's cache serves
                return False
            with file_lock(self.lock_file(), wait=True):
                artifacts.drop([record])
                os.replace(Path(tmp) / cc.output_file, so)
                artifacts.write_record(record, [so], {f: before[f] for f in files})
        self._module, self._checked = None, False
        return True


def _scipy_lapack_alone() -> None:
    """numba's runtime inside a build finds BLAS and LAPACK by importing ``scipy.linalg.cython_blas`` and
    ``cython_lapack`` on first use; that imports the whole ``scipy.linalg`` package (~0.2 s, half of a warm
    run's imports). Load the two extension modules alone under those names instead (the package, if anyone
    imports it later, finds them in ``sys.modules``); when scipy keeps them elsewhere, its import does it."""
    import scipy

    folder = Path(scipy.__file__).parent / "linalg"
    for name in ("cython_blas", "cython_lapack"):
        full = f"scipy.linalg.{name}"
        path = next((folder / (name + suffix) for suffix in importlib.machinery.EXTENSION_SUFFIXES
                     if (folder / (name + suffix)).is_file()), None)
        if full in sys.modules or path is None:
            continue
        spec = importlib.util.spec_from_file_location(full, path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        sys.modules[full] = module


@contextlib.contextmanager
def _quiet():
    """The compiler's own output (its command lines, warnings) out of the user's terminal."""
    saved = [os.dup(1), os.dup(2)]
    with open(os.devnull, "w") as null:
        sys.stdout.flush(), sys.stderr.flush()
        os.dup2(null.fileno(), 1), os.dup2(null.fileno(), 2)
        try:
            yield
        finally:
            for fd, copy in zip((1, 2), saved):
                os.dup2(copy, fd)
                os.close(copy)
