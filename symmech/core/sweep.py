"""What every ``symmech sweep`` shares: the axes of a swept plane, dotted paths into a scene, the cost
refusal, and the dispatch of the point tasks on Dask with a progress bar.

A scene kind offers a sweep by registering ``sweep`` with its :class:`~symmech.core.registry.Kind`
(``sweep(source, out, ctx, **options) -> Result``, ``source`` the scene's path, which its summary names, or its
table); :func:`run` reads the scene, finds its kind and calls it, so no central list names the kinds that sweep. The work runs on Dask: a local process
pool by default, serial with ``scheduler="synchronous"``, or a ``dask.distributed`` scheduler
by address (``--scheduler``); the results do not depend on where they ran.

Before any work a sweep is checked as a whole: its options (:func:`check_options`: ``--out`` as ``symmech run``
checks it, ``--workers``, the ``--scheduler`` reached), then its axes resolved to the entries of the scene they
set and checked as a set (:func:`check_disjoint`), then its cost, from counts and at most one timed point
(:func:`refuse`). The points then run against one deadline (:func:`deadline`, :func:`point_context`).
"""
from __future__ import annotations

import inspect
from contextlib import contextmanager
import os
import time
from pathlib import Path

import numpy as np

from symmech.core import schema as s
from symmech.core import units
from symmech.core.scene import SceneError, SymmechError

CONNECT_TIMEOUT = 5.0  # s: how long --scheduler's address may take to answer (--connect-timeout)
FIELD_PATH = r"[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*"
MAX_VALUES = 200  # values per axis
MAX_WORKERS = 256  # local worker processes (--workers)
LABELLED_CELLS = 10  # a swept plane with at most this many values per axis has every cell's limit written in it
LOCAL = (None, "processes", "synchronous", "threads")  # schedulers on this machine; anything else is an address


def _values(path, value):
    if not isinstance(value, list) or not 1 <= len(value) <= MAX_VALUES:
        raise SceneError(path, f"expected a list of 1 to {MAX_VALUES} numbers, got {value!r}")
    return [s.check_real(f"{path}[{i}]", v, "", None, None, False, False) for i, v in enumerate(value)]


def check_axis(axis: dict, path: str) -> None:
    """Values, or start, stop and num (log spacing with positive ends), never both; no repeats."""
    if axis["values"] is not None:
        for key in ("start", "stop", "num", "log"):
            if axis[key] is not None and axis[key] is not False:
                raise SceneError(f"{path}.{key}", "give either values = [...] or start, stop and num, not both")
        repeated = sorted({v for v in axis["values"] if axis["values"].count(v) > 1})
        if repeated:
            raise SceneError(f"{path}.values", f"the values must differ; {repeated[0]:g} repeats")
        return
    if axis["num"] is None:
        raise SceneError(f"{path}.values", "give values = [...] or start, stop and num")
    for key in ("start", "stop"):
        if axis[key] is None:
            raise SceneError(f"{path}.{key}", "start and stop are required with num")
        if axis["log"] and axis[key] <= 0:
            raise SceneError(f"{path}.{key}", f"log = true spaces values geometrically: {key} must be > 0, "
                                              f"got {axis[key]:g}")
    if axis["num"] > 1 and axis["start"] == axis["stop"]:
        raise SceneError(f"{path}.stop", f"equals start ({axis['start']:g}): the {axis['num']} values would repeat")


def check_plane(sweep: dict, path: str) -> None:
    """The y axis sweeps another field than x."""
    if sweep["y"] is not None and sweep["y"]["field"] == sweep["x"]["field"]:
        raise SceneError(f"{path}.y.field", f"{sweep['x']['field']} is already swept by {path}.x")


