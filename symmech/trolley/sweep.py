"""Design sweeps of a trolley (rigid, or with the ``[elastic]`` table): ``symmech sweep SCENE --out DIR``.

A trolley scene's ``[sweep]`` names one or two swept fields (:data:`FIELDS`: a speed scale or a
constant of the speed expression, the roller stiffness or damping, a beam's stiffness, tip mass or
damping, the body's mass, a comfort limit) and optional reaction limits. Every point of the plane
is the scene with those fields set, run through the scene's own path (``pipeline.load(...).run()``:
whatever engine the trolley kind uses runs the points), and reduced to its design numbers
(:func:`point_metrics`): peak reactions, their dynamic amplification (elastic / rigid peak of the
elastic model), the largest roller and body deflections, each report point's comfort margin and
the closest resonance.

Before any run the plane is checked as a whole, at a cost that does not grow with its points
(:func:`validate`): the axes resolved to the scene entries they set, disjoint whatever their spelling,
alias or scale; every value of every axis against its table of the scene; both ends of every comfort
envelope at every point; the plane's corners as whole scenes. A bad swept value is named by its axis
(``sweep.x``), in one line. The cost is estimated from counts, then from one timed point
(:func:`compute`).
"""
from __future__ import annotations

import copy
import math
import re
import time
from dataclasses import dataclass, replace

import numpy as np

from symmech.core import engines, units
from symmech.core import schema as s
from symmech.core import sweep as core_sweep
from symmech.core.results import Column, Result, Table
from symmech.core.scene import SceneError
from symmech.trolley import sweep_plots

AXES = ("x1", "x2", "x3")
# (name in messages, pattern of a swept field, its unit, what setting it does, its name on a chart); NAME, I and
# the axis are the field's own
FIELDS = (
    ("motion.speed_scale", r"motion\.speed_scale", "1", "multiplies the speed expression: V0(t) → value × V0(t)",
     "speed scale"),
    ("motion.constants.NAME", r"motion\.constants\.[A-Za-z_][A-Za-z0-9_]*", "1",
     "sets the constant NAME of motion.constants (the axis's `unit` labels it)", "motion constant"),
    ("trolley.mass", r"trolley\.mass", "kg", "sets the body's mass", "body mass"),
    ("elastic.rollers.stiffness", r"elastic\.rollers\.stiffness", "N/m", "sets the stiffness of all five rollers",
     "roller stiffness"),
    ("elastic.rollers.stiffness_scale", r"elastic\.rollers\.stiffness_scale", "1",
     "multiplies the five roller stiffnesses", "roller stiffness scale"),
    ("elastic.rollers.damping", r"elastic\.rollers\.damping", "N s/m", "sets the damping of all five rollers",
     "roller damping"),
    ("elastic.rollers.damping_scale", r"elastic\.rollers\.damping_scale", "1", "multiplies the five roller dampings",
     "roller damping scale"),
    ("elastic.beams[I].ei_scale", r"elastic\.beams\[[0-9]+\]\.ei_scale", "1",
     "multiplies beam I's bending stiffness in both planes", "beam bending-stiffness scale"),
    ("elastic.beams[I].tip_mass", r"elastic\.beams\[[0-9]+\]\.tip_mass", "kg", "sets beam I's tip mass",
     "beam tip mass"),
    ("elastic.beams[I].damping_ratio", r"elastic\.beams\[[0-9]+\]\.damping_ratio", "1",
     "sets beam I's damping ratio", "beam damping ratio"),
    ("comfort.x1.lo (x1, x2, x3; lo, hi)", r"comfort\.x[123]\.(lo|hi)", "g",
     "sets the lower or upper end of the comfort envelope along that axis", "comfort limit"),
)
REACTIONS = tuple(f"P{i}" for i in range(6))


def _field(path, value):
    if not isinstance(value, str) or not any(re.fullmatch(p, value) for _, p, *_ in FIELDS):
        raise SceneError(path, f"{s.show(value)} is not a field a trolley sweep can vary; choose one of "
                               f"{', '.join(name for name, *_ in FIELDS)}")
    return value


def unit_of(axis: dict) -> str:
    """The unit of a resolved axis's field (a motion constant's: the axis's ``unit``, default "1")."""
    if axis["field"].startswith("motion.constants."):
        return axis["unit"] or "1"
    return next(unit for _, pattern, unit, *_ in FIELDS if re.fullmatch(pattern, axis["field"]))


def name_of(axis: dict) -> str:
    """The human name of a resolved axis's field, for charts and answers (``beam 0 tip mass``)."""
    field = axis["field"]
    name = next(name for _, pattern, _, _, name in FIELDS if re.fullmatch(pattern, field))
    if field.startswith("motion.constants."):
        return f"{name} {field.rpartition('.')[2]}"
    if field.startswith("elastic.beams["):
        return name.replace("beam", f"beam {int(re.search(r'[0-9]+', field).group())}", 1)
    if field.startswith("comfort."):
        _, envelope, end = field.split(".")
        return f"{'lower' if end == 'lo' else 'upper'} {name} along {envelope}"
    return name


