"""Scene kind ``trolley``: prepare, estimate, run and precision (see docs/scenes-trolley.md); its schema is
:mod:`symmech.trolley.schema`.

``run`` returns a :class:`~symmech.core.results.Result` with the tables ``case1``
(and ``case2`` with the local-curvature effect): t, V1..V3, a1..a3, P0..P5 (SI,
body-frame components of the centre of mass), and ``caseN_overload`` (t, n1..n3 in
g); the plots ``track.png``, ``reactions.png``, ``overloads.png``; with
``report.paper_tables`` the file ``paper_tables.txt``; with an ``[elastic]`` table the
elastic model's tables, summary, warnings and plots beside them (:mod:`.elastic.scene`).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from symmech.core import expressions, plotting, registry
from symmech.core.context import Context
from symmech.core.results import Column, Headline, Result, Table, at_most, within
from symmech.core.scene import SceneError, SymmechError
from symmech.trolley import model, plots, tables, track as tracks
from symmech.trolley.comfort import COMFORT, comfort_warning
from symmech.trolley.schema import MAX_LENGTH, MAX_SPEED, SCHEMA
from symmech.trolley import sweep as design_sweep

ROLE = "kind"  # found by symmech.core.discovery

# Measured on 2 cores (helix, 200000 steps): wall time per grid step and frame evaluation,
# per grid step and case for the CSV files and plots, and per traction right-hand side.
SECONDS_PER_STEP = 5e-6
SECONDS_PER_OUTPUT_ROW = 9e-5
SECONDS_PER_RHS = 2e-4
MAX_RHS = 2_000_000  # traction right-hand sides before the integration counts as stalled


@dataclass
class Setup:
    """Everything a run needs, built and checked from the resolved scene."""

    track: tracks.Track
    body: model.Body
    frame: str
    conventions: str
    t: np.ndarray
    speed: object  # (V0(t), dV0/dt(t)) callables, or None with traction
    traction: object  # callable (t, V0) -> P0, or None
    v_initial: float
    s0: float
    local_curvature: bool
    fd_order: int
    fd_step: float
    lstar_derivative: str
    small_angle_limit: float
    comfort: dict
    paper_tables: bool
    plan: model.FramePlan = None
    notes: list = None
    elastic: elastic_scene.Setup | None = None  # noqa: F821 (imported where an [elastic] table is prepared)
    output: dict = None  # the resolved [output] table: plots and formats

    def frames(self, case: int) -> model.TrackFrames:
        """The frame along the track of case 1 or 2 (the chord between the axles), as a function of s."""
        return model.TrackFrames(self.track, self.body.l, self.frame, case != 1, self.fd_order, self.fd_step, self.plan)


def _time_functions(field: str, text: str, variables: tuple[str, ...], t_end: float, constants: dict):
    """Numeric f and df/dt of an expression field in ``variables`` (t first) and ``constants`` (name:
    number), checked over t ∈ [0, t_end] (and, for traction, v ∈ [0, MAX_SPEED])."""
    expr = expressions.parse(field, text, variables, constants)
    t = expressions.symbol("t")
    rate = expressions.derivatives(field, expr, "t", 1)[1]
    fixed = [{}] if len(variables) == 1 else [{expressions.symbol("v"): v} for v in np.linspace(0, MAX_SPEED, 9)]
    for subs in fixed:
        expressions.check_domain(field, expr.subs(subs), "t", 0.0, t_end, unit="s")
        expressions.check_domain(field, rate.subs(subs), "t", 0.0, t_end, unit="s", guards=False)
    if len(variables) == 2:
        for t_val in np.linspace(0.0, t_end, 5):
            expressions.check_domain(field, expr.subs(t, t_val), "v", 0.0, MAX_SPEED, unit="m/s")
    both = tracks.lambdify_arrays([expr, rate], [expressions.symbol(v) for v in variables])
    if len(variables) == 1:
        grid = np.linspace(0.0, t_end, 2001)
        fast = np.abs(both(grid)[0]) > MAX_SPEED
        if fast.any():
            raise SceneError(field, f"|V0| = {abs(both(grid)[0][np.argmax(fast)]):.3g} m/s at t = "
                                    f"{grid[np.argmax(fast)]:.6g} s exceeds {MAX_SPEED:g} m/s")
    return (lambda *a: both(*a)[0]), (lambda *a: both(*a)[1])


def prepare(scene: dict) -> Setup:
    """The Setup of a resolved scene: track and body built, every expression checked over
    the run's time range and the track over the arc lengths the run visits, the frame
    made continuous along them (see :func:`model.plan_frames`)."""
    tr_spec, body_spec, motion, num = scene["track"], scene["trolley"], scene["motion"], scene["numerics"]
    effects = scene["effects"]
    t_end, steps = scene["time"]["t_end"], scene["time"]["steps"]
    track = tracks.build(tr_spec)
    axle = body_spec["axle_distance"]
    body = model.Body(body_spec["mass"], tuple(body_spec["com"]), tuple(body_spec["inertia"]), axle,
                      body_spec["half_gauge"], scene["constants"]["g0"] if effects["gravity"] else 0.0)
    speed = traction = None
    if effects["traction"]:
        traction = _time_functions("motion.traction", motion["traction"], ("t", "v"), t_end,
                                   motion["constants"])[0]
    else:
        speed = _time_functions("motion.speed", motion["speed"], ("t",), t_end, motion["constants"])
    setup = Setup(track, body, scene["frame"], scene["conventions"], np.linspace(0.0, t_end, steps + 1), speed,
                  traction, motion["initial_speed"], motion["s0"], effects["local_curvature"], num["fd_order"],
                  num["fd_step"] if num["fd_step"] is not None else min(0.02, 0.05 * axle),
                  num["lstar_derivative"], num["small_angle_limit"],
                  {axis: tuple(scene["comfort"][axis]) for axis in COMFORT}, scene["report"]["paper_tables"],
                  notes=[], output=scene["output"])
    if setup.paper_tables:
        _table_grid(setup)
    lo, hi, front = _visited(setup)
    track.check_domain("track", lo, front)
    setup.plan = model.plan_frames(track, lo, front, setup.frame, num["min_curvature"])
    setup.plan.span = (lo, hi)
    setup.notes += [f"frame: {e['kind']} at s = {e['s']:.6g} m: {e['action']}" for e in setup.plan.events
                    if e["kind"] != "fast turn"]
    noise = getattr(track, "noise", None)
    if noise:
        setup.notes += _noise_notes(noise)
    if scene["elastic"] is not None:
        if setup.conventions == "paper":
            raise SceneError("elastic", "the elastic model needs conventions = \"physics\"")
        case = 2 if setup.local_curvature else 1
        from symmech.trolley.elastic import scene as elastic_scene  # the elastic model: imported only when a scene has one

        setup.elastic = elastic_scene.prepare(scene["elastic"], body, elastic_scene.drive_of(setup, case), setup.t)
    return setup


def _visited(setup: Setup) -> tuple[float, float, float]:
    """Rear-axle arc lengths (lo, hi) [m] the run evaluates frames on — in case 2 at least
    two difference stencils wide, so that one-sided stencils fit at its ends — and the
    farthest arc length [m] it evaluates the track on (the front axle in case 2)."""
    reach = FRONT_REACH * setup.body.l if setup.local_curvature else 0.0
    length = setup.track.length
    if setup.speed is not None:
        s = arc_length(setup)
        if not np.all(np.abs(s) <= MAX_LENGTH):
            raise SceneError("motion.speed", f"the arc length reaches {np.abs(s).max():.3g} m; at most "
                                             f"{MAX_LENGTH:g} m")
        lo, hi = float(s.min()), float(s.max())
    else:  # traction: the speed is unknown before the run but bounded by MAX_SPEED
        span = min(MAX_SPEED * setup.t[-1], MAX_LENGTH)
        lo, hi = setup.s0 - span, setup.s0 + span
        if math.isfinite(length):
            lo, hi = max(lo, 0.0), max(min(hi, length - reach), setup.s0)
    if setup.local_curvature:
        width = 2 * (setup.fd_order + 1) * setup.fd_step
        if hi - lo < width:
            lo = max(0.5 * (lo + hi - width), 0.0) if math.isfinite(length) else 0.5 * (lo + hi - width)
            hi = lo + width
        if hi + reach > length and hi + setup.body.l <= length:
            reach = _front_axle(setup, hi) - hi
    return lo, hi, hi + reach


# The front axle's arc length exceeds the axle distance l by ~κ² l³/24: a bound for moderate curvature.
FRONT_REACH = 1.05


def _front_axle(setup: Setup, s: float) -> float:
    """Arc length [m] of the front axle when the rear one is at ``s``; beyond the track
    (where the check refuses it) when the track ends within its reach."""
    try:
        return float(model.chord_point(setup.track, np.array([s]), setup.body.l)[0])
    except SymmechError:
        return s + FRONT_REACH * setup.body.l


def _table_grid(setup: Setup) -> None:
    for time_ in tables.TIMES:
        k = int(round(time_ / (setup.t[1] - setup.t[0])))
        if k >= len(setup.t) or abs(setup.t[k] - time_) > 1e-9:
            raise SceneError("report.paper_tables", f"t = {time_:g} s is not a grid point of this scene "
                                                    "(use the paper's t_end = 20 s, steps = 5000)")


def _noise_notes(noise: dict) -> list[str]:
    """Warnings when the data say the table's derived accelerations are not to be trusted."""
    ratio = noise["curvature_error_per_m"] / max(noise["curvature_max_per_m"], 1e-300)
    noise["curvature_error_ratio"] = ratio
    notes = []
    if ratio > NOISE_WARN:
        notes.append(f"track.points: derived accelerations are dominated by noise: the points scatter by about "
                     f"{noise['point_noise_m']:.2g} m per coordinate, giving a curvature error of "
                     f"{noise['curvature_error_per_m']:.3g} 1/m against a largest curvature of "
                     f"{noise['curvature_max_per_m']:.3g} 1/m ({100 * ratio:.0f} %); set track.smoothing to at "
                     f"least the RMS distance of the noise, about {2 * math.sqrt(3) * noise['point_noise_m']:.2g} m")
    elif noise["curvature_overshoot"] > OVERSHOOT_WARN:
        notes.append(f"track.points: the fitted curvature overshoots the three-point curvature of the points by "
                     f"{100 * noise['curvature_overshoot']:.1f} % of its largest value near "
                     f"{noise['overshoot_near_m']:.4g} m along the table (a curvature jump: the spline rings); "
                     "accelerations there are overestimated by about as much; add points or a transition curve")
    return notes