def axis_table(field: s.Field, extra: dict | None = None) -> s.Table:
    """The schema of one swept axis: ``field`` (what may be swept, the kind's own), its values, and
    the kind's ``extra`` keys."""
    return s.Table("a swept field", {
        "field": field,
        "values": s.Custom("explicit values, in the field's unit", parse=_values, type_doc="list of numbers",
                           default=None),
        "start": s.Float("first value (with stop, num)", default=None),
        "stop": s.Float("last value (with start, num)", default=None),
        "num": s.Int("number of values from start to stop", lo=1, hi=MAX_VALUES, default=None),
        "log": s.Bool("space start..stop logarithmically", default=False),
        **(extra or {}),
    }, checks=(check_axis,))


def plane_fields(axis: s.Table) -> dict:
    """The ``x`` (required) and ``y`` (optional) axes of a ``[sweep]`` table."""
    return {"x": axis, "y": s.Table(axis.doc, axis.fields, checks=axis.checks, default=None)}


def axis_values(axis: dict) -> np.ndarray:
    """The values of a resolved axis table, in its field's unit."""
    if axis["values"] is not None:
        return np.array(axis["values"])
    space = np.geomspace if axis["log"] else np.linspace
    return space(axis["start"], axis["stop"], axis["num"])


def edges(values: np.ndarray, log: bool) -> np.ndarray:
    """Cell edges (n + 1,) around the swept ``values`` (n,): midway between neighbours (geometrically on a
    log axis), the end cells ending at the first and last values, so no cell leaves the swept range (one
    value: ±50 %)."""
    v = np.log(values) if log else np.asarray(values, float)
    if len(v) == 1:
        out = v[0] + np.array([-0.5, 0.5]) * abs(v[0] or 1)
    else:
        out = np.concatenate([[v[0]], (v[1:] + v[:-1]) / 2, [v[-1]]])
    return np.exp(out) if log else out


def flat_statement(values: np.ndarray, title: str, unit: str, rtol: float, atol: float = 0.0) -> dict | None:
    """``values`` (n,) [SI ``unit``] of the quantity ``title`` stated as one number when their spread is within
    ``rtol`` of their magnitude plus ``atol`` [``unit``] (a chart of them would colour round-off); None when they
    vary, or fewer than two are finite."""
    v = values[np.isfinite(values)]
    if v.size < 2:
        return None
    spread, magnitude = float(v.max() - v.min()), float(np.abs(v).max())
    if spread > rtol * magnitude + atol:
        return None
    mean = float(v.mean())
    shown = f"{mean:.4f}" if unit == "1" else units.format(mean, unit, 5)
    suffix = "" if unit == "1" else f" {unit}"
    absolute = f" + {atol:g}{suffix}" if atol else ""
    return {"value": mean, "unit": unit, "spread": spread, "tolerance_relative": rtol,
            "text": f"{title}: {shown} everywhere, within the tolerance (its spread over the sweep, "
                    f"{spread:.2g}{suffix}, is below {rtol:g} of its size{absolute}); not charted"}


def centres(e: np.ndarray, log: bool) -> np.ndarray:
    """The centres (n,) of the cells with edges ``e`` (n + 1,) (geometric on a log axis)."""
    return np.sqrt(e[:-1] * e[1:]) if log else (e[:-1] + e[1:]) / 2


def cell_labels(ax, xc: np.ndarray, yc: np.ndarray, labels: list[str], shape: tuple[int, int]) -> None:
    """What limits the points of a plane that are not admissible, written over their cells: ``xc`` (nx,), ``yc``
    (ny,) the cells' centres (an end cell ends at its point, which would put the text across the frame),
    ``labels`` (nx ny,) x-major, "" for an admissible point. A plane of at most LABELLED_CELLS values per axis has
    each cell labelled; on a larger one a label would not fit its cell, so each distinct label is written once,
    on the cell of its points nearest their middle."""
    if max(shape) <= LABELLED_CELLS:
        places, size = [(k, text) for k, text in enumerate(labels) if text], 6
    else:
        places, size = [], 8
        for text in dict.fromkeys(text for text in labels if text):
            ks = np.flatnonzero([label == text for label in labels])
            ij = np.column_stack(np.unravel_index(ks, shape))
            places.append((ks[np.argmin(np.linalg.norm(ij - ij.mean(axis=0), axis=1))], text))
    for k, text in places:
        i, j = np.unravel_index(k, shape)
        ax.annotate(text.replace(", ", "\n"), (xc[i], yc[j]), ha="center", va="center", fontsize=size, color="k",
                    bbox={"boxstyle": "round,pad=0.15", "fc": "w", "ec": "none", "alpha": 0.75})


