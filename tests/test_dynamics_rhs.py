"""Generated rhs(t, y, p) / jac(t, y, p) of the dynamics modules, as solve_ivp takes them.

The rates are checked against hand-typed closed forms (grain flight) and the numeric
SMM assembly (an independent route), the Jacobians against central finite
differences, the numba twins against the numpy reference; then bundled scenes are
integrated through solve_ivp on the generated rhs and compared with ``scene.run()``.
"""
import importlib
import importlib.util
import subprocess
import sys
import textwrap
import tomllib

import numba
import numpy as np
import pytest
import sympy
from scipy.integrate import solve_ivp

import symmech
from symmech.core import emit
from symmech.numerics import kernels
from symmech.core.derivation import Arg, Dynamics, ModuleSpec, NamedMatrix, args_of, jacobian
from symmech.core.scene import scenes_folder
from symmech.generated import grain_motion as gm
from symmech.generated import smm_rotor_boom
from symmech.smm import numeric

TEXTS = {p.stem: p.read_text() for p in emit.default_directory().glob("*.py") if not p.stem.endswith("_nb")}
DYNAMICS = sorted(name for name, text in TEXTS.items() if "\nSTATE = (" in text)
WITH_JACOBIAN = [name for name in DYNAMICS if "\ndef jac(" in TEXTS[name]]
# twins compiled in the default tier (each 3-10 s of CPU); the slow tier compiles every one
QUICK_TWINS = ("grain_motion", "smm_rotor_boom")
# the twins numba compiles here are those of docs/python-api.md's example: one worker compiles them once
pytestmark = pytest.mark.xdist_group("twins")


def test_dynamics_modules_and_those_with_a_jacobian():
    """Grain flight, the mechanisms' free motion (with jac), the small elastic trolley (M(q): rhs only)."""
    assert WITH_JACOBIAN == DYNAMICS[:-1]
    assert DYNAMICS == ["grain_motion", "smm_double_pendulum", "smm_excavator", "smm_rotor_boom",
                        "smm_spatial_boom", "trolley_elastic_lagrange"]


def _point(module, seed):
    """A state and a parameter vector with entries in [0.5, 1.5] (masses and lengths positive)."""
    rng = np.random.default_rng(seed)
    return rng.uniform(0.5, 1.5, len(module.STATE)), rng.uniform(0.5, 1.5, len(module.PARAMS))


@pytest.mark.parametrize("name", DYNAMICS)
def test_layout_constants_name_units_and_meanings(name):
    module = importlib.import_module(f"symmech.generated.{name}")
    for entries in (module.STATE, module.PARAMS):
        assert all(len(e) == 3 and e[0].isidentifier() and e[1] and e[2] for e in entries)
    assert "rhs" in module.__all__ and ("jac" in module.__all__) == (name in WITH_JACOBIAN)
    y, p = _point(module, 1)
    with pytest.raises(ValueError, match="expected"):
        module.rhs(0.0, y[:-1], p)
    with pytest.raises(ValueError, match="expected"):
        module.rhs(0.0, y, np.append(p, 1.0))


@pytest.mark.parametrize("name", WITH_JACOBIAN)
def test_jacobian_matches_central_differences(name):
    """Central differences with step h = 1e-6 |y_i| (truncation ~h^2, round-off ~eps/h): 1e-7 relative."""
    module = importlib.import_module(f"symmech.generated.{name}")
    for seed in (2, 3):
        y, p = _point(module, seed)
        J = module.jac(0.37, y, p)
        fd = np.empty_like(J)
        for i in range(len(y)):
            h = 1e-6 * abs(y[i])
            up, down = y.copy(), y.copy()
            up[i] += h
            down[i] -= h
            fd[:, i] = (module.rhs(0.37, up, p) - module.rhs(0.37, down, p)) / (2 * h)
        scale = np.abs(J).max(axis=1, keepdims=True)
        assert np.all(np.abs(J - fd) <= 1e-7 * scale + 1e-12)


# compiling a twin takes 5-40 s: the default tier checks the grain's and the rotor boom's, the slow tier all
@pytest.mark.parametrize("name", [n if n in QUICK_TWINS else pytest.param(n, marks=pytest.mark.slow)
                                  for n in DYNAMICS])
