"""Mutation testing by shard: one physics or contract module against the test files that cover it.

    python tools/mutate.py                 every shard in SHARDS through mutmut, one after the other
    python tools/mutate.py membrane ...    the named shards (or module paths) through mutmut
    python tools/mutate.py --list          the shards
    python tools/mutate.py --screen SHARD [--fresh] [--rest]
                                           screen the shard's mutants (tools/mutation_screen.py) and write
                                           their outcomes into mutation/results/<module>.tsv; --fresh makes
                                           the mutants again from the current tree, --rest screens only
                                           those recorded without a kill (after a new test)
    python tools/mutate.py --screen SHARD ... --survived
                                           as --rest, only the survivors (a new test written against them)
    python tools/mutate.py --screen SHARD --sample N [--seed S] [--unrecorded]
                                           screen a seeded random sample of N of the shard's mutants (a record
                                           of its own module: the table gives its rate a binomial interval);
                                           --unrecorded: only those drawn that the record does not hold yet (a
                                           sample stopped early, finished); without --sample, every mutant the
                                           record does not hold, and its lines whose change is no longer made
                                           (the module was edited) are dropped
    python tools/mutate.py --rename OLD NEW
                                           a module moved (paths such as symmech/core/ode.py): its record,
                                           mutant names and proofs follow it
    python tools/mutate.py --table         docs/mutation.md's per-module table from mutation/results/
    python tools/mutate.py --check [--killed N] [--seed S] [MODULE ...]
                                           rerun N killed mutants per record at random (default 30) and every
                                           proven-equivalent one against the current tree (the records of the
                                           dotted MODULEs only, if named); exit 1 when a recorded outcome no
                                           longer holds (`make mutate-check`)

mutmut reads its settings from ./pyproject.toml and keeps its cache in ./mutants, so each shard
runs in its own folder mutants/<shard>/: links to tests/ and to what [tool.mutmut] copies, and a
pyproject.toml made of the repository's [tool.mutmut] and [tool.pytest.ini_options] with the shard's
module and test files. One worker: the machine is shared. The method: docs/mutation.md; the outcomes:
mutation/results/.
"""
from __future__ import annotations

import fnmatch
import json
import random
import subprocess
import sys
import time
from collections import Counter
from pathlib import Path

import mutation_record as rec
import mutation_screen

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]

IMPACT_TESTS = ["tests/test_grain_impact_solver.py", "tests/test_grain_impact_solver_details.py",
                "tests/test_grain_impact_derivation.py", "tests/test_bad_impact.py"]

TROLLEY_TESTS = ["tests/test_trolley_physics.py", "tests/test_trolley_paper.py", "tests/test_trolley_continuity.py",
                 "tests/test_trolley_table_ends.py"]
# the reactions' shards, from now on with the tests written against their survivors
REACTION_TESTS = TROLLEY_TESTS + ["tests/test_trolley_reactions_closed_form.py", "tests/test_trolley_chord_frame.py",
                                   "tests/test_trolley_paper_conventions.py"]

SMM_FORMS_TESTS = ["tests/test_smm_forms.py", "tests/test_smm_closed_form.py", "tests/test_smm_spatial_eq.py",
                   "tests/test_smm_structural.py", "tests/test_smm_torsion_twist.py",
                   "tests/test_smm_torsion_preload_terms.py", "tests/test_smm_turn_order_hessian.py",
                   "tests/test_smm_factor_columns.py", "tests/test_smm_ends_meet_in_equilibrium.py"]

SMM_NUMERIC_TESTS = ["tests/test_smm_structural.py", "tests/test_smm_closed_form.py", "tests/test_smm_hard.py",
                     "tests/test_smm_response.py", "tests/test_smm_spatial_eq.py", "tests/test_smm_pivot.py",
                     "tests/test_smm_equilibrium_search.py", "tests/test_smm_redraw.py",
                     "tests/test_smm_mode_kinds.py", "tests/test_smm_response_grids.py",
                     "tests/test_smm_torsion_twist.py", "tests/test_smm_equilibrium_tensions.py"]

# the elastic trolley's fast covering tests (the Python reference engine: none is marked compiled_elastic), without
# the five that integrate (10 of the 14 s a survivor costs)
ELASTIC_TESTS = ["tests/test_trolley_elastic.py", "tests/test_elastic_damping.py", "-k",
                 "not rigid_limit and not jacobi_energy and not reactions_equal and not stiff_rollers "
                 "and not free_decay"]

# the elastic trolley's outputs and timeline: the cheapest tests that integrate (5 s, 4 s and 5 s at load 5)
DAMPING_TESTS = ["tests/test_trolley_elastic.py", "tests/test_elastic_damping.py", "tests/test_roller_clamped_pair.py"]
ELASTIC_OUTPUT_TESTS = ["tests/test_trolley_elastic.py::test_reactions_equal_the_resultants_at_every_step",
                        "tests/test_trolley_elastic_kind.py::test_energy_changes_by_the_work_of_the_track_forces[True]"]
ELASTIC_TIMELINE_TESTS = ["tests/test_trolley_elastic.py::test_reactions_equal_the_resultants_at_every_step",
                          "tests/test_trolley_elastic_kind.py::test_traction_on_a_straight_level_track_follows_newton"]

GRAIN_MOTION_TESTS = ["tests/test_grain_motion_parts.py", "tests/test_grain_motion_physics.py",
                      "tests/test_grain_regimes.py", "tests/test_grain_hard_cases.py",
                      "tests/test_grain_motion_closed_forms.py", "tests/test_grain_motion_release.py",
                      "tests/test_grain_compiled_python_side.py", "tests/test_grain_motion_start_state.py",
                      "tests/test_grain_motion_stall.py", "tests/test_grain_motion_hops.py",
                      "tests/test_grain_motion_resting.py", "tests/test_grain_motion_idle_reset.py",
                      "tests/test_grain_motion_final_progress.py", "tests/test_grain_motion_rocking_count.py",
                      "-m", "not slow"]
# the motion loop's sample and the outcome's: GRAIN_MOTION_TESTS without the nine that take 4-22 s each (their 150 s
# would be every survivor's cost) and with the texts' and rows' tests
MOTION_SAMPLE_TESTS = ["tests/test_texts_warnings_and_sparse_rows.py", *GRAIN_MOTION_TESTS[:-2], "-m", "not slow", "-k",
                       "not moreau_reference and not default_scene_impacts and not sideways_sliding_population "
                       "and not effects_off and not period_doubling and not no_period1 and not chattering_ends "
                       "and not flat_and_long and not steep_downhill"]

# the grain's parts (geometry, contact, flight, sliding, paper mode): the fast files first, then the parts tests
# without the four that take seconds each (the screen stops at the first failure)
GRAIN_PARTS_TESTS = ["tests/test_sliding_step_and_surface_work.py", "tests/test_paper_mode_slides.py",
                     "tests/test_grain_impact_solver_details.py",
                     "tests/test_grain_motion_closed_forms.py", "tests/test_grain_motion_parts.py", "-k",
                     "not effects_off and not chattering_ends and not flat_and_long and not high_frequency"]

# the compiled engine's tests are in the slow tier (its build), which the default `-m` leaves out
ENGINE_PY_TESTS = ["tests/test_grain_compiled.py", "tests/test_grain_compiled_python_side.py",
                   "tests/test_grain_compiled_start.py", "tests/test_grain_compiled_summary.py",
                   "tests/test_grain_compiled_printed_energy.py", "tests/test_grain_compiled_batches.py", "-m",
                   "compiled_engine or not slow"]

# the tests that hold --out from a child process (tests/probe_kind.py) time out in the mutated copy,
# and a child imports the unmutated package anyway
PIPELINE_TESTS = ["tests/test_outputs.py", "tests/test_api.py", "tests/test_pipeline_output.py", "-k",
                         "not interrupted_run and not racing_runs and not second_run_into_the_same"]