def border(xe: np.ndarray, ye: np.ndarray, ok: np.ndarray) -> list:
    """The cell edges between admissible and other points: segments ((x, y), (x, y)) over the cells with
    edges xe (nx + 1,), ye (ny + 1,) of the points ok (nx, ny)."""
    across_x = [((xe[i + 1], ye[j]), (xe[i + 1], ye[j + 1])) for i, j in zip(*np.nonzero(ok[1:] != ok[:-1]))]
    across_y = [((xe[i], ye[j + 1]), (xe[i + 1], ye[j + 1])) for i, j in zip(*np.nonzero(ok[:, 1:] != ok[:, :-1]))]
    return across_x + across_y


def region_border(ax, xe: np.ndarray, ye: np.ndarray, ok: np.ndarray, label: str) -> None:
    """The :func:`border` of the points ``ok`` (nx, ny) on a plane's chart, white outlined in black (seen on every
    colour of the map) and, by an empty twin, in the legend on the white page; nothing when all or none are ok."""
    from matplotlib.collections import LineCollection
    from matplotlib.patheffects import withStroke

    if ok.any() and not ok.all():
        outlined = {"color": "w", "linewidth": 2.0, "path_effects": [withStroke(linewidth=3.5, foreground="k")]}
        ax.add_collection(LineCollection(border(xe, ye, ok), **outlined))
        ax.plot([], [], **outlined, label=label)


def line(ax, xs: np.ndarray, z: np.ndarray, ok: np.ndarray, labels: list[str], best: int | None, log: bool,
         title: str, allowed: str = "admissible") -> None:
    """The chart of a sweep along one axis on ``ax``: ``z`` (n,) over the swept values ``xs`` (n,), the cells of
    the ``allowed`` points ``ok`` (n,) shaded green, the others labelled with what limits them (``labels``), the
    ``best`` point (its index, or None) starred; the x range stops at the outer cells' edges."""
    ax.plot(xs, z, "o-", color="C0", label=title)
    e = edges(xs, log)
    for n, k in enumerate(np.flatnonzero(ok)):
        ax.axvspan(e[k], e[k + 1], color="C2", alpha=0.2, lw=0, label=None if n else allowed)
    for k in np.flatnonzero(~ok):
        ax.annotate(labels[k], (xs[k], z[k]), textcoords="offset points", xytext=(0, 8), ha="center", fontsize=7,
                    color="#a00")
    if best is not None:
        ax.plot(xs[best], z[best], "*", color="gold", ms=16, mec="k", label=f"best {allowed} point")
    if log:
        ax.set_xscale("log")
    ax.set_xlim(e[0], e[-1])


def get(data: dict, path: str):
    """The value at the dotted ``path`` of ``data``; None when it is missing."""
    node = data
    for key in path.split("."):
        if not isinstance(node, dict) or key not in node:
            return None
        node = node[key]
    return node


def put(data: dict, path: str, value, field: str) -> None:
    """Set the dotted ``path`` of ``data``; a SceneError naming ``field`` when a table on the way is not one."""
    *parents, last = path.split(".")
    node = data
    for depth, key in enumerate(parents):
        node = node.setdefault(key, {})
        if not isinstance(node, dict):
            prefix = ".".join(parents[:depth + 1])
            raise SceneError(field, f"{prefix} is {s.show(node)} in the scene, not a table: give {prefix} whole")
    node[last] = value


def dotted(keys: tuple) -> str:
    """The field name of a key path into a scene, as its errors name it (``elastic.beams[0].ei``)."""
    out = ""
    for key in keys:
        out += f"[{key}]" if isinstance(key, int) else (f".{key}" if out else key)
    return out