NOISE_WARN = 0.1  # curvature error / largest curvature beyond which a table's accelerations are noise
OVERSHOOT_WARN = 0.05  # curvature overshoot (fraction) beyond which a table's fit is said to ring


# A step in the paper's conventions against one in the physics conventions (the bundled helices' 5000 steps:
# 0.025 s against 0.09 s); the paper's tables run the cases in both.
PAPER_CONVENTIONS_WORK = 0.3


def estimate(setup: Setup) -> registry.Estimate:
    steps = len(setup.t) - 1
    cases = 2 if setup.local_curvature else 1
    runs = cases * (6 if setup.local_curvature else 1)
    own = PAPER_CONVENTIONS_WORK if setup.conventions == "paper" else 1.0
    conventions = 1.0 + PAPER_CONVENTIONS_WORK if setup.paper_tables else own
    seconds = (SECONDS_PER_STEP * runs + SECONDS_PER_OUTPUT_ROW * cases) * (steps + 1) * conventions
    what = f"{steps} steps, {cases} case(s) with outputs"
    once = 0.0
    if setup.traction is not None:
        rhs = 40 * steps + 2000
        seconds += SECONDS_PER_RHS * rhs * cases
        what += f", ~{rhs} traction evaluations"
    if setup.elastic is not None and setup.elastic.system is not None:
        from symmech.trolley.elastic import scene as elastic_scene  # the elastic model: imported only when a scene has one

        engine, why = elastic_scene.engine(setup.elastic)
        what += f", the elastic model ({engine} engine{'; ' + why if why.startswith('auto') else ''})"
        seconds += elastic_scene.SECONDS_PER_STEP[engine] * steps
        if engine == "compiled":
            from symmech.core import engines

            elastic = engines.get("elastic")  # its module imports numba: only when the compiled engine runs
            once = elastic.compile_seconds()
            if once:
                seconds += once
                what += (f"; compiling the elastic engine once, ~{once:.0f} s "
                         f"(numba's cache {elastic.builder().cache_dir()}; `symmech warm` builds it ahead)")
    return registry.Estimate(seconds, what, once)



