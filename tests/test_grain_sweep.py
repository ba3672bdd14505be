"""Populations and sweeps (issue 14 item 3): Dask equals serial bit for bit, the throw number,
the lift-off threshold across a swept plane, the separation chart, and validation first."""
import math

import numpy as np
import pytest

from symmech.core import pipeline
from symmech.core.scene import SceneError
from symmech.grain import sweep

# sweep.compute builds the compiled engine before dispatch: ordered last, after the session's build (conftest.py)
pytestmark = pytest.mark.compiled_engine
G = 9.81
FREQ = 25.0
W = 2 * math.pi * FREQ


def amplitude(gamma_v, angle_deg=30.0):
    """Amplitude whose normal throw number A w^2 sin(angle) / g is gamma_v."""
    return gamma_v * G / (W**2 * math.sin(math.radians(angle_deg)))


def conveyor(**extra):
    """A 1 mm sphere on a horizontal plate vibrated at 30 deg: the classical conveying problem."""
    scene = {
        "kind": "grain", "duration": 4 / FREQ,
        "body": {"semi_axes": [1e-3, 1e-3, 1e-3], "density": 1200.0},
        "surface": {"g": G, "alpha_deg": 0.0},
        "vibration": {"amplitude": amplitude(1.5), "frequency": FREQ, "direction": "angle", "angle_deg": 30.0},
        "impact": {"law": "printed", "e": 0.0, "lambda": 1.0},
        "sliding": {"friction": 100.0},
        "effects": {"rotation": False},
    }
    scene.update(extra)
    return scene


def build(raw):
    return sweep.plan(raw, pipeline.load(raw).resolved)


def test_liftoff_threshold_and_throw_number_over_the_plane():
    raw = conveyor(sweep={"x": {"field": "vibration.amplitude", "values": [amplitude(0.9), amplitude(1.5)]}})
    p = build(raw)
    np.testing.assert_allclose(p.gamma[:, 0], np.array([amplitude(0.9), amplitude(1.5)]) * W**2 / G, rtol=1e-15)
    st = sweep.statistics(sweep.compute(p, scheduler="synchronous")[0][0])
    assert st["flight_fraction"][0, 0] == 0.0 and st["hop_fraction"][0, 0] == 0.0  # below lift-off
    assert st["flight_fraction"][1, 0] > 0.2 and st["mean_vx"][1, 0] > 0.0  # conveyed forward


def test_identical_populations_do_not_separate():
    pops = [{"name": n, "count": 3, "seed": 7, "vary": {"body.semi_axes": 0.2}} for n in ("a", "b")]
    raw = conveyor(duration=2 / FREQ, population=pops,
                   sweep={"x": {"field": "vibration.frequency", "values": [FREQ]}})
    p = build(raw)
    res = sweep.result(p, *sweep.compute(p, scheduler="synchronous"))
    sep = res.tables["separation"]
    assert sep.column("delta_vx")[0] == 0.0
    assert sep.column("overlap")[0] == pytest.approx(1.0, abs=1e-6)


def test_overlap_of_two_normals_matches_the_closed_form():
    rng = np.random.default_rng(3)
    a = rng.normal(size=200_000)
    b = a + 1.0  # same spread, means one sigma apart: OVL = 2 Phi(-1/2)
    expected = 1 + math.erf(-0.5 / math.sqrt(2))
    assert sweep.overlap(a, b) == pytest.approx(expected, abs=2e-3)


def test_a_bad_grain_of_the_population_is_named_before_any_work():
    pops = [{"name": "weed", "count": 2, "set": {"body.semi_axes": [1e-3, -1e-3, 1e-3]}}]
    raw = conveyor(population=pops, sweep={"x": {"field": "vibration.frequency", "values": [FREQ]}})
    with pytest.raises(SceneError) as info:
        sweep.validate(build(raw))
    assert info.value.field == "population[0].set.body.semi_axes[1]"


def test_dask_cluster_equals_serial_bit_for_bit():
    import dask.distributed as distributed
    pops = [{"name": "wheat", "count": 2, "seed": 1, "vary": {"body.density": 0.1}},
            {"name": "weed", "count": 2, "seed": 2, "set": {"body.semi_axes": [7e-4, 7e-4, 7e-4]}}]
    raw = conveyor(duration=2 / FREQ, population=pops,
                   sweep={"x": {"field": "vibration.amplitude", "values": [amplitude(1.2), amplitude(1.6)]},
                          "y": {"field": "vibration.frequency", "start": 20.0, "stop": 30.0, "num": 2}})
    p = build(raw)
    serial = sweep.compute(p, scheduler="synchronous")[0]
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        remote = sweep.compute(p, scheduler=cluster.scheduler_address)[0]
    for a, b in zip(serial, remote):
        assert a.shape == (2, 2, 2, 3)
        assert np.array_equal(a, b)