# shard name -> (module to mutate, test files that cover it, the mutants it runs: glob patterns over
# mutmut's names, "<module>.x_<function>__mutmut_<n>" and "<module>.xǁ<Class>ǁ<method>__mutmut_<n>")
SHARDS = {
    "membrane": ("symmech/trolley/elastic/membrane.py",
                 ["tests/test_trolley_membrane.py", "tests/test_membrane_two_beams.py",
                  "tests/test_membrane_shared_coordinates.py"], ["*"]),
    # the elastic model is split by function: its tests take 45 s, a whole-module shard would take hours
    "elastic_damping": ("symmech/trolley/elastic/body.py", DAMPING_TESTS,
                        ["*.x__beam_damping__*", "*.x_roller_forces__*"]),
    "elastic_damping_modes": ("symmech/trolley/elastic/system.py", DAMPING_TESTS, ["*ǁSystemǁlinear_modes__*"]),
    "elastic_dissipation": ("symmech/trolley/elastic/simulate.py", DAMPING_TESTS, ["*.x__dissipation__*"]),
    # the rest of elastic.py by function, physics first; the fast elastic tests (test_trolley_elastic.py ~11 s)
    "elastic_invariants": ("symmech/trolley/elastic/body.py", ELASTIC_TESTS,
                           ["*.x_invariants__*", "*.x__beam_samples__*", "*.x__beam_stiffness__*",
                            "*.x_beam_basis__*", "*.x_rigid_cloud__*", "*.x__frame_of__*"]),
    "elastic_system": ("symmech/trolley/elastic/system.py", ELASTIC_TESTS,
                       ["*ǁSystemǁ__init__*", "*ǁSystemǁevaluate__*", "*ǁSystemǁcoefficients__*", "*ǁSystemǁ_dv__*",
                        "*ǁSystemǁquadratic_rates__*", "*ǁSystemǁmass__*", "*ǁSystemǁaccelerations__*",
                        "*ǁSystemǁroller_state__*", "*ǁSystemǁ_frame_mats__*"]),
    "elastic_balances": ("symmech/trolley/elastic/system.py", ELASTIC_TESTS,
                         ["*ǁSystemǁresultants__*", "*ǁSystemǁreactions__*", "*ǁSystemǁcontact_moment__*",
                          "*ǁSystemǁpotential__*", "*ǁSystemǁjacobi_energy__*",
                          "*ǁSystemǁtotal_energy__*", "*ǁSystemǁtrack_power__*"]),
    "elastic_roller_energy": ("symmech/trolley/elastic/body.py", ELASTIC_TESTS, ["*.x_roller_energy__*"]),
    # the quasi-static tests first (ELASTIC_TESTS' -k, global, leaves them in)
    "elastic_quasi_static": ("symmech/trolley/elastic/system.py",
                             ["tests/test_elastic_quasi_static.py", "tests/test_texts_warnings_and_sparse_rows.py",
                              *ELASTIC_TESTS], ["*ǁSystemǁquasi_static__*"]),
    "elastic_frame": ("symmech/trolley/elastic/frame.py", ELASTIC_TESTS,
                      ["*.x_frame_state__*", "*.x_frame_motion__*", "*.x_frames__*"]),
    "elastic_state_at": ("symmech/trolley/elastic/simulate.py", ELASTIC_TESTS, ["*.x__state_at__*"]),
    # reached only through simulate (ELASTIC_TESTS leave out every test that integrates): the cheapest
    # integrating tests, a short run on the helix (prescribed speed) and, for the timeline, one with traction
    "elastic_timeline": ("symmech/trolley/elastic/simulate.py", ELASTIC_TIMELINE_TESTS,
                         ["*ǁTimelineǁ*", "*.x_traction_start__*"]),
    "elastic_arc_length": ("symmech/trolley/elastic/frame.py", ELASTIC_TIMELINE_TESTS, ["*.x_arc_length__*"]),
    # reached only through simulate (rigid_body by outputs, beam_mode by a scene's initial mode): the cheapest
    # integrating test that reaches each (the "before" selection, mutation/history.md) and the closed-form tests
    # written against their survivors; one shard each (a survivor runs every selected test that covers it)
    "elastic_rigid_body": ("symmech/trolley/elastic/body.py",
                           ["tests/test_trolley_elastic.py", "tests/test_elastic_bodies.py", "-k",
                            "reactions_equal or rigid_body"], ["*.x_rigid_body__*"]),
    "elastic_beam_mode": ("symmech/trolley/elastic/system.py",
                          ["tests/test_trolley_elastic_initial.py", "tests/test_elastic_bodies.py", "-k",
                           "vibrates_at or beam_mode"], ["*.x_beam_mode__*"]),
    "elastic_simulate": ("symmech/trolley/elastic/simulate.py",
                         ["tests/test_trolley_elastic.py", "tests/test_trolley_elastic_kind.py",
                          "tests/test_elastic_simulate.py", "-k",
                          "reactions_equal or energy_changes and True or traction_on or test_elastic_simulate"],
                         ["*.x_simulate__*"]),
    "elastic_outputs": ("symmech/trolley/elastic/simulate.py", ELASTIC_OUTPUT_TESTS, ["*.x_row_terms__*", "*.x_outputs__*"]),
    # what the two shards above left without a result (mutation/history.md), for a screen with their new test files
    "elastic_outputs_rest": ("symmech/trolley/elastic/simulate.py",
                             ["tests/test_elastic_outputs.py", "tests/test_elastic_timeline.py",
                              *ELASTIC_OUTPUT_TESTS, ELASTIC_TIMELINE_TESTS[1]],
                             ["*.x_outputs__mutmut_119", "*.x_outputs__mutmut_1[2-3][0-9]", "*.x_outputs__mutmut_14[0-4]",
                              "*ǁTimelineǁs__*", "*ǁTimelineǁstate__*", "*ǁTimelineǁ_integral__*"]),
    # impact.py (1482 mutants) is split: its tests take 6 s, most mutants run all of them
    "impact": ("symmech/grain/impact.py", IMPACT_TESTS,
               ["*ǁDescentOptionsǁ*", "*.x__golden_section__*", "*.x_solve_descent_batch__*", "*.x_solve_scipy__*",
                "*.x_kinetic_energy__*", "*.x_euler_rates__*", "*.x_reduction_tensor__*"]),
    "impact_one": ("symmech/grain/impact.py", IMPACT_TESTS, ["*.x_solve_impact__*"]),
    "impact_robust": ("symmech/grain/impact.py", IMPACT_TESTS,
                      ["*.x__h_args__*", "*.x_impact_geometry__*", "*.x__prescribed_uK__*", "*.x_residual_19__*",
                       "*.x__trig_roots__*", "*.x_solve_robust_batch__*"]),
    "coulomb": ("symmech/grain/coulomb_law.py",
                ["tests/test_grain_motion_parts.py", "tests/test_grain_motion_physics.py",
                 "tests/test_coulomb_impact_law.py"],
                ["*.x_inverse_effective_mass__*", "*.x_coulomb_impulse__*", "*.x_kinetic_energy__*",
                 "*.x_principal_inertia__*"]),
    # the whole module in one record: the fast tests of the law, its printed check and the motion parts that call it
    "coulomb_law": ("symmech/grain/coulomb_law.py",
                    ["tests/test_coulomb_impact_law.py", "tests/test_impact_law_apply.py",
                     "tests/test_printed_law_reversal.py", "tests/test_texts_warnings_and_sparse_rows.py",
                     "tests/test_coulomb_law_precision.py", "tests/test_grain_motion_parts.py"], ["*"]),
    # ImpactLaw.apply: 241 mutants, many in log texts; without the grain motion physics tests (100 s a survivor),
    # which reach the law only through whole runs
    "coulomb_apply": ("symmech/grain/coulomb_law.py",
                      ["tests/test_grain_motion_parts.py", "tests/test_coulomb_impact_law.py",
                       "tests/test_impact_law_apply.py"], ["*ǁImpactLawǁapply__*"]),
    # the structural model method: forms.py (spatial term lists, principal axes and torsion springs in
    # test_smm_spatial_eq.py, the planar graph form of structural.py against the term lists), numeric.py (equilibrium, modes, responses, the pivot order of eq. (5))
    "smm_forms": ("symmech/smm/forms.py", SMM_FORMS_TESTS, ["*"]),
    # smm_forms split by function (its tests take 35 s, a surviving mutant runs all of them); _twist_hessian's
    # _1..._24 ran in the first, unsplit run (mutation/history.md)
    "smm_forms_chain": ("symmech/smm/forms.py", SMM_FORMS_TESTS,
                        ["*.x_turn__*", "*.x_cross__*", "*.x_dot__*", "*.x__vsum__*", "*.x__nonzero__*",
                         "*ǁGeometryǁ*", "*.x_chain_kinematics__*", "*.x_tension_system__*", "*.x__diff__*",
                         "*.x_torsion_column__*", "*.x_triple_product__*", "*.x__twist_hessian__mutmut_2[5-9]",
                         "*.x__twist_hessian__mutmut_[3-5][0-9]"]),
    "smm_forms_assemble": ("symmech/smm/forms.py", SMM_FORMS_TESTS,
                           ["*.x_assemble__mutmut_[1-9]", "*.x_assemble__mutmut_[1-9][0-9]",
                            "*.x_assemble__mutmut_1[0-9][0-9]"]),
    "smm_forms_assemble_b": ("symmech/smm/forms.py", SMM_FORMS_TESTS, ["*.x_assemble__mutmut_[2-9][0-9][0-9]"]),
    # what smm_forms_chain and smm_forms_assemble left without a result (mutation/history.md; mutmut runs a
    # function's mutants in order of number)
    "smm_forms_chain_rest": ("symmech/smm/forms.py", SMM_FORMS_TESTS,
                             ["*.x_chain_kinematics__mutmut_6[1-9]", "*.x_chain_kinematics__mutmut_[7-9][0-9]",
                              "*.x_chain_kinematics__mutmut_1[0-4][0-9]", "*ǁGeometryǁ__init____*"]),
    "smm_forms_assemble_rest": ("symmech/smm/forms.py", SMM_FORMS_TESTS,
                                ["*.x_assemble__mutmut_6[3-9]", "*.x_assemble__mutmut_[7-9][0-9]",
                                 "*.x_assemble__mutmut_1[0-9][0-9]"]),
    # smm_forms_chain_rest and smm_forms_assemble_rest together, for a screen (no result after two sessions)
    "smm_forms_rest": ("symmech/smm/forms.py", SMM_FORMS_TESTS,
                       ["*.x_assemble__mutmut_6[3-9]", "*.x_assemble__mutmut_[7-9][0-9]",
                        "*.x_assemble__mutmut_1[0-9][0-9]", "*.x_chain_kinematics__mutmut_6[1-9]",
                        "*.x_chain_kinematics__mutmut_[7-9][0-9]", "*.x_chain_kinematics__mutmut_1[0-4][0-9]",
                        "*ǁGeometryǁ__init____*"]),
    "smm_numeric": ("symmech/smm/numeric.py", SMM_NUMERIC_TESTS, ["*"]),
    # the 95 mutants of equilibrium_tensions smm_numeric left without a result: its _1..._16 had one
    "smm_numeric_tensions": ("symmech/smm/numeric.py", SMM_NUMERIC_TESTS,
                             ["*.x_equilibrium_tensions__mutmut_1[7-9]", "*.x_equilibrium_tensions__mutmut_[2-9][0-9]",
                              "*.x_equilibrium_tensions__mutmut_1[01][0-9]"]),
    # test_aot.py's test of verify_built_from finds generated/ beside integrity.py, which the mutated copy has not;
    # test_integrity.py runs fresh interpreters, which import the unmutated package; the codegen tests that
    # compare source keys fail on the mutated copy (its source differs) and derive every module (minutes).
    # --noconftest: tests/conftest.py's autouse fixtures import the scenes, hence generated modules through the
    # import hook under test, before each test: a mutant that breaks the hook made every test a fixture error (no
    # verdict); these tests use none of its fixtures and call the hook themselves
    "integrity": ("symmech/core/integrity.py",
                  ["tests/test_integrity_built_from.py", "tests/test_integrity_units.py", "tests/test_codegen.py",
                   "--noconftest", "-k",
                   "integrity_built_from or test_integrity_units or verify_refuses or used_modules or atomic_write"],
                  ["*"]),
    # the rigid trolley: trolley_frames run in part (mutation/history.md)
    "trolley_frames": ("symmech/trolley/model.py", TROLLEY_TESTS + ["tests/test_trolley_frames_units.py"],
                       ["*.x_moving_frame__*", "*.x__raw_frame__*", "*ǁFramePlanǁ*", "*.x_plan_frames__*",
                        "*.x__check_grid__*", "*.x__turns__*", "*.x__bisect_jump__*", "*.x__angle__*",
                        "*ǁRotationMinimisingǁ*", "*.x__reflect__*", "*.x__first_bad__*"]),
    # what trolley_frames left unrun or untriaged (mutation/history.md: all but _angle, _reflect, RotationMinimising),
    # split by function so each shard stays under 30 min, physics first
    "trolley_frames_raw": ("symmech/trolley/model.py", TROLLEY_TESTS + ["tests/test_trolley_frames_units.py"],
                           ["*.x_moving_frame__*", "*.x__raw_frame__*", "*.x__first_bad__*"]),
    "trolley_frames_plan": ("symmech/trolley/model.py", TROLLEY_TESTS + ["tests/test_trolley_frames_units.py"],
                            ["*.x_plan_frames__*", "*.x__turns__*", "*.x__bisect_jump__*"]),
    # plan_frames alone: trolley_frames_plan's unrun mutants are all in it (_bisect_jump and _turns ran in full)
    "trolley_frames_plan_rest": ("symmech/trolley/model.py", TROLLEY_TESTS + ["tests/test_trolley_frames_units.py"],
                                 ["*.x_plan_frames__*"]),
    "trolley_frames_grid": ("symmech/trolley/model.py", TROLLEY_TESTS + ["tests/test_trolley_frames_units.py"],
                            ["*ǁFramePlanǁ*", "*.x__check_grid__*"]),
    # the rigid trolley's reactions (890 mutants, 20-60 s per survivor) split in three
    "trolley_reactions": ("symmech/trolley/model.py", REACTION_TESTS,
                          ["*.x_point_coefficients__*", "*.x_body_motion__*", "*.x__dynamics__*", "*.x__cols__*",
                           "*.x__mv__*"]),
    "trolley_chord": ("symmech/trolley/model.py", REACTION_TESTS,
                      ["*.x_chord_point__*", "*.x_chord_rotation__*", "*.x_local_curvature_frame__*",
                       "*.x__stencil__*", "*.x__weights__*"]),
    "trolley_paper": ("symmech/trolley/model.py", REACTION_TESTS,
                      ["*.x_paper_case__*", "*.x_paper_lstar__*", "*.x_paper_lstar_derivative__*",
                       "*.x_small_angle_check__*"]),
    # what the first runs of trolley_chord and trolley_paper left unrun (mutation/history.md; mutmut ran each
    # function's mutants in order, so the unrun ones are the last by number)
    "trolley_chord_rest": ("symmech/trolley/model.py", REACTION_TESTS,
                           ["*.x_chord_point__mutmut_11[7-9]", "*.x__stencil__*", "*.x__weights__*"]),
    "trolley_paper_rest": ("symmech/trolley/model.py", REACTION_TESTS,
                           ["*.x_paper_case__*", "*.x_paper_lstar__*", "*.x_paper_lstar_derivative__*",
                            "*.x_small_angle_check__mutmut_4[7-9]", "*.x_small_angle_check__mutmut_[5-9][0-9]"]),
    # the grain motion loop (the Python reference engine): the tests that run motion.simulate; scenes on "auto" run
    # the Python loop there (the mutated copy's numba cache is cold)
    "motion": ("symmech/grain/motion.py", GRAIN_MOTION_TESTS, ["*"]),
    # the rocking warning's words and the trajectory's sample times, which the earlier triage called equivalent
    "motion_texts_and_rows": ("symmech/grain/motion.py",
                              ["tests/test_texts_warnings_and_sparse_rows.py",
                               "tests/test_grain_motion_rocking_count.py"],
                              ["*.x_rocking_warning__*", "*ǁ_Recorderǁtimes__*"]),
    # what the motion shard left without a result (mutation/history.md)
    "motion_rest": ("symmech/grain/motion.py", GRAIN_MOTION_TESTS,
                    ["*.x_simulate__*", "*ǁ_Budgetǁreport__*", "*.x_impact_record__*", "*ǁModelǁ__post_init____*",
                     "*.x__contact_velocity__*", "*.x__gap__*", "*.x__gap_noise__*", "*.x__velocity_noise__*",
                     "*ǁProgressǁ*", "*ǁStateǁrow__*"]),
    # what motion_rest left (mutation/history.md): simulate and impact_record unrun (it ran the cheaper helpers first);
    # its three untriaged survivors, not named, are in the helpers: motion_helpers reruns them
    "motion_simulate": ("symmech/grain/motion.py", GRAIN_MOTION_TESTS,
                        ["*.x_simulate__mutmut_[1-9]", "*.x_simulate__mutmut_[1-9][0-9]",
                         "*.x_simulate__mutmut_1[0-3][0-9]"]),
    "motion_simulate_b": ("symmech/grain/motion.py", GRAIN_MOTION_TESTS,
                          ["*.x_simulate__mutmut_1[4-9][0-9]", "*.x_simulate__mutmut_2[0-9][0-9]",
                           "*.x_impact_record__*"]),
    "motion_helpers": ("symmech/grain/motion.py", GRAIN_MOTION_TESTS,
                       ["*ǁModelǁ__post_init____*", "*.x__contact_velocity__*", "*.x__gap__*", "*.x__gap_noise__*",
                        "*ǁProgressǁ*", "*ǁStateǁrow__*"]),
    # the compiled engine's Python side (mutmut leaves decorated functions, the numba kernels, alone); its tests
    # compile the engine once per run in the mutated copy (~80 s, cached in mutants/engine_py/)
    "engine_py": ("symmech/grain/motion_engine/driver.py",
                  ["tests/test_grain_compiled.py", "tests/test_grain_compiled_python_side.py",
                   "tests/test_grain_compiled_start.py"],
                  ["*.x_pack__*", "*.x_warning_text__*", "*.x_impact_log__*", "*.x_state_view__*", "*.x_deferred_log__*",
                   "*.x_energy_budget__*", "*.x_raise_failure__*", "*.x_simulate__*", "*.x_simulate_many__*",
                   "*.x_entry_signature__*"]),
    # what engine_py left (mutation/history.md): simulate from _90, simulate_many, entry_signature; its ten
    # untriaged survivors, not named, were the last run (simulate): this shard reruns all of simulate
    "engine_py_rest": ("symmech/grain/motion_engine/driver.py", ENGINE_PY_TESTS,
                       ["*.x_simulate__*", "*.x_simulate_many__*", "*.x_entry_signature__*"]),
    "pipeline_output": ("symmech/core/pipeline.py", PIPELINE_TESTS,
                        ["*.x_check_out__*", "*.x_locked__*", "*.x__acquire__*", "*.x_write__*",
                         "*.x_write_files__*", "*.x__replace_dir__*", "*.x__remove_leftovers__*", "*.x_run_to__*"]),
    # every other module that computes physics or numerics, screened by a seeded random sample
    # (`--screen SHARD --sample N --seed S`): the fast test files that cover it
    "body": ("symmech/grain/body.py", ["tests/test_grain_body.py", *GRAIN_PARTS_TESTS], ["*"]),
    "contact": ("symmech/grain/contact.py", ["tests/test_grain_contact_parts.py", *GRAIN_PARTS_TESTS], ["*"]),
    "flight": ("symmech/grain/flight.py", ["tests/test_grain_flight_parts.py", *GRAIN_PARTS_TESTS], ["*"]),
    "sliding": ("symmech/grain/sliding.py", ["tests/test_sliding_phase_contract.py", *GRAIN_PARTS_TESTS], ["*"]),
    "paper_mode": ("symmech/grain/paper_mode.py", GRAIN_PARTS_TESTS, ["*"]),
    "grain_sweep_statistics": ("symmech/grain/sweep.py",
                               ["tests/test_grain_sweep_edges.py", "tests/test_grain_sweep.py", "-m", "not slow", "-k",
                                "sweep_edges or interval or overlap or separate or half_width or best"],
                               ["*.x__moments__*", "*.x_mean_interval__*", "*.x_std_interval__*",
                                "*.x_proportion_interval__*", "*.x_difference_interval__*", "*.x_statistics__*",
                                "*.x_overlap_normal__*", "*.x_overlap__*", "*.x_overlap_interval__*",
                                "*.x_grains_needed__*", "*.x_separation__*", "*.x_best_point__*", "*.x__spread__*"]),
    # what every sweep shares (axes, paths, cells, cost refusal, dispatch): the sweeps' validation, estimates and
    # refusals without the ones that build a plane of 40000 points, start a scheduler or run a sweep of seconds;
    # the refusal of a kind without a sweep
    "core_sweep_sample": ("symmech/core/sweep.py",
                          ["tests/test_sweep_validation.py", "tests/test_estimates.py", "tests/test_bad_sweep.py",
                           "tests/test_trolley_sweep_answer.py",
                           "tests/test_plotting.py::test_a_large_plane_writes_each_limit_once_a_small_one_in_every_cell",
                           "tests/test_trolley_sweep.py::test_command_line_refuses_a_kind_without_sweep_and_a_bad_sweep",
                           "-k", "not 200_by_200 and not alias_in_one_line and not unreachable and not lift_off and not "
                           "chain and not slowdown and not no_smaller_run and not run_estimate_holds"], ["*"]),
    # the trolley's design sweep (plan, point metrics, decision, answer): its tests without the command-line runs
    # and the lift-off sweep (5-14 s each), with the plane checks of test_sweep_validation.py
    "trolley_sweep_sample": ("symmech/trolley/sweep.py",
                             ["tests/test_trolley_sweep.py", "tests/test_trolley_sweep_answer.py",
                              "tests/test_sweep_validation.py", "-k",
                              "not lift_off and not command_line and not 200_by_200 and not unreachable"], ["*"]),
    # the scene files' expression language: its own tests without the fuzzing (10 s), and the mechanism's messages
    "expressions_sample": ("symmech/core/expressions.py",
                           ["tests/test_expressions.py", "tests/test_smm_expression_messages.py", "-k", "not fuzzed"],
                           ["*"]),
    # the grain scene kinds by a seeded sample: their refusals, runs, headlines and sweeps through the CLI and API,
    # without the report (64 s), the Dask sweep (10 s), the latex listing (69 s) and the errata (9 s); the auto
    # engine's stand-in test fails under mutmut (tests/conftest.py forces the Python loop for auto); the grain's
    # slow tier for its printed-law checks and precision study (1-2 s), not its compiled run or bundled sweeps
    "grain_scene_sample": ("symmech/grain/motion_scene.py",
                           ["tests/test_bad_grain.py", "tests/test_headline.py::test_grain_headline_from_the_tables",
                            "tests/test_headline.py::test_grain_sampled_too_coarsely_for_its_impacts_warns",
                            "tests/test_grain_motion_scene.py", "tests/test_grain_engine_through_registry.py",
                            "tests/test_grain_sweep.py", "-m", "slow or not slow", "-k",
                            "not auto_reads_the_registered and not dask_cluster and not default_scene_and_precision "
                            "and not bundled_separation_sweep and not slice_the_budget"], ["*"]),
    "impact_scene_sample": ("symmech/grain/impact_scene.py",
                            ["tests/test_cli_impact.py", "tests/test_bad_impact.py",
                             "tests/test_headline.py::test_impact_headline_from_momentum_and_the_law", "-k",
                             "not latex_list and not errata_json"], ["*"]),
    "track": ("symmech/trolley/track.py",
              ["tests/test_track_tables_and_messages.py", "tests/test_trolley_physics.py", "tests/test_trolley_frames_units.py",
               "tests/test_trolley_continuity.py"], ["*"]),
    # with the moving frame's closed forms (2 s), which hold the jump events' kinds
    "trolley_model": ("symmech/trolley/model.py",
                      ["tests/test_trolley_moving_frame_closed_forms.py", *REACTION_TESTS,
                       "tests/test_trolley_frames_units.py"], ["*"]),
    # the rigid trolley's run (its traction integration, arc length and visited span): the rigid trolley's tests and
    # its refusals, the bundled elastic scene's run (6 s) and the physics helix's precision study (slow tier, 21 s),
    # without the paper's precision study (slow tier, paper conventions only)
    "trolley_scene_sample": ("symmech/trolley/scene.py",
                             [*TROLLEY_TESTS, "tests/test_bad_trolley.py",
                              "tests/test_output_contract.py::test_run_output_contract[trolley_elastic_helix]",
                              "tests/test_output_contract.py::test_bench_precision_works_on_every_bundled_scene"
                              "[trolley_helix]", "-m", "slow or not slow", "-k", "not orders_one_two_four"], ["*"]),
    "modal": ("symmech/trolley/elastic/modal.py",
              ["tests/test_modal_groups_and_phase.py", "tests/test_trolley_elastic_modes_tracking.py",
               "tests/test_trolley_elastic_accel_shift.py"], ["*"]),
    "smm_structural": ("symmech/smm/structural.py",
                       ["tests/test_smm_structural_parts.py", "tests/test_smm_expression_messages.py",
                        "tests/test_smm_structural.py"], ["*"]),
    "smm_model": ("symmech/smm/model.py",
                  ["tests/test_smm_mechanism_lookups.py", "tests/test_smm_expression_messages.py",
                   "tests/test_smm_closed_form.py", "tests/test_smm_structural.py", "tests/test_smm_forms.py", "-k",
                   "mechanism_lookups or expression_messages or closed_form or structural or small_systems"], ["*"]),
    # the mechanism's chains and build (admissibility refusals first: they assert the field and the words), then the
    # structural and closed-form files; the CLI's refusals run a child process, which imports the unmutated package
    "smm_chain_sample": ("symmech/smm/chain.py",
                         ["tests/test_bad_mechanism.py", "tests/test_smm_structural.py", "tests/test_smm_hard.py",
                          "-k", "not cli"], ["*"]),
    "smm_build_sample": ("symmech/smm/build.py",
                         ["tests/test_bad_mechanism.py", "tests/test_smm_mechanism_lookups.py",
                          "tests/test_smm_expression_messages.py", "tests/test_smm_closed_form.py",
                          "tests/test_smm_structural.py", "-k", "not cli"], ["*"]),
    # the independent Lagrange check: the tests that compare it with the chain and graph forms (10 s), without the
    # random planar chains (6 s: derivations of their own)
    "smm_lagrange_sample": ("symmech/smm/lagrange.py",
                            ["tests/test_smm_forms.py", "tests/test_smm_spatial_eq.py", "-k",
                             "lagrange or small_systems or torsion_preload_from_equilibrium"], ["*"]),
    "impact_all": ("symmech/grain/impact.py", IMPACT_TESTS, ["*"]),
    # with the torsion tests, which cover _twist_hessian (35 s at load 9)
    "smm_forms_sample": ("symmech/smm/forms.py",
                         ["tests/test_smm_forms_geometry.py", "tests/test_smm_torsion_between_bodies.py",
                          "tests/test_smm_closed_form.py", "tests/test_smm_structural.py", "tests/test_smm_forms.py",
                          "tests/test_smm_torsion_twist.py", "-k",
                          "not random_spatial and not spatial_boom and not excavator and not many_random"],
                         ["*"]),
    # the responses', searches' and tensions' own tests first (5 s together)
    "smm_numeric_sample": ("symmech/smm/numeric.py",
                           ["tests/test_smm_response.py", "tests/test_smm_response_grids.py",
                            "tests/test_smm_equilibrium_tensions.py", "tests/test_smm_equilibrium_search.py",
                            "tests/test_smm_redraw.py", "tests/test_smm_torsion_twist.py",
                            "tests/test_smm_closed_form.py", "tests/test_smm_mode_kinds.py", "tests/test_smm_structural.py",
                            "tests/test_smm_pivot.py", "-k", "not numerically_many"], ["*"]),
    # the exact free rotation (elliptic functions) and the flight's gap bounds: its own tests, 2.5 s
    "free_flight": ("symmech/grain/free_flight.py",
                    ["tests/test_grain_free_flight_record.py", "tests/test_grain_free_flight.py"], ["*"]),
    # the elastic trolley's modules split from elastic.py, each by a seeded sample against the fast elastic tests
    # with the rigid cloud's and the frame's own tests (1 s and 2 s)
    # with the rigid body of the same mass (moved into body.py: reached before only through integrating tests)
    "elastic_body_sample": ("symmech/trolley/elastic/body.py",
                            ["tests/test_elastic_invariants.py",
                             "tests/test_elastic_bodies.py::test_rigid_body_is_the_trolley_with_its_rods_and_tip_masses",
                             "tests/test_elastic_bodies.py::test_rigid_body_of_a_bare_trolley_is_the_trolley",
                             *ELASTIC_TESTS], ["*"]),
    "elastic_frame_sample": ("symmech/trolley/elastic/frame.py", ["tests/test_elastic_frame.py", *ELASTIC_TESTS],
                             ["*"]),
    # the frame's spline table (moved in from the compiled engine): its tests are slow-tier ones that build no kernel
    "elastic_frame_table": ("symmech/trolley/elastic/frame.py",
                            ["tests/test_elastic_compiled.py", "tests/test_elastic_frame.py", "-m", "slow or not slow",
                             "-k", "frame_table or kink_is_not or not compiled"],
                            ["*frame_table*", "*_subsampled*", "*geometry_scales*", "*_scales*", "*arc_length*"]),
    # the motion loop by a seeded sample
    "motion_sample": ("symmech/grain/motion.py", MOTION_SAMPLE_TESTS, ["*"]),
    # the energy budget and the warnings' and errors' texts both accurate-mode engines report
    "grain_outcome_sample": ("symmech/grain/outcome.py", MOTION_SAMPLE_TESTS, ["*"]),
    # the chattering window's closed form and the Python loop's exact flight (slow tier, 1-8 s): the motion_sample's
    # survivors again
    "motion_chatter": ("symmech/grain/motion.py",
                       ["tests/test_grain_motion_closed_forms.py::"
                        "test_exact_flight_of_a_tumbling_needle_meets_the_plate_where_dop853_does",
                        "tests/test_grain_motion_closed_forms.py::"
                        "test_a_hundred_bounces_within_the_chattering_window_end_in_sliding", "-m", "slow"], ["*"]),
    # the elastic Python engine's run: its own files, then the fast elastic tests with the cheapest that integrate
    "elastic_simulate_sample": ("symmech/trolley/elastic/simulate.py",
                                ["tests/test_elastic_simulate.py", "tests/test_elastic_timeline.py",
                                 "tests/test_elastic_outputs.py", "tests/test_trolley_elastic.py",
                                 "tests/test_elastic_damping.py", "-m", "not slow", "-k",
                                 "not rigid_limit and not jacobi_energy and not stiff_rollers and not free_decay"],
                                ["*"]),
    # the compiled elastic engine's driver by a seeded sample: the runs against the Python engine that take seconds,
    # the fallbacks, the inputs' record and the Jacobians (the engine's cache kept warm: NUMBA_CACHE_DIR)
    "elastic_compiled_sample": ("symmech/trolley/elastic/compiled.py",
                                ["tests/test_elastic_timeline.py", "tests/test_elastic_compiled.py",
                                 "tests/test_elastic_frame.py", "-m", "slow or not slow", "-k",
                                 "short_ride or rigid_rollers or kink or estimate_of_a_built or leaves_its_table "
                                 "or compiled_run_reads or jacobian or traction_agrees or assembly_matches "
                                 "or failed_compiled_solve or turn_between or entries_typed"], ["*"]),
    # the elastic scene (setup, run, outputs): its refusals and the engine's choice first, then its runs and warnings
    # (25 s), the curvature-shift warning's (2 s) and the work-precision study's (slow tier, 15 s); the initial state's
    # 14-20 s decay studies, the other slow tests, two integrations of the Python engine's own (9 s each) and the CLI's
    # child processes (they import the unmutated package) left out
    "elastic_scene_sample": ("symmech/trolley/elastic/scene.py",
                             ["tests/test_bad_trolley.py", "tests/test_elastic_engine_choice.py",
                              "tests/test_trolley_elastic_scene.py", "tests/test_trolley_elastic_initial.py",
                              "tests/test_trolley_elastic_kind.py", "tests/test_trolley_elastic_modes_tracking.py",
                              "tests/test_trolley_elastic_accel_shift.py::"
                              "test_the_shift_beyond_the_consistent_order_is_flagged", "-m", "slow or not slow", "-k",
                              "not cli and not vibrates_at and not decays_at and not long_run and not explode "
                              "and not traction_on_a_straight and not energy_changes and not duffing_backbone "
                              "and not membrane_energy and not rigid_limit_with and not bundled_scene_runs"], ["*"]),
    # the elastic equations of motion by a seeded sample: the quasi-static and energy tests first (fast, exact), then
    # the fast elastic files and the cheapest that integrate (test_dynamics_rhs.py, 40 s of other kinds, left out)
    "elastic_system_sample": ("symmech/trolley/elastic/system.py",
                              ["tests/test_elastic_quasi_static.py", "tests/test_texts_warnings_and_sparse_rows.py",
                               "tests/test_elastic_energies.py", "tests/test_elastic_residual.py",
                               "tests/test_elastic_bodies.py", "tests/test_elastic_damping.py",
                               "tests/test_trolley_elastic.py", "tests/test_elastic_assembly.py",
                               "tests/test_elastic_simulate.py", "tests/test_elastic_timeline.py",
                               "tests/test_elastic_outputs.py", "-m", "not slow", "-k",
                               "not rigid_limit and not jacobi_energy and not stiff_rollers and not free_decay"],
                              ["*"]),
    # the compiled_engine tests build the mutated copy's engine in the first unmutated run (minutes) into numba's
    # cache, and every later fork loads it from there (15-20 s a run at load 9): run with NUMBA_CACHE_DIR set to a
    # folder that outlives the screen (the mutated copy's files keep their paths and times, so the cache stays valid)
    "engine_py_sample": ("symmech/grain/motion_engine/driver.py", ENGINE_PY_TESTS, ["*"]),
    "pipeline_sample": ("symmech/core/pipeline.py", PIPELINE_TESTS, ["*"]),
    "kinematics": ("symmech/core/kinematics.py", ["tests/test_kinematics.py", "tests/test_trolley_physics.py"], ["*"]),
    # the toolkit's Python side (mutmut leaves the numba kernels, decorated, alone) without the order studies
    "ode": ("symmech/numerics/ode.py", ["tests/test_ode_toolkit.py", "-k", "not empirical_order and not fresh_process"],
            ["*"]),
    # what mutmut mutates in the numba modules: the undecorated Python around the kernels (the closures' bodies
    # and the decorated functions are left alone)
    "brent_closures": ("symmech/numerics/brent.py",
                       ["tests/test_ode_toolkit.py", "-k",
                        "brentq_and_bounded or grain_flight_at_contact or compiled_newton"], ["*"]),
    # the safeguarded Newton root finder: plain Python, which the compiled loop compiles as it is
    "newton": ("symmech/numerics/newton.py", ["tests/test_ode_toolkit.py", "-k", "newton"], ["*"]),
    "radau_closures": ("symmech/numerics/radau.py",
                       ["tests/test_ode_toolkit.py", "-m", "slow or not slow", "-k", "radau_stiff_prothero"], ["*"]),
    "kernel_twins": ("symmech/numerics/kernels.py", ["tests/test_compiled.py"], ["*"]),
    "elastic_traction_callback": ("symmech/trolley/elastic/kernels.py",
                                  ["tests/test_elastic_compiled.py", "-m", "slow or not slow", "-k", "traction"],
                                  ["*"]),
    # integrate, _adapter, make and steppers are reached only where a test builds a generated module's solver in the
    # mutant's process (its closures are compiled anew in each process: tens of seconds a mutant)
    "ode_integrate": ("symmech/numerics/ode.py",
                      ["tests/test_ode_toolkit.py", "-m", "slow", "-k",
                       "integrate_refuses or integrate_generated_module or integrate_radau_with"], ["*"]),
}


