"""Building a compiled engine into numba's cache once per machine.

An engine is a few cached numba entries (``cache=True`` dispatchers) and the argument types a run calls
them with. :meth:`Engine.warm` compiles them unless numba's cache holds them, under a machine-wide build
lock (``fcntl.flock`` on a file beside the cache: the OS releases it when its holder dies, so a killed
builder never blocks later builds); a process that waits for the lock then loads what the holder built.
numba writes each cache file whole (a temporary file renamed), so an interrupted build leaves none half
written. What a build leaves is recorded (:mod:`symmech.numerics.artifacts`: each entry's index and data files, the
sources they were compiled from, the checkout) in ``symmech-<name>-numba.json`` beside them; :meth:`Engine.cold`
accepts the cache only when that record matches, else warns once naming the refused file and the engine is
cold (the next build drops the refused files and compiles); the entries' module is imported only once the
record matches. :meth:`Engine.warm_in_background` starts a detached builder (``symmech warm --engine NAME
--background``, its own session: Ctrl-C or SIGTERM of the caller does not reach it), unless
``SYMMECH_BACKGROUND_BUILD=0`` (CI jobs and containers that warm their cache on purpose, or never want a
process that outlives the run).
"""
from __future__ import annotations

import fcntl
import hashlib
import importlib.util
import os
import subprocess
import sys
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path
from collections.abc import Callable

from symmech.numerics import artifacts


COLD = "auto: the compiled engine is not built yet"  # how every cold-cache reason starts


def background_builds() -> bool:
    """Whether a run may start a detached builder (not with ``SYMMECH_BACKGROUND_BUILD=0``)."""
    return os.environ.get("SYMMECH_BACKGROUND_BUILD") != "0"


def ahead_of_time_builds() -> bool:
    """Whether engines are built and run ahead of time where they can (not with ``SYMMECH_AHEAD_OF_TIME=0``)."""
    return os.environ.get("SYMMECH_AHEAD_OF_TIME") != "0"


def numba_folder(source: str) -> Path:
    """The folder where numba caches the ``cache=True`` functions of the file ``source``: ``NUMBA_CACHE_DIR``
    when set, else ``__pycache__`` beside it, or numba's user-wide cache folder when that folder is read-only
    (numba's own choice, private API)."""
    from numba.core.caching import CodeLibraryCacheImpl

    for locator_class in CodeLibraryCacheImpl._locator_classes:
        locator = locator_class.from_function(numba_folder, source)  # any function: its line names no folder
        if locator is not None:
            return Path(locator.get_cache_path())
    raise OSError(f"numba has no cache folder for {source}")


def cache_dir(dispatcher) -> Path:
    """The folder where numba caches the ``cache=True`` dispatcher (:func:`numba_folder` of its file)."""
    return Path(dispatcher._cache._cache_path)  # numba's cache locator (private API)


def _mtime(path: Path) -> int | None:
    """The modification time [ns] of ``path``, None when it is missing."""
    try:
        return path.stat().st_mtime_ns
    except OSError:
        return None


