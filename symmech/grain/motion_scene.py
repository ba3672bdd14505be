"""Scene kind ``grain``: the whole motion of a grain on an inclined vibrating surface.

Fields are documented in docs/scenes-grain.md. ``run`` writes ``trajectory.csv``,
``impacts.csv``, ``path``, ``velocity`` and ``phase`` plots (PNG + SVG; and the CLI writes ``summary.json``);
``precision`` writes a work-precision study (CSV + PNG).
"""
from __future__ import annotations

import csv
import math
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from symmech.core import precision as wp
from symmech.core.scene import SceneError, Section
from symmech.generated import grain_motion as gm
from symmech.grain import contact, flight, motion, paper_mode, plots
from symmech.grain.body import rotation
from symmech.grain.coulomb_law import ImpactLaw


@dataclass(frozen=True)
class GrainScene:
    model: motion.Model
    numerics: motion.Numerics
    start: motion.State
    duration: float
    alpha_beta: tuple  # inclination [rad], for the printed gravity of paper mode as printed
    precision: Section


def parse(scene: Section) -> GrainScene:
    """Validate a grain scene; every problem names its field."""
    duration = scene.float("duration", unit="s", lo=0.0, lo_open=True, hi=1e4)
    scene.str("title", default="")
    scene.str("kind")
    effects_s = scene.section("effects", default={})
    effects = motion.Effects(**{k: effects_s.bool(k, default=True)
                                for k in ("vibration", "inclination", "rotation", "friction")})
    effects_s.finish()

    body = scene.section("body")
    axes = tuple(body.vector("semi_axes", 3, unit="m", lo=0.0, lo_open=True, hi=1.0))
    if body.has("mass") == body.has("density"):
        raise SceneError("body.mass", "give exactly one of body.mass [kg] or body.density [kg/m^3]")
    if body.has("mass"):
        mass = body.float("mass", unit="kg", lo=0.0, lo_open=True)
    else:
        mass = body.float("density", unit="kg/m^3", lo=0.0, lo_open=True) * 4.0 / 3.0 * math.pi * np.prod(axes)
    angles = body.vector("orientation", 3, unit="rad", default=[0.0, 0.0, 0.0])
    body.finish()

    surface = scene.section("surface", default={})
    g = surface.float("g", unit="m/s^2", default=9.81, lo=0.0, lo_open=True)
    alpha = math.radians(surface.float("alpha_deg", unit="deg", default=0.0, lo=-89.0, hi=89.0))
    beta = math.radians(surface.float("beta_deg", unit="deg", default=0.0, lo=-89.0, hi=89.0))
    surface.finish()
    if not effects.inclination:
        alpha = beta = 0.0
    if math.sin(alpha) ** 2 + math.sin(beta) ** 2 >= 1.0 - 1e-12:
        raise SceneError("surface.beta_deg", "sin^2(alpha) + sin^2(beta) must be < 1 (the surface would be vertical)")
    g_k = tuple(float(x) for x in gm.gravity(g, alpha, beta))

    vib_s = scene.section("vibration", default={})
    amplitude = vib_s.float("amplitude", unit="m", default=0.0, lo=0.0, hi=1.0)
    frequency = vib_s.float("frequency", unit="Hz", default=1.0, lo=0.0, lo_open=True, hi=1e5)
    phase = math.radians(vib_s.float("phase_deg", unit="deg", default=0.0))
    kind = vib_s.choice("direction", ("vertical", "normal", "angle"), default="vertical")
    angle = math.radians(vib_s.float("angle_deg", unit="deg", default=90.0, lo=-180.0, hi=180.0))
    vib_s.finish()
    direction = {"vertical": tuple(-x / g for x in g_k), "normal": (0.0, 0.0, 1.0),
                 "angle": (math.cos(angle), 0.0, math.sin(angle))}[kind]
    if not effects.vibration:
        amplitude = 0.0
    vibration = flight.Vibration(amplitude, 2 * math.pi * frequency, phase, direction)

    law = _law(scene.section("impact"))
    sliding = scene.section("sliding", default={})
    mu = sliding.float("friction", unit="", default=0.5, lo=0.0, hi=100.0) if effects.friction else 0.0
    if not effects.friction:
        sliding.float("friction", unit="", default=0.0, lo=0.0, hi=100.0)
    sliding.finish()

    model = motion.Model(axes, mass, g_k, vibration, law, mu, effects)
    numerics = _numerics(scene.section("numerics", default={}), model)

    init = scene.section("initial", default={})
    Q0 = rotation(np.array(angles))
    support = float(contact.support_distance(axes, Q0))
    r0 = np.array(init.vector("position", 3, unit="m", default=[0.0, 0.0, support]))
    v0 = np.array(init.vector("velocity", 3, unit="m/s", default=[0.0, 0.0, 0.0]))
    w0 = np.array(init.vector("angular_velocity", 3, unit="rad/s", default=[0.0, 0.0, 0.0]))
    init.finish()
    if r0[2] < support * (1.0 - 1e-12):
        raise SceneError("initial.position", f"z = {r0[2]:.6g} m puts the grain into the surface; "
                         f"with this orientation the centre must be at z >= {support:.6g} m")
    if not effects.rotation:
        w0 = np.zeros(3)
    start = motion.State(0.0, r0, v0, flight.quaternion_from_matrix(Q0), Q0.T @ w0)
    prec = scene.section("precision", default={})
    scene.finish()
    return GrainScene(model, numerics, start, duration, (alpha, beta), prec)