def test_numba_twin_equals_numpy_and_vectorized_equals_columns(name):
    module = importlib.import_module(f"symmech.generated.{name}")
    twin = kernels.load(name)
    y, p = _point(module, 4)
    Y = np.column_stack([_point(module, s)[0] for s in range(5, 9)])
    reference = module.rhs(0.2, Y, p)
    assert reference.shape == Y.shape
    for k in range(Y.shape[1]):
        np.testing.assert_allclose(module.rhs(0.2, Y[:, k], p), reference[:, k], rtol=1e-14, atol=0)
    np.testing.assert_allclose(twin.rhs(0.2, Y, p), reference, rtol=1e-12, atol=1e-12 * np.abs(reference).max())
    f = module.rhs(0.2, y, p)
    np.testing.assert_allclose(twin.rhs_scalar(0.2, y, p), f, rtol=1e-12, atol=1e-12 * np.abs(f).max())
    if name in WITH_JACOBIAN:
        J = module.jac(0.2, y, p)
        np.testing.assert_allclose(twin.jac(0.2, y, p), J, rtol=1e-12, atol=1e-12 * np.abs(J).max())


@numba.njit
def _rows_into(rhs_into, t, Y, p, out):
    """rhs_into called from compiled code: row i of ``out`` (k, n) from row i of ``Y`` (k, n)."""
    for i in range(Y.shape[0]):
        rhs_into(t, Y[i], p, out[i:i + 1])


@pytest.mark.parametrize("name", [n if n in QUICK_TWINS else pytest.param(n, marks=pytest.mark.slow)
                                  for n in WITH_JACOBIAN])
def test_into_kernels_from_numba_code_equal_the_numpy_module(name):
    """rhs_into in a numba loop and jac_into write what the numpy module's rhs/jac return (1e-12); wrong
    lengths of y, p or out raise instead of reading or writing past an array."""
    module = importlib.import_module(f"symmech.generated.{name}")
    twin = kernels.load(name)
    Y = np.array([_point(module, s)[0] for s in range(5, 9)])
    p = _point(module, 4)[1]
    out = np.full(Y.shape, np.nan)
    _rows_into(twin.rhs_into, 0.2, Y, p, out)
    for y, f in zip(Y, out):
        expected = module.rhs(0.2, y, p)
        np.testing.assert_allclose(f, expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max())
    J = np.full((1, Y.shape[1], Y.shape[1]), np.nan)
    twin.jac_into(0.2, Y[0], p, J)
    expected = module.jac(0.2, Y[0], p)
    np.testing.assert_allclose(J[0], expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max())
    for args in ((Y[0][:-1], p, out[:1]), (Y[0], p[:-1], out[:1]), (Y[0], p, out[:1, :-1])):
        with pytest.raises(ValueError, match="rhs_into: y must hold"):
            twin.rhs_into(0.2, *args)
    with pytest.raises(ValueError, match="jac_into: y must hold"):
        twin.jac_into(0.2, Y[0], p, J[:, :-1])


def test_numba_rhs_and_jac_take_what_the_numpy_ones_take():
    """float64 C vectors go straight to the kernel compiled for them; lists, an int t, a float32 or
    strided y, a column batch take the converting path; all equal the numpy module to 1e-12, and a wrong
    length raises the layout's ValueError."""
    twin = kernels.load("grain_motion")
    y, p = _point(gm, 8)
    strided = np.repeat(y, 2)[::2]
    for t, yy, pp in ((0.1, y, p), (0.1, list(y), list(p)), (1, y, p), (0.1, y.astype(np.float32), p),
                      (0.1, strided, p), (0.1, np.column_stack([y, 2 * y]), p)):
        expected = gm.rhs(t, yy, pp)
        np.testing.assert_allclose(twin.rhs(t, yy, pp), expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max())
        if np.ndim(yy) == 1:
            J = gm.jac(t, yy, pp)
            np.testing.assert_allclose(twin.jac(t, yy, pp), J, rtol=1e-12, atol=1e-12 * np.abs(J).max())
    for yy, pp in ((y[:-1], p), (y, p[:-1])):
        for f in (twin.rhs, twin.jac):
            with pytest.raises(ValueError, match="expected \\(13,\\) or \\(13, k\\), and \\(15,\\)"):
                f(0.1, yy, pp)


