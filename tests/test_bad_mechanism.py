"""Bad mechanism scenes: each is refused before any work with a one-line error naming the field.

Every case mutates a bundled scene at one dotted path; ``assert_rejected`` loads it through
the same path as `symmech run` and checks the SceneError's field. The issue-11 defects (duplicate
names, non-unit gravity, negative inertia and viscosity, a torsion spring on one body, a
coordinate repeated in a chain, a NaN mass, parameters named like internal symbols, unknown
fields found only after a minute of work) were all accepted or misreported before.
"""
import math

import pytest

from badinput import DELETE, assert_rejected, bundled, changed, cli_rejects
from test_smm_cli import BASE
from symmech.core import pipeline
from symmech.core.context import Context
from symmech.core.schema import markdown
from symmech.smm.schema import SCHEMA

DP, RB, SB, CH = "smm_double_pendulum", "smm_rotor_boom", "smm_spatial_boom", "mechanism_chain_large"
NAN, INF = float("nan"), float("inf")

CASES = [
    # unknown fields anywhere, with their dotted path
    ("unknown_top_field", DP, "gravty", {"g": 9.81}, "gravty"),
    ("unknown_field_in_precision", CH, "precision.mode", 3, "precision.mode"),
    ("unknown_field_in_body", DP, "bodies[0].mas", 1.0, "bodies[0].mas"),
    ("unknown_field_in_point", DP, "points[1].turn", ["phi1"], "points[1].turn"),
    ("unknown_kind", DP, "kind", "mechansim", "kind"),
    # types
    ("name_not_a_string", DP, "name", 3, "name"),
    ("coordinate_type_typo", DP, "coordinates[0].type", "angel", "coordinates[0].type"),
    ("coordinates_not_a_list", DP, "coordinates", {"name": "x"}, "coordinates"),
    ("mass_is_a_bool", DP, "bodies[0].mass", True, "bodies[0].mass"),
    ("effects_not_bool", DP, "effects", {"gravity": "yes"}, "effects.gravity"),
    # non-finite, overflowing, underflowing numbers
    ("mass_nan", DP, "bodies[0].mass", NAN, "bodies[0].mass"),
    ("mass_inf", DP, "bodies[0].mass", INF, "bodies[0].mass"),
    ("mass_overflowing_integer", DP, "bodies[0].mass", 10**400, "bodies[0].mass"),
    ("mass_underflowing", DP, "bodies[0].mass", 1e-308, "bodies[0].mass"),
    ("mass_negative", DP, "bodies[0].mass", -1.0, "bodies[0].mass"),
    ("parameter_value_nan", DP, "parameters.m1", {"value": NAN}, "parameters.m1.value"),
    ("parameter_underflowing_mass", DP, "parameters.m1", {"value": 1e-300, "unit": "kg"}, "bodies[0].mass"),
    # parameter names clashing with internal symbols
    ("parameter_named_x0", DP, "parameters.x0", 1.0, "parameters.x0"),
    ("parameter_named_numpy", DP, "parameters.numpy", 1.0, "parameters.numpy"),
    ("parameter_named_dunder_import", DP, "parameters.__import__", 1.0, "parameters.__import__"),
    ("parameter_named_sin", DP, "parameters.sin", 1.0, "parameters.sin"),
    # expressions
    ("expression_division_by_zero", DP, "bodies[0].mass", "1/0", "bodies[0].mass"),
    ("expression_log_zero", DP, "bodies[0].mass", "log(0)*m1", "bodies[0].mass"),
    ("expression_complex", DP, "bodies[0].mass", "(-1)**0.5", "bodies[0].mass"),
    ("expression_wrong_arity", DP, "bodies[0].mass", "sin(1,2)", "bodies[0].mass"),
    ("expression_tower_of_powers", DP, "bodies[0].mass", "9**9**9", "bodies[0].mass"),
    ("expression_import", DP, "bodies[0].mass", "__import__('os')", "bodies[0].mass"),
    ("expression_attribute", DP, "bodies[0].mass", "m1.real", "bodies[0].mass"),
    ("expression_lambda", DP, "points[1].vector", [0, "(lambda: 1)()"], "points[1].vector[1]"),
    ("expression_unknown_parameter", DP, "points[1].vector", [0, "-l3"], "points[1].vector[1]"),
    ("expression_syntax", DP, "bodies[0].mass", "m1 +", "bodies[0].mass"),
    ("expression_too_long", DP, "bodies[0].mass", "m1+" * 400 + "m1", "bodies[0].mass"),
    ("expression_overflow", DP, "points[1].vector", [0, "exp(1000)"], "points[1].vector[1]"),
    # duplicate names and dangling references
    ("duplicate_point", DP, "points[2].name", "A", "points[2].name"),
    ("duplicate_body", DP, "bodies[1].name", "bob1", "bodies[1].name"),
    ("duplicate_coordinate", DP, "coordinates[1].name", "phi1", "coordinates[1].name"),
    ("damper_named_like_a_spring", RB, "dampers[0].name", "rope", "dampers[0].name"),
    ("body_named_ground", DP, "bodies[0].name", "ground", "bodies[0].name"),
    ("body_com_undefined", DP, "bodies[0].com", "Z", "bodies[0].com"),
    ("body_com_misspelt", DP, "bodies[0].com", "AB", "bodies[0].com"),
    ("point_parent_undefined", DP, "points[1].from", "Q", "points[1].from"),
    ("point_loop", DP, "points[1].from", "B", "points[1].from"),
    ("point_root_and_chain", DP, "points[1].at", [0, 1], "points[1].at"),
    ("turns_unknown_coordinate", DP, "points[1].turns", ["phi9"], "points[1].turns"),
    ("spring_end_undefined", RB, "springs[0].ends", ["A", "Z"], "springs[0].ends"),
    ("spring_three_ends", RB, "springs[0].ends", ["A", "M", "B"], "springs[0].ends"),
    # self-connections and repeated coordinates
    ("spring_from_point_to_itself", RB, "springs[0].ends", ["A", "A"], "springs[0].ends"),
    ("torsion_spring_body_to_itself", SB, "torsion_springs[0].bodies", ["boom", "boom"], "torsion_springs[0].bodies"),
    ("torsion_spring_unknown_body", SB, "torsion_springs[0].bodies", ["ground", "bom"], "torsion_springs[0].bodies"),
    ("coordinate_repeated_in_point_chain", DP, "points[2].turns", ["phi1", "phi1"], "points[2].turns"),
    ("coordinate_repeated_after_the_first", DP, "points[2].turns", ["phi1", "phi2", "phi2"], "points[2].turns"),
    ("coordinate_repeated_in_body", DP, "bodies[1].turns", ["phi1", "phi2", "phi2"], "bodies[1].turns"),
    # directions
    ("gravity_direction_not_unit", DP, "gravity.direction", [0, -2], "gravity.direction"),
    ("gravity_direction_zero", DP, "gravity.direction", [0, 0], "gravity.direction"),
    ("gravity_negative", DP, "gravity.g", -9.81, "gravity.g"),
    ("coordinate_axis_not_unit", SB, "coordinates[0].axis", [1, 1, 0], "coordinates[0].axis"),
    ("torsion_axis_not_unit", SB, "torsion_springs[0].axis", [0, 0, 2], "torsion_springs[0].axis"),
    ("principal_axes_not_orthonormal", SB, "bodies[0].principal_axes", [[1, 0, 0], [1, 0, 0], [0, 0, 1]],
     "bodies[0].principal_axes"),
    # physical admissibility
    ("inertia_negative", SB, "bodies[0].inertia", ["-Jx", "Jy", "Jz"], "bodies[0].inertia[0]"),
    ("inertia_triangle_inequality", SB, "bodies[0].inertia", [1e6, 1.0, 1.0], "bodies[0].inertia[0]"),
    ("viscosity_negative", RB, "dampers[0].viscosity", -1.0, "dampers[0].viscosity"),
    ("stiffness_negative", RB, "springs[0].stiffness", -5.0, "springs[0].stiffness"),
    ("torsion_stiffness_negative", SB, "torsion_springs[0].stiffness", -1.0, "torsion_springs[0].stiffness"),
    ("equilibrium_preload_with_search", SB, "equilibrium", {"solve": True}, "springs[0].preload"),
    # responses
    ("duration_huge", RB, "initial.duration", 1e308, "initial.duration"),
    ("initial_rate_huge", RB, "initial.qdot", [1e300, 0.0], "initial.qdot[0]"),
    ("initial_q_wrong_length", RB, "initial.q", [0.1], "initial.q"),
    ("initial_steps_zero", RB, "initial.steps", 0, "initial.steps"),
    ("forcing_omega_reversed", RB, "forcing.omega", [40.0, 0.5], "forcing.omega"),
    ("forcing_point_undefined", RB, "forcing.point", "Z", "forcing.point"),
    ("forcing_force_nan", RB, "forcing.force", [NAN, 0.0], "forcing.force[0]"),
    ("forcing_without_force", RB, "forcing.force", DELETE, "forcing.force"),
    # chains
    ("chain_without_masses", CH, "chain.n", 0, "chain.n"),
    ("chain_too_long", CH, "chain.n", 10**7, "chain.n"),
    ("chain_massless", CH, "chain.mass", 0.0, "chain.mass"),
    ("chain_with_points", CH, "points", [{"name": "O", "at": [0, 0]}], "points"),
    ("precision_modes_beyond_range", CH, "precision.modes", 500, "precision.modes"),
]