def check_disjoint(sets: list[tuple[str, str, list[tuple]]]) -> None:
    """No scene entry set twice: ``sets`` lists (where: the axis or table that sets, e.g. ``sweep.y.field``; its
    field as written; the key paths of the scene entries it sets, e.g. ``("elastic", "beams", 0, "ei")``). Two
    setters clash when a key path of one equals or contains one of the other's, whatever the spelling, alias or
    scale that reached it; a SceneError naming the later one."""
    for k, (where, field, keys) in enumerate(sets):
        for other, other_field, other_keys in sets[:k]:
            for a in keys:
                for b in other_keys:
                    if a[:len(b)] == b or b[:len(a)] == a:
                        same = "" if field == other_field else f" (as {other_field})"
                        raise SceneError(where, f"{field} sets {dotted(a)}, which {other}{same} sets already: "
                                                "each scene entry may be set by one of them only")


def refuse(cost, ctx, advice: str = "give --scheduler ADDRESS of a larger cluster", tell: bool = True) -> None:
    """Refuse a sweep whose estimate (a ``registry.Estimate`` of the work left) and the time already spent
    exceed ``--max-time``; else, with ``tell``, tell it and keep it (from the sweep's start) in ``ctx.estimates``.
    An estimate from counts alone, which a timed one follows within seconds, is told only when a compile comes
    first (the user waits for it): ``tell=cost.once > 0``."""
    total = ctx.elapsed() + cost.seconds
    if total > ctx.max_time:
        raise SymmechError(f"estimated sweep time {total:.3g} s ({cost.what}) exceeds --max-time "
                           f"{ctx.max_time:g} s; raise --max-time, or {advice}")
    if not tell:
        return
    ctx.say(f"estimated sweep time {total:.3g} s ({cost.what})")
    ctx.estimates.append(type(cost)(total, cost.what))


def process_age() -> float:
    """Wall time [s] since this process started (Linux: /proc; elsewhere 0): what a new worker process spends
    importing what this one imported before its estimate."""
    try:
        after_name = Path("/proc/self/stat").read_text().rsplit(")", 1)[1].split()
        started = int(after_name[19]) / os.sysconf("SC_CLK_TCK")  # field 22, starttime, in clock ticks
        return max(float(Path("/proc/uptime").read_text().split()[0]) - started, 0.0)
    except (OSError, ValueError, IndexError):
        return 0.0


def startup_seconds(scheduler: str | None, loaded: float) -> float:
    """What the local worker processes of ``scheduler`` cost before their first task [s], started side by side:
    each imports what this process imported (:func:`process_age`) and loads the engine (``loaded`` [s], as
    measured here); none for a serial run or a cluster's running workers."""
    return process_age() + loaded if scheduler in (None, "processes") else 0.0


def chart_seconds(shape: tuple[int, ...]) -> float:
    """Wall time [s] of one heat map of ``shape`` cells with its colour bar, contours, cell labels and legend, drawn and saved as PNG
    here and now (the faster of two after a first that pays matplotlib's import): a sweep's chart on this machine;
    a line of ``shape`` (n,) as a plane of two rows."""
    import io

    from symmech.core import plotting

    shape = tuple(max(n, 2) for n in (tuple(shape) + (1,))[:2])  # contours need two rows

    def draw():
        fig, grid = plotting.figure(width=7.5, height=5.2)
        z = np.add.outer(np.arange(shape[0]), np.arange(shape[1]) ** 2).astype(float)
        ax = grid[0, 0]
        fig.colorbar(ax.pcolormesh(z.T), ax=ax)
        ax.contour(z.T, colors="k")
        for i, j in np.ndindex(*shape):  # a sweep chart labels its cells
            ax.text(i + 0.5, j + 0.5, "lift-off", ha="center", va="center", fontsize=6)
        ax.plot([0.5], [0.5], "*", label="best admissible point")
        ax.legend(loc="upper left", bbox_to_anchor=(1.25, 1.0))
        fig.savefig(io.BytesIO(), format="png", dpi=plotting.DPI, bbox_inches="tight")  # as plotting.save

    def timed() -> float:
        start = time.perf_counter()
        draw()
        return time.perf_counter() - start

    draw()
    return min(timed(), timed())  # a moment's load on a shared machine timed once made a chart 6x its cost


