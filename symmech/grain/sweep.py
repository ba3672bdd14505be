"""Populations of grains and sweeps over the vibration: the seed cleaner designer's charts.

A grain scene may carry ``[sweep]`` (one or two swept fields of the scene) and
``[[population]]`` (one or two grain populations: a count, a seed, fields set for
the population and fields varied per grain). ``symmech sweep SCENE --out DIR``
runs every grain of every population at every sweep point and reports, per point,
the mean transport velocity and its spread, the fraction of grains that hop
(more than half of the time in flight) and the throw number Γ = A ω² / g; with two
populations also the separation chart: the difference of their mean velocities and
the overlap of their velocity distributions, with the best operating point marked.

Every grain is an ordinary grain scene (the base scene with the population's and the
sweep point's fields changed), validated before any simulation. The work runs on
Dask: a local process pool by default, a ``dask.distributed`` scheduler by address
with ``--scheduler``; results do not depend on where they ran (tested bit for bit).
"""
from __future__ import annotations

import copy
import math
from dataclasses import dataclass

import numpy as np

from symmech.core import plotting
from symmech.core import schema as s
from symmech.core.results import Column, Result, Table
from symmech.core.scene import SceneError

CONNECT_TIMEOUT = 5.0  # s: how long --scheduler's address may take to answer (--connect-timeout)
FIELD_PATH = r"[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*"
# the fields a sweep may vary, with their units
SWEPT = {"vibration.amplitude": "m", "vibration.frequency": "Hz", "vibration.angle_deg": "deg",
         "vibration.phase_deg": "deg", "surface.alpha_deg": "deg", "surface.beta_deg": "deg",
         "sliding.friction": "1", "impact.e_n": "1", "impact.e_t": "1", "impact.mu": "1", "impact.e": "1",
         "impact.lambda": "1"}


def _values(path, value):
    if not isinstance(value, list) or not 1 <= len(value) <= 200:
        raise SceneError(path, f"expected a list of 1 to 200 numbers, got {value!r}")
    return [s.check_real(f"{path}[{i}]", v, "", None, None, False, False) for i, v in enumerate(value)]


def _check_axis(axis: dict, path: str) -> None:
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


def _check_plane(sweep: dict, path: str) -> None:
    if sweep["y"] is not None and sweep["y"]["field"] == sweep["x"]["field"]:
        raise SceneError(f"{path}.y.field", f"{sweep['x']['field']} is already swept by {path}.x")


# Top-level keys of the grain scene that a population may not set or vary: they are not grain fields.
NOT_GRAIN_FIELDS = ("kind", "sweep", "population")


def _check_population(pop: dict, path: str) -> None:
    for table in ("set", "vary"):
        for key in pop[table]:
            if key.split(".")[0] in NOT_GRAIN_FIELDS:
                raise SceneError(f"{path}.{table}.{key}", f"{key} is not a grain field a population can change")
            if pop["random_orientation"] and key == "body.orientation":
                raise SceneError(f"{path}.{table}.{key}", "random_orientation = true draws body.orientation; "
                                                          "drop one of the two")


def _check_names(pops: list, path: str) -> None:
    for k, pop in enumerate(pops):
        first = next(i for i, other in enumerate(pops) if other["name"] == pop["name"])
        if first != k:
            raise SceneError(f"{path}[{k}].name", f"{pop['name']!r} is already the name of {path}[{first}] "
                                                  "(each population writes sweep_<name>.csv)")


AXIS = s.Table("a swept field", {
    "field": s.Choice("the grain-scene field swept (dotted path)", choices=tuple(SWEPT)),
    "values": s.Custom("explicit values, in the field's unit", parse=_values, type_doc="list of numbers",
                       default=None),
    "start": s.Float("first value (with stop, num)", default=None),
    "stop": s.Float("last value (with start, num)", default=None),
    "num": s.Int("number of values from start to stop", lo=1, hi=200, default=None),
    "log": s.Bool("space start..stop logarithmically", default=False),
}, checks=(_check_axis,))

SWEEP = s.Table("the swept plane (used by `symmech sweep`; `symmech run` ignores it)", {
    "x": AXIS,
    "y": s.Table(AXIS.doc, AXIS.fields, checks=AXIS.checks, default=None),
    "duration": s.Float("simulated time per grain (default: the scene's duration)", unit="s", lo=0.0,
                        lo_open=True, hi=1e4, default=None),
}, default=None, checks=(_check_plane,))

