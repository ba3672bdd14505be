"""The compiled elastic engine against the Python engine, the reference.

Both engines integrate the same equations by Radau IIA with the same step control (the toolkit's port of
scipy's) and the same tolerances, except that the Python engine's steps are bound by the output spacing and
the compiled engine's are not (its outputs come from the collocation polynomial); the compiled engine
interpolates the frame along the track from a table checked to 1e-3 rtol of each channel's scale. So the
reactions agree within the tolerance: bounds of 1e-7 relative to max|P| at rtol 1e-8 (the issue's target),
measured 7e-9 on the bundled scene (each against Radau at rtol 1e-11: compiled 7.9e-9, Python 1.5e-9). The
assembly itself (q̈, the resultants, M, ∂R/∂q, ∂R/∂q̇) is compared at random states to round-off, and the
compiled Jacobian against central differences of the compiled right-hand side.
"""
import copy
import math
import tomllib
from functools import partial

import numpy as np
import pytest

from symmech.core import pipeline, scene
from symmech.core.scene import SymmechError
from symmech.trolley import model
from symmech.trolley.elastic import frame as el_frame, simulate as el_sim
from symmech.trolley.elastic import scene as elastic_scene

# slow: the engine compiles ~60 s of CPU, a third of the default tier's budget; the default tier
# runs the elastic model on the Python engine, this reference
pytestmark = [pytest.mark.slow, pytest.mark.compiled_elastic, pytest.mark.xdist_group("test_elastic_compiled")]

RNG = np.random.default_rng(20)
BUNDLED = tomllib.loads((scene.scenes_folder() / "trolley_elastic_helix.toml").read_text(encoding="utf-8"))


def helix(t_end=0.15, steps=50, case=1, **elastic):
    """The bundled scene, shortened (outputs every 3 ms as bundled), its [elastic] table updated."""
    doc = copy.deepcopy(BUNDLED)
    doc["time"] = {"t_end": t_end, "steps": steps}
    doc["effects"]["local_curvature"] = case == 2
    for key, value in elastic.items():
        doc["elastic"][key] = value
    doc["elastic"]["numerics"] = {**doc["elastic"]["numerics"], "modal_samples": 0}
    return pipeline.load(doc).setup.elastic


def exact_channels(setup):
    """The exact frame channels of the setup's drive at times x[at], as a compiled run evaluates them."""
    return lambda x, at=slice(None): el_frame.channels(setup.drive, setup.system.mdl.g0, x, at)


def both(setup, rtol):
    runs = {}
    for engine in ("compiled", "python"):
        st = elastic_scene.Setup(**{**setup.__dict__, "engine": engine})
        runs[engine] = elastic_scene.simulate(st, rtol=rtol)
    assert runs["compiled"]["engine"] == "compiled" and runs["python"]["engine"] == "python"
    assert runs["compiled"]["engine_reason"] == 'numerics.engine = "compiled"'  # why the scene chose it, as it said
    return runs["compiled"], runs["python"]


def relative(a, b):
    return np.abs(a - b).max() / max(np.abs(b).max(), 1e-300)


def agree(c, p, bound):
    """P within ``bound`` of max|P|, the other tabulated outputs within 100 ``bound`` of their largest magnitude
    (q̈, not tabulated, follows the undamped roller modes at 500 rad/s: its difference is the integration error
    times ω²), the states q, q̇, E_d, W within that plus 10 x their absolute tolerance (1e-12 m, 1e-9 m/s, 1e-9 J,
    WORK_ATOL: the rates of the stiff start transient are ~1e-5 m/s, the dissipated energy of a short ride
    ~1e-10 J, so there atol rules, and the engines' steps differ)."""
    assert relative(c["P"], p["P"]) < bound
    for key, atol in (("q", 1e-12), ("qd", 1e-9), ("dissipated", 1e-9), ("work", el_sim.WORK_ATOL)):
        assert np.abs(c[key] - p[key]).max() <= 100 * bound * np.abs(p[key]).max() + 10 * atol, key
    for key in ("F", "M", "h", "E", "probe_overload", "probe_elastic"):
        scale = np.abs(p[key]).max()
        if scale > 0:
            assert relative(c[key], p[key]) < 100 * bound, key


