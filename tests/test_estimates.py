"""Estimates that hold: a run's estimate comes from timed samples of the scene on this machine, whatever the
count model's seconds say, and a sweep's from a timed wave of its tasks; each is compared with the time the
same process then measures (a loaded machine slows both alike)."""
import dataclasses
import json
import os
import statistics
import subprocess
import sys
import time

import dask
import pytest

from badinput import bundled, edited
from symmech.core import pipeline, sample
from symmech.core import sweep as core_sweep
from symmech.core.context import Context
from symmech.core.scene import SymmechError
from symmech.smm import scene as smm_scene
from symmech.trolley import scene as trolley_scene

# the rigid helix, 8 s on 2000 steps, both cases: ~0.1 s of run on an idle machine
RIGID = edited(bundled("trolley_helix"), ("time.t_end", 8.0), ("time.steps", 2000), ("report.paper_tables", False))




def chain(n: int, **tables) -> dict:
    """A mechanism scene: a fixed-fixed chain of ``n`` masses of 0.1 kg on springs of 10 kN/m, 10 mm apart."""
    return {"kind": "mechanism", "name": f"chain_{n}", "output": {"plots": []},
            "chain": {"n": n, "mass": 0.1, "stiffness": 1.0e4, "spacing": 0.01, "ends": "fixed-fixed"}, **tables}


class Told(Context):
    """A Context that keeps what it says (not quiet: a run's estimate is told, so sampled)."""

    def __init__(self, **kw):
        super().__init__(quiet=False, **kw)
        self.told = []

    def say(self, message: str) -> None:
        self.told.append(message)


def run_seconds(scene) -> float:
    """Wall time [s] of the scene's run stage once more (the median of three is robust to a loaded moment)."""
    started = time.perf_counter()
    scene.kind.run(scene.setup, Context(quiet=True))
    return time.perf_counter() - started


def told_seconds(ctx: Told) -> float:
    """The last sweep estimate ``ctx`` was told, in seconds."""
    return float([m for m in ctx.told if m.startswith("estimated sweep time")][-1].split()[3])


@pytest.mark.parametrize("off", [1.0, 1000.0])
def test_a_run_estimate_holds_whatever_the_count_model_says(monkeypatch, off):
    """The count model's seconds per step as they are (tens of times under this scene's time) and 1000x that
    (a machine far slower than this one): the estimate told is within 2x of the run's own time either way,
    since samples set the scale; the count estimate alone is more than 2x off either way (the test can fail).
    A wall-time estimate against wall time: when the machine's load changes between the samples and the runs
    (other jobs on 2 cores), the pair is taken once more, sampled anew; the count model, tens of times off, fails
    both."""
    for name in ("SECONDS_PER_STEP", "SECONDS_PER_OUTPUT_ROW"):
        monkeypatch.setattr(trolley_scene, name, getattr(trolley_scene, name) * off)
    scene = pipeline.load(RIGID)
    count = scene.kind.estimate(scene.setup).seconds
    for _ in range(2):
        scene.run(Told())  # told (not quiet): sampled
        actual = statistics.median([scene.timing["run"], *(run_seconds(scene) for _ in range(2))])
        assert "timed samples" in scene.cost.what
        if 0.5 <= scene.cost.seconds / actual <= 2.0:
            break
    assert 0.5 <= scene.cost.seconds / actual <= 2.0, (scene.cost, actual)
    assert not 0.5 <= count / actual <= 2.0  # the count model alone would not hold: the test can fail


def test_sweep_points_and_quiet_runs_far_from_the_budget_are_not_sampled():
    """A sweep's points run with the sweep's own estimate, and a quiet run (the API's) whose count estimate is
    far below --max-time is told to nobody: neither times samples."""
    for ctx in (core_sweep.point_context(time.time() + 60.0), Context(quiet=True)):
        scene = pipeline.load(RIGID)
        scene.run(ctx)
        assert scene.cost == scene.kind.estimate(scene.setup)