POPULATION = s.Table("a population of grains", {
    "name": s.Str("name used in the outputs", pattern=r"[A-Za-z][A-Za-z0-9_-]{0,31}"),
    "count": s.Int("number of grains", lo=1, hi=100_000),
    "seed": s.Int("random seed of the population", lo=0, hi=2**63 - 1, default=0),
    "set": s.Mapping("grain-scene fields (dotted paths) with this population's values, e.g. "
                     "\"body.semi_axes\" = [...]", value=s.Custom("any TOML value", parse=lambda p, v: v),
                     key_pattern=FIELD_PATH, default={}),
    "vary": s.Mapping("grain-scene number or vector fields (dotted paths) varied per grain: each component "
                      "times a uniform factor in [1 - spread, 1 + spread]",
                      value=s.Float("relative spread", lo=0.0, hi=0.9), key_pattern=FIELD_PATH, default={}),
    "random_orientation": s.Bool("draw body.orientation uniformly over all rotations", default=False),
}, checks=(_check_population,))
POPULATIONS = s.TableList("one or two grain populations with distinct names (default: one grain, the scene "
                          "itself)", item=POPULATION, min_items=1, max_items=2, default=None,
                          checks=(_check_names,))
MAX_GRAIN_RUNS = 100_000  # grains times points: every grain scene is built and validated before any run


def axis_values(axis: dict) -> np.ndarray:
    if axis["values"] is not None:
        return np.array(axis["values"])
    space = np.geomspace if axis["log"] else np.linspace
    return space(axis["start"], axis["stop"], axis["num"])


def _get(data: dict, path: str):
    node = data
    for key in path.split("."):
        if not isinstance(node, dict) or key not in node:
            return None
        node = node[key]
    return node


def _set(data: dict, path: str, value, field: str) -> None:
    """Set the dotted ``path`` of ``data``; a SceneError naming ``field`` when a table on the way is not one."""
    *parents, last = path.split(".")
    node = data
    for depth, key in enumerate(parents):
        node = node.setdefault(key, {})
        if not isinstance(node, dict):
            prefix = ".".join(parents[:depth + 1])
            raise SceneError(field, f"{prefix} is {s._show(node)} in the scene, not a table: give {prefix} whole")
    node[last] = value


def _is_vector(value) -> bool:
    """A number, or a non-empty list of numbers (what ``vary`` scales)."""
    items = value if isinstance(value, list) and value else [value]
    return all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in items)


def _scaled(value, factor):
    if isinstance(value, list):
        return [v * f for v, f in zip(value, factor)]
    return value * factor[0]


def members(base: dict, population: dict, field: str = "population[0]") -> list[dict]:
    """The raw grain scenes of one population (before the sweep point's fields are set); ``field`` names
    the population in errors."""
    rng = np.random.default_rng(population["seed"])
    out = []
    for _ in range(population["count"]):
        data = copy.deepcopy(base)
        for path, value in population["set"].items():
            _set(data, path, copy.deepcopy(value), f"{field}.set.{path}")
        for path, spread in population["vary"].items():
            value = _get(data, path)
            if not _is_vector(value):
                found = "missing" if value is None else s._show(value)
                raise SceneError(f"{field}.vary.{path}", f"varies a number or vector of numbers of the scene; "
                                                         f"{path} is {found}")
            size = len(value) if isinstance(value, list) else 1
            _set(data, path, _scaled(value, rng.uniform(1 - spread, 1 + spread, size).tolist()), f"{field}.vary.{path}")
        if population["random_orientation"]:
            _set(data, "body.orientation", [float(rng.uniform(0, 2 * math.pi)),
                                            float(math.acos(rng.uniform(-1, 1))),
                                            float(rng.uniform(0, 2 * math.pi))], field)
        out.append(data)
    return out


@dataclass
class Plan:
    """Every grain scene of the sweep, validated: ``grains[p][i][j]`` is a list of raw scenes of
    population p at sweep point (i, j)."""

    x: dict
    y: dict | None
    names: list[str]
    grains: list
    gamma: np.ndarray  # (nx, ny) throw number at each point
    populations: list  # the resolved [[population]] tables (errors name their fields)