@pytest.mark.parametrize("name", WITH_JACOBIAN)
def test_one_state_on_floats_equals_the_batch_path(name):
    """The numpy module computes one state on Python floats with math, a batch with numpy: jac at y (n,)
    equals jac at y (n, 1) to 1e-14 (rhs: test_numba_twin_equals_numpy_and_vectorized_equals_columns)."""
    module = importlib.import_module(f"symmech.generated.{name}")
    y, p = _point(module, 6)
    J = module.jac(0.3, y, p)
    np.testing.assert_allclose(J, module.jac(0.3, y[:, None], p)[0], rtol=1e-14, atol=1e-14 * np.abs(J).max())


def test_one_state_where_math_raises_gives_what_numpy_gives():
    """I1 = 0 divides by zero: math raises, so rhs at one state takes the numpy path (inf/nan where numpy
    puts them, as before the float path existed) instead of raising ZeroDivisionError."""
    y, p = _point(gm, 7)
    p[9] = 0.0
    with np.errstate(divide="ignore", invalid="ignore"):
        f = gm.rhs(0.1, y, p)
        batch = gm.rhs(0.1, y[:, None], p)[:, 0]
    assert not np.isfinite(f[10]) and np.isfinite(f[:10]).all()
    assert np.array_equal(f, batch, equal_nan=True)


def test_grain_flight_rates_equal_the_closed_forms():
    """r'' = g_K + A w^2 d sin(w t + phase); I1 w1' = (I2 - I3) w2 w3 (cyclic); q' = q (x) (0, w)/2."""
    y, p = _point(gm, 5)
    t = 0.123
    f = gm.rhs(t, y, p)
    g_k, (A, om, ph), d, inertia = p[0:3], p[3:6], p[6:9], p[9:12]
    np.testing.assert_allclose(f[0:3], y[3:6], rtol=1e-15)
    np.testing.assert_allclose(f[3:6], g_k + A * om**2 * d * np.sin(om * t + ph), rtol=1e-14)
    q0, qv, w = y[6], y[7:10], y[10:13]
    np.testing.assert_allclose(f[6], -qv @ w / 2, rtol=1e-14)
    np.testing.assert_allclose(f[7:10], (q0 * w + np.cross(qv, w)) / 2, rtol=1e-14)
    I1, I2, I3 = inertia
    euler = [(I2 - I3) * w[1] * w[2] / I1, (I3 - I1) * w[2] * w[0] / I2, (I1 - I2) * w[0] * w[1] / I3]
    np.testing.assert_allclose(f[10:13], euler, rtol=1e-13, atol=1e-15)


def test_grain_flight_contact_event_is_the_gap_over_the_plane():
    """g = rz - |D n'| with n' the third row of Q(q / |q|) (the generated rotation_matrix and support_distance,
    eq (63)), also for a quaternion off unit length, in both targets; spinning about the plane normal (q = 1)
    it is rz - c."""
    assert [e[:4] for e in gm.EVENTS] == [("contact", -1, True, "m")]
    twin = kernels.load("grain_motion")
    assert twin.EVENTS == gm.EVENTS
    y, p = _point(gm, 6)
    a, b, c = p[12:15]
    for scale in (1.0, 1.3):
        yy = y.copy()
        yy[6:10] = scale * y[6:10] / np.linalg.norm(y[6:10])
        n_body = gm.rotation_matrix(*(y[6:10] / np.linalg.norm(y[6:10])))[2]
        expected = y[2] - gm.support_distance(a, b, c, *n_body)
        np.testing.assert_allclose(gm.events(0.1, yy, p), [expected], rtol=1e-14)
        np.testing.assert_allclose(twin.events(0.1, yy, p), [expected], rtol=1e-14)
    upright = np.concatenate([y[:6], [1.0, 0.0, 0.0, 0.0], y[10:]])
    np.testing.assert_allclose(gm.events(0.1, upright, p), [y[2] - c], rtol=1e-15)
    batch = gm.events(0.1, np.column_stack([y, upright]), p)
    np.testing.assert_allclose(batch[0], [gm.events(0.1, y, p)[0], y[2] - c], rtol=1e-14)