SAMPLE_STEPS = 10  # steps a timed sample takes at least


def sample(setup: Setup, share: float) -> Setup:
    """The scene over the first ``share`` of its steps (at least :data:`SAMPLE_STEPS`), without the paper's tables
    (they read the whole grid), for :func:`symmech.core.sample.timed`; ``auto`` picks the run's engine for it."""
    import dataclasses

    t = setup.t[:max(int(share * (len(setup.t) - 1)), SAMPLE_STEPS) + 1]
    elastic = setup.elastic and dataclasses.replace(setup.elastic, t=t)
    return dataclasses.replace(setup, t=t, paper_tables=False, elastic=elastic, notes=[])

def arc_length(setup: Setup) -> np.ndarray:
    """s(t) = s0 + ∫ V0 dt on the grid, 8-point Gauss-Legendre per step [m]."""
    t = setup.t
    nodes, weights = np.polynomial.legendre.leggauss(8)
    mid, half = (t[1:] + t[:-1]) / 2, (t[1:] - t[:-1]) / 2
    v = setup.speed[0](mid[:, None] + half[:, None] * nodes)
    return setup.s0 + np.concatenate([[0.0], np.cumsum((v * weights).sum(axis=1) * half)])


def integrate_traction(setup: Setup, case: int, ctx=None):
    """s, V0, dV0 on the grid from m a1 = P0 - m g0 ν1 along x1 (a1 = α1 V̇0 + β1 V0²)."""
    from scipy.integrate import solve_ivp

    body, frames = setup.body, setup.frames(case)
    calls, reached = [0], [setup.t[0]]
    ctx = ctx or Context(quiet=True)

    def rates(t, y):
        calls[0] += 1
        if calls[0] % 1000 == 0:
            ctx.tick(f"traction integration at t = {t:.6g} s")
            if calls[0] > MAX_RHS:
                raise SymmechError(f"traction integration stalls at t = {t:.6g} s: {calls[0]} evaluations "
                                   f"(limit {MAX_RHS}); the motion is too stiff or singular there")
            bar.update(max(t - reached[0], 0.0))
            reached[0] = max(reached[0], t)
        if not abs(y[1]) <= MAX_SPEED:
            raise SymmechError(f"traction: the speed reaches {y[1]:.6g} m/s at t = {t:.6g} s, beyond "
                               f"{MAX_SPEED:g} m/s (motion.traction)")
        fr = frames(np.array([y[0]]))
        alpha, beta = (c[0] for c in model.point_coefficients(fr, body))
        if alpha[0] <= 1e-6:
            raise SymmechError(f"traction: the centre of mass cannot be driven along the track at s = {y[0]:.6g} m "
                               f"(α1 = {alpha[0]:.3g})")
        p0 = float(setup.traction(t, y[1]))
        dv = (p0 / body.m - body.g0 * fr.lam[0, 0, 1] - beta[0] * y[1] ** 2) / alpha[0]
        return [y[1], dv]

    with ctx.progress(setup.t[-1], f"case {case}: traction", unit="s") as bar:
        sol = solve_ivp(rates, (setup.t[0], setup.t[-1]), [setup.s0, setup.v_initial], method="DOP853",
                        t_eval=setup.t, rtol=1e-10, atol=1e-10)
    if sol.status != 0 or not np.all(np.isfinite(sol.y)):
        raise SymmechError(f"traction integration failed: {sol.message}")
    s, v = sol.y
    dv = np.array([rates(ti, [si, vi])[1] for ti, si, vi in zip(setup.t, s, v)])
    return s, v, dv