OUTCOMES_UNKILLED = tuple(o for o in rec.OUTCOMES if o not in rec.KILLS)  # what --rest screens again

# every module that computes physics or numerics: "" when it is screened (its record), else why it is not
COVERAGE = {
    "symmech/grain/body.py": "",
    "symmech/grain/contact.py": "",
    "symmech/grain/flight.py": "",
    "symmech/grain/sliding.py": "",
    "symmech/grain/impact.py": "",
    "symmech/grain/coulomb_law.py": "",
    "symmech/grain/paper_mode.py": "",
    "symmech/grain/motion.py": "a seeded sample of 40 (shard motion_sample) beside the 16 mutants of the trajectory's "
                               "sample times screened before as a part and outside the draw (2 of them survive): "
                               "the interval treats all 56 as drawn",
    "symmech/grain/sweep.py": "the statistics only (shard grain_sweep_statistics); the rest is the plan, dispatch "
                              "and tables",
    "symmech/grain/motion_scene.py": ("a seeded sample of 30 (shard grain_scene_sample: the grain kind's refusals, "
                                      "estimates, runs, headline, sweeps, printed-law checks and precision study)"),
    "symmech/grain/impact_scene.py": ("a seeded sample of 30 (shard impact_scene_sample: the impact kind's refusals, "
                                      "runs through the CLI and API, headline and precision study)"),
    "symmech/grain/outcome.py": "",
    "symmech/grain/motion_engine/driver.py": ("drawn again (757 mutants) after the population's results were built in "
                                              "bulk (packs, start vectors, counts in one tolist); its old proof "
                                              "went with the rewritten line"),
    "symmech/grain/motion_engine/*.py (the loop)": "numba kernels (mutmut does not mutate decorated functions); "
                                                   "the engine is held to the Python reference by the "
                                                   "compiled-engine tests",
    "symmech/grain/free_flight.py": "",
    "symmech/trolley/track.py": "",
    "symmech/trolley/model.py": "",
    "symmech/trolley/scene.py": ("a seeded sample of 30 (shard trolley_scene_sample: the rigid trolley's tests, the bundled "
                                 "elastic scene's run and the physics helix's precision study)"),
    "symmech/trolley/sweep.py": ("a seeded sample of 30 (shard trolley_sweep_sample): a design sweep's point metrics "
                                 "(peaks, amplification, comfort margin, closest resonance), decision and answer"),
    "symmech/trolley/elastic/modal.py": "",
    "symmech/trolley/elastic/membrane.py": "",
    "symmech/trolley/elastic/system.py": ("a seeded sample of the whole module (shard elastic_system_sample); it "
                                          "replaced the record of quasi_static's 52 mutants (a part, not a random "
                                          "sample: 48 killed, 4 survived; in git before the sample)"),
    "symmech/trolley/elastic/body.py": "",
    "symmech/trolley/elastic/frame.py": ("drawn again after the frame along the track moved out to "
                                         "model.TrackFrames (590 mutants, from 638); its survivors screened again "
                                         "by shard elastic_frame_table, with the table's slow-tier tests that build "
                                         "no kernel"),
    "symmech/trolley/elastic/simulate.py": "",
    "symmech/trolley/elastic/scene.py": ("a seeded sample of 30 (shard elastic_scene_sample: the scene's refusals, "
                                         "runs, warnings and modes, with the work-precision study of the slow tier)"),
    "symmech/trolley/elastic/compiled.py": (
        "a seeded sample of 30 (shard elastic_compiled_sample), drawn again after the cached entries' signatures were "
        "written as numba types (369 mutants, from 405)"),
    "symmech/trolley/elastic/kernels.py": ("whole (shard elastic_traction_callback): its 27 mutants, all of the one "
                                           "undecorated function (traction_force, the traction's Python callback); "
                                           "the numba kernels (not mutated) are held to the Python engine by "
                                           "tests/test_elastic_compiled.py"),
    "symmech/smm/forms.py": "",
    "symmech/smm/numeric.py": ("sample drawn on from 30 to 40 (prefix-stable); left: lstsq without rcond=None "
                               "(numpy >= 2's default, the same call on the numpy installed; differs on numpy "
                               "1.26, which pyproject admits)"),
    "symmech/smm/structural.py": "",
    "symmech/smm/model.py": "",
    "symmech/smm/chain.py": "",
    "symmech/smm/build.py": "",
    "symmech/smm/lagrange.py": ("sample drawn on from 30 to 34 (prefix-stable) for its proof (sympy.zeros(n) is "
                                "square); left: the rates' symbols declared non-real (b holds no rate: believed "
                                "equivalent, not claimed, a second proof at 34 would exceed the 3 % cap)"),
    "symmech/core/kinematics.py": "",
    "symmech/core/sweep.py": ("a seeded sample of 30 (shard core_sweep_sample): what every sweep shares (axes, cell "
                              "edges, flat statements, the cost estimate and refusal, the dispatch)"),
    "symmech/core/expressions.py": ("a seeded sample drawn on from 30 to 67 (prefix-stable), so that its 2 proofs are "
                                    "at most 3 %; left: 3 survivors of the domain check's minimum search (`|` for `&` "
                                    "picking minima, no xatol, `<` for `<=` at the threshold)"),
    "symmech/numerics/ode.py": "",
    "symmech/numerics/brent.py": ("whole (shard brent_closures): its 8 mutants, the namespace roots returns and the "
                                  "compiled Newton; the root finder and the minimiser are numba closures, which "
                                  "mutmut does not mutate, held to scipy's brentq and bounded minimiser by "
                                  "tests/test_ode_toolkit.py, the compiled Newton to the screened newton.py"),
    "symmech/numerics/newton.py": "",
    "symmech/numerics/radau.py": ("whole (shard radau_closures): its 2 mutants, the first step's factory in "
                                  "steppers; the rest is numba kernels and closures (not mutated), held to scipy's "
                                  "Radau steps (with RADAU5's hold after a Newton failure: to that rule) and "
                                  "collocation conditions by tests/test_ode_toolkit.py"),
    "symmech/numerics/kernels.py": "",
    "symmech/numerics/dop853.py, first_step.py, linalg.py": (
        "numba kernels and closures only: mutmut makes no mutant of them; tests/test_ode_toolkit.py holds them to "
        "scipy's DOP853 steps, its select_initial_step and to LU solves bit for bit"),
    "symmech/grain/free_flight_nb.py": ("numba kernels only (no mutant made); held to the screened Python free flight "
                                        "(free_flight.py) by tests/test_grain_free_flight_nb.py"),
    "symmech/*/derive*.py (the derivations)": (
        "sympy: what they compute is generated/, and a mutant either renders a different byte, which "
        "tests/test_codegen.py::test_generated_folder_is_up_to_date (slow tier) finds against the committed "
        "modules, or renders the same modules (no output differs); the generated modules' numbers are held to "
        "closed forms and the papers by their tests"),
    "symmech/trolley/elastic/symbolic_assembly.py": (
        "sympy: the elastic equations a scene's C module prints; tests/test_elastic_assembly.py holds the generated "
        "assembly equal to the Python engine's (the screened system.py)"),
    "symmech/*/printed*.py, errata*.py": (
        "the papers' printed formulas transcribed, and their comparison with the derivations: no computation of "
        "their own; tests/test_errata_coverage.py and each paper's errata tests name every disagreement"),
    "symmech/trolley/tables.py, comfort.py": "the paper's tables and the comfort envelope transcribed: data",
    "symmech/core/layout.py, grain/vectors.py, grain/motion_engine/layouts.py, trolley/elastic/layout.py": (
        "declared layouts (offsets, pack and unpack of float64 vectors): no physics or numerics; "
        "tests/test_layouts.py holds the offsets, the pack-unpack round trip and the slots both engines were built "
        "with"),
    "symmech/core/sample.py": ("cost estimates scaled by timed samples: times, which no test can assert beyond "
                               "tests/test_estimates.py's factor-of-2 bounds"),
    "symmech/export/*.py": (
        "the C and FMU emission: the physics in an exported model is the generated C of the derivations; the "
        "exported models are held to the native runs by FMPy in tests/test_export_*.py"),
    "symmech/numerics/aot.py, artifacts.py, build.py, fastcall.py, jit.py": (
        "building, recording and loading compiled artifacts: no arithmetic on physical quantities; "
        "tests/test_artifact_*.py, test_aot.py and test_fastcall.py hold what is loaded and refused"),
    "symmech/numerics/dop853_tableau.py": "a table of constants (Hairer's tableau), no code to mutate; tests/test_ode_toolkit.py "
                              "holds it bit-equal to scipy's",
    "symmech/core/precision.py": "no physics or numerics of its own: wall-clock timing (its numbers are times, which "
                                 "no test can assert) and the study's rows laid out as a table and a plot",
}


