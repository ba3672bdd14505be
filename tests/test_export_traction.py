"""`symmech export fmu|c` of the elastic trolley under traction (states s and V0, the input traction_force),
checked with FMPy against the native compiled traction run.

No bundled scene has traction: the tests ride a traction variant of the bundled helix (P0 = 100 - 10 v N from
3 m/s), written here. All in the slow tier: one export derives the assembly (sympy), compiles it and runs the
native scene (~8 s on 2 shared cores), far beyond the default tier's budget per test; the default tier keeps the
refusals (tests/test_export_trolley.py).
"""
from __future__ import annotations

import csv
import io
import shutil
import subprocess
import tomllib

import numpy as np
import pytest

from fuzzscenes import toml_text
from symmech.cli import main
from symmech.core import pipeline
from symmech.core.scene import scenes_folder
from symmech.export.model import deviation
from symmech.trolley.elastic import scene as elastic_scene

fmpy = pytest.importorskip("fmpy")
from fmpy import read_model_description  # noqa: E402
from fmpy.validation import validate_fmu  # noqa: E402

pytestmark = [pytest.mark.skipif(shutil.which("cc") is None, reason="needs a C compiler"), pytest.mark.slow,
              pytest.mark.compiled_elastic, pytest.mark.xdist_group("test_elastic_compiled")]
SCENES = scenes_folder()
TOLERANCE = 1e-7  # of each series' largest magnitude
MOTION = [f"P{i}" for i in range(6)] + ["s", "V0"]
# roller deflections and the mast tip's deflection and overload
OUTPUTS = [f"d{i}" for i in range(1, 6)] + [f"tip_e{k}" for k in (1, 2, 3)] + [f"tip_n{k}" for k in (1, 2, 3)]
LAW = "100 - 10*v"  # N, v the speed [m/s]
EXTRA = 50.0  # N: the input's force in the input test


def traction_helix(folder, t_end: float, steps: int, law: str = LAW, name: str = "traction_helix"):
    """The bundled helix under the traction ``law`` from 3 m/s over t_end [s] in ``steps``, without the modal
    study: its path, ``name``.toml in ``folder``."""
    doc = tomllib.loads((SCENES / "trolley_elastic_helix.toml").read_text(encoding="utf-8"))
    doc["motion"] = {"traction": law, "initial_speed": 3.0}
    doc["effects"]["traction"] = True
    doc["time"] = {"t_end": t_end, "steps": steps}
    doc["elastic"]["numerics"]["modal_samples"] = 0
    path = folder / f"{name}.toml"
    path.write_text(toml_text(doc))
    return path


def _native(path) -> dict:
    """The compiled engine's traction run of the scene at ``path``, its coordinates' absolute tolerance 1e-14 m
    (the scene's 1e-12 m alone leaves P1…P5 up to ~9e-8 of their scale off a tighter run: the roller deflections
    are ~10 µm, and their forces 1e7 N/m times them)."""
    run = elastic_scene.simulate(pipeline.load(path).setup.elastic, atol_q=1e-14)
    assert run["engine"] == "compiled"
    return run


def _series(run: dict) -> np.ndarray:
    return np.column_stack([run["P"], run["s"], run["V0"]])


def _simulate(fmu, t, names, start_values=None):
    kwargs = {"solver": "CVode"} if "_me" in fmu.name else {}
    result = fmpy.simulate_fmu(str(fmu), stop_time=t[-1], output_interval=t[1] - t[0], output=names,
                               relative_tolerance=1e-10, start_values=start_values or {}, **kwargs)
    assert len(result) == len(t)
    np.testing.assert_allclose(result["time"], t, rtol=0, atol=1e-9 * t[-1])
    return np.column_stack([result[n] for n in names])


def _export(path, tmp_path, fmi: int, kind: str):
    fmu = tmp_path / f"traction_{fmi}_{kind}.fmu"
    assert main(["export", "fmu", str(path), "--out", str(fmu), "--fmi", str(fmi), "--type", kind]) == 0
    assert validate_fmu(str(fmu)) == []
    return fmu