def compute(setup: Setup, conventions: str | None = None, ctx=None) -> dict:
    """Results per case: {1: {...}, 2: {...}} with s, V0, dV0 and :func:`model.body_motion` arrays."""
    conventions = conventions or setup.conventions
    cases = (1, 2) if setup.local_curvature else (1,)
    results = {}
    for case in cases:
        if ctx is not None:
            ctx.tick(f"case {case}")
        if setup.traction is not None:
            s, v0, dv0 = integrate_traction(setup, case, ctx)
        else:
            s = arc_length(setup)
            v0, dv0 = setup.speed[0](setup.t), setup.speed[1](setup.t)
        if conventions == "paper":
            out = model.paper_case(setup.track, s, v0, dv0, setup.body, setup.frame, case == 2,
                                   setup.lstar_derivative, plan=setup.plan)
        else:
            fr = setup.frames(case)(s)
            out = model.body_motion(fr, v0, dv0, setup.body)
            out["frame"] = fr
        out.update(s=s, V0=v0, dV0=dv0)
        results[case] = out
    return results


def _extremes(t, values, names, unit):
    out = {}
    for i, name in enumerate(names):
        col = values[:, i]
        hi, lo = int(np.argmax(col)), int(np.argmin(col))
        out[name] = {"max": float(col[hi]), "t_max": float(t[hi]), "min": float(col[lo]), "t_min": float(t[lo]),
                     "unit": unit}
    return out