def _check_unit(axis: dict, path: str) -> None:
    if axis["unit"] is not None and not axis["field"].startswith("motion.constants."):
        raise SceneError(f"{path}.unit", f"{axis['field']} has its own unit ({unit_of(axis)}); `unit` labels a "
                                         "motion constant only")


_AXIS = core_sweep.axis_table(
    s.Custom("the trolley-scene field swept (see the list of swept fields)", parse=_field, type_doc="dotted path"),
    {"unit": s.Str("unit of a swept motion constant, for the labels and CSV headers", default=None)})
AXIS = s.Table(_AXIS.doc, _AXIS.fields, checks=_AXIS.checks + (_check_unit,))

# design numbers an objective may name; all but the first two need the [elastic] table
OBJECTIVES = ("comfort_margin", "peak_reaction_max", "amplification_max", "roller_deflection_max",
              "body_deflection_max", "resonance_detuning")


def _check_objective(sweep: dict, path: str) -> None:
    quantity = (sweep["objective"] or {}).get("quantity")
    if quantity == "y" and sweep["y"] is None:
        raise SceneError(f"{path}.objective.quantity", "y is not swept: give [sweep.y], or objective x")


SWEEP = s.Table("the swept plane of a design sweep (used by `symmech sweep`; `symmech run` ignores it)", {
    **core_sweep.plane_fields(AXIS),
    "limits": s.Table("stated limits of the peak reactions (largest magnitudes) of P0…P5; a point beyond "
                      "one is outside the admissible region", {name: s.Float(f"largest admissible magnitude of "
                                                                             f"{name}", unit="N", lo=0.0,
                                                           lo_open=True, hi=1e12, default=None)
                                             for name in REACTIONS}, default={}),
    "objective": s.Table("what the best point is best at; only admissible points are eligible (default: the "
                         "largest comfort margin)", {
        "quantity": s.Choice("`x` or `y`: the swept value; else a design number of the sweep table",
                             choices=("x", "y") + OBJECTIVES, default="comfort_margin"),
        "goal": s.Choice("whether the best point has the largest or the smallest of it", choices=("max", "min"),
                         default="max"),
    }, default=None),
}, default=None, checks=(core_sweep.check_plane, _check_objective))


def edits(field: str, resolved: dict, value: float, where: str) -> list[tuple[tuple, object]]:
    """The raw-scene entries (keys path, value) that setting the swept ``field`` to ``value`` writes, from the
    base scene's ``resolved`` fields; a SceneError naming ``where`` (the axis's field) when the scene has
    nothing the field could change."""
    head, _, rest = field.partition(".")
    if field == "motion.speed_scale":
        if resolved["motion"]["speed"] is None:
            raise SceneError(where, "motion.speed_scale multiplies motion.speed; this scene is driven by "
                                    "motion.traction")
        return [(("motion", "speed"), f"({value!r})*({resolved['motion']['speed']})")]
    if head == "motion":
        name = rest.removeprefix("constants.")
        if name not in resolved["motion"]["constants"]:
            have = ", ".join(resolved["motion"]["constants"]) or "none"
            raise SceneError(where, f"{field}: the scene's motion.constants has no {name!r} (it has: {have})")
        return [(("motion", "constants", name), value)]
    if head == "comfort":  # one end of the envelope: the plan's base holds the other (:func:`plan`)
        axis, end = rest.split(".")
        return [(("comfort", axis, ("lo", "hi").index(end)), value)]
    if head == "trolley":
        return [(("trolley", "mass"), value)]
    if resolved["elastic"] is None:
        raise SceneError(where, f"{field}: the scene has no [elastic] table")
    if rest.startswith("rollers."):
        if resolved["elastic"]["rollers"] is None:
            raise SceneError(where, f"{field}: the scene has no [elastic.rollers] table")
        key, scale = rest.removeprefix("rollers.").removesuffix("_scale"), rest.endswith("_scale")
        base = resolved["elastic"]["rollers"][key]
        return [(("elastic", "rollers", key), [b * value for b in base] if scale else [value] * 5)]
    index, key = re.fullmatch(r"beams\[([0-9]+)\]\.(\w+)", rest).groups()
    beams = resolved["elastic"]["beams"]
    if int(index) >= len(beams):
        raise SceneError(where, f"{field}: beam {index} is not a beam index ({len(beams)} beams given)")
    if key == "ei_scale":
        return [(("elastic", "beams", int(index), "ei"), [e * value for e in beams[int(index)]["ei"]])]
    return [(("elastic", "beams", int(index), key), value)]


def _write(data: dict, keys: tuple, value) -> None:
    node = data
    for key in keys[:-1]:
        node = node.setdefault(key, {}) if isinstance(key, str) else node[key]
    node[keys[-1]] = value