@pytest.mark.parametrize("case", [1, 2])
def test_a_short_ride_agrees_at_rtol_1e_8(case):
    c, p = both(helix(t_end=0.03, steps=10, case=case), 1e-8)
    agree(c, p, 1e-7)
    assert c["frame_interpolation_error"] <= 1e-3 * 1e-8
    assert c["nfev"] < p["nfev"]  # the steps are not bound by the output spacing (3 ms) as the Python engine's


def test_a_short_ride_by_default_is_the_run_at_atol_1e_12_and_gives_qdd():
    """compiled.simulate's default absolute tolerance on q is 1e-12 m, the Python engine's: the run without it
    equals the run given it, bit for bit (an atol of 1 m moves P by 2e-7); its q̈ is the Python engine's within
    1e-2 of the largest (measured 1.1e-3: the integration error times the roller modes' ω², see agree)."""
    from symmech.trolley.elastic import compiled as el_compiled

    setup = helix(t_end=0.03, steps=10)
    default = el_compiled.simulate(setup.system, setup.drive, setup.t)
    given = el_compiled.simulate(setup.system, setup.drive, setup.t, atol_q=1e-12)
    for key in ("P", "q", "qd", "qdd"):
        assert np.array_equal(default[key], given[key]), key
    python = el_sim.simulate(setup.system, setup.drive, setup.t, "Radau", 1e-8)
    assert relative(default["qdd"], python["qdd"]) < 1e-2


def test_a_short_ride_s_rows_of_integer_heights_use_the_cached_entry(monkeypatch):
    """row_terms takes the heights [m] as float64 whatever their dtype: integer heights run the cached entry of the
    rows kernel (no new specialisation compiled) and give the terms of the same heights as floats, bit for bit."""
    from symmech.trolley.elastic import compiled as el_compiled, kernels as ek

    calls, row_terms = [], el_compiled.row_terms
    monkeypatch.setattr(el_compiled, "row_terms", lambda *args: calls.append(args) or row_terms(*args))
    setup = helix(t_end=0.03, steps=10)
    el_compiled.simulate(setup.system, setup.drive, setup.t)
    *args, height = calls[0]
    entries = len(ek.rows.signatures)
    whole = row_terms(*args, np.rint(1e3 * height).astype(np.int64))
    assert len(ek.rows.signatures) == entries
    as_floats = row_terms(*args, np.rint(1e3 * height))
    for key, value in as_floats.items():
        assert np.array_equal(whole[key], value), key


def test_a_short_ride_at_integer_output_times_runs_the_cached_entries():
    """Output times given as integers [s] (0 and 1 s) are read as float64: the run calls the cached entries (numba
    may compile nothing more) and equals the run at the same times as floats, bit for bit."""
    from symmech.trolley.elastic import compiled as el_compiled, kernels as ek

    setup = helix()
    as_floats = el_compiled.simulate(setup.system, setup.drive, [0.0, 1.0])
    for entry in (ek.solve, ek.rows):
        entry.disable_compile()
    try:
        whole = el_compiled.simulate(setup.system, setup.drive, [0, 1])
    finally:
        for entry in (ek.solve, ek.rows):
            entry.disable_compile(False)
    for key in ("P", "q", "qd", "t"):
        assert np.array_equal(whole[key], as_floats[key]), key


@pytest.mark.parametrize("status, finite, why, reached", [(1, 4, "required step size is less than spacing", 0.3),
                                                           (0, 2, "no finite state", 0.1)])
def test_a_failed_compiled_solve_names_the_last_finite_time(status, finite, why, reached):
    """A solve that stopped on too small a step, or whose states turned non-finite after the 2nd output: the
    error names the engine, the reason and the last output time whose state is finite; a finite successful
    solve passes."""
    from symmech.numerics import ode
    from symmech.trolley.elastic import compiled as el_compiled

    t, Y = np.array([0.0, 0.1, 0.2, 0.3]), np.ones((4, 3))
    Y[finite:] = np.nan
    with pytest.raises(SymmechError) as error:
        el_compiled._check(status, Y, t)
    assert str(error.value) == f"elastic trolley: integration failed after t = {reached:g} s (compiled Radau: " + (
        ode.STEP_TOO_SMALL_TEXT if status else why) + ")"
    assert why in str(error.value)
    el_compiled._check(ode.SUCCESS, np.ones((4, 3)), t)


