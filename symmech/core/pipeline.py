"""Load, validate, run and write a scene: the one path behind ``symmech run`` and the API.

Order of work (nothing is computed or written before the scene is fully valid):
read TOML -> registry kind -> schema.validate -> kind.prepare -> estimate ->
kind.run -> Result.check_finite -> write into a temporary folder beside ``out``
-> rename into place. The output contract is docs/outputs.md; the summary's
JSON Schema is ``symmech/core/output_schema.json``.

Transactional outputs: ``out`` is replaced as a whole by a complete folder, so a
failed, interrupted or full-disk run leaves the previous results untouched and
no file of an earlier scene survives a successful one. A lock file
``.<out>.lock`` beside ``out`` (an flock, naming the owner's pid) refuses a second
run into the same folder; the kernel releases it when its process dies.
"""
from __future__ import annotations

import csv
import fcntl
import glob
import json
import os
import shutil
import signal
import socket
import sys
import tempfile
import threading
import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from symmech import __version__
from symmech.core import integrity, registry, sample
from symmech.core.context import DEFAULT_MAX_TIME, Context
from symmech.core.results import Result
from symmech.core.scene import SymmechError, check_depth, read_toml
from symmech.core.schema import validate

# Keys of every summary.json; a kind's own summary keys sit beside them.
ENVELOPE = ("symmech_version", "kind", "status", "scene_file", "timing_s", "estimate", "generated_modules",
            "headline", "checks", "warnings", "files", "tables", "scene")
SHOW_ESTIMATE = 2.0  # s; longer runs tell their estimate before starting
COUNT_UNCERTAINTY = 30.0  # a count model's seconds may be this far off on a loaded or another machine


@dataclass
class Scene:
    """A validated scene: its kind, the resolved fields (defaults filled in) and the setup.

    ``timing`` holds the wall time [s] of each stage done so far (validate, estimate, run); ``cost`` the
    estimate the run told (or refused on), once it ran; a sweep of the scene sets it to the sweep's last.
    """

    kind: registry.Kind
    resolved: dict
    setup: Any
    source: str = "<dict>"
    timing: dict = field(default_factory=dict)
    cost: registry.Estimate | None = None

    def estimate(self, max_time: float = DEFAULT_MAX_TIME, sampled: bool = False) -> registry.Estimate | None:
        """The run's cost: the kind's count model (instant, nothing run), scaled by timed samples on this machine
        when ``sampled`` (:func:`symmech.core.sample.timed`, within ``max_time`` [s]; what :meth:`run` tells), or
        None for a kind without one."""
        if self.kind.estimate is None:
            return None
        cost = self.kind.estimate(self.setup)
        return sample.timed(self.kind, self.setup, cost, max_time) if sampled else cost

    def run(self, ctx: Context | None = None) -> Result:
        """Compute (no files written); raises SymmechError on a non-finite result."""
        ctx = ctx or Context(quiet=True)
        self.budget(ctx)
        return self._finish(self.kind.run, ctx, "run")

    def budget(self, ctx: Context) -> registry.Estimate | None:
        """The run's estimate (:meth:`estimate`, sampled unless ``ctx`` is quiet and far from its budget) held to
        ``ctx.max_time`` before any work: a SymmechError when it exceeds it, told in one line when it is long. What
        :meth:`run` and `symmech export` (which runs the scene natively) do first."""
        start = time.perf_counter()
        cost = self.cost = self.estimate(ctx.max_time, ctx.sampled and (not ctx.quiet or self._near_budget(ctx)))
        self.timing["estimate"] = time.perf_counter() - start
        if cost is not None and cost.seconds > ctx.max_time:
            raise SymmechError(f"estimated run time {cost.seconds:.3g} s ({cost.what}) exceeds "
                               f"--max-time {ctx.max_time:g} s; raise --max-time to run it")
        if cost is not None and cost.seconds >= SHOW_ESTIMATE:
            ctx.say(f"estimated run time {cost.seconds:.3g} s ({cost.what})")
        return cost

    def _near_budget(self, ctx: Context) -> bool:
        """Whether the count estimate, off by up to :data:`COUNT_UNCERTAINTY` either way, may reach ``--max-time``:
        a quiet run (the API's, a test's) times samples only then, since nobody is told its estimate."""
        return self.kind.estimate is not None and \
            self.kind.estimate(self.setup).seconds * COUNT_UNCERTAINTY > ctx.max_time

    def precision(self, ctx: Context | None = None) -> Result:
        """The kind's work-precision study (``symmech bench precision``), as a Result."""
        if self.kind.precision is None:
            having = [k.name for k in registry.kinds().values() if k.precision is not None]
            raise SymmechError(f"scene kind '{self.kind.name}' has no precision benchmark "
                               f"(kinds with one: {', '.join(having) or 'none'})")
        return self._finish(self.kind.precision, ctx or Context(quiet=True), "precision")

    def _finish(self, compute, ctx: Context, stage: str) -> Result:
        start = time.perf_counter()
        result = compute(self.setup, ctx)
        result.warnings = list(ctx.warnings) + [w for w in result.warnings if w not in ctx.warnings]
        result.check_finite()
        self.timing[stage] = time.perf_counter() - start
        return result