@dataclass
class Plan:
    """The sweep's plane over a base trolley scene: point (i, j) is ``base`` with :meth:`point`'s edits."""

    x: dict
    y: dict | None
    base: dict  # the raw scene without [sweep]
    resolved: dict  # the base scene's resolved fields
    limits: dict  # {"P3": N, ...}: the stated reaction limits
    objective: tuple[str, str] = ("comfort_margin", "max")  # (x, y or a design number; "max" or "min")

    @property
    def values(self) -> tuple[np.ndarray, np.ndarray]:
        """The swept values along x and y ([nan] without y)."""
        return core_sweep.axis_values(self.x), core_sweep.axis_values(self.y) if self.y else np.array([np.nan])

    @property
    def shape(self) -> tuple[int, int]:
        return tuple(len(v) for v in self.values)

    @property
    def axes(self) -> list[tuple[str, dict]]:
        return [("x", self.x)] + ([("y", self.y)] if self.y else [])

    def point(self, i: int, j: int) -> dict:
        """The raw scene of point (i, j)."""
        data = copy.deepcopy(self.base)
        for (name, axis), value in zip(self.axes, (self.values[0][i], self.values[1][j])):
            for keys, v in edits(axis["field"], self.resolved, float(value), f"sweep.{name}.field"):
                _write(data, keys, v)
        return data

    def load(self, i: int, j: int, whole: bool = True):
        """``pipeline.load`` of point (i, j) (``whole``; else only the scene's tables the axes set, by their
        schema); its SceneError renamed to the axis whose value it refuses."""
        from symmech.core import pipeline, registry

        data = self.point(i, j)
        try:
            if whole:
                return pipeline.load(data)
            fields = registry.get("trolley").schema.fields
            for head in {keys[0] for _, axis in self.axes for keys in targets(axis["field"], self.resolved)}:
                fields[head].resolve(head, True, data[head])
        except SceneError as exc:
            xs, ys = self.values
            for (name, axis), value in zip(self.axes, (xs[i], ys[j])):
                names = [core_sweep.dotted(keys) for keys in targets(axis["field"], self.resolved)]
                if any(_within(exc.field, t) or _within(t, exc.field) for t in names):
                    raise SceneError(f"sweep.{name}", f"{axis['field']} = {value:g}: {exc.field}: "
                                                      f"{str(exc).partition(': ')[2]}") from None
            raise


def _within(field: str, entry: str) -> bool:
    """Whether the dotted ``field`` is the scene entry ``entry`` or lies inside it."""
    return field == entry or field.startswith((f"{entry}.", f"{entry}["))


def targets(field: str, resolved: dict) -> list[tuple]:
    """The key paths of the scene entries the swept ``field`` sets (its alias, scale or index spelling
    resolved: ``elastic.beams[00].ei_scale`` sets ``("elastic", "beams", 0, "ei")``)."""
    return [keys for keys, _ in edits(field, resolved, 1.0, "")]


def plan(raw: dict, resolved: dict) -> Plan:
    """The plan of a trolley scene with a ``[sweep]`` table; the swept fields checked against the scene."""
    sweep = resolved["sweep"]
    if sweep is None:
        raise SceneError("sweep", "the scene has no [sweep] table (see docs/scenes-trolley.md)")
    base = {k: v for k, v in copy.deepcopy(raw).items() if k != "sweep"}
    limits = {k: v for k, v in sweep["limits"].items() if v is not None}
    objective = sweep["objective"] or {"quantity": "comfort_margin", "goal": "max"}
    if objective["quantity"] in OBJECTIVES[2:] and resolved["elastic"] is None:
        raise SceneError("sweep.objective.quantity", f"{objective['quantity']} is a number of the elastic model; "
                                                     "this scene has no [elastic] table")
    p = Plan(sweep["x"], sweep["y"], base, resolved, limits, (objective["quantity"], objective["goal"]))
    for name, axis in p.axes:
        edits(axis["field"], resolved, float(core_sweep.axis_values(axis)[0]), f"sweep.{name}.field")
        if axis["field"].startswith("comfort."):  # the swept end's partner, as the scene gives it
            envelope = axis["field"].split(".")[1]
            base.setdefault("comfort", {})[envelope] = list(resolved["comfort"][envelope])
    core_sweep.check_disjoint([(f"sweep.{name}.field", axis["field"], targets(axis["field"], resolved))
                               for name, axis in p.axes])
    return p


def validate(p: Plan):
    """The plane checked before any run, at a cost independent of its number of points: both ends of each
    comfort envelope at every point (:func:`check_envelopes`), each value of each axis (the other at its first
    value) against the scene's tables it sets, the corners as whole scenes (schema, prepare). Returns the loaded
    scene of point (0, 0)."""
    nx, ny = p.shape
    check_envelopes(p)
    for i in range(1, nx):
        p.load(i, 0, whole=False)
    for j in range(1, ny):
        p.load(0, j, whole=False)
    first = p.load(0, 0)
    for i, j in {(nx - 1, 0), (0, ny - 1), (nx - 1, ny - 1)} - {(0, 0)}:
        p.load(i, j)
    return first