def test_rigid_rollers_agree():
    """Beams only (effects.rollers = false): P from the rigid model's reaction system on both engines."""
    setup = helix(t_end=0.06, steps=20, effects={"rollers": False})
    assert not setup.system.rollers_on
    c, p = both(setup, 1e-8)
    agree(c, p, 1e-7)


@pytest.mark.slow
def test_the_bundled_scene_agrees_at_rtol_1e_8():
    """The whole bundled scene (3 s, 1000 outputs): P0…P5 within 1e-7 of max|P| (measured 7.2e-9), the
    compiled steps longer than the output spacing (measured 256 steps for 999 intervals)."""
    doc = copy.deepcopy(BUNDLED)
    doc["elastic"]["numerics"] = {"modal_samples": 0}
    c, p = both(pipeline.load(doc).setup.elastic, 1e-8)
    agree(c, p, 1e-7)
    assert c["steps"] < len(c["t"]) / 2


@pytest.mark.slow
@pytest.mark.parametrize("case", [1, 2])
def test_damping_off_agrees(case):
    c, p = both(helix(t_end=0.06, steps=20, case=case, effects={"damping": False}), 1e-8)
    agree(c, p, 1e-7)
    assert c["dissipated"][-1] == 0.0


@pytest.mark.slow
def test_clamped_pair_with_preload_agrees():
    rollers = {**BUNDLED["elastic"]["rollers"], "law": "clamped_pair", "preload": [2e-5, 1e-5, 2e-5, -1e-6, 1e-5]}
    c, p = both(helix(rollers=rollers), 1e-8)
    agree(c, p, 1e-7)
    assert np.abs(c["deflection"]).max() > 1e-5  # beyond some preloads: both branches of the law are used


@pytest.mark.slow
@pytest.mark.parametrize("damping", [True, False])
def test_a_held_membrane_beam_agrees(damping):
    beam = {"root": [0.2, 0.3, -0.5], "axis": [0, 0, 1], "plane": [0, 1, 0], "length": 1.0, "mass_per_length": 3.0,
            "ei": [50.0, 80.0], "support": "pinned", "axial": "held", "ea": 2e5, "modes": 2, "damping_ratio": 0.02}
    setup = helix(t_end=0.06, steps=20, beams=[beam], points=[{"name": "mid", "beam": 0, "xi": 0.5}],
                  effects={"damping": damping}, initial={"beams": [{"beam": 0, "plane": 1, "amplitude": 0.01}]})
    assert setup.system.inv.membrane and setup.system.inv.D.any() == damping
    c, p = both(setup, 1e-8)
    agree(c, p, 1e-7)
    assert (c["dissipated"][-1] > 0) == damping and np.abs(c["probe_elastic"]).max() > 5e-3


@pytest.mark.slow
def test_the_checks_hold_on_the_compiled_engine():
    """The elastic review's checks (energy balance, rollers' small rotation) all pass on a compiled run of the
    shortened bundled scene, as on the Python one, and the summary names the engine."""
    from symmech.trolley.elastic import review as elastic_review

    verdicts = {}
    for engine in ("compiled", "python"):
        doc = copy.deepcopy(BUNDLED)
        doc["time"] = {"t_end": 0.15, "steps": 50}
        doc["elastic"]["numerics"] = {"engine": engine, "modal_samples": 3, "rtol": 1e-8}
        doc["motion"]["speed"] = "30*t + 7*sin(t/2)"  # the frame turns within the short ride
        setup = pipeline.load(doc).setup.elastic
        result = elastic_scene.run(setup)
        assert result.summary["elastic"]["engine"] == engine
        _, checks, _ = elastic_review.review(setup, result)
        verdicts[engine] = {c.what: c.verdict for c in checks}
        assert result.summary["elastic"]["energy_residual_relative"] < 10 * 1e-8
    assert verdicts["compiled"] == verdicts["python"] and "fail" not in verdicts["compiled"].values()