def load(source, data: dict | None = None) -> Scene:
    """A validated :class:`Scene` from a TOML path or a dict (as TOML would give); ``data``: the table already read
    from the path ``source`` (a sweep reads it first), not read again."""
    start = time.perf_counter()
    if isinstance(source, dict):
        data, name = source, "<dict>"
        check_depth(data)
    else:
        data, name = read_toml(source) if data is None else data, str(source)
    if not isinstance(data, dict):
        raise SymmechError("a scene must be a table of fields")
    kind = registry.get(data.get("kind"))
    resolved = validate(kind.schema, data)
    scene = Scene(kind, resolved, kind.prepare(resolved), name)
    scene.timing["validate"] = time.perf_counter() - start
    return scene


def check_out(out) -> Path:
    """The absolute folder ``out`` resolves to, if a run may replace it; SymmechError otherwise.

    Cheap, so the CLI calls it before any work: ``out`` must not be a file, must not
    contain the current folder, and an existing non-empty folder must hold a previous
    result (a summary.json) — a folder of other files is never replaced.
    """
    target = Path(out).resolve()
    if target.exists() and not target.is_dir():
        raise SymmechError(f"--out {out} is a file, not a folder; choose a folder")
    if target == target.parent or Path.cwd().resolve().is_relative_to(target):
        raise SymmechError(f"--out {out} contains the current folder; choose a folder of its own")
    if target.is_dir() and any(target.iterdir()) and not (target / "summary.json").is_file():
        raise SymmechError(f"--out {out} is a folder of other files (no summary.json of an earlier "
                           "run); choose a new or empty folder")
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise SymmechError(f"--out {out}: cannot create its parent folder ({exc.strerror or exc})") from None
    return target


_HELD: dict[Path, int] = {}  # lock file -> thread holding it (a thread may re-enter its own lock)


@contextmanager
def locked(out: Path):
    """Hold ``.<out>.lock`` beside ``out`` while writing it; refuse if another run holds it.

    The lock is an flock on that file, so the kernel drops it when its process dies:
    a lock file left by a killed run is taken over, whatever pid it names.
    """
    lock = out.parent / f".{out.name}.lock"
    me = threading.get_ident()
    if _HELD.get(lock) == me:
        yield
        return
    fd = _acquire(lock, out)
    _HELD[lock] = me
    try:
        yield
    finally:
        del _HELD[lock]
        lock.unlink(missing_ok=True)
        os.close(fd)


def _acquire(lock: Path, out: Path) -> int:
    """An open descriptor of ``lock`` holding its flock, with our pid and host written in it."""
    while True:
        try:
            fd = os.open(lock, os.O_CREAT | os.O_RDWR, 0o644)
        except OSError as exc:
            raise SymmechError(f"--out {out}: cannot create the lock file {lock} "
                               f"({exc.strerror or exc})") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.read(fd, 200).decode(errors="replace").split()
            os.close(fd)
            who = f"pid {holder[0]} on {holder[1]}" if len(holder) == 2 else "starting now"
            raise SymmechError(f"--out {out} is being written by another symmech run ({who}); "
                               "wait for it or choose another --out") from None
        try:
            current = os.stat(lock).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            current = False
        if current:
            os.ftruncate(fd, 0)
            os.write(fd, f"{os.getpid()} {socket.gethostname()}\n".encode())
            return fd
        os.close(fd)  # its holder removed the file as we opened it: lock the new one