def test_sweep_writes_tables_with_units_heat_maps_and_the_best_point(tmp_path):
    import csv
    import json

    from symmech.core.context import Context

    pops = [{"name": "crop", "count": 1}, {"name": "weed", "count": 1, "set": {"body.semi_axes": [6e-4, 6e-4, 6e-4]}}]
    raw = conveyor(duration=2 / FREQ, population=pops,
                   sweep={"x": {"field": "vibration.amplitude", "values": [amplitude(1.2), amplitude(1.8)]},
                          "y": {"field": "vibration.angle_deg", "values": [20.0, 40.0]}})
    sweep.run(raw, tmp_path / "out", Context(quiet=True), scheduler="synchronous")
    out = tmp_path / "out"
    summary = json.loads((out / "summary.json").read_text())
    assert summary["points"] == 4 and summary["populations"] == ["crop", "weed"]
    best = summary["best_operating_point"]
    with open(out / "separation.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert list(rows[0])[:3] == ["x [m]", "y [deg]", "gamma [1]"]
    least = min(float(r["overlap [1]"]) for r in rows)
    assert best["overlap"] == pytest.approx(least, abs=0)
    for name in ("crop_mean_vx", "weed_hop_fraction", "separation_overlap"):
        assert (out / f"{name}.png").stat().st_size > 5000


def test_sweep_refuses_past_the_time_budget(tmp_path):
    from symmech.core.context import Context
    from symmech.core.scene import SymmechError

    raw = conveyor(duration=100.0, population=[{"name": "many", "count": 1000}],
                   sweep={"x": {"field": "vibration.frequency", "start": 20.0, "stop": 30.0, "num": 50}})
    with pytest.raises(SymmechError, match="exceeds --max-time"):
        sweep.run(raw, tmp_path / "out", Context(quiet=True, max_time=60.0), scheduler="synchronous")
    assert not (tmp_path / "out").exists()


def test_a_grain_that_stops_with_an_error_is_reported_not_averaged(monkeypatch):
    from symmech.core.scene import SymmechError

    real = pipeline.Scene.run
    calls = []

    def flaky(self, ctx=None):
        calls.append(1)
        if len(calls) == 2:
            raise SymmechError("sliding integration stagnates at t = 0.01 s")
        return real(self, ctx)

    monkeypatch.setattr(pipeline.Scene, "run", flaky)
    raw = conveyor(duration=1 / FREQ, population=[{"name": "a", "count": 3, "vary": {"body.density": 0.1}}],
                   sweep={"x": {"field": "vibration.frequency", "values": [FREQ]}})
    p = build(raw)
    values, failed, warned = sweep.compute(p, scheduler="synchronous")
    assert [f[:4] for f in failed] == [("a", 0, 0, 1)] and "stagnates" in failed[0][4]
    res = sweep.result(p, values, failed)
    table = res.tables["sweep_a"]
    assert table.column("failed")[0] == 1.0
    ok = values[0][0, 0, [0, 2], 0]
    assert table.column("mean_vx")[0] == pytest.approx(ok.mean(), rel=1e-15)
    assert res.summary["failed_grains"][0]["grain"] == 1 and res.warnings


def test_a_grain_that_warns_is_averaged_in_and_listed(monkeypatch):
    """E.g. a rocking contact (issue 13): the grain's result counts, its warnings go to the summary."""
    real = pipeline.Scene.run
    calls = []

    def warning(self, ctx=None):
        calls.append(1)
        res = real(self, ctx)
        if len(calls) == 3:
            res.warnings.append("1 rocking contact(s): ...")
        return res

    monkeypatch.setattr(pipeline.Scene, "run", warning)
    raw = conveyor(duration=1 / FREQ, population=[{"name": "a", "count": 3, "vary": {"body.density": 0.1}}],
                   sweep={"x": {"field": "vibration.frequency", "values": [FREQ]}})
    p = build(raw)
    values, failed, warned = sweep.compute(p, scheduler="synchronous")
    assert failed == [] and warned == [("a", 0, 0, 2, ["1 rocking contact(s): ..."])]
    res = sweep.result(p, values, failed, warned)
    assert res.tables["sweep_a"].column("failed")[0] == 0.0
    assert res.tables["sweep_a"].column("mean_vx")[0] == pytest.approx(values[0][0, 0, :, 0].mean(), rel=1e-15)
    assert res.summary["warned_grains"] == [{"population": "a", "point": [0, 0], "grain": 2,
                                             "warnings": ["1 rocking contact(s): ..."]}]
    assert any("ran with warnings" in w for w in res.warnings)