def test_the_frame_table_meets_its_bound_between_its_nodes():
    """At 400 random times the spline is within 4x its midpoint error of the exact channels, which is at most
    the bound (1e-3 rtol) where the exact frame is smooth; case 2's second differences of Λ* (step 1e-3 m)
    carry ~1e-10 of rounding, which no table resolves: at rtol 1e-8 the table stops on that noise, flagged,
    within INTERP_NOISE, and meets the bound at rtol 1e-6. On 20 outputs the table adds midpoints; on 400
    at rtol 1e-6 every 2^j-th output time is a node (measured j = 2) and it meets the bound at all of them."""
    from symmech.trolley.elastic import kernels as ek

    for case, rtol, noise, steps in ((1, 1e-8, False, 20), (2, 1e-6, False, 20), (2, 1e-8, True, 20),
                                     (1, 1e-6, False, 400)):
        setup = helix(t_end=1.0, steps=steps, case=case)
        table = el_frame.frame_table(setup.t, rtol, exact_channels(setup))
        assert table.noise == noise and table.bound == 1e-3 * rtol
        assert table.nodes.size > 21 if steps == 20 else set(table.nodes) < set(setup.t)
        assert table.error <= (el_frame.INTERP_NOISE if noise else table.bound)
        t = np.sort(RNG.uniform(0.0, 1.0, 400))
        exact = el_frame.channels(setup.drive, setup.system.mdl.g0, np.r_[0.0, t])[1:]
        spline = np.empty_like(exact)
        for i, ti in enumerate(t):
            ek._channels((table.nodes, table.coef), ti, spline[i])
        # with noise, the exact values at other times carry their own (measured 1.4e-9 on case 2)
        assert (np.abs(spline - exact) / el_frame._scales(exact)).max() <= 4 * (1e-9 if noise else table.error)


def kinked():
    """The bundled scene over 0.03 s at a speed 3 + 20 |t - 0.015| m/s: a kink in V0."""
    doc = copy.deepcopy(BUNDLED)
    doc["motion"]["speed"] = "3 + 20*abs(t - 0.015)"
    doc["time"] = {"t_end": 0.03, "steps": 10}
    doc["elastic"]["numerics"] = {"modal_samples": 0}
    return pipeline.load(doc).setup.elastic


def test_a_speed_with_a_kink_is_not_tabulated():
    """At the kink the spline of ω, v0 misses by O(h): halving no longer gains 16x, above INTERP_NOISE."""

    setup = kinked()
    assert el_frame.frame_table(setup.t, 1e-6, exact_channels(setup)) is None


@pytest.mark.slow
def test_a_speed_with_a_kink_falls_back_to_the_python_engine_and_says_why():
    out = elastic_scene.simulate(kinked(), rtol=1e-6)
    assert out["engine"] == "python" and "tabulated" in out["engine_reason"]


def test_the_compiled_jacobian_matches_central_differences_of_the_compiled_rhs():
    from symmech.trolley.elastic import kernels as ek

    rollers = {**BUNDLED["elastic"]["rollers"], "law": "clamped_pair", "preload": [2e-5] * 5}
    beam = {"root": [0.2, 0.3, -0.5], "axis": [0, 0, 1], "plane": [0, 1, 0], "length": 1.0, "mass_per_length": 3.0,
            "ei": [50.0, 80.0], "support": "pinned", "axial": "held", "ea": 5e6, "modes": 2}
    setup = helix(case=2, rollers=rollers, beams=[*BUNDLED["elastic"]["beams"], beam])
    system = setup.system
    table = el_frame.frame_table(setup.t, 1e-8, exact_channels(setup))
    args = (system.record, (table.nodes, table.coef), np.zeros(1))
    n = 2 * system.N + 2
    y = np.r_[RNG.normal(size=system.N) * 1e-3, RNG.normal(size=system.N) * 1e-2, 0.0, 0.0]
    y[:5] = RNG.uniform(-1e-5, 1e-5, 5)  # away from the kinks of the clamped pair (|d| = 2e-5 m)
    J = np.empty((n, n))
    ek._jac(0.07, y, args, J)
    fd = np.empty((n, n))
    plus, minus = np.empty(n), np.empty(n)
    for j in range(2 * system.N):
        h = 1e-4 * max(abs(y[j]), 1e-4)  # truncation ~h², rounding ~eps/h: 2e-9 of the largest entry here
        ek._rhs(0.07, y + h * np.eye(n)[j], args, plus)
        ek._rhs(0.07, y - h * np.eye(n)[j], args, minus)
        fd[:, j] = (plus - minus) / (2 * h)
    rows = slice(system.N, 2 * system.N)
    assert np.abs(J[rows, :2 * system.N] - fd[rows, :2 * system.N]).max() < 1e-7 * np.abs(fd[rows]).max()
    assert np.array_equal(J[:system.N, system.N:2 * system.N], np.eye(system.N))


