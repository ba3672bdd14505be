"""Populations of grains and sweeps over the vibration: the seed cleaner designer's charts.

A grain scene may carry ``[sweep]`` (one or two swept fields of the scene) and
``[[population]]`` (one or two grain populations: a count, a seed, fields set for
the population and fields varied per grain). ``symmech sweep SCENE --out DIR``
runs every grain of every population at every sweep point and reports, per point,
the mean transport velocity and its spread, the fraction of grains that hop
(more than half of the time in flight) and the throw number Γ = A ω² / g; with two
populations also the separation chart: the difference of their mean velocities and
the overlap of their velocity distributions, with the best operating point marked. Every
statistic carries its 95 % confidence interval; the points not significantly worse than the
best are marked, and the summary sizes the populations for a stated precision.

Every grain is an ordinary grain scene (the base scene with the population's and the
sweep point's fields changed). Before any simulation the swept fields and the populations'
entries are checked to set disjoint entries of the scene, the cost is estimated from counts,
and the grains are validated at the cost of one point's (:func:`validate`). The plan holds counts,
not scenes: each task builds its grains from (population, seed, index). The work runs on
Dask: a local process pool by default, a ``dask.distributed`` scheduler by address
with ``--scheduler``; results do not depend on where they ran (tested bit for bit).
"""
from __future__ import annotations

import copy
import math
import time
from dataclasses import dataclass, field as dataclass_field, replace
from functools import cached_property

import numpy as np

from symmech.core import engines
from symmech.core import sweep as core_sweep
from symmech.core import schema as s
from symmech.core.results import Column, Headline, Result, Table
from symmech.core.scene import SceneError
from symmech.core.sweep import CONNECT_TIMEOUT, FIELD_PATH, axis_values, get as _get, put as _set
from symmech.grain import sweep_report

# the fields a sweep may vary, with their units
SWEPT = {"vibration.amplitude": "m", "vibration.frequency": "Hz", "vibration.angle_deg": "deg",
         "vibration.phase_deg": "deg", "surface.alpha_deg": "deg", "surface.beta_deg": "deg",
         "sliding.friction": "1", "impact.e_n": "1", "impact.e_t": "1", "impact.mu": "1", "impact.e": "1",
         "impact.lambda": "1"}


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


AXIS = core_sweep.axis_table(s.Choice("the grain-scene field swept (dotted path)", choices=tuple(SWEPT)))

def _check_band(c: dict, path: str) -> None:
    if None not in (c["hop_fraction_min"], c["hop_fraction_max"]) and c["hop_fraction_min"] > c["hop_fraction_max"]:
        raise SceneError(f"{path}.hop_fraction_max", f"{c['hop_fraction_max']:g} is below hop_fraction_min "
                                                     f"{c['hop_fraction_min']:g}: the band must not be empty")


SWEEP = s.Table("the swept plane (used by `symmech sweep`; `symmech run` ignores it)", {
    **core_sweep.plane_fields(AXIS),
    "duration": s.Float("simulated time per grain (default: the scene's duration)", unit="s", lo=0.0,
                        lo_open=True, hi=1e4, default=None),
    "constraints": s.Table("what an eligible operating point keeps (only eligible points can be best)", {
        "population": s.Str("the population they apply to (default: every population)", default=None),
        "min_mean_vx": s.Float("least mean transport velocity along X", unit="m/s", lo=-100.0, hi=100.0,
                               default=None),
        "hop_fraction_min": s.Float("least fraction of grains hopping", lo=0.0, hi=1.0, default=None),
        "hop_fraction_max": s.Float("largest fraction of grains hopping", lo=0.0, hi=1.0, default=None),
    }, default=None, checks=(_check_band,)),
}, default=None, checks=(core_sweep.check_plane,))

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


CHUNK = 500  # grains per task at most: a point of a large population spreads over workers


def _is_vector(value) -> bool:
    """A number, or a non-empty list of numbers (what ``vary`` scales)."""
    items = value if isinstance(value, list) and value else [value]
    return all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in items)


def _scaled(value, factor):
    if isinstance(value, list):
        return [v * f for v, f in zip(value, factor)]
    return value * factor[0]


def _population_base(base: dict, population: dict, field: str) -> tuple[dict, int]:
    """The base scene with the population's `set` fields, and the number of random doubles each grain
    draws (one per varied component, three for a random orientation); ``field`` names the population."""
    data = copy.deepcopy(base)
    for path, value in population["set"].items():
        _set(data, path, copy.deepcopy(value), f"{field}.set.{path}")
    draws = 0
    for path in population["vary"]:
        value = _get(data, path)
        if not _is_vector(value):
            found = "missing" if value is None else s.show(value)
            raise SceneError(f"{field}.vary.{path}", f"varies a number or vector of numbers of the scene; "
                                                     f"{path} is {found}")
        draws += len(value) if isinstance(value, list) else 1
    return data, draws + 3 * population["random_orientation"]