def _comfort(t, overload, comfort):
    out = {}
    for i, (axis, (lo, hi)) in enumerate(comfort.items()):
        bad = (overload[:, i] < lo) | (overload[:, i] > hi)
        out[axis] = {"envelope_g": [lo, hi], "samples_outside": int(bad.sum()),
                     "first_t_outside": float(t[np.argmax(bad)]) if bad.any() else None}
    return out


def paper_table_rows(setup: Setup, paper: dict, physics: dict) -> dict:
    """Printed Tables 1, 2 beside the paper-conventions and default-physics values."""
    index = {time_: int(round(time_ / (setup.t[1] - setup.t[0]))) for time_ in tables.TIMES}
    rows, reproduced = [], 0
    for table, q, case, time_, value, decimals in tables.entries():
        if case not in paper:
            continue
        k = index[time_]
        pick = lambda r: float(quantity(r, q)[k])  # noqa: E731
        got = pick(paper[case])
        ok = round(got, decimals) == round(value, decimals)
        reproduced += ok
        rows.append({"table": table, "quantity": q, "unit": UNITS[q], "case": case, "t": time_, "printed": value,
                     "paper_conventions": got, "default_physics": pick(physics[case]),
                     "reproduced_to_printed_digits": bool(ok)})
    return {"entries": len(rows), "reproduced": reproduced, "rows": rows}


def _paper_tables_text(tab: dict) -> str:
    """The printed entries beside both computations, as an aligned text table."""
    lines = [f"{'table':<8} {'qty':<4} {'case':>4} {'t [s]':>6} {'printed':>12} {'paper conv.':>14} "
             f"{'physics':>14}  reproduced"]
    for r in tab["rows"]:
        lines.append(f"{r['table']:<8} {r['quantity']:<4} {r['case']:>4} {r['t']:>6g} {r['printed']:>12.6g} "
                     f"{r['paper_conventions']:>14.6f} {r['default_physics']:>14.6f}  "
                     f"{'yes' if r['reproduced_to_printed_digits'] else 'NO'}")
    lines.append(f"{tab['reproduced']} of {tab['entries']} printed entries reproduced to the printed digits "
                 "in paper conventions")
    return "\n".join(lines) + "\n"


def quantity(res, name) -> np.ndarray:
    """The column of a quantity named like the printed tables (P0…P5, V1…V3, a1…a3) in a case's results."""
    kind, i = name[0], int(name[1:])
    if kind == "P":
        return res["P"][:, i]
    return res["V" if kind == "V" else "a"][:, i - 1]


T = Column("t", "s", "time")
REACTION_COLUMNS = (Column("P0", "N", "traction at O along x1"), Column("P1", "N", "rear roller B along x2"),
                    Column("P2", "N", "rear roller C along x2"), Column("P3", "N", "front axle A along x2"),
                    Column("P4", "N", "rear axle O along x3"), Column("P5", "N", "front axle A along x3"))
CASE_COLUMNS = (T, *(Column(f"V{i}", "m/s", f"velocity of the centre of mass along x{i}") for i in (1, 2, 3)),
                *(Column(f"a{i}", "m/s^2", f"acceleration of the centre of mass along x{i}") for i in (1, 2, 3)),
                *REACTION_COLUMNS)
UNITS = {c.name: c.unit for c in CASE_COLUMNS}  # the printed tables' quantities in SI
OVERLOAD_COLUMNS = (T, *(Column(f"n{i}", "g", f"overload (a + g0 ν)/g0 along x{i}") for i in (1, 2, 3)))


