"""Emission layer: reproducible, checked, sympy-free generated modules."""
import dataclasses
import hashlib
import importlib.metadata
import os
import shutil
import subprocess
import sys
import textwrap
import types
from pathlib import Path

import numpy as np
import pytest
import sympy

from symmech import __version__
from symmech.cli import main
from symmech.core import codegen, emit, integrity
from symmech.core.scene import SymmechError
from symmech.core.derivation import Arg, ModuleSpec, NamedMatrix


@pytest.fixture(scope="module")
def specs():
    return codegen.module_specs()


# every derivation runs once per process (codegen.derive caches): one xdist worker derives them all
pytestmark = pytest.mark.xdist_group("derive")

GENERATED = emit.default_directory()


def _copy_generated(tmp_path):
    target = tmp_path / "generated"
    shutil.copytree(GENERATED, target, ignore=shutil.ignore_patterns("__pycache__"))
    return target


@pytest.mark.slow  # renders every module (~40 s); the default tier checks the cache keys (codegen --check)
def test_generated_folder_is_up_to_date(specs):
    """Every module of every target is exactly what its derivation renders (the slow path)."""
    index = codegen.Index.read(GENERATED)
    assert sorted(index.modules) == sorted(s.name for s in specs)
    for spec in specs:
        producer = index.modules[spec.name]
        key = codegen.source_key(producer, index.inputs[producer])
        for target in emit.TARGETS:
            path = GENERATED / target.file(spec.name)
            assert path.read_text() == emit.render(spec, target, key), path.name


def test_header_names_version_inputs_key_and_body(specs):
    for spec in specs:
        for target in emit.TARGETS:
            text = (GENERATED / target.file(spec.name)).read_text()
            header, body = integrity.split(text)
            assert header.version == __version__
            assert header.inputs == emit.inputs_hash(spec, target)
            assert header.body == hashlib.sha256(body.encode()).hexdigest()
            assert len(text.splitlines()[0]) < 120


@pytest.mark.slow  # a fresh interpreter derives every module (~30 s)
def test_render_is_byte_identical_under_another_hash_seed(tmp_path):
    """A fresh interpreter with a different PYTHONHASHSEED writes the same bytes, index included."""
    env = dict(os.environ, PYTHONHASHSEED="12345")
    subprocess.run([sys.executable, "-m", "symmech", "codegen", "--dir", str(tmp_path)],
                   check=True, env=env, capture_output=True)
    written = sorted(p.name for tail in ("*.py", "*.c") for p in tmp_path.glob(tail))
    assert written == sorted(p.name for tail in ("*.py", "*.c") for p in GENERATED.glob(tail))
    for name in written:
        assert (tmp_path / name).read_bytes() == (GENERATED / name).read_bytes(), name


def test_no_change_check_runs_no_derivation():
    """The cached path of `codegen --check` and `codegen` imports neither sympy nor numpy."""
    code = textwrap.dedent("""
        import sys
        from symmech.cli import main
        assert main(["codegen", "--check"]) == 0
        assert main(["codegen"]) == 0
        print(sorted(m for m in ("sympy", "numpy", "jinja2") if m in sys.modules))
    """)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert "0 files written, nothing derived" in done.stdout
    assert done.stdout.strip().splitlines()[-1] == "[]"


def test_check_names_stale_and_stray_files(tmp_path, capsys):
    """An edited module is named, its twin not; codegen writes it back. A printed module: its derivation takes
    0.1 s, where a derived module's takes seconds; the check and the rewrite are the same for every module."""
    folder = _copy_generated(tmp_path)
    target = folder / "trolley_printed.py"
    target.write_text(target.read_text() + "# edited by hand\n")
    (folder / "leftover.py").write_text("")
    assert main(["codegen", "--check", "--dir", str(folder)]) == 1
    err = capsys.readouterr().err
    assert str(target) in err and str(folder / "leftover.py") in err
    assert str(folder / "trolley_printed_nb.py") not in err
    assert main(["codegen", "--dir", str(folder)]) == 0
    assert target.read_bytes() == (GENERATED / "trolley_printed.py").read_bytes()
    assert (folder / "leftover.py").exists()  # not written by codegen: named, never deleted
    (folder / "leftover.py").unlink()
    assert main(["codegen", "--check", "--dir", str(folder)]) == 0