def plan(raw: dict, resolved: dict) -> Plan:
    """Expand the sweep into grain scenes (the first grain of each point validated; :func:`validate`
    checks them all)."""
    from symmech.core import pipeline

    sweep = resolved["sweep"]
    if sweep is None:
        raise SceneError("sweep", "the scene has no [sweep] table (see docs/scenes-grain.md)")
    base = {k: v for k, v in copy.deepcopy(raw).items() if k not in ("sweep", "population")}
    if sweep["duration"] is not None:
        base["duration"] = sweep["duration"]
    pops = resolved["population"] or [{"name": "grain", "count": 1, "seed": 0, "set": {}, "vary": {},
                                       "random_orientation": False}]
    xs = axis_values(sweep["x"])
    ys = axis_values(sweep["y"]) if sweep["y"] else np.array([np.nan])
    _check_plan(sweep, pops, len(xs) * len(ys))
    gamma = np.empty((len(xs), len(ys)))
    grains = []
    for k, pop in enumerate(pops):
        crowd = members(base, pop, f"population[{k}]")
        grid = []
        for i, xv in enumerate(xs):
            row = []
            for j, yv in enumerate(ys):
                point = []
                for member in crowd:
                    data = copy.deepcopy(member)
                    _set(data, sweep["x"]["field"], float(xv), "sweep.x.field")
                    if sweep["y"]:
                        _set(data, sweep["y"]["field"], float(yv), "sweep.y.field")
                    point.append(data)
                gamma[i, j] = throw_number(load_grain(point[0], sweep, pop, k).resolved)
                row.append(point)
            grid.append(row)
        grains.append(grid)
    return Plan(sweep["x"], sweep["y"], [p["name"] for p in pops], grains, gamma, pops)


def _check_plan(sweep: dict, pops: list, points: int) -> None:
    """No population sets or varies a swept field (the sweep would overwrite it), and the plan is bounded."""
    for k, pop in enumerate(pops):
        for table in ("set", "vary"):
            for axis in ("x", "y"):
                if sweep[axis] is not None and sweep[axis]["field"] in pop[table]:
                    raise SceneError(f"population[{k}].{table}.{sweep[axis]['field']}",
                                     f"the field is swept by sweep.{axis}, which sets it at every point")
    runs = sum(pop["count"] for pop in pops) * points
    if runs > MAX_GRAIN_RUNS:
        raise SceneError("population", f"{runs} grain runs (grains of every population times {points} sweep "
                                       f"points) exceed {MAX_GRAIN_RUNS}; use fewer grains or points")


def load_grain(data: dict, sweep: dict, pop: dict, k: int):
    """``pipeline.load`` of one grain scene of the sweep; its SceneError renamed to the sweep or population
    field the bad value came from."""
    from symmech.core import pipeline

    try:
        return pipeline.load(data)
    except SceneError as exc:
        sources = {sweep[a]["field"]: f"sweep.{a}" for a in ("x", "y") if sweep[a] is not None}
        sources |= {path: f"population[{k}].{table}.{exc.field}" for table in ("set", "vary") for path in pop[table]}
        if pop["random_orientation"]:
            sources["body.orientation"] = f"population[{k}].random_orientation"
        for path, field in sources.items():
            if exc.field == path or exc.field.startswith((f"{path}.", f"{path}[")):
                raise SceneError(field, f"{exc.field}: {str(exc).partition(': ')[2]}") from None
        raise


def validate(p: Plan) -> None:
    """Validate every grain scene of the plan: a bad grain is named before any simulation."""
    for k, grid in enumerate(p.grains):
        for row in grid:
            for point in row:
                for data in point:
                    load_grain(data, {"x": p.x, "y": p.y}, p.populations[k], k)


def throw_number(resolved: dict) -> float:
    """Γ = A ω² / g of a resolved grain scene (dimensionless)."""
    vib = resolved["vibration"]
    g = resolved["surface"]["g"]
    return vib["amplitude"] * (2 * math.pi * vib["frequency"]) ** 2 / g


def simulate_point(scenes: list[dict]) -> tuple[np.ndarray, list, list]:
    """Per grain: mean transport velocity (X, Y) [m/s] and the fraction of time in flight, shape (n, 3);
    a grain whose simulation stops with an error (e.g. a stagnation guard) gets a row of NaN and its
    message in the list of (grain index, message) — it is reported, never averaged in. A grain whose run
    warned (e.g. a rocking contact the model does not follow) is averaged in and listed as (grain index,
    warnings)."""
    from symmech.core import pipeline
    from symmech.core.scene import SymmechError

    out, failed, warned = [], [], []
    for k, data in enumerate(scenes):
        try:
            res = pipeline.load(data).run()
        except SymmechError as exc:
            out.append((np.nan, np.nan, np.nan))
            failed.append((k, str(exc)))
            continue
        vx, vy = res.summary["mean_transport_velocity_m_s"]
        out.append((vx, vy, res.summary["time_fraction"].get("flight", 0.0)))
        if res.warnings:
            warned.append((k, list(res.warnings)))
    return np.array(out), failed, warned


