"""The numba target against the numpy reference, at seeded and adversarial points.

Kernels compile on first call (cached beside the modules afterwards); the
default suite compiles a representative subset, ``-m slow`` every function.
"""
import ast
import importlib
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import sympy

from symmech.core import emit
from symmech.numerics import kernels
from symmech.core.derivation import Arg, ModuleSpec, NamedMatrix
from symmech.generated import grain_impact as gi

GENERATED = emit.default_directory()
# Relative to the largest element of the configuration: libm (numba) and numpy's
# own sin/cos may differ in the last bit, which CSE chains amplify by a few ulp.
RTOL = 1e-12


def assert_close(compiled, reference, per_configuration=True):
    """Equal shapes, NaN and inf where the reference has them; elsewhere within RTOL of each
    configuration's largest finite element (``per_configuration``) or of the whole batch's."""
    assert compiled.shape == reference.shape
    finite = np.isfinite(reference)
    np.testing.assert_array_equal(np.where(finite, 0, compiled), np.where(finite, 0, reference))
    flat_c = np.where(finite, compiled, 0).reshape(max(compiled.shape[:1]), -1)
    flat_r = np.where(finite, reference, 0).reshape(flat_c.shape)
    largest = np.abs(flat_r).max(axis=1, keepdims=True) if per_configuration else np.abs(flat_r).max()
    scale = np.maximum(largest, 1e-300)
    error = np.abs(flat_c - flat_r) / scale
    assert error.max() <= RTOL, f"max relative error {error.max():.2e}"


def grain_configurations(n=1000, seed=11):
    """Semi-axes a >= b >= c [m] and z-x-z angles [rad]: random, spheres, needles, discs, theta 0 and pi."""
    rng = np.random.default_rng(seed)
    axes = np.sort(rng.uniform(0.2e-3, 5e-3, (n, 3)), axis=1)[:, ::-1].copy()
    angles = rng.uniform(-np.pi, np.pi, (n, 3))
    k = n // 8
    axes[:k] = 2e-3                                   # spheres
    axes[k:2 * k] = [10e-3, 0.05e-3, 0.05e-3]         # needles
    axes[2 * k:3 * k] = [5e-3, 5e-3, 0.02e-3]         # flat discs
    angles[3 * k:4 * k, 1] = 0.0                      # theta = 0 (gimbal lock of z-x-z)
    angles[4 * k:5 * k, 1] = np.pi                    # theta = pi
    angles[5 * k:5 * k + 10] = [[0, 0, 0], [np.pi, np.pi, np.pi], [-np.pi, 0, np.pi],
                                [np.pi / 2, np.pi / 2, np.pi / 2], [0, np.pi / 2, 0],
                                [1e-300, 1e-300, 1e-300], [0, 1e-12, 0], [0, np.pi - 1e-12, 0],
                                [3.0, -0.0, -3.0], [7.0, 2 * np.pi, -7.0]]
    return (*axes.T, *angles.T)


@pytest.mark.parametrize("parallel_batch", [0, 10**9], ids=["parallel loop", "serial loop"])
def test_impact_tensor_compiled_equals_numpy_at_1000_configurations(monkeypatch, parallel_batch):
    args = grain_configurations()
    nb = kernels.load("grain_impact")
    assert nb.__name__ == "symmech.generated.grain_impact_nb"
    monkeypatch.setattr(nb, "PARALLEL_BATCH", parallel_batch)
    assert_close(nb.H(*args), gi.H(*args))
    assert_close(nb.contact_height(*args), gi.contact_height(*args))
    assert_close(nb.rotation(*args[3:]), gi.rotation(*args[3:]))


def test_scalar_twins_take_floats_and_match_the_reference():
    args = np.array(grain_configurations(200, seed=5)).T
    nb = kernels.load("grain_impact")
    scalar = np.array([nb.H_scalar(*map(float, row)) for row in args])
    assert_close(scalar, gi.H(*args.T))
    heights = [nb.contact_height_scalar(*map(float, row)) for row in args]
    assert all(type(h) is float for h in heights)
    assert_close(np.array(heights), gi.contact_height(*args.T))


