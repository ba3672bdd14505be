"""The command line on impact scenes: results, one-line errors, latex, errata."""
import json
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

from symmech.cli import main
from symmech.core import codegen, pipeline

ROOT = Path(__file__).resolve().parents[1]
DEFAULT = (ROOT / "scenes" / "impact_default.toml").read_text()


def run_scene(tmp_path, text, capsys):
    scene = tmp_path / "scene.toml"
    scene.write_text(text)
    code = main(["run", str(scene), "--out", str(tmp_path / "out")])
    return code, capsys.readouterr()


def test_default_scene_summary(tmp_path, capsys):
    code, _ = run_scene(tmp_path, DEFAULT, capsys)
    assert code == 0
    s = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert s["solver"]["name"] == "robust" and s["solver"]["converged"]
    assert s["solver"]["residual_19"] < 1e-13
    uK0, uK1 = np.array(s["contact_velocity_before"]), np.array(s["contact_velocity_after"])
    assert uK1[2] == pytest.approx(-0.5 * uK0[2], rel=1e-12)
    assert np.hypot(*uK1[:2]) == pytest.approx(0.7 * np.hypot(*uK0[:2]), rel=1e-12)
    assert s["kinetic_energy_after"] < s["kinetic_energy_before"]
    rates = s["euler_rates_after"]
    np.testing.assert_allclose(rates["cramer_derived"], rates["from_angular_velocity"], rtol=1e-10)
    # The printed (51)/(55) change the spin rate only.
    np.testing.assert_allclose(rates["cramer_printed"][:2], rates["from_angular_velocity"][:2], rtol=1e-10)
    assert abs(rates["cramer_printed"][2] - rates["from_angular_velocity"][2]) > 1.0
    for key in ("impulse_T", "mu", "centre_velocity_after", "angular_velocity_after", "roots"):
        assert key in s
    assert s["warnings"] == []  # far from gimbal lock (theta = 0.7), an admissible root
    assert (tmp_path / "out" / "impact.png").stat().st_size > 10000


def test_a_pulling_root_fails_its_check_and_gimbal_lock_is_warned():
    """The grazing impact of tests/test_grain_impact_solver_details.py (u = (0.5, 0.2, -1e-6) m/s, no spin): its
    least-impulse root pulls the grain into the plane, and the admissibility check fails (value 0). At theta = 0
    the Euler rates are undefined: the run warns and reports no rates."""
    grazing = tomllib.loads(DEFAULT)
    grazing["state"] = {"velocity": [0.5, 0.2, -1e-6], "angular_velocity": [0.0, 0.0, 0.0]}
    check = pipeline.load(grazing).run().checks[2]
    assert (check.what, check.value, check.threshold, check.verdict) == (
        "an admissible root: no energy created, no pull into the plane", 0.0, "= 1 (admissible)", "fail")
    locked = tomllib.loads(DEFAULT)
    locked["body"]["orientation"] = [0.3, 0.0, 1.1]
    result = pipeline.load(locked).run()
    assert result.warnings == ["gimbal lock: sin(theta) = 0.00e+00; the Euler rates psi' and phi' are undefined "
                               "(only psi' + phi' is), the angular velocity is reported instead"]
    assert result.summary["euler_rates_after"] == dict.fromkeys(("from_angular_velocity", "cramer_derived",
                                                                 "cramer_printed"))


@pytest.mark.parametrize("solver", ["paper", "paper-corrected", "scipy"])
def test_every_solver_runs_from_a_scene(tmp_path, capsys, solver):
    text = DEFAULT.replace('name = "robust"', f'name = "{solver}"\nmax_steps = 20')
    code, _ = run_scene(tmp_path, text, capsys)
    assert code == 0
    s = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert s["solver"]["name"] == solver
    assert s["solver"]["converged"] == (solver == "scipy")


@pytest.mark.parametrize("edit, field", [
    (("mass = 1.0e-5", ""), "body.mass"),
    (("mass = 1.0e-5", "mass = -1.0"), "body.mass"),
    (("e = 0.5", "e = 1.5"), "impact.e"),
    (("lambda = 0.3", "lambda = -0.1"), "impact.lambda"),
    (("[2.0e-3, 1.5e-3, 1.0e-3]", "[2.0e-3, 0.0, 1.0e-3]"), "body.semi_axes[1]"),
    (('name = "robust"', 'name = "newton"'), "solver.name"),
    (("lambda = 0.3", "lambda = 0.3\nlamda = 0.2"), "impact.lamda"),
    (("velocity = [0.3, 0.1, -0.5]", "velocity = [0.3, 0.1]"), "state.velocity"),
    (('kind = "impact"', 'kind = "rocket"'), "kind"),
])
def test_bad_input_is_one_line_naming_the_field(tmp_path, capsys, edit, field):
    code, out = run_scene(tmp_path, DEFAULT.replace(*edit), capsys)
    assert code == 2
    lines = out.err.strip().splitlines()
    assert len(lines) == 1 and f"'{field}'" in lines[0] and lines[0].startswith("symmech: error:")


def test_separating_contact_point_is_a_clear_error(tmp_path, capsys):
    code, out = run_scene(tmp_path, DEFAULT.replace("[0.3, 0.1, -0.5]", "[0.3, 0.1, 0.5]"), capsys)
    assert code == 2 and "not approaching" in out.err