def estimate(p: Plan, workers: int):
    """Cost of the whole sweep: the grain kind's estimate of each population's first grain, times the
    grains and points, shared by ``workers`` (a ``registry.Estimate``)."""
    from symmech.core import pipeline, registry

    first = [_as_dispatched(grid[0][0][0]).estimate() for grid in p.grains]
    once = max(e.once for e in first)
    seconds = once + sum((e.seconds - e.once) * len(grid[0][0]) * len(grid) * len(grid[0])
                         for e, grid in zip(first, p.grains))
    grains = sum(len(grid[0][0]) * len(grid) * len(grid[0]) for grid in p.grains)
    return registry.Estimate(seconds / max(workers, 1), f"{grains} grain runs on {workers} worker(s)")


def _as_dispatched(data: dict):
    """A grain scene (pipeline.Scene) as the workers run it: engine `auto` runs compiled, since :func:`compute`
    builds the compiled engine before dispatch."""
    from dataclasses import replace

    from symmech.core import pipeline

    scene = pipeline.load(data)
    num = scene.setup.numerics
    if num.engine == "auto":
        scene.setup = replace(scene.setup, numerics=replace(num, engine="compiled"))
    return scene


def _compiled_needed(p: Plan) -> bool:
    """Whether a population's grains run the compiled engine (accurate mode, engine not `python`)."""
    return any(n.mode == "accurate" and n.engine == "compiled"
               for n in (_as_dispatched(grid[0][0][0]).setup.numerics for grid in p.grains))


def _warm_worker() -> None:
    """On a dask worker: the compiled engine built once per machine (the others wait on the build lock)."""
    from symmech.grain import compiled

    compiled.warm()


def run(source, out, ctx, scheduler: str | None = None, workers: int | None = None,
        connect_timeout: float = CONNECT_TIMEOUT) -> Result:
    """``symmech sweep``: validate the scene and every grain of the sweep, estimate, compute, write."""
    import os

    from symmech.core import pipeline
    from symmech.core.scene import SymmechError, read_toml

    raw = source if isinstance(source, dict) else read_toml(source)
    scene = pipeline.load(raw)
    p = plan(raw, scene.resolved)
    workers = workers or os.cpu_count() or 1
    cost = estimate(p, 1 if scheduler == "synchronous" else workers)
    if cost.seconds > ctx.max_time:
        raise SymmechError(f"estimated sweep time {cost.seconds:.3g} s ({cost.what}) exceeds --max-time "
                           f"{ctx.max_time:g} s; raise --max-time, or give --scheduler ADDRESS of a larger cluster")
    validate(p)
    res = result(p, *compute(p, scheduler, workers, connect_timeout, say=ctx.say))
    pipeline.write(res, out, scene)
    return res


def compute(p: Plan, scheduler: str | None = None, processes: int | None = None,
            connect_timeout: float = CONNECT_TIMEOUT, say=None) -> tuple[list, list, list]:
    """Per population, an array (nx, ny, grains, 3) of :func:`simulate_point` results, on Dask, the failed
    grains as (population, i, j, grain, message) and the grains that warned as (population, i, j, grain,
    warnings).

    ``scheduler``: None for a local process pool, "synchronous" for serial, or the
    address of a ``dask.distributed`` scheduler (a SymmechError when none answers within
    ``connect_timeout`` seconds). Grains on the compiled engine find it built: this process
    builds it first (in the foreground, ``say(text)`` tells it), and so does each machine of a
    ``dask.distributed`` cluster, once per machine (the build lock of :func:`symmech.grain.compiled.warm`).
    """
    import dask

    warm = _compiled_needed(p)
    if warm:
        from symmech.grain import compiled

        compiled.warm(say=say)

    tasks = [[[dask.delayed(simulate_point)(point, dask_key_name=f"grain-{k}-{i}-{j}")
               for j, point in enumerate(row)] for i, row in enumerate(grid)] for k, grid in enumerate(p.grains)]
    if scheduler in (None, "processes", "synchronous", "threads"):
        kwargs = {"num_workers": processes} if processes and scheduler in (None, "processes") else {}
        (values,) = dask.compute(tasks, scheduler=scheduler or "processes", **kwargs)
    else:
        with _client(scheduler, connect_timeout) as client:
            if warm:
                client.run(_warm_worker)
            values = client.gather(client.compute(tasks))
    arrays = [np.array([[point[0] for point in row] for row in grid]) for grid in values]
    failed, warned = ([(p.names[k], i, j, g, msg) for k, grid in enumerate(values) for i, row in enumerate(grid)
                       for j, point in enumerate(row) for g, msg in point[which]] for which in (1, 2))
    return arrays, failed, warned