def shard_pyproject(module: str, tests: list[str]) -> str:
    """The shard's pyproject.toml text: [tool.mutmut] narrowed to one module, pytest's settings kept."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text("utf-8"))
    # a shard's `-m` goes to every mutant's run too: mutmut passes the selection only to the clean and stats runs,
    # and the default `-m 'not slow'` would leave a slow-tier test uncollected (exit 5, "no tests")
    marks = tests[tests.index("-m"):tests.index("-m") + 2] if "-m" in tests else []
    mutmut = dict(project["tool"]["mutmut"], only_mutate=[module], pytest_add_cli_args_test_selection=tests)
    mutmut["pytest_add_cli_args"] = mutmut["pytest_add_cli_args"] + marks
    tables = {"tool.mutmut": mutmut, "tool.pytest.ini_options": project["tool"]["pytest"]["ini_options"]}
    # JSON strings, lists, numbers and booleans are valid TOML values
    return "".join(f"[{name}]\n" + "".join(f"{k} = {json.dumps(v)}\n" for k, v in table.items()) + "\n"
                   for name, table in tables.items())


def shard_folder(name: str, suffix: str = "") -> Path:
    """mutants/<name><suffix>/, set up for mutmut: links to the sources and tests, the shard's pyproject.toml."""
    module, tests, _ = SHARDS[name]
    folder = ROOT / "mutants" / (name + suffix)
    folder.mkdir(parents=True, exist_ok=True)
    settings = tomllib.loads((ROOT / "pyproject.toml").read_text("utf-8"))["tool"]["mutmut"]
    for link in ["tests", *settings["source_paths"], *settings["also_copy"]]:
        if not (folder / link).is_symlink():
            (folder / link).symlink_to(ROOT / link, target_is_directory=True)
    (folder / "pyproject.toml").write_text(shard_pyproject(module, tests), "utf-8")
    return folder