def _bundled(name):
    return tomllib.loads((scenes_folder() / name).read_text())


def test_smm_rate_equals_the_numeric_assembly():
    """y' = (q', -a^-1 (b q' + c q)) with a, b, c of smm.numeric (sparse numeric assembly, not symbolic)."""
    scene = symmech.load(_bundled("smm_rotor_boom.toml"))
    m = scene.setup.m
    num = numeric.assemble(m)
    a, b, c = (x.toarray() for x in (num.a, num.b, num.c))
    p = [m.parameters[name].value for name, _, _ in smm_rotor_boom.PARAMS]
    y = np.array([1e-3, -2e-3, 0.05, 0.02])
    n = len(a)
    expected = np.concatenate([y[n:], -np.linalg.solve(a, b @ y[n:] + c @ y[:n])])
    np.testing.assert_allclose(smm_rotor_boom.rhs(0.0, y, p), expected, rtol=1e-10,
                               atol=1e-12 * np.abs(expected).max())
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(a, c), -np.linalg.solve(a, b)]])
    np.testing.assert_allclose(smm_rotor_boom.jac(0.0, y, p), A, rtol=1e-10, atol=1e-12 * np.abs(A).max())


@pytest.mark.parametrize("method, rtol, tol", [("DOP853", 1e-11, 1e-9), ("Radau", 1e-9, 1e-8)])
def test_solve_ivp_on_the_generated_rhs_matches_the_mechanism_run(method, rtol, tol):
    """Damped free response of the rotor boom: the run steps the exact matrix exponential; solve_ivp
    (Radau with the generated jac) on rhs must agree to ``tol`` times the largest |q| (measured:
    2e-11 with DOP853, 1e-10 with Radau)."""
    scene = symmech.load(_bundled("smm_rotor_boom.toml"))
    table = scene.run().tables["free_response"]
    t, q_run = table.data[:, 0], table.data[:, 1:]
    m = scene.setup.m
    p = [m.parameters[name].value for name, _, _ in smm_rotor_boom.PARAMS]
    ini = scene.resolved["initial"]
    y0 = np.concatenate([ini["q"], ini["qdot"] or np.zeros(len(ini["q"]))])
    implicit = {"jac": smm_rotor_boom.jac} if method == "Radau" else {}
    sol = solve_ivp(smm_rotor_boom.rhs, (t[0], t[-1]), y0, method=method, t_eval=t, args=(p,),
                    rtol=rtol, atol=rtol * 1e-3 * np.abs(y0).max(), **implicit)
    assert sol.success
    n = q_run.shape[1]
    assert np.abs(q_run).max() > 0.1 * np.abs(y0).max()  # the response is not trivially zero
    np.testing.assert_array_less(np.abs(sol.y[:n].T - q_run).max(axis=0), tol * np.abs(q_run).max(axis=0))


