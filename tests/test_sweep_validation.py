"""Sweeps checked as a whole before any work: the axes resolved to the scene entries they set (no entry set
twice, whatever the spelling, alias or scale), both ends of a swept comfort envelope kept and ordered at every
point, the options (--out, --workers, --scheduler) refused first, and a plane of any size refused from counts
within 10 s and 200 MB. Each refusal is one line naming the field or option, its value and what is admissible;
on the command line exit 2."""
import copy
import math
import os
import subprocess
import sys
import time

import dask
import numpy as np
import pytest

from badinput import SCENES, bundled, edited
from symmech import cli
from symmech.core import pipeline, sweep as core_sweep
from symmech.core.context import Context
from symmech.core.scene import SceneError, SymmechError
from symmech.grain import sweep as grain_sweep
from symmech.trolley import sweep as trolley_sweep

# the bundled elastic helix, short (0.12 s on 24 steps, one Ritz function per plane, 3 modal samples)
TINY = edited(bundled("trolley_elastic_helix"), ("time.t_end", 0.12), ("time.steps", 24),
              ("elastic.beams[0].modes", 1), ("elastic.numerics.modal_samples", 3))
# the bundled separation sweep, 2 x 2 points of 2 grains per population
GRAIN = edited(bundled("grain_separation"), ("sweep.x", {"field": "vibration.amplitude", "values": [0.8e-3, 1e-3]}),
               ("sweep.y", {"field": "vibration.frequency", "values": [20.0, 25.0]}),
               ("population[0].count", 2), ("population[1].count", 2))


def swept(base, x, y=None):
    return copy.deepcopy(base) | {"sweep": {"x": x, **({"y": y} if y else {})}}


def trolley_plan(raw):
    """What `symmech sweep` checks of a trolley scene before any run; the plan."""
    p = trolley_sweep.plan(raw, pipeline.load(raw).resolved)
    trolley_sweep.validate(p)
    return p


def grain_plan(raw):
    p = grain_sweep.plan(raw, pipeline.load(raw).resolved)
    grain_sweep.validate(p)
    return p


def refused(check, raw, field: str) -> str:
    with pytest.raises(SymmechError) as info:
        check(raw)
    err = info.value
    assert "\n" not in str(err) and isinstance(err, SceneError), str(err)
    assert err.field == field, f"named {err.field!r}, expected {field!r}: {err}"
    return str(err)


TWICE = [  # two axes that reach one scene entry: (id, x, y, the entry as the message names it)
    ("field-and-its-scale", {"field": "elastic.rollers.stiffness", "values": [1e7, 2e7]},
     {"field": "elastic.rollers.stiffness_scale", "values": [1.0, 2.0]}, "elastic.rollers.stiffness"),
    ("scale-and-its-field", {"field": "elastic.rollers.damping_scale", "values": [1.0, 2.0]},
     {"field": "elastic.rollers.damping", "values": [1e3, 2e3]}, "elastic.rollers.damping"),
    ("one-index-two-ways", {"field": "elastic.beams[0].tip_mass", "values": [1.0, 2.0]},
     {"field": "elastic.beams[00].tip_mass", "values": [3.0, 4.0]}, "elastic.beams[0].tip_mass"),
    ("one-index-two-ways-scaled", {"field": "elastic.beams[000].ei_scale", "values": [1.0, 2.0]},
     {"field": "elastic.beams[0].ei_scale", "values": [0.5, 3.0]}, "elastic.beams[0].ei"),
]


@pytest.mark.parametrize("x, y, entry", [c[1:] for c in TWICE], ids=[c[0] for c in TWICE])
def test_two_axes_setting_one_entry_are_refused(x, y, entry):
    message = refused(trolley_plan, swept(TINY, x, y), "sweep.y.field")
    assert f"{y['field']} sets {entry}, which sweep.x.field (as {x['field']}) sets already" in message