def members(base: dict, population: dict, start: int = 0, stop: int | None = None, field: str = "population[0]"):
    """The raw grain scenes ``start..stop`` of one population (before the sweep point's fields are set),
    one at a time; ``field`` names the population in errors. Grain k is a function of (population, seed,
    k) alone: its random numbers are the population stream's doubles k·d .. (k+1)·d − 1 (d per grain),
    reached by advancing the PCG64 generator, the same numbers as drawing the grains 0..k in turn."""
    data0, draws = _population_base(base, population, field)
    rng = np.random.default_rng(population["seed"])
    rng.bit_generator.advance(start * draws)  # PCG64: one step per double drawn
    for _ in range(start, population["count"] if stop is None else stop):
        data = copy.deepcopy(data0)
        for path, spread in population["vary"].items():
            value = _get(data, path)
            size = len(value) if isinstance(value, list) else 1
            _set(data, path, _scaled(value, rng.uniform(1 - spread, 1 + spread, size).tolist()), f"{field}.vary.{path}")
        if population["random_orientation"]:
            _set(data, "body.orientation", [float(rng.uniform(0, 2 * math.pi)),
                                            float(math.acos(rng.uniform(-1, 1))),
                                            float(rng.uniform(0, 2 * math.pi))], field)
        yield data


@dataclass
class Plan:
    """The sweep as counts and recipes, not grain scenes: grain g of population k at point (i, j) is
    built where it runs, by :func:`grains` from (population, seed, g), so the client's memory does not
    grow with the number of grains."""

    x: dict
    y: dict | None
    names: list[str]
    base: dict  # the grain scene without [sweep] and [[population]], the sweep's duration set
    populations: list[dict]  # resolved [[population]] tables
    gamma: np.ndarray  # (nx, ny) throw number at each point
    first: list = dataclass_field(default_factory=list)  # grain 0 of each population at (0, 0), dispatched
    constraints: dict | None = None  # the resolved [sweep.constraints]

    @property
    def shape(self) -> tuple[int, int]:
        """(nx, ny): the number of sweep points along x and y (ny = 1 without y)."""
        return self.gamma.shape

    @property
    def grain_runs(self) -> int:
        return sum(pop["count"] for pop in self.populations) * self.gamma.size

    @cached_property
    def values(self) -> tuple[np.ndarray, np.ndarray | None]:
        """The swept values along x and y (None without y)."""
        return axis_values(self.x), axis_values(self.y) if self.y else None

    def point(self, i: int, j: int) -> dict:
        """The swept fields' values at point (i, j), by dotted path."""
        xs, ys = self.values
        return {self.x["field"]: float(xs[i])} | ({self.y["field"]: float(ys[j])} if self.y else {})


def grains(p: Plan, k: int, i: int, j: int, start: int = 0, stop: int | None = None):
    """The raw grain scenes ``start..stop`` of population k at sweep point (i, j), one at a time."""
    return point_grains(p.base, p.populations[k], p.point(i, j), start, stop, f"population[{k}]")


def point_grains(base: dict, population: dict, fields: dict, start: int = 0, stop: int | None = None,
                 field: str = "population[0]"):
    """:func:`members` ``start..stop`` with the sweep point's ``fields`` (dotted path: value) set."""
    for data in members(base, population, start, stop, field):
        for path, value in fields.items():
            _set(data, path, value, "sweep")
        yield data


def _first(p: Plan, k: int) -> dict:
    """Grain 0 of population k at point (0, 0)."""
    return next(grains(p, k, 0, 0, 0, 1))


def plan(raw: dict, resolved: dict) -> Plan:
    """The sweep's plan from the scene's counts (cost independent of the number of grains); grain 0 of
    each population at the first point is validated (:func:`validate` checks the rest); the swept fields and
    the populations' entries checked to be disjoint (:func:`_check_plan`)."""
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
    _check_plan(sweep, pops)
    names = [pop["name"] for pop in pops]
    constrained = (sweep["constraints"] or {}).get("population")
    if constrained is not None and constrained not in names:
        raise SceneError("sweep.constraints.population", f"{constrained!r} is not a population "
                                                         f"(they are: {', '.join(names)})")
    p = Plan(sweep["x"], sweep["y"], names, base, pops, np.empty((len(xs), len(ys))),
             constraints=sweep["constraints"])
    # grain 0 of each population validated (kept for the estimate); Γ from the last one's, as always
    p.first = [_as_dispatched(load_grain(_first(p, k), sweep, pops[k], k)) for k in range(len(pops))]
    resolved = p.first[-1].resolved
    for i, j in np.ndindex(*p.shape):
        swept = {path.removeprefix("vibration."): value for path, value in p.point(i, j).items()
                 if path.startswith("vibration.")}
        p.gamma[i, j] = throw_number({"vibration": resolved["vibration"] | swept, "surface": resolved["surface"]})
    return p