# the words a user reads, for the cases that name a coordinate, offer a name or give a unit
WORDS = {"coordinate_repeated_after_the_first": "coordinate 'phi2' is listed twice",
         "body_com_misspelt": "point 'AB' is not defined (did you mean 'B'?)",
         "torsion_stiffness_negative": "-1 = -1 N m/rad is outside [0, 1e+30] N m/rad"}


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_bad_mechanism_refused(case):
    name, base, path, value, field = case
    err = assert_rejected(changed(bundled(base), path, value), field)
    if name in WORDS:
        assert str(err) == f"scene field '{field}': {WORDS[name]}"


def test_corpus_size():
    assert len({c[0] for c in CASES}) == len(CASES) >= 45


def test_nan_mass_is_named_as_such():
    """Before: "unknown parameter 'nan'"."""
    err = assert_rejected(changed(bundled(DP), "bodies[0].mass", NAN), "bodies[0].mass")
    assert "not finite" in str(err) and "unknown parameter" not in str(err)


def test_principal_axes_off_by_exactly_the_tolerance_are_admitted():
    """axis 1 . axis 2 = 1e-9 exactly in binary (axis 2 = (1e-9, 1, 0) has the norm 1.0 in double): the
    orthonormality tolerance, 1e-9, is met, not exceeded."""
    pipeline.load(changed(bundled(SB), "bodies[0].principal_axes", [[1, 0, 0], [1e-9, 1, 0], [0, 0, 1]]))