def test_batch_wrapper_broadcasts_like_numpy():
    """Scalars mixed with arrays, a 2-D batch, read-only and empty inputs: the numpy contract."""
    nb = kernels.load("grain_impact")
    psi = np.linspace(-3, 3, 12).reshape(3, 4)
    theta = np.linspace(0, np.pi, 4)                     # broadcasts along the last axis
    readonly = np.full((3, 4), 0.7)
    readonly.flags.writeable = False
    for args in [(2e-3, 1.5e-3, 1e-3, psi, theta, readonly),
                 (2e-3, 1.5e-3, 1e-3, 0.1, 0.2, 0.3),
                 (np.full((3, 1), 2e-3), 1.5e-3, 1e-3, psi, 0.2, 0.3),
                 (2e-3, 1.5e-3, 1e-3, np.empty(0), 0.2, 0.3)]:
        reference = gi.H(*args)
        compiled = nb.H(*args)
        assert compiled.shape == reference.shape
        np.testing.assert_allclose(compiled, reference, rtol=0, atol=RTOL * 4)


@pytest.mark.parametrize("module, function", [
    ("trolley_frame", "Lambda"),
    ("grain_motion", "flight_translation"),
    ("smm_double_pendulum", "c"),
])
def test_representative_kernels_of_each_paper(module, function):
    reference = getattr(importlib.import_module(f"symmech.generated.{module}"), function)
    compiled = getattr(kernels.load(module), function)
    n_args = reference.__code__.co_argcount
    args = np.random.default_rng(3).uniform(0.3, 1.7, (n_args, 64))
    assert_close(compiled(*args), reference(*args))
    assert_close(np.array([getattr(kernels.load(module), f"{function}_scalar")(*args[:, k])
                           for k in range(3)]), reference(*args[:, :3]))
    out = np.empty((1,) + reference(*args[:, :1]).shape[1:])
    getattr(kernels.load(module), f"{function}_into")(*args[:, 3], out)
    assert_close(out, reference(*args[:, 3:4]))


def test_chunked_function_compiles_and_matches(tmp_path, monkeypatch):
    """A 3x3 output in chunks of 4 elements (three CSE chunks) through the numba template;
    arguments named like the numba template's loop index and steps in other tools."""
    monkeypatch.setattr(emit, "CHUNK_ELEMENTS", 4)
    s, t = sympy.symbols("steps k")
    M = sympy.Matrix(3, 3, lambda i, j: sympy.sin(s) ** (i % 3) * (i + 1) + j * s / (t - 1))
    spec = ModuleSpec("big_mod", "big", "test", [NamedMatrix("big", M, (Arg(s, "s", "1"), Arg(t, "k", "1")),
                                                             "big", "1")])
    for target in emit.TARGETS:
        emit.write(spec, tmp_path, target)
    monkeypatch.syspath_prepend(str(tmp_path))
    numpy_module, numba_module = importlib.import_module("big_mod"), importlib.import_module("big_mod_nb")
    assert (tmp_path / "big_mod_nb.py").read_text().count("def _big_") == 5  # 3 chunks, serial and parallel loops
    s_values, t_values = np.linspace(-2, 2, 9), np.array([0.0, 1.0, 2.0])[:, None]  # t = 1: 1/0
    with np.errstate(divide="ignore", invalid="ignore"):
        assert_close(numba_module.big(s_values, t_values).reshape(27, 3, 3),
                     numpy_module.big(s_values, t_values).reshape(27, 3, 3))
    assert np.isinf(numba_module.big_scalar(0.5, 1.0)[0, 1])  # error_model="numpy": no ZeroDivisionError


def _imports(path) -> set[str]:
    imported = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            imported.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            imported.add(node.module)
    return imported


def test_compiled_modules_import_numpy_numba_math_only():
    """Every numpy module has its numba twin, which imports math, numba and numpy only; the report's MathML
    twins import nothing."""
    files = sorted(GENERATED.glob("*_nb.py"))
    numpy_modules = [p for p in GENERATED.glob("*.py")
                     if p.name != "__init__.py" and not p.stem.endswith(("_nb", "_mathml"))]
    assert sorted(p.stem for p in files) == sorted(f"{p.stem}_nb" for p in numpy_modules) and len(files) > 15
    for path in files:
        assert _imports(path) == {"math", "numba", "numpy"}, path.name
    mathml = sorted(GENERATED.glob("*_mathml.py"))
    assert sorted(p.stem for p in mathml) == sorted(f"{p.stem}_mathml" for p in numpy_modules)
    for path in mathml:
        assert _imports(path) == set(), path.name