def test_both_ends_of_one_envelope_compose_at_every_point():
    """lo along x and hi along y: point (i, j) has the envelope [x_i, y_j]; a bound swept alone keeps the
    scene's other end (the default envelope of n2 is [-1.5, 6] g, docs/scenes-trolley.md)."""
    p = trolley_plan(swept(TINY, {"field": "comfort.x1.lo", "values": [-3.0, -2.5]},
                           {"field": "comfort.x1.hi", "values": [2.0, 3.0, 4.0]}))
    for i, j in np.ndindex(2, 3):
        assert p.point(i, j)["comfort"]["x1"] == [[-3.0, -2.5][i], [2.0, 3.0, 4.0][j]]
    alone = trolley_plan(swept(TINY, {"field": "comfort.x2.hi", "values": [5.0, 7.0]}))
    assert [alone.point(i, 0)["comfort"]["x2"] for i in range(2)] == [[-1.5, 5.0], [-1.5, 7.0]]


def test_envelope_order_is_checked_at_every_point():
    """lo = 1 g and hi = 0.5 g each pass against the scene's other end (2 g, -2 g); together, at point
    (1, 1) only, they cross."""
    message = refused(trolley_plan, swept(TINY, {"field": "comfort.x3.lo", "values": [-3.0, 1.0]},
                                          {"field": "comfort.x3.hi", "values": [2.0, 0.5]}), "sweep.x")
    assert "comfort.x3 = [1, 0.5] g at point (1, 1) of the plane" in message and "lo < hi" in message


def test_a_value_inside_the_plane_is_checked_without_loading_every_point(monkeypatch):
    """A bad value in the middle of an axis is named by its axis, while the whole scene is loaded at the
    corners only (4 loads for a 5 x 3 plane, not 15)."""
    loads = []
    real = pipeline.load
    monkeypatch.setattr(pipeline, "load", lambda data: loads.append(1) or real(data))
    raw = swept(TINY, {"field": "elastic.beams[0].tip_mass", "values": [1.0, 2.0, 3.0, 4.0, 5.0]},
                {"field": "elastic.rollers.damping_scale", "values": [1.0, 2.0, 3.0]})
    p = trolley_sweep.plan(raw, real(raw).resolved)
    trolley_sweep.validate(p)
    assert len(loads) == 4
    bad = swept(TINY, {"field": "elastic.beams[0].tip_mass", "values": [1.0, -2.0, 3.0, 4.0, 5.0]},
                {"field": "elastic.rollers.damping_scale", "values": [1.0, 2.0, 3.0]})
    message = refused(trolley_plan, bad, "sweep.x")
    assert "elastic.beams[0].tip_mass = -2: elastic.beams[0].tip_mass: -2 kg is outside [0" in message


GRAIN_TWICE = [  # a population's entries that reach an entry the sweep, or another of its entries, sets
    ("set-the-swept-field-as-a-table", ("population[1].set", {"vibration": {"amplitude": 2e-3}}),
     "population[1].set.vibration", "vibration.amplitude"),
    ("set-one-field-two-ways", ("population[1].set", {"body.semi_axes": [1e-3, 1e-3, 1e-3],
                                                      "body": {"semi_axes": [2e-3, 1e-3, 1e-3]}}),
     "population[1].set.body", "body.semi_axes"),
    ("set-the-orientation-as-a-table", ("population[0].set", {"body": {"orientation": [0.0, 0.0, 0.0]}}),
     "population[0].random_orientation", "body.orientation"),
]


@pytest.mark.parametrize("edit, field, entry", [c[1:] for c in GRAIN_TWICE], ids=[c[0] for c in GRAIN_TWICE])
def test_grain_populations_set_no_entry_twice(edit, field, entry):
    assert f"sets {entry}, which " in refused(grain_plan, edited(GRAIN, edit), field)