def check_envelopes(p: Plan) -> None:
    """lo < hi of every comfort envelope an axis sets one end of, at every point of the plane."""
    xs, ys = p.values
    for envelope in AXES:
        ends = [np.full(p.shape, bound) for bound in p.resolved["comfort"][envelope]]
        swept = {}
        for (name, axis), grid in zip(p.axes, np.meshgrid(xs, ys, indexing="ij")):
            head, _, rest = axis["field"].partition(".")
            if head == "comfort" and rest.startswith(envelope):
                end = ("lo", "hi").index(rest.split(".")[1])
                ends[end], swept[end] = grid, name
        bad = np.argwhere(~(ends[0] < ends[1]))
        if swept and bad.size:
            i, j = bad[0]
            lo, hi = ends[0][i, j], ends[1][i, j]
            name = swept.get(0, swept.get(1))
            raise SceneError(f"sweep.{name}", f"comfort.{envelope} = [{lo:g}, {hi:g}] g at point ({i}, {j}) of the "
                                              "plane: the envelope [lo, hi] must be increasing (lo < hi)")


def comfort_margin(overload: np.ndarray, envelope: dict) -> float:
    """The least signed distance [g] of the overloads ``overload`` (n, 3) [g] to the box ``envelope``
    ({axis: (lo, hi)} along x1, x2, x3): inside, the distance to the nearest face (> 0); outside, minus
    the Euclidean distance to the box."""
    lo, hi = (np.array([envelope[a][k] for a in AXES]) for k in (0, 1))
    excess = np.maximum(np.maximum(lo - overload, overload - hi), 0.0)
    outside = np.sqrt((excess**2).sum(-1))
    inside = np.minimum(overload - lo, hi - overload).min(-1)
    return float(np.where(outside > 0, -outside, inside).min())


def _peaks(table: Table, suffix: str = "") -> np.ndarray:
    return np.array([np.abs(table.column(f"{name}{suffix}")).max() for name in REACTIONS])


def point_metrics(res: Result, comfort: dict) -> tuple[list[Column], list[float], dict[str, str]]:
    """The design numbers of one trolley run ``res`` (its tables) with the comfort envelope ``comfort``:
    columns, values and text values (the closest resonance's forcing and mode)."""
    t = res.tables
    elastic = "elastic_reactions" in t and "P0_rigid" in [c.name for c in t["elastic_reactions"].columns]
    case = "case2" if "case2" in t else "case1"
    peak = _peaks(t["elastic_reactions"]) if elastic else _peaks(t[case])
    model = "elastic model" if elastic else "rigid model"
    out = [(Column(f"peak_{n}", "N", f"largest |{n}| ({model})"), p) for n, p in zip(REACTIONS, peak)]
    out.append((Column("peak_reaction_max", "N", f"largest |P1…P5| ({model})"), peak[1:].max()))
    text = {}
    if elastic:
        rigid = _peaks(t["elastic_reactions"], "_rigid")
        amp = np.divide(peak, rigid, out=np.full(6, np.nan), where=rigid > 0)
        out += [(Column(f"amplification_{n}", "1", f"dynamic amplification: elastic / rigid peak |{n}|"), a)
                for n, a in zip(REACTIONS, amp)]
        out.append((Column("amplification_max", "1", "largest dynamic amplification of P0…P5"), np.nanmax(amp)))
    if "roller_deflections" in t:
        from symmech.trolley.elastic.scene import DEFLECTIONS

        d = t["roller_deflections"].select([c.name for c in DEFLECTIONS])
        out.append((Column("roller_deflection_max", "m", "largest roller deflection |d1…d5|"), np.abs(d).max()))
    names = [c.name[:-3] for c in t["points"].columns if c.name.endswith("_n1")] if "points" in t else []
    if names:
        pts = t["points"]
        e = np.array([np.linalg.norm(np.column_stack([pts.column(f"{n}_e{k}") for k in (1, 2, 3)]), axis=1)
                      for n in names])
        out.append((Column("body_deflection_max", "m", "largest elastic deflection of a report point"), e.max()))
        series = {n: np.column_stack([pts.column(f"{n}_n{k}") for k in (1, 2, 3)]) for n in names}
    else:
        series = {"com": t[f"{case}_overload"].select(("n1", "n2", "n3"))}
    margins = {n: comfort_margin(v, comfort) for n, v in series.items()}
    where = "report point" if names else "centre of mass (rigid model)"
    out += [(Column(f"comfort_margin_{n}", "g", f"least distance of the {where} {n}'s overload to the comfort "
                    "envelope (< 0: outside)"), m) for n, m in margins.items()]
    out.append((Column("comfort_margin", "g", "least comfort margin of all points"), min(margins.values())))
    if "modes" in t:
        resonance, text = _closest_resonance(t["modes"])
        out += resonance
    cols, values = zip(*out)
    return list(cols), [float(v) for v in values], text


