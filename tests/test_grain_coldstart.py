"""Fast from the first second: engine `auto`, the one background build per cache, `symmech warm`,
and sweeps that compile once per machine.

The fast tests stand in for numba's cache with ``compiled.ENGINE.cold`` and a temporary lock folder; the slow one
compiles for real, once, into an empty ``NUMBA_CACHE_DIR`` in fresh processes (a CPU-minute or more).
"""
import csv
import fcntl
import json
import os
import re
import signal
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from symmech.cli import main
from symmech.core import engines, pipeline, sample
from symmech.numerics import build
from symmech.grain import motion_scene, sweep
from symmech.grain.motion_engine import driver as compiled, loop as compiled_loop

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "grain_default.toml"
POPEN = subprocess.Popen  # the real one: the fixture cold_cache replaces it to catch the builder


def scene_file(tmp_path: Path, duration: float, engine: str | None = None) -> Path:
    text = re.sub(r"(?m)^duration = .*$", f"duration = {duration}", SCENE.read_text())
    if engine:
        text = text.replace('mode = "accurate"', f'mode = "accurate"\nengine = "{engine}"')
    path = tmp_path / f"grain_{duration}_{engine}.toml"
    path.write_text(text)
    return path


@pytest.fixture
def cold_cache(tmp_path, monkeypatch):
    """numba's cache reported empty (and no build ahead of time), the build lock in a temporary folder, and no
    builder process started: returns the list of builder command lines that would have been started."""
    started = []
    monkeypatch.delenv("SYMMECH_BACKGROUND_BUILD", raising=False)  # tests/conftest.py's
    monkeypatch.setattr(compiled.ENGINE, "cold", lambda: True)
    monkeypatch.setattr(compiled.ENGINE, "ahead_of_time", lambda: None)
    monkeypatch.setattr(compiled.ENGINE, "cache_dir", lambda: tmp_path / "cache")
    monkeypatch.setattr(build.subprocess, "Popen", lambda args, **kw: started.append((args, kw)))
    monkeypatch.setattr(compiled.ENGINE, "started_builder", False)  # none by this process so far
    return started


