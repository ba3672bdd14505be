"""`symmech export fmu|c` of mechanism scenes, checked with FMPy (a client no one here wrote) against the
native run (`symmech run`'s free_response table, from the exact modal solution of numeric.free_response).

Default tier: one small FMU (rotor boom, FMI 3, Model Exchange), the C example program, the inputs against a
closed form, the refusals. Slow tier: every bundled mechanism scene, FMI 2 and 3, ME and CS."""
from __future__ import annotations

import csv
import io
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from symmech.cli import main
from symmech.core import emit, integrity, pipeline
from symmech.core.context import Context
from symmech.core.scene import read_toml, scenes_folder
from symmech.export import build, description, model
from symmech.export.model import deviation
from symmech.smm import numeric

fmpy = pytest.importorskip("fmpy")
from fmpy.validation import validate_fmu  # noqa: E402

sys.path.insert(0, str(Path(__file__).parent))
from fmpy_cvode import cvode  # noqa: E402

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="needs a C compiler")
SCENES = scenes_folder()
MECHANISMS = sorted(p.stem for p in SCENES.glob("smm_*.toml"))
TOLERANCE = 1e-7  # of each series' largest magnitude
def _scene_with_initial(name: str, tmp_path):
    """The bundled scene, with a free response from a small initial deflection when it has none."""
    path = SCENES / f"{name}.toml"
    text, data = path.read_text(), read_toml(path)
    if "initial" not in data:
        n = len(data["coordinates"])
        text += f"\n[initial]\nq = [{', '.join(['0.001'] * n)}]\nduration = 1.0\nsteps = 500\n"
        path = tmp_path / f"{name}.toml"
        path.write_text(text)
    return path


def _native(path) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """Times, coordinates (rows) and coordinate names of `symmech run`'s free_response."""
    scene = pipeline.load(path)
    table = scene.kind.run(scene.setup, Context(quiet=True)).tables["free_response"]
    return table.data[:, 0], table.data[:, 1:], [c.name for c in table.columns[1:]]


@pytest.fixture(scope="module")
def rotor_boom():
    """The rotor boom's export model (its native run included) and its native free response, once."""
    path = SCENES / "smm_rotor_boom.toml"
    return model.load(path), _native(path)


def _simulate(fmu, t, names, start_values=None, rtol: float | None = 1e-10):
    """FMPy's run of ``fmu`` at the native times ``t`` [s] (rtol None: the FMU's DefaultExperiment tolerance)."""
    kwargs = {"solver": "CVode"} if "_me" in fmu.name else {}
    result = fmpy.simulate_fmu(str(fmu), stop_time=t[-1], output_interval=t[1] - t[0], output=names,
                               start_values=start_values or {}, relative_tolerance=rtol, **kwargs)
    assert len(result) == len(t)
    np.testing.assert_allclose(result["time"], t, rtol=0, atol=1e-9 * t[-1])
    return np.column_stack([result[n] for n in names])


def _check_fmu(path, tmp_path, fmi: int, kind: str, rtol: float | None = 1e-10,
               tolerance: float = TOLERANCE) -> None:
    """Export, validate and simulate at the importer's relative tolerance ``rtol``; the deviation from the native
    run within ``tolerance`` of each series' largest magnitude."""
    fmu = tmp_path / f"model_{fmi}_{kind}.fmu"
    assert main(["export", "fmu", str(path), "--out", str(fmu), "--fmi", str(fmi), "--type", kind]) == 0
    assert validate_fmu(str(fmu)) == []
    t, q, names = _native(path)
    assert deviation(_simulate(fmu, t, names, rtol=rtol), q) <= tolerance


def test_rotor_boom_fmu_validates_and_reproduces_the_native_run(tmp_path):
    _check_fmu(SCENES / "smm_rotor_boom.toml", tmp_path, 3, "me")


def test_co_simulation_fmu_steps_with_the_native_accuracy(rotor_boom, tmp_path):
    """DOP853 inside the FMU at the importer's tolerance 1e-10: far closer than CVode's Model Exchange run."""
    exported, (t, q, names) = rotor_boom
    fmu = build.fmu(exported, tmp_path / "rb_cs.fmu", 2, "cs")
    assert validate_fmu(str(fmu)) == []
    assert fmpy.read_model_description(str(fmu)).defaultExperiment.tolerance is None  # its DOP853's default
    got = _simulate(fmu, t, names)
    assert deviation(got, q) <= 1e-9


