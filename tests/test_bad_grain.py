"""Bad grain scenes: every one refused before any work, one line naming the field."""
import json
import math
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from badinput import DELETE, assert_rejected, bundled, changed, cli_rejects, edited
from symmech.core import pipeline
from symmech.core.context import Context
from symmech.core.scene import SymmechError
from symmech.core.schema import markdown
from symmech.grain import motion, motion_scene, sliding

ROOT = Path(__file__).resolve().parents[1]
BASE = bundled("grain_default")
BASE_TEXT = (ROOT / "scenes" / "grain_default.toml").read_text()


def edits(*pairs):
    return edited(BASE, *pairs)


MASS = (("body.density", DELETE),)  # a scene that gives the mass directly
CASES = [
    # types, ranges and overflow of plain numbers
    ("duration-string", edits(("duration", "2 s")), "duration"),
    ("duration-bool", edits(("duration", True)), "duration"),
    ("duration-zero", edits(("duration", 0.0)), "duration"),
    ("duration-negative", edits(("duration", -1.0)), "duration"),
    ("duration-1e308", edits(("duration", 1e308)), "duration"),
    ("duration-nan", edits(("duration", math.nan)), "duration"),
    ("duration-inf", edits(("duration", math.inf)), "duration"),
    ("duration-int-overflows-float", edits(("duration", 10**400)), "duration"),
    ("title-not-text", edits(("title", 123)), "title"),
    ("kind-typo", edits(("kind", "grian")), "kind"),
    ("unknown-top-level-field", edits(("durration", 2.0)), "durration"),
    ("numerics-not-a-table", edits(("numerics", 5)), "numerics"),
    # the body: shape, mass, density, inertia underflow
    ("body-missing", edits(("body", DELETE)), "body"),
    ("semi-axes-two-numbers", edits(("body.semi_axes", [1e-3, 1e-3])), "body.semi_axes"),
    ("semi-axis-zero", edits(("body.semi_axes", [1e-3, 0.0, 1e-3])), "body.semi_axes[1]"),
    ("semi-axis-negative", edits(("body.semi_axes", [1e-3, -1e-3, 1e-3])), "body.semi_axes[1]"),
    ("semi-axis-inertia-underflows", edits(("body.semi_axes", [1e-160, 1e-160, 1e-160])), "body.semi_axes[0]"),
    ("semi-axes-needle-aspect-5000", edits(("body.semi_axes", [0.5, 1e-4, 1e-4])), "body.semi_axes"),
    ("mass-underflows-1e-308", edits(*MASS, ("body.mass", 1e-308)), "body.mass"),
    ("mass-nan", edits(*MASS, ("body.mass", math.nan)), "body.mass"),
    ("mass-negative", edits(*MASS, ("body.mass", -1.0)), "body.mass"),
    ("mass-and-density", edits(("body.mass", 1e-5)), "body.mass"),
    ("neither-mass-nor-density", edits(*MASS), "body.mass"),
    ("density-1e-300", edits(("body.density", 1e-300)), "body.density"),
    ("density-above-range", edits(("body.density", 1e6)), "body.density"),
    ("density-gives-mass-below-range", edits(("body.semi_axes", [2e-5, 2e-5, 2e-5]), ("body.density", 2.0)),
     "body.density"),
    ("orientation-1e20-rad", edits(("body.orientation", [0.0, 0.0, 1e20])), "body.orientation[2]"),
    ("orientation-not-a-list", edits(("body.orientation", "flat")), "body.orientation"),
    ("body-field-typo", edits(("body.semi_axis", [1e-3] * 3)), "body.semi_axis"),
    # the surface and its vibration
    ("alpha-90-deg", edits(("surface.alpha_deg", 90.0)), "surface.alpha_deg"),
    ("surface-vertical-alpha-beta-60", edits(("surface.alpha_deg", 60.0), ("surface.beta_deg", 60.0)),
     "surface.beta_deg"),
    ("gravity-zero", edits(("surface.g", 0.0)), "surface.g"),
    ("gravity-negative", edits(("surface.g", -9.81)), "surface.g"),
    ("amplitude-negative", edits(("vibration.amplitude", -1e-3)), "vibration.amplitude"),
    ("frequency-zero", edits(("vibration.frequency", 0.0)), "vibration.frequency"),
    ("surface-speed-157-m-s", edits(("vibration.amplitude", 1.0)), "vibration.amplitude"),
    ("direction-unknown", edits(("vibration.direction", "diagonal")), "vibration.direction"),
    ("direction-vector-not-unit", edits(("vibration.direction", "vector"), ("vibration.angle_deg", DELETE),
                                        ("vibration.vector", [0.0, 0.0, 2.0])), "vibration.vector"),
    ("direction-vector-zero", edits(("vibration.direction", "vector"), ("vibration.angle_deg", DELETE),
                                    ("vibration.vector", [0.0, 0.0, 0.0])), "vibration.vector"),
    ("direction-vector-0.92-long", edits(("vibration.direction", "vector"), ("vibration.angle_deg", DELETE),
                                         ("vibration.vector", [0.6, 0.0, 0.7])), "vibration.vector"),
    ("direction-vector-missing", edits(("vibration.direction", "vector"), ("vibration.angle_deg", DELETE)),
     "vibration.vector"),
    ("angle-with-vertical-direction", edits(("vibration.direction", "vertical")), "vibration.angle_deg"),
    ("angle-270-deg", edits(("vibration.angle_deg", 270.0)), "vibration.angle_deg"),
    # the impact law and sliding friction
    ("impact-missing", edits(("impact", DELETE)), "impact"),
    ("law-unknown", edits(("impact.law", "newton")), "impact.law"),
    ("restitution-above-one", edits(("impact.e_n", 1.5)), "impact.e_n"),
    ("tangential-restitution-below-minus-one", edits(("impact.e_t", -2.0)), "impact.e_t"),
    ("impact-friction-negative", edits(("impact.mu", -0.5)), "impact.mu"),
    ("printed-law-without-e", edits(("impact", {"law": "printed", "lambda": 0.3})), "impact.e"),
    ("printed-coefficient-with-coulomb-law", edits(("impact.e", 0.5)), "impact.e"),
    ("sliding-friction-negative", edits(("sliding.friction", -0.1)), "sliding.friction"),
    ("sliding-friction-1e9", edits(("sliding.friction", 1e9)), "sliding.friction"),
    # the initial state
    ("velocity-1e6-m-s", edits(("initial.velocity", [1e6, 0.0, 0.0])), "initial.velocity[0]"),
    ("velocity-1e308", edits(("initial.velocity", [0.0, 1e308, 0.0])), "initial.velocity[1]"),
    ("velocity-nan", edits(("initial.velocity", [0.0, 0.0, math.nan])), "initial.velocity[2]"),
    ("spin-1e9-rad-s", edits(("initial.angular_velocity", [0.0, 0.0, 1e9])), "initial.angular_velocity[2]"),
    ("position-inside-surface", edits(("initial.position", [0.0, 0.0, 1e-4])), "initial.position"),
    ("position-two-numbers", edits(("initial.position", [0.0, 0.0])), "initial.position"),
    # effects, numerics, precision
    ("effects-typo", edits(("effects.vibrations", False)), "effects.vibrations"),
    ("effects-not-bool", edits(("effects.rotation", "yes")), "effects.rotation"),
    ("mode-unknown", edits(("numerics.mode", "fast")), "numerics.mode"),
    ("tolerance-zero", edits(("numerics.tolerance", 0.0)), "numerics.tolerance"),
    ("as-printed-in-accurate-mode", edits(("numerics.as_printed", True)), "numerics.as_printed"),
    ("sample-interval-2e9-rows", edits(("numerics.sample_interval", 1e-9)), "numerics.sample_interval"),
    ("max-impacts-zero", edits(("numerics.max_impacts", 0)), "numerics.max_impacts"),
    ("max-impacts-fraction", edits(("numerics.max_impacts", 1.5)), "numerics.max_impacts"),
    ("nodes-three", edits(("numerics.nodes", 3)), "numerics.nodes"),
    ("dt-negative", edits(("numerics.dt", -1.0)), "numerics.dt"),
    ("precision-field-typo", edits(("precision.durration", 0.1)), "precision.durration"),
    ("precision-reference-tolerance-1e-20", edits(("precision.reference_tolerance", 1e-20)),
     "precision.reference_tolerance"),
]