PROBES = [  # axis values a sweep must refuse before any work
    ("nan-value", {"field": "elastic.rollers.stiffness", "values": [1e7, math.nan]}, "sweep.x.values[1]",
     "nan is not finite"),
    ("inf-stop", {"field": "elastic.rollers.stiffness", "start": 1e7, "stop": math.inf, "num": 3},
     "sweep.x.stop", "inf is not finite"),
    ("empty-values", {"field": "trolley.mass", "values": []}, "sweep.x.values", "expected a list of 1 to 200"),
    ("too-many-values", {"field": "trolley.mass", "start": 50.0, "stop": 150.0, "num": 201}, "sweep.x.num",
     "201 is outside [1, 200]"),
    ("duplicate-values", {"field": "trolley.mass", "values": [50.0, 80.0, 50.0]}, "sweep.x.values",
     "50 repeats"),
    ("minus-zero-repeats-zero", {"field": "elastic.beams[0].tip_mass", "values": [0.0, -0.0]}, "sweep.x.values",
     "0 repeats"),
]


@pytest.mark.parametrize("x, field, words", [c[1:] for c in PROBES], ids=[c[0] for c in PROBES])
def test_bad_axis_values_are_named(x, field, words):
    assert words in refused(trolley_plan, swept(TINY, x), field)


def test_grain_axis_of_another_impact_law_is_named_by_its_axis():
    """`impact.e` belongs to the printed law; the bundled scene's law is coulomb."""
    message = refused(grain_plan, edited(GRAIN, ("sweep.y", {"field": "impact.e", "values": [0.3, 0.5]})), "sweep.y")
    assert "impact.e" in message


def test_tasks_past_the_deadline_stop_the_sweep():
    """Tasks that end past --max-time: the sweep stops there, in one line naming the budget, and writes nothing;
    a task that starts past the deadline has no time left."""
    ctx = Context(quiet=True, max_time=0.3)
    tasks = [dask.delayed(time.sleep)(0.2, dask_key_name=f"nap-{k}") for k in range(2)]  # two: no estimate
    with pytest.raises(SymmechError, match=r"over the time budget --max-time 0.3 s \(2 sweep tasks\)"):
        core_sweep.compute(tasks, "synchronous", ctx=ctx)
    point = core_sweep.point_context(time.time() - 1.0)
    assert (point.max_time, point.quiet, point.sampled) == (0.0, True, False)  # the sweep estimated its points


@pytest.mark.parametrize("workers", [-1, 0, 257])
def test_workers_out_of_range_are_refused_first(tmp_path, capsys, workers):
    scene = tmp_path / "never-read.toml"  # the options are refused before the scene is read
    assert cli.main(["sweep", str(scene), "--out", str(tmp_path / "o"), "--workers", str(workers)]) == 2
    err = capsys.readouterr().err
    assert err == f"symmech: error: --workers {workers} is outside [1, 256]: the number of local worker processes\n"


def _sweep(args, timeout, env=None):
    started = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "symmech", "sweep", *map(str, args)], capture_output=True,
                          text=True, timeout=timeout, env=env)
    return proc, time.perf_counter() - started


def _toml(tmp_path, sweep_table: str):
    """The bundled elastic sweep with its [sweep] tables replaced by ``sweep_table``."""
    text = (SCENES / "trolley_elastic_sweep.toml").read_text(encoding="utf-8")
    scene = tmp_path / "sweep.toml"
    scene.write_text(text.split("[sweep.x]")[0] + sweep_table)
    return scene


def test_command_line_refuses_an_alias_in_one_line(tmp_path):
    scene = _toml(tmp_path, '[sweep.x]\nfield = "elastic.rollers.stiffness"\nvalues = [1e7, 2e7]\n'
                            '[sweep.y]\nfield = "elastic.rollers.stiffness_scale"\nvalues = [1.0, 2.0]\n')
    proc, _ = _sweep([scene, "--out", tmp_path / "o"], timeout=120)
    assert (proc.returncode, proc.stdout) == (2, ""), proc.stderr
    assert proc.stderr.startswith("symmech: error: scene field 'sweep.y.field': elastic.rollers.stiffness_scale "
                                  "sets elastic.rollers.stiffness") and len(proc.stderr.splitlines()) == 1
    assert not (tmp_path / "o").exists()