def test_the_assembly_matches_system_evaluate_at_random_states():
    """q̈, M, ∂R/∂q, ∂R/∂q̇ and the resultants of the kernels against System.evaluate / resultants (numpy)."""
    from symmech.trolley.elastic import kernels as ek

    rollers = {**BUNDLED["elastic"]["rollers"], "law": "clamped_pair", "preload": [2e-5] * 5}
    setup = helix(rollers=rollers)
    system, mdl = setup.system, setup.system.record
    line = el_sim.Timeline(system, setup.drive, setup.t, el_frame.arc_length(setup.drive, setup.t))
    for time in (0.0, 0.07):
        fs = line.state(time)
        ch = el_frame.channels(setup.drive, system.mdl.g0, np.array([0.0, time]) if time else np.array([0.0]))[-1]
        q, qd = RNG.normal(size=system.N) * 1e-4, RNG.normal(size=system.N) * 1e-2
        qdd = system.accelerations(fs, q, qd)
        _, M, Rq, Rqd = system.evaluate(fs, q, qd, qdd, jacobian=True)
        assert relative(ek._accelerations(mdl, ch, q, qd)[0], qdd) < 1e-12
        for mine, ref in zip(ek._jacobians(mdl, ch, q, qd), (M, Rq, Rqd)):
            assert relative(mine, ref) < 1e-12


def test_the_estimate_of_a_built_engine_announces_no_compile():
    warm = pipeline.load(copy.deepcopy(BUNDLED)).estimate()
    assert "elastic model (compiled engine; auto: the compiled engine is built" in warm.what
    assert "compiling" not in warm.what


# ---------------------------------------------------------------- traction (s and V0 are states)

TRACTION = "400 + 300*sin(3*t) - 2*v**2"  # N: a varying drive against a drag quadratic in the speed


def traction_scene(t_end=0.06, steps=20, case=1, **elastic):
    """The bundled scene driven by TRACTION from 5 m/s instead of its speed."""
    doc = copy.deepcopy(BUNDLED)
    doc["time"] = {"t_end": t_end, "steps": steps}
    doc["effects"].update(local_curvature=case == 2, traction=True)
    doc["motion"] = {"traction": TRACTION, "initial_speed": 5.0}
    doc["elastic"]["numerics"] = {"modal_samples": 0}
    doc["elastic"].update(elastic)
    return pipeline.load(doc).setup.elastic


@pytest.mark.parametrize("case", [1, 2])
def test_the_traction_jacobian_matches_central_differences_of_the_compiled_rhs(case):
    """All columns (q, q̇, s, V0) of the rows of q̈ and V̇0; s and V0 enter through the geometry table's
    spline and its derivative, V0 also through P0's drag (-4 V0 N s/m)."""
    from symmech.trolley.elastic import kernels as ek

    setup = traction_scene(case=case)
    system, drive, N = setup.system, setup.drive, setup.system.N
    span = el_frame.reach(drive, partial(model.traction_acceleration, system.rigid), setup.t)
    table = el_frame.frame_table(np.linspace(*span, 21), 1e-8, lambda s, at=slice(None): el_frame.geometry(drive, s, at),
                                 scales=el_frame.geometry_scales)
    ek.TRACTIONS[0] = drive.traction
    args = (system.record, (table.nodes, table.coef), np.zeros(1), 0)
    n = 2 * N + 4
    y = np.r_[RNG.normal(size=N) * 1e-4, RNG.normal(size=N) * 1e-2, 0.0, 0.0, 0.2, 5.3]
    J = np.empty((n, n))
    ek._jac_traction(0.04, y, args, J)
    fd = np.empty((n, n))
    plus, minus = np.empty(n), np.empty(n)
    for j in range(n):
        h = 1e-4 * max(abs(y[j]), 1e-4)
        ek._rhs_traction(0.04, y + h * np.eye(n)[j], args, plus)
        ek._rhs_traction(0.04, y - h * np.eye(n)[j], args, minus)
        fd[:, j] = (plus - minus) / (2 * h)
    del ek.TRACTIONS[0]
    cols = np.r_[0:2 * N, 2 * N + 2, 2 * N + 3]
    for rows in (slice(N, 2 * N), [2 * N + 3]):
        assert np.abs(J[rows][:, cols] - fd[rows][:, cols]).max() < 1e-7 * np.abs(fd[rows][:, cols]).max()
        for col in (2 * N + 2, 2 * N + 3):  # s and V0 one by one: their entries are far smaller than those of q
            assert np.abs(J[rows, col] - fd[rows, col]).max() < 1e-6 * np.abs(fd[rows, col]).max()
    assert np.abs(fd[N:2 * N, 2 * N + 2]).max() > 0 and J[2 * N + 2, 2 * N + 3] == 1.0


