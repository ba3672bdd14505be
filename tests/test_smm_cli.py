"""CLI: runs, latex, and one-line errors naming the element for bad mechanism scenes."""
import json

import pytest

from symmech.cli import main
from symmech.core import emit
from symmech.smm.derive import bundled_scenes, module_specs

BASE = """kind = "mechanism"
[parameters]
m = {value = 1.0, unit = "kg"}
[[coordinates]]
name = "x"
type = "slide"
axis = [1, 0]
[[points]]
name = "O"
at = [0, 0]
[[points]]
name = "P"
from = "O"
vector = [1, 0]
slides = ["x"]
[[bodies]]
name = "bob"
mass = "m"
com = "P"
[[springs]]
name = "k1"
ends = ["O", "P"]
stiffness = 100.0
"""

BAD = {
    "unreachable point": (BASE.replace('from = "O"', 'from = "Q"'),
                          "points[1].from': point 'Q' is not defined"),
    "loop": (BASE.replace('from = "O"', 'from = "P"'), "points[1].from': the chain of vectors of 'P' loops"),
    "coordinate moves nothing": (BASE + '[[coordinates]]\nname = "y"\ntype = "slide"\naxis = [0, 1]\n',
                                 "coordinates[1].name': coordinate 'y' moves nothing"),
    "zero-length spring": (BASE.replace('vector = [1, 0]', 'vector = [0, 0]'), "springs[0].ends': ends 'O' and 'P' coincide"),
    "singular mass": (BASE.replace('value = 1.0, unit = "kg"', 'value = 0.0, unit = "kg"'),
                      "coordinates[0]': inertia matrix is singular"),
    "unknown parameter": (BASE.replace('mass = "m"', 'mass = "mm"'), "bodies[0].mass': unknown parameter 'mm' in 'mm' (did you mean 'm'?)"),
    "unknown field": (BASE.replace('stiffness = 100.0', 'stiffness = 100.0\nstifness = 3'),
                      "springs[0].stifness': unknown field (did you mean 'stiffness'?)"),
    "negative mass": (BASE.replace('value = 1.0, unit = "kg"', 'value = -1.0, unit = "kg"'),
                      "bodies[0].mass': m = -1 kg is outside 0 or [1e-12, 1e+12] kg"),
    "non-unit axis": (BASE.replace('axis = [1, 0]', 'axis = [2, 0]'), "coordinates[0].axis': [2.0, 0.0, 0.0] must be a unit vector"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_scene_one_line_error(case, tmp_path, capsys):
    text, message = BAD[case]
    path = tmp_path / "bad.toml"
    path.write_text(text)
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert message in err, err


def test_run_writes_results(tmp_path, capsys):
    path = tmp_path / "ok.toml"
    path.write_text(BASE + "[initial]\nq = [0.01]\nduration = 1.0\n[forcing]\npoint = \"P\"\nforce = [1, 0]\n"
                           "omega = [0, 20]\n[[dampers]]\nname = \"d\"\nends = [\"O\", \"P\"]\nviscosity = 2.0\n")
    assert main(["run", str(path), "--out", str(tmp_path / "o")]) == 0
    s = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert abs(s["frequencies_rad_s"][0] - 10.0) < 1e-12
    # zeta = c_d / (2 sqrt(k m)) = 2 / 20
    assert abs(s["damping_ratios"][0] - 0.1) < 1e-12
    for f in ("modes.csv", "modes.png", "free_response.csv", "frequency_response.csv", "frequency_response.png"):
        assert (tmp_path / "o" / f).exists()


def test_latex_bundled(capsys):
    assert main(["latex", "smm:double_pendulum.a"]) == 0
    assert "l_{2}^{2} m_{2}" in capsys.readouterr().out
    # spring directions are normalised in the display form: no sqrt, no |h|
    assert main(["latex", "smm:spatial_boom.L_c"]) == 0
    out = capsys.readouterr().out
    assert "sqrt" not in out and "left|" not in out and "> 0" in out.splitlines()[0]


@pytest.mark.parametrize("scene, key", [("rotor_boom", "c"), ("spatial_boom", "L_c"), ("spatial_boom", "c")])
def test_readable_form_equals_derived(scene, key):
    """The display form is the derived matrix: equal at 50 seeded points with positive parameters
    (the assumption it states), and it actually got shorter."""
    import numpy as np
    import sympy

    from symmech.smm.derive import SCENES, load_mechanism, named_matrices, readable

    m = load_mechanism(SCENES / f"smm_{scene}.toml")
    nm = named_matrices(m)[key]
    nice = readable(nm, m.values())
    syms = [a.symbol for a in nm.args]
    f, g = (sympy.lambdify(syms, x.matrix, "numpy") for x in (nm, nice))
    rng = np.random.default_rng(7)
    for _ in range(50):
        x = [v * rng.uniform(0.5, 1.5) for v in m.values().values()]
        a, b = np.array(f(*x), float), np.array(g(*x), float)
        assert np.allclose(a, b, rtol=1e-10, atol=1e-10 * np.abs(a).max())
    ops = lambda M: sum(sympy.count_ops(e) for e in M)  # noqa: E731
    assert ops(nice.matrix) < ops(nm.matrix)


def test_bundled_scenes_have_modules():
    """Every bundled mechanism scene declares a generated module (kept current by test_codegen)."""
    names = {s.name for s in module_specs()}
    assert {f"smm_{p.stem[4:]}" for p in bundled_scenes()} == names
    assert all((emit.default_directory() / f"{n}.py").exists() for n in names)


def test_errata_records_computed():
    from symmech.core.errata import evaluate
    from symmech.smm.errata import checks

    records = [evaluate(c, n=20) for c in checks()]
    assert {r["equation"] for r in records} >= {"5.1 (a)", "5.2 (L_a)"}
    for r in records:
        assert r["status"] == "agrees" and r["max_rel_diff"] < 1e-12, r


@pytest.mark.parametrize("path", bundled_scenes(), ids=[p.stem for p in bundled_scenes()])
def test_bundled_scenes_run_cleanly(path, tmp_path, capsys):
    assert main(["run", str(path), "--out", str(tmp_path)]) == 0
    s = json.loads((tmp_path / "summary.json").read_text())
    assert s["warnings"] == []
    assert all(w is None or w >= 0 for w in s["frequencies_rad_s"])
    assert (tmp_path / "modes.png").exists()


def test_precision_bench(tmp_path):
    path = tmp_path / "p.toml"
    path.write_text('kind = "mechanism"\n[chain]\nn = 400\nmass = 1.0\nstiffness = 100.0\nspacing = 1.0\n'
                    '[precision]\nmodes = 5\n')
    assert main(["bench", "precision", str(path), "--out", str(tmp_path / "o")]) == 0
    rows = _csv(tmp_path / "o" / "precision.csv")
    assert rows[0]["method"] == "dense eigh" and len(rows) == 7
    # the tightest eigsh tolerance reproduces the dense frequencies
    assert float(rows[-1]["max_rel_error_omega2 [1]"]) < 1e-10


def _csv(path):
    import csv

    with open(path) as fh:
        return list(csv.DictReader(fh))


@pytest.mark.parametrize("path", bundled_scenes(), ids=[p.stem for p in bundled_scenes()])
def test_precision_bench_on_bundled_scenes(path, tmp_path):
    """Default mode count fits every bundled scene (at most coordinates - 1, eigsh's limit); the
    eigsh solution at tol 0 reproduces the dense one."""
    assert main(["bench", "precision", str(path), "--out", str(tmp_path / "o"), "--quiet"]) == 0
    rows = _csv(tmp_path / "o" / "precision.csv")
    s = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert s["modes"] == min(10, s["dof"] - 1)
    assert rows[0]["method"] == "dense eigh"
    assert float(rows[-1]["max_rel_error_omega2 [1]"]) < 1e-8


def test_latex_chain_scene(tmp_path, capsys):
    path = tmp_path / "c.toml"
    path.write_text('kind = "mechanism"\n[chain]\nn = 2\nmass = 1.0\nstiffness = 100.0\nspacing = 1.0\n')
    assert main(["latex", f"smm:{path}.c"]) == 0
    assert "2 k" in capsys.readouterr().out


def test_large_run_writes_sparse_matrices_and_refuses_huge(tmp_path, capsys):
    path = tmp_path / "c.toml"
    text = 'kind = "mechanism"\n[chain]\nn = 250\nmass = 1.0\nstiffness = 100.0\nspacing = 1.0\n[output]\nplots = []\n'
    path.write_text(text)
    assert main(["run", str(path), "--out", str(tmp_path / "o")]) == 0
    rows = (tmp_path / "o" / "matrices.csv").read_text().splitlines()
    assert len(rows) == 1 + 3 * 250 - 2
    path.write_text(text.replace("n = 250", "n = 3001"))
    assert main(["run", str(path), "--out", str(tmp_path / "o")]) == 2
    assert "has 3001 coordinates" in capsys.readouterr().err


def test_parameterless_scene_gets_a_constant_module(tmp_path):
    """A scene of numbers only still gets its generated module (zero-argument functions)."""
    import importlib.util

    path = tmp_path / "n.toml"
    path.write_text('kind = "mechanism"\nname = "numbers"\n[[coordinates]]\nname = "x"\ntype = "slide"\n'
                    'axis = [1, 0]\n[[points]]\nname = "O"\nat = [0, 0]\n[[points]]\nname = "P"\nfrom = "O"\n'
                    'vector = [1, 0]\nslides = ["x"]\n[[bodies]]\nname = "bob"\nmass = 2.0\ncom = "P"\n'
                    '[[springs]]\nname = "k1"\nends = ["O", "P"]\nstiffness = 200.0\n')
    assert main(["run", str(path), "--out", str(tmp_path / "o")]) == 0
    s = json.loads((tmp_path / "o" / "summary.json").read_text())
    spec = importlib.util.spec_from_file_location("numbers_module", tmp_path / "o" / s["generated_module"])
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert float(module.a()) == 2.0 and float(module.c()) == 200.0 and float(module.b()) == 0.0
    assert abs(s["frequencies_rad_s"][0] - 10.0) < 1e-12


@pytest.mark.slow
def test_large_chain_scene_runs(tmp_path):
    """`symmech run scenes/mechanism_chain_large.toml` failed after a minute with
    "precision: unknown field"; it runs (3000 DOF, dense) and its omega^2 match the closed form."""
    import math

    from symmech.smm.derive import SCENES

    assert main(["run", str(SCENES / "mechanism_chain_large.toml"), "--out", str(tmp_path / "o"), "--quiet"]) == 0
    s = json.loads((tmp_path / "o" / "summary.json").read_text())
    n, k, m = 3000, 1.0e4, 0.1
    exact = [2 * k / m * (1 - math.cos(j * math.pi / (n + 1))) for j in (1, 2, n)]
    w2 = s["omega2_1_per_s2"]
    assert s["rigid_body_modes"] == 0
    assert abs(w2[0] - exact[0]) < 1e-6 * exact[2] and abs(w2[-1] - exact[2]) < 1e-9 * exact[2]
