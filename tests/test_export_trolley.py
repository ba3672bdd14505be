"""`symmech export fmu|c` of the elastic trolley, checked with FMPy against the native run (the elastic model's
engine: P0…P5, roller deflections, the report points' overloads).

Default tier: a short ride of the bundled helix (0.15 s, the Python engine as the reference), FMI 3 Model
Exchange and Co-Simulation and the C example program. Slow tier: the bundled elastic scenes whole, FMI 2 and 3,
ME and CS, and the C example program, on the compiled engine the export reads its frame table from."""
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
from fmpy.validation import validate_fmu  # noqa: E402

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="needs a C compiler")
SCENES = scenes_folder()
ELASTIC = sorted(p.stem for p in SCENES.glob("trolley_elastic_*.toml"))
TOLERANCE = 1e-7  # of each series' largest magnitude
P = [f"P{i}" for i in range(6)]


@pytest.fixture(scope="module")
def short_helix(tmp_path_factory):
    """The bundled helix over its first 0.15 s (outputs every 3 ms as bundled), without the modal study: its
    path and native run, once."""
    tmp_path = tmp_path_factory.mktemp("short_helix")
    doc = tomllib.loads((SCENES / "trolley_elastic_helix.toml").read_text(encoding="utf-8"))
    doc["time"] = {"t_end": 0.15, "steps": 50}
    doc["elastic"]["numerics"]["modal_samples"] = 0
    path = tmp_path / "short_helix.toml"
    path.write_text(toml_text(doc))
    with pytest.MonkeyPatch.context() as patch:  # the engine the export's run takes (tests/conftest.py)
        patch.setattr(elastic_scene, "engine", lambda setup, runs=1: ("python", "tests: the reference engine"))
        return path, _native(path)


def _native(path) -> dict:
    """The elastic model's run of the scene at ``path`` (the engine elastic_scene.engine picks)."""
    return elastic_scene.simulate(pipeline.load(path).setup.elastic)


def _simulate(fmu, t, names, rtol=1e-10):
    kwargs = {"solver": "CVode"} if "_me" in fmu.name else {}
    result = fmpy.simulate_fmu(str(fmu), stop_time=t[-1], output_interval=t[1] - t[0], output=names,
                               relative_tolerance=rtol, **kwargs)
    assert len(result) == len(t)
    np.testing.assert_allclose(result["time"], t, rtol=0, atol=1e-9 * t[-1])
    return np.column_stack([result[n] for n in names])


def _check_fmu(path, native, tmp_path, fmi: int, kind: str) -> np.ndarray:
    """Export, validate, simulate; P0…P5 within TOLERANCE of the native run's; the FMU's OUTPUTS returned."""
    fmu = tmp_path / f"elastic_{fmi}_{kind}.fmu"
    assert main(["export", "fmu", str(path), "--out", str(fmu), "--fmi", str(fmi), "--type", kind]) == 0
    assert validate_fmu(str(fmu)) == []
    got = _simulate(fmu, native["t"], P + OUTPUTS)
    assert deviation(got[:, :6], native["P"]) <= TOLERANCE
    return got[:, 6:]


# roller deflections and the mast tip's deflection and overload, against the native run's
OUTPUTS = [f"d{i}" for i in range(1, 6)] + [f"tip_e{k}" for k in (1, 2, 3)] + [f"tip_n{k}" for k in (1, 2, 3)]


def _native_outputs(native) -> np.ndarray:
    return np.column_stack([native["deflection"], native["probe_elastic"][:, 0], native["probe_overload"][:, 0]])


# CS (the FMU's Radau IIA) in the slow tier with every bundled elastic scene: the C model code is ME's
@pytest.mark.parametrize("kind", ["me", pytest.param("cs", marks=pytest.mark.slow)])
def test_short_elastic_ride_fmu_reproduces_the_native_run(short_helix, tmp_path, kind):
    path, native = short_helix
    got = _check_fmu(path, native, tmp_path, 3, kind)
    assert deviation(got, _native_outputs(native)) <= TOLERANCE


def _check_c_program(path, native, tmp_path):
    """Export the C folder, run its example program (Radau IIA, dense output): t, s and P0…P5 as the native
    run's."""
    folder = tmp_path / "helix_c"
    assert main(["export", "c", str(path), "--out", str(folder)]) == 0
    assert "elastic_assembly.c" in (folder / "Makefile").read_text()
    printed = subprocess.run([str(folder / "example")], check=True, capture_output=True, text=True).stdout
    rows = list(csv.reader(io.StringIO(printed)))
    assert rows[0] == ["t", "s", *P]
    got = np.array(rows[1:], dtype=float)
    np.testing.assert_allclose(got[:, 0], native["t"], rtol=0, atol=1e-12)
    assert np.abs(got[:, 1] - native["s"]).max() <= 1e-9 * native["s"].max()  # s(t): a spline in the C
    assert deviation(got[:, 2:], native["P"]) <= TOLERANCE