def test_a_sweep_estimate_comes_from_its_second_wave():
    """Six tasks of 0.05 s, serial: the first pays the workers' start, the second is timed; four waves left.
    The estimate told (time so far plus four waves) is within 2x of the whole sweep's time; the progress bar of
    six tasks advances by one per task."""
    ctx = Told()
    bars = []
    ctx.progress = lambda total, desc, unit: bars.append((total, [])) or Bar(bars[-1][1])
    tasks = [dask.delayed(time.sleep)(0.05, dask_key_name=f"nap-{k}") for k in range(6)]
    core_sweep.compute(tasks, "synchronous", ctx=ctx)
    assert "a wave of 1 in" in ctx.told[-1] and "4 more waves" in ctx.told[-1]
    assert 0.5 <= told_seconds(ctx) / ctx.elapsed() <= 2.0
    assert bars == [(6, [1] * 6)]


class Bar:
    """A progress bar that keeps its steps in ``steps``."""

    def __init__(self, steps: list):
        self.update = steps.append

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        return False


def test_local_workers_start_at_this_process_s_age_plus_the_engine_s_loading():
    """A local pool's workers import what this process imported: its age, as `ps` counts it (whole seconds),
    plus the engine's loading (0 off Linux, where /proc is missing); a serial run, threads or a cluster's running
    workers start nothing."""
    age = 0.0
    if sys.platform == "linux":
        ps = subprocess.run(["ps", "-o", "etimes=", "-p", str(os.getpid())], capture_output=True, text=True, check=True)
        age = float(ps.stdout)
    assert core_sweep.process_age() == pytest.approx(age, abs=1.5)
    for scheduler in (None, "processes"):
        assert core_sweep.startup_seconds(scheduler, 100.0) == pytest.approx(100.0 + age, abs=1.5)
    for scheduler in ("synchronous", "threads", "tcp://10.0.0.1:8786"):
        assert core_sweep.startup_seconds(scheduler, 100.0) == 0.0


def test_a_sweep_is_refused_from_its_timed_wave_before_the_rest_runs():
    """Tasks of 0.1 s under a 0.3 s budget: after two (the first two of the spread order), the estimate
    (0.2 s + 4 x 0.1 s) is over it, and the sweep stops there in one line, with the remaining four never run."""
    ran = []

    def nap(k):
        ran.append(k)
        time.sleep(0.1)

    tasks = [dask.delayed(nap)(k, dask_key_name=f"nap-{k}") for k in range(6)]
    with pytest.raises(SymmechError, match=r"estimated sweep time .* exceeds --max-time 0.3 s"):
        core_sweep.compute(tasks, "synchronous", ctx=Context(quiet=True, max_time=0.3))
    assert ran == core_sweep.spread(6)[:2] == [0, 4]


@pytest.mark.slow  # ~4 s: five runs, the answer, its two charts
def test_a_small_trolley_sweep_is_told_an_estimate_that_holds(tmp_path):
    """Five speeds of a short rigid helix, serial: the charts counted are the rigid model's two (comfort margin and
    peak reaction), the last estimate told is within 2x of the sweep's time, and summary.json records it."""
    raw = edited(RIGID, ("time.t_end", 1.0), ("time.steps", 50)) | {
        "sweep": {"x": {"field": "motion.speed_scale", "start": 0.5, "stop": 1.5, "num": 5}}}
    ctx = Told()
    core_sweep.run(raw, tmp_path / "out", ctx, scheduler="synchronous")
    assert any("up to 2 charts at" in m for m in ctx.told), ctx.told
    assert 0.5 <= told_seconds(ctx) / ctx.elapsed() <= 2.0, ctx.told
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["estimate"]["seconds"] == pytest.approx(told_seconds(ctx), rel=1e-2)  # the last told, recorded


def test_a_chain_sample_is_the_same_chain_on_the_run_s_path_with_its_share_of_the_work():
    """A 1200-mass chain with an initial state and a force at its far end: the sample of a share s has
    1200 s^(1/3) masses, never fewer than the run's path allows (above the JSON limit: no symbolic matrices,
    matrices.csv), its initial state and force cut to them (the force moved to the last mass), and its count
    model is s of the run's (the cubic term dominates) within 10%. An explicit mechanism and a chain with symbolic
    matrices have no sample."""
    n = 1200
    scene = pipeline.load(chain(n, initial={"q": [1e-3] * n, "duration": 0.1, "steps": 10},
                                forcing={"point": f"P{n}", "force": [1.0, 0.0, 0.0], "omega": [1.0, 2.0],
                                         "samples": 3}))
    full = smm_scene.estimate(scene.setup).seconds
    for share, masses in ((0.0, smm_scene.JSON_LIMIT + 1), (0.03, 373), (0.125, 600), (1.0, n)):
        small = smm_scene.sample(scene.setup, share)
        assert small.n == masses and len(small.scene["initial"]["q"]) == masses
        assert small.scene["forcing"]["point"] == f"P{masses}"
        if share:
            assert smm_scene.estimate(small).seconds / full == pytest.approx(share, rel=0.1)
    explicit = dataclasses.replace(scene.setup, scene=scene.setup.scene | {"chain": None})  # the same size
    assert smm_scene.sample(explicit, 0.5) is None
    assert smm_scene.sample(pipeline.load(chain(smm_scene.SYMBOLIC_LIMIT)).setup, 0.5) is None