@pytest.mark.slow  # every bundled mechanism, FMI 2 and 3, ME and CS (~1 min)
@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("kind", ["me", "cs"])
@pytest.mark.parametrize("name", MECHANISMS)
def test_every_mechanism_fmu(name, fmi, kind, tmp_path):
    """CVode's global error at rtol 1e-10 reaches 1.9e-7 on the excavator and 8.2e-7 on the spatial boom (10 s,
    2000 output steps), 2e-9 and 1.3e-8 on the others; at rtol 1e-12 it is 4e-9 and 1.5e-8 (it falls with rtol:
    the FMU's equations are the native ones). Model Exchange is checked at the FMU's DefaultExperiment tolerance
    (rtol 1e-12, which FMPy takes when not given one) within the 1e-7 target, Co-Simulation (DOP853 inside) at
    1e-10 within 1e-9."""
    rtol, tolerance = (None, TOLERANCE) if kind == "me" else (1e-10, 1e-9)
    _check_fmu(_scene_with_initial(name, tmp_path), tmp_path, fmi, kind, rtol, tolerance)


@pytest.mark.slow  # an export and two CVode runs a scene (~2.5 s of CPU each)
@pytest.mark.parametrize("name", MECHANISMS)
def test_model_exchange_error_is_cvodes_own(name, tmp_path, monkeypatch):
    """At rtol 1e-10 the ME run misses 1e-7 on the undamped excavator and spatial boom (1.9e-7, 8.2e-7: CVode's
    BDF error, growing with the periods run; docs/export.md). The FMU adds nothing to it: FMPy's CVode is never
    reset (the FMU signals no event) and the FMU's run is the same CVode driver's on the native y' = A y (the
    assembled matrices, no FMU) within 1e-8 (at most 2.2e-9 measured)."""
    path = _scene_with_initial(name, tmp_path)
    fmu = tmp_path / "model_3_me.fmu"
    assert main(["export", "fmu", str(path), "--out", str(fmu)]) == 0
    resets = []
    reset = fmpy.sundials.CVodeSolver.reset
    monkeypatch.setattr(fmpy.sundials.CVodeSolver, "reset", lambda solver, time: resets.append(time) or
                        reset(solver, time))
    t, _, names = _native(path)
    got = _simulate(fmu, t, names)
    assert resets == []
    setup = pipeline.load(path).setup
    m = numeric.solve_equilibrium(setup.m)[0] if setup.scene["equilibrium"]["solve"] else setup.m
    num = numeric.assemble(m)
    a, b, c = (x.toarray() for x in (num.a, num.b, num.c))
    n = len(names)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(a, c), -np.linalg.solve(a, b)]])
    states = [d.variable.derivative for d in fmpy.read_model_description(str(fmu)).derivatives]  # (q, q')
    y0, nominals = (np.array([float(getattr(v, k)) for v in states]) for k in ("start", "nominal"))
    reference, _ = cvode(A, y0, nominals, t, 1e-10)
    assert deviation(got, reference[:, :n]) <= 1e-8


def test_model_description_names_units_and_causality(tmp_path):
    fmu = tmp_path / "dp.fmu"
    assert main(["export", "fmu", str(SCENES / "smm_double_pendulum.toml"), "--out", str(fmu), "--fmi", "2"]) == 0
    md = fmpy.read_model_description(str(fmu))
    by_name = {v.name: v for v in md.modelVariables}
    assert (by_name["phi1"].causality, by_name["phi1"].unit, by_name["der(phi1)"].derivative.name) == \
        ("output", "rad", "phi1")
    assert by_name["der(phi1,2)"].derivative.name == "der(phi1)" and by_name["der(phi1,2)"].unit == "rad/s^2"
    assert (by_name["Q_phi2"].causality, by_name["Q_phi2"].unit, float(by_name["Q_phi2"].start)) == \
        ("input", "N m", 0.0)
    assert (by_name["l1"].causality, by_name["l1"].variability, float(by_name["l1"].start)) == \
        ("parameter", "tunable", 1.0)
    assert float(md.defaultExperiment.tolerance) == 1e-12  # CVode's rtol that meets the 1e-7 target (slow tests)
    units = {u.name: u.baseUnit for u in md.unitDefinitions}
    assert (units["N m"].kg, units["N m"].m, units["N m"].s) == (1, 2, -2)
    assert (units["rad/s^2"].rad, units["rad/s^2"].s) == (1, -2)


@pytest.mark.parametrize("unit, exponents", [
    ("N m", {"kg": 1, "m": 2, "s": -2}), ("m/s^2", {"m": 1, "s": -2}), ("kg m^2", {"kg": 1, "m": 2}),
    ("N s/m", {"kg": 1, "s": -1}), ("1/s^2", {"s": -2}), ("1", {}), ("furlong", None)])