def run_shard(name: str) -> int:
    """Run one shard in mutants/<name>/; mutmut's exit status."""
    module, tests, patterns = SHARDS[name]
    folder = shard_folder(name)
    mutmut = [sys.executable, "-m", "mutmut"]  # this interpreter's mutmut (a venv may see a system-wide one)
    print(f"== shard {name}: {module} against {' '.join(tests)}", flush=True)
    status = subprocess.call(mutmut + ["run", "--max-children", "1", *patterns], cwd=folder)
    listing = subprocess.run(mutmut + ["results", "--all", "true"], cwd=folder, capture_output=True, text=True).stdout
    verdicts = dict(line.strip().rsplit(": ", 1) for line in listing.splitlines() if ": " in line)
    mine = {k: v for k, v in verdicts.items() if any(fnmatch.fnmatchcase(k, p) for p in patterns)}
    for k, v in mine.items():
        if v != "killed":
            print(f"    {k}: {v}")
    counts = Counter(mine.values())
    tally = ", ".join(f"{n} {verdict}" for verdict, n in counts.most_common())
    print(f"== shard {name}: {len(mine)} mutants, {tally}", flush=True)
    return status


def shards_named(arg: str) -> list[str]:
    """The shards an argument names: a shard, or every shard of a module path (itself when neither)."""
    if arg in SHARDS:
        return [arg]
    return [name for name, (module, *_) in SHARDS.items() if module == arg] or [arg]


