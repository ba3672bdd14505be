"""Emission layer: reproducible, checked, sympy-free generated modules."""
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import sympy

from symmech import __version__
from symmech.cli import main
from symmech.core import emit
from symmech.core.derivation import Arg, ModuleSpec, NamedMatrix


@pytest.fixture(scope="module")
def specs():
    return emit.module_specs()


def test_generated_folder_is_up_to_date(specs):
    assert emit.stale(emit.default_directory(), specs) == []


def test_first_line_names_version_and_input_hash(specs):
    for spec in specs:
        first = (emit.default_directory() / f"{spec.name}.py").read_text().splitlines()[0]
        assert first == f"# symmech {__version__} generated module; inputs sha256 {emit.inputs_hash(spec)}"


def test_render_is_byte_identical_under_another_hash_seed(tmp_path):
    """A fresh interpreter with a different PYTHONHASHSEED writes the same bytes."""
    env = dict(os.environ, PYTHONHASHSEED="12345")
    subprocess.run([sys.executable, "-m", "symmech", "codegen", "--dir", str(tmp_path)],
                   check=True, env=env, capture_output=True)
    for path in tmp_path.glob("*.py"):
        assert path.read_bytes() == (emit.default_directory() / path.name).read_bytes(), path.name


def test_check_names_stale_and_stray_files(tmp_path, specs, capsys):
    spec = specs[0]
    emit.write(spec, tmp_path)
    (tmp_path / "__init__.py").write_text("")
    target = tmp_path / f"{spec.name}.py"
    target.write_text(target.read_text() + "# edited by hand\n")
    (tmp_path / "leftover.py").write_text("")
    bad = emit.stale(tmp_path, [spec])
    assert bad == [str(target), str(tmp_path / "leftover.py")]
    assert main(["codegen", "--check", "--dir", str(tmp_path)]) == 1
    assert str(target) in capsys.readouterr().err


def test_undeclared_symbols_are_named():
    x, y, z = sympy.symbols("x_a y_b z_c")
    with pytest.raises(ValueError, match="y_b, z_c"):
        NamedMatrix("f", sympy.Matrix([x + y * z]), (Arg(x, "x", "m"),), "f", "m")


def test_keywords_and_primes_become_identifiers(tmp_path):
    lam, rp = sympy.Symbol("lambda"), sympy.Symbol("R_x'")
    nm = NamedMatrix("f", sympy.Matrix([[lam * rp, lam], [1, rp]]),
                     (Arg(lam, "factor", "1"), Arg(rp, "offset", "m")), "demo", "m")
    assert [a.name for a in nm.args] == ["lambda_", "R_xp"]
    path = emit.write(ModuleSpec("demo_mod", "demo", "test", [nm]), tmp_path)
    namespace = {}
    exec(compile(path.read_text(), str(path), "exec"), namespace)
    out = namespace["f"](np.array([2.0, 3.0]), 5.0)
    np.testing.assert_allclose(out, [[[10, 2], [1, 5]], [[15, 3], [1, 5]]])


def test_large_outputs_are_chunked(tmp_path):
    """A 12x12 output is split into helper functions and still evaluates exactly."""
    s = sympy.Symbol("s")
    M = sympy.Matrix(12, 12, lambda i, j: sympy.sin(s) ** (i % 3) * (i + 1) + j * s)
    nm = NamedMatrix("big", M, (Arg(s, "parameter", "1"),), "big", "1")
    text = emit.render(ModuleSpec("big_mod", "big", "test", [nm]))
    assert text.count("def _big_") == 3  # 144 elements, 64 per chunk
    namespace = {}
    exec(compile(text, "big_mod", "exec"), namespace)
    value = 0.7
    expected = np.array(M.subs(s, value).evalf(), dtype=float)
    np.testing.assert_allclose(namespace["big"](value), expected, rtol=1e-14)


SYMPY_BLOCKER = textwrap.dedent("""
    import sys
    class Block:
        def find_spec(self, name, path=None, target=None):
            if name == "sympy" or name.startswith("sympy."):
                raise ImportError("sympy is blocked for this test")
    sys.meta_path.insert(0, Block())
""")


def test_generated_modules_and_solvers_work_without_sympy(specs):
    names = [s.name for s in specs]
    code = SYMPY_BLOCKER + textwrap.dedent(f"""
        import importlib, numpy as np
        for name in {names!r}:
            importlib.import_module("symmech.generated." + name)
        from symmech.generated import grain_impact as g
        H = g.H(np.full(4, 2e-3), 1.5e-3, 1e-3, np.linspace(0, 1, 4), 0.7, 1.1)
        assert H.shape == (4, 3, 3)
        from symmech.grain.body import Ellipsoid, rotation
        from symmech.grain.impact import solve_impact
        r = solve_impact(Ellipsoid(2e-3, 1.5e-3, 1e-3, 1e-5), rotation([0.3, 0.7, 1.1]),
                         [0.3, 0.1, -0.5], [1, 2, 3], 0.5, 0.3)
        assert r.converged
        assert "sympy" not in sys.modules
        print("ok")
    """)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "ok"


def test_batch_and_scalar_calls_agree():
    from symmech.generated import grain_impact as g

    psi = np.linspace(-3, 3, 7)
    batch = g.H(2e-3, 1.5e-3, 1e-3, psi, 0.7, 1.1)
    assert batch.shape == (7, 3, 3)
    for k, p in enumerate(psi):
        np.testing.assert_array_equal(g.H(2e-3, 1.5e-3, 1e-3, p, 0.7, 1.1), batch[k])
    assert g.contact_height(1e-3, 1e-3, 1e-3, 0.1, 0.2, 0.3).shape == ()