def run(setup: Setup, ctx) -> Result:
    """Cases 1 (and 2) on the grid: tables, summary, plots (nothing written here)."""
    with np.errstate(all="ignore"):  # a non-finite result is reported once, naming quantity and time
        res = compute(setup, ctx=ctx)
    for note in setup.notes:
        ctx.warn(note)
    summary = {"conventions": setup.conventions, "frame": setup.frame,
               "effects": {"gravity": setup.body.g0 > 0, "local_curvature": setup.local_curvature,
                           "traction": setup.traction is not None},
               "steps": len(setup.t) - 1, "frame_continuity": setup.plan.report(), "cases": {},
               "captions": plotting.captions(plots.FIGURES, setup.output)}
    if getattr(setup.track, "noise", None):
        summary["track_noise"] = setup.track.noise
    result = Result("trolley", summary)
    for case, r in res.items():
        _check_finite_case(setup, case, r)
        result.tables[f"case{case}"] = Table(CASE_COLUMNS, np.column_stack([setup.t, r["V"], r["a"], r["P"]]))
        result.tables[f"case{case}_overload"] = Table(OVERLOAD_COLUMNS, np.column_stack([setup.t, r["overload"]]))
        summary["cases"][f"case{case}"] = _case_summary(setup, case, r, ctx)
        result.headline += _case_headline(setup, case, r)
        result.checks += [within(f"case {case}: overload n{k + 1} in the comfort envelope", n.min(), n.max(),
                                 envelope, "g") for k, (n, envelope) in enumerate(zip(r["overload"].T,
                                                                                      setup.comfort.values()))]
        if "small_angle_defect_max" in summary["cases"][f"case{case}"]:
            result.checks.append(at_most(f"case {case}: small-angle correction (13)-(14) in range (defect)",
                                         summary["cases"][f"case{case}"]["small_angle_defect_max"],
                                         setup.small_angle_limit, otherwise="warn"))
    if setup.paper_tables:
        other = compute(setup, "physics" if setup.conventions == "paper" else "paper", ctx)
        paper, physics = (res, other) if setup.conventions == "paper" else (other, res)
        summary["paper_tables"] = paper_table_rows(setup, paper, physics)
        result.files["paper_tables.txt"] = _paper_tables_text(summary["paper_tables"])
    elastic = None
    if setup.elastic is not None:
        from symmech.trolley.elastic import review as elastic_review, scene as elastic_scene  # the elastic model: only when a scene has one

        elastic = elastic_scene.run(setup.elastic, ctx, setup.comfort)
        result.tables.update(elastic.tables)
        summary.update(elastic.summary)
        headline, checks, warnings = elastic_review.review(setup.elastic, elastic)
        result.headline += headline
        result.checks += checks
        for warning in elastic.warnings + warnings:
            ctx.warn(warning)

    def draw(folder):
        return plots.write_all(setup, res, folder, setup.output) + (elastic.plots(folder, setup.output) if elastic else [])
    result.plots = draw
    return result


def _case_headline(setup, case, r) -> list[Headline]:
    """Per axis the overload extreme nearest to (or furthest beyond) the comfort envelope, and the peak
    reactions of a case, with time and place."""
    def at(i):
        return f"t = {setup.t[i]:.4g} s, s = {r['s'][i]:.4g} m"

    out = []
    for k, (axis, (lo, hi)) in enumerate(setup.comfort.items()):
        n = r["overload"][:, k]
        i_max, i_min = int(np.argmax(n)), int(np.argmin(n))
        i = i_max if hi - n[i_max] <= n[i_min] - lo else i_min  # the smaller margin to the envelope
        out.append(Headline(f"case {case}: critical overload n{k + 1}", n[i], "g",
                            f"along {axis}: the extreme nearest to or beyond the comfort envelope [{lo:g}, {hi:g}] g",
                            at(i), (lo, hi)))
    for j, column in enumerate(REACTION_COLUMNS):
        i = int(np.argmax(np.abs(r["P"][:, j])))
        out.append(Headline(f"case {case}: peak reaction {column.name}", r["P"][i, j], "N", column.doc, at(i)))
    return out


def _check_finite_case(setup, case, r):
    for key in ("V", "a", "P"):
        bad = ~np.all(np.isfinite(r[key]), axis=-1)
        if bad.any():
            i = int(np.argmax(bad))
            raise SymmechError(f"case {case}: non-finite {key} at t = {setup.t[i]:.6g} s (s = {r['s'][i]:.6g} m)")


def _case_summary(setup, case, r, ctx) -> dict:
    info = {
        "speed": _extremes(setup.t, r["V0"][:, None], ["V0"], "m/s"),
        "velocity": _extremes(setup.t, r["V"], ["V1", "V2", "V3"], "m/s"),
        "acceleration": _extremes(setup.t, r["a"], ["a1", "a2", "a3"], "m/s^2"),
        "reactions": _extremes(setup.t, r["P"], [f"P{i}" for i in range(6)], "N"),
        "overload": _extremes(setup.t, r["overload"], ["n1", "n2", "n3"], "g"),
        "comfort": _comfort(setup.t, r["overload"], setup.comfort),
        "s_end": float(r["s"][-1]),
    }
    if case == 2 and setup.conventions == "physics":
        info.update(_small_angle(setup, r, ctx))
    for axis, c in info["comfort"].items():
        if c["samples_outside"]:
            ctx.warn(comfort_warning(f"case {case}: overload", axis, c["envelope_g"], c["first_t_outside"]))
    return info