def deadline(ctx) -> float:
    """The wall-clock time (``time.time()``, s) at which the sweep of ``ctx`` runs out of ``--max-time``: its
    tasks, wherever they run, stop there."""
    return time.time() + ctx.max_time - ctx.elapsed()


def point_context(until: float):
    """A quiet Context for one task of a sweep whose budget ends at ``until`` (:func:`deadline`)."""
    from symmech.core.context import Context

    return Context(quiet=True, max_time=max(until - time.time(), 0.0), sampled=False)


def check_options(out, workers: int | None, scheduler: str | None, connect_timeout: float) -> None:
    """What a sweep's options can be refused for, before the scene is read: ``out`` as ``symmech run`` checks
    it, ``workers`` in [1, MAX_WORKERS], a ``scheduler`` address reached within ``connect_timeout`` seconds."""
    from symmech.core import pipeline

    pipeline.check_out(out)
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or not 1 <= workers <= MAX_WORKERS):
        raise SymmechError(f"--workers {workers} is outside [1, {MAX_WORKERS}]: the number of local worker "
                           "processes")
    if scheduler not in LOCAL:
        with client(scheduler, connect_timeout):
            pass


def workers(count: int | None, scheduler: str | None) -> int:
    """The worker processes a sweep's estimate divides by: 1 when serial, else ``count`` or the CPU count."""
    return 1 if scheduler == "synchronous" else count or os.cpu_count() or 1