CASES_BY_ID = {c[0]: c[1] for c in CASES}


@pytest.mark.parametrize("data, field", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_bad_grain_scene_is_refused_naming_the_field(data, field):
    assert_rejected(data, field)


def test_corpus_is_large_and_named_uniquely():
    assert len(CASES) >= 45 and len({c[0] for c in CASES}) == len(CASES)


def test_messages_give_value_and_range():
    assert "1e-308 kg is outside [1e-12, 1000] kg" in str(assert_rejected(CASES_BY_ID["mass-underflows-1e-308"],
                                                                          "body.mass"))
    # A NaN mass is a NaN mass (it was reported as "unknown parameter 'nan'").
    assert "nan is not finite" in str(assert_rejected(CASES_BY_ID["mass-nan"], "body.mass"))
    assert "|d| = 2 is not a unit vector" in str(assert_rejected(CASES_BY_ID["direction-vector-not-unit"],
                                                                 "vibration.vector"))
    assert "did you mean 'duration'" in str(assert_rejected(CASES_BY_ID["unknown-top-level-field"], "durration"))


@pytest.mark.parametrize("replacements, words", [
    ((("density = 1300.0", "mass = 1e-308"),), "'body.mass': 1e-308 kg is outside [1e-12, 1000] kg"),
    ((("density = 1300.0", "mass = nan"),), "'body.mass': nan is not finite"),
    ((('direction = "angle"', 'direction = "vector"'), ("angle_deg = 30.0", "vector = [0.0, 0.0, 0.0]")),
     "'vibration.vector': [0, 0, 0] has no direction"),
])
def test_cli_refuses_in_one_line(tmp_path, replacements, words):
    text = BASE_TEXT
    for old, new in replacements:
        text = text.replace(old, new)
    cli_rejects(tmp_path, text, words)


def test_unit_vector_direction_equals_the_angle_it_names():
    """direction = "vector" with (cos 30°, 0, sin 30°) is the bundled throw angle of 30°."""
    c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
    as_vector = edits(("vibration.direction", "vector"), ("vibration.angle_deg", DELETE), ("vibration.vector", [c, 0, s]))
    a, b = pipeline.load(BASE).setup.model.vibration, pipeline.load(as_vector).setup.model.vibration
    np.testing.assert_allclose(b.direction, a.direction, rtol=0, atol=1e-15)


# --------------------------------------------------------------------------- no hang, estimate, progress


def test_a_surface_at_exactly_one_g_throws_nothing():
    """Normal vibration whose peak acceleration A (2 pi f)^2 equals g exactly (Gamma = 1): the surface never
    throws the grain, so the estimate is the one bounce sequence of a grain resting on it, launched at the
    surface's peak speed A 2 pi f: 1 + ln(v_rest / v0) / ln(e) bounces (the sequence ends long before 2 s)."""
    amplitude, frequency, e = 1e-3, 25.0, 0.4
    g = amplitude * (2 * math.pi * frequency) ** 2
    scene = pipeline.load(edits(("surface.g", g), ("surface.alpha_deg", 0.0), ("vibration.direction", "normal"),
                                ("vibration.angle_deg", DELETE), ("initial.position", DELETE)))
    v0 = amplitude * 2 * math.pi * frequency
    assert motion_scene.expected_impacts(scene.setup) == pytest.approx(1 + math.log(1e-5 / v0) / math.log(e),
                                                                         rel=1e-12)


def test_a_timed_sample_is_a_share_of_the_run_and_at_least_one_period():
    """The 2 s default scene (25 Hz: T = 0.04 s): a tenth is 0.2 s, a thousandth is raised to one period, and a
    share above one is the whole run; nothing else changes."""
    sc = pipeline.load(BASE).setup
    assert [motion_scene.sample(sc, share).duration for share in (0.1, 1e-3, 2.0)] == pytest.approx([0.2, 0.04, 2.0],
                                                                                                   rel=1e-15)
    assert motion_scene.sample(sc, 0.1).model is sc.model and motion_scene.sample(sc, 0.1).start is sc.start


def test_1000_s_scene_is_refused_at_once_past_max_time(tmp_path):
    scene = tmp_path / "long.toml"
    scene.write_text(re.sub(r"(?m)^duration = .*$", "duration = 1000.0", BASE_TEXT))
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "symmech", "run", str(scene), "--out", str(tmp_path / "o"),
                           "--max-time", "10"], capture_output=True, text=True, timeout=120)
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2 and len(lines) == 1 and "Traceback" not in proc.stderr
    # the compiled engine's estimate for 1000 s is ~30 s (1e5 impacts): above 10 s
    assert "estimated run time" in lines[0] and "impacts" in lines[0] and "--max-time 10" in lines[0]
    assert time.perf_counter() - start < 30
    assert not (tmp_path / "o").exists()


