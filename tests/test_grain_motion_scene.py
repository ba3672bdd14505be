"""The `grain` scene kind through the CLI: files, summary and the precision study."""
import csv
import json
import re
from pathlib import Path

import pytest

from symmech.cli import main

SCENE = Path(__file__).resolve().parents[1] / "scenes" / "grain_default.toml"


def short_scene(tmp_path, duration, extra=""):
    text = re.sub(r"(?m)^duration = .*$", f"duration = {duration}", SCENE.read_text())
    path = tmp_path / "grain.toml"
    path.write_text(text + extra)
    return path


def test_run_writes_trajectory_impacts_summary_and_plots(tmp_path):
    out = tmp_path / "out"
    assert main(["run", str(short_scene(tmp_path, 0.3)), "--out", str(out)]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["kind"] == "grain" and summary["bounces"] > 3
    assert sum(summary["time_fraction"].values()) == pytest.approx(1.0, abs=1e-9)
    assert summary["impacts_creating_energy"] == 0
    assert summary["energy_dissipated_by_impacts_J"] > 0
    for name in ("trajectory.csv", "impacts.csv", "path.png"):
        assert (out / name).stat().st_size > 0
    assert summary["files"] == ["impacts.csv", "path.png", "trajectory.csv"]  # default [output]: the path plot
    rows = list(csv.reader(l for l in (out / "impacts.csv").read_text().splitlines() if not l.startswith("#")))
    assert len(rows) - 1 == summary["bounces"]
    regimes = {l.rsplit(",", 1)[1] for l in (out / "trajectory.csv").read_text().splitlines()[2:]}
    assert {"flight", "impact"} <= regimes


def test_paper_mode_scene_as_printed(tmp_path):
    path = short_scene(tmp_path, 0.1)
    path.write_text(path.read_text().replace('mode = "accurate"', 'mode = "paper"\nas_printed = true\ndt = 4e-5'))
    # --quiet: a quiet run far from its budget times no samples for an estimate nobody is told (pipeline.Scene.run),
    # a third of this test's CPU; the accurate run above is told one, test_estimates.py checks estimates
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["mode"] == "paper" and summary["bounces"] >= 1


def test_as_printed_needs_paper_mode(tmp_path, capsys):
    path = short_scene(tmp_path, 0.1)
    path.write_text(path.read_text().replace('mode = "accurate"', 'mode = "accurate"\nas_printed = true'))
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 2
    assert "numerics.as_printed" in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.compiled_engine
def test_default_scene_and_precision_study(tmp_path):
    assert main(["run", str(SCENE), "--out", str(tmp_path / "run")]) == 0
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    # the 2 s run closes its energy books (speed is measured in benchmarks/bench_pipeline.py, not here)
    assert summary["engine"] == "compiled" and summary["energy_budget"]["relative_residual"] < 1e-9
    assert main(["bench", "precision", str(SCENE), "--out", str(tmp_path / "wp")]) == 0
    text = (tmp_path / "wp" / "precision_grain.csv").read_text()
    assert text.startswith("value [1],error [1],seconds [s],method,knob\n")
    reference = json.loads((tmp_path / "wp" / "summary.json").read_text())["reference"]
    assert reference.startswith("accurate mode at tolerance")
    assert (tmp_path / "wp" / "precision_grain.png").stat().st_size > 0


def test_api_run_has_the_impacts_as_event_log():
    """symmech.load(grain scene).run().event_log(): one row per impact, with units, the impact times
    equal to the trajectory's pre/post impact rows."""
    import tomllib

    import numpy as np

    import symmech
    from symmech.core.scene import scenes_folder

    data = tomllib.loads((scenes_folder() / "grain_default.toml").read_text())
    data["duration"] = 0.1
    result = symmech.load(data).run()
    log = result.event_log()
    assert result.events == "impacts"
    dissipated = -log["energy_change"].values.sum()
    assert dissipated == pytest.approx(result.summary["energy_dissipated_by_impacts_J"], rel=1e-12)
    trajectory = result.tables["trajectory"]
    impact_rows = np.array(trajectory.text["regime"]) == "impact"
    np.testing.assert_array_equal(log["t"].values, trajectory.column("t")[impact_rows][::2])
    assert log.sizes["row"] >= 3
    assert (log["t"].attrs["units"], log["Tz"].attrs["units"], log["vz_before"].attrs["units"]) == ("s", "N s", "m/s")
    assert set(log["admissible"].values) <= {"True", "False"}


@pytest.mark.slow
def test_a_printed_law_creating_energy_fails_one_check_and_warns_in_the_other():
    """The needle (5:1:1) of tests/test_grain_motion_closed_forms.py tumbling onto a still plate under the printed
    law (e = lambda = 0.9), as a grain scene: its one impact gains kinetic energy, so "impacts creating energy"
    fails, while the printed law's own verdict is advice (warn); both law warnings reach the run."""
    import numpy as np

    from symmech.core import pipeline
    from symmech.grain import body, contact, flight

    axes, q0 = [5e-3, 1e-3, 1e-3], np.array([-0.529, 0.693, -0.481, 0.091])
    Q = flight.rotation_matrix(q0 / np.linalg.norm(q0))
    z = float(contact.support_distance(tuple(axes), Q)) + 1e-9
    data = {"kind": "grain", "duration": 1e-5,
            "body": {"semi_axes": axes, "mass": 1e-6, "orientation": body.euler_from_matrix(Q).tolist()},
            "impact": {"law": "printed", "e": 0.9, "lambda": 0.9}, "sliding": {"friction": 0.3},
            "initial": {"position": [0.0, 0.0, z], "velocity": [0.01, 0.084, -0.3],
                        "angular_velocity": [43.5, 3.4, -2.4]},
            "numerics": {"engine": "python", "scan_step": 1e-5, "sample_interval": 1e-5}}
    result = pipeline.load(data).run()
    checks = {c.what: (c.value, c.threshold, c.verdict) for c in result.checks}
    assert checks["impacts creating energy"] == (1.0, "<= 0", "fail")
    assert checks["impacts where the printed law would create energy"] == (1.0, "<= 0", "warn")
    assert result.warnings[0] == "printed impact law: no admissible root; the one used creates kinetic energy"
    assert result.warnings[1].startswith("impact law 'printed' created energy: ")


@pytest.mark.slow
def test_precision_study_rows_and_the_first_order_of_paper_mode():
    """The default grain over 4 ms (T/10, before its first contact at ~27 ms): accurate mode's exact flight meets
    the reference at every tolerance; paper mode's error falls as its step (first order: error / dt within 10 %
    over dt = T/100 ... T/3000); the node count, which only the contact test reads, changes nothing."""
    import tomllib

    from symmech.core import pipeline

    data = tomllib.loads(SCENE.read_text())
    data["numerics"]["engine"] = "python"
    data["precision"]["duration"] = 0.004
    result = pipeline.load(data).precision()
    table = result.tables["precision_grain"]
    period = 1 / 25
    rows = [("accurate (exact flight, root-located contact)", "tolerance", tol) for tol in (1e-3, 1e-5, 1e-7, 1e-9)]
    rows += [("paper mode, 400 nodes", "dt", period / steps) for steps in (100, 300, 1000, 3000)]
    rows += [("paper mode, dt = T/1000, nodes", "nodes", nodes) for nodes in (50, 200, 800)]
    assert list(zip(table.text["method"], table.text["knob"])) == [row[:2] for row in rows]
    assert list(table.column("value")) == pytest.approx([row[2] for row in rows], rel=1e-15)
    error = table.column("error")
    assert max(error[:4]) < 1e-12
    per_dt = error[4:8] / table.column("value")[4:8]
    assert max(per_dt) < 1.1 * min(per_dt) and min(error[4:8]) > 1e-5
    assert list(error[8:]) == [error[6]] * 3
    assert result.summary["reference"] == "accurate mode at tolerance 1e-12, scan step 0.00025 s, duration 0.004 s"