def test_command_line_refuses_out_naming_a_file_before_the_scene(tmp_path):
    (tmp_path / "taken").write_text("not a folder")
    proc, seconds = _sweep([tmp_path / "no-such-scene.toml", "--out", tmp_path / "taken"], timeout=60)
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr == f"symmech: error: --out {tmp_path / 'taken'} is a file, not a folder; choose a folder\n"
    assert (tmp_path / "taken").read_text() == "not a folder"


def test_a_200_by_200_plane_is_refused_from_counts_within_10_cpu_s_and_200_MB(tmp_path):
    """40000 points of the bundled elastic sweep with --max-time 10: refused from the counts alone (no point
    scene built but its corners, no engine built, no point run), in one line, under 10 s of CPU time (wall
    time on a machine shared by other jobs: under 60 s; ~3.5 s on 2 idle cores) and 200 MB of memory (the
    process's peak resident set). It took 0.12 s of CPU per point, over 80 min, before."""
    scene = _toml(tmp_path, '[sweep.x]\nfield = "motion.speed_scale"\nstart = 0.5\nstop = 1.5\nnum = 200\n'
                            '[sweep.y]\nfield = "elastic.rollers.stiffness"\nstart = 3e6\nstop = 3e7\nnum = 200\n'
                            'log = true\n')
    # the peak of this process image: VmHWM (ru_maxrss keeps the peak of the forking pytest worker across exec)
    code = ("import re, resource, sys\nfrom symmech import cli\nrc = cli.main(sys.argv[1:])\n"
            "use = resource.getrusage(resource.RUSAGE_SELF)\n"
            "peak = re.search(r'VmHWM:\\s+(\\d+) kB', open('/proc/self/status').read()).group(1)\n"
            "print(use.ru_utime + use.ru_stime, peak, file=sys.stderr)\nsys.exit(rc)\n")
    started = time.perf_counter()
    proc = subprocess.run([sys.executable, "-c", code, "sweep", str(scene), "--out", str(tmp_path / "o"),
                           "--max-time", "10"], capture_output=True, text=True, timeout=60)
    seconds = time.perf_counter() - started
    *message, usage = proc.stderr.splitlines()
    cpu, peak_kb = usage.split()
    assert proc.returncode == 2 and len(message) == 1, proc.stderr
    assert message[0].startswith("symmech: error: estimated sweep time ")
    assert "(from counts: 40000 points at ~" in message[0] and "exceeds --max-time 10 s" in message[0]
    assert float(cpu) < 10.0 and seconds < 60.0 and int(peak_kb) < 200_000, (cpu, seconds, peak_kb)
    assert not (tmp_path / "o").exists()


def test_an_unreachable_scheduler_is_reported_before_any_engine_is_built(tmp_path):
    """On a fresh install (an empty numba cache: the elastic engine would compile for minutes first), an
    unreachable --scheduler is the first thing reported: within its timeout and the start-up, exit 2."""
    import socket

    scene = _toml(tmp_path, '[sweep.x]\nfield = "motion.speed_scale"\nvalues = [1.0, 1.2]\n')
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "empty-cache")}
    with socket.socket() as held:
        held.bind(("127.0.0.1", 0))
        address = f"tcp://127.0.0.1:{held.getsockname()[1]}"
        proc, seconds = _sweep([scene, "--out", tmp_path / "o", "--scheduler", address, "--connect-timeout", "1"],
                               timeout=120, env=env)
    assert proc.returncode == 2 and len(proc.stderr.splitlines()) == 1, proc.stderr
    assert proc.stderr.startswith(f"symmech: error: --scheduler {address}: no dask scheduler answered within 1 s")
    assert seconds < 30.0, seconds
    assert not (tmp_path / "empty-cache").exists() or not any((tmp_path / "empty-cache").rglob("*.nbc"))