def _check_plan(sweep: dict, pops: list) -> None:
    """No scene entry set twice in a population's grains: the swept fields, and then each population's `set`
    entries (tables resolved to the entries they hold, ``"body" = {density = ...}`` to ``body.density``) and
    its random orientation, or its `vary` entries (a population varies what it sets, by design)."""
    axes = [(f"sweep.{a}.field", sweep[a]["field"], [tuple(sweep[a]["field"].split("."))])
            for a in ("x", "y") if sweep[a] is not None]
    for k, pop in enumerate(pops):
        where = f"population[{k}]"
        sets = [(f"{where}.set.{path}", path, _leaves(tuple(path.split(".")), value))
                for path, value in pop["set"].items()]
        if pop["random_orientation"]:
            sets.append((f"{where}.random_orientation", "random_orientation", [("body", "orientation")]))
        core_sweep.check_disjoint(axes + sets)
        core_sweep.check_disjoint(axes + [(f"{where}.vary.{path}", path, [tuple(path.split("."))])
                                          for path in pop["vary"]])


def _leaves(keys: tuple, value) -> list[tuple]:
    """The key paths of the entries ``value`` (a table, or one value) sets at ``keys``."""
    if isinstance(value, dict) and value:
        return [leaf for key, v in value.items() for leaf in _leaves(keys + (key,), v)]
    return [keys]


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
    """The grain scenes checked before any simulation at the cost of one point's grains, not of every point's:
    every grain of each population at point (0, 0), and its grain 0 at every value of each axis and at the
    plane's far corner (the swept fields and a population's entries set disjoint entries, :func:`_check_plan`;
    a grain a check couples both in fails on its own, reported among the failed grains). A bad grain is named
    by the sweep or population field its value came from."""
    nx, ny = p.shape
    points = sorted({(i, 0) for i in range(nx)} | {(0, j) for j in range(ny)} | {(nx - 1, ny - 1)})
    for k, pop in enumerate(p.populations):
        for data in grains(p, k, 0, 0):
            load_grain(data, {"x": p.x, "y": p.y}, pop, k)
        for i, j in points:
            load_grain(next(grains(p, k, i, j, 0, 1)), {"x": p.x, "y": p.y}, pop, k)


def throw_number(resolved: dict) -> float:
    """Γ = A ω² / g of a resolved grain scene (dimensionless)."""
    vib = resolved["vibration"]
    g = resolved["surface"]["g"]
    return vib["amplitude"] * (2 * math.pi * vib["frequency"]) ** 2 / g


POPULATION_SLICE = 16  # grains per compiled population call
BUDGET_MARGIN = 10.0  # a slice runs as one population (no clock inside it) only while the time left holds this many
# times its count estimate (at most 0.7 of the actual, motion_scene's fit); else its grains run one by one, watched


def simulate_point(scenes, first: int = 0, until: float = math.inf) -> tuple[np.ndarray, list, list]:
    """Per grain of the iterable ``scenes`` (raw grain scenes, numbered from ``first``): mean transport velocity
    (X, Y) [m/s] and the fraction of time in flight, shape (n, 3); a grain whose scene or simulation stops with an
    error (e.g. a stagnation guard, or the sweep's deadline ``until``, a ``time.time()``) gets a row of NaN and its
    message in the list of (grain index, message) — it is reported, never averaged in. A grain whose run warned
    (e.g. a rocking contact the model does not follow) is averaged in and listed as (grain index, warnings).
    The grains run in slices of :data:`POPULATION_SLICE` (:func:`_slice`), each as ``symmech run`` would run it."""
    from symmech.core import pipeline
    from symmech.core.scene import SymmechError

    out, failed, warned, loaded = [], [], [], []
    for k, data in enumerate(scenes, first):
        try:
            loaded.append((k, pipeline.load(data)))
        except SymmechError as exc:
            failed.append((k, str(exc)))
        out.append((np.nan, np.nan, np.nan))
    for at in range(0, len(loaded), POPULATION_SLICE):
        for k, answer in _slice(loaded[at:at + POPULATION_SLICE], until):
            if isinstance(answer, SymmechError):
                failed.append((k, str(answer)))
                continue
            out[k - first], warnings = answer
            if warnings:
                warned.append((k, warnings))
    return np.array(out).reshape(-1, 3), sorted(failed), sorted(warned)


def _slice(part: list, until: float) -> list:
    """(grain index, ((vx, vy, flight fraction), warnings) or the grain's SymmechError) of each loaded grain scene
    of ``part`` (a list of (index, pipeline.Scene)): as one population (the kind's ``population``:
    ``motion_scene.sweep_answers``, the results built in bulk) while the time to ``until`` holds
    :data:`BUDGET_MARGIN` times the slice's count estimate, else one by one, each run watched by the deadline as
    ``symmech run`` watches it."""
    scenes = [scene for _, scene in part]
    if scenes[0].estimate().seconds * len(part) * BUDGET_MARGIN < until - time.time():
        return list(zip([k for k, _ in part], scenes[0].kind.population([scene.setup for scene in scenes])))
    return [(k, _alone(scene, until)) for k, scene in part]