def write(result: Result, out, scene: Scene, plots: bool = True) -> Path:
    """Write ``result`` into a fresh folder beside ``out``, then rename it into place as ``out``.

    On any failure (an exception, Ctrl-C, a full disk) the temporary folder is removed
    and ``out`` keeps its previous content. Returns the absolute output folder.
    """
    start = time.perf_counter()
    target = check_out(out)
    with locked(target):
        _remove_leftovers(target)
        try:
            tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.partial-", dir=target.parent))
        except OSError as exc:
            raise SymmechError(f"--out {out}: cannot write beside it ({exc.strerror or exc})") from None
        try:
            files = write_files(tmp, result, plots)
            timing = {**scene.timing, "write": time.perf_counter() - start}
            summary = _summary(result, scene, files, timing)
            with open(tmp / "summary.json", "w") as fh:
                fh.write(json.dumps(summary, indent=2, allow_nan=False, default=_json_default) + "\n")
            _replace_dir(tmp, target)
        except OSError as exc:
            where = f" ({Path(exc.filename).name})" if exc.filename else ""
            raise SymmechError(f"cannot write the results into {out}: {exc.strerror or exc}{where}; "
                               "previous results left untouched") from None
        finally:
            shutil.rmtree(tmp, ignore_errors=True)  # gone already after a successful rename
    return target


def write_files(folder: Path, result: Result, plots: bool) -> list[str]:
    """Tables, extra files and (if ``plots``) plots of ``result`` into ``folder``; their names."""
    for name, table in result.tables.items():
        _write_csv(folder / f"{name}.csv", table)
    for name, content in result.files.items():
        with open(folder / name, "wb" if isinstance(content, bytes) else "w") as fh:
            fh.write(content)
    files = [f"{n}.csv" for n in result.tables] + list(result.files)
    if plots and result.plots is not None:
        files += [Path(p).name for p in result.plots(folder)]
    return sorted(files)


def _summary(result: Result, scene: Scene, files: list[str], timing: dict) -> dict:
    clash = sorted(set(result.summary) & set(ENVELOPE))
    if clash:
        raise ValueError(f"kind {result.kind!r} puts reserved keys {clash} in its summary")
    return {"symmech_version": __version__, "kind": result.kind,
            "status": "warnings" if result.warnings else "ok", "scene_file": scene.source,
            "timing_s": {**timing, "total": sum(timing.values())},
            "estimate": scene.cost and {"seconds": scene.cost.seconds, "what": scene.cost.what},
            "generated_modules": integrity.used_modules(),
            "headline": [h.to_json() for h in result.headline], "checks": [c.to_json() for c in result.checks],
            **result.summary, "warnings": result.warnings, "files": files, "tables": _describe(result.tables),
            "scene": json.loads(json.dumps(scene.resolved, default=str))}


def _describe(tables: dict) -> dict:
    """What each ``<name>.csv`` holds: rows, numeric columns (name, SI unit, meaning), text columns."""
    return {name: {"rows": len(t.data), "doc": t.doc, "text_columns": list(t.text),
                   "columns": [{"name": c.name, "unit": c.unit, "doc": c.doc} for c in t.columns]}
            for name, t in tables.items()}


def _json_default(value):
    import numpy as np

    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"summary value of type {type(value).__name__} is not JSON")


def _write_csv(path: Path, table) -> None:
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow([c.header for c in table.columns] + list(table.text))
        text_columns = list(table.text.values())
        for i, row in enumerate(table.data):
            w.writerow([repr(float(x)) for x in row] + [col[i] for col in text_columns])


def _replace_dir(new: Path, out: Path) -> None:
    """Move ``new`` to ``out``; an existing ``out`` is moved aside first and removed after.

    Ctrl-C is held back between the two renames, so ``out`` is never left missing.
    """
    blocked = {signal.SIGINT, signal.SIGTERM}
    in_main = threading.current_thread() is threading.main_thread()
    if in_main:
        signal.pthread_sigmask(signal.SIG_BLOCK, blocked)
    try:
        if out.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{out.name}.old-", dir=out.parent))
            os.rename(out, old / "previous")
            os.rename(new, out)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.rename(new, out)
    finally:
        if in_main:
            signal.pthread_sigmask(signal.SIG_UNBLOCK, blocked)


def _remove_leftovers(out: Path) -> None:
    """Temporary folders of ``out`` left by killed runs (we hold the lock: none is live)."""
    for kind in ("partial", "old"):
        for path in glob.glob(os.path.join(glob.escape(str(out.parent)), f".{glob.escape(out.name)}.{kind}-*")):
            shutil.rmtree(path, ignore_errors=True)


def run_to(source, out, ctx: Context, plots: bool = True, study: str = "run") -> tuple[Scene, Result]:
    """Validate ``source``, run it (or its ``"precision"`` study) and write the outputs atomically.

    ``out`` is checked before the scene is read and locked before any computation, so a
    bad ``--out`` or a concurrent run is refused at once.
    """
    target = check_out(out)
    scene = load(source)
    with locked(target):
        result = scene.precision(ctx) if study == "precision" else scene.run(ctx)
        write(result, out, scene, plots=plots)
    for warning in result.warnings:
        print(f"symmech: warning: {warning}", file=sys.stderr)
    return scene, result