def test_changed_derivation_is_caught_and_unchanged_output_passes(tmp_path, monkeypatch, capsys):
    """A new source key makes codegen derive; only a changed text is stale."""
    folder = _copy_generated(tmp_path)
    real_key, real_derive = codegen.source_key, codegen.derive
    monkeypatch.setattr(codegen, "source_key", lambda p, d: "f" * 64 if p.endswith("trolley.derive")
                        else real_key(p, d))
    assert main(["codegen", "--check", "--dir", str(folder)]) == 0
    assert "outdated source keys" in capsys.readouterr().err

    def derive(producer):
        specs, data = real_derive(producer)
        if producer.endswith("trolley.derive"):
            specs = (dataclasses.replace(specs[0], doc=specs[0].doc + " Changed."),) + specs[1:]
        return specs, data

    monkeypatch.setattr(codegen, "derive", derive)
    assert main(["codegen", "--check", "--dir", str(folder)]) == 1
    stale = [line.strip() for line in capsys.readouterr().err.splitlines() if line.startswith("  ")]
    assert stale == [str(folder / name) for name in ("trolley_frame.py", "trolley_frame_nb.py", "trolley_frame.c",
                                                        "trolley_frame_mathml.py")]


@pytest.mark.parametrize("damage", ["one byte", "truncated", "no header"])
def test_verify_refuses_a_damaged_module(tmp_path, damage):
    folder = _copy_generated(tmp_path)
    path = folder / "grain_impact.py"
    text = path.read_text()
    header, body = integrity.split(text)
    assert integrity.problem(path) is None
    assert integrity.verify_file("grain_impact", path) == header.body
    spot = text.index("x0*x1 - x2*x5")
    path.write_text({"one byte": text[:spot] + "x0*x1 + x2*x5" + text[spot + 13:],
                     "truncated": text[:len(text) // 2],
                     "no header": body}[damage])
    with pytest.raises(SymmechError, match=r"generated module grain_impact is edited.*regenerate with `symmech codegen`"):
        integrity.verify_file("grain_impact", path)


def test_verify_refuses_a_module_of_another_version(tmp_path):
    folder = _copy_generated(tmp_path)
    path = folder / "trolley_frame.py"
    path.write_text(path.read_text().replace(f"# symmech {__version__} ", "# symmech 0.0.1 ", 1))
    with pytest.raises(SymmechError, match="trolley_frame is stale .*0.0.1"):
        integrity.verify_file("trolley_frame", path)


def test_deleted_module_is_named_by_check_and_recreated(tmp_path, capsys):
    """Two deleted modules of two producers, a numpy module and a numba twin, are named and written again (printed
    modules: cheap derivations; the check and the rewrite are the same for every module)."""
    folder = _copy_generated(tmp_path)
    (folder / "smm_printed.py").unlink()
    (folder / "grain_motion_printed_nb.py").unlink()
    assert main(["codegen", "--check", "--dir", str(folder)]) == 1
    err = capsys.readouterr().err
    assert str(folder / "smm_printed.py") in err and str(folder / "grain_motion_printed_nb.py") in err
    assert main(["codegen", "--dir", str(folder)]) == 0
    out = capsys.readouterr().out
    assert "2 files written, 2 derivation modules run" in out
    for name in ("smm_printed.py", "grain_motion_printed_nb.py"):
        assert (folder / name).read_bytes() == (GENERATED / name).read_bytes()


@pytest.mark.slow  # derives and renders every module again
def test_deleted_index_rebuilds_everything(tmp_path, capsys):
    folder = _copy_generated(tmp_path)
    (folder / "__init__.py").unlink()
    assert main(["codegen", "--check", "--dir", str(folder)]) == 1
    assert str(folder / "__init__.py") in capsys.readouterr().err
    assert main(["codegen", "--dir", str(folder)]) == 0
    assert (folder / "__init__.py").read_bytes() == (GENERATED / "__init__.py").read_bytes()


def test_an_index_without_a_modules_listing_rebuilds_it(tmp_path):
    """An index that lacks a module's listing (as one written before ``latex --list`` read it; signed, the module
    current) derives that module's producer once and is written with the listing, byte for byte the committed
    one. One small module, one cheap derivation."""
    folder = _copy_generated(tmp_path)
    index = codegen.Index.read(folder)
    for key in index.listing("grain_impact_printed"):
        del index.matrices[key]
    (folder / "__init__.py").write_text(index.text(), encoding="utf-8")
    report = codegen.run(folder, check=False)
    assert report.derived == ["symmech.grain.printed"] and report.written == [str(folder / "__init__.py")]
    assert (folder / "__init__.py").read_bytes() == (GENERATED / "__init__.py").read_bytes()


def test_installed_package_refuses_codegen_without_dir(monkeypatch, capsys):
    """Not a checkout (as after `pip install .`): one line, exit 2, nothing written."""
    monkeypatch.setattr(codegen, "ROOT", Path("/nonexistent/site-packages"))
    assert main(["codegen"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "not a writable symmech checkout" in err and "--dir" in err


def test_unwritable_dir_is_one_line(tmp_path, monkeypatch, capsys):
    folder = _copy_generated(tmp_path)
    (folder / "grain_impact_printed.py").unlink()  # one small module to write: one cheap derivation

    def refuse(path, text):
        raise PermissionError(13, "Permission denied", str(path))

    monkeypatch.setattr(integrity, "write_atomic", refuse)
    assert main(["codegen", "--dir", str(folder)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert f"cannot use {folder / 'grain_impact_printed.py'}: Permission denied" in err


def test_dir_that_is_a_file_is_refused(tmp_path, capsys):
    (tmp_path / "f").write_text("")
    assert main(["codegen", "--dir", str(tmp_path / "f")]) == 2
    assert "is not a folder" in capsys.readouterr().err


def test_used_modules_lists_the_recorded_hashes():
    from symmech.generated import grain_impact, trolley_frame  # noqa: F401

    used = integrity.used_modules()
    assert used["grain_impact"] == integrity.verify_file("grain_impact", GENERATED / "grain_impact.py")
    assert used["trolley_frame"] == integrity.split((GENERATED / "trolley_frame.py").read_text())[0].body


def test_atomic_write_leaves_no_partial_file(tmp_path, monkeypatch):
    path = tmp_path / "m.py"
    path.write_text("old")

    def fail(*args):
        raise OSError("disk full")

    monkeypatch.setattr(os, "replace", fail)
    with pytest.raises(OSError):
        integrity.write_atomic(path, "new text")
    assert path.read_text() == "old"
    assert [p.name for p in tmp_path.iterdir()] == ["m.py"]


def test_source_key_follows_imports_and_data(tmp_path):
    """The key covers what the derivation imports from symmech, and the scenes it reads."""
    module = tmp_path / "fake.py"
    module.write_text("import numpy\nfrom . import forms\nfrom ..core import scene\n"
                      "def f():\n    from symmech.smm.model import Mechanism\n")
    assert sorted(codegen._imported("symmech.smm.fake", module)) == [
        "symmech", "symmech.core", "symmech.core.scene", "symmech.smm", "symmech.smm.forms", "symmech.smm.model"]
    assert "symmech.smm.forms" in codegen.closure("symmech.smm.derive")
    assert "symmech.core.scene" in codegen.closure("symmech.smm.derive")
    assert "symmech.grain.body" not in codegen.closure("symmech.grain.derive")
    inputs = codegen.Index.read(GENERATED).inputs
    assert "scenes/smm_excavator.toml" in inputs["symmech.smm.derive"]
    assert inputs["symmech.grain.derive"] == ()
    assert codegen.source_key("symmech.smm.derive", inputs["symmech.smm.derive"]) != \
        codegen.source_key("symmech.smm.derive", inputs["symmech.smm.derive"][:-1])


def test_a_scenes_folder_is_keyed_by_its_scenes_not_its_bytecode(tmp_path, monkeypatch):
    """Importing the scenes package writes scenes/__pycache__ where Python writes bytecode: the mechanisms' key
    stays (their modules were reported outdated after any run), while a scene added or removed changes it."""
    (tmp_path / "a.toml").write_text("kind = 'mechanism'\n")
    monkeypatch.setattr(codegen, "scenes_folder", lambda: tmp_path)
    before = codegen.source_key("symmech.smm.derive", ("scenes",))
    (tmp_path / "__pycache__").mkdir()
    (tmp_path / "__pycache__" / "__init__.cpython-311.pyc").write_bytes(b"bytecode")
    assert codegen.source_key("symmech.smm.derive", ("scenes",)) == before
    (tmp_path / "b.toml").write_text("kind = 'mechanism'\n")
    assert codegen.source_key("symmech.smm.derive", ("scenes",)) != before


def test_a_derivation_records_the_package_data_only(tmp_path, monkeypatch):
    """What a derivation opens in a virtual environment inside the checkout (a wheel's direct_url.json, read
    through importlib.metadata) is not an input: only bundled scenes and files of the symmech package are."""
    checkout = tmp_path / "clone"  # a clone with `python -m venv .venv` inside it
    metadata = checkout / ".venv/lib/python3.11/site-packages/numpy-2.2.6.dist-info"
    metadata.mkdir(parents=True)
    (metadata / "METADATA").write_text("Metadata-Version: 2.1\nName: numpy\nVersion: 2.2.6\n")
    (metadata / "direct_url.json").write_text("{}")
    monkeypatch.setattr(codegen, "ROOT", checkout)
    monkeypatch.syspath_prepend(str(metadata.parent))

    def module_specs():
        assert importlib.metadata.distribution("numpy").read_text("direct_url.json") == "{}"
        (codegen.scenes_folder() / "smm_excavator.toml").read_bytes()
        (Path(codegen.__file__).parent / "output_schema.json").read_bytes()
        return []

    producer = types.ModuleType("fake_producer")
    producer.module_specs = module_specs
    monkeypatch.setitem(sys.modules, "fake_producer", producer)
    assert codegen.derive.__wrapped__("fake_producer") == \
        ((), ("scenes/smm_excavator.toml", "symmech/core/output_schema.json"))


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


def test_the_code_names_matrix_is_renamed_once_and_leaves_equality_alone():
    """Every target reads one renamed, immutable matrix per NamedMatrix; two equal NamedMatrix stay equal whether or
    not one has renamed its matrix."""
    lam, rp = sympy.Symbol("lambda"), sympy.Symbol("R_x'")
    args = (Arg(lam, "factor", "1"), Arg(rp, "offset", "m"))
    nm, twin = (NamedMatrix("f", sympy.Matrix([[lam * rp, lam]]), args, "demo", "m") for _ in range(2))
    renamed = nm.code_matrix
    lam_, rp_ = sympy.Symbol("lambda_"), sympy.Symbol("R_xp")
    assert renamed == sympy.ImmutableMatrix([[lam_ * rp_, lam_]]) and isinstance(renamed, sympy.ImmutableMatrix)
    assert nm == twin and "code_matrix" in vars(nm) and "code_matrix" not in vars(twin)
    assert nm.code_matrix is renamed and emit.cse_chunks(nm) == emit.cse_chunks(twin)
    assert NamedMatrix("f", sympy.Matrix([[lam * rp, rp]]), args, "demo", "m") != nm


def test_the_code_names_matrix_rebuilds_no_tree_with_nothing_to_rename():
    """Symbols named as their code names, without assumptions, are renamed to themselves: the matrix's own
    expressions, the same objects (a rename rebuilds each tree it reaches); a real symbol is renamed to a plain one."""
    a, b = sympy.symbols("a b")
    plain = NamedMatrix("f", sympy.Matrix([[a * b + 1, a]]), (Arg(a, "a", "1"), Arg(b, "b", "1")), "demo", "1")
    assert all(x is y for x, y in zip(plain.code_matrix, plain.matrix))
    r = sympy.Symbol("a", real=True)
    real = NamedMatrix("f", sympy.Matrix([[r * b + 1, r]]), (Arg(r, "a", "1"), Arg(b, "b", "1")), "demo", "1")
    assert real.code_matrix == plain.matrix and real.code_matrix != real.matrix


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