def _alone(scene, until: float):
    """One grain's ((vx, vy, flight fraction), warnings) from its whole run (a ``pipeline.Scene`` under the
    deadline ``until``), or its SymmechError."""
    from symmech.core.scene import SymmechError

    try:
        res = scene.run(core_sweep.point_context(until))
    except SymmechError as exc:
        return exc
    vx, vy = res.summary["mean_transport_velocity_m_s"]
    return (vx, vy, res.summary["time_fraction"].get("flight", 0.0)), list(res.warnings)


def simulate_grains(base: dict, population: dict, fields: dict, start: int, stop: int, until: float):
    """A task: grains ``start..stop`` of a population at one sweep point, built here (:func:`point_grains`)
    and simulated (:func:`simulate_point`) until the wall-clock time ``until``."""
    return simulate_point(point_grains(base, population, fields, start, stop), start, until)


def estimate(p: Plan, workers: int):
    """Cost of the whole sweep from its counts: the grain kind's estimate of each population's first grain,
    times the grains and points, shared by ``workers``, after a compile (done once, here) if the engine is cold (a
    ``registry.Estimate``)."""
    from symmech.core import registry

    first = [scene.estimate() for scene in p.first]
    once = max(e.once for e in first)
    work = sum((e.seconds - e.once) * pop["count"] * p.gamma.size for e, pop in zip(first, p.populations))
    return registry.Estimate(once + work / max(workers, 1), f"{p.grain_runs} grain runs on {workers} worker(s)"
                             + (f" after a {once:.3g} s compile" if once else ""), once)


SAMPLE_GRAINS = 4  # grains of the first population, at points spread over the grid, timed for the estimate


def timed_estimate(p: Plan, processes: int, scheduler: str | None, drawing: float):
    """The sweep's cost from timed samples here (a ``registry.Estimate``): grains of the first population at
    points spread over the grid (:func:`symmech.core.sweep.spread`), one each, on the engine the workers run (the
    first of them alone pays loading it), the count model's ratio between populations, the workers' start (:func:`symmech.core.sweep.startup_seconds`) and the charts,
    ``drawing`` [s] (:func:`chart_count` times :func:`symmech.core.sweep.chart_seconds`)."""
    from symmech.core import registry

    pop, ny = p.populations[0], p.shape[1]
    # one grain per point, the points spread over the grid: a corner's grains may cost far more or less (point
    # (0, 0) alone overestimated the bundled separation sweep 2.1x)
    cells = core_sweep.spread(p.gamma.size)[:SAMPLE_GRAINS + 1]
    grains = [next(point_grains(p.base, pop, p.point(*divmod(c, ny)), k % pop["count"], k % pop["count"] + 1))
              for k, c in enumerate(cells)]
    started = time.perf_counter()
    simulate_point(grains[:1])
    first = time.perf_counter() - started
    timed = grains[1:] or grains
    started = time.perf_counter()
    simulate_point(timed)
    per_grain = (time.perf_counter() - started) / len(timed)
    models = [scene.estimate().seconds for scene in p.first]
    work = per_grain / models[0] * sum(m * q["count"] for m, q in zip(models, p.populations)) * p.gamma.size
    startup = core_sweep.startup_seconds(scheduler, max(first - per_grain, 0.0))
    return registry.Estimate(startup + work / processes + drawing,
                             f"{p.grain_runs} grain runs at {per_grain:.3g} s (timed here) on {processes} "
                             f"worker(s), {startup:.3g} s to start them, {drawing:.3g} s for the charts")


def chart_count(p: Plan) -> int:
    """The sweep's charts: transport velocity and hop fraction per population, the separation's two."""
    return 2 * len(p.populations) + (2 if len(p.populations) == 2 else 0)


def _as_dispatched(scene):
    """A loaded grain scene (pipeline.Scene) as the workers run it: engine `auto` runs compiled, since
    :func:`compute` builds the compiled engine before dispatch."""
    num = scene.setup.numerics
    if num.engine == "auto":
        scene.setup = replace(scene.setup, numerics=replace(num, engine="compiled"))
    return scene


def _compiled_needed(p: Plan) -> bool:
    """Whether a population's grains run the compiled engine (accurate mode, engine not `python`)."""
    return any(n.mode == "accurate" and n.engine == "compiled"
               for n in (scene.setup.numerics for scene in p.first))


def _warm_worker() -> None:
    """On a dask worker: the compiled engine built once per machine (the others wait on the build lock)."""
    engines.get("grain").warm()


def run(source, out, ctx, scheduler: str | None = None, workers: int | None = None,
        connect_timeout: float = CONNECT_TIMEOUT, half_width: float | None = None) -> Result:
    """``symmech sweep``: validate the scene and its plan, estimate from counts, validate the grains, compute,
    write;
    ``half_width`` [m/s] the summary's precision target (default 1 mm/s)."""
    from symmech.core import pipeline
    from symmech.core.scene import read_toml

    raw = source if isinstance(source, dict) else read_toml(source)
    scene = pipeline.load(source, raw)
    p = plan(raw, scene.resolved)
    processes = core_sweep.workers(workers, scheduler)
    cost = estimate(p, processes)
    core_sweep.refuse(cost, ctx, tell=cost.once > 0)
    validate(p)
    res = result(p, *compute(p, scheduler, processes, connect_timeout, say=ctx.say, ctx=ctx),
                 half_width=1e-3 if half_width is None else half_width)
    scene.cost = ctx.estimates[-1]  # the summary's estimate: the sweep's last
    pipeline.write(res, out, scene)
    return res


