"""Bad sweep tables and an unreachable scheduler: every one refused before any
simulation, one line naming the field or the option, exit 2."""
import socket
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from badinput import DELETE, bundled, edited
from symmech.core import pipeline
from symmech.core.scene import SceneError, SymmechError
from symmech.grain import sweep

ROOT = Path(__file__).resolve().parents[1]


def axis(**fields):
    return {"field": "vibration.amplitude", **fields}


# the bundled separation sweep on a 3 x 3 plane of listed values, 3 grains per population
BASE = edited(bundled("grain_separation"), ("sweep.x", axis(values=[0.6e-3, 1.0e-3, 1.4e-3])),
              ("sweep.y", {"field": "vibration.frequency", "values": [18.0, 25.0, 32.0]}),
              ("population[0].count", 3), ("population[1].count", 3))


def edits(*pairs):
    return edited(BASE, *pairs)


CASES = [
    # the axes: values or start/stop/num, never both; log spacing needs positive ends
    ("log-start-zero", edits(("sweep.x", axis(start=0.0, stop=1e-3, num=3, log=True))), "sweep.x.start"),
    ("log-stop-negative", edits(("sweep.x", axis(start=1e-4, stop=-1e-3, num=3, log=True))), "sweep.x.stop"),
    ("log-with-values", edits(("sweep.x.log", True)), "sweep.x.log"),
    ("values-and-start", edits(("sweep.x.start", 0.0)), "sweep.x.start"),
    ("values-and-num", edits(("sweep.y.num", 3)), "sweep.y.num"),
    ("num-without-stop", edits(("sweep.x", axis(start=1e-4, num=3))), "sweep.x.stop"),
    ("start-stop-without-num", edits(("sweep.x", axis(start=1e-4, stop=1e-3))), "sweep.x.values"),
    ("num-points-at-one-value", edits(("sweep.x", axis(start=1e-3, stop=1e-3, num=4))), "sweep.x.stop"),
    ("repeated-values", edits(("sweep.y.values", [18.0, 25.0, 18.0])), "sweep.y.values"),
    ("num-zero", edits(("sweep.x", axis(start=1e-4, stop=1e-3, num=0))), "sweep.x.num"),
    ("values-empty", edits(("sweep.x.values", [])), "sweep.x.values"),
    ("values-not-numbers", edits(("sweep.x.values", ["1 mm"])), "sweep.x.values[0]"),
    ("field-not-sweepable", edits(("sweep.x.field", "body.density")), "sweep.x.field"),
    ("same-field-twice", edits(("sweep.y.field", "vibration.amplitude")), "sweep.y.field"),
    ("no-x", edits(("sweep.x", DELETE)), "sweep.x"),
    ("unknown-sweep-key", edits(("sweep.z", axis(values=[1e-3]))), "sweep.z"),
    # a swept value the grain scene refuses is named by the axis
    ("swept-value-out-of-range", edits(("sweep.x.values", [-1e-3, 1e-3])), "sweep.x"),
    ("swept-range-out-of-range", edits(("sweep.y", {"field": "vibration.frequency", "start": 10.0,
                                                   "stop": 1e9, "num": 3})), "sweep.y"),
    # populations: names, and the fields they set or vary
    ("same-name-twice", edits(("population[1].name", "crop")), "population[1].name"),
    ("set-list-element", edits(("population[0].set", {"body.semi_axes.x": 1e-3})),
     "population[0].set.body.semi_axes.x"),
    ("set-below-a-number", edits(("population[1].set", {"duration.x": 1.0})), "population[1].set.duration.x"),
    ("set-kind", edits(("population[0].set", {"kind": "impact"})), "population[0].set.kind"),
    ("set-the-sweep", edits(("population[0].set", {"sweep.x.field": "impact.mu"})), "population[0].set.sweep.x.field"),
    ("set-a-swept-field", edits(("population[1].set", {"vibration.amplitude": 2e-3})),
     "population[1].set.vibration.amplitude"),
    ("vary-a-swept-field", edits(("population[0].vary", {"vibration.frequency": 0.1})),
     "population[0].vary.vibration.frequency"),
    ("set-orientation-and-random", edits(("population[0].set", {"body.orientation": [0.0, 0.0, 0.0]})),
     "population[0].set.body.orientation"),
    ("set-unknown-field", edits(("population[0].set", {"body.colour": 1.0})), "population[0].set.body.colour"),
    ("set-value-out-of-range", edits(("population[1].set", {"body.semi_axes": [1e-3, 1e-3, 1e-3],
                                                           "body.density": -1.0})),
     "population[1].set.body.density"),
    ("vary-missing-field", edits(("population[1].vary", {"body.nothing": 0.1})), "population[1].vary.body.nothing"),
    ("vary-list-element", edits(("population[1].vary", {"body.semi_axes.x": 0.1})),
     "population[1].vary.body.semi_axes.x"),
    ("vary-text", edits(("population[0].vary", {"impact.law": 0.1})), "population[0].vary.impact.law"),
    ("vary-spread-too-large", edits(("population[0].vary", {"body.semi_axes": 0.95})),
     "population[0].vary.body.semi_axes"),
    ("set-path-not-dotted-name", edits(("population[0].set", {"body..density": 1.0})),
     "population[0].set.body..density"),
    ("count-zero", edits(("population[0].count", 0)), "population[0].count"),
    ("name-empty", edits(("population[0].name", "")), "population[0].name"),
    ("three-populations", edits(("population", BASE["population"] + [{"name": "chaff", "count": 1}])), "population"),
]


