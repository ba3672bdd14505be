"""Bad impact scenes: every one refused before any solve, one line naming the field; the estimate's refusal."""
import math
from pathlib import Path

import pytest

from badinput import DELETE, assert_rejected, bundled, cli_rejects, edited
from symmech.core import pipeline
from symmech.core.context import Context
from symmech.core.scene import SymmechError
from symmech.core.schema import markdown
from symmech.grain import impact_scene

ROOT = Path(__file__).resolve().parents[1]
BASE = bundled("impact_default")
BASE_TEXT = (ROOT / "scenes" / "impact_default.toml").read_text()


def edits(*pairs):
    return edited(BASE, *pairs)


CASES = [
    ("kind-typo", edits(("kind", "impcat")), "kind"),
    ("unknown-top-level-field", edits(("solvers", {})), "solvers"),
    ("title-not-text", edits(("title", ["a"])), "title"),
    ("body-not-a-table", edits(("body", 3)), "body"),
    ("semi-axis-zero", edits(("body.semi_axes", [2e-3, 0.0, 1e-3])), "body.semi_axes[1]"),
    ("semi-axes-inertia-underflows", edits(("body.semi_axes", [1e-160, 1e-160, 1e-160])), "body.semi_axes[0]"),
    ("semi-axes-four-numbers", edits(("body.semi_axes", [1e-3] * 4)), "body.semi_axes"),
    ("semi-axes-aspect-2000", edits(("body.semi_axes", [0.2, 1e-4, 1e-4])), "body.semi_axes"),
    ("mass-underflows-1e-308", edits(("body.mass", 1e-308)), "body.mass"),
    ("mass-nan", edits(("body.mass", math.nan)), "body.mass"),
    ("mass-negative", edits(("body.mass", -1.0)), "body.mass"),
    ("mass-inf", edits(("body.mass", math.inf)), "body.mass"),
    ("mass-int-overflows-float", edits(("body.mass", 10**400)), "body.mass"),
    ("mass-missing", edits(("body.mass", DELETE)), "body.mass"),
    ("mass-and-density", edits(("body.density", 1000.0)), "body.mass"),
    ("density-1e-308", edits(("body.mass", DELETE), ("body.density", 1e-308)), "body.density"),
    ("orientation-1e10-rad", edits(("body.orientation", [0.0, 1e10, 0.0])), "body.orientation[1]"),
    ("state-missing", edits(("state", DELETE)), "state"),
    ("velocity-missing", edits(("state.velocity", DELETE)), "state.velocity"),
    ("velocity-two-numbers", edits(("state.velocity", [0.3, 0.1])), "state.velocity"),
    ("velocity-1e308", edits(("state.velocity", [1e308, 0.1, -0.5])), "state.velocity[0]"),
    ("velocity-nan", edits(("state.velocity", [0.3, 0.1, math.nan])), "state.velocity[2]"),
    ("contact-point-separating", edits(("state.velocity", [0.3, 0.1, 0.5])), "state.velocity"),
    ("contact-point-at-rest", edits(("state.velocity", [0.0, 0.0, 0.0]), ("state.angular_velocity", [0.0] * 3)),
     "state.velocity"),
    ("spin-1e7-rad-s", edits(("state.angular_velocity", [0.0, 0.0, 1e7])), "state.angular_velocity[2]"),
    ("spin-not-a-list", edits(("state.angular_velocity", "spin")), "state.angular_velocity"),
    ("restitution-above-one", edits(("impact.e", 1.5)), "impact.e"),
    ("restitution-negative", edits(("impact.e", -0.1)), "impact.e"),
    ("restitution-text", edits(("impact.e", "half")), "impact.e"),
    ("lambda-missing", edits(("impact.lambda", DELETE)), "impact.lambda"),
    ("lambda-typo", edits(("impact.lamda", 0.2)), "impact.lamda"),
    ("solver-unknown", edits(("solver.name", "newton")), "solver.name"),
    ("solver-tol-zero", edits(("solver.tol", 0.0)), "solver.tol"),
    ("descent-steps-zero", edits(("solver.max_steps", 0)), "solver.max_steps"),
    ("descent-steps-1e9", edits(("solver.max_steps", 10**9)), "solver.max_steps"),
    ("line-iterations-fraction", edits(("solver.line_iterations", 1.5)), "solver.line_iterations"),
    ("step-max-negative", edits(("solver.step_max", -1.0)), "solver.step_max"),
    ("precision-field-unknown", edits(("precision.repeats", 3)), "precision.repeats"),
]


@pytest.mark.parametrize("data, field", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_bad_impact_scene_is_refused_naming_the_field(data, field):
    assert_rejected(data, field)


def test_corpus_is_large_and_named_uniquely():
    assert len(CASES) >= 30 and len({c[0] for c in CASES}) == len(CASES)


def test_separating_contact_point_names_its_normal_velocity():
    err = assert_rejected(edits(("state.velocity", [0.3, 0.1, 0.5]), ("state.angular_velocity", [0.0] * 3)),
                          "state.velocity")
    assert "not approaching the plane: u_Kz(0) = 0.5 m/s must be < 0" in str(err)


@pytest.mark.parametrize("old, new, words", [
    ("mass = 1.0e-5", "mass = 1e-308", "'body.mass': 1e-308 kg is outside [1e-12, 1000] kg"),
    ("e = 0.5", "e = nan", "'impact.e': nan is not finite"),
    ("[0.3, 0.1, -0.5]", "[0.3, 0.1, 0.5]", "'state.velocity': the contact point is not approaching"),
])
def test_cli_refuses_in_one_line(tmp_path, old, new, words):
    cli_rejects(tmp_path, BASE_TEXT.replace(old, new), words)


def test_long_descent_is_refused_by_its_estimate_before_it_starts():
    scene = pipeline.load(edits(("solver.name", "paper-corrected"), ("solver.max_steps", 1_000_000)))
    ctx = Context(quiet=True, max_time=10.0)
    with pytest.raises(SymmechError, match=r"estimated run time 3\.\d+e\+03 s \(up to 1000000 descent steps"):
        scene.run(ctx)
    assert ctx.elapsed() < 1.0


def test_docs_hold_the_current_field_table():
    assert markdown(impact_scene.SCHEMA) in (ROOT / "docs" / "scenes-impact.md").read_text()