def test_solve_ivp_on_the_generated_rhs_matches_the_grain_flights():
    """Every flight of 0.3 s of the default grain, from the initial row or an impact's post row to the
    next impact's pre row: position within 1e-12 m, velocity 1e-11 m/s (the run's translation is the
    closed form; measured 1e-14, 8e-14), quaternion 1e-8 and body rates 1e-8 relative (the run
    integrates the rotation to tolerance 1e-9; measured 1.3e-9, 6.5e-10)."""
    data = _bundled("grain_default.toml")
    data["duration"] = 0.3
    scene = symmech.load(data)
    table = scene.run().tables["trajectory"]
    model = scene.setup.model
    vib = model.vibration
    p = np.concatenate([model.g_k, [vib.amplitude, vib.omega, vib.phase], vib.direction, model.inertia, model.axes])
    regime = np.array(table.text["regime"])
    starts = [0] + [i + 1 for i in range(len(regime) - 1) if regime[i] == regime[i + 1] == "impact"]
    flights = 0
    for start in starts:
        stop = start + 1
        while stop < len(regime) and regime[stop] == "flight":
            stop += 1
        if stop >= len(regime) or regime[stop] != "impact" or stop - start < 3:
            continue  # the run ended in flight, or sliding follows, or nothing between
        rows = table.data[start:stop + 1]
        t, r, v, q, w_k = rows[:, 0], rows[:, 1:4], rows[:, 4:7], rows[:, 7:11], rows[:, 11:14]
        w_body = np.einsum("nji,nj->ni", gm.rotation_matrix(*q.T), w_k)
        y0 = np.concatenate([r[0], v[0], q[0], w_body[0]])
        sol = solve_ivp(gm.rhs, (t[0], t[-1]), y0, method="DOP853", t_eval=t, args=(p,), rtol=1e-12, atol=1e-14)
        assert sol.success
        y = sol.y.T
        assert np.abs(y[:, 0:3] - r).max() < 1e-12
        assert np.abs(y[:, 3:6] - v).max() < 1e-11
        assert np.abs(y[:, 6:10] - q).max() < 1e-8
        assert np.abs(y[:, 10:13] - w_body).max() < 1e-8 * np.abs(w_body).max()
        # the generated contact event is zero where the run found the impact (its root to ~1e-12 m)
        assert abs(gm.events(t[-1], np.concatenate([r[-1], v[-1], q[-1], w_body[-1]]), p)[0]) < 1e-10
        flights += 1
    assert flights >= 10


def _emitted(spec, target, folder):
    path = emit.write(spec, folder, target)
    loader = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(loader)
    loader.loader.exec_module(module)
    return module


def _oscillator():
    """m x'' = -k x + F0 cos(W t): a declared Dynamics with a mass matrix and explicit time."""
    x, v, k, mass, f0, w, t = sympy.symbols("x v k m F0 W t", real=True)
    dyn = Dynamics(args_of([(x, "position", "m"), (v, "velocity", "m/s")]),
                   args_of([(k, "stiffness", "N/m"), (mass, "mass", "kg"), (f0, "force amplitude", "N"),
                            (w, "forcing angular frequency", "rad/s")]),
                   sympy.Matrix([v, -k * x + f0 * sympy.cos(w * t)]), sympy.diag(1, mass), Arg(t, "time", "s"),
                   "a forced spring-mass oscillator")
    return ModuleSpec("test_oscillator", "Forced oscillator (tests).", "tests", (), dyn)


# the numba target compiles the emitted module (~10 s of CPU): slow tier; the default tier checks that
# target's dynamics functions on the generated twins (test_numba_twin_equals_numpy..., test_into_kernels...)
@pytest.mark.parametrize("target", [emit.TARGETS[0], pytest.param(emit.TARGETS[1], marks=pytest.mark.slow)],
                         ids=["numpy", "numba"])
def test_declared_dynamics_integrate_to_the_closed_form(tmp_path, target):
    """x(t) = (x0 - F0/(k - m W^2)) cos(w0 t) + F0/(k - m W^2) cos(W t) from rest at x0; solve_ivp on the
    emitted rhs/jac (Radau) within 1e-8 of the amplitude over 5 periods."""
    module = _emitted(_oscillator(), target, tmp_path)
    assert [e[0] for e in module.STATE] == ["x", "v"] and module.PARAMS[1] == ("m", "kg", "mass")
    k, m, f0, w = 40.0, 2.5, 3.0, 1.3
    p = [k, m, f0, w]
    np.testing.assert_allclose(module.rhs(0.7, [0.2, -0.1], p), [-0.1, (-k * 0.2 + f0 * np.cos(w * 0.7)) / m],
                               rtol=1e-15)
    np.testing.assert_allclose(module.jac(0.7, [0.2, -0.1], p), [[0, 1], [-k / m, 0]], rtol=1e-15)
    w0, x0 = np.sqrt(k / m), 0.05
    t = np.linspace(0.0, 5 * 2 * np.pi / w0, 400)
    static = f0 / (k - m * w * w)
    exact = (x0 - static) * np.cos(w0 * t) + static * np.cos(w * t)
    sol = solve_ivp(module.rhs, (0.0, t[-1]), [x0, 0.0], method="Radau", t_eval=t, args=(p,), jac=module.jac,
                    rtol=1e-11, atol=1e-14)
    assert np.abs(sol.y[0] - exact).max() < 1e-8 * np.abs(exact).max()