def test_the_traction_slope_is_the_central_difference_of_the_documented_step():
    """P0 = sin(k V0), k = 1000 s/m: traction_force's ∂P0/∂V0 is the central difference of step
    h = 1e-6 (1 + |V0|) m/s, whose closed form is k cos(k V0) sin(k h)/(k h): at V0 = 99 m/s (h = 1e-4, 0.17 %
    under the derivative) and -0.5 m/s (h = 1.5e-6), within 1e-8 of it (the phases' rounding: ~1e-10)."""
    from symmech.trolley.elastic import kernels as ek

    k = 1000.0
    ek.TRACTIONS["probe"] = lambda t, v: math.sin(k * v)
    try:
        for v in (99.0, -0.5):
            h = 1e-6 * (1.0 + abs(v))
            p0, slope = ek.traction_force("probe", 0.3, v)
            assert p0 == math.sin(k * v)
            assert slope == pytest.approx(k * math.cos(k * v) * math.sin(k * h) / (k * h), rel=1e-8)
    finally:
        del ek.TRACTIONS["probe"]


def traction_agree(c, p, bound):
    """P0…P5 within ``bound`` of max|P|, s and V0 within ``bound`` of their largest magnitude; on both engines
    the energy balance closing to 1e-8 of the work of the track forces and P0, the x1 resultant of the state,
    equal to TRACTION at the run's t and V0."""
    assert c["engine"] == "compiled" and p["engine"] == "python"
    assert relative(c["P"], p["P"]) < bound
    for key in ("s", "V0"):
        assert relative(c[key], p[key]) < bound, key
    for run in (c, p):
        assert np.abs(elastic_scene.energy_residual(run)).max() < 1e-8 * np.abs(run["work"]).max()
        drive = 400 + 300 * np.sin(3 * run["t"]) - 2 * run["V0"] ** 2
        assert np.abs(run["P"][:, 0] - drive).max() < 1e-9 * np.abs(drive).max()


@pytest.mark.parametrize("case", [1, pytest.param(2, marks=pytest.mark.slow)])  # case 2: 20 s on the Python engine
def test_traction_agrees_with_the_python_engine_at_rtol_1e_9(case):
    """From 5 m/s on the bundled helix (measured: case 1 over 0.03 s P 2.9e-9, s 2.8e-13, V0 2.7e-11; case 2 over
    0.06 s P 1.8e-8, s 4.4e-13, V0 1.2e-11); the geometry table within its bound (case 1) or, on case 2's
    noise, within INTERP_NOISE (measured 2.8e-10)."""
    c, p = both(traction_scene(t_end=0.03 * case, steps=10 * case, case=case), 1e-9)
    traction_agree(c, p, 1e-7)
    assert c["frame_interpolation_error"] <= (1e-3 * 1e-9 if case == 1 else el_frame.INTERP_NOISE)


@pytest.mark.slow
def test_a_second_of_traction_agrees_with_the_python_engine():
    """1 s, 333 outputs, case 1 (measured: P 1.3e-8, s 5.8e-14, V0 2.7e-11)."""
    c, p = both(traction_scene(t_end=1.0, steps=333), 1e-9)
    traction_agree(c, p, 1e-7)
    assert np.ptp(c["V0"]) > 1.0


@pytest.mark.slow
def test_a_traction_run_that_leaves_its_table_falls_back_to_the_python_engine(monkeypatch):
    """A geometry table over 2 mm about s0 while the trolley runs 0.15 m: the Python engine runs, and says why."""
    setup = traction_scene(t_end=0.03, steps=10)
    monkeypatch.setattr(el_frame, "reach", lambda drive, body, t: (drive.s0 - 1e-3, drive.s0 + 1e-3))
    out = elastic_scene.simulate(setup, rtol=1e-8)
    assert out["engine"] == "python" and "left the tabulated s" in out["engine_reason"]
    assert out["s"][-1] - out["s"][0] > 0.1