def assert_sweep_rejected(data: dict, field: str) -> SceneError:
    """Everything ``symmech sweep`` does before simulating (validation, plan, every grain) refuses ``data``
    with a one-line SceneError naming ``field``."""
    with pytest.raises(SymmechError) as info:
        sweep.validate(sweep.plan(data, pipeline.load(data).resolved))
    err = info.value
    assert "\n" not in str(err), str(err)
    assert isinstance(err, SceneError), f"not a field error: {err}"
    assert err.field == field, f"named {err.field!r}, expected {field!r}: {err}"
    return err


@pytest.mark.parametrize("data, field", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_bad_sweep_is_named(data, field):
    assert_sweep_rejected(data, field)


def test_the_bundled_sweep_and_its_log_spaced_variant_are_accepted():
    p = sweep.plan(BASE, pipeline.load(BASE).resolved)
    sweep.validate(p)
    assert p.names == ["crop", "weed"] and p.shape == (3, 3) and p.grain_runs == 54
    raw = edits(("sweep.x", axis(start=1e-4, stop=1e-2, num=3, log=True)))
    np.testing.assert_allclose(sweep.axis_values(pipeline.load(raw).resolved["sweep"]["x"]), [1e-4, 1e-3, 1e-2],
                               rtol=1e-14)


def test_messages_say_what_to_do():
    log = assert_sweep_rejected(CASES[0][1], "sweep.x.start")
    assert "log = true" in str(log) and "> 0" in str(log) and "got 0" in str(log)
    twice = assert_sweep_rejected(edits(("population[1].name", "crop")), "population[1].name")
    assert "'crop' is already the name of population[0]" in str(twice)
    element = assert_sweep_rejected(edits(("population[0].set", {"body.semi_axes.x": 1e-3})),
                                    "population[0].set.body.semi_axes.x")
    assert "body.semi_axes is [0.0035, 0.0016, 0.0014] in the scene, not a table" in str(element)
    assert str(assert_sweep_rejected(CASES[5][1], "sweep.x.stop")).endswith(": start and stop are required with num")
    assert str(assert_sweep_rejected(CASES[7][1], "sweep.x.stop")).endswith(": equals start (0.001): the 4 values "
                                                                            "would repeat")
    swept = assert_sweep_rejected(edits(("sweep.x.values", [-1e-3, 1e-3])), "sweep.x")
    assert "vibration.amplitude: -0.001 m is outside [0, 1] m" in str(swept)


def _sweep(tmp_path, scene: Path, *options, timeout=120) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "symmech", "sweep", str(scene), "--out", str(tmp_path / "sw"),
                           "--quiet", *options], capture_output=True, text=True, timeout=timeout)


def test_command_line_refuses_a_bad_sweep_in_one_line(tmp_path):
    scene = tmp_path / "bad.toml"
    scene.write_text((ROOT / "scenes" / "grain_separation.toml").read_text()
                     .replace("start = 0.6e-3", "log = true\nstart = 0.0"))
    proc = _sweep(tmp_path, scene)
    assert (proc.returncode, proc.stdout) == (2, ""), proc.stderr
    assert proc.stderr.startswith("symmech: error: scene field 'sweep.x.start': log = true")
    assert len(proc.stderr.splitlines()) == 1 and not (tmp_path / "sw").exists()


def _one_grain_sweep(tmp_path) -> Path:
    scene = tmp_path / "one.toml"
    scene.write_text('kind = "grain"\nduration = 0.02\n[body]\nsemi_axes = [1e-3, 1e-3, 1e-3]\ndensity = 1200.0\n'
                     '[vibration]\namplitude = 1e-3\nfrequency = 25.0\n'
                     '[impact]\nlaw = "printed"\ne = 0.0\nlambda = 1.0\n[numerics]\nengine = "python"\n'
                     '[sweep.x]\nfield = "vibration.amplitude"\nvalues = [1e-3]\n')
    return scene


def test_unreachable_scheduler_is_a_user_error(tmp_path):
    """A port bound but not listening refuses every connection: one line naming --scheduler, the address and
    what to check, exit 2, after the --connect-timeout given (the subprocess itself is bounded)."""
    with socket.socket() as held:
        held.bind(("127.0.0.1", 0))
        address = f"tcp://127.0.0.1:{held.getsockname()[1]}"
        proc = _sweep(tmp_path, _one_grain_sweep(tmp_path), "--scheduler", address, "--connect-timeout", "1",
                      timeout=90)
    assert (proc.returncode, proc.stdout) == (2, ""), proc.stderr
    assert len(proc.stderr.splitlines()) == 1, proc.stderr
    assert proc.stderr.startswith(f"symmech: error: --scheduler {address}: no dask scheduler answered within 1 s")
    assert "check that the scheduler is running" in proc.stderr and "--connect-timeout" in proc.stderr
    assert not (tmp_path / "sw").exists()


def test_scheduler_that_is_not_an_address_is_a_user_error(tmp_path):
    proc = _sweep(tmp_path, _one_grain_sweep(tmp_path), "--scheduler", "localhost", timeout=90)
    assert proc.returncode == 2 and len(proc.stderr.splitlines()) == 1, proc.stderr
    assert proc.stderr.startswith("symmech: error: --scheduler localhost: ")


@pytest.mark.parametrize("value", ["0", "-1", "nan", "inf", "soon"])
def test_connect_timeout_must_be_positive_seconds(tmp_path, value):
    proc = _sweep(tmp_path, _one_grain_sweep(tmp_path), "--scheduler", "tcp://127.0.0.1:1",
                  "--connect-timeout", value, timeout=60)
    assert proc.returncode == 2 and len(proc.stderr.splitlines()) == 1, proc.stderr
    assert "--connect-timeout" in proc.stderr