def _client(address: str, timeout: float):
    """A ``dask.distributed`` client of the scheduler at ``address``: the user's address, so a
    scheduler that does not answer within ``timeout`` seconds is a one-line SymmechError."""
    from dask.distributed import Client

    from symmech.core.scene import SymmechError

    try:
        return Client(address, timeout=timeout)
    except (OSError, ValueError) as exc:  # OSError: nothing answered; ValueError: not an address
        raise SymmechError(f"--scheduler {address}: no dask scheduler answered within {timeout:g} s "
                           f"({' '.join(str(exc).split())}); check that the scheduler is running and reachable "
                           "at that address (tcp://HOST:PORT), or raise --connect-timeout") from None


def statistics(grid: np.ndarray) -> dict:
    """Mean and spread of the transport velocity and the hopping fraction over the grains."""
    ok = np.isfinite(grid[..., 2])
    with np.errstate(invalid="ignore", divide="ignore"):  # a point where every grain failed stays NaN
        hop = np.where(ok, grid[..., 2] > 0.5, 0).sum(-1) / ok.sum(-1)
        return {"mean_vx": np.nanmean(grid[..., 0], -1), "std_vx": np.nanstd(grid[..., 0], -1),
                "mean_vy": np.nanmean(grid[..., 1], -1), "std_vy": np.nanstd(grid[..., 1], -1),
                "hop_fraction": hop, "flight_fraction": np.nanmean(grid[..., 2], -1),
                "failed": (~ok).sum(-1).astype(float)}


def overlap(a: np.ndarray, b: np.ndarray) -> float:
    """Overlap coefficient of two samples of X velocities (area under the lower of their normal fits)."""
    a, b = a[np.isfinite(a)], b[np.isfinite(b)]
    mu1, mu2 = a.mean(), b.mean()
    s1, s2 = max(a.std(), 1e-12), max(b.std(), 1e-12)
    lo, hi = min(mu1 - 6 * s1, mu2 - 6 * s2), max(mu1 + 6 * s1, mu2 + 6 * s2)
    v = np.linspace(lo, hi, 4001)
    pdf = lambda mu, sd: np.exp(-0.5 * ((v - mu) / sd) ** 2) / (sd * math.sqrt(2 * math.pi))  # noqa: E731
    return float(np.trapezoid(np.minimum(pdf(mu1, s1), pdf(mu2, s2)), v))


def _column(axis: dict, name: str) -> Column:
    return Column(name, SWEPT[axis["field"]], f"swept field {axis['field']}")


def _point_columns(p: Plan) -> tuple[list[Column], np.ndarray]:
    xs = axis_values(p.x)
    ys = axis_values(p.y) if p.y else np.array([np.nan])
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    cols = [_column(p.x, "x")] + ([_column(p.y, "y")] if p.y else []) + [Column("gamma", "1", "throw number A w^2/g")]
    data = [X.ravel()] + ([Y.ravel()] if p.y else []) + [p.gamma.ravel()]
    return cols, np.column_stack(data)


STAT_COLUMNS = [Column("mean_vx", "m/s", "mean transport velocity along X"),
                Column("std_vx", "m/s", "spread (standard deviation) of the X velocity over the grains"),
                Column("mean_vy", "m/s", "mean transport velocity along Y"),
                Column("std_vy", "m/s", "spread of the Y velocity"),
                Column("hop_fraction", "1", "fraction of grains more than half of the time in flight"),
                Column("flight_fraction", "1", "mean fraction of time in flight"),
                Column("failed", "1", "grains whose simulation stopped with an error (left out of the statistics)")]


