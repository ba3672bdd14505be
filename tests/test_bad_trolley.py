"""Named bad trolley scenes: each is refused before any work with one line naming the field."""
import pytest

from badinput import DELETE, assert_rejected, bundled, changed, cli_rejects

HELIX = "trolley_helix"
HILL = "trolley_table_hill"
ELASTIC = "trolley_elastic_helix"
EXPR = {"kind": "trolley", "track": {"type": "expression", "x": "s", "y": "0", "z": "0"},
        "trolley": {"mass": 100.0, "com": [0.0, 0.0, 0.0], "axle_distance": 2.0, "half_gauge": 1.0},
        "motion": {"speed": "10"}, "time": {"t_end": 2.0, "steps": 20}}
TRACTION = {**EXPR, "effects": {"traction": True}, "motion": {"traction": "100"}}

CASES = [
    # types and structure
    ("kind-misspelt", HELIX, "kind", "trolly", "kind"),
    ("conventions-unknown", HELIX, "conventions", "papr", "conventions"),
    ("frame-unknown", HELIX, "frame", "frenett", "frame"),
    ("unknown-top-field", HELIX, "colour", "red", "colour"),
    ("unknown-trolley-field-did-you-mean", HELIX, "trolley.mas", 3.0, "trolley.mas"),
    ("unknown-effect", HELIX, "effects.wind", True, "effects.wind"),
    ("track-not-a-table", HELIX, "track", 3, "track"),
    ("track-type-unknown", HELIX, "track", {"type": "spiral"}, "track.type"),
    ("trolley-mass-missing", HELIX, "trolley.mass", DELETE, "trolley.mass"),
    ("helix-field-on-expression-track", EXPR, "track.radius", 7.0, "track.radius"),
    ("gravity-not-bool", HELIX, "effects.gravity", "yes", "effects.gravity"),
    ("steps-float", HELIX, "time.steps", 10.5, "time.steps"),
    ("steps-zero", HELIX, "time.steps", 0, "time.steps"),
    ("steps-huge", HELIX, "time.steps", 10**9, "time.steps"),
    ("com-two-numbers", HELIX, "trolley.com", [1.0, 0.5], "trolley.com"),
    ("com-string-entry", HELIX, "trolley.com", [1.0, "a", 0.0], "trolley.com[1]"),
    ("fd-order-three", HELIX, "numerics.fd_order", 3, "numerics.fd_order"),
    # ranges, NaN, inf, overflow, underflow
    ("mass-negative", HELIX, "trolley.mass", -5.0, "trolley.mass"),
    ("mass-nan", HELIX, "trolley.mass", float("nan"), "trolley.mass"),
    ("mass-inf", HELIX, "trolley.mass", float("inf"), "trolley.mass"),
    ("mass-underflow-1e-308", HELIX, "trolley.mass", 1e-308, "trolley.mass"),
    ("mass-huge-int-overflow", HELIX, "trolley.mass", 10**400, "trolley.mass"),
    ("axle-zero", HELIX, "trolley.axle_distance", 0.0, "trolley.axle_distance"),
    ("half-gauge-negative", HELIX, "trolley.half_gauge", -1.0, "trolley.half_gauge"),
    ("duration-1e308", HELIX, "time.t_end", 1e308, "time.t_end"),
    ("duration-zero", HELIX, "time.t_end", 0.0, "time.t_end"),
    ("g0-zero", HELIX, "constants.g0", 0.0, "constants.g0"),
    ("helix-radius-negative", HELIX, "track.radius", -7.0, "track.radius"),
    ("comfort-decreasing", HELIX, "comfort.x2", [6.0, -1.5], "comfort.x2"),
    ("fd-step-beyond-tenth-of-axle", HELIX, "numerics.fd_step", 0.5, "numerics.fd_step"),
    ("s0-negative", HELIX, "motion.s0", -1.0, "motion.s0"),
    ("huge-speed", HELIX, "motion.speed", "1e5 + t", "motion.speed"),
    # physical admissibility
    ("inertia-negative-moment", HELIX, "trolley.inertia", [-1.0, 2.0, 2.0, 0, 0, 0], "trolley.inertia"),
    ("inertia-not-positive-definite", HELIX, "trolley.inertia", [1.0, 1.0, 1.0, 2.0, 0, 0], "trolley.inertia"),
    ("inertia-triangle-violated", HELIX, "trolley.inertia", [1.0, 1.0, 5.0, 0, 0, 0], "trolley.inertia"),
    ("inertia-five-entries", HELIX, "trolley.inertia", [1.0, 1.0, 1.0, 0, 0], "trolley.inertia"),
    ("twist-with-frenet", HELIX, "track.twist", "0.1*s", "track.twist"),
    ("traction-without-expression", EXPR, "effects", {"traction": True}, "motion.traction"),
    ("traction-in-paper-conventions", "trolley_helix_paper", "effects.traction", True, "effects.traction"),
    ("table-points-coincide", HILL, "track.points[3]", [4.0, 0.0915, 0.6237], "track.points"),
    ("table-too-few-points", HILL, "track.points", [[0, 0, 0], [1, 0, 0]], "track.points"),
    ("table-point-nan", HILL, "track.points[2]", [4.0, float("nan"), 0.6], "track.points[2][1]"),
    ("table-smoothing-negative", HILL, "track.smoothing", -0.01, "track.smoothing"),
    ("motion-leaves-table", HILL, "time.t_end", 40.0, "motion.speed"),
    ("paper-tables-off-grid", HELIX, "time.steps", 4999, "report.paper_tables"),
    # the [elastic] table (docs/scenes-trolley-elastic.md)
    ("elastic-not-a-table", ELASTIC, "elastic", 3, "elastic"),
    ("elastic-unknown-field-did-you-mean", ELASTIC, "elastic.rolers", {}, "elastic.rolers"),
    ("elastic-beam-young-modulus-not-a-field", ELASTIC, "elastic.beams[0].E", 2e11, "elastic.beams[0].E"),
    ("elastic-beam-ei-negative", ELASTIC, "elastic.beams[0].ei", [-2e4, 3e4], "elastic.beams[0].ei[0]"),
    ("elastic-beam-ei-one-plane", ELASTIC, "elastic.beams[0].ei", [2e4], "elastic.beams[0].ei"),
    ("elastic-beam-length-zero", ELASTIC, "elastic.beams[0].length", 0.0, "elastic.beams[0].length"),
    ("elastic-beam-length-subnormal", ELASTIC, "elastic.beams[0].length", 5e-324, "elastic.beams[0].length"),
    ("elastic-beam-mass-subnormal", ELASTIC, "elastic.beams[0].mass_per_length", 5e-324,
     "elastic.beams[0].mass_per_length"),
    ("elastic-beam-mass-nan", ELASTIC, "elastic.beams[0].mass_per_length", float("nan"),
     "elastic.beams[0].mass_per_length"),
    ("elastic-beam-axis-zero", ELASTIC, "elastic.beams[0].axis", [0, 0, 0], "elastic.beams[0].axis"),
    ("elastic-beam-plane-along-axis", ELASTIC, "elastic.beams[0].plane", [0, 3, 0], "elastic.beams[0].plane"),
    ("elastic-beam-support-unknown", ELASTIC, "elastic.beams[0].support", "clamped", "elastic.beams[0].support"),
    ("elastic-beam-modes-nine", ELASTIC, "elastic.beams[0].modes", 9, "elastic.beams[0].modes"),
    ("elastic-beam-damping-ratio-one", ELASTIC, "elastic.beams[0].damping_ratio", 1.0,
     "elastic.beams[0].damping_ratio"),
    ("elastic-roller-stiffness-zero", ELASTIC, "elastic.rollers.stiffness", [1e7, 1e7, 0.0, 1e7, 1e7],
     "elastic.rollers.stiffness[2]"),
    ("elastic-roller-stiffness-four", ELASTIC, "elastic.rollers.stiffness", [1e7] * 4, "elastic.rollers.stiffness"),
    ("elastic-roller-damping-negative", ELASTIC, "elastic.rollers.damping", [-1.0] * 5, "elastic.rollers.damping[0]"),
    ("elastic-roller-law-unknown", ELASTIC, "elastic.rollers.law", "cubic", "elastic.rollers.law"),
    ("elastic-rollers-missing", ELASTIC, "elastic.rollers", DELETE, "elastic.rollers"),
    ("elastic-point-beam-index", ELASTIC, "elastic.points[0].beam", 4, "elastic.points[0].beam"),
    ("elastic-point-xi-beyond-tip", ELASTIC, "elastic.points[0].xi", 1.5, "elastic.points[0].xi"),
    ("elastic-point-name-digit", ELASTIC, "elastic.points[1].name", "1seat", "elastic.points[1].name"),
    ("elastic-point-name-twice", ELASTIC, "elastic.points[1].name", "tip", "elastic.points[1].name"),
    ("elastic-point-nowhere", ELASTIC, "elastic.points[1].at", DELETE, "elastic.points[1]"),
    ("elastic-method-unknown", ELASTIC, "elastic.numerics.method", "Euler", "elastic.numerics.method"),
    ("elastic-resonance-band-zero", ELASTIC, "elastic.numerics.resonance_band", 0.0,
     "elastic.numerics.resonance_band"),
    ("elastic-effect-not-bool", ELASTIC, "elastic.effects.body", "yes", "elastic.effects.body"),
    ("elastic-in-paper-conventions", ELASTIC, "conventions", "paper", "elastic"),
    ("elastic-rollers-under-a-point-mass", ELASTIC, "trolley.inertia", [0.0] * 6, "trolley.inertia"),
    ("elastic-traction-without-effects", TRACTION, "elastic", {"effects": {"rollers": False, "body": False}},
     "elastic.effects"),
    ("elastic-initial-unknown-field", ELASTIC, "elastic.initial.q", [0.0], "elastic.initial.q"),
    ("elastic-initial-rollers-four", ELASTIC, "elastic.initial.rollers", [0.0] * 4, "elastic.initial.rollers"),
    ("elastic-initial-roller-offset-beyond-0.1", ELASTIC, "elastic.initial.rollers", [0, 0, 0.5, 0, 0],
     "elastic.initial.rollers[2]"),
    ("elastic-initial-roller-rate-nan", ELASTIC, "elastic.initial.roller_rates", [float("nan"), 0, 0, 0, 0],
     "elastic.initial.roller_rates[0]"),
    ("elastic-initial-beam-index", ELASTIC, "elastic.initial.beams", [{"beam": 2, "plane": 1, "amplitude": 0.01}],
     "elastic.initial.beams[0].beam"),
    ("elastic-initial-beam-plane-three", ELASTIC, "elastic.initial.beams", [{"beam": 0, "plane": 3}],
     "elastic.initial.beams[0].plane"),
    ("elastic-initial-beam-plane-missing", ELASTIC, "elastic.initial.beams", [{"beam": 0}],
     "elastic.initial.beams[0].plane"),
    ("elastic-initial-beam-mode-beyond-modes", ELASTIC, "elastic.initial.beams", [{"beam": 0, "plane": 1, "mode": 4}],
     "elastic.initial.beams[0].mode"),
    ("elastic-initial-beam-amplitude-beyond-tenth-of-length", ELASTIC, "elastic.initial.beams",
     [{"beam": 0, "plane": 1, "amplitude": 0.2}], "elastic.initial.beams[0].amplitude"),
    ("elastic-initial-beam-mode-twice", ELASTIC, "elastic.initial.beams",
     [{"beam": 0, "plane": 1, "amplitude": 0.01}, {"beam": 0, "plane": 1, "amplitude": 0.02}],
     "elastic.initial.beams[1]"),
    # expressions
    ("speed-1-over-0", HELIX, "motion.speed", "1/0", "motion.speed"),
    ("speed-log0-times-t", HELIX, "motion.speed", "log(0)*t", "motion.speed"),
    ("speed-complex-power", HELIX, "motion.speed", "(-1)**0.5", "motion.speed"),
    ("speed-sin-two-args", HELIX, "motion.speed", "sin(1,2)", "motion.speed"),
    ("speed-power-tower", HELIX, "motion.speed", "9**9**9", "motion.speed"),
    ("speed-name-x0", HELIX, "motion.speed", "x0*t", "motion.speed"),
    ("speed-name-numpy", HELIX, "motion.speed", "numpy.pi*t", "motion.speed"),
    ("speed-dunder-import", HELIX, "motion.speed", "__import__('os')", "motion.speed"),
    ("speed-pole-inside-run", HELIX, "motion.speed", "1/(t-2)", "motion.speed"),
    ("speed-nan-after-5s", HELIX, "motion.speed", "sqrt(5 - t)", "motion.speed"),
    ("speed-a-list", HELIX, "motion.speed", [3.0], "motion.speed"),
    ("speed-number-nan", HELIX, "motion.speed", float("nan"), "motion.speed"),
    ("fd-step-underflow", HELIX, "numerics.fd_step", 1e-308, "numerics.fd_step"),
    ("helix-radius-underflow", HELIX, "track.radius", 1e-308, "track.radius"),
    ("speed-overflow-exp", HELIX, "motion.speed", "exp(50*t)", "motion.speed"),
    ("track-x-power-tower", EXPR, "track.x", "s + 9**9**9", "track.x"),
    ("track-x-derivatives-explode", EXPR, "track.x", "s + 1e-9*" + "**".join(["(s + 2)"] * 12), "track.x"),
    ("track-x-unknown-name", EXPR, "track.y", "q*s", "track.y"),
    ("track-x-not-arc-length", EXPR, "track.x", "2*s", "track.x"),
    ("track-y-log-singular", EXPR, "track.y", "0.01*log(s - 5)", "track.y"),
    ("track-constant-named-x0", EXPR, "track.constants", {"x0": 1.0}, "track.constants.x0"),
    ("track-constant-named-numpy", EXPR, "track.constants", {"numpy": 1.0}, "track.constants.numpy"),
    ("twist-singular", EXPR, "track.twist", "1/(s-3)", "track.twist"),
    ("u-range-decreasing", EXPR, "track", {"type": "expression", "parameter": "u", "x": "u", "y": "0", "z": "0",
                                           "u_range": [2.0, 1.0]}, "track.u_range"),
    ("u-track-singular", EXPR, "track", {"type": "expression", "parameter": "u", "x": "u", "y": "sqrt(u)",
                                         "z": "0", "u_range": [-1.0, 1.0]}, "track.y"),
]