def test_free_free_chain_of_one_mass():
    data = changed(changed(bundled(CH), "chain.ends", "free-free"), "chain.n", 1)
    assert_rejected(data, "chain.n")


def test_precision_modes_beyond_the_coordinates():
    scene = pipeline.load(changed(bundled(DP), "precision", {"modes": 5}))
    with pytest.raises(Exception) as info:
        scene.kind.precision(scene.setup, Context(quiet=True))
    assert getattr(info.value, "field", None) == "precision.modes"


def test_unknown_field_refused_before_any_work():
    """The 3000-mass scene with a typo in [precision] fails in validation (milliseconds), not after
    the dense eigenproblem."""
    import time

    start = time.process_time()  # CPU: the machine's load does not stretch it
    assert_rejected(changed(bundled(CH), "precision.dense_limt", 10), "precision.dense_limt")
    assert time.process_time() - start < 1.0


@pytest.mark.parametrize("mass, words", [
    ("nan", "bodies[0].mass': nan is not finite"),
    ('"9**9**9"', "bodies[0].mass': exponent 3.8742e+08 exceeds 100"),
    ('"1/0"', "bodies[0].mass': division by zero in '1/0'"),
], ids=["nan_mass", "tower_of_powers", "division_by_zero"])
def test_cli_one_line(tmp_path, mass, words):
    cli_rejects(tmp_path, BASE.replace('mass = "m"', f"mass = {mass}"), words)


def test_cli_gravity_without_direction(tmp_path):
    cli_rejects(tmp_path, BASE + "[gravity]\ng = 9.81\ndirection = [0, 0]\n",
                "gravity.direction': [0.0, 0.0, 0.0] must be a unit vector")


def test_cli_duplicate_points(tmp_path):
    text = BASE + '[[points]]\nname = "P"\nat = [2, 0]\n'
    cli_rejects(tmp_path, text, "points[2].name': 'P' is defined twice")


def test_docs_show_the_schema():
    """docs/scenes-mechanism.md holds the field tables generated from the schema (no drift)."""
    from pathlib import Path

    docs = (Path(__file__).resolve().parents[1] / "docs" / "scenes-mechanism.md").read_text()
    assert markdown(SCHEMA) in docs


def test_gravity_magnitude_unchanged_by_direction():
    """A unit direction other than -y gives the same pendulum frequency g/l (before, a non-unit
    direction scaled g silently; now only unit directions pass)."""
    data = bundled(DP)
    data["bodies"] = data["bodies"][:1]
    data["points"] = data["points"][:2]
    data["coordinates"] = data["coordinates"][:1]
    for direction, vector in (([0, -1], [0, "-l1"]), ([1, 0], ["l1", 0])):
        d = changed(changed(data, "gravity.direction", direction), "points[1].vector", vector)
        s = pipeline.load(changed(d, "output", {"plots": []})).run(Context(quiet=True)).summary
        assert math.isclose(s["omega2_1_per_s2"][0], 9.81, rel_tol=1e-12)