def test_estimated_bounces_of_a_dropped_sphere_follow_the_geometric_series():
    """Still plate, sphere dropped from h: bounces until the rebound is below rest_velocity, in closed form."""
    h, e, v_rest = 4e-3, 0.5, 1e-5
    data = edits(("duration", 0.5), ("body.semi_axes", [1e-3] * 3), ("vibration.amplitude", 0.0),
                 ("surface.alpha_deg", 0.0), ("impact.e_n", e), ("impact.e_t", 0.0),
                 ("initial.position", [0.0, 0.0, 1e-3 + h]), ("initial.angular_velocity", [0.0, 0.0, 0.0]))
    scene = pipeline.load(data)
    v0 = math.sqrt(2 * 9.81 * h)
    closed_form = 1 + math.log(v_rest / v0) / math.log(e)  # bounces whose rebound speed exceeds v_rest, + the last
    assert motion_scene.expected_impacts(scene.setup) == pytest.approx(closed_form, rel=1e-12)
    simulated = len(scene.run().tables["impacts"].data)
    assert abs(simulated - closed_form) <= 2, (simulated, closed_form)


def test_estimate_of_the_default_scene_is_within_a_factor_of_three_of_the_bounces():
    scene = pipeline.load(changed(BASE, "duration", 0.3))
    bounces = len(scene.run().tables["impacts"].data)
    assert 1 / 3 < motion_scene.expected_impacts(scene.setup) / bounces < 3