def shard_mutants(name: str) -> list[str]:
    """The mutmut names of the shard's mutants (its patterns over the module's mutants)."""
    module, _, patterns = SHARDS[name]
    names = mutation_screen.mutant_names(ROOT / "mutants" / name, module)
    return [k for k in names if any(fnmatch.fnmatchcase(k, p) for p in patterns)]


def rescreen_shards(path: Path) -> set[str]:
    """The shards of a record whose every screen was of its unkilled mutants again (`--rest`, `--survived`): they
    added no mutant of their own, so their lines are mutants another shard drew."""
    screens = [n.removeprefix("shard ").split(":")[0] for n in rec.notes_of(path) if n.startswith("shard ")]
    shards = {label.split(" (")[0] for label in screens}
    again = f" ({mutation_screen.AGAIN})"
    return {s for s in shards if all(label == s + again for label in screens if label.split(" (")[0] == s)}


def screen(name: str, fresh: bool, rest: tuple = (), size: int = 0, seed: int = 0, unrecorded: bool = False) -> int:
    """Screen the mutants of one shard into its module's record: all, or a seeded random sample of `size` (when
    > 0); of those, only the ones the record holds with one of the outcomes `rest`, or (`unrecorded`) only the
    ones it does not hold. A recorded mutant is found by its function and change, not its number, which moves
    when the module is edited; every line the record keeps is written under its mutant's current name."""
    module, tests, _ = SHARDS[name]
    folder = shard_folder(name)
    mutation_screen.generate(folder, fresh)
    names = shard_mutants(name)
    drawn = ""
    if size:
        # from the sorted names (the draw depends on the seed and the set of names only), screened in the order
        # drawn: a screen stopped early leaves a smaller random sample, not the first functions
        population = len(names)
        names = random.Random(seed).sample(sorted(names), min(size, population))
        drawn = (f"seed {seed}, {len(names)} drawn of the {population} mutants of shard {name} "
                 f"(random.Random({seed}).sample of their sorted names, screened in the order drawn); this "
                 "record's lines are the mutants screened")
    found, stale = {}, []
    if rest or unrecorded:
        entries = list(rec.read(rec.record_path(module)).values())
        functions = {rec.function_of(e.mutant) for e in entries}
        candidates = [n for n in shard_mutants(name) if rec.function_of(n) in functions]
        current = {n: (rec.function_of(n), digest)
                   for n, (digest, _) in mutation_screen.changes(folder, module, candidates).items()}
        found = rec.match(entries, current)
        if rest:
            names = [found[e.mutant] for e in entries if e.mutant in found and e.outcome in rest]
        else:
            drawn_names = set(names)
            names = [n for n in names if n not in found.values()]
            # lines of the shard's mutants whose change is no longer made (the module was edited, or the function
            # moved out of it): mutate-check could not find them; their functions' current mutants are screened now
            stale = [e.mutant for e in entries
                     if e.mutant not in found and any(fnmatch.fnmatchcase(e.mutant, p) for p in SHARDS[name][2])]
            # a sample's lines are the mutants drawn: when an edit changed the population, the draw did too; so are
            # the lines of shards that only screened the record's own mutants again (another shard's --survived)
            drawers = {name} | rescreen_shards(rec.record_path(module))
            stale += [e.mutant for e in entries
                      if size and e.shard in drawers and e.mutant in found and found[e.mutant] not in drawn_names]
    which = (mutation_screen.AGAIN if rest else
             "the rest of its sample" if size else "its mutants not recorded" if unrecorded else "")
    return mutation_screen.screen(name, folder, module, tests, names, fresh=False, which=which, drawn=drawn,
                                  renames=found, stale=stale)