def test_auto_on_a_cold_cache_answers_with_the_python_engine_and_starts_one_builder(tmp_path, cold_cache):
    out = tmp_path / "out"
    assert main(["run", str(scene_file(tmp_path, 0.05)), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["engine"] == "python" and "background" in summary["engine_reason"]
    assert "Python engine" in summary["estimate"]["what"] and summary["bounces"] >= 3
    (args, kw), = cold_cache  # one builder: detached in its own session, so Ctrl-C of the run does not reach it
    assert args[1:] == ["-m", "symmech", "warm", "--engine", "grain", "--background"]
    assert kw["start_new_session"] is True


def test_no_builder_with_background_builds_off(tmp_path, cold_cache, monkeypatch):
    """SYMMECH_BACKGROUND_BUILD=0 (CI jobs, containers): a cold `auto` run answers on the Python engine, starts
    no builder, and its summary says so."""
    monkeypatch.setenv("SYMMECH_BACKGROUND_BUILD", "0")
    out = tmp_path / "out"
    assert main(["run", str(scene_file(tmp_path, 0.05)), "--out", str(out), "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["engine"] == "python" and "no background build" in summary["engine_reason"]
    assert cold_cache == []


@pytest.fixture
def idle(monkeypatch):
    """Compiles estimated as on an idle core (their seconds as declared), whatever the load now."""
    monkeypatch.setattr(sample, "slowdown", lambda: 1.0)


def test_auto_compiles_first_when_the_python_engine_would_take_longer(tmp_path, cold_cache, idle):
    """1000 s of the default scene: ~1e5 impacts, ~1500 s on the Python loop against 80 s of compilation
    plus 1/50 of that: auto waits for the compile, as `compiled` does, and the estimate says so."""
    sc = pipeline.load(scene_file(tmp_path, 1000.0)).setup
    engine, why = motion_scene.choose_engine(sc)
    assert engine == "compiled" and "longer than compiling" in why
    cost = motion_scene.estimate(sc)
    python = motion_scene.estimate(replace(sc, numerics=replace(sc.numerics, engine="python")))
    assert cost.once == compiled.COLD_COMPILE_SECONDS
    assert cost.seconds == pytest.approx(python.seconds / motion_scene.COMPILED_SPEEDUP + cost.once, rel=1e-12)
    assert cold_cache == []  # nothing built in the background: this run compiles in the foreground


def test_explicit_engines_are_kept_whatever_the_cache(tmp_path, cold_cache):
    for engine in ("python", "compiled"):
        sc = pipeline.load(scene_file(tmp_path, 0.05, engine)).setup
        assert motion_scene.choose_engine(sc) == (engine, f'numerics.engine = "{engine}"')


def test_the_build_lock_admits_one_builder_and_dies_with_its_holder(tmp_path, cold_cache):
    """A second builder does not wait (``warm(wait=False)``) and a run starts none while the lock is held; a
    builder killed with SIGKILL leaves the lock free (flock: the OS releases it)."""
    lock = tmp_path / "cache" / compiled.ENGINE.lock_name
    lock.parent.mkdir()
    holder = POPEN([sys.executable, "-c", "import fcntl, sys, time; fh = open(sys.argv[1], 'a'); "
                               "fcntl.flock(fh, fcntl.LOCK_EX); print('held', flush=True); time.sleep(120)",
                               str(lock)], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline() == "held\n"
        assert compiled.ENGINE.warm(wait=False) is False
        assert compiled.ENGINE.warm_in_background() is False and cold_cache == []
    finally:
        holder.send_signal(signal.SIGKILL)
        holder.wait(timeout=30)
    with compiled.ENGINE.build_lock(wait=False) as mine:
        assert mine
    assert compiled.ENGINE.warm_in_background() is True and len(cold_cache) == 1


def test_waiting_for_a_cold_engine_builds_it_here_once_no_builder_works_on_it(tmp_path, cold_cache, monkeypatch):
    """``wait_warm`` polls while another process holds the build lock; once none does and the engine is still
    cold (no builder may start: tests/conftest.py's ``SYMMECH_BACKGROUND_BUILD=0``; the other build ended with
    its record refused), it builds in this process instead of waiting out its 1200 s."""
    monkeypatch.setenv("SYMMECH_BACKGROUND_BUILD", "0")
    built, polls = [], []
    monkeypatch.setattr(compiled.ENGINE, "cold", lambda: not built)
    monkeypatch.setattr(compiled.ENGINE, "warm", lambda: built.append("here"))
    lock = tmp_path / "cache" / compiled.ENGINE.lock_name
    lock.parent.mkdir()
    holder = POPEN([sys.executable, "-c", "import fcntl, sys, time; fh = open(sys.argv[1], 'a'); "
                               "fcntl.flock(fh, fcntl.LOCK_EX); print('held', flush=True); time.sleep(120)",
                               str(lock)], stdout=subprocess.PIPE, text=True)

    def poll(seconds):  # the other builder ends while this one waits, the cache still cold
        polls.append(seconds)
        assert len(polls) == 1, "waits on with no builder at work"
        holder.send_signal(signal.SIGKILL)
        holder.wait(timeout=30)

    # build's own clock only: subprocess's wait sleeps through the time module too (Python 3.13)
    monkeypatch.setattr(build, "time", SimpleNamespace(sleep=poll, monotonic=time.monotonic))
    try:
        assert holder.stdout.readline() == "held\n"
        assert compiled.ENGINE.wait_warm(1200.0) is True
    finally:
        holder.kill()
        holder.wait(timeout=30)
    assert polls == [0.5] and built == ["here"] and cold_cache == []


def test_the_background_builder_runs_at_the_lowest_priority(monkeypatch):
    niceness = []
    monkeypatch.setattr(os, "nice", niceness.append)
    monkeypatch.setattr(engines, "engines", dict)  # no engine: nothing compiles
    assert main(["warm", "--background"]) == 0 and niceness == [19]
    assert main(["warm", "--quiet"]) == 0 and niceness == [19]  # a warm the user asked for keeps its priority


def test_warm_help_names_the_cache_locations(capsys):
    with pytest.raises(SystemExit) as info:
        main(["warm", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert info.value.code == 0 and "NUMBA_CACHE_DIR" in text and "__pycache__" in text


@pytest.mark.slow
@pytest.mark.compiled_engine
def test_warm_on_a_built_cache_prints_its_location_and_compiles_nothing(capsys):
    misses = sum(compiled_loop.run.stats.cache_misses.values())
    assert main(["warm", "--engine", "grain"]) == 0
    captured = capsys.readouterr()
    assert f"cache: {compiled.ENGINE.cache_dir()}" in captured.out and "compiling" not in captured.err
    assert sum(compiled_loop.run.stats.cache_misses.values()) == misses and not compiled.ENGINE.cold()


def test_a_sweep_on_auto_is_estimated_on_the_compiled_engine_built_once(tmp_path, cold_cache, idle):
    """The sweep builds the engine before dispatch, so its grains run compiled: the estimate is the compiled
    one, with the compile counted once for all grains."""
    raw = {"kind": "grain", "duration": 0.1, "body": {"semi_axes": [1e-3, 1e-3, 1e-3], "density": 1200.0},
           "impact": {"law": "printed", "e": 0.5, "lambda": 1.0},
           "population": [{"name": "many", "count": 10}],
           "sweep": {"x": {"field": "vibration.frequency", "values": [20.0, 30.0]}}}
    p = sweep.plan(raw, pipeline.load(raw).resolved)
    assert sweep._compiled_needed(p)
    cost = sweep.estimate(p, workers=1)
    grain = pipeline.load(next(sweep.grains(p, 0, 0, 0))).setup
    one = motion_scene.estimate(replace(grain, numerics=replace(grain.numerics, engine="compiled")))
    assert one.once == compiled.COLD_COMPILE_SECONDS
    assert cost.seconds == pytest.approx(one.once + 20 * (one.seconds - one.once), rel=1e-12)
    shared = sweep.estimate(p, workers=2)  # the grains shared by two workers, the compile done once, here
    assert shared.seconds == pytest.approx(one.once + 10 * (one.seconds - one.once), rel=1e-12)
    raw["numerics"] = {"engine": "python"}
    assert not sweep._compiled_needed(sweep.plan(raw, pipeline.load(raw).resolved))


# --------------------------------------------------------------------------- real compiles (slow)


def _env(cache: Path) -> dict:
    """A fresh process's environment: the cache ``cache``, background builds as a user has them."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    env.pop("SYMMECH_BACKGROUND_BUILD", None)  # tests/conftest.py's
    return env


def _impact_times(out: Path) -> np.ndarray:
    lines = [line for line in (out / "impacts.csv").read_text().splitlines() if not line.startswith("#")]
    return np.array([float(row[0]) for row in list(csv.reader(lines))[1:]])


def _final_position(out: Path) -> np.ndarray:
    lines = [line for line in (out / "trajectory.csv").read_text().splitlines() if not line.startswith("#")]
    return np.array([float(x) for x in lines[-1].split(",")[1:4]])


SWEEP_ON_FRESH_WORKERS = """
import json, sys
import dask.distributed as distributed
from symmech.core import pipeline
from symmech.numerics import build
from symmech.grain import sweep
from symmech.grain.motion_engine import driver as compiled, loop as compiled_loop


def stats(which):  # cache misses or hits of the engine's entries: a grain (run), a population (run_many: the sweep's)
    return sum(sum(getattr(d.stats, which).values()) for d in (compiled_loop.run, compiled_loop.run_many))


raw = {"kind": "grain", "duration": 0.08, "body": {"semi_axes": [1e-3, 1e-3, 1e-3], "density": 1200.0},
       "vibration": {"amplitude": 1e-3, "frequency": 25.0}, "impact": {"law": "printed", "e": 0.5, "lambda": 1.0},
       "population": [{"name": "a", "count": 2, "vary": {"body.density": 0.1}}],
       "sweep": {"x": {"field": "vibration.frequency", "values": [20.0, 25.0, 30.0]}}}
p = sweep.plan(raw, pipeline.load(raw).resolved)
with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                              dashboard_address=None) as cluster:
    values = sweep.compute(p, scheduler=cluster.scheduler_address)[0]
    with distributed.Client(cluster.scheduler_address) as client:
        workers = client.run(lambda: [stats("cache_misses"), stats("cache_hits")])
print(json.dumps({"client": stats("cache_misses"), "workers": list(workers.values()),
                  "finite": bool(all(v[..., :2].size and abs(v[..., :2]).max() < 1 for v in values))}))
"""


def _builder_holds_the_lock(cache: Path, seconds: float = 60.0) -> bool:
    """Whether a builder takes the grain engine's build lock under ``cache`` within ``seconds``."""
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        for lock in cache.rglob(compiled.ENGINE.lock_name):  # numba's cache folder for the package, under cache
            with open(lock) as fh:
                try:
                    fcntl.flock(fh, fcntl.LOCK_EX | fcntl.LOCK_NB)
                except BlockingIOError:
                    return True
        time.sleep(0.1)
    return False


@pytest.mark.slow
def test_first_runs_and_a_sweep_on_fresh_worker_processes_compile_the_engine_once(tmp_path):
    """One cold compile on the machine, whoever asks. Two first runs at once on an empty cache both answer
    (Python engine) and start one builder between them. A sweep on two fresh worker processes, started while
    that builder compiles, waits for it (its client before dispatch) and no worker compiles: no cache miss in
    the client or either worker. `symmech warm` then finds the cache built and the engine built ahead of time
    (the builder did both), and a third run uses that build: same impacts, times to 1e-11 s and final position to 1e-7 relative (the documented agreement of
    the two engines, docs/scenes-grain.md)."""
    cache, scene = tmp_path / "cache", scene_file(tmp_path, 0.6)
    cmd = [sys.executable, "-m", "symmech", "run", str(scene), "--quiet", "--no-plots", "--out"]
    first = [subprocess.Popen([*cmd, str(tmp_path / f"run{k}")], env=_env(cache), stderr=subprocess.PIPE,
                              text=True) for k in (1, 2)]
    for proc in first:
        assert proc.wait(timeout=600) == 0, proc.stderr.read()
    engines = [json.loads((tmp_path / f"run{k}" / "summary.json").read_text())["engine"] for k in (1, 2)]
    assert engines == ["python", "python"]
    assert _builder_holds_the_lock(cache)
    sweep_run = subprocess.run([sys.executable, "-c", SWEEP_ON_FRESH_WORKERS], env=_env(cache), capture_output=True,
                               text=True, timeout=1800, cwd=tmp_path)
    assert sweep_run.returncode == 0, sweep_run.stderr
    counts = json.loads(sweep_run.stdout.splitlines()[-1])
    assert counts["client"] == 0 and counts["finite"]
    assert [misses for misses, _ in counts["workers"]] == [0, 0]
    assert sum(hits for _, hits in counts["workers"]) >= 1  # the grains ran compiled, loaded from the cache
    warm = subprocess.run([sys.executable, "-m", "symmech", "warm", "--engine", "grain"], env=_env(cache),
                          capture_output=True, text=True, timeout=1800)
    assert warm.returncode == 0 and str(cache) in warm.stdout, warm.stderr
    assert "compiling" not in warm.stderr and "building" not in warm.stderr  # the builder built both
    assert "built ahead of time: " in warm.stdout
    assert subprocess.run([*cmd, str(tmp_path / "run3")], env=_env(cache), timeout=600).returncode == 0
    third = json.loads((tmp_path / "run3" / "summary.json").read_text())
    assert third["engine"] == "compiled" and third["engine_reason"].endswith("built (ahead of time)")
    python, fast = _impact_times(tmp_path / "run1"), _impact_times(tmp_path / "run3")
    assert len(python) == len(fast) > 100 and np.abs(python - fast).max() <= 1e-11
    r_python, r_fast = _final_position(tmp_path / "run1"), _final_position(tmp_path / "run3")
    assert np.linalg.norm(r_fast - r_python) <= 1e-7 * np.linalg.norm(r_python)
    assert np.array_equal(_impact_times(tmp_path / "run2"), python)