def _closest_resonance(modes: Table) -> tuple[list, dict]:
    """The (sample, mode, forcing) of the modes table whose natural frequency is nearest, relatively, to a
    positive forcing frequency."""
    from symmech.trolley.elastic.body import FORCING

    f = modes.column("f")[:, None]
    forcing = np.column_stack([modes.column(f"forcing_{name}") for name, _ in FORCING])
    with np.errstate(divide="ignore", invalid="ignore"):
        detuning = np.where((forcing > 0) & (f > 0), np.abs(f / forcing - 1), np.inf)
    row, k = np.unravel_index(int(np.argmin(detuning)), detuning.shape)
    found = np.isfinite(detuning[row, k])
    pick = lambda v: v if found else math.nan  # noqa: E731  no positive forcing at all: no resonance
    out = [(Column("resonance_detuning", "1", "closest resonance: |f / f_forcing - 1|"), pick(detuning[row, k])),
           (Column("resonance_f", "Hz", "its natural frequency"), pick(f[row, 0])),
           (Column("resonance_forcing_f", "Hz", "its forcing frequency"), pick(forcing[row, k])),
           (Column("resonance_mode", "1", "its mode_id (the modes table's)"), pick(modes.column("mode_id")[row])),
           (Column("resonance_t", "s", "when it is closest"), pick(modes.column("t")[row])),
           (Column("resonance_s", "m", "where on the track it is closest"), pick(modes.column("s")[row]))]
    text = {"resonance_forcing": FORCING[k][0] if found else "none",
            "resonance_component": modes.text["component"][row] if found else "none"}
    return out, text


def evaluate(p: Plan, i: int, j: int, until: float):
    """A task: point (i, j) of the plan ``p`` built here, run through the scene's own path until the wall-clock
    time ``until`` (:func:`symmech.core.sweep.deadline`) and reduced to its design numbers
    (:func:`point_metrics`) and what needs attention (its warnings and the checks that did not pass, as a single run
    lists them); ("failed", message) when the run stops with a user error. BLAS runs on one
    thread, as on a dask worker: a multi-threaded product rounds differently, and the numbers of a point
    must not depend on where it ran (nor a process pool oversubscribe the cores)."""
    from threadpoolctl import threadpool_limits

    from symmech.core import pipeline
    from symmech.core.scene import SymmechError

    try:
        with threadpool_limits(limits=1):
            scene = pipeline.load(p.point(i, j))
            res = scene.run(core_sweep.point_context(until))
    except SymmechError as exc:
        return "failed", str(exc)
    attention = res.warnings + [c.text() for c in res.checks if c.verdict != "pass"]
    return "ok", *point_metrics(res, scene.setup.comfort), attention


def run(source, out, ctx, scheduler: str | None = None, workers: int | None = None,
        connect_timeout: float = core_sweep.CONNECT_TIMEOUT) -> Result:
    """``symmech sweep`` of a trolley scene: validate the plane, estimate from counts and from the first
    point's run, compute the rest, write."""
    from symmech.core import pipeline
    from symmech.core.scene import read_toml

    raw = source if isinstance(source, dict) else read_toml(source)
    scene = pipeline.load(source, raw)
    p = plan(raw, scene.resolved)
    first = validate(p)
    outcomes = compute(p, scheduler, core_sweep.workers(workers, scheduler), connect_timeout, ctx, first)
    res = result(p, outcomes)
    scene.cost = ctx.estimates[-1]  # the summary's estimate: the sweep's last
    pipeline.write(res, out, scene)
    return res


def estimate(first, points: int, processes: int):
    """The sweep's cost from counts (a ``registry.Estimate``): the kind's estimate of the loaded point scene
    ``first`` on the engine the sweep runs, its one-off part (a compile) once, the rest ``points`` times,
    shared by ``processes``."""
    from symmech.core import registry

    cost = first.kind.estimate(_on_sweep_engine(first.setup, points))
    seconds = cost.once + (cost.seconds - cost.once) * points / processes
    return registry.Estimate(seconds, f"from counts: {points} points at ~{cost.seconds - cost.once:.3g} s "
                                      f"({cost.what}) on {processes} worker(s)", cost.once)


def cheapest(first, points: int, processes: int):
    """A lower bound of :func:`estimate` (a ``registry.Estimate``): every point on the elastic model's cheapest
    engine, nothing compiled. It reads no engine's state, so refusing on it loads no numba."""
    from symmech.core import registry
    from symmech.trolley.elastic import scene as elastic_scene

    setup = first.setup
    per_point = first.kind.estimate(replace(setup, elastic=None)).seconds
    if setup.elastic is not None and setup.elastic.system is not None:
        per_point += min(elastic_scene.SECONDS_PER_STEP.values()) * (len(setup.t) - 1)
    return registry.Estimate(per_point * points / processes, f"from counts: {points} points at ~{per_point:.3g} s "
                                                              f"or more each, on the cheapest engine without a "
                                                              f"compile, on {processes} worker(s)")