def check(killed: int, seed: int, only: list[str]) -> int:
    """Rerun a sample of every record (or of the records of the dotted modules `only`) against the current tree
    (`make mutate-check`), one shard at a time."""
    status, total, start = 0, 0, time.monotonic()
    for path in sorted(rec.RESULTS.glob("*.tsv")):
        if only and path.stem not in only:
            continue
        entries = rec.read(path)
        chosen = mutation_screen.sample(entries, path.stem, killed, seed)
        total += len(chosen)
        for name in sorted({e.shard for e in chosen}):
            mine = [e for e in chosen if e.shard == name]
            print(f"== check {path.name}, shard {name}: {len(mine)} recorded outcomes", flush=True)
            # each shard in a process of its own: a screen imports one mutated copy of the package
            status |= subprocess.call([sys.executable, __file__, "--recheck", name,
                                       json.dumps([e.mutant for e in mine])])
    print(f"== check: {total} recorded outcomes {'hold' if status == 0 else 'do NOT all hold'} "
          f"({time.monotonic() - start:.0f} s)")
    return status


def check_arguments(args: list[str]) -> tuple[int, int, list[str]]:
    """(killed per record, seed, dotted modules) of `--check`'s arguments `[--killed N] [--seed S] [MODULE ...]`."""
    options, only = {}, []
    words = iter(args)
    for word in words:
        if word.startswith("--"):
            options[word] = next(words, "")
        else:
            only.append(word)
    return int(options.get("--killed", 30)), int(options.get("--seed", 0)), only