def _law(s: Section) -> ImpactLaw:
    kind = s.choice("law", ("printed", "coulomb"), default="coulomb")
    if kind == "printed":
        law = ImpactLaw("printed", e=s.float("e", unit="", lo=0.0, hi=1.0),
                        lam=s.float("lambda", unit="", lo=0.0, hi=1.0))
    else:
        # No mu: no Coulomb bound on the tangential impulse.
        mu = s.float("mu", unit="", lo=0.0, hi=1e6) if s.has("mu") else np.inf
        law = ImpactLaw("coulomb", e_n=s.float("e_n", unit="", lo=0.0, hi=1.0),
                        e_t=s.float("e_t", unit="", lo=-1.0, hi=1.0), mu=mu,
                        check_printed=s.bool("check_printed", default=True))
    s.finish()
    return law


def _numerics(s: Section, model: motion.Model) -> motion.Numerics:
    period = model.period
    mode = s.choice("mode", ("accurate", "paper"), default="accurate")
    num = motion.Numerics(
        mode=mode,
        tolerance=s.float("tolerance", unit="", default=1e-9, lo=1e-14, hi=1e-2),
        scan_step=s.float("scan_step", unit="s", default=period / 40, lo=0.0, lo_open=True),
        dt=s.float("dt", unit="s", default=period / 2000, lo=0.0, lo_open=True),
        nodes=s.int("nodes", default=400, lo=6, hi=100000),
        as_printed=s.bool("as_printed", default=False),
        rest_velocity=s.float("rest_velocity", unit="m/s", default=1e-5, lo=0.0, lo_open=True),
        max_impacts=s.int("max_impacts", default=100000, lo=1),
        sample_interval=s.float("sample_interval", unit="s", default=period / 40, lo=0.0, lo_open=True),
    )
    s.finish()
    if num.as_printed and mode != "paper":
        raise SceneError("numerics.as_printed", "the printed formulas apply to mode = \"paper\" only")
    return num


def simulate(sc: GrainScene, numerics: motion.Numerics | None = None, duration: float | None = None):
    """Run the scene's grain (optionally with other numerics or duration); returns a Motion."""
    num = numerics or sc.numerics
    t_end = sc.duration if duration is None else duration
    if num.mode == "paper":
        return paper_mode.simulate(sc.model, num, sc.start, t_end, sc.alpha_beta)
    return motion.simulate(sc.model, num, sc.start, t_end)


def run(scene: Section, out: Path) -> dict:
    sc = parse(scene)
    start = time.perf_counter()
    result = simulate(sc)
    seconds = time.perf_counter() - start
    _write_trajectory(result, out / "trajectory.csv")
    _write_impacts(result, out / "impacts.csv")
    plots.motion_plots(sc, result, out)
    summary = {"kind": "grain", "mode": sc.numerics.mode, "impact_law": sc.model.law.kind,
               "effects": sc.model.effects.__dict__, "wall_time_s": seconds, **result.summary()}
    summary["files"] = [str(out / n) for n in ("trajectory.csv", "impacts.csv", "path.png", "velocity.png", "phase.png")]
    return summary