def compute(tasks: list, scheduler: str | None = None, processes: int | None = None,
            connect_timeout: float = CONNECT_TIMEOUT, ctx=None, on_workers=None, after: float = 0.0) -> list:
    """The values of the ``dask.delayed`` ``tasks``, in order, with a progress bar on ``ctx`` (a Context).

    ``scheduler``: None for a local process pool of ``processes`` workers, "synchronous" for serial,
    "threads", or the address of a ``dask.distributed`` scheduler (a SymmechError when none answers
    within ``connect_timeout`` seconds); there ``on_workers()`` runs on every worker first.

    The tasks run in :func:`spread` order, so that the first waves are spread over the sweep (a grid's corner may
    cost far more or less than the rest). The second wave of tasks, one per worker (the first paid their start and
    the engine's loading), is the sweep's timed sample on the workers that run it: its wall time per wave left,
    plus ``after`` [s] (what follows the tasks, e.g. the charts), is the estimate told, and refused past ``--max-time`` (:func:`refuse`).
    A local pool and a cluster's client are kept from one wave to the next."""
    from symmech.core.context import Context
    from symmech.core.registry import Estimate

    ctx = ctx or Context(quiet=True)
    wave = workers(processes, scheduler)
    order = spread(len(tasks))
    tasks = [tasks[k] for k in order]
    with ctx.progress(len(tasks), "sweep points", unit="task") as bar, \
            _runner(scheduler, processes, connect_timeout, on_workers, bar, {t.key for t in tasks}) as run:
        values = run(tasks[:wave])  # pays the workers' start and the engine's loading
        if len(tasks) > 2 * wave:
            started = time.perf_counter()
            values += run(tasks[wave:2 * wave])
            took = time.perf_counter() - started
            waves = -(-(len(tasks) - 2 * wave) // wave)
            refuse(Estimate(took * waves + after, f"{len(tasks)} tasks on {wave} worker(s), a wave of {wave} in "
                                                  f"{took:.3g} s (timed), {waves} more waves, then {after:.3g} s "
                                                  "for the charts"), ctx)
        values += run(tasks[len(values):])
    ctx.tick(f"{len(tasks)} sweep tasks")  # tasks past the deadline stopped at once: the sweep is over time
    return [value for _, value in sorted(zip(order, values), key=lambda pair: pair[0])]


def spread(n: int) -> list[int]:
    """0 .. n - 1 in van der Corput order (by their bits reversed: 0, n/2, n/4, 3n/4, ...): any first few of
    them are spread over the whole range."""
    bits = max(n - 1, 1).bit_length()
    return sorted(range(n), key=lambda k: int(f"{k:0{bits}b}"[::-1], 2))


@contextmanager
def _runner(scheduler: str | None, processes: int | None, connect_timeout: float, on_workers, bar, keys: set):
    """A function computing a list of tasks on ``scheduler`` (:func:`compute`), its workers kept from one call
    to the next (a local process pool, or a cluster's client)."""
    import dask

    if scheduler in (None, "processes"):
        from concurrent.futures import ProcessPoolExecutor

        from dask.multiprocessing import get_context, initialize_worker_process

        with ProcessPoolExecutor(processes, mp_context=get_context(), initializer=initialize_worker_process) as pool, \
                _ticks(bar, keys):
            yield lambda part: list(dask.compute(part, scheduler="processes", pool=pool)[0])
    elif scheduler in LOCAL:
        with _ticks(bar, keys):
            yield lambda part: list(dask.compute(part, scheduler=scheduler)[0])
    else:
        from dask.distributed import as_completed

        with client(scheduler, connect_timeout) as c:
            if on_workers is not None:
                c.run(on_workers)

            def run(part):
                futures = c.compute(part)
                for _ in as_completed(futures):
                    bar.update(1)
                return c.gather(futures)

            yield run


def _ticks(bar, keys):
    """A dask local-scheduler callback that advances ``bar`` once per finished task of ``keys``."""
    from dask.callbacks import Callback

    class Ticks(Callback):
        def _posttask(self, key, result, dsk, state, worker_id):
            if key in keys:
                bar.update(1)

    return Ticks()


def client(address: str, timeout: float):
    """A ``dask.distributed`` client of the scheduler at ``address``: the user's address, so a
    scheduler that does not answer within ``timeout`` seconds is a one-line SymmechError."""
    from dask.distributed import Client

    try:
        return Client(address, timeout=timeout)
    except (OSError, ValueError) as exc:  # OSError: nothing answered; ValueError: not an address
        raise SymmechError(f"--scheduler {address}: no dask scheduler answered within {timeout:g} s "
                           f"({' '.join(str(exc).split())}); check that the scheduler is running and reachable "
                           "at that address (tcp://HOST:PORT), or raise --connect-timeout") from None


def run(source, out, ctx, **options):
    """``symmech sweep``: the sweep its scene kind registered, on the scene ``source`` (a TOML path or a
    dict as TOML gives it), written into ``out`` (locked while the sweep runs); a SceneError naming ``kind``
    when the kind has none, a SymmechError naming an option (``--half-width``) its sweep does not take; the
    options :func:`check_options` checks, first."""
    from symmech.core import pipeline, registry
    from symmech.core.scene import read_toml

    check_options(out, options.get("workers"), options.get("scheduler"),
                  options.get("connect_timeout", CONNECT_TIMEOUT))
    raw = source if isinstance(source, dict) else read_toml(source)
    if not isinstance(raw, dict):
        raise SymmechError("a scene must be a table of fields")
    kind = registry.get(raw.get("kind"))
    if kind.sweep is None:
        having = [k.name for k in registry.kinds().values() if k.sweep is not None]
        raise SceneError("kind", f"scene kind '{kind.name}' has no sweep (kinds with one: {', '.join(having)})")
    accepted = inspect.signature(kind.sweep).parameters
    for name in options:
        if name not in accepted:
            raise SymmechError(f"--{name.replace('_', '-')} does not apply to a sweep of a {kind.name} scene")
    with pipeline.locked(pipeline.check_out(out)):
        return kind.sweep(source, out, ctx, **options)  # the path, so the summary names the scene file