def compute(p: Plan, scheduler: str | None = None, processes: int | None = None,
            connect_timeout: float = CONNECT_TIMEOUT, say=None, ctx=None) -> tuple[list, list, list]:
    """Per population, an array (nx, ny, grains, 3) of :func:`simulate_point` results, on Dask
    (:func:`symmech.core.sweep.compute`: ``scheduler``, ``processes``, ``connect_timeout``, progress on
    ``ctx``), the failed grains as (population, i, j, grain, message) and the grains that warned as
    (population, i, j, grain, warnings).

    Grains on the compiled engine find it built: this process builds it first (in the foreground,
    ``say(text)`` tells it), and so does each machine of a ``dask.distributed`` cluster, once per
    machine (the build lock of :meth:`symmech.numerics.build.Engine.warm`).
    """
    import dask

    warm = _compiled_needed(p)
    if warm:
        engines.get("grain").warm(say=say)
    drawing = 0.0
    if ctx is not None:
        drawing = chart_count(p) * core_sweep.chart_seconds(p.shape)
        core_sweep.refuse(timed_estimate(p, core_sweep.workers(processes, scheduler), scheduler, drawing), ctx)

    jobs = [(k, i, j, start, min(start + CHUNK, pop["count"])) for k, pop in enumerate(p.populations)
            for i, j in np.ndindex(*p.shape) for start in range(0, pop["count"], CHUNK)]
    until = core_sweep.deadline(ctx) if ctx is not None else math.inf
    tasks = [dask.delayed(simulate_grains)(p.base, p.populations[k], p.point(i, j), a, b, until,
                                           dask_key_name=f"grains-{k}-{i}-{j}-{a}") for k, i, j, a, b in jobs]
    values = core_sweep.compute(tasks, scheduler, processes, connect_timeout, ctx,
                                on_workers=_warm_worker if warm else None, after=drawing)
    arrays = [np.empty(p.shape + (pop["count"], 3)) for pop in p.populations]
    failed, warned = [], []
    for (k, i, j, a, b), (rows, fail, warn) in zip(jobs, values):
        arrays[k][i, j, a:b] = rows
        failed += [(p.names[k], i, j, g, msg) for g, msg in fail]
        warned += [(p.names[k], i, j, g, msg) for g, msg in warn]
    return arrays, failed, warned


LEVEL = 0.95  # confidence level of every interval
_Q = 0.5 + LEVEL / 2
RESAMPLES = 999  # bootstrap resamples of the overlap's interval


def _moments(x: np.ndarray):
    """Sample size, mean and sum of squared deviations along the last axis, NaN (failed grains) left out."""
    n = np.isfinite(x).sum(-1)
    m = np.nanmean(x, -1)
    return n, m, np.nansum((x - m[..., None]) ** 2, -1)


def mean_interval(x: np.ndarray):
    """Student t interval (lo, hi) of the mean of the samples x (..., n), along the last axis."""
    from scipy import stats  # on use: its import costs seconds the refusal of a sweep need not pay

    n, m, ss = _moments(x)
    h = stats.t.ppf(_Q, n - 1) * np.sqrt(ss / (n - 1) / n)
    return m - h, m + h


def std_interval(x: np.ndarray):
    """Chi-square interval (lo, hi) of the standard deviation of normal samples x (..., n), last axis."""
    from scipy import stats

    n, _, ss = _moments(x)
    return np.sqrt(ss / stats.chi2.ppf(_Q, n - 1)), np.sqrt(ss / stats.chi2.ppf(1 - _Q, n - 1))


def proportion_interval(k: np.ndarray, n: np.ndarray):
    """Wilson score interval (lo, hi) of a proportion from k successes in n trials."""
    from scipy import stats

    z = stats.norm.ppf(_Q)
    p = k / n
    centre = (p + z**2 / (2 * n)) / (1 + z**2 / n)
    h = z * np.sqrt(p * (1 - p) / n + z**2 / (4 * n**2)) / (1 + z**2 / n)
    return centre - h, centre + h


def difference_interval(a: np.ndarray, b: np.ndarray):
    """Welch t interval (lo, hi) of mean(a) − mean(b) of samples (..., n), along the last axis."""
    from scipy import stats

    (na, ma, ssa), (nb, mb, ssb) = _moments(a), _moments(b)
    va, vb = ssa / (na - 1) / na, ssb / (nb - 1) / nb  # squared standard errors
    df = (va + vb) ** 2 / (va**2 / (na - 1) + vb**2 / (nb - 1))
    h = np.where(va + vb > 0, stats.t.ppf(_Q, df) * np.sqrt(va + vb), 0.0)
    return ma - mb - h, ma - mb + h