def test_cli_process_prints_no_traceback(tmp_path):
    scene = tmp_path / "bad.toml"
    scene.write_text(DEFAULT.replace("e = 0.5", "e = 2"))
    done = subprocess.run([sys.executable, "-m", "symmech", "run", str(scene)], capture_output=True, text=True)
    assert done.returncode == 2
    assert done.stderr.strip() == "symmech: error: scene field 'impact.e': 2 is outside [0, 1]"
    missing = subprocess.run([sys.executable, "-m", "symmech", "run", str(tmp_path / "nope.toml")],
                             capture_output=True, text=True)
    assert missing.returncode == 2 and "Traceback" not in missing.stderr


@pytest.mark.xdist_group("derive")  # derives every module: in the worker that already has them
def test_latex_list_plain_and_cse(capsys, monkeypatch):
    """The listing is the index's (no derivation runs for it, nor for refusing a name it lacks), line for line
    what the derivations declare: every generated function by module, in its declared order, with its meaning
    and equations."""
    with monkeypatch.context() as patch:
        patch.setattr(codegen, "derive", lambda producer: pytest.fail(f"--list derived {producer}"))
        assert main(["latex", "--list"]) == 0
        listing = capsys.readouterr().out
        assert main(["latex", "grain_impact.HH"]) == 2  # refused from the index, before any derivation
        assert capsys.readouterr().err == ("symmech: error: no derived matrix named 'grain_impact.HH' (did you mean "
                                           "'grain_impact.H'?) (see `symmech latex --list`)\n")
    declared = [f"{key:<40} {f.meaning}" + (f"  eqs. {f.equations}" if f.equations else "")
                for key, f in codegen.named_matrices().items()]
    assert listing.splitlines() == declared and len(declared) > 150
    assert "grain_impact.H " in listing and "grain_impact_printed.functional" in listing
    assert main(["latex", "grain_impact.euler_rate_matrix"]) == 0
    comment, body = capsys.readouterr().out.split("\n", 1)
    assert comment.startswith("% grain_impact.euler_rate_matrix: ")
    assert body.startswith("\\begin{aligned}\n\\mathrm{euler\\_rate\\_matrix} &= "
                           "\\left[\\begin{matrix}\\cos{\\left(\\phi \\right)}")
    assert main(["latex", "--cse", "grain_impact.H"]) == 0
    cse = capsys.readouterr().out.split("\n", 1)[1]
    assert cse.startswith("\\begin{aligned}\nx_{0} &= ") and "H_{3,3} &= " in cse
    assert main(["latex", "no.such"]) == 2


@pytest.mark.xdist_group("errata")  # the errata checks' sympy work, cached: once, with tests/test_errata_coverage.py
def test_errata_json_records(capsys):
    assert main(["errata", "--json"]) == 0
    records = json.loads(capsys.readouterr().out)["records"]
    # eqs. (1)-(60): the impact records (the motion ones, (61)-(64), are tested with the motion)
    grain = {r["equation"]: r for r in records
             if r["seed"] == "000_b52a2f612feb4113" and r["equation"] not in ("(61)", "(63)")}
    for r in grain.values():
        assert set(r) >= {"seed", "equation", "status", "max_rel_diff", "example"}
        assert set(r["example"]) == {"inputs", "printed", "derived"}
    # Misprints found by hand in the paper: the tool must find exactly these.
    differs = {eq for eq, r in grain.items() if r["status"] == "differs"}
    assert differs == {"(11)-(12)", "(24)", "(27)", "(51)", "(55)", "(43)-(60)"}
    assert all(grain[eq]["max_rel_diff"] > 0.1 for eq in differs)
    assert all(r["max_rel_diff"] < 1e-9 for eq, r in grain.items() if eq not in differs)


def test_bench_precision_writes_csv_and_png(tmp_path, capsys):
    assert main(["bench", "precision", str(ROOT / "scenes" / "impact_default.toml"), "--out", str(tmp_path)]) == 0
    rows = (tmp_path / "precision_impact.csv").read_text().splitlines()
    assert rows[0] == "value [1],error [1],seconds [s],method,knob"
    assert json.loads((tmp_path / "summary.json").read_text())["reference"].startswith("mpmath")
    robust = [r.split(",") for r in rows[1:] if r.split(",")[3].startswith("robust")]
    assert len(robust) == 4 and max(float(r[1]) for r in robust) < 1e-14
    knobs = [("robust (exact reduction)", "newton_iterations", n) for n in (0, 1, 2, 3)]
    knobs += [("scipy.optimize.root", "xtol", x) for x in (1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12)]
    knobs += [(f"descent ({v})", "max_steps", n) for v in ("paper", "paper-corrected") for n in (1, 10, 100, 1000)]
    assert [(r.split(",")[3], r.split(",")[4], float(r.split(",")[0])) for r in rows[1:]] == knobs
    tables = json.loads((tmp_path / "summary.json").read_text())["tables"]
    assert tables["precision_impact"]["doc"] == "Impact solvers: work-precision"
    assert (tmp_path / "precision_impact.png").stat().st_size > 10000