def test_the_jacobian_is_sympys_entry_for_entry():
    """``derivation.jacobian`` holds the subtrees free of y as symbols while it differentiates: the same
    expressions as ``Matrix.jacobian`` (structural equality), on a rate that nests y under functions, powers,
    a Piecewise and an absolute value beside parameter-only subtrees and repeated ones, and on the rotor boom's free
    motion (coefficients that are large expressions of its parameters)."""
    x, v, k, m, c = sympy.symbols("x v k m c", real=True)
    heavy = sympy.sqrt(k**2 + m**2) * sympy.cos(k / m) + sympy.exp(c * k)
    rate = sympy.Matrix([v * heavy + heavy**2, -k * sympy.sin(x * heavy) / m + sympy.Abs(v) * c,
                         sympy.Piecewise((x**2 * heavy, x > c), (v, True)), heavy, (x + heavy) ** 3 / (1 + v**2)])
    y = sympy.Matrix([x, v])
    assert jacobian(rate, y) == rate.jacobian(y)
    from symmech.smm import derive

    boom = derive.load_mechanism(scenes_folder() / "smm_rotor_boom.toml")
    dyn = derive.free_motion(boom, derive.named_matrices(boom))
    y = sympy.Matrix([a.symbol for a in dyn.state])
    expected = dyn.rate.jacobian(y)
    assert jacobian(dyn.rate, y) == expected and expected.shape == (len(y), len(y))


def test_dynamics_refuses_a_state_dependent_mass_and_a_wrong_shape():
    x, v = sympy.symbols("x v", real=True)
    state = args_of([(x, "position", "m"), (v, "velocity", "m/s")])
    with pytest.raises(ValueError, match="depends on the state: \\['x'\\]"):
        Dynamics(state, (), sympy.Matrix([v, -x]), sympy.diag(1, 1 + x**2))
    with pytest.raises(ValueError, match="rate has shape \\(1, 1\\)"):
        Dynamics(state, (), sympy.Matrix([v]))


def test_dynamics_without_its_rates_has_the_layout_alone_in_c_only():
    """``rates=False``: the module's own function reads (t, y, p) by the layout (its C signature), no ``rate`` or
    ``rate_mass`` is emitted, and the Python targets, whose rhs calls rate, refuse the module."""
    oscillator = _oscillator()
    dyn = oscillator.dynamics
    both = NamedMatrix("rate_and_mass_block", sympy.Matrix([*dyn.rate, dyn.mass[1, 1]]), dyn.args, "F, then m", "N")
    spec = ModuleSpec("test_layout_only", "Forced oscillator (tests).", "tests", (both,), dyn, rates=False)
    assert [f.name for f in spec.functions] == ["rate_and_mass_block"]
    assert [f.name for f in oscillator.functions] == ["rate", "rate_jacobian", "rate_mass"]
    text = emit.render(spec, emit.C99)
    assert "void test_layout_only_rate_and_mass_block(double sm_t, const double *sm_y, const double *sm_p" in text
    assert "const double x = sm_y[0];" in text and "_rate(" not in text and "rate_mass" not in text
    for target in (emit.NUMPY, emit.NUMBA):
        with pytest.raises(ValueError, match="test_layout_only: dynamics without its rate functions have no Python"):
            emit.render(spec, target)


@pytest.mark.parametrize("integrate", [False, pytest.param(True, marks=pytest.mark.slow)],
                         ids=["rates", "solve_ivp (slow)"])