def statistics(grid: np.ndarray) -> dict:
    """Per point of grid (..., grains, 3): mean and spread of the transport velocity, the hopping and
    flight fractions, each with its LEVEL interval (keys ``<name>_lo``, ``<name>_hi``)."""
    ok = np.isfinite(grid[..., 2])
    with np.errstate(invalid="ignore", divide="ignore"):  # a point with fewer than two grains has no interval
        hops, n = np.where(ok, grid[..., 2] > 0.5, 0).sum(-1), ok.sum(-1)
        out = {"mean_vx": np.nanmean(grid[..., 0], -1), "std_vx": np.nanstd(grid[..., 0], -1),
               "mean_vy": np.nanmean(grid[..., 1], -1), "std_vy": np.nanstd(grid[..., 1], -1),
               "hop_fraction": hops / n, "flight_fraction": np.nanmean(grid[..., 2], -1),
               "failed": (~ok).sum(-1).astype(float)}
        intervals = {"mean_vx": mean_interval(grid[..., 0]), "std_vx": std_interval(grid[..., 0]),
                     "mean_vy": mean_interval(grid[..., 1]), "std_vy": std_interval(grid[..., 1]),
                     "hop_fraction": proportion_interval(hops, n), "flight_fraction": mean_interval(grid[..., 2])}
    for name, (lo, hi) in intervals.items():
        out[f"{name}_lo"], out[f"{name}_hi"] = lo, hi
    return out


def overlap_normal(m1, s1, m2, s2):
    """Overlap coefficient of the normal densities N(m1, s1²) and N(m2, s2²) (arrays broadcast, s > 0):
    the area under the lower of the two, from the points where they cross."""
    from scipy import stats

    narrow = s1 <= s2
    mn, sn, mw, sw = (np.where(narrow, u, v) for u, v in ((m1, m2), (s1, s2), (m2, m1), (s2, s1)))
    # the narrow density is the higher one where a x² + b x + c < 0, between the roots
    a, b = 1 / sn**2 - 1 / sw**2, -2 * (mn / sn**2 - mw / sw**2)
    c = mn**2 / sn**2 - mw**2 / sw**2 - 2 * np.log(sw / sn)
    with np.errstate(invalid="ignore", divide="ignore"):  # equal spreads: one root at ±inf (a = 0)
        q = -0.5 * (b + np.where(b >= 0, 1.0, -1.0) * np.sqrt(np.maximum(b**2 - 4 * a * c, 0.0)))
        r1, r2 = q / a, c / q
    x1, x2 = np.minimum(r1, r2), np.maximum(r1, r2)
    phi = stats.norm.cdf
    ovl = phi(x2, mw, sw) - phi(x1, mw, sw) + phi(x1, mn, sn) + phi(-x2, -mn, sn)
    return np.where((mn == mw) & (sn == sw), 1.0, ovl)


def overlap(a: np.ndarray, b: np.ndarray, axis: int = -1):
    """Overlap coefficient of two samples of X velocities along ``axis`` (of their normal fits; NaN, failed
    grains, left out)."""
    def fit(x):
        return np.nanmean(x, axis), np.maximum(np.nanstd(x, axis), 1e-12)

    return overlap_normal(*fit(a), *fit(b))


def overlap_interval(a: np.ndarray, b: np.ndarray, rng: np.random.Generator) -> tuple[float, float]:
    """Bootstrap percentile interval (lo, hi) of :func:`overlap` of two samples (NaN left out)."""
    from scipy import stats

    a, b = a[np.isfinite(a)], b[np.isfinite(b)]
    if min(len(a), len(b)) < 2:
        return math.nan, math.nan
    res = stats.bootstrap((a, b), overlap, n_resamples=RESAMPLES, confidence_level=LEVEL, method="percentile",
                          vectorized=True, rng=rng)
    return float(res.confidence_interval.low), float(res.confidence_interval.high)


def grains_needed(spread: float, half_width: float) -> int:
    """Smallest number of grains n ≥ 2 whose Student t interval of a mean, for the spread (standard
    deviation) ``spread``, has at most ``half_width`` (same unit) at LEVEL."""
    from scipy import stats

    n = max(2, math.ceil((stats.norm.ppf(_Q) * spread / half_width) ** 2))
    while stats.t.ppf(_Q, n - 1) * spread / math.sqrt(n) > half_width:
        n += 1
    return n


def _column(axis: dict, name: str) -> Column:
    return Column(name, SWEPT[axis["field"]], f"swept field {axis['field']}")


def _point_columns(p: Plan) -> tuple[list[Column], np.ndarray]:
    xs = axis_values(p.x)
    ys = axis_values(p.y) if p.y else np.array([np.nan])
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    cols = [_column(p.x, "x")] + ([_column(p.y, "y")] if p.y else []) + [Column("gamma", "1", "throw number A w^2/g")]
    data = [X.ravel()] + ([Y.ravel()] if p.y else []) + [p.gamma.ravel()]
    return cols, np.column_stack(data)