def main(argv: list[str]) -> int:
    if argv[:1] in (["-h"], ["--help"]):
        print(__doc__)
        return 0
    if argv == ["--list"]:
        for name, (module, tests, patterns) in SHARDS.items():
            print(f"{name:16} {module:28} {' '.join(tests)}  [{' '.join(patterns)}]")
        return 0
    if argv == ["--table"]:
        rec.write_table(sorted({module for module, *_ in SHARDS.values()}), COVERAGE)
        return 0
    if argv[:1] == ["--check"]:
        return check(*check_arguments(argv[1:]))
    if argv[:1] == ["--recheck"] and len(argv) == 3:
        module, tests, _ = SHARDS[argv[1]]
        entries = rec.read(rec.record_path(module))
        chosen = [entries[n] for n in json.loads(argv[2])]
        # a folder of its own: the check makes the mutants afresh, beside a screen that may be running
        return mutation_screen.recheck(argv[1], shard_folder(argv[1], ".check"), module, tests, chosen)
    if argv[:1] == ["--screen"] and len(argv) > 1 and argv[1] in SHARDS:
        flags = [a for a in argv[2:] if a in ("--fresh", "--rest", "--survived", "--unrecorded")]
        options = dict(zip(*[iter(a for a in argv[2:] if a not in flags)] * 2))
        if set(options) <= {"--sample", "--seed"}:
            rest = ("survived",) if "--survived" in flags else OUTCOMES_UNKILLED if "--rest" in flags else ()
            return screen(argv[1], "--fresh" in flags, rest, int(options.get("--sample", 0)),
                          int(options.get("--seed", 0)), "--unrecorded" in flags)
    if argv[:1] == ["--rename"] and len(argv) == 3:
        rec.rename(argv[1], argv[2])
        return 0
    names = [n for a in argv for n in shards_named(a)] or list(SHARDS)
    unknown = [n for n in names if n not in SHARDS]
    if unknown:
        print(f"unknown shard {unknown[0]!r}; shards: {', '.join(SHARDS)}", file=sys.stderr)
        return 2
    return max(run_shard(n) for n in names)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