@contextmanager
def file_lock(path: Path, wait: bool):
    """An exclusive ``flock`` on the file ``path`` (created with its folder); yields whether this process
    holds it (always, with ``wait``)."""
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fh = open(path, "a")
    except OSError:  # a read-only cache folder: the lock lives in the user's temporary folder
        path = Path(tempfile.gettempdir()) / f"{path.name}-{hashlib.sha256(bytes(path)).hexdigest()[:16]}"
        fh = open(path, "a")
    with fh:
        try:
            fcntl.flock(fh, fcntl.LOCK_EX if wait else fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            yield False
            return
        yield True  # closing the file releases the lock


class Engine:
    """The compiled engine ``name`` (``symmech warm --engine NAME``): ``entries()`` maps each cached entry
    (a numba dispatcher of the module named ``module``) to the argument types a run calls it with;
    ``seconds`` [s] is the cold compile a run announces (wall time, idle machine)."""

    def __init__(self, name: str, module: str, entries: Callable[[], dict], seconds: float, ahead=None):
        self.name, self.module, self.entries, self.seconds = name, module, entries, seconds
        self.ahead = ahead  # its symmech.numerics.aot.Build, if it has one
        self.lock_name = f"symmech-{name}-build.lock"
        self._accepted = None  # the modification time [ns] of the record cold() accepted
        self._holding = False  # whether this process holds the build lock
        self.started_builder = False  # whether this process started a builder (it may not hold the lock yet)
        self._builder_process = None  # that builder's process

    def ahead_of_time(self):
        """The engine's ahead-of-time build (:mod:`symmech.numerics.aot`) when it is current, else None (always
        with ``SYMMECH_AHEAD_OF_TIME=0``: runs then take numba's cache, and nothing is built); loads no numba.
        A build refused as damaged, foreign or stale is rebuilt by a background builder."""
        if self.ahead is None or not ahead_of_time_builds():
            return None
        module = self.ahead.load()
        if module is None and self.ahead.refused:
            self.start_builder()
        return module

    def needs_compile(self) -> bool:
        """Whether running the engine now compiles: no current ahead-of-time build and a cold cache."""
        return self.ahead_of_time() is None and self.cold()

    def cold_reason(self) -> str:
        """Why ``auto`` runs the reference engine on a cold cache (the estimate and summary.json)."""
        then = ("building it in the background for the next run" if background_builds()
                else "no background build (SYMMECH_BACKGROUND_BUILD=0)")
        return f"{COLD}; {then} (`symmech warm --engine {self.name}` builds it now)"

    def cold(self) -> bool:
        """Whether the next run compiles: no current record of the entries' cache files (a record that does not
        match: one warning line naming the refused file), or an entry has no machine code cached for its
        source. Imports the entries' module (and so numba and its generated twins) only once the record matches."""
        record = self.record_file()
        if self._builder_at_work():
            return True
        stamp = _mtime(record)
        if stamp is None:  # never built and recorded (numba's files, if any, are replaced by the next build)
            return True
        if self._accepted != stamp:
            _, why = artifacts.check(record, [])
            if why is not None:
                artifacts.warn(f"{why}; numba's cache of the {self.name} engine is not used (the next build "
                               "compiles it again)")
                return True
            self._accepted = stamp
        artifacts.guard_numba_cache()  # before numba reads an index: an unreadable one is a warning, not an error
        return any(not entry._cache._cache_file._load_index() for entry in self.entries())  # numba's (private)

    def _builder_at_work(self) -> bool:
        """Whether another process holds the build lock (its cache files are not all written and recorded)."""
        if self._holding:
            return False
        with self.build_lock(wait=False) as free:
            return not free

    def record_file(self) -> Path:
        """The record of what the last build left in numba's cache (:mod:`symmech.numerics.artifacts`)."""
        return self.cache_dir() / f"symmech-{self.name}-numba.json"

    def sources(self) -> list[str]:
        """The files the entries are compiled from, and the ahead-of-time build's anchors when it has one (its
        exports are the entries' module's); imports that module, compiles nothing."""
        files = {f for entry in self.entries() for f in artifacts.sources(sys.modules[entry.__module__])}
        return sorted(files | set(self.ahead.anchors if self.ahead is not None else ()))

    def _record(self, before: dict[str, str]) -> None:
        """Record the entries' cache files as built from the sources whose digests ``before`` the build took
        (a cache folder that cannot be written: one warning, and the next run compiles again)."""
        built = []
        for entry in self.entries():
            cache = entry._cache._cache_file  # numba's (private API)
            built += [Path(cache._index_path), *(Path(cache._data_path(n)) for n in cache._load_index().values())]
        try:
            artifacts.write_record(self.record_file(), built, before)
        except OSError as exc:
            artifacts.warn(f"{self.record_file()} cannot be written ({exc.strerror or exc}); the next run "
                           "compiles the engine again")

    def cache_dir(self) -> Path:
        """Where numba caches the entries: its cache folder for the file of :attr:`module`."""
        return numba_folder(importlib.util.find_spec(self.module).origin)

    def build_lock(self, wait: bool):
        """The machine-wide build lock; yields whether this process holds it (always, with ``wait``)."""
        return file_lock(self.cache_dir() / self.lock_name, wait)

    def warm(self, wait: bool = True, say=None, ahead: bool = False) -> bool:
        """Compile the entries into numba's cache unless they are there, and with ``ahead`` the ahead-of-time
        build too (``symmech warm`` and the background builder; it reuses numba's compiled functions); returns
        whether numba's cache holds them. Without ``wait``, return False at once when another process holds
        the build lock. ``say(text)`` tells what it does. The sources' digests are taken first, before the wait
        for the lock and the compile: a source edited meanwhile leaves a stale record, never a false one."""
        before = artifacts.digests(self.sources())
        with self.build_lock(wait) as mine:
            if not mine:
                return False
            self._holding = True
            try:
                self._build(say, ahead, before)
            finally:
                self._holding = False
        return True

    def _build(self, say, ahead: bool, before: dict[str, str]) -> None:
        """:meth:`warm`'s work under the build lock, from the sources whose digests are ``before``."""
        if self.cold():
            if say:
                say(f"compiling the {self.name} engine once, ~{self.seconds:.0f} s (cache: {self.cache_dir()})")
            self._drop_cache()
            for entry, signature in self.entries().items():
                entry.compile(signature)
                if not Path(entry._cache._cache_file._index_path).exists():  # compiled before in this process
                    entry._cache.save_overload(signature, entry.overloads[tuple(signature)])  # numba's (private)
            self._record(before)
        if ahead and self.ahead is not None and ahead_of_time_builds() and self.ahead.load() is None:
            if say:
                say(f"building the {self.name} engine ahead of time too (runs then load it without numba)")
            self.ahead.build(before)

    def _drop_cache(self) -> None:
        """Remove the cache files of every numba function the entries are built from, and their record, before a
        build: numba would load what it finds, and it checks a cached callee against its own file only."""
        for module in {m for entry in self.entries() for m in artifacts.reached(sys.modules[entry.__module__])}:
            for value in vars(module).values():
                cache = getattr(getattr(value, "_cache", None), "_cache_file", None)  # numba's (private API)
                if cache is not None:
                    index = Path(cache._index_path)
                    artifacts.drop([index, *index.parent.glob(cache._data_name_pattern.replace("{number:d}", "*"))])
        artifacts.drop([self.record_file()])
        self._accepted = None

    def warm_in_background(self) -> bool:
        """Start a detached builder unless the engine is cached or a builder holds the lock; returns at once,
        whether one was started. ``SYMMECH_BACKGROUND_BUILD=0`` starts none (the run still answers, on the
        engine that needs no compile)."""
        return background_builds() and self.cold() and self.start_builder()

    def start_builder(self) -> bool:
        """Start a detached builder (``symmech warm --engine NAME --background``) unless background builds are
        off, a builder holds the lock or this process started one already (a run's timed samples and the run
        each ask; the builder may not hold the lock yet); returns whether one was started."""
        if not background_builds() or self.started_builder:
            return False
        with self.build_lock(wait=False) as free:
            if not free:
                return False
        self._builder_process = subprocess.Popen(
            [sys.executable, "-m", "symmech", "warm", "--engine", self.name, "--background"],
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
        self.started_builder = True
        return True

    def wait_warm(self, timeout: float) -> bool:
        """Start the builder if none runs and wait up to ``timeout`` [s] for the engine to be cached; returns
        whether it is. Cold with no builder at work (background builds off, or a build ended with the cache
        cold: another process compiled into it meanwhile, and its record refuses it), it builds here instead of
        waiting for nothing."""
        deadline = time.monotonic() + timeout
        self.warm_in_background()
        while self.cold():
            if not (self._builder_at_work() or self._builder_starting()):
                self.warm()
                return not self.cold()
            if time.monotonic() >= deadline:
                return False
            time.sleep(0.5)
        return True

    def _builder_starting(self) -> bool:
        """Whether the builder this process started still runs (before it takes the lock, or after)."""
        return self._builder_process is not None and self._builder_process.poll() is None