@pytest.mark.slow  # ~4 s: timed samples of up to ~1 s, then the run three times
@pytest.mark.parametrize("off", [1e-3, 1e3])
def test_a_chain_estimate_holds_whatever_the_count_model_says(monkeypatch, off):
    """A 600-mass chain (~0.5 s of dense eigenproblems on one core) with the count model's seconds per flop a
    thousandth and a thousand times the calibrated: the estimate told is within 2x of the run's own time in the
    same process (the median of three), since the timed samples set the scale; the count estimate alone is more
    than 2x off (the test can fail)."""
    monkeypatch.setattr(smm_scene, "FLOP_SECONDS", smm_scene.FLOP_SECONDS * off)
    scene = pipeline.load(chain(600))
    count = scene.kind.estimate(scene.setup).seconds
    scene.run(Told())
    actual = statistics.median([scene.timing["run"], *(run_seconds(scene) for _ in range(2))])
    assert "timed samples" in scene.cost.what
    assert 0.5 <= scene.cost.seconds / actual <= 2.0, (scene.cost, actual)
    assert not 0.5 <= count / actual <= 2.0


def test_the_slowdown_is_the_wall_time_over_the_cpu_time_of_a_probe(monkeypatch):
    """A process given a third of a core (its CPU clock running at a third of the wall clock's rate) is slowed
    down 3x; the value is reused for PROBE_KEPT seconds, with no second probe (a clock that raises is not read).
    Both clocks are fakes driven by the probe's own reads (1 ms of CPU per read), so that the machine's load, which
    stretches the real wall clock between two reads, cannot move the answer."""
    wall = [100.0]

    def cpu_read() -> float:
        wall[0] += 3e-3
        return wall[0] / 3.0

    monkeypatch.setattr(sample, "_probed", [])
    monkeypatch.setattr(sample.time, "perf_counter", lambda: wall[0])
    monkeypatch.setattr(sample.time, "process_time", cpu_read)
    assert sample.slowdown() == pytest.approx(3.0, rel=1e-9)
    monkeypatch.setattr(sample.time, "process_time", lambda: 1 / 0)
    assert sample.slowdown() == pytest.approx(3.0, rel=1e-9)


def test_a_scene_with_no_smaller_run_is_estimated_at_the_share_of_a_core_now(monkeypatch):
    """A chain of 60 masses (its run is mostly its symbolic matrices: no sample) on a third of a core: the count
    model's idle-core seconds times 3, and the estimate says so."""
    monkeypatch.setattr(sample, "slowdown", lambda: 3.0)
    scene = pipeline.load(chain(smm_scene.SYMBOLIC_LIMIT))
    count = scene.kind.estimate(scene.setup)
    cost = sample.timed(scene.kind, scene.setup, count, max_time=1e9)
    assert cost.seconds == pytest.approx(3.0 * count.seconds, rel=1e-12) and "at 3x an idle core's time" in cost.what


def test_spread_order_is_a_permutation_whose_first_few_cover_the_range():
    """Van der Corput order: a permutation of 0 .. n - 1; its first two are the ends' halves, its first four the
    quarters (for 16: 0, 8, 4, 12), and for any n its first k leave no gap wider than 4 n / k + 1."""
    assert core_sweep.spread(16)[:4] == [0, 8, 4, 12]
    for n in (1, 2, 3, 7, 18, 25, 100):
        order = core_sweep.spread(n)
        assert sorted(order) == list(range(n))
        for k in range(2, n + 1):
            first = sorted(order[:k]) + [n]
            assert max(b - a for a, b in zip(first, first[1:])) <= 4 * n / k + 1
