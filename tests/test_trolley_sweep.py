"""Vehicle design sweeps: a point's numbers equal those of a direct run of the scene with
the same fields set, the comfort margin against hand-built cases, bad [sweep] tables named before any run,
the command line's outputs, and a LocalCluster equal to the serial run bit for bit (slow tier)."""
import copy
import csv
import json

import numpy as np
import pytest

from badinput import DELETE, SCENES, bundled, edited
from outcontract import assert_valid_output
from symmech import cli
from symmech.core import pipeline
from symmech.core import sweep as core_sweep
from symmech.core.context import Context
from symmech.core.results import Column, Result, Table
from symmech.core.scene import SceneError, SymmechError
from symmech.trolley import sweep

pytestmark = pytest.mark.xdist_group("test_trolley_sweep")

# the bundled elastic helix, short: 0.12 s on 24 steps, one Ritz function per plane, 3 modal samples; the
# speed's slope a constant a sweep can vary
TINY = edited(bundled("trolley_elastic_helix"), ("time.t_end", 0.12), ("time.steps", 24),
              ("elastic.beams[0].modes", 1), ("elastic.numerics.modal_samples", 3),
              ("motion.speed", "a*t + 7*sin(t/2)"), ("motion.constants", {"a": 3.0}))
# the rigid paper helix, 1 s on 50 steps
RIGID = edited(bundled("trolley_helix"), ("time.t_end", 1.0), ("time.steps", 50), ("report.paper_tables", False),
               ("effects.local_curvature", False))
RIGID_TOML = (SCENES / "trolley_helix.toml").read_text().replace("t_end = 20.0", "t_end = 1.0").replace(
    "steps = 5000", "steps = 50").replace("local_curvature = true", "local_curvature = false").replace(
    "paper_tables = true", "paper_tables = false")


def swept(base, x, y=None, **extra):
    return copy.deepcopy(base) | {"sweep": {"x": x, **({"y": y} if y else {}), **extra}}


def outcomes(raw):
    p = sweep.plan(raw, pipeline.load(raw).resolved)
    return p, sweep.compute(p, scheduler="synchronous")


def test_amplification_equals_a_direct_run_with_the_same_fields():
    """The point a = 4 m/s², all five roller stiffnesses 2e7 N/m: its amplification of each reaction is
    max|P| / max|P_rigid| of the elastic reactions of that scene, run directly."""
    raw = swept(TINY, {"field": "motion.constants.a", "values": [4.0], "unit": "m/s^2"},
                {"field": "elastic.rollers.stiffness", "values": [2e7]})
    p, out = outcomes(raw)
    status, cols, values, text, _ = out[0]
    got = dict(zip([c.name for c in cols], values))
    direct = edited(TINY, ("motion.constants.a", 4.0), ("elastic.rollers.stiffness", [2e7] * 5))
    er = pipeline.load(direct).run().tables["elastic_reactions"]
    for i in range(6):
        elastic, rigid = np.abs(er.column(f"P{i}")).max(), np.abs(er.column(f"P{i}_rigid")).max()
        assert got[f"amplification_P{i}"] == pytest.approx(elastic / rigid, rel=1e-13)
        assert got[f"peak_P{i}"] == pytest.approx(elastic, rel=1e-13)
    assert status == "ok" and text["resonance_forcing"] in ("axle", "rotation", "curvature")
    # a stiffer roller deflects less under the same loads: d ≈ P / k at the largest reaction
    assert got["roller_deflection_max"] == pytest.approx(got["peak_reaction_max"] / 2e7, rel=0.2)