def test_elastic_trolley_rhs_equals_the_runtime_model_and_integrates_alike(integrate):
    """trolley_elastic_lagrange.rhs (Lagrange's equations, M(q) solved numerically) against the runtime's
    invariants + d'Alembert accelerations (trolley.elastic.System) in a frame of constant motion: rates to
    1e-12 of the largest (measured 2e-15), and solve_ivp (Radau, rtol 1e-10) on both over 0.05 s to 1e-9
    of the largest coordinate (measured 2e-14)."""
    from symmech.generated import trolley_elastic_lagrange as lag
    from symmech.trolley.elastic import system as el, body as el_body, frame as el_frame

    assert not hasattr(lag, "jac")  # M depends on q: no Jacobian is derived
    rng = np.random.default_rng(11)
    m0, com, inertia = 90.0, np.array([0.7, 0.4, -0.2]), np.array([12.0, 18.0, 15.0])
    rho_a, length, tip, b1, b3, ei = 3.0, 1.4, 1.5, 0.6, 0.3, (2e3, 5e3)
    k, c, l, ah, g0 = np.array([1e5, 2e5, 1.5e5, 3e5, 2.5e5]), np.array([50.0, 80.0, 60.0, 40.0, 70.0]), 2.0, 0.8, 9.81
    beam = el_body.Beam((b1, 0, b3), (0, 1, 0), (1, 0, 0), length, rho_a, ei, "cantilever", 1, tip)
    system = el.System(el_body.ElasticModel(m0, tuple(com), (*inertia, 0, 0, 0), l, ah, g0,
                                       el_body.Rollers(tuple(k), tuple(c)), (beam,)))
    flip = np.array([1, 1, 1, 1, 1, 1, -1])  # the runtime's second plane is axis × plane = -x3
    nu = np.array([0.1, 0.2, 0.97])
    fs = el_frame.FrameState(np.array([8.0, 0.5, 0.0]), np.array([0.3, -1.0, 0.2]), np.array([0.05, 0.1, 0.4]),
                       np.array([0.01, 0.0, -0.02]), nu / np.linalg.norm(nu))
    p = np.r_[fs.v0, fs.a0 - np.cross(fs.w, fs.v0), fs.w, fs.dw, fs.nu, m0, com, inertia, rho_a, length, tip, b1, b3,
              ei, k, c, g0, l, ah]
    assert len(p) == len(lag.PARAMS)

    def runtime(_t, y):
        return np.r_[y[7:], system.accelerations(fs, flip * y[:7], flip * y[7:]) * flip]

    for _ in range(3):
        y = np.r_[rng.normal(size=7) * np.r_[1e-2, 1e-2, 0.05, 0.05, 0.05, 0.1, 0.1], rng.normal(size=7)]
        expected = runtime(0.0, y)
        assert np.abs(lag.rhs(0.0, y, p) - expected).max() < 1e-12 * np.abs(expected).max()
    if not integrate:
        return
    y0 = np.r_[1e-3, -2e-3, 0.01, 0.0, -0.01, 0.02, 0.01, np.zeros(7)]
    t = np.linspace(0.0, 0.05, 11)
    generated = solve_ivp(lag.rhs, (0, t[-1]), y0, method="Radau", t_eval=t, args=(p,), rtol=1e-10, atol=1e-13)
    reference = solve_ivp(runtime, (0, t[-1]), y0, method="Radau", t_eval=t, rtol=1e-10, atol=1e-13)
    assert generated.success and reference.success
    q = reference.y[:7]
    assert np.abs(generated.y[:7] - q).max() < 1e-9 * np.abs(q).max()


def test_without_numba_kernels_load_gives_the_numpy_rhs_and_layouts():
    code = textwrap.dedent("""
        import sys
        class Block:
            def find_spec(self, name, path=None, target=None):
                if name.split(".")[0] in ("numba", "llvmlite"):
                    raise ImportError(name)
        sys.meta_path.insert(0, Block())
        import numpy as np
        from symmech.numerics import kernels
        from symmech.generated import smm_rotor_boom as rb
        k = kernels.load("smm_rotor_boom")
        assert k.STATE == rb.STATE and k.PARAMS == rb.PARAMS
        y, p = np.array([1e-3, 0.0, 0.1, 0.2]), np.linspace(1.0, 2.0, len(rb.PARAMS))
        assert np.array_equal(k.rhs_scalar(0.0, y, p), rb.rhs(0.0, y, p))
        assert np.array_equal(k.jac(0.0, y, p), rb.jac(0.0, y, p))
        out = np.zeros((1, 4))
        k.rhs_into(0.0, y, p, out)
        assert np.array_equal(out[0], rb.rhs(0.0, y, p))
        print("ok")
    """)
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "ok"