@pytest.mark.slow  # the default tier builds the same C model code into the ME FMU
def test_elastic_c_example_prints_the_native_reactions(short_helix, tmp_path):
    path, native = short_helix
    _check_c_program(path, native, tmp_path)


@pytest.mark.slow
@pytest.mark.compiled_elastic
@pytest.mark.xdist_group("test_elastic_compiled")
@pytest.mark.parametrize("name", ELASTIC)
def test_bundled_elastic_c_programs_print_the_native_reactions(name, tmp_path):
    """Every bundled elastic ride's C program prints the native run's reactions (within 1e-7). Its real-time
    factor (target <= 0.01 for the helix) and the export's time (target <= 30 s with the compile) are measured in
    benchmarks/bench_export.py, not asserted here: a CPU bound in a test fails on a slower machine, not on a
    slower program."""
    path = SCENES / f"{name}.toml"
    native = _native(path)
    assert native["engine"] == "compiled"
    _check_c_program(path, native, tmp_path)


TRACTION = [('speed = "3*t + 7*sin(t/2)"', 'traction = "100 - 10*v"\ninitial_speed = 3.0'),
            ("local_curvature = false", "local_curvature = false\ntraction = true")]
RIGID_ROLLERS = [("[elastic.rollers]", "[elastic.effects]\nrollers = false\n\n[elastic.rollers]")]


@pytest.mark.parametrize("edits", [RIGID_ROLLERS, TRACTION + RIGID_ROLLERS])
def test_uncovered_elastic_scenes_are_refused_in_one_line(edits, tmp_path, capsys):
    text = (SCENES / "trolley_elastic_helix.toml").read_text(encoding="utf-8")
    for old, new in edits:
        assert old in text
        text = text.replace(old, new)
    scene = tmp_path / "uncovered.toml"
    scene.write_text(text)
    assert main(["export", "fmu", str(scene), "--out", str(tmp_path / "x.fmu")]) == 2
    err = capsys.readouterr().err
    assert "elastic rollers" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "x.fmu").exists()


@pytest.mark.slow
@pytest.mark.compiled_elastic
@pytest.mark.xdist_group("test_elastic_compiled")
@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("kind", ["me", "cs"])
@pytest.mark.parametrize("name", ELASTIC)
def test_bundled_elastic_scene_fmu(name, fmi, kind, tmp_path):
    path = SCENES / f"{name}.toml"
    native = _native(path)
    assert native["engine"] == "compiled"
    got = _check_fmu(path, native, tmp_path, fmi, kind)
    assert deviation(got, _native_outputs(native)) <= TOLERANCE


@pytest.mark.slow  # a second native run of the short ride (the Python engine) and an FMU run
def test_tuned_roller_stiffness_matches_the_native_run_of_that_scene(short_helix, tmp_path):
    """The rollers' stiffnesses are tunable parameters: the FMU exported from the bundled values, set to twice
    them (and started from that scene's quasi-static state), reproduces the native run of the stiffer scene."""
    path, _ = short_helix
    stiffer = tmp_path / "stiffer.toml"
    doc = tomllib.loads(path.read_text(encoding="utf-8"))
    assert doc["elastic"]["rollers"]["stiffness"] == [1e7] * 5
    doc["elastic"]["rollers"]["stiffness"] = [2e7] * 5
    stiffer.write_text(toml_text(doc))
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(elastic_scene, "engine", lambda setup, runs=1: ("python", "tests: the reference engine"))
        native = _native(stiffer)
    fmu = tmp_path / "elastic_3_me.fmu"
    assert main(["export", "fmu", str(path), "--out", str(fmu)]) == 0
    names = list(pipeline.load(path).setup.elastic.system.inv.names)
    start = {f"elastic.rollers.stiffness[{r}]": 2e7 for r in range(1, 6)}
    start.update((name, float(native["q"][0, i])) for i, name in enumerate(names))
    result = fmpy.simulate_fmu(str(fmu), solver="CVode", relative_tolerance=1e-10, stop_time=native["t"][-1],
                               output_interval=native["t"][1] - native["t"][0], output=P, start_values=start)
    assert deviation(np.column_stack([result[n] for n in P]), native["P"]) <= TOLERANCE