def test_comfort_margin_of_hand_built_overloads():
    envelope = {"x1": (-2.0, 2.0), "x2": (-1.5, 6.0), "x3": (-2.0, 2.0)}
    inside = np.array([[0.0, 1.0, 0.0], [0.5, 4.0, -1.0]])
    # nearest faces: 2 - 0 along x1 and x3 at the first sample; -1 - (-2) = 1 along x3 at the second
    assert sweep.comfort_margin(inside, envelope) == 1.0
    # beyond two faces at a corner: minus the Euclidean distance, a 3-4-5 triangle
    corner = np.vstack([inside, [2.3, 6.4, 0.0]])
    assert sweep.comfort_margin(corner, envelope) == pytest.approx(-0.5, abs=1e-15)
    # a rigid run of two samples with those overloads and a modes table: natural frequencies 10 Hz (at t = 0.5 s)
    # and 30 Hz (t = 1 s) against the forcings 12 and 40 Hz, then 25 Hz; the closest, |10 / 12 - 1| = 1/6
    reactions = Table([Column(f"P{i}", "N") for i in range(6)], np.array([[1.0, -2.0, 3.0, -4.0, 5.0, -6.0],
                                                                         [0.5, 7.0, -1.0, 2.0, -9.0, 3.0]]))
    overload = Table([Column(n, "g") for n in ("n1", "n2", "n3")], inside)
    modes = Table([Column(n, "1") for n in ("f", "forcing_axle", "forcing_rotation", "forcing_curvature", "mode_id",
                                              "t", "s")],
                  np.array([[10.0, 12.0, 0.0, 40.0, 3.0, 0.5, 2.0], [30.0, 0.0, 25.0, 0.0, 4.0, 1.0, 4.0]]),
                  text={"component": ["beam 0 y", "beam 1 z"]})
    run = Result("trolley", {}, {"case1": reactions, "case1_overload": overload, "modes": modes})
    cols, values, text = sweep.point_metrics(run, envelope)
    got = dict(zip([c.name for c in cols], values))
    assert [got[f"peak_P{i}"] for i in range(6)] == [1.0, 7.0, 3.0, 4.0, 9.0, 6.0] and got["peak_reaction_max"] == 9.0
    assert got["comfort_margin"] == got["comfort_margin_com"] == 1.0
    assert [got[f"resonance_{k}"] for k in ("f", "forcing_f", "mode", "t", "s")] == [10.0, 12.0, 3.0, 0.5, 2.0]
    assert got["resonance_detuning"] == pytest.approx(1 / 6, rel=1e-15)
    assert text == {"resonance_forcing": "axle", "resonance_component": "beam 0 y"}


def test_rigid_comfort_margin_against_the_swept_upper_limit(tmp_path, monkeypatch):
    """The rigid helix's largest normal overload n2 is the only one beyond an upper limit set below it, so
    the margin is that limit minus max n2 (a direct run's), and the point is not admissible."""
    direct = pipeline.load(RIGID).run().tables
    n2 = direct["case1_overload"].column("n2")
    limit = round(float(n2.max()) - 0.2, 3)
    p, out = outcomes(swept(RIGID, {"field": "comfort.x2.hi", "values": [limit, 6.0]}))
    res = sweep.result(p, out)
    margin = res.tables["sweep"].column("comfort_margin")
    assert margin[0] == pytest.approx(limit - n2.max(), rel=1e-12)
    assert list(res.tables["sweep"].column("admissible")) == [0.0, 1.0]
    assert res.summary["worst_point"]["x"] == limit and res.summary["best_point"]["x"] == 6.0
    ds = res.tables["sweep"].to_xarray()  # over the swept axis, in the order swept
    assert ds.comfort_margin.dims == ("x",) and ds.x.values.tolist() == [limit, 6.0]
    assert ds.admissible.sel(x=6.0).item() == 1.0
    # a line over x (no y): the comfort margin charted; the comfort limit moves no reaction, so the largest one
    # is the same at both points: stated as the direct run's number, not charted
    assert sorted(p.name for p in res.plots(tmp_path)) == ["sweep_comfort_margin.png"]
    peak = max(np.abs(direct["case1"].column(f"P{i}")).max() for i in range(1, 6))
    flat = res.summary["flat"]["peak_reaction_max"]
    assert flat["value"] == pytest.approx(peak, rel=1e-12) and flat["spread"] == 0.0
    assert "everywhere, within the tolerance" in flat["text"]
    assert any(h.name == "largest roller reaction |P1…P5|" and h.at == "every point" for h in res.headline)
    # the charts are in the estimate, the rigid model's two: at 100 s a chart, two points are refused under 150 s
    monkeypatch.setattr(core_sweep, "chart_seconds", lambda shape: 100.0)
    with pytest.raises(SymmechError, match=r"estimated sweep time 2\d\d s .* up to 2 charts at 100 s"):
        sweep.compute(p, "synchronous", ctx=Context(quiet=True, max_time=150.0))


def axis(**fields):
    return {"field": "elastic.rollers.stiffness", **fields}