NUMBA_BLOCKER = textwrap.dedent("""
    import sys
    class Block:
        def find_spec(self, name, path=None, target=None):
            if name.split(".")[0] in ("numba", "llvmlite"):
                raise ImportError(f"No module named {name!r}", name=name)
    sys.meta_path.insert(0, Block())
""")


def test_without_numba_the_numpy_module_stands_in():
    code = NUMBA_BLOCKER + textwrap.dedent("""
        import numpy as np
        from symmech.numerics import kernels
        from symmech.generated import grain_impact as gi
        k = kernels.load("grain_impact")
        assert k.__name__ == "symmech.generated.grain_impact"
        H = k.H_scalar(2e-3, 1.5e-3, 1e-3, 0.3, 0.7, 1.1)
        assert isinstance(H, np.ndarray) and H.shape == (3, 3)
        assert np.array_equal(H, gi.H(2e-3, 1.5e-3, 1e-3, 0.3, 0.7, 1.1))
        h = k.contact_height_scalar(2e-3, 1.5e-3, 1e-3, 0.3, 0.7, 1.1)
        assert type(h) is float and h == float(gi.contact_height(2e-3, 1.5e-3, 1e-3, 0.3, 0.7, 1.1))
        out = np.zeros((1, 3, 3))
        k.H_into(2e-3, 1.5e-3, 1e-3, 0.3, 0.7, 1.1, out)
        assert np.array_equal(out[0], H)
        assert k.H_scalar.__doc__ == "H on floats (numpy fallback: numba is not installed)."  # help() reads them
        assert k.H_into.__doc__ == "H on floats into out[0] (numpy fallback: numba is not installed)."
        assert np.array_equal(k.H(2e-3, 1e-3, 1e-3, np.zeros(4), 0.5, 0.5), gi.H(2e-3, 1e-3, 1e-3, np.zeros(4), 0.5, 0.5))
        try:
            import symmech.generated.grain_impact_nb
        except ImportError as exc:
            assert exc.name == "numba"
        assert "numba" not in sys.modules
        print("ok")
    """)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "ok"


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore:invalid value encountered")  # NaN outside a domain: compared as NaN
@pytest.mark.parametrize("name", [path.stem.removesuffix("_nb") for path in sorted(GENERATED.glob("*_nb.py"))])
def test_every_compiled_function_matches_numpy(name):
    """All functions of every module (one test each, so xdist spreads the compiles), batch, into and scalar,
    at 64 seeded points in [0.3, 1.7], to RTOL of each function's largest value over the points: a
    configuration where a whole function nearly vanishes (the held axial field of a beam at its pins, ~1e-3 of
    its size) is known to absolute accuracy only there, and the two targets' rounding differs (numba forms
    integer powers by multiplication)."""
    rng = np.random.default_rng(17)
    reference = importlib.import_module(f"symmech.generated.{name}")
    compiled = kernels.load(name)
    # rhs(t, y, p), jac and events take vectors: compared in tests/test_dynamics_rhs.py
    for function in [f for f in reference.__all__ if f not in ("rhs", "jac", "events")]:
        f = getattr(reference, function)
        args = rng.uniform(0.3, 1.7, (f.__code__.co_argcount, 64))
        expected = f(*args)
        assert_close(getattr(compiled, function)(*args), expected, per_configuration=False)
        if not len(args):  # a constant (a function of no argument) has no batch axis
            expected = np.stack([expected] * 2)
        scalar = getattr(compiled, f"{function}_scalar")(*args[:, 0])
        assert_close(np.asarray(scalar)[None], expected[:1], per_configuration=False)
        out = np.full((2,) + expected.shape[1:], 7.0)  # into out[0] only
        getattr(compiled, f"{function}_into")(*args[:, 1], out)
        assert_close(out[:1], expected[1:2], per_configuration=False)
        assert np.all(out[1] == 7.0)