@pytest.mark.parametrize("base, path, value, field", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_bad_trolley_scene_is_refused_naming_the_field(base, path, value, field):
    data = bundled(base) if isinstance(base, str) else base
    assert_rejected(changed(data, path, value), field)


def test_corpus_has_at_least_45_cases():
    assert len(CASES) >= 45 and len({c[0] for c in CASES}) == len(CASES)


SCENE = """
kind = "trolley"
[track]
type = "expression"
x = "s"
y = "0"
z = "0"
[trolley]
mass = 100.0
com = [0.0, 0.0, 0.0]
axle_distance = 2.0
half_gauge = 1.0
[motion]
speed = "{speed}"
[time]
t_end = 10.0
steps = 100
"""


@pytest.mark.parametrize("speed, words", [
    ("9**9**9", "exponent"),
    ("sqrt(5 - t)", "motion.speed"),
    ("__import__('os').system('true')", "only the functions"),
    ("log(0)*t", "motion.speed"),
], ids=["power-tower", "nan-speed-names-field-and-time", "import", "log0"])
def test_cli_refuses_in_one_line(tmp_path, speed, words):
    line = cli_rejects(tmp_path, SCENE.format(speed=speed), words)
    assert "scene field 'motion.speed'" in line


def test_long_run_is_refused_by_its_estimate_before_any_work():
    from symmech.core import pipeline
    from symmech.core.context import Context
    from symmech.core.scene import SymmechError

    scene = pipeline.load(changed(bundled(HELIX), "time.steps", 1_000_000))
    assert scene.estimate().seconds > 100
    with pytest.raises(SymmechError, match="exceeds --max-time 10 s"):
        scene.run(Context(quiet=True, max_time=10.0))