CASES = [
    ("field-not-sweepable", swept(TINY, axis(field="trolley.com", values=[1.0])), "sweep.x.field"),
    ("log-start-zero", swept(TINY, axis(start=0.0, stop=1e7, num=3, log=True)), "sweep.x.start"),
    ("values-and-num", swept(TINY, axis(values=[1e7], num=2)), "sweep.x.num"),
    ("repeated-values", swept(TINY, axis(values=[1e7, 1e7])), "sweep.x.values"),
    ("same-field-twice", swept(TINY, axis(values=[1e7]), axis(values=[2e7])), "sweep.y.field"),
    ("no-x", swept(TINY, DELETE), "sweep.x"),
    ("unknown-key", swept(TINY, axis(values=[1e7]), z=axis(values=[1e7])), "sweep.z"),
    ("constant-not-in-scene", swept(TINY, {"field": "motion.constants.b", "values": [1.0]}), "sweep.x.field"),
    ("speed-scale-of-traction", swept(edited(RIGID, ("motion.speed", DELETE), ("effects.traction", True),
                                             ("motion.traction", "100.0")), {"field": "motion.speed_scale",
                                                                             "values": [1.0]}), "sweep.x.field"),
    ("beam-not-in-scene", swept(TINY, axis(values=[1e7]), {"field": "elastic.beams[2].tip_mass", "values": [1.0]}),
     "sweep.y.field"),
    ("rollers-of-a-rigid-scene", swept(RIGID, axis(values=[1e7])), "sweep.x.field"),
    ("unit-of-a-field-with-one", swept(TINY, axis(values=[1e7], unit="kN/m")), "sweep.x.unit"),
    ("limit-unknown-reaction", swept(TINY, axis(values=[1e7]), limits={"P7": 1.0}), "sweep.limits.P7"),
    ("limit-not-positive", swept(TINY, axis(values=[1e7]), limits={"P1": 0.0}), "sweep.limits.P1"),
    # a swept value the scene refuses is named by its axis
    ("stiffness-out-of-range", swept(TINY, axis(values=[1e7]), axis(field="elastic.rollers.damping",
                                                                    values=[3e3, -1.0])), "sweep.y"),
    ("comfort-limits-cross", swept(TINY, {"field": "comfort.x2.lo", "values": [0.0, 7.0]}), "sweep.x"),
    ("speed-too-fast", swept(TINY, {"field": "motion.speed_scale", "values": [1.0, 1e5]}), "sweep.x"),
    ("tip-mass-negative", swept(TINY, {"field": "elastic.beams[0].tip_mass", "values": [-2.0]}), "sweep.x"),
    ("objective-y-not-swept", swept(RIGID, {"field": "motion.speed_scale", "values": [1.0]}, objective={"quantity": "y"}),
     "sweep.objective.quantity"),
]


def assert_sweep_rejected(data, field):
    with pytest.raises(SymmechError) as info:
        sweep.validate(sweep.plan(data, pipeline.load(data).resolved))
    err = info.value
    assert "\n" not in str(err) and isinstance(err, SceneError), str(err)
    assert err.field == field, f"named {err.field!r}, expected {field!r}: {err}"
    return err