def result(p: Plan, values: list, failed: list = (), warned: list = ()) -> Result:
    """Tables per population (and the separation chart for two), summary and heat-map plots;
    ``failed`` and ``warned`` grains (from :func:`compute`) are listed in the summary and warned about."""
    cols, base = _point_columns(p)
    tables, summary = {}, {"populations": p.names, "points": int(base.shape[0]),
                           "grains_per_point": [int(v.shape[2]) for v in values],
                           "swept": [p.x["field"]] + ([p.y["field"]] if p.y else []),
                           "failed_grains": [{"population": n, "point": [i, j], "grain": g, "error": m}
                                             for n, i, j, g, m in failed],
                           "warned_grains": [{"population": n, "point": [i, j], "grain": g, "warnings": m}
                                             for n, i, j, g, m in warned]}
    stats = [statistics(v) for v in values]
    for name, st in zip(p.names, stats):
        data = np.column_stack([base] + [st[c.name].ravel() for c in STAT_COLUMNS])
        tables[f"sweep_{name}"] = Table(cols + STAT_COLUMNS, data, f"population {name} over the swept plane")
    if len(values) == 2:
        a, b = values
        ovl = np.array([[overlap(a[i, j, :, 0], b[i, j, :, 0]) for j in range(a.shape[1])]
                        for i in range(a.shape[0])])
        dvx = stats[0]["mean_vx"] - stats[1]["mean_vx"]
        dvy = stats[0]["mean_vy"] - stats[1]["mean_vy"]
        sep = [Column("delta_vx", "m/s", f"mean X velocity of {p.names[0]} minus {p.names[1]}"),
               Column("delta_vy", "m/s", "the same along Y"),
               Column("overlap", "1", "overlap coefficient of the two X-velocity distributions")]
        tables["separation"] = Table(cols + sep, np.column_stack([base, dvx.ravel(), dvy.ravel(), ovl.ravel()]),
                                     "separation chart of the two populations")
        # best operating point: the least overlap, ties broken by the larger velocity difference
        best = int(np.lexsort((-np.abs(dvx.ravel()), ovl.ravel()))[0])
        summary["best_operating_point"] = {c.name: float(base[best, k]) for k, c in enumerate(cols)} | {
            "delta_vx_m_s": float(dvx.ravel()[best]), "overlap": float(ovl.ravel()[best])}
    best_ij = None if len(values) != 2 else divmod(best, values[0].shape[1])
    warnings = [f"{len(failed)} grain simulation(s) stopped with an error and are left out of the statistics "
                f"(summary.json: failed_grains); first: {failed[0][4]}"] if failed else []
    warnings += [f"{len(warned)} grain simulation(s) ran with warnings (summary.json: warned_grains); first: "
                 f"{warned[0][4][0]}"] if warned else []
    return Result("grain_sweep", summary, tables, plots=lambda folder: _plots(p, stats, tables, best_ij, folder),
                  warnings=warnings)


def _plots(p: Plan, stats, tables, best, folder) -> list:
    if not p.y:
        return []
    xs, ys = axis_values(p.x), axis_values(p.y)
    x_label = (p.x["field"], SWEPT[p.x["field"]])
    y_label = (p.y["field"], SWEPT[p.y["field"]])
    charts = [(f"{name}_mean_vx", st["mean_vx"], f"{name}: mean transport velocity", "m/s")
              for name, st in zip(p.names, stats)]
    charts += [(f"{name}_hop_fraction", st["hop_fraction"], f"{name}: fraction of grains hopping", "1")
               for name, st in zip(p.names, stats)]
    if "separation" in tables:
        sep = tables["separation"]
        charts.append(("separation_overlap", sep.column("overlap").reshape(len(xs), len(ys)),
                       "overlap of the X-velocity distributions (1 = inseparable)", "1"))
    written = []
    for name, z, title, unit in charts:
        fig, axes = plotting.figure(width=6.4, height=4.8)
        ax = axes[0, 0]
        mesh = ax.pcolormesh(xs, ys, z.T, shading="nearest", cmap="viridis")
        fig.colorbar(mesh, ax=ax, label=plotting.label(title, unit))
        if len(xs) > 1 and len(ys) > 1:
            lines = ax.contour(xs, ys, p.gamma.T, colors="w", linewidths=0.8)
            ax.clabel(lines, fmt="Γ=%.2g", fontsize=7)
        if name == "separation_overlap" and best is not None:
            ax.plot(xs[best[0]], ys[best[1]], "r*", ms=14, label="best operating point")
            ax.legend(fontsize=8, loc="upper right")
        plotting.set_labels(ax, x_label, y_label)
        ax.set_title(title, fontsize=9)
        written += plotting.save(fig, folder, name)
    return written
