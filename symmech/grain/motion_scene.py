"""Scene kind ``grain``: the whole motion of a grain on an inclined vibrating surface.

The whole scene is declared once in :data:`SCHEMA` (the field tables of
docs/scenes-grain.md are generated from it). ``prepare`` builds the model and
checks its physical admissibility, ``estimate`` predicts impacts and wall time
before anything runs, ``run`` returns the trajectory and impact tables and the
summary, ``precision`` the work-precision study of ``symmech bench precision``.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from symmech.core import precision as wp
from symmech.core import engines, plotting, registry
from symmech.core.context import Context
from symmech.core.results import Check, Column, Headline, Result, Table, at_most
from symmech.core.scene import SceneError, SymmechError
from symmech.core.schema import Bool, Choice, Float, Int, Str, Table as Fields, Vector, plot_output
from symmech.core.watchdog import watchdog
from symmech.generated import grain_motion as gm
from symmech.grain import contact, fields, flight, motion, paper_mode, plots, sweep
from symmech.grain.body import rotation
from symmech.grain.coulomb_law import ImpactLaw
from symmech.grain.vectors import T_AT

ROLE = "kind"  # found by symmech.core.discovery

MAX_ROWS = 10_000_000  # trajectory rows a run may record
MAX_SURFACE_ACCELERATION = 1e6  # m/s^2, peak of the vibrating surface
UNIT_TOLERANCE = 1e-6  # |d| - 1 of a given vibration direction
# CPU time of accurate mode per impact (with its flight), per simulated second (sliding,
# sticking) and per scan step, and of paper mode per fixed step and per node and step:
# fitted on fifteen variants of the default scene (restitution, amplitude, frequency 25 Hz to
# 1e5 Hz, effects, tolerance, mode, nodes): never below 0.7 of the measured time, up to 7 times
# above it (high restitution, where fewer bounces chatter than the geometric series says).
SECONDS_PER_IMPACT = 6e-3
SECONDS_PER_SIMULATED_SECOND = 0.8
SECONDS_PER_SCAN = 6e-5
# The compiled engine's cost as a fraction of the Python loop's: 162x faster measured on the default scene
# (2 s), 122-288x on the hard grains of tests/test_grain_compiled.py (0.4 s; stiff slips in the compiled
# Radau; benchmarks/bench_grain_motion.py); a conservative 50x.
COMPILED_SPEEDUP = 50.0
SECONDS_PER_PAPER_STEP = 1e-4
SECONDS_PER_PAPER_NODE_STEP = 5e-9
STAGNANT_PHASES = 1000  # consecutive regime phases that advance time by less than the event resolution


def _not_vertical(surface: dict, path: str) -> None:
    alpha, beta = math.radians(surface["alpha_deg"]), math.radians(surface["beta_deg"])
    if math.sin(alpha) ** 2 + math.sin(beta) ** 2 >= 1.0 - 1e-12:
        raise SceneError(f"{path}.beta_deg", "sin^2(alpha) + sin^2(beta) must be < 1 (the surface would be vertical)")


def _admissible_vibration(vib: dict, path: str) -> None:
    if vib["direction"] == "vector":
        norm = float(np.linalg.norm(vib["vector"]))
        if norm == 0.0:
            raise SceneError(f"{path}.vector", "[0, 0, 0] has no direction; give a unit vector")
        if abs(norm - 1.0) > UNIT_TOLERANCE:
            raise SceneError(f"{path}.vector", f"|d| = {norm:.6g} is not a unit vector (tolerance {UNIT_TOLERANCE:g}); "
                                               "give the magnitude as vibration.amplitude [m]")
    omega = 2 * math.pi * vib["frequency"]
    speed, acceleration = vib["amplitude"] * omega, vib["amplitude"] * omega**2
    if speed > fields.SPEED or acceleration > MAX_SURFACE_ACCELERATION:
        raise SceneError(f"{path}.amplitude", f"{vib['amplitude']:g} m at {vib['frequency']:g} Hz gives a peak surface "
                                              f"velocity {speed:.3g} m/s and acceleration {acceleration:.3g} m/s^2; "
                                              f"admissible up to {fields.SPEED:g} m/s and "
                                              f"{MAX_SURFACE_ACCELERATION:g} m/s^2")


def _as_printed_needs_paper(numerics: dict, path: str) -> None:
    if numerics["as_printed"] and numerics["mode"] != "paper":
        raise SceneError(f"{path}.as_printed", "the printed formulas apply to mode = \"paper\" only")


SCHEMA = Fields("a grain scene", {
    "kind": Choice("selects this kind", choices=("grain",)),
    "title": Str("free text", default=""),
    "duration": Float("physical time simulated (the estimate refuses runs past `--max-time`)", unit="s",
                      lo=0.0, lo_open=True, hi=1e4),
    "body": fields.BODY,
    "surface": Fields("the inclined working surface", {
        "g": Float("gravitational acceleration", unit="m/s^2", lo=0.0, lo_open=True, hi=1e3, default=9.81),
        "alpha_deg": Float("rise of the X axis above the horizontal", unit="deg", lo=-89.0, hi=89.0, default=0.0),
        "beta_deg": Float("rise of the Y axis above the horizontal; sin²α + sin²β < 1", unit="deg",
                          lo=-89.0, hi=89.0, default=0.0),
    }, default={}, checks=(_not_vertical,)),
    "vibration": Fields("surface displacement s(t) = A d sin(2π f t + phase); peak velocity 2π f A at most "
                        "100 m/s, peak acceleration (2π f)² A at most 1e6 m/s²", {
        "amplitude": Float("A", unit="m", lo=0.0, hi=1.0, default=0.0),
        "frequency": Float("f", unit="Hz", lo=0.0, lo_open=True, hi=1e5, default=1.0),
        "phase_deg": Float("phase at t = 0", unit="deg", lo=-360.0, hi=360.0, default=0.0),
        "direction": Choice("d: the true vertical, the surface normal e_Z, in the X-Z plane at `angle_deg`, "
                            "or a given unit `vector`", choices=("vertical", "normal", "angle", "vector"),
                            default="vertical"),
    }, variants=("direction", {
        "angle": {"angle_deg": Float("d = (cos γ, 0, sin γ), from +X towards +Z (the throw angle)", unit="deg",
                                     lo=-180.0, hi=180.0, default=90.0)},
        "vector": {"vector": Vector("d in KXYZ, a unit vector (the magnitude is `amplitude`)", n=3)},
    }), default={}, checks=(_admissible_vibration,)),
    "impact": Fields("the impact law", {
        "law": Choice("`coulomb`: Chatterjee-Ruina with a Coulomb bound; `printed`: (14)-(20) of the paper",
                      choices=("coulomb", "printed"), default="coulomb"),
    }, variants=("law", {
        "printed": {"e": Float("normal restitution: ż_K = −e ż_K(0)", lo=0.0, hi=1.0),
                    "lambda": Float("tangential speed × (1 − λ)", lo=0.0, hi=1.0)},
        "coulomb": {"e_n": Float("normal restitution", lo=0.0, hi=1.0),
                    "e_t": Float("tangential restitution (u_t → −e_t u_t when sticking; the printed law for a "
                                 "sphere is e_t = λ − 1)", lo=-1.0, hi=1.0),
                    "mu": Float("friction coefficient bounding the tangential impulse; omitted: no bound",
                                lo=0.0, hi=1e6, default=None),
                    "check_printed": Bool("evaluate the printed law (e = e_n, λ = 1 + e_t) at every impact and "
                                          "log whether it would have created energy", default=True)},
    })),
    "sliding": Fields("the sliding regime", {
        "friction": Float("Coulomb friction coefficient while sliding", lo=0.0, hi=100.0, default=0.5),
    }, default={}),
    "initial": Fields("the state at t = 0, relative to the surface (KXYZ)", {
        "position": Vector("centre position; z at least the support height of the orientation; "
                           "omitted: resting on the plane at the origin", n=3, unit="m", lo=-100.0, hi=100.0,
                           default=None),
        "velocity": fields.velocity("centre velocity", default=[0.0, 0.0, 0.0]),
        "angular_velocity": fields.angular_velocity("angular velocity", default=[0.0, 0.0, 0.0]),
    }, default={}),
    "effects": Fields("switches; an effect that is off runs no code for it", {
        "vibration": Bool("off: the surface is still", default=True),
        "inclination": Bool("off: α = β = 0", default=True),
        "rotation": Bool("off: no spin, impacts act on a point mass (H = E)", default=True),
        "friction": Bool("off: frictionless sliding (no friction force)", default=True),
    }, default={}),
    "sweep": sweep.SWEEP,
    "population": sweep.POPULATIONS,
    "numerics": Fields("numerical choices; T is the vibration period (1 s without vibration)", {
        "mode": Choice("`accurate`: exact flight, root-located events; `paper`: the printed fixed-step scheme",
                       choices=("accurate", "paper"), default="accurate"),
        "engine": Choice("accurate mode: `compiled`, the event loop in numba (symmech.grain.motion_engine; the first "
                         "run on a machine compiles it, ~80 s, cached for later runs); `python`, the reference loop "
                         "in Python (same events, results to round-off or, in stiff slips, to the tolerance; "
                         "120-290x slower, never compiles); `auto`: `compiled` when it is cached, else `python` "
                         "while the compiled engine is built in the background for the next run",
                         choices=("auto", "compiled", "python"), default="auto"),
        "tolerance": Float("accurate mode: relative tolerance of rotation, sliding and event times (times to "
                           "tolerance × scan step)", lo=1e-14, hi=1e-2, default=1e-9),
        "scan_step": Float("accurate mode: spacing at which contact and lift-off roots are bracketed; "
                           "omitted: T/40", unit="s", lo=0.0, lo_open=True, hi=1.0, default=None),
        "dt": Float("paper mode: fixed step Δt of (61)-(62); omitted: T/2000", unit="s", lo=0.0, lo_open=True,
                    hi=1.0, default=None),
        "nodes": Int("paper mode: surface nodes of the contact test (63)", lo=6, hi=100000, default=400),
        "as_printed": Bool("paper mode only: (61), (63), (64) verbatim", default=False),
        "rest_velocity": Float("a bounce whose contact point leaves slower than this ends the chattering: the "
                               "grain slides", unit="m/s", lo=0.0, lo_open=True, hi=1.0, default=1e-5),
        "max_impacts": Int("safety stop (reported as a warning)", lo=1, hi=10_000_000, default=100000),
        "sample_interval": Float("spacing of trajectory rows (events are always recorded); omitted: T/40; "
                                 "at most 1e7 rows", unit="s", lo=0.0, lo_open=True, hi=1e4, default=None),
    }, default={}, checks=(_as_printed_needs_paper,)),
    "precision": Fields("`symmech bench precision` only", {
        "duration": Float("simulated time per run; omitted: min(duration, 4T)", unit="s", lo=0.0, lo_open=True,
                          hi=1e4, default=None),
        "reference_tolerance": Float("tolerance of the reference (accurate mode, scan step / 4)",
                                     lo=1e-14, hi=1e-6, default=1e-12),
    }, default={}),
    "output": plot_output(plots.MOTION, default=("path",)),
})


@dataclass(frozen=True)
class GrainScene:
    """A prepared grain scene: the model, numerics, start state, ``duration`` [s], inclination
    ``alpha_beta`` [rad] (for the printed gravity of paper mode) and the resolved ``precision`` table."""

    model: motion.Model
    numerics: motion.Numerics
    start: motion.State
    duration: float
    alpha_beta: tuple
    precision: dict
    output: dict  # the resolved [output] table: plots and formats


def prepare(r: dict) -> GrainScene:
    """The model of a resolved grain scene; SceneError for anything physically inadmissible."""
    effects = motion.Effects(**r["effects"])
    axes = tuple(r["body"]["semi_axes"])
    surface = r["surface"]
    alpha, beta = ((math.radians(surface["alpha_deg"]), math.radians(surface["beta_deg"]))
                   if effects.inclination else (0.0, 0.0))
    g_k = tuple(float(x) for x in gm.gravity(surface["g"], alpha, beta))
    vibration = _vibration(r["vibration"], g_k)
    law = _law(r["impact"])
    numerics = _numerics(r["numerics"], vibration.period)
    rows = r["duration"] / numerics.sample_interval
    if rows > MAX_ROWS:
        raise SceneError("numerics.sample_interval", f"{numerics.sample_interval:.3g} s gives {rows:.3g} trajectory "
                                                     f"rows over {r['duration']:g} s; at most {MAX_ROWS:g}")
    start = _start(r["initial"], axes, r["body"]["orientation"], effects)
    model = motion.Model(axes, fields.body_mass(r["body"]), g_k, vibration, law, r["sliding"]["friction"], effects)
    return GrainScene(model, numerics, start, r["duration"], (alpha, beta), r["precision"], r["output"])


def _vibration(v: dict, g_k: tuple) -> flight.Vibration:
    g = float(np.linalg.norm(g_k))
    if v["direction"] == "vertical":
        direction = tuple(-x / g for x in g_k)
    elif v["direction"] == "normal":
        direction = (0.0, 0.0, 1.0)
    elif v["direction"] == "angle":
        angle = math.radians(v["angle_deg"])
        direction = (math.cos(angle), 0.0, math.sin(angle))
    else:
        direction = tuple(float(x) for x in np.asarray(v["vector"]) / np.linalg.norm(v["vector"]))
    return flight.Vibration(v["amplitude"], 2 * math.pi * v["frequency"], math.radians(v["phase_deg"]), direction)


def _law(law: dict) -> ImpactLaw:
    if law["law"] == "printed":
        return ImpactLaw("printed", e=law["e"], lam=law["lambda"])
    return ImpactLaw("coulomb", e_n=law["e_n"], e_t=law["e_t"], mu=np.inf if law["mu"] is None else law["mu"],
                     check_printed=law["check_printed"])


def _numerics(n: dict, period: float) -> motion.Numerics:
    def given(key, default):
        return default if n[key] is None else n[key]

    return motion.Numerics(mode=n["mode"], engine=n["engine"], tolerance=n["tolerance"], scan_step=given("scan_step", period / 40),
                           dt=given("dt", period / 2000), nodes=n["nodes"], as_printed=n["as_printed"],
                           rest_velocity=n["rest_velocity"], max_impacts=n["max_impacts"],
                           sample_interval=given("sample_interval", period / 40))


def _start(init: dict, axes: tuple, angles: list, effects: motion.Effects) -> motion.State:
    Q0 = rotation(np.array(angles))
    support = float(contact.support_distance(axes, Q0))
    r0 = np.array([0.0, 0.0, support] if init["position"] is None else init["position"])
    if r0[2] < support * (1.0 - 1e-12):
        raise SceneError("initial.position", f"z = {r0[2]:.6g} m puts the grain into the surface; "
                         f"with this orientation the centre must be at z >= {support:.6g} m")
    w0 = np.array(init["angular_velocity"]) if effects.rotation else np.zeros(3)
    return motion.State(0.0, r0, np.array(init["velocity"]), flight.quaternion_from_matrix(Q0), Q0.T @ w0)


# --------------------------------------------------------------------------- cost


def expected_impacts(sc: GrainScene) -> float:
    """Impacts expected over the run, from restitution, amplitude, frequency and the drop height.

    A bounce sequence launched at a normal speed v0 decays geometrically (v -> e v) until the
    contact point leaves slower than ``rest_velocity``: about ln(v_rest / v0) / ln(e) bounces,
    fewer if the sequence outlasts the time it has. A surface that throws the grain
    (normal acceleration amplitude over g_n, Gamma > 1) launches a new sequence every period,
    or every Gamma / pi periods once a throw outlasts a period.
    """
    model, num = sc.model, sc.numerics
    law = model.law
    e = law.e if law.kind == "printed" else law.e_n
    g_n = abs(model.g_k[2])
    vib = model.vibration
    a_n = vib.amplitude * vib.omega**2 * abs(vib.direction[2])
    drop = max(float(sc.start.r[2] - contact.support_distance(model.axes, flight.rotation_matrix(sc.start.q))), 0.0)
    v_drop = math.hypot(sc.start.v[2], math.sqrt(2 * g_n * drop)) + vib.amplitude * vib.omega * abs(vib.direction[2])
    impacts = flight.bounces(v_drop, e, g_n, num.rest_velocity, sc.duration)
    if a_n > g_n:
        period = sc.model.period
        v_throw = vib.amplitude * vib.omega * abs(vib.direction[2])
        launches = sc.duration / period * min(1.0, math.pi * g_n / a_n)
        impacts += launches * flight.bounces(v_throw, e, g_n, num.rest_velocity, period)
    return min(impacts, float(num.max_impacts))


def estimate(sc: GrainScene) -> registry.Estimate:
    """Expected wall time: per fixed step in paper mode; per impact, simulated second and scan step in
    accurate mode (the Python loop's figures, divided by :data:`COMPILED_SPEEDUP` on the compiled engine)
    on the engine of :func:`choose_engine`, which the text names with the reason."""
    num = sc.numerics
    if num.mode == "paper":
        steps = sc.duration / num.dt
        seconds = steps * (SECONDS_PER_PAPER_STEP + num.nodes * SECONDS_PER_PAPER_NODE_STEP)
        return registry.Estimate(seconds, f"{steps:.3g} fixed steps of {num.dt:.3g} s, {num.nodes} nodes")
    seconds, what = _python_cost(sc, num, sc.duration)
    engine, why = choose_engine(sc)
    if engine == "python":
        return registry.Estimate(seconds, f"{what}; Python engine ({why})")
    from symmech.core import engines

    seconds /= COMPILED_SPEEDUP
    once = engines.get("grain").compile_seconds()
    if once:
        return registry.Estimate(seconds + once, f"{what}; compiled engine ({why}); compiling the grain engine "
                                 f"once, ~{once:.0f} s; later runs start in ~1 s", once=once)
    return registry.Estimate(seconds, f"{what}; compiled engine")



SAMPLE_PERIODS = 1.0  # vibration periods a timed sample covers at least


def sample(sc: GrainScene, share: float) -> GrainScene:
    """The scene over ``share`` of its duration (at least :data:`SAMPLE_PERIODS` periods, at most all of it), for
    :func:`symmech.core.sample.timed`. It runs on the run's engine: ``auto`` takes the compiled engine for both
    once it is built, and the Python engine for both while it is cold (a compile first is a count estimate's
    ``once``, never sampled), starting the background build whose load the run shares."""
    return replace(sc, duration=min(max(share * sc.duration, SAMPLE_PERIODS * sc.model.period), sc.duration))

def _python_cost(sc: GrainScene, num: motion.Numerics, duration: float) -> tuple[float, str]:
    """Accurate mode on the Python loop: expected wall time [s] over ``duration`` [s], and what it counts."""
    impacts = expected_impacts(replace(sc, numerics=num, duration=duration))
    scans = duration / num.scan_step
    seconds = impacts * SECONDS_PER_IMPACT + duration * SECONDS_PER_SIMULATED_SECOND + scans * SECONDS_PER_SCAN
    return seconds, f"~{impacts:.3g} impacts, {scans:.3g} scan steps of {num.scan_step:.3g} s"


def choose_engine(sc: GrainScene, num: motion.Numerics | None = None,
                  duration: float | None = None) -> tuple[str, str]:
    """The engine that runs accurate mode, "compiled" or "python", and why (for the estimate and summary.json).

    ``auto`` takes the compiled engine when it is built (ahead of time, or in numba's cache). Else it takes whichever the estimate says
    answers first: the Python loop (seconds on a default scene; :func:`simulate` then has the compiled engine
    built in the background for the next run) or compiling first (~80 s once, then 50x faster)."""
    num = num or sc.numerics
    if num.engine == "python":
        return "python", 'numerics.engine = "python"'
    if num.engine == "compiled":
        return "compiled", 'numerics.engine = "compiled"'
    compiled = engines.get("grain").builder()  # no numba: the engine's Python side
    if compiled.ahead_of_time() is not None:
        return "compiled", "auto: the compiled engine is built (ahead of time)"
    if not compiled.cold():
        return "compiled", "auto: the compiled engine is built (numba's cache)"
    python = _python_cost(sc, num, sc.duration if duration is None else duration)[0]
    if python > compiled.seconds + python / COMPILED_SPEEDUP:
        return "compiled", (f"auto: the Python engine would take ~{python:.3g} s, longer than compiling "
                            "the compiled engine first")
    return "python", compiled.cold_reason()


# --------------------------------------------------------------------------- run


def simulate(sc: GrainScene, numerics: motion.Numerics | None = None, duration: float | None = None,
             on_step=None) -> motion.Motion:
    """Run the scene's grain (optionally with other numerics or duration) on the engine of
    :func:`choose_engine`; returns a Motion whose ``extra`` names the engine and why.

    ``on_step(t)`` [s] is called at most every ``motion.PROGRESS_INTERVAL`` of wall time, in both modes."""
    num = numerics or sc.numerics
    t_end = sc.duration if duration is None else duration
    engine, why = ("paper", "") if num.mode == "paper" else choose_engine(sc, num, t_end)
    if engine == "compiled":
        from symmech.grain.motion_engine.driver import Run  # the engine's Python side: no numba

        compiled: engines.Engine = _compiled()
        return compiled.run(Run(sc.model, num, sc.start, t_end, on_step, why))
    if engine == "paper":
        return paper_mode.simulate(sc.model, num, sc.start, t_end, sc.alpha_beta, on_step=on_step)
    if num.engine == "auto":
        engines.get("grain").builder().warm_in_background()
    return motion.simulate(sc.model, num, sc.start, t_end, on_step=on_step, reason=why)


def simulate_many(scenes: list, workers: int | None = None, strict: bool = True) -> list:
    """The grains of ``scenes`` (a list of :class:`GrainScene`), each as :func:`simulate` runs it without ``on_step``;
    on the compiled engine, the scenes that share numerics and duration run as one population (packed once, the
    loop over grains compiled, the results built in bulk: the engine's ``run_many``, ``workers`` threads), the
    others one by one. A grain whose run fails raises its SymmechError (``strict``) or stands in the list as it."""
    out = [None] * len(scenes)
    groups = {}
    for k, sc in enumerate(scenes):
        groups.setdefault((sc.numerics, sc.duration), []).append(k)
    for (num, duration), members in groups.items():
        engine, why = choose_engine(scenes[members[0]]) if num.mode == "accurate" else ("paper", "")
        if engine == "compiled":
            from symmech.grain.motion_engine.driver import Population  # the engine's Python side: no numba

            runs = _compiled().run_many(Population([scenes[k].model for k in members], num,
                                                   [scenes[k].start for k in members], duration, workers, why, strict))
        else:
            runs = [_one(scenes[k], strict) for k in members]
        for k, m in zip(members, runs):
            out[k] = m
    return out


def _one(sc: GrainScene, strict: bool):
    """:func:`simulate` of one scene; its SymmechError raised (``strict``) or returned."""
    try:
        return simulate(sc)
    except SymmechError as exc:
        if strict:
            raise
        return exc


def _compiled() -> engines.Engine:
    """The grain's compiled engine, ready: compiled under the build lock, or loaded as a concurrent builder made it."""
    compiled = engines.get("grain")
    if compiled.builder().needs_compile():
        compiled.warm()
    return compiled


class _Watch:
    """``on_step`` of a run: progress bar, time budget, and the stagnation guard of the phase loop."""

    def __init__(self, ctx: Context, bar, resolution: float):
        self.ctx, self.bar, self.resolution = ctx, bar, resolution
        self.t, self.stalled = 0.0, 0

    def __call__(self, t: float) -> None:
        self.ctx.tick(f"grain at t = {t:.6g} s")
        if t - self.t < self.resolution:
            self.stalled += 1
            if self.stalled >= STAGNANT_PHASES:
                raise SymmechError(f"grain: the simulation stopped advancing at t = {t:.9g} s ({self.stalled} "
                                   f"regime changes within {self.resolution:.3g} s, the event resolution); "
                                   "please report this scene")
            return
        self.bar.update(t - self.t)
        self.t, self.stalled = t, 0


def simulate_watched(sc: GrainScene, ctx: Context) -> motion.Motion:
    """:func:`simulate` under ``ctx``: its progress bar, its time budget (ticked at each step and by the watchdog)
    and the guard against a loop that stops advancing; what `symmech run` and `symmech export` run."""
    with ctx.progress(sc.duration, "grain", unit="s") as bar, watchdog(ctx, where="grain simulation"):
        return simulate(sc, on_step=_Watch(ctx, bar, sc.numerics.tolerance * sc.numerics.scan_step))


def run(sc: GrainScene, ctx: Context) -> Result:
    """Simulate the scene: trajectory and impact tables, summary, and the plots."""
    started = time.perf_counter()
    m = simulate_watched(sc, ctx)
    summary = {"mode": sc.numerics.mode, "impact_law": sc.model.law.kind, "effects": sc.model.effects.__dict__,
               "wall_time_s": time.perf_counter() - started,
               **m.summary(), "captions": plotting.captions(plots.MOTION, sc.output)}
    warnings = summary.pop("warnings")
    checks = _checks(summary, m.impacts)
    if summary["bounces"]:
        sampling, advice = _sampling(sc, summary["duration_s"], summary["bounces"])
        checks.append(sampling)
        warnings += advice

    def draw(folder: Path) -> list[Path]:
        return plots.motion_plots(sc, m, folder, sc.output)

    return Result("grain", summary, {"trajectory": _trajectory(m), "impacts": _impacts(m)},
                  plots=draw, warnings=warnings, events="impacts", headline=_headline(summary), checks=checks)


def transport(sc: GrainScene, m: motion.Motion) -> tuple[tuple, list[str]]:
    """What a sweep reads of a grain's run, as :func:`run` reports it but without its tables: (mean transport
    velocity along X and Y [m/s], fraction of the time in flight) and the run's warnings (the motion's, then the
    sampling advice). SymmechError for a non-finite result, as the run's."""
    duration = m.final.t - m.start.t
    (vx, vy), flight_share = m.transport_velocity(), m.time_in.get("flight", 0.0) / duration
    bad = ~np.isfinite(m.trajectory)
    if bad.any() or not all(map(math.isfinite, (vx, vy, flight_share))):
        row = int(np.argwhere(bad)[0, 0]) if bad.any() else -1
        raise SymmechError(f"non-finite result: the grain's trajectory or transport (row {row})")
    warnings = list(m.warnings)
    bounces = len(m.impact_times())
    if bounces:
        warnings += _sampling(sc, duration, bounces)[1]
    return (vx, vy, flight_share), warnings


def sweep_answers(scenes: list) -> list:
    """Per grain scene of ``scenes`` (GrainScenes), run together as one population (:func:`simulate_many`), what a
    sweep reads of it (:func:`transport`) or its SymmechError (the kind's ``population``)."""
    answers = []
    for sc, m in zip(scenes, simulate_many(scenes, workers=1, strict=False)):
        try:
            if isinstance(m, SymmechError):
                raise m
            answers.append(transport(sc, m))
        except SymmechError as exc:
            answers.append(exc)
    return answers


MIN_SAMPLES_PER_IMPACT = 2  # trajectory rows per mean interval between impacts, to draw the bounces


def _headline(s: dict) -> list[Headline]:
    """Transport velocity, time shares, impacts, dissipation: the answers of a grain run."""
    over = f"mean over {s['duration_s']:.4g} s"
    vx, vy = s["mean_transport_velocity_m_s"]
    out = [Headline("transport velocity along the slope", vx, "m/s", "net displacement along X / duration", over),
           Headline("transport velocity across the slope", vy, "m/s", "net displacement along Y / duration", over)]
    for regime, share in s["time_fraction"].items():
        spent = "in flight" if regime == "flight" else regime
        out.append(Headline(f"time {spent}", 100 * share, "%", f"share of the run spent {spent}"))
    out += [Headline("impacts", s["bounces"], "1", "rows of impacts.csv"),
            Headline("energy dissipated by impacts", s["energy_dissipated_by_impacts_J"], "J",
                     "sum of ke_before - ke_after over impacts.csv")]
    budget = s.get("energy_budget")
    if budget:
        lost = budget["lost_in_impacts_J"] + budget["lost_at_landings_J"] + budget["lost_in_sliding_J"]
        out.append(Headline("energy dissipated in all", lost, "J", "impacts, landings and sliding friction"))
    return out


def _checks(s: dict, impacts: list) -> list[Check]:
    out = [at_most("impacts creating energy", s["impacts_creating_energy"], 0),
           at_most("impacts whose solver did not converge", sum(not i["converged"] for i in impacts), 0)]
    budget = s.get("energy_budget")
    if budget:
        out.insert(0, at_most("energy balance closes (relative residual)", budget["relative_residual"],
                              budget["tolerance"]))
    if any(i["printed_creates_energy"] is not None for i in impacts):
        out.append(at_most("impacts where the printed law would create energy",
                           s["impacts_where_printed_law_creates_energy"], 0, otherwise="warn"))
    return out


def _sampling(sc: GrainScene, duration: float, bounces: int) -> tuple[Check, list[str]]:
    """Can the trajectory show the bounces (``bounces`` > 0 over ``duration`` [s])? Its rows per mean interval
    between impacts, and advice if not."""
    gap = duration / bounces
    per_impact = gap / sc.numerics.sample_interval
    check = Check("trajectory rows per mean interval between impacts", per_impact, "1",
                  f">= {MIN_SAMPLES_PER_IMPACT}", "pass" if per_impact >= MIN_SAMPLES_PER_IMPACT else "warn")
    if check.verdict == "pass":
        return check, []
    return check, [f"grain: {bounces} impacts in {duration:.4g} s, one every {gap:.3g} s on average, "
                   f"but trajectory rows every {sc.numerics.sample_interval:.3g} s: set numerics.sample_interval "
                   f"<= {gap / MIN_SAMPLES_PER_IMPACT:.3g} s to see the bounces"]


TRAJECTORY = (Column("t", "s", "time"), *(Column(x, "m", f"centre {x}, KXYZ, relative") for x in "xyz"),
              *(Column(f"v{x}", "m/s", f"centre velocity {x}, relative") for x in "xyz"),
              *(Column(f"q{i}", "1", "orientation quaternion (scalar first), body axes in KXYZ") for i in range(4)),
              *(Column(f"w{x}", "rad/s", f"angular velocity {x}, KXYZ") for x in "xyz"))


def _trajectory(m: motion.Motion) -> Table:
    tr = m.trajectory
    return Table(TRAJECTORY, np.delete(tr, T_AT.regime, axis=1), "rows at the sample interval and at every event; "
                 "regime: flight, impact (pre and post rows) or sliding",
                 {"regime": [motion.REGIMES[int(c)] for c in tr[:, T_AT.regime]]})


IMPACTS = (Column("t", "s", "impact time"), *(Column(x, "m", f"centre {x}") for x in "xyz"),
           *(Column(f"v{x}_{when}", "m/s", f"centre velocity {x} {when} the impact, relative")
             for when in ("before", "after") for x in "xyz"),
           *(Column(f"w{i}_{when}", "rad/s", f"body-axis rate {i} {when} the impact")
             for when in ("before", "after") for i in (1, 2, 3)),
           *(Column(f"T{x}", "N s", f"impulse {x}") for x in "xyz"),
           Column("ke_before", "J", "kinetic energy before"), Column("ke_after", "J", "kinetic energy after"),
           Column("energy_change", "J", "ke_after - ke_before"))
IMPACT_FLAGS = ("admissible", "printed_law_admissible", "printed_law_creates_energy", "converged")


def _impacts(m: motion.Motion) -> Table:
    rows = [[i["t"], *i["r"], *i["v_before"], *i["v_after"], *i["w_before"], *i["w_after"], *i["impulse"],
             i["ke_before"], i["ke_after"], i["ke_after"] - i["ke_before"]] for i in m.impacts]
    flags = {name: ["" if i[key] is None else str(i[key]) for i in m.impacts]
             for name, key in zip(IMPACT_FLAGS, ("admissible", "printed_admissible", "printed_creates_energy",
                                                 "converged"))}
    return Table(IMPACTS, np.array(rows).reshape(len(rows), len(IMPACTS)),
                 "one row per impact; admissible: no energy created by this law; printed_law_*: the printed "
                 "law's verdict at this impact (empty when not evaluated)", flags)


def precision(sc: GrainScene, ctx: Context) -> Result:
    """Work-precision study: paper mode over steps and node counts, accurate mode over tolerances."""
    p = sc.precision
    duration = min(sc.duration, 4 * sc.model.period) if p["duration"] is None else p["duration"]
    ref_tol = p["reference_tolerance"]
    acc = replace(sc.numerics, mode="accurate", as_printed=False)
    ref_num = replace(acc, tolerance=ref_tol, scan_step=acc.scan_step / 4)
    with watchdog(ctx, where="grain precision study"):
        ref = simulate(sc, ref_num, duration).final
        scale = max(float(np.linalg.norm(ref.r - sc.start.r)), max(sc.model.axes))
        rows = []

        def add(method, knob, value, num):
            ctx.tick(f"grain precision study, {method}")
            seconds, m = wp.best_time(lambda: simulate(sc, num, duration), repeats=1, min_seconds=0.0)
            rows.append({"method": method, "knob": knob, "value": value, "seconds": seconds,
                         "error": float(np.linalg.norm(m.final.r - ref.r) / scale)})

        for tol in (1e-3, 1e-5, 1e-7, 1e-9):
            add("accurate (exact flight, root-located contact)", "tolerance", tol, replace(acc, tolerance=tol))
        paper = replace(sc.numerics, mode="paper", as_printed=False)
        period = sc.model.period
        for steps in (100, 300, 1000, 3000):
            add(f"paper mode, {paper.nodes} nodes", "dt", period / steps, replace(paper, dt=period / steps))
        for nodes in (50, 200, 800):
            add("paper mode, dt = T/1000, nodes", "nodes", nodes, replace(paper, dt=period / 1000, nodes=nodes))
    reference = (f"accurate mode at tolerance {ref_tol:g}, scan step {ref_num.scan_step:.3g} s, "
                 f"duration {duration:.4g} s")
    return wp.result("grain", rows, "precision_grain", "Grain motion: work-precision (final position)", reference)


registry.register(registry.Kind(
    name="grain", summary="the whole motion of a grain on an inclined vibrating surface (seed 000, eqs (61)-(64))",
    schema=SCHEMA, prepare=prepare, run=run, estimate=estimate, precision=precision, docs="docs/scenes-grain.md",
    sample=sample,
    sweep=sweep.run, population=sweep_answers))