def _small_angle(setup, r, ctx) -> dict:
    psi = r["frame"].info["psi"]
    k = int(np.argmax(psi))
    defect, _ = model.small_angle_check(r["frame"].info["base"], r["frame"].info["chord"], setup.body.l)
    j = int(np.argmax(defect))
    if defect[j] > setup.small_angle_limit:
        ctx.warn(f"case 2: the small-angle correction (13)-(14) is out of its range: orthogonality "
                 f"defect {defect[j]:.3g} > {setup.small_angle_limit:g} at t = {setup.t[j]:.4g} s "
                 f"(chord angle {psi[j]:.3g} rad); the exact rotation Λ* is used")
    return {"chord_angle_max_rad": float(psi[k]), "chord_angle_t_max": float(setup.t[k]),
            "small_angle_defect_max": float(defect[j])}


PRECISION_STEPS = (250, 500, 1000, 2000, 5000, 10000, 20000)
PRECISION_METHODS = ("backward", "central2", "central4")


def _symbolic_chord(setup: Setup):
    """Symbols s, s_A, the midline at both, the tangent at O, and d/ds along the chord
    equation: ∂/∂s + ds_A/ds ∂/∂s_A with ds_A/ds = (ΔR̄·t(s_O)) / (ΔR̄·t(s_A))."""
    import sympy as sp

    tr = setup.track
    if getattr(tr, "exprs", None) is None:
        raise SymmechError("bench precision needs a track given by expressions in s (type helix or expression)")
    s, sa = tr.var, sp.Symbol("s_A", real=True)
    x_o = sp.Matrix(tr.exprs)
    x_a = x_o.subs(s, sa)
    chord = x_a - x_o
    dsa = chord.dot(x_o.diff(s)) / chord.dot(x_a.diff(sa))
    total = lambda m: m.diff(s) + m.diff(sa) * dsa  # noqa: E731
    return s, sa, x_o, chord, total


def _matrix_function(matrices, s, sa):
    """Numeric f(s, s_A) -> tuple of (n, 3, 3) arrays of the sympy 3x3 ``matrices``."""
    f = tracks.lambdify_arrays([e for m in matrices for e in m], (s, sa))

    def value(s_val, sa_val):
        flat = np.stack(f(s_val, sa_val), axis=-1)
        return tuple(flat[..., 9 * k:9 * k + 9].reshape(np.shape(s_val) + (3, 3)) for k in range(len(matrices)))
    return value


def exact_paper_lstar_derivative(setup: Setup):
    """dΛ*/ds of the paper's Λ* (ξ = t × ρ, printed Rodrigues) by symbolic differentiation.

    Returns f(s, s_A) -> (n, 3, 3), s_A(s) from the chord equation.
    """
    import sympy as sp

    from symmech.trolley import printed as printed_formulas

    s, sa, x_o, chord, total = _symbolic_chord(setup)
    t_o = x_o.diff(s)
    rho = chord / setup.body.l
    xi = t_o.cross(rho)
    subs = {printed_formulas.psi: sp.acos(t_o.dot(rho)), printed_formulas.xi1: xi[0],
            printed_formulas.xi2: xi[1], printed_formulas.xi3: xi[2]}
    f = _matrix_function([total(printed_formulas.RODRIGUES.subs(subs))], s, sa)
    return lambda s_val, sa_val: f(s_val, sa_val)[0]


def exact_lstar_derivatives(setup: Setup):
    """Λ*' and Λ*'' of the physically consistent chord rotation, symbolically (Frenet frame).

    Returns f(s, s_A) -> (Λ*', Λ*''), each (n, 3, 3).
    """
    import sympy as sp

    from symmech.trolley import derive

    if setup.frame != "frenet":
        raise SymmechError("bench precision: the exact case 2 reference is built for frame = \"frenet\"")
    s, sa, x_o, chord, total = _symbolic_chord(setup)
    t = x_o.diff(s)
    curv = t.diff(s)
    n = curv / sp.sqrt(curv.dot(curv))
    lam = sp.Matrix.vstack(t.T, n.T, t.cross(n).T)
    rho = lam * chord / setup.body.l
    spec = derive.chord_rotation()
    syms = [a.symbol for a in spec.args]
    lstar = spec.matrix.subs(dict(zip(syms, rho)))
    d1 = total(lstar)
    return _matrix_function([d1, total(d1)], s, sa)


PRECISION_FD_STEPS = (0.3, 0.1, 0.03, 0.01, 0.003, 0.001, 0.0003)
TABLE_REFERENCE_STEP = 0.002  # m: about eps^(1/6) times the metre scale of a track


