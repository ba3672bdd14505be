"""A numba twin's ``rhs(t, y, p)`` / ``jac(t, y, p)`` called from Python at C speed.

A call into any numba dispatcher costs ~1.45x JiTCODE's whole C call (numba types its arguments), so a
dispatcher cannot return a new array within 2x of it. The C extension ``_fastcall.c`` (beside this file)
defines ``Kernel``: a callable holding a C function pointer, here the twin's ``rhs_cfunc()`` /
``jac_cfunc()`` (numba ``cfunc`` of the generated ``rhs_into`` / ``jac_into``: the physics stays the
generated kernels), that checks float64 C vectors of the right lengths in C, allocates the output and
calls the kernel; anything else, and a kernel that raised (a singular mass matrix), goes to the twin's
general Python path, so results and errors stay those of the generated ``rhs``/``jac``.

The extension is compiled once with the system C compiler (sysconfig's ``CC``, or ``$CC``) into numba's
cache folder of the twin (:func:`symmech.numerics.build.cache_dir`), named by the hash of the source, the
Python ABI and numpy's version, under a file lock, through a temporary file renamed into place, and recorded
beside it (:mod:`symmech.numerics.artifacts`: its SHA-256, the source's, the checkout, the platform). It is loaded
only when that record matches (hashed before it is loaded: a truncated extension would be mapped past its end);
a damaged, foreign or unrecorded file is dropped and rebuilt after one warning line naming it. It is never
required: without a compiler, or when the build fails, ``rhs``/``jac`` stay the twin's numba path (one debug
log record). Nothing is compiled at import: :func:`install` (``kernels.load``) gives the twin
a C ``Kernel`` whose first call compiles (or loads from numba's cache) the cfunc, or, while the extension
is not built, a stand-in whose first call builds it and rebinds the module's name.
"""
from __future__ import annotations

import functools
import hashlib
import importlib.util
import logging
import os
import shlex
import subprocess
import sys
import sysconfig
import tempfile
from pathlib import Path
from types import FunctionType, ModuleType

from symmech.numerics import artifacts
from symmech.numerics.build import cache_dir, file_lock

SOURCE = Path(__file__).with_name("_fastcall.c")
_log = logging.getLogger(__name__)


@functools.cache  # per folder: the source is read and hashed once per process
def artifact(folder: Path) -> Path:
    """The extension's file in ``folder`` for this C source, Python ABI and numpy version."""
    import numpy

    key = hashlib.sha256(SOURCE.read_bytes())
    for part in (sys.implementation.cache_tag, sysconfig.get_config_var("EXT_SUFFIX"), numpy.__version__):
        key.update(b"\0" + part.encode())
    return Path(folder) / f"_fastcall-{key.hexdigest()[:16]}{sysconfig.get_config_var('EXT_SUFFIX')}"


def _compile(target: Path) -> None:
    """Compile :data:`SOURCE` into ``target`` (temporary file renamed into place); OSError or
    subprocess.SubprocessError when there is no compiler or it fails (its output kept in the error)."""
    import numpy

    cc = shlex.split(os.environ.get("CC") or sysconfig.get_config_var("CC") or "")
    ldshared = shlex.split(sysconfig.get_config_var("LDSHARED") or "")  # the platform's flags for an extension
    if not cc or not ldshared:
        raise OSError("no C compiler in sysconfig (CC, LDSHARED)")
    paths = sysconfig.get_paths()
    includes = [f"-I{d}" for d in dict.fromkeys((paths["include"], paths["platinclude"], numpy.get_include()))]
    fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".tmp")
    os.close(fd)
    try:
        subprocess.run([*cc, *ldshared[1:], "-O2", "-fPIC", *includes, str(SOURCE), "-o", tmp], check=True,
                       capture_output=True, timeout=300)
        os.chmod(tmp, 0o755)
        os.replace(tmp, target)
    finally:
        Path(tmp).unlink(missing_ok=True)


def _load(path: Path) -> ModuleType:
    """The extension module in the file ``path`` (ImportError when it does not load)."""
    spec = importlib.util.spec_from_file_location("_fastcall", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@functools.cache
def extension(folder: Path) -> ModuleType | None:
    """The extension module built in ``folder`` (compiled first when missing or refused, once per folder: a
    process waiting for the lock then loads what the holder built); None when it cannot be built or loaded."""
    path = artifact(folder)
    record = path.with_name(path.name.removesuffix(sysconfig.get_config_var("EXT_SUFFIX")) + ".json")
    try:
        with file_lock(Path(folder) / "symmech-fastcall-build.lock", wait=True):
            _, why = artifacts.check(record, [path])
            if why not in (None, "missing"):
                artifacts.warn(f"{why}; dropped and built again")
                artifacts.drop([record, path])
            if why is not None:
                source = artifacts.digests([str(SOURCE)])
                _compile(path)
                artifacts.write_record(record, [path], source)
        return _load(path)
    except (OSError, subprocess.SubprocessError, ImportError) as exc:
        _log.debug("no C path for generated rhs/jac, the numba path serves them: %s %s", exc,
                   (getattr(exc, "stderr", None) or b"")[-2000:])
        return None


def kernel(ext: ModuleType, module: ModuleType, name: str, generated: FunctionType) -> object:
    """The twin ``module``'s ``name`` ("rhs" or "jac") as a C ``Kernel`` of the extension ``ext``, named and
    documented as ``generated`` (the generated function); its first call compiles (or loads from numba's
    cache) the twin's ``<name>_cfunc`` and binds it, with the twin's ``_<name>_general`` as the general
    path."""
    def first_call(*args, **kwargs):
        cfunc = getattr(module, f"{name}_cfunc")()
        fast.bind(cfunc.address, cfunc, getattr(module, f"_{name}_general"))
        return fast(*args, **kwargs)

    fast = ext.Kernel(len(module.STATE), len(module.PARAMS), 1 if name == "rhs" else 2, first_call)
    return functools.update_wrapper(fast, generated)


class _FirstCall:
    """A twin's ``rhs``/``jac`` while the extension is not built: its first call builds it, rebinds the
    module's name to a C ``Kernel`` (or back to the generated function without a compiler) and calls it; a
    reference taken before forwards to that, at Python speed."""

    def __init__(self, module: ModuleType, name: str):
        self.module, self.name, self.generated, self.bound = module, name, getattr(module, name), None
        functools.update_wrapper(self, self.generated)

    def __call__(self, t, y, p):
        if self.bound is None:
            ext = extension(cache_dir(self.module.rhs_into))
            self.bound = kernel(ext, self.module, self.name, self.generated) if ext else self.generated
            setattr(self.module, self.name, self.bound)
        return self.bound(t, y, p)


def install(module: ModuleType) -> None:
    """Give the numba twin ``module`` the C path for its ``rhs`` and ``jac`` (a module without dynamics is
    left as it is): a C ``Kernel`` at once when the extension is built (loading it takes ~1 ms; the cfunc
    waits for the first call), else a stand-in whose first call builds it. Nothing is compiled here."""
    names = [name for name in ("rhs", "jac")
             if hasattr(module, f"{name}_cfunc") and isinstance(getattr(module, name), FunctionType)]
    if not names:
        return
    folder = cache_dir(module.rhs_into)
    ext = extension(folder) if artifact(folder).exists() else None
    for name in names:
        generated = getattr(module, name)
        setattr(module, name, kernel(ext, module, name, generated) if ext else _FirstCall(module, name))
