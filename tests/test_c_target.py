"""The C99 target: generated/*.c compiled with the system C compiler equals the numpy reference modules.

Each function of a module is called through ctypes at seeded random arguments and compared with the numpy
module's function (the reference) entry by entry; the rates of a dynamics module are called in their (t, y, p)
layout. Default tier: three modules of the three papers; slow tier: every module."""
from __future__ import annotations

import ctypes
import importlib
import inspect
import shutil
import subprocess

import numpy as np
import pytest

from symmech.core import codegen, emit, integrity
from symmech.core.emit import DYNAMICS_FUNCTIONS

GENERATED = emit.default_directory()
ALL = sorted(p.stem for p in GENERATED.glob("*.c"))
QUICK = ["smm_rotor_boom", "trolley_frame", "grain_impact_printed"]
DOUBLES = ctypes.POINTER(ctypes.c_double)

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="needs a C compiler")


def _library(name: str, tmp_path):
    library = tmp_path / f"{name}.so"
    subprocess.run(["cc", "-std=c99", "-O2", "-fPIC", "-shared", "-Wall", "-Werror", "-o", str(library),
                    str(GENERATED / f"{name}.c"), "-lm"], check=True)
    return ctypes.CDLL(str(library))


def _pointer(values: np.ndarray):
    return values.ctypes.data_as(DOUBLES)


def _compare(name: str, tmp_path) -> int:
    """Every function of module ``name`` in C against numpy at 5 random points; the number compared."""
    module = importlib.import_module(f"symmech.generated.{name}")
    library = _library(name, tmp_path)
    rng = np.random.default_rng(7)
    dynamics = hasattr(module, "STATE")
    compared = 0
    for function in module.__all__:
        if function in ("rhs", "jac", "events"):
            continue
        reference = getattr(module, function)
        arguments = list(inspect.signature(reference).parameters)
        c_function = getattr(library, f"{name}_{function}")
        for _ in range(5):
            args = rng.uniform(0.5, 1.5, len(arguments))
            with np.errstate(all="ignore"):  # a random point may leave a function's domain: nan in both
                expected = np.asarray(reference(*args), dtype=float).ravel()
            out = np.full(expected.size, np.nan)
            if dynamics and function in DYNAMICS_FUNCTIONS:
                n, m = len(module.STATE), len(module.PARAMS)
                t = args[0] if len(args) > n + m else 0.0
                y, p = np.ascontiguousarray(args[-n - m:-m]), np.ascontiguousarray(args[-m:])
                c_function(ctypes.c_double(t), _pointer(y), _pointer(p), _pointer(out))
            else:
                args = np.ascontiguousarray(args)
                c_function(_pointer(args), _pointer(out))
            scale = max(np.nanmax(np.abs(expected), initial=0.0), 1.0)
            np.testing.assert_allclose(out, expected, rtol=1e-12, atol=1e-12 * scale, err_msg=f"{name}.{function}")
        compared += 1
    return compared


@pytest.mark.parametrize("name", QUICK)
def test_c_module_equals_numpy(name, tmp_path):
    assert _compare(name, tmp_path) >= 3


@pytest.mark.slow  # compiles every generated C module (~1 min)
@pytest.mark.parametrize("name", sorted(set(ALL) - set(QUICK)))
def test_every_c_module_equals_numpy(name, tmp_path):
    assert _compare(name, tmp_path) >= 1


def test_every_spec_has_a_c_module_with_a_c_header():
    index = codegen.Index.read(GENERATED)
    assert sorted(index.modules) == ALL
    for name in ALL:
        text = (GENERATED / f"{name}.c").read_text()
        assert text.startswith("// symmech ") and integrity.problem(GENERATED / f"{name}.c") is None


def test_edited_c_module_is_named_by_check(tmp_path, capsys):
    from symmech.cli import main

    folder = tmp_path / "generated"
    shutil.copytree(GENERATED, folder, ignore=shutil.ignore_patterns("__pycache__"))
    path = folder / "trolley_frame.c"
    path.write_text(path.read_text().replace("out[0] =", "out[0] = 2 *", 1))
    (folder / "stray.c").write_text("int x;\n")
    assert main(["codegen", "--check", "--dir", str(folder)]) == 1
    err = capsys.readouterr().err
    assert str(path) in err and str(folder / "stray.c") in err and str(folder / "trolley_frame.py") not in err
