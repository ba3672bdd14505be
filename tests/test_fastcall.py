"""The C path of a numba twin's rhs/jac (symmech.numerics.fastcall, symmech/numerics/_fastcall.c).

The C Kernel calls the twin's rhs_into/jac_into compiled as a numba cfunc, so its results must be
bit-equal to the twin's rhs_scalar/jac_scalar (the same generated kernel, the same machine code); the
numpy module computes with Python's math and numpy's LAPACK instead of LLVM's and scipy's, which may
differ in the last bit on other machines, so against it the bound is 1e-15 of the largest entry (0
measured here). Anything the C side does not take goes to the generated function's path.
"""
import os
import pickle
import subprocess
import sys
from types import SimpleNamespace

import numpy as np
import pytest

from symmech.numerics import fastcall, kernels
from symmech.generated import grain_motion, smm_rotor_boom

# grain_motion (no mass matrix) and smm_rotor_boom (M solved in the kernel): the twins the default tier
# compiles already (tests/test_dynamics_rhs.py QUICK_TWINS), in the same worker
pytestmark = pytest.mark.xdist_group("twins")
MODULES = {"grain_motion": grain_motion, "smm_rotor_boom": smm_rotor_boom}


def _states(module):
    """Seeded states with entries of both signs over 16 decades, then adversarial ones: zero, subnormal,
    huge (rates overflow to inf), a NaN entry; parameters in [0.5, 1.5]."""
    n, m = len(module.STATE), len(module.PARAMS)
    rng = np.random.default_rng(20)
    p = rng.uniform(0.5, 1.5, m)
    for _ in range(5):
        yield rng.uniform(-10, 10), rng.uniform(-3, 3, n) * 10.0 ** rng.integers(-8, 8, n), p
    for y in (np.zeros(n), np.full(n, 5e-324), np.full(n, -1e200), np.where(np.arange(n) == 1, np.nan, 1.0)):
        yield 0.25, y, p


def _near(actual, reference):
    """Equal where not finite; elsewhere within 1e-15 of the largest finite reference entry."""
    finite = np.isfinite(reference)
    np.testing.assert_array_equal(actual[~finite], reference[~finite])
    scale = np.abs(reference[finite]).max(initial=0.0)
    assert np.abs(actual[finite] - reference[finite]).max(initial=0.0) <= 1e-15 * scale


def _outcome(f, *args):
    """f(*args), or the type and message of what it raised."""
    try:
        return f(*args)
    except Exception as exc:  # noqa: BLE001 (compared, not swallowed)
        return type(exc), str(exc)


@pytest.mark.parametrize("name", MODULES)
def test_c_path_equals_the_kernels_and_the_numpy_module(name):
    """Values, or the error the kernel raises (numba's solve refuses a mass matrix with inf or NaN)."""
    twin, module = kernels.load(name), MODULES[name]
    with np.errstate(all="ignore"):
        for t, y, p in _states(module):
            for name, kernel, reference, shape in (("rhs", twin.rhs_scalar, module.rhs, y.shape),
                                                   ("jac", twin.jac_scalar, module.jac, y.shape * 2)):
                value, expected = _outcome(getattr(twin, name), t, y, p), _outcome(kernel, t, y, p)
                assert type(getattr(twin, name)).__name__ == "Kernel"  # the first call bound the C path
                if isinstance(expected, tuple):
                    assert value == expected
                    continue
                assert value.shape == shape and value.flags.owndata
                np.testing.assert_array_equal(value, expected)  # bit-equal, NaN where NaN
                _near(value, reference(t, y, p))


