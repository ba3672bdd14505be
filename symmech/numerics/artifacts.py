"""Built artifacts, recorded when built and verified before they are loaded.

An artifact is a file built on this machine that a run loads as machine code: numba's cache entries of a
compiled engine (:mod:`symmech.numerics.build`), an engine built ahead of time (:mod:`symmech.numerics.aot`), the
fast-call extension (:mod:`symmech.numerics.fastcall`). Its *record* (JSON, written atomically after the files it
records) holds the SHA-256 of every built file, of every source file it was built from, the checkout that
built it (the folder of the ``symmech`` package) and the platform (Python ABI and version, numpy's version).
:func:`check` accepts an artifact only when all of these match this installation; a loader then refuses a
damaged, foreign or stale artifact, prints ONE warning line naming the file (:func:`warn`), drops it
(:func:`drop`) and rebuilds it or goes around it. The built file is hashed before it is dlopen'ed or
unpickled: a truncated extension module would otherwise be mapped past its end (SIGBUS).

numba loads its own cache files; :func:`guard_numba_cache` turns a damaged index or data file (truncated,
random bytes: the unpickling fails) into one warning, the file dropped and a recompile, and a cache file numba
cannot write into one warning instead of an error.
"""
from __future__ import annotations

import hashlib
import importlib.machinery
import json
import sys
from pathlib import Path
from types import ModuleType

from symmech.core.integrity import write_atomic

CHECKOUT = str(Path(__file__).resolve().parents[1])  # the symmech package folder that builds and loads
_warned: set[str] = set()  # warning lines printed by this process


def digest(path) -> str:
    """SHA-256 (hex) of the file ``path``."""
    sha = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            sha.update(block)
    return sha.hexdigest()


def platform() -> dict:
    """What a built file depends on besides its sources: the Python ABI and version, numpy's version."""
    import numpy

    return {"abi": importlib.machinery.EXTENSION_SUFFIXES[0], "python": sys.version, "numpy": numpy.__version__}


def reached(module: ModuleType) -> list[ModuleType]:
    """``module`` and every symmech module its globals reach (the functions, constants and generated kernels
    compiled into a build), by name."""
    seen, todo = {}, [module]
    while todo:
        m = todo.pop()
        if m is None or m.__name__ in seen or not getattr(m, "__file__", None) or (
                m is not module and not m.__name__.startswith("symmech")):
            continue
        seen[m.__name__] = m
        todo += [v if isinstance(v, ModuleType) else sys.modules.get(getattr(v, "__module__", None) or "")
                 for v in vars(m).values()]
    return [seen[name] for name in sorted(seen)]


def sources(module: ModuleType) -> list[str]:
    """The files of :func:`reached` modules, sorted: what a build of ``module``'s functions is made from."""
    return sorted(m.__file__ for m in reached(module))


def digests(files) -> dict[str, str]:
    """The SHA-256 of each of ``files`` by path: what a build is made from, taken before it compiles."""
    return {f: digest(f) for f in sorted(set(files))}


def write_record(record: Path, built: list[Path], built_from: dict[str, str]) -> None:
    """Record the files ``built`` (all in the folder of ``record``) as built by this checkout from the sources
    whose :func:`digests` ``built_from`` were taken before the build began (a source edited while it compiled is
    then stale at the next check, not recorded as built); OSError when the folder cannot be written."""
    text = json.dumps({"checkout": CHECKOUT, "platform": platform(),
                       "built": {Path(p).name: digest(p) for p in built},
                       "sources": dict(sorted(built_from.items()))}, indent=1, sort_keys=True)
    write_atomic(record, text + "\n")


def check(record: Path, built: list[Path]) -> tuple[dict | None, str | None]:
    """(the record, None) when the files ``built`` and every other file the record lists are current for this
    installation; (None, why not, naming the file) otherwise, "missing" when none of them exists."""
    record = Path(record)
    try:
        data = json.loads(record.read_text(encoding="utf-8"))
        files, recorded = {Path(p).name for p in built}, dict(data["built"])
        checkout, built_from = data["checkout"], dict(data["sources"])
    except (FileNotFoundError, NotADirectoryError):
        present = [p for p in built if Path(p).exists()]
        return None, f"{present[0]} is not recorded (no {record.name})" if present else "missing"
    except (OSError, UnicodeDecodeError, ValueError, KeyError, TypeError) as exc:
        return None, f"{record} is unreadable ({exc.__class__.__name__})"
    if checkout != CHECKOUT:
        return None, f"{record} was built by another checkout ({checkout})"
    if data.get("platform") != platform():
        return None, f"{record} was built for another Python or numpy"
    for name in sorted(files | set(recorded)):
        path = record.parent / name
        if name not in recorded:
            return None, f"{path} is not in its record {record.name}"
        try:
            if digest(path) != recorded[name]:
                return None, f"{path} is damaged or replaced (its SHA-256 differs from {record.name})"
        except OSError:
            return None, f"{path} is missing or unreadable"
    for source, sha in built_from.items():
        try:
            current = digest(source) == sha
        except OSError:
            current = False
        if not current:
            return None, f"{record} is stale (built from another version of {source})"
    return data, None


def warn(message: str) -> None:
    """One warning line on stderr, once per process: what was refused or could not be written, naming the file,
    and what the run does instead."""
    line = f"symmech: warning: {message}"
    if line not in _warned:
        _warned.add(line)
        print(line, file=sys.stderr, flush=True)


def drop(paths) -> bool:
    """Remove the files ``paths`` (missing ones are fine); returns whether none is left."""
    gone = True
    for path in paths:
        try:
            Path(path).unlink(missing_ok=True)
        except OSError:
            gone = False
    return gone


_numba_guarded = False


def guard_numba_cache() -> None:
    """Have numba treat a cache file it cannot unpickle as absent (one warning naming it, the file dropped, the
    function recompiled) and a cache file it cannot write as a warning (the function stays compiled in
    memory). Patches numba's cache file class once per process (private API, numba 0.5x-0.6x)."""
    global _numba_guarded
    if _numba_guarded:
        return
    from numba.core.caching import IndexDataCacheFile

    load_index, load_data, save = IndexDataCacheFile._load_index, IndexDataCacheFile._load_data, \
        IndexDataCacheFile.save

    def guarded_load_index(self):
        try:
            return load_index(self)
        except Exception as exc:  # unpickling garbage raises anything (UnpicklingError, EOFError, ValueError ...)
            _damaged(Path(self._index_path), exc)
            return {}

    def guarded_load_data(self, name):
        try:
            return load_data(self, name)
        except OSError:
            raise
        except Exception as exc:
            _damaged(Path(self._data_path(name)), exc)
            raise OSError(f"damaged numba cache file {name}") from exc  # numba's load(): no entry, compile

    def guarded_save(self, key, data):
        try:
            save(self, key, data)
        except OSError as exc:
            warn(f"numba's cache folder {self._cache_path} cannot be written ({exc.strerror or exc}); "
                 "compiled in memory for this run")

    IndexDataCacheFile._load_index = guarded_load_index
    IndexDataCacheFile._load_data = guarded_load_data
    IndexDataCacheFile.save = guarded_save
    _numba_guarded = True


def _damaged(path: Path, exc: Exception) -> None:
    drop([path])
    warn(f"numba cache file {path} is damaged ({exc.__class__.__name__}); dropped and recompiled")