def _with_interval(column: Column, method: str) -> list[Column]:
    """The column and the ends of its LEVEL confidence interval (``method``)."""
    return [column] + [Column(f"{column.name}_{end}", column.unit, f"{word} end of the {LEVEL:.0%} confidence "
                              f"interval of {column.name} ({method})") for end, word in (("lo", "lower"),
                                                                                          ("hi", "upper"))]


STAT_COLUMNS = [
    *_with_interval(Column("mean_vx", "m/s", "mean transport velocity along X"), "Student t"),
    *_with_interval(Column("std_vx", "m/s", "spread (standard deviation) of the X velocity over the grains"),
                    "chi-square, normal velocities"),
    *_with_interval(Column("mean_vy", "m/s", "mean transport velocity along Y"), "Student t"),
    *_with_interval(Column("std_vy", "m/s", "spread of the Y velocity"), "chi-square, normal velocities"),
    *_with_interval(Column("hop_fraction", "1", "fraction of grains more than half of the time in flight"),
                    "Wilson score"),
    *_with_interval(Column("flight_fraction", "1", "mean fraction of time in flight"), "Student t"),
    Column("failed", "1", "grains whose simulation stopped with an error (left out of the statistics)")]


def separation(a: np.ndarray, b: np.ndarray, seed: int = 0) -> dict:
    """Per point of two populations' grids (nx, ny, grains, 3): the differences of the mean velocities and
    the overlap of the X-velocity distributions, each with its LEVEL interval (``<name>_lo``, ``_hi``)."""
    rng = np.random.default_rng(seed)  # the bootstrap's resamples: the same tables on every run
    with np.errstate(invalid="ignore", divide="ignore"):
        out = {"delta_vx": np.nanmean(a[..., 0], -1) - np.nanmean(b[..., 0], -1),
               "delta_vy": np.nanmean(a[..., 1], -1) - np.nanmean(b[..., 1], -1),
               "overlap": overlap(a[..., 0], b[..., 0])}
        for k in range(2):
            out[f"{('delta_vx', 'delta_vy')[k]}_lo"], out[f"{('delta_vx', 'delta_vy')[k]}_hi"] = \
                difference_interval(a[..., k], b[..., k])
    ends = np.array([[overlap_interval(a[i, j, :, 0], b[i, j, :, 0], rng) for j in range(a.shape[1])]
                     for i in range(a.shape[0])]).reshape(a.shape[:2] + (2,))
    out["overlap_lo"], out["overlap_hi"] = ends[..., 0], ends[..., 1]
    return out


def _separation_columns(names: list[str]) -> list[Column]:
    return [*_with_interval(Column("delta_vx", "m/s", f"mean X velocity of {names[0]} minus {names[1]}"), "Welch t"),
            *_with_interval(Column("delta_vy", "m/s", "the same along Y"), "Welch t"),
            *_with_interval(Column("overlap", "1", "overlap coefficient of the two X-velocity distributions"),
                            f"bootstrap percentile, {RESAMPLES} resamples")]


def best_point(sep: dict, ok: np.ndarray | None = None) -> tuple[int | None, np.ndarray | None]:
    """The best eligible operating point (flat index: the least overlap, ties broken by the larger velocity
    difference; ``ok`` (n,) the eligible points, default all) and the mask (nx, ny) of the eligible points not
    significantly worse: their overlap interval meets the best's. (None, None) when no point is eligible."""
    ok = np.ones(sep["overlap"].size, bool) if ok is None else ok
    best = sweep_report.best(ok, [], [], sep)
    if best is None:
        return None, None
    return best, (sep["overlap_lo"] <= sep["overlap_hi"].ravel()[best]) & ok.reshape(sep["overlap"].shape)


def _number(x) -> float | None:
    """A summary value: the float, or None where there is none (NaN: too few grains)."""
    return float(x) if math.isfinite(x) else None


def _spread(x: np.ndarray) -> np.ndarray:
    """Sample standard deviation (ddof 1) along the last axis; NaN below two grains."""
    n, _, ss = _moments(x)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.sqrt(ss / (n - 1))


def _precision(names: list[str], stats_: list[dict], values: list, best: int | None, half_width: float) -> dict:
    """How many grains per population a mean X velocity (and the best point's Δv_x) to ± ``half_width`` m/s
    at LEVEL needs, from the largest observed spread (None below two grains per point)."""
    def needed(spread):
        return grains_needed(spread, half_width) if math.isfinite(spread) else None

    out = {"level": LEVEL, "half_width_m_s": half_width}
    for name, st, v in zip(names, stats_, values):
        spread = float(np.fmax.reduce(_spread(v[..., 0]), axis=None))
        out[name] = {"largest_spread_m_s": _number(spread), "grains_needed": needed(spread),
                     "largest_half_width_m_s": _number(np.fmax.reduce(st["mean_vx_hi"] - st["mean_vx"], axis=None))}
    if best is not None:  # the same n in both populations: the spread of a difference is the root sum square
        spread = math.hypot(*(float(_spread(v[..., 0]).ravel()[best]) for v in values))
        out["delta_vx_at_best"] = {"spread_m_s": _number(spread), "grains_needed": needed(spread)}
    return out