def test_base_units(unit, exponents):
    assert description.base_units(unit) == exponents


def test_constant_input_and_a_changed_parameter_against_the_closed_form(rotor_boom, tmp_path):
    """A constant generalized force Q moves the rest state to q_s = c^-1 Q: q(t) = q_s + the free response from
    (q0 - q_s, v0), computed from the native matrices; with the rope stiffness c1 changed through the FMU."""
    exported, (t, _, names) = rotor_boom
    fmu = build.fmu(exported, tmp_path / "rb_me.fmu", 3, "me")
    Q = np.array([2.0e5, -4.0e4])
    changed = {"c1": 3.0e7}  # the scene has 4e7 N/m
    data = read_toml(SCENES / "smm_rotor_boom.toml")
    data["parameters"]["c1"]["value"] = changed["c1"]
    m = pipeline.load(data).setup.m
    num = numeric.assemble(m)
    a, b, c = (x.toarray() for x in (num.a, num.b, num.c))
    q_s = np.linalg.solve(c, Q)
    q0 = np.array([v.start for v in exported.variables if v.name in names])
    expected = q_s + numeric.free_response(a, b, c, q0 - q_s, np.zeros(2), t)
    got = _simulate(fmu, t, names, {"Q_" + names[0]: Q[0], "Q_" + names[1]: Q[1], **changed})
    assert deviation(got, expected) <= TOLERANCE


def test_export_c_from_the_command_line_to_a_relative_folder(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["export", "c", str(SCENES / "smm_double_pendulum.toml"), "--out", "dp_c"]) == 0
    assert capsys.readouterr().out == f"wrote {tmp_path / 'dp_c'}\n"
    printed = subprocess.run([str(tmp_path / "dp_c" / "example")], check=True, capture_output=True, text=True)
    rows = printed.stdout.split()  # no [initial]: the start state (rest) over 1 s in 100 steps
    assert rows[0] == "t,phi1,phi2" and len(rows) == 102 and rows[-1] == "1,0,0"


def test_exported_c_is_the_checked_generated_module(rotor_boom):
    """The export renders the scene's module with the codegen emitter: for a bundled scene, the body of the
    integrity-checked generated/<name>.c."""
    exported, _ = rotor_boom
    generated = emit.default_directory() / f"{exported.identifier}.c"
    assert integrity.split(exported.c_source)[1] == integrity.split(generated.read_text())[1]
    assert integrity.problem(generated) is None


def test_c_example_prints_the_native_table(rotor_boom, tmp_path):
    exported, (t, q, names) = rotor_boom
    build.c_folder(exported, tmp_path / "rotor_boom_c")  # an earlier export is replaced
    folder = build.c_folder(exported, tmp_path / "rotor_boom_c")
    assert {"Makefile", "model.h", "symmech_model.h", "smm_rotor_boom.c", "example.c"} <= \
        {p.name for p in folder.iterdir()}
    subprocess.run(["make", "-s", "-B", "example"], cwd=folder, check=True, capture_output=True)
    printed = subprocess.run([str(folder / "example")], check=True, capture_output=True, text=True).stdout
    rows = list(csv.reader(io.StringIO(printed)))
    assert rows[0] == ["t", *names]
    got = np.array(rows[1:], dtype=float)
    np.testing.assert_allclose(got[:, 0], t, rtol=0, atol=1e-12)
    assert deviation(got[:, 1:], q) <= TOLERANCE


# the example program's own "%.17g" (exact integer digits for |x| in [1e-6, 1e16), printf elsewhere), run on each
# double of stdin (16 hex digits of its bits) instead of the model
HARNESS = r"""
#include <stdio.h>
#include <string.h>
#define main example_main
#include "example.c"
#undef main
int main(void)
{
    unsigned long long bits;
    while (scanf("%llx", &bits) == 1) {
        double x;
        char text[32];
        memcpy(&x, &bits, sizeof x);
        format_g17(x, text);
        puts(text);
    }
    return 0;
}
"""