def _timed(fn, repeat: int = 3):
    """Best wall time of ``repeat`` calls [s] and the last result."""
    best = np.inf
    for _ in range(repeat):
        start = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - start)
    return best, result


PRECISION_COLUMNS = (Column("steps", "1", "grid intervals"), Column("fd_step", "m", "difference step (0: grid)"),
                     Column("time", "s", "best wall time of 3"), Column("max_abs_error", "N", "max |P - P_exact|"))


def precision(setup: Setup, ctx) -> Result:
    """Work-precision of the derivative approximations, against exact symbolic references
    (with an ``[elastic]`` table: of the elastic model's integrators, :func:`elastic_scene.precision`).

    Paper conventions, case 2: dΛ*/ds by the paper's backward difference, central2 and
    central4 between grid points, for ``PRECISION_STEPS`` (the step count is the knob).
    With ``conventions = "physics"`` also the consistent case 2: Λ*', Λ*'' by central
    differences of order 2 and 4 for ``PRECISION_FD_STEPS`` on the scene's grid.
    Table ``precision`` (text columns family, method) and plot ``precision.png``.
    """
    import dataclasses

    if setup.elastic is not None:
        from symmech.trolley.elastic import scene as elastic_scene  # the elastic model: imported only when a scene has one

        return elastic_scene.precision(setup.elastic, ctx)
    if not setup.local_curvature or setup.speed is None:
        raise SymmechError("bench precision needs effects.local_curvature = true and a given speed")
    symbolic = getattr(setup.track, "exprs", None) is not None
    if not symbolic and setup.conventions != "physics":
        raise SymmechError("bench precision of a point-table track needs conventions = \"physics\" "
                           "(the paper's backward difference has no exact reference on a table)")
    exact = exact_paper_lstar_derivative(setup) if symbolic else None
    rows = []
    t_end = setup.t[-1]
    for steps in PRECISION_STEPS if symbolic else ():
        ctx.tick(f"precision at {steps} steps")
        st = dataclasses.replace(setup, t=np.linspace(0.0, t_end, steps + 1))
        s, v0, dv0 = arc_length(st), st.speed[0](st.t), st.speed[1](st.t)
        sa = model.chord_point(st.track, s, st.body.l)
        case2 = lambda **kw: model.paper_case(st.track, s, v0, dv0, st.body, st.frame, True,  # noqa: E731
                                              plan=st.plan, **kw)["P"]
        ref = case2(dlstar=exact(s, sa))
        for method in PRECISION_METHODS:
            elapsed, got = _timed(lambda: case2(derivative=method))
            rows.append(("paper", method, steps, "", elapsed, float(np.abs(got - ref).max())))
    if setup.conventions == "physics":
        s, v0, dv0 = arc_length(setup), setup.speed[0](setup.t), setup.speed[1](setup.t)
        case2 = lambda **kw: model.body_motion(  # noqa: E731
            model.local_curvature_frame(setup.track, s, setup.body.l, setup.frame, plan=setup.plan, **kw),
            v0, dv0, setup.body)["P"]
        # a point table has no symbolic derivative: the reference is central-4 differences at the
        # step where truncation (h^4) and rounding (eps/h^2) balance, stated in the summary
        ref = case2(derivatives=exact_lstar_derivatives(setup)) if symbolic else \
            case2(fd_order=4, fd_step=TABLE_REFERENCE_STEP)
        for order in (2, 4):
            for h in PRECISION_FD_STEPS:
                elapsed, got = _timed(lambda: case2(fd_order=order, fd_step=h))
                rows.append(("physics", f"central{order}", len(setup.t) - 1, h, elapsed,
                             float(np.abs(got - ref).max())))
    table = Table(PRECISION_COLUMNS, np.array([(r[2], r[3] or 0.0, r[4], r[5]) for r in rows], dtype=float),
                  text={"family": [r[0] for r in rows], "method": [r[1] for r in rows]})

    def draw(folder):
        return plots.work_precision(rows, folder / "precision.png")
    reference = "exact symbolic derivatives" if symbolic else \
        f"central-4 differences at {TABLE_REFERENCE_STEP:g} m (a point table has no exact derivative)"
    return Result("trolley", {"rows": len(rows), "reference": reference}, {"precision": table}, plots=draw)


registry.register(registry.Kind("trolley", "a rigid trolley on a curved two-rail track (seed 002)", SCHEMA, prepare,
                                run, estimate, precision, "docs/scenes-trolley.md",
                                design_sweep.run, sample))