def _write_trajectory(result: motion.Motion, path: Path) -> None:
    with path.open("w", newline="") as fh:
        fh.write("# relative to the surface frame KXYZ: r [m], v [m/s], quaternion q (body axes), "
                 "w [rad/s] in KXYZ; regime 0 flight, 1 impact, 2 sliding\n")
        writer = csv.writer(fh)
        writer.writerow(motion.TRAJECTORY_COLUMNS)
        for row in result.trajectory:
            writer.writerow([f"{x:.12g}" for x in row[:-1]] + [motion.REGIMES[int(row[-1])]])


IMPACT_COLUMNS = ("t", "x", "y", "z", "vx_before", "vy_before", "vz_before", "vx_after", "vy_after", "vz_after",
                  "w1_before", "w2_before", "w3_before", "w1_after", "w2_after", "w3_after",
                  "Tx", "Ty", "Tz", "ke_before", "ke_after", "energy_change", "admissible",
                  "printed_law_admissible", "printed_law_creates_energy", "converged")


def _write_impacts(result: motion.Motion, path: Path) -> None:
    with path.open("w", newline="") as fh:
        fh.write("# velocities relative to the surface [m/s], w body-axis rates [rad/s], impulse T [N s], "
                 "energies [J]; printed_law_admissible / printed_law_creates_energy: the printed law's verdict at "
                 "this impact (admissible: no energy created and no pull into the plane)\n")
        writer = csv.writer(fh)
        writer.writerow(IMPACT_COLUMNS)
        for i in result.impacts:
            values = [i["t"], *i["r"], *i["v_before"], *i["v_after"], *i["w_before"], *i["w_after"],
                      *i["impulse"], i["ke_before"], i["ke_after"], i["ke_after"] - i["ke_before"]]
            writer.writerow([f"{x:.12g}" for x in values] +
                            [i["admissible"], *("" if i[k] is None else i[k]
                                                 for k in ("printed_admissible", "printed_creates_energy")),
                             i["converged"]])


def precision(scene: Section, out: Path) -> dict:
    """Work-precision study: paper mode over steps and node counts, accurate mode over tolerances."""
    sc = parse(scene)
    p = sc.precision
    duration = p.float("duration", unit="s", default=min(sc.duration, 4 * sc.model.period), lo=0.0, lo_open=True)
    ref_tol = p.float("reference_tolerance", unit="", default=1e-12, lo=1e-14, hi=1e-6)
    p.finish()
    acc = replace(sc.numerics, mode="accurate", as_printed=False)
    ref_num = replace(acc, tolerance=ref_tol, scan_step=acc.scan_step / 4)
    ref = simulate(sc, ref_num, duration).final
    scale = max(float(np.linalg.norm(ref.r - sc.start.r)), max(sc.model.axes))

    def error(m):
        return float(np.linalg.norm(m.final.r - ref.r) / scale)

    rows = []

    def add(method, knob, value, num):
        seconds, m = wp.best_time(lambda: simulate(sc, num, duration), repeats=1, min_seconds=0.0)
        rows.append({"method": method, "knob": knob, "value": value, "seconds": seconds, "error": error(m)})

    for tol in (1e-3, 1e-5, 1e-7, 1e-9):
        add("accurate (exact flight, root-located contact)", "tolerance", tol, replace(acc, tolerance=tol))
    paper = replace(sc.numerics, mode="paper", as_printed=False)
    period = sc.model.period
    for steps in (100, 300, 1000, 3000):
        add(f"paper mode, {paper.nodes} nodes", "dt", period / steps, replace(paper, dt=period / steps))
    for nodes in (50, 200, 800):
        add(f"paper mode, dt = T/1000, nodes", "nodes", nodes, replace(paper, dt=period / 1000, nodes=nodes))
    files = wp.write(rows, out, "precision_grain", "Grain motion: work-precision (final position)",
                     f"accurate mode at tolerance {ref_tol:g}, scan step {ref_num.scan_step:.3g} s, "
                     f"duration {duration:.4g} s")
    return {"files": [str(f) for f in files], "rows": rows}