def test_incline_of_minus_37_7_deg_finishes_or_stops_within_the_budget():
    """A valid scene on an incline of -37.7 deg for 0.25 s crept for an estimated days."""
    scene = pipeline.load(edits(("duration", 0.25), ("surface.alpha_deg", -37.7)))
    ctx = Context(quiet=True, max_time=20.0)
    try:
        result = scene.run(ctx)
        assert result.summary["duration_s"] == pytest.approx(0.25)
    except SymmechError as err:
        assert "\n" not in str(err)
    assert ctx.elapsed() < 25.0


def test_a_creeping_phase_is_stopped_by_the_time_budget(monkeypatch):
    """A sliding phase that stops advancing (pure Python, no callback) ends at --max-time with one line."""
    def creep(model, t0, r0, v0, t_end, *args):
        deadline = time.perf_counter() + 30.0
        while time.perf_counter() < deadline:
            pass
        raise AssertionError("not stopped by the watchdog")

    monkeypatch.setattr(motion, "slide", creep)
    scene = pipeline.load(edits(("duration", 0.3), ("vibration.amplitude", 0.0), ("numerics.engine", "python"),
                                ("initial.position", DELETE)))  # resting on the plane: it slides at once
    ctx = Context(quiet=True, max_time=1.0)
    with pytest.raises(SymmechError, match=r"over the time budget --max-time 1 s \(grain simulation\)"):
        scene.run(ctx)
    assert ctx.elapsed() < 3.0