def test_c_example_prints_each_double_as_python_formats_it(rotor_boom, tmp_path):
    """The example program's table numbers against Python's own correctly rounded "%.17g" (its dtoa, ties to
    even): random magnitudes over the exact digits' range and beyond, random bit patterns, exact ties in the 17th
    digit, the neighbours of powers of ten and of the range's ends; each read back is the same double."""
    exported, _ = rotor_boom
    folder = build.c_folder(exported, tmp_path / "rotor_boom_c")
    (folder / "harness.c").write_text(HARNESS)
    build.compile_c(folder, ["harness.c", "symmech_model.c", *exported.c_files()], folder / "harness", shared=False)
    rng = np.random.default_rng(7)
    magnitudes = 10.0 ** rng.uniform(-8, 17, 40000) * rng.choice([-1.0, 1.0], 40000)
    patterns = rng.integers(0, 2**63, 20000, dtype=np.uint64).view(np.float64)
    ties = np.ldexp(rng.integers(2**52, 2**53, 20000) | 1, -rng.integers(1, 9, 20000))  # x.5, .25, ... at 1e14-1e15
    powers = 10.0 ** np.arange(-8, 18)
    edges = np.concatenate([np.nextafter(powers, 0), powers, np.nextafter(powers, np.inf), [0.0, -0.0, 1.0]])
    x = np.concatenate([magnitudes, patterns[np.isfinite(patterns)], ties, edges, -edges])
    printed = subprocess.run([str(folder / "harness")], input="\n".join(f"{b:016x}" for b in x.view(np.uint64)),
                             check=True, capture_output=True, text=True).stdout.split()
    assert printed == [f"{v:.17g}" for v in x.tolist()]
    assert np.array_equal(np.array(printed, dtype=float), x)


@pytest.mark.parametrize("args, says", [
    (["fmu", "trolley_helix.toml", "--out", "x.fmu"], "an elastic effect), mechanism and grain scenes"),
    (["fmu", "mechanism_chain_large.toml", "--out", "x.fmu"], "up to 60 coordinates"),
    pytest.param(["c", "impact_default.toml", "--out", "x_c"], "covers mechanism, elastic trolley and grain",
                 marks=pytest.mark.slow),  # the default tier's budget: one kind's refusal there is enough
    (["fmu", "smm_double_pendulum.toml", "--out", "x.zip"], "ends in .fmu"),
    (["c", "smm_double_pendulum.toml", "--out", "mine"], "a folder of other files"),
])
def test_refusals_are_one_line(args, says, tmp_path, capsys):
    what, scene, *rest = args
    rest[-1] = str(tmp_path / rest[-1])
    if what == "c":  # a folder of the user's own files is never replaced
        (tmp_path / "mine").mkdir()
        (tmp_path / "mine" / "notes.txt").write_text("keep")
    assert main(["export", what, str(SCENES / scene), *rest]) == 2
    err = capsys.readouterr().err
    assert says in err and len(err.strip().splitlines()) == 1
    assert sorted(p.name for p in tmp_path.rglob("*")) == (["mine", "notes.txt"] if what == "c" else [])


def test_a_parameter_named_like_a_c_keyword_is_refused(tmp_path, capsys):
    text = (SCENES / "smm_double_pendulum.toml").read_text().replace("l1 = {", "long = {").replace('"-l1"', '"-long"')
    scene = tmp_path / "keyword.toml"
    scene.write_text(text)
    assert main(["export", "fmu", str(scene), "--out", str(tmp_path / "x.fmu")]) == 2
    err = capsys.readouterr().err
    assert "parameters.long: a reserved word in C" in err and len(err.strip().splitlines()) == 1


def test_no_compiler_is_one_line(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("CC", "no-such-compiler")
    for what, out in (("fmu", "x.fmu"), ("c", "x_c")):
        assert main(["export", what, str(SCENES / "smm_double_pendulum.toml"), "--out", str(tmp_path / out)]) == 2
        err = capsys.readouterr().err
        assert "no C compiler" in err and len(err.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


@pytest.mark.slow  # FMPy's cmake build of the sources (~20 s)
@pytest.mark.skipif(shutil.which("cmake") is None, reason="FMPy builds source FMUs with cmake")
def test_source_fmu_built_by_fmpy_runs(rotor_boom, tmp_path):
    """The FMU's sources (FMI 3 buildDescription.xml) are complete: FMPy builds this platform's binary from them
    alone, and that binary reproduces the native run."""
    import zipfile

    from fmpy.build import build_platform_binary

    exported, (t, q, names) = rotor_boom
    fmu = build.fmu(exported, tmp_path / "rb_me.fmu", 3, "me")
    folder = tmp_path / "unzipped"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder, [n for n in z.namelist() if not n.startswith("binaries/")])
    (tmp_path / "build").mkdir()
    build_platform_binary(folder, tmp_path / "build")
    result = fmpy.simulate_fmu(str(folder), solver="CVode", relative_tolerance=1e-10, stop_time=t[-1],
                               output_interval=t[1] - t[0], output=names)
    assert deviation(np.column_stack([result[n] for n in names]), q) <= TOLERANCE