def compute(p: Plan, scheduler: str | None = None, processes: int = 1,
            connect_timeout: float = core_sweep.CONNECT_TIMEOUT, ctx=None, first=None) -> list:
    """The outcome of :func:`evaluate` per point, x-major: refused past ``ctx.max_time`` from counts
    (:func:`estimate`: nothing built or run yet), then point (0, 0) run here and timed for the estimate of the
    rest, the others on Dask (:func:`symmech.core.sweep.compute`), all against the deadline of ``ctx``.
    ``first``: the loaded scene of point (0, 0) (:func:`validate`'s)."""
    from symmech.core import registry
    from symmech.core.context import Context

    ctx = ctx or Context(quiet=True)
    first = first or p.load(0, 0)
    points = int(np.prod(p.shape))
    least = cheapest(first, points, processes)
    if ctx.elapsed() + least.seconds > ctx.max_time:  # refused before any engine's state is read (numba unloaded)
        core_sweep.refuse(least, ctx)
    cost = estimate(first, points, processes)
    core_sweep.refuse(cost, ctx, tell=cost.once > 0)
    warm = _compiled_needed(first, points)
    if warm:  # built here first (its cost is in the estimate): each point then runs it
        _warm_worker(ctx.say)
    until = core_sweep.deadline(ctx)
    cells = list(np.ndindex(*p.shape))
    # the first point pays loading the engine, as each worker's first does; a second, the grid's middle, costs
    # what the rest cost (the first point's time for every point overestimated the elastic sweep 2.3x)
    outcome, first = _timed(p, cells[0], until)
    done, took = {0: outcome}, first
    if points > 2:
        done[points // 2], took = _timed(p, cells[points // 2], until)
    startup = core_sweep.startup_seconds(scheduler, max(first - took, 0.0))
    charts = chart_count(outcome)
    drawing = charts * core_sweep.chart_seconds(p.shape)
    rest = [k for k in range(points) if k not in done]
    core_sweep.refuse(registry.Estimate(startup + took * len(rest) / processes + drawing,
                                        f"{points} points at {took:.3g} s (timed here) on {processes} "
                                        f"worker(s), {startup:.3g} s to start them, up to {charts} charts at "
                                        f"{drawing / charts:.3g} s"), ctx)
    import dask  # after the refusals: a refused sweep loads no Dask

    shared = dask.delayed(p, pure=True)  # one node of the graph: each task builds its own point scene
    tasks = [dask.delayed(evaluate)(shared, *cells[k], until, dask_key_name=f"point-{cells[k][0]}-{cells[k][1]}")
             for k in rest]
    values = dict(zip(rest, core_sweep.compute(tasks, scheduler, processes, connect_timeout, ctx,
                                               on_workers=_warm_worker if warm else None, after=drawing)))
    return [done[k] if k in done else values[k] for k in range(points)]


def chart_count(outcome) -> int:
    """The charts a sweep can draw whose first point's :func:`evaluate` gave ``outcome``: those of
    :data:`CHARTS` its model has (the rigid model two of six); all if it failed."""
    if outcome[0] != "ok":
        return len(CHARTS)
    names = {c.name for c in outcome[1]}
    return sum(name in names for name, *_ in CHARTS)


def _timed(p: Plan, cell: tuple[int, int], until: float):
    """(:func:`evaluate`'s outcome at ``cell``, its wall time [s])."""
    started = time.perf_counter()
    outcome = evaluate(p, *cell, until)
    return outcome, time.perf_counter() - started


def _on_sweep_engine(setup, points: int):
    """The trolley ``setup`` with its elastic model's engine the one the sweep's ``points`` runs choose
    (``auto`` weighs a compile against the Python engine over all of them)."""
    from symmech.trolley.elastic import scene as elastic_scene

    elastic = setup.elastic
    if elastic is None or elastic.system is None:
        return setup
    return replace(setup, elastic=replace(elastic, engine=elastic_scene.engine(elastic, runs=points)[0]))


def _compiled_needed(first, points: int) -> bool:
    """Whether the points run the compiled elastic engine (the swept fields choose no engine)."""
    elastic = _on_sweep_engine(first.setup, points).elastic
    return elastic is not None and elastic.system is not None and elastic.engine == "compiled"


def _warm_worker(say=None) -> None:
    """The compiled elastic engine built once per machine (other processes wait on the build lock)."""
    engines.get("elastic").builder().warm(say=say)


# Charts over the plane: (column, title, whether larger is worse)
CHARTS = (("comfort_margin", "least comfort margin", False),
          ("amplification_max", "largest dynamic amplification of the reactions", True),
          ("peak_reaction_max", "largest roller reaction |P1…P5|", True),
          ("roller_deflection_max", "largest roller deflection", True),
          ("body_deflection_max", "largest body deflection", True),
          ("resonance_detuning", "closest resonance |f / f_forcing - 1|", False))
# A design number whose spread over the plane is below this fraction of its magnitude is stated, not charted: the
# peaks are read off the output samples, whose spacing alone moves them by more than that.
FLAT_RTOL = 1e-3


def _number(x) -> float | None:
    return float(x) if math.isfinite(x) else None


def _worst_best(values: np.ndarray, larger_is_worse: bool) -> tuple[int, int]:
    """Flat indices of the worst and best finite values (NaN, failed points, left out)."""
    v = np.where(np.isfinite(values), values, np.nan)
    hi, lo = int(np.nanargmax(v)), int(np.nanargmin(v))
    return (hi, lo) if larger_is_worse else (lo, hi)


# (pattern of a single run's warning or check, its short label on a chart cell)
ATTENTION = ((r"sampled at|samples per period", "output sampling"), (r"natural frequenc", "resonance"),
             (r"energy balance", "energy balance"), (r"small-rotation", "roller rotation"),
             (r"small-angle", "small-angle range"), (r"consistent order", "model order"),
             (r"opposite sign of the rigid", "sign vs rigid"))


def reasons(row: dict, attention: list[str], limits: dict) -> list[tuple[str, str]]:
    """Why a point is not admissible, as (short label for a chart cell, sentence) pairs: its comfort margin below
    0, a reaction beyond its stated limit, a roller reaction changing sign (lift-off), any other warning or
    check that did not pass (``attention``: a single run's). Empty: admissible. ``row``: its design numbers."""
    out = []
    if row["comfort_margin"] < 0:
        out.append(("comfort", f"leaves the comfort envelope by {-row['comfort_margin']:.3g} g"))
    for name, limit in limits.items():
        if row[f"peak_{name}"] > limit:
            out.append((f"{name} limit", f"|{name}| reaches {row[f'peak_{name}']:.4g} N > limit {limit:.4g} N"))
    lifted = sorted(set(re.findall(r"(P[0-9]) changes sign", " ".join(attention))))
    if lifted:
        out.append(("lift-off", f"roller reaction {', '.join(lifted)} changes sign: the roller would lift off"))
    # the lift-off warnings and their check ("... changing sign"), the comfort check: reasons of their own above
    rest = [a for a in attention if not re.search(r"chang(es|ing) sign|comfort envelope", a)]
    out += [(next((label for pattern, label in ATTENTION if re.search(pattern, a)), "check"), a) for a in rest]
    return out


def result(p: Plan, outcomes: list) -> Result:
    """Table ``sweep`` (one row per point, x-major, with its verdict), the decision (:func:`decide`: best
    admissible point for the objective, the admissible region, what limits the rest) as summary, headline and
    checks, the charts with the same best point, and the design numbers too flat to chart stated instead."""
    xs, ys = p.values
    X, Y = np.meshgrid(xs, ys, indexing="ij")
    base_cols = [Column(name, unit_of(axis), f"swept field {axis['field']}") for name, axis in p.axes]
    base = np.column_stack([X.ravel()] + ([Y.ravel()] if p.y else []))
    done = [o for o in outcomes if o[0] == "ok"]
    if not done:
        raise SceneError("sweep", f"every point failed; first: {outcomes[0][1]}")
    cols, _, text0, _ = done[0][1:]
    names = [c.name for c in cols]
    rows = np.array([o[2] if o[0] == "ok" else [math.nan] * len(cols) for o in outcomes])
    why = [[("failed", f"the run stopped: {o[1]}")] if o[0] != "ok" else
           reasons(dict(zip(names, o[2])), o[4], p.limits) for o in outcomes]
    ok = np.array([not w for w in why])
    text = {key: [o[3][key] if o[0] == "ok" else "failed" for o in outcomes] for key in text0}
    text["verdict"] = ["admissible" if not w else "; ".join(sentence for _, sentence in w) for w in why]
    metric = Table(cols, rows)
    table = Table(base_cols + cols + [Column("admissible", "1", "1: comfort margin ≥ 0, the reactions within the "
                                                                 "stated limits, no warning and no check failed")],
                  np.column_stack([base, rows, ok.astype(float)]), "design numbers over the swept plane", text,
                  grid={c.name: c.name for c in base_cols})

    def at(k: int) -> dict:
        point = {"index": [int(v) for v in np.unravel_index(k, p.shape)][:len(p.axes)]}
        point |= {c.name: float(base[k, n]) for n, c in enumerate(base_cols)}
        point |= {c.name: _number(rows[k, n]) for n, c in enumerate(cols)} | {key: text[key][k] for key in text}
        return point | {"admissible": bool(ok[k])}

    extremes = {}
    for name, _, larger in CHARTS:
        if name in names:
            worst, best = _worst_best(metric.column(name), larger)
            extremes[name] = {"worst": at(worst), "best": at(best)}
    flat = {name: statement for name, title, _ in CHARTS if name in names
            for statement in [core_sweep.flat_statement(metric.column(name), title, unit_of_column(cols, name),
                                                        FLAT_RTOL)] if statement}
    decision = decide(p, table, ok, why)
    best = decision["best"]
    failed = [{"index": [int(v) for v in np.unravel_index(k, p.shape)][:len(p.axes)], "error": o[1]}
              for k, o in enumerate(outcomes) if o[0] != "ok"]
    warned = [{"index": [int(v) for v in np.unravel_index(k, p.shape)][:len(p.axes)], "warnings": len(o[4]),
               "first": o[4][0]} for k, o in enumerate(outcomes) if o[0] == "ok" and o[4]]
    summary = {"points": len(outcomes), "swept": [axis["field"] for _, axis in p.axes],
               "units": [unit_of(axis) for _, axis in p.axes], "limits_N": p.limits,
               "criterion": decision["objective"], "decision": {**decision, "best": None if best is None else at(best)},
               "worst_point": extremes["comfort_margin"]["worst"],
               "best_point": None if best is None else at(best), "extremes": extremes, "flat": flat,
               "admissible_points": int(ok.sum()), "failed_points": failed, "warned_points": warned,
               "captions": {f"sweep_{name}": caption(p, title) for name, title, _ in CHARTS
                            if name in names and name not in flat}}
    headline, checks, warnings = answer(p, table, decision, flat)
    charts = [(name, title, unit_of_column(cols, name)) for name, title, _ in CHARTS if name in names
              and name not in flat]
    axes = [(name_of(axis), unit_of(axis), axis["log"]) for _, axis in p.axes]
    return Result("trolley_sweep", summary, {"sweep": table}, warnings=warnings, headline=headline, checks=checks,
                  plots=lambda folder: sweep_plots.plots(p.values, axes, table, ok, why, best, charts, folder))


def unit_of_column(cols: list[Column], name: str) -> str:
    return next(c.unit for c in cols if c.name == name)


def caption(p: Plan, title: str) -> str:
    """A chart's caption, as a sentence."""
    over = " and ".join(name_of(axis) for _, axis in p.axes)
    if p.y is None:
        return (f"The {title} along {over}. The star is the best admissible point for the objective; the green "
                "band holds the admissible points, the others are labelled with what limits them.")
    return (f"The {title} over {over}. The star is the best admissible point for the objective; hatched cells are "
            "not admissible, labelled with what limits them.")


def objective_text(p: Plan) -> str:
    quantity, goal = p.objective
    what = name_of(p.x if quantity == "x" else p.y) if quantity in ("x", "y") else quantity
    return f"{'largest' if goal == 'max' else 'smallest'} {what}"


def objective_values(p: Plan, table: Table) -> np.ndarray:
    """The objective per point, signed so that larger is better."""
    quantity, goal = p.objective
    if quantity not in [c.name for c in table.columns]:
        raise SceneError("sweep.objective.quantity", f"{quantity}: this sweep's points have no such design number "
                                                     f"(they have: {', '.join(n for n, *_ in CHARTS)})")
    v = table.column(quantity)
    return v if goal == "max" else -v


def decide(p: Plan, table: Table, ok: np.ndarray, why: list) -> dict:
    """The decision: the best admissible point (flat index, or None) for the plan's objective, the admissible
    region (count and bounds of each swept value), and per reason the points it excludes and where."""
    score = np.where(ok & np.isfinite(objective_values(p, table)), objective_values(p, table), -np.inf)
    best = int(np.argmax(score)) if np.isfinite(score).any() else None
    swept = [c.name for c in table.columns][:len(p.axes)]

    def bounds(mask) -> dict:
        return {name: [float(table.column(name)[mask].min()), float(table.column(name)[mask].max())]
                for name in swept}

    limited = {}
    for k, w in enumerate(why):
        for label in dict.fromkeys(label for label, _ in w):
            limited.setdefault(label, []).append(k)
    return {"objective": objective_text(p), "best": best,
            "admissible": {"count": int(ok.sum()), "of": int(ok.size), "bounds": bounds(ok) if ok.any() else None},
            "limited_by": [{"reason": label, "points": len(ks), "bounds": bounds(np.isin(np.arange(ok.size), ks)),
                            "first": why[ks[0]][[lbl for lbl, _ in why[ks[0]]].index(label)][1]}
                           for label, ks in sorted(limited.items(), key=lambda kv: -len(kv[1]))]}


def _where(p: Plan, bounds: dict) -> str:
    parts = []
    for name, axis in p.axes:
        lo, hi = bounds[name]
        unit = unit_of(axis)
        parts.append(f"{name_of(axis)} {units.format(lo, unit)}" if lo == hi else
                     f"{name_of(axis)} {units.format(lo, unit)} … {units.format(hi, unit)}")
    return ", ".join(parts)


def answer(p: Plan, table: Table, decision: dict, flat: dict):
    """(headline, checks, warnings) of a sweep: its decision first, as a single run's answers read."""
    from symmech.core.results import Check, Headline

    quantity = p.objective[0]
    headline, best = [], decision["best"]
    n, total = decision["admissible"]["count"], decision["admissible"]["of"]
    if best is not None:
        point = {name: float(table.column(name)[best]) for name, _ in p.axes}
        where = _where(p, {name: (v, v) for name, v in point.items()})
        unit = unit_of(p.x if quantity == "x" else p.y) if quantity in ("x", "y") else unit_of_column(table.columns,
                                                                                                      quantity)
        value = table.column(quantity)[best]
        admissible = table.column("admissible") == 1
        tied = int(np.count_nonzero(admissible & (table.column(quantity) == value)))
        headline.append(Headline(f"best point: {decision['objective']}", float(value), unit,
                                 f"the {decision['objective']} of the {n} admissible points (no warning, no "
                                 "failed check, comfort and the stated limits kept); its cell reaches halfway "
                                 "to the neighbouring values" + (f"; {tied} admissible points share this value, the "
                                                                 "first in sweep order is starred" if tied > 1 else ""),
                                 where))
    headline.append(Headline("admissible points", float(n), "1", f"of {total}: "
                             + (_where(p, decision["admissible"]["bounds"]) if n else "none"), ""))
    headline += [Headline(s["text"].partition(":")[0], s["value"], s["unit"], s["text"].partition(": ")[2],
                          "every point") for s in flat.values()]
    checks = [Check("points admissible (no warning, no failed check, within the limits)", float(n), "1", "> 0",
                    "pass" if n else "fail")]
    warnings = [f"{c['points']} of {total} point(s) limited by {c['reason']} at {_where(p, c['bounds'])}; "
                f"first: {c['first']}" for c in decision["limited_by"]]
    return headline, checks, warnings