@pytest.fixture(scope="module")
def ride(tmp_path_factory):
    """The traction helix over the bundled helix's 3 s in 1000 steps and its native run, once."""
    path = traction_helix(tmp_path_factory.mktemp("traction"), 3.0, 1000)
    return path, _native(path)


@pytest.fixture(scope="module")
def short_ride(tmp_path_factory):
    """The traction helix over 0.15 s in 50 steps (its folder, path and native run), once."""
    folder = tmp_path_factory.mktemp("short_traction")
    path = traction_helix(folder, 0.15, 50)
    return folder, path, _native(path)


@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("kind", ["me", "cs"])
def test_traction_fmu_reproduces_the_native_traction_run(ride, tmp_path, fmi, kind):
    path, native = ride
    fmu = _export(path, tmp_path, fmi, kind)
    got = _simulate(fmu, native["t"], MOTION + OUTPUTS)
    assert deviation(got[:, :8], _series(native)) <= TOLERANCE
    outputs = np.column_stack([native["deflection"], native["probe_elastic"][:, 0], native["probe_overload"][:, 0]])
    assert deviation(got[:, 8:], outputs) <= TOLERANCE


def test_traction_fmu_declares_its_input_and_motion_states(short_ride, tmp_path):
    """traction_force is a continuous input in N starting at 0; s, V0 are states with V0 = der(s) and der(V0)
    its derivative; every variable has a unit and a description."""
    _, path, native = short_ride
    md = read_model_description(str(_export(path, tmp_path, 3, "me")))
    by_name = {v.name: v for v in md.modelVariables}
    force = by_name["traction_force"]
    assert (force.causality, force.variability, force.unit, float(force.start)) == ("input", "continuous", "N", 0.0)
    derivative_of = {v.name: v.derivative.name for v in md.modelVariables if v.derivative is not None}
    assert derivative_of["V0"] == "s" and derivative_of["der(V0)"] == "V0"
    assert [float(by_name[n].start) for n in ("s", "V0")] == [native["s"][0], native["V0"][0]] == [0.0, 3.0]
    assert (by_name["s"].unit, by_name["V0"].unit, by_name["der(V0)"].unit) == ("m", "m/s", "m/s^2")
    assert all(v.description and v.unit for v in md.modelVariables)
    assert {d.variable.name for d in md.derivatives} >= {"V0", "der(V0)"}


@pytest.mark.parametrize("kind", ["me", "cs"])
def test_traction_force_input_adds_to_the_scene_law(short_ride, tmp_path, kind):
    """The FMU of the law 100 - 10 v with the input at 50 N rides as the native run of the law 150 - 10 v (from
    that run's start state, quasi-static under its larger traction); without the input it does not."""
    folder, path, _ = short_ride
    stronger = traction_helix(folder, 0.15, 50, f"{100 + EXTRA:g} - 10*v", "stronger")
    native = _native(stronger)
    fmu = _export(path, tmp_path, 3, kind)
    names = list(pipeline.load(stronger).setup.elastic.system.inv.names)
    start = {name: float(native["q"][0, i]) for i, name in enumerate(names)}
    got = _simulate(fmu, native["t"], MOTION, start | {"traction_force": EXTRA})
    assert deviation(got, _series(native)) <= TOLERANCE
    assert deviation(_simulate(fmu, native["t"], MOTION, start), _series(native)) > 1e-2


def test_traction_c_example_prints_the_native_run(short_ride, tmp_path):
    """The C example program (Radau IIA, dense output) prints t, s, V0 and P0…P5 as the native run."""
    _, path, native = short_ride
    folder = tmp_path / "traction_c"
    assert main(["export", "c", str(path), "--out", str(folder)]) == 0
    printed = subprocess.run([str(folder / "example")], check=True, capture_output=True, text=True).stdout
    rows = list(csv.reader(io.StringIO(printed)))
    assert rows[0] == ["t", "s", "V0", *MOTION[:6]]
    got = np.array(rows[1:], dtype=float)
    np.testing.assert_allclose(got[:, 0], native["t"], rtol=0, atol=1e-12)
    assert deviation(got[:, 1:], np.column_stack([native["s"], native["V0"], native["P"]])) <= TOLERANCE