def test_anything_else_takes_the_generated_path_with_its_results_and_errors():
    """Lists, an int t, a float32, strided or big-endian y, an (n, k) batch and keywords give
    exactly what the generated function gives (the Kernel carries its name and docstring and pickles by
    name); wrong lengths its ValueError; a singular mass matrix the
    twin's LinAlgError (the cfunc reports it, the general path raises it), and the next call works."""
    twin = kernels.load("grain_motion")
    y, p = next(_states(grain_motion))[1:]
    twin.rhs(0.1, y, p), twin.jac(0.1, y, p)  # bind the C path
    for f in (twin.rhs, twin.jac):
        generated = f.__wrapped__
        assert f.__name__ == generated.__name__ and f.__doc__ == generated.__doc__
        assert pickle.loads(pickle.dumps(f)) is f  # by name, as the function it stands for
        for t, yy, pp in ((0.1, list(y), list(p)), (1, y, p), (0.1, y.astype(np.float32), p),
                          (0.1, np.repeat(y, 2)[::2], p), (0.1, y.astype(">f8"), p)):
            np.testing.assert_array_equal(f(t, yy, pp), generated(t, yy, pp))
        np.testing.assert_array_equal(f(0.1, y=y, p=p), generated(0.1, y, p))
        for yy, pp in ((y[:-1], p), (y, p[:-1])):
            with pytest.raises(ValueError, match=r"expected \(13,\) or \(13, k\), and \(15,\)"):
                f(0.1, yy, pp)
    batch = np.column_stack([y, 2 * y])
    np.testing.assert_array_equal(twin.rhs(0.1, batch, p), twin.rhs.__wrapped__(0.1, batch, p))
    boom = kernels.load("smm_rotor_boom")
    y, p = np.ones(4), np.ones(13)
    p[[0, 2, 3]] = 0.0  # I1 = m2 = I2 = 0: M = diag(1, 1, 0)
    for name in ("rhs", "jac"):
        assert np.isfinite(getattr(boom, name)(0.0, y, np.ones(13))).all()
        assert type(getattr(boom, name)).__name__ == "Kernel"
        with pytest.raises(np.linalg.LinAlgError, match="singular"):
            getattr(boom, name)(0.0, y, p)
        assert np.isfinite(getattr(boom, name)(0.0, y, np.ones(13))).all()


def _fresh_copy(twin):
    """The twin's names with the generated rhs and jac, as kernels.load finds them before install."""
    return SimpleNamespace(**(vars(twin) | {"rhs": twin.rhs.__wrapped__, "jac": twin.jac.__wrapped__}))


def test_without_a_compiler_the_numba_path_serves_and_nothing_is_said(tmp_path, monkeypatch, capfd):
    """CC names a missing program and the cache folder is fresh: no extension, no file, no output; the
    twin's rhs binds back to the generated (numba) function and computes."""
    twin = kernels.load("grain_motion")
    monkeypatch.setenv("CC", str(tmp_path / "no-such-cc"))
    monkeypatch.setattr(fastcall, "cache_dir", lambda dispatcher: tmp_path / "cache")
    copy = _fresh_copy(twin)
    generated = copy.rhs
    fastcall.install(copy)
    y, p = next(_states(grain_motion))[1:]
    np.testing.assert_array_equal(copy.rhs(0.1, y, p), twin.rhs_scalar(0.1, y, p))
    assert copy.rhs is generated
    assert [f.name for f in (tmp_path / "cache").iterdir()] == ["symmech-fastcall-build.lock"]
    assert capfd.readouterr() == ("", "")


def test_built_once_then_loaded_by_every_process(tmp_path, monkeypatch):
    """A fresh folder: the first call builds the extension and binds the C path. Another process (CC
    pointing nowhere: it could not build) loads that file, which keeps its mtime, and leaves no other file;
    an install that finds the file gives a C Kernel at once, so a reference taken before the first call
    is the C path too."""
    twin = kernels.load("grain_motion")
    monkeypatch.setattr(fastcall, "cache_dir", lambda dispatcher: tmp_path)
    y, p = next(_states(grain_motion))[1:]
    first = _fresh_copy(twin)
    fastcall.install(first)
    np.testing.assert_array_equal(first.rhs(0.1, y, p), twin.rhs_scalar(0.1, y, p))
    assert type(first.rhs).__name__ == "Kernel" and first.rhs.bound
    built = fastcall.artifact(tmp_path)
    stamp, files = built.stat().st_mtime_ns, sorted(tmp_path.iterdir())
    code = (f"from pathlib import Path; from symmech.numerics import fastcall; "
            f"print(fastcall.extension(Path({str(tmp_path)!r})).Kernel.__name__)")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                          env=os.environ | {"CC": str(tmp_path / "no-such-cc")})
    assert proc.stdout.strip() == "Kernel", proc.stderr
    assert built.stat().st_mtime_ns == stamp and sorted(tmp_path.iterdir()) == files
    again = _fresh_copy(twin)
    fastcall.install(again)
    early = again.jac
    assert type(early).__name__ == "Kernel" and not early.bound
    np.testing.assert_array_equal(early(0.1, y, p), twin.jac_scalar(0.1, y, p))
    assert early.bound and again.jac is early