def result(p: Plan, values: list, failed: list = (), warned: list = (), half_width: float = 1e-3) -> Result:
    """Tables per population (and the separation chart for two), summary and heat-map plots; every statistic
    with its LEVEL interval; ``failed`` and ``warned`` grains (from :func:`compute`) are listed in the summary
    and warned about; the summary's ``precision`` sizes the populations for ± ``half_width`` m/s."""
    cols, base = _point_columns(p)
    tables, summary = {}, {"populations": p.names, "points": int(base.shape[0]),
                           "grains_per_point": [int(v.shape[2]) for v in values],
                           "swept": [p.x["field"]] + ([p.y["field"]] if p.y else []),
                           "failed_grains": [{"population": n, "point": [i, j], "grain": g, "error": m}
                                             for n, i, j, g, m in failed],
                           "warned_grains": [{"population": n, "point": [i, j], "grain": g, "warnings": m}
                                             for n, i, j, g, m in warned]}
    stats_ = [statistics(v) for v in values]
    sep = separation(*values) if len(values) == 2 else None
    grid = {c.name: c.name for c in cols[:2 if p.y else 1]}  # x-major: to_xarray over the swept axes
    why = sweep_report.reasons(p.names, stats_, p.constraints, failed, warned, p.shape)
    ok = np.array([not w for w in why])
    verdict = {"verdict": ["eligible" if not w else "; ".join(sentence for _, sentence in w) for w in why]}
    eligible = Column("eligible", "1", "1: the constraints kept and no grain failed or warned at this point")
    for name, st in zip(p.names, stats_):
        data = np.column_stack([base] + [st[c.name].ravel() for c in STAT_COLUMNS] + [ok.astype(float)])
        tables[f"sweep_{name}"] = Table(cols + STAT_COLUMNS + [eligible], data, f"population {name} over the swept "
                                        "plane", verdict, grid=grid)
    best, similar = (None, None) if sep is None else best_point(sep, ok)
    if sep is not None:
        sep_cols = _separation_columns(p.names)
        tables["separation"] = Table(cols + sep_cols, np.column_stack([base] + [sep[c.name].ravel() for c in sep_cols]),
                                     "separation chart of the two populations", grid=grid)
    else:
        best = sweep_report.best(ok, p.names, stats_, None)
    if sep is not None and best is not None:
        at = {c.name: _number(sep[c.name].ravel()[best]) for c in sep_cols}
        summary["best_operating_point"] = {c.name: float(base[best, k]) for k, c in enumerate(cols)} | {
            "delta_vx_m_s": at["delta_vx"], "delta_vx_interval_m_s": [at["delta_vx_lo"], at["delta_vx_hi"]],
            "overlap": at["overlap"], "overlap_interval": [at["overlap_lo"], at["overlap_hi"]],
            "level": LEVEL, "points_not_significantly_worse": [list(ij) for ij in zip(*map(np.ndarray.tolist,
                                                                                            np.nonzero(similar)))]}
    elif best is not None:
        summary["best_operating_point"] = {c.name: float(base[best, k]) for k, c in enumerate(cols)} | {
            "mean_vx_m_s": _number(stats_[0]["mean_vx"].ravel()[best]), "level": LEVEL}
    summary["precision"] = _precision(p.names, stats_, values, best, half_width)
    warnings = [f"{len(failed)} grain simulation(s) stopped with an error and are left out of the statistics "
                f"(summary.json: failed_grains); first: {failed[0][4]}"] if failed else []
    warnings += [f"{len(warned)} grain simulation(s) ran with warnings (summary.json: warned_grains); first: "
                 f"{warned[0][4][0]}"] if warned else []
    axes = [(sweep_report.NAMES[a["field"]], SWEPT[a["field"]], a["log"]) for a in (p.x, p.y) if a]
    values_ = [v for v in p.values if v is not None]
    headline, checks, limits, limited_by = sweep_report.answer(axes, values_, why, best, p.names, stats_, sep,
                                                               summary["precision"], half_width)
    charts = sweep_report.charts(p.names, stats_, sep)
    flat = sweep_report.flat(charts)
    headline += [Headline(f["text"].partition(":")[0], f["value"], f["unit"], f["text"].partition(": ")[2],
                          "every point") for f in flat.values()]
    summary |= {"eligible_points": int(ok.sum()), "limited_by": limited_by, "flat": flat,
                "criterion": "least overlap, ties to the larger |delta_vx|" if sep is not None else "largest mean_vx",
                "captions": {stem: sweep_report.caption(title, axes) for stem, _, title, _, _ in charts
                             if stem not in flat}}
    shown = [c for c in charts if c[0] not in flat]
    return Result("grain_sweep", summary, tables, headline=headline, checks=checks,
                  plots=lambda folder: sweep_report.plots(axes, values_, p.gamma, shown, why, best, folder),
                  warnings=warnings + limits)