@pytest.mark.parametrize("data, field", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_bad_trolley_sweep_is_named(data, field):
    assert_sweep_rejected(data, field)


def test_messages_name_value_and_range():
    err = assert_sweep_rejected(CASES[14][1], "sweep.y")
    assert "elastic.rollers.damping = -1: elastic.rollers.damping[0]: -1 N s/m is outside [0, 1e+09]" in str(err)
    err = assert_sweep_rejected(CASES[7][1], "sweep.x.field")
    assert "has no 'b' (it has: a)" in str(err)


def test_command_line_sweeps_a_rigid_scene_and_marks_worst_and_best(tmp_path, capsys):
    scene = tmp_path / "rigid.toml"
    scene.write_text(RIGID_TOML + '[sweep.x]\nfield = "motion.speed_scale"\nvalues = [0.5, 1.5]\n'
                     '[sweep.y]\nfield = "trolley.mass"\nvalues = [50.0, 100.0]\n[sweep.limits]\nP3 = 1e3\n')
    assert cli.main(["sweep", str(scene), "--out", str(tmp_path / "o"), "--quiet", "--scheduler",
                     "synchronous"]) == 0
    out = tmp_path / "o"
    assert_valid_output(out)
    with open(out / "sweep.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 4 and list(rows[0])[:3] == ["x [1]", "y [kg]", "peak_P0 [N]"]
    summary = json.loads((out / "summary.json").read_text())
    margins = [float(r["comfort_margin [g]"]) for r in rows]
    assert summary["worst_point"]["comfort_margin"] == min(margins)
    assert summary["best_point"]["comfort_margin"] == max(margins)
    ok = [float(r["comfort_margin [g]"]) >= 0 and float(r["peak_P3 [N]"]) <= 1e3 for r in rows]
    assert [r["admissible [1]"] == "1.0" for r in rows] == ok and summary["admissible_points"] == sum(ok)
    assert (out / "sweep_comfort_margin.png").stat().st_size > 5000
    assert (out / "sweep_peak_reaction_max.png").stat().st_size > 5000


def test_command_line_refuses_a_kind_without_sweep_and_a_bad_sweep(tmp_path, capsys):
    scene = tmp_path / "impact.toml"
    scene.write_text('kind = "impact"\n')
    assert cli.main(["sweep", str(scene), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err == "symmech: error: scene field 'kind': scene kind 'impact' has no sweep (kinds with one: grain, trolley)\n"
    bad = tmp_path / "bad.toml"
    bad.write_text(RIGID_TOML + '[sweep.x]\nfield = "motion.speed_scale"\nvalues = [1.0, 1e5]\n')
    assert cli.main(["sweep", str(bad), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("symmech: error: scene field 'sweep.x': motion.speed_scale = 100000: motion.speed: ")
    assert len(err.splitlines()) == 1 and not (tmp_path / "o").exists()
    assert cli.main(["sweep", str(bad), "--out", str(tmp_path / "o"), "--half-width", "0.01"]) == 2
    assert capsys.readouterr().err == "symmech: error: --half-width does not apply to a sweep of a trolley scene\n"


@pytest.mark.slow
# the default engine, here and in the worker processes (the fixture's reference engine reaches this one only)
@pytest.mark.compiled_elastic
def test_local_cluster_equals_serial_bit_for_bit():
    import dask.distributed as distributed

    raw = swept(TINY, {"field": "motion.speed_scale", "values": [0.8, 1.2]},
                {"field": "elastic.rollers.stiffness_scale", "values": [0.5, 2.0]})
    p, serial = outcomes(raw)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        remote = sweep.compute(p, scheduler=cluster.scheduler_address, processes=2)
    a, b = sweep.result(p, serial).tables["sweep"], sweep.result(p, remote).tables["sweep"]
    assert a.data.shape == (4, 28) and np.array_equal(a.data, b.data) and a.text == b.text


def test_chart_cells_sit_midway_between_the_swept_values_and_stay_within_the_range():
    np.testing.assert_allclose(core_sweep.edges(np.array([1.0, 2.0, 4.0]), False), [1.0, 1.5, 3.0, 4.0], rtol=1e-15)
    np.testing.assert_allclose(core_sweep.edges(np.array([1.0, 10.0, 100.0]), True),
                               10 ** np.array([0.0, 0.5, 1.5, 2.0]), rtol=1e-14)


def test_the_compiled_engine_is_built_before_the_first_point_is_timed(monkeypatch):
    """A sweep on the compiled elastic engine builds it (or loads it) first, so its one-off compile is
    neither in the first point's time, which the estimate scales to the whole plane, nor paid per worker."""
    from symmech.trolley.elastic import compiled as elastic_compiled, scene as elastic_scene

    calls = []
    monkeypatch.setattr(elastic_scene, "engine", lambda setup, runs=1: ("compiled", "test"))
    monkeypatch.setattr(elastic_compiled.ENGINE, "warm", lambda wait=True, say=None: calls.append("warm") or True)
    monkeypatch.setattr(sweep, "evaluate", lambda p, i, j, until: calls.append("point") or ("failed", "stub"))
    raw = swept(TINY, {"field": "motion.constants.a", "values": [3.0, 4.0]})
    outcomes(raw)
    assert calls == ["warm", "point", "point"]
    calls.clear()
    monkeypatch.setattr(elastic_scene, "engine", lambda setup, runs=1: ("python", "test"))
    outcomes(raw)
    assert calls == ["point", "point"]


def test_the_admissible_border_runs_along_the_cell_edges():
    """Points admissible left of x = 2 and below y = 1 (a 3 x 2 plane): the border is the edge x = 2.5
    over the lower row's cell and the edge y = 15 over the two left columns, nothing else."""
    xe, ye = np.array([0.5, 1.5, 2.5, 3.5]), np.array([5.0, 15.0, 25.0])
    ok = np.array([[True, False], [True, False], [False, False]])
    assert sorted(core_sweep.border(xe, ye, ok)) == sorted([((2.5, 5.0), (2.5, 15.0)), ((0.5, 15.0), (1.5, 15.0)),
                                                            ((1.5, 15.0), (2.5, 15.0))])
