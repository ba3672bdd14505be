"""Populations and sweeps: Dask equals serial bit for bit, the throw number,
the lift-off threshold across a swept plane, the separation chart, and validation first."""
import math
import warnings

import numpy as np
import pytest

from symmech.core import pipeline
from symmech.core.scene import SceneError
from symmech.grain import motion_scene, sweep

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
        # the sweep's logic, not the engine's (tests/test_grain_compiled.py): the Python loop needs no compile
        "numerics": {"engine": "python"},
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
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        sweep.run(raw, tmp_path / "out", Context(quiet=True), scheduler="synchronous")
    # one grain a point has no spread (0 / 0 grains less one): said by a null, not by numpy's warning
    assert [str(w.message) for w in caught if w.category is RuntimeWarning] == []
    out = tmp_path / "out"
    summary = json.loads((out / "summary.json").read_text())
    assert summary["points"] == 4 and summary["populations"] == ["crop", "weed"]
    best = summary["best_operating_point"]
    with open(out / "separation.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert list(rows[0])[:3] == ["x [m]", "y [deg]", "gamma [1]"]
    least = min(float(r["overlap [1]"]) for r in rows)
    assert best["overlap"] == pytest.approx(least, abs=0)
    for name in ("crop_mean_vx", "weed_hop_fraction"):
        assert (out / f"{name}.png").stat().st_size > 5000
    # one grain per population, identical velocities: the overlap and Δv_x are the same at every point (to
    # round-off), so they are stated as numbers, not colour-mapped
    assert summary["flat"]["separation_overlap"]["value"] == pytest.approx(least, abs=0)
    assert "everywhere, within the tolerance" in summary["flat"]["separation_overlap"]["text"]
    assert abs(summary["flat"]["separation_delta_vx"]["value"]) < 1e-15
    assert not (out / "separation_overlap.png").exists() and not (out / "separation_delta_vx.png").exists()
    # one grain per population: no interval, no spread to size a population from (null, not NaN, in JSON)
    assert best["overlap_interval"] == [None, None] and summary["precision"]["crop"]["grains_needed"] is None


def test_the_half_width_option_is_a_positive_speed():
    from symmech import cli

    parser = cli.build_parser()
    assert parser.parse_args(["sweep", "s.toml", "--half-width", "5e-4"]).half_width == 5e-4
    for bad in ("0", "-1e-3", "inf", "fast"):
        with pytest.raises(SystemExit) as info:
            parser.parse_args(["sweep", "s.toml", "--half-width", bad])
        assert info.value.code == 2


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

    real = motion_scene.simulate_many

    def flaky(scenes, workers=None, strict=True):  # the second grain's run fails
        runs = real(scenes, workers, strict)
        runs[1] = SymmechError("sliding integration stagnates at t = 0.01 s")
        return runs

    monkeypatch.setattr(motion_scene, "simulate_many", flaky)
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
    ds = table.to_xarray()  # over the swept axis, its values the coordinate
    assert ds.mean_vx.dims == ("x",) and ds.x.values.tolist() == [FREQ] and ds.failed.sel(x=FREQ).item() == 1.0


def test_a_grain_that_warns_is_averaged_in_and_listed(monkeypatch):
    """E.g. a rocking contact: the grain's result counts, its warnings go to the summary."""
    real = motion_scene.simulate_many

    def warning(scenes, workers=None, strict=True):  # the third grain's run warns
        runs = real(scenes, workers, strict)
        runs[2].warnings.append("1 rocking contact(s): ...")
        return runs

    monkeypatch.setattr(motion_scene, "simulate_many", warning)
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


# --- a lazy plan, and statistics with confidence intervals -----------------------------

def _eager_set(data: dict, path: str, value) -> None:
    sweep._set(data, path, value, "eager plan")


def eager_plan(raw):
    """Reference: the plan as symmech built it before the lazy plan (every grain scene of the sweep in memory,
    the grains of a population drawn in turn from one generator); scenes[k][i][j] lists population k's
    grain scenes at point (i, j)."""
    import copy

    resolved = pipeline.load(raw).resolved
    base = {k: v for k, v in copy.deepcopy(raw).items() if k not in ("sweep", "population")}
    sw = resolved["sweep"]
    xs, ys = sweep.axis_values(sw["x"]), sweep.axis_values(sw["y"]) if sw["y"] else [np.nan]
    gamma, scenes = np.empty((len(xs), len(ys))), []
    for pop in resolved["population"]:
        rng = np.random.default_rng(pop["seed"])
        crowd = []
        for _ in range(pop["count"]):
            data = copy.deepcopy(base)
            for path, value in pop["set"].items():
                _eager_set(data, path, copy.deepcopy(value))
            for path, spread in pop["vary"].items():
                value = sweep._get(data, path)
                size = len(value) if isinstance(value, list) else 1
                _eager_set(data, path, sweep._scaled(value, rng.uniform(1 - spread, 1 + spread, size).tolist()))
            if pop["random_orientation"]:
                _eager_set(data, "body.orientation", [float(rng.uniform(0, 2 * math.pi)),
                                                      float(math.acos(rng.uniform(-1, 1))),
                                                      float(rng.uniform(0, 2 * math.pi))])
            crowd.append(data)
        grid = []
        for i, xv in enumerate(xs):
            row = []
            for j, yv in enumerate(ys):
                point = copy.deepcopy(crowd)
                for data in point:
                    _eager_set(data, sw["x"]["field"], float(xv))
                    if sw["y"]:
                        _eager_set(data, sw["y"]["field"], float(yv))
                gamma[i, j] = sweep.throw_number(pipeline.load(point[0]).resolved)
                row.append(point)
            grid.append(row)
        scenes.append(grid)
    return gamma, scenes


def small_populations(count=3):
    return [{"name": "crop", "count": count, "seed": 11, "vary": {"body.semi_axes": 0.2, "body.density": 0.1},
             "random_orientation": True},
            {"name": "weed", "count": count, "seed": 2**40 + 3, "set": {"body.semi_axes": [7e-4, 6e-4, 5e-4]},
             "vary": {"impact.e": 0.3}}]


def test_the_lazy_plan_builds_the_grains_of_the_eager_plan_and_runs_them_bit_for_bit(monkeypatch):
    raw = conveyor(duration=1 / FREQ, population=small_populations(3),
                   sweep={"x": {"field": "vibration.amplitude", "values": [amplitude(1.2), amplitude(1.6)]},
                          "y": {"field": "vibration.frequency", "values": [FREQ, 1.2 * FREQ]}})
    gamma, eager = eager_plan(raw)
    p = build(raw)
    assert np.array_equal(p.gamma, gamma) and p.grain_runs == 2 * 3 * 4
    for k, i, j in np.ndindex(2, 2, 2):
        assert list(sweep.grains(p, k, i, j)) == eager[k][i][j]
        for start, stop in ((1, 3), (2, 3), (0, 1)):  # any grain from (population, seed, index) alone
            assert list(sweep.grains(p, k, i, j, start, stop)) == eager[k][i][j][start:stop]
    # results: point (1, 1) of each population, spread over two tasks, against the eager plan's grains run
    # as before (one point per task)
    monkeypatch.setattr(sweep, "CHUNK", 2)
    corner = build(conveyor(duration=1 / FREQ, population=small_populations(3),
                            sweep={"x": {"field": "vibration.amplitude", "values": [amplitude(1.6)]},
                                   "y": {"field": "vibration.frequency", "values": [1.2 * FREQ]}}))
    lazy = sweep.compute(corner, scheduler="synchronous")[0]
    for k in range(2):
        assert np.array_equal(lazy[k][0, 0], sweep.simulate_point(eager[k][1][1])[0])


SWEEP_CHILD = """
import resource, subprocess, sys, time
t = time.perf_counter()
run = subprocess.run([sys.executable, "-m", "symmech", "sweep", sys.argv[1], "--out", sys.argv[2], "--max-time", "1"],
                     capture_output=True, text=True)
print(run.returncode, time.perf_counter() - t, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)
print(run.stderr, end="")
"""


def test_a_sweep_of_ten_million_grains_is_refused_from_its_counts_in_seconds(tmp_path):
    """2 populations x 100,000 grains x 50 points: refused by its estimate without a grain scene built
    (before the lazy plan the plan built them all: minutes and gigabytes)."""
    import subprocess
    import sys

    from symmech.core.scene import scenes_folder

    text = (scenes_folder() / "grain_separation.toml").read_text()
    text = text.replace("count = 30", "count = 100000").replace("num = 12", "num = 50", 1)
    text = text.replace("num = 12", "num = 1").replace("start = 18.0", "start = 25.0")
    (tmp_path / "huge.toml").write_text(text)
    # a fresh parent: RUSAGE_CHILDREN then measures the sweep process alone
    out = subprocess.run([sys.executable, "-c", SWEEP_CHILD, str(tmp_path / "huge.toml"), str(tmp_path / "out")],
                         capture_output=True, text=True, check=True).stdout.splitlines()
    code, seconds, peak_kib = out[0].split()
    assert int(code) == 2 and len(out) == 2
    assert "exceeds --max-time 1 s" in out[1] and "10000000 grain runs" in out[1]
    assert float(seconds) < 10.0  # generous on a loaded machine: about 2 s, nearly all imports
    assert int(peak_kib) < 200 * 1024
    assert not (tmp_path / "out").exists()


def test_mean_and_spread_intervals_cover_a_normal_population_at_their_level():
    """2000 points of 30 normal grains each (mu, sigma known): the Student t interval of the mean and the
    chi-square interval of the spread each cover the truth at 95 %, within the binomial 99.9 % bounds."""
    from scipy import stats

    mu, sigma, points, n = 0.07, 0.012, 2000, 30
    grid = np.random.default_rng(22).normal(mu, sigma, (points, 1, n, 3))
    st = sweep.statistics(grid)
    lo, hi = stats.binom.ppf([0.0005, 0.9995], points, 0.95)
    for name, truth in (("mean_vx", mu), ("mean_vy", mu), ("flight_fraction", mu), ("std_vx", sigma)):
        covered = int(((st[f"{name}_lo"] <= truth) & (truth <= st[f"{name}_hi"])).sum())
        assert lo <= covered <= hi, (name, covered)


def test_intervals_equal_scipys_tests_of_the_same_samples():
    """Student t (ttest_1samp), Welch (ttest_ind, equal_var=False) and Wilson (binomtest) intervals, with a
    failed grain (NaN) left out."""
    from scipy import stats

    rng = np.random.default_rng(4)
    a, b = rng.normal(0.05, 0.01, (1, 1, 25, 3)), rng.normal(0.03, 0.02, (1, 1, 18, 3))
    a[0, 0, 3] = np.nan
    clean = a[0, 0, np.isfinite(a[0, 0, :, 0])]
    st = sweep.statistics(a)
    ref = stats.ttest_1samp(clean[:, 0], 0.0).confidence_interval(0.95)
    assert st["mean_vx_lo"][0, 0] == pytest.approx(ref.low, rel=1e-12)
    assert st["mean_vx_hi"][0, 0] == pytest.approx(ref.high, rel=1e-12)
    lo, hi = sweep.difference_interval(a[..., 1], b[..., 1])
    ref = stats.ttest_ind(clean[:, 1], b[0, 0, :, 1], equal_var=False).confidence_interval(0.95)
    assert (lo[0, 0], hi[0, 0]) == pytest.approx((ref.low, ref.high), rel=1e-12)
    for k, n in ((0, 30), (7, 30), (30, 30), (1, 3)):
        ref = stats.binomtest(k, n).proportion_ci(0.95, method="wilson")
        assert sweep.proportion_interval(np.array(k), np.array(n)) == pytest.approx((ref.low, ref.high), abs=1e-12)


def test_overlap_of_normals_with_different_spreads_matches_quadrature():
    from scipy import integrate, stats

    for m1, s1, m2, s2 in ((0.0, 1.0, 1.0, 1.5), (0.3, 0.2, -0.1, 0.05), (1.0, 1.0, 1.0, 2.0)):
        pdf_min = lambda v: min(stats.norm.pdf(v, m1, s1), stats.norm.pdf(v, m2, s2))  # noqa: E731
        ref = integrate.quad(pdf_min, -20, 20, points=[m1, m2], limit=200, epsabs=1e-12)[0]
        assert float(sweep.overlap_normal(m1, s1, m2, s2)) == pytest.approx(ref, abs=1e-6)  # quad: kinks


def test_overlap_interval_covers_the_true_overlap():
    """Bootstrap percentile intervals of the overlap of two normal samples of 30: coverage near 95 % (an
    asymptotic method: a bound of 0.87 at 200 repeats, observed about 0.93)."""
    rng = np.random.default_rng(9)
    truth = float(sweep.overlap_normal(0.0, 1.0, 1.0, 1.5))
    ends = np.array([sweep.overlap_interval(rng.normal(0, 1, 30), rng.normal(1, 1.5, 30), rng) for _ in range(200)])
    coverage = np.mean((ends[:, 0] <= truth) & (truth <= ends[:, 1]))
    assert 0.87 <= coverage <= 0.99


def test_points_whose_overlap_interval_meets_the_best_are_marked():
    """Three points of 30 + 30 normal grains: identical populations (overlap 1), 4 sigma apart (0.046) and
    3.9 sigma apart (0.051): the last two are not significantly different, the first is."""
    rng = np.random.default_rng(1)
    a = rng.normal(0.0, 0.01, (3, 1, 30, 3))
    b = rng.normal(0.0, 0.01, (3, 1, 30, 3)) + np.array([0.0, 0.04, 0.039])[:, None, None, None]
    sep = sweep.separation(a, b)
    best, similar = sweep.best_point(sep)
    assert best in (1, 2) and similar[:, 0].tolist() == [False, True, True]
    assert sep["overlap_lo"][best, 0] < sep["overlap"][best, 0] < sep["overlap_hi"][best, 0]
    # the same tables on every run (docs/scenes-grain.md): the resamples drawn from a generator seeded 0, the
    # first point's interval scipy's percentile bootstrap of 999 resamples from that generator's start
    from scipy import stats

    first = stats.bootstrap((a[0, 0, :, 0], b[0, 0, :, 0]), sweep.overlap, n_resamples=999, confidence_level=0.95,
                            method="percentile", vectorized=True, rng=np.random.default_rng(0)).confidence_interval
    assert (sep["overlap_lo"][0, 0], sep["overlap_hi"][0, 0]) == pytest.approx((first.low, first.high), rel=1e-12)


def test_grains_needed_for_a_half_width():
    from scipy import stats

    for spread, half in ((0.01, 1e-3), (0.02, 5e-3), (1e-4, 1e-3)):
        n = sweep.grains_needed(spread, half)
        assert stats.t.ppf(0.975, n - 1) * spread / math.sqrt(n) <= half
        assert n == 2 or stats.t.ppf(0.975, n - 2) * spread / math.sqrt(n - 1) > half
    assert sweep.grains_needed(0.01, 1e-3) == pytest.approx((1.959964 * 0.01 / 1e-3) ** 2, abs=4)


@pytest.mark.slow
def test_the_bundled_separation_sweep_carries_its_intervals(tmp_path):
    """scenes/grain_separation.toml: 12 x 12 points x 30 grains per population (minutes on 2 cores)."""
    import json

    from symmech.core.context import Context
    from symmech.core.scene import scenes_folder

    res = sweep.run(scenes_folder() / "grain_separation.toml", tmp_path / "out", Context(quiet=True, max_time=3600))
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["points"] == 144 and summary["grains_per_point"] == [30, 30]
    for table in res.tables.values():
        names = {c.name for c in table.columns}
        for c in table.columns:
            if f"{c.name}_lo" in names:
                v, lo, hi = (table.column(n) for n in (c.name, f"{c.name}_lo", f"{c.name}_hi"))
                assert np.all(lo <= v + 1e-15) and np.all(v <= hi + 1e-15), c.name
    best = summary["best_operating_point"]
    assert best["overlap_interval"][0] <= best["overlap"] <= best["overlap_interval"][1]
    assert best["delta_vx_interval_m_s"][0] <= best["delta_vx_m_s"] <= best["delta_vx_interval_m_s"][1]
    assert len(best["points_not_significantly_worse"]) >= 1
    for name in ("crop", "weed"):
        assert summary["precision"][name]["grains_needed"] >= 2
    assert (tmp_path / "out" / "separation_overlap.png").stat().st_size > 5000


@pytest.mark.slow
def test_a_slice_the_budget_cannot_hold_runs_grain_by_grain_to_the_same_answers():
    """Near the deadline (less time left than BUDGET_MARGIN times a slice's count estimate) the grains run one by one,
    each watched by the deadline, and give what the population gives; past it, each is refused by the deadline."""
    import time

    raw = conveyor(duration=1 / FREQ, population=[{"name": "a", "count": 3, "vary": {"body.density": 0.1}}],
                   sweep={"x": {"field": "vibration.frequency", "values": [FREQ]}})
    p = build(raw)
    grains = list(sweep.grains(p, 0, 0, 0))
    estimate = pipeline.load(grains[0]).estimate().seconds
    together = sweep.simulate_point(grains)
    near = sweep.simulate_point(grains, until=time.time() + 0.5 * sweep.BUDGET_MARGIN * len(grains) * estimate)
    assert estimate * len(grains) * sweep.BUDGET_MARGIN > 0.5 * sweep.BUDGET_MARGIN * len(grains) * estimate > estimate
    assert np.array_equal(together[0], near[0]) and together[1:] == near[1:] == ([], [])
    past = sweep.simulate_point(grains, until=time.time() - 1.0)
    assert np.isnan(past[0]).all() and [k for k, _ in past[1]] == [0, 1, 2]
    assert all("max-time" in message for _, message in past[1])