def test_a_phase_loop_that_stops_advancing_is_reported(monkeypatch):
    """Lift-off and landing at the same instant forever: the stagnation guard names the time."""
    def lift_at_once(model, body, t0, r0, v0, q0, w0, *args):
        return sliding.SlideResult(t0, np.asarray(r0), np.asarray(v0), np.asarray(w0), np.asarray(q0), True,
                                   0.0, 0.0,
                                   (np.zeros(0), np.zeros((0, 2)), np.zeros((0, 2)), np.zeros((0, 4)), np.zeros((0, 3))))

    monkeypatch.setattr(motion, "slide", lift_at_once)
    monkeypatch.setattr(motion, "MAX_IDLE_STEPS", 50)  # the guard, not its size, is under test
    scene = pipeline.load(edits(("duration", 0.3), ("vibration.amplitude", 0.0), ("numerics.engine", "python"),
                                ("initial.position", DELETE)))
    with pytest.raises(SymmechError, match=r"stopped advancing at t = [0-9.e-]+ s \(50 regime changes"):
        scene.run(Context(quiet=True, max_time=60.0))


def test_progress_reports_the_simulated_time(monkeypatch):
    monkeypatch.setattr(motion, "PROGRESS_INTERVAL", 0.0)  # every phase, not every 0.2 s of wall time
    seen = []

    class Bar:
        def __enter__(self):
            return self

        def __exit__(self, *exc):
            return False

        def update(self, dt):
            seen.append(dt)

    class Recording(Context):
        def progress(self, total, desc, unit="it"):
            seen.append((total, desc, unit))
            return Bar()

    # The Python loop reports every phase; the compiled one between batches of phases (test_grain_compiled).
    scene = pipeline.load(changed(changed(BASE, "duration", 0.1), "numerics.engine", "python"))
    scene.run(Recording(quiet=True))
    assert seen[0] == (0.1, "grain", "s")
    assert 0.05 < sum(seen[1:]) <= 0.1 + 1e-12 and len(seen) > 10


# --------------------------------------------------------------------------- outputs


def test_fastest_admissible_grain_gives_finite_strict_json(tmp_path):
    """Huge velocities gave NaN/Inf and invalid JSON; the largest admissible ones give finite output."""
    data = edits(("duration", 0.02), ("initial.velocity", [100.0, -100.0, 100.0]),
                 ("initial.angular_velocity", [1e4, -1e4, 1e4]))
    scene = pipeline.load(data)
    pipeline.write(scene.run(), tmp_path / "out", scene, plots=False)

    def refuse(constant):
        raise AssertionError(f"non-strict JSON constant {constant}")

    summary = json.loads((tmp_path / "out" / "summary.json").read_text(), parse_constant=refuse)
    assert summary["scene"]["initial"]["velocity"] == [100.0, -100.0, 100.0]
    header = (tmp_path / "out" / "impacts.csv").read_text().splitlines()[0]
    assert header.startswith("t [s],x [m],y [m],z [m],vx_before [m/s]") and "Tz [N s]" in header
    assert "ke_before [J]" in header and header.endswith("converged")


@pytest.mark.parametrize("path, schema", [("docs/scenes-grain.md", motion_scene.SCHEMA)])
def test_docs_hold_the_current_field_tables(path, schema):
    assert markdown(schema) in (ROOT / path).read_text()
