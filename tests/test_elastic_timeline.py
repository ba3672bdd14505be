"""The elastic trolley's timeline: arc length s(t), the frame state at t, and the traction steps, in closed form.

On the catenary with a twist of tests/test_trolley_elastic_kind.py at the speed V0 = 8 + 3 sin t the arc length is
s = s0 + 8 t + 3 (1 - cos t); with traction the frame's x1 balance F1 = P0(t, V0) and the equations of motion hold
together, checked by the explicit point cloud of tests/test_elastic_energies.py (sums over weighted points), and the
start carries the whole body's acceleration P0/m - g0 dy/ds (the catenary's slope dy/ds = s/√(400 + s²))."""
import dataclasses
import sys
from functools import partial
from pathlib import Path

import numpy as np
import pytest

from symmech.core.context import Context
from symmech.core.scene import SymmechError
from symmech.trolley import model as trolley_model
from symmech.trolley.elastic import body as el_body, system as el, frame as el_frame, simulate as el_sim
from symmech.trolley.elastic import compiled as el_compiled, scene as elastic_scene

sys.path.insert(0, str(Path(__file__).parent))
from test_elastic_energies import G0, cloud, model, resultants_of_cloud  # noqa: E402
from test_elastic_residual import C_ROLL, elastic_forces, virtual_work  # noqa: E402
from test_trolley_elastic_kind import CATENARY  # noqa: E402
from trolley_util import prepared  # noqa: E402

pytestmark = pytest.mark.xdist_group("test_elastic_timeline")

S0 = 2.5
GRID = np.array([0.0, 0.3, 1.0, 2.2, 4.0])


def arc(t):
    return S0 + 8.0 * t + 3.0 * (1.0 - np.cos(t))


@pytest.fixture(scope="module")
def drive():
    return dataclasses.replace(elastic_scene.drive_of(prepared(CATENARY), 1), s0=S0)


@pytest.fixture(scope="module")
def system():
    return el.System(model(damping=C_ROLL))


def test_arc_length_on_an_uneven_grid_is_the_integral_of_the_speed(drive):
    assert np.abs(el_frame.arc_length(drive, GRID) - arc(GRID)).max() < 1e-12
    steady = dataclasses.replace(drive, speed=lambda t: (5.0, 0.0))  # a scalar speed for the whole grid
    assert np.abs(el_frame.arc_length(steady, GRID) - (S0 + 5.0 * GRID)).max() < 1e-13


def test_timeline_arc_length_between_on_and_beyond_the_nodes(drive):
    line = el_sim.Timeline(None, drive, GRID, el_frame.arc_length(drive, GRID))
    for time in (0.0, 0.15, 0.3, 0.65, 1.0, 3.1, 4.0, 5.5):
        assert line.s(time) == pytest.approx(arc(time), abs=1e-12), time


def test_timeline_states_are_the_frames_at_the_arc_length_and_speed(drive, system):
    line = el_sim.Timeline(system, drive, GRID, el_frame.arc_length(drive, GRID))
    fr = drive.frames(arc(np.linspace(0.0, 4.0, 200)))
    kept = 0
    for i, time in enumerate(np.linspace(0.0, 4.0, 200)):  # more times than the cache keeps
        fs = line.state(time)
        expected = el_frame.frame_state(fr, i, 8.0 + 3.0 * np.sin(time), 3.0 * np.cos(time))
        for key in ("v0", "a0", "w", "dw", "nu"):
            assert np.abs(getattr(fs, key) - getattr(expected, key)).max() < 1e-9, (time, key)
        assert line.state(time) is fs  # an implicit step's stage times are revisited: cached
        kept = max(kept, len(line.cache))
    assert kept == 65  # the last 65 states, then cleared


def traction_drive(drive):
    """The catenary driven by P0 = 200 + 50 t - 3 V0 [N] from 6 m/s at S0."""
    return dataclasses.replace(drive, speed=None, traction=lambda t, V0: 200.0 + 50.0 * t - 3.0 * V0, v_initial=6.0)


@pytest.mark.parametrize("case", [1, 2])
def test_traction_states_differ_by_a_unit_rate_along_the_tangent(drive, system, case):
    """Case 2 moves the chord frame of the axle distance l (tests/test_elastic_frame.py)."""
    drive = dataclasses.replace(drive, frames=dataclasses.replace(drive.frames, local_curvature=case == 2))
    line = el_sim.Timeline(system, traction_drive(drive), GRID, None)
    assert line.s_nodes is None
    for s, V0 in ((3.0, 6.0), (9.0, 11.0)):
        fs0, fs1 = line.traction_states(s, V0)
        fr = drive.frames(s)
        for fs, rate in ((fs0, 0.0), (fs1, 1.0)):
            expected = el_frame.frame_state(fr, 0, V0, rate)
            for key in ("v0", "a0", "w", "dw", "nu"):
                assert np.abs(getattr(fs, key) - getattr(expected, key)).max() < 1e-12, key
        assert np.abs(fs1.a0 - fs0.a0 - fs0.v0 / V0).max() < 1e-12  # ∂a0/∂V̇0 = e, the tangent
    for s in np.linspace(1.0, 30.0, 70 if case == 1 else 0):  # more arc lengths than the cache keeps
        line.traction_states(s, 6.0)
        assert len(line.cache) <= 65


def test_traction_step_solves_the_motion_with_the_traction_balance(drive, system):
    """q̈ and V̇0 make the cloud's d'Alembert forces balance the elastic ones, and its x1 resultant the traction."""
    body = cloud(system.mdl)
    tdrive = traction_drive(drive)
    line = el_sim.Timeline(system, tdrive, GRID, None)
    rng = np.random.default_rng(5)
    N = system.N
    for time, s, V0 in ((0.4, 4.0, 6.5), (1.7, 12.0, 9.0)):
        q = rng.normal(size=N) * np.r_[np.full(5, 1e-2), np.full(N - 5, 0.1)]
        qd = rng.normal(size=N)
        y = np.r_[q, qd, 1.0, 2.0, s, V0]
        fs, qdd, dv = line.traction_step(time, y)
        expected = el_frame.frame_state(drive.frames(s), 0, V0, dv)
        for key in ("v0", "a0", "w", "dw", "nu"):
            assert np.abs(getattr(fs, key) - getattr(expected, key)).max() < 1e-12, key
        forces = elastic_forces(q, qd)
        scale = np.abs(virtual_work(body, fs, q, qd, 0 * q)).max() + np.abs(forces).max()
        assert np.abs(virtual_work(body, fs, q, qd, qdd) + forces).max() < 1e-9 * scale
        F, _ = resultants_of_cloud(body, fs, q, qd, qdd)
        assert F[0] == pytest.approx(200.0 + 50.0 * time - 3.0 * V0, abs=1e-9 * np.abs(F).max())
        assert abs(dv) > 0.1


def test_traction_start_carries_the_whole_bodys_acceleration(drive, system):
    """q at rest relative to the frame at S0, 6 m/s, under V̇0 = P0(t0, 6)/m - g0 dy/ds."""
    tdrive = traction_drive(drive)
    line = el_sim.Timeline(system, tdrive, GRID, None)
    t0 = 0.8
    q = el_sim.traction_start(line, t0)
    mass = system.mdl.mass + system.mdl.beams[0].rho_a * system.mdl.beams[0].length + system.mdl.beams[0].tip_mass
    dv = (200.0 + 50.0 * t0 - 18.0) / mass - G0 * S0 / np.sqrt(400.0 + S0 ** 2)
    fs = el_frame.frame_state(drive.frames(S0), 0, 6.0, dv)
    body = cloud(system.mdl)
    zero = np.zeros(system.N)
    forces = elastic_forces(q, zero)
    scale = np.abs(virtual_work(body, fs, zero, zero, zero)).max()
    assert np.abs(virtual_work(body, fs, q, zero, zero) + forces).max() < 1e-9 * scale
    assert np.abs(q).max() > 1e-5


def test_timeline_integrates_from_the_last_node_only(drive):
    """At V0 = 8 + 3 sin(3.5 t) on nodes 1 s apart the 8-point Gauss rule over one interval is exact to 3e-14,
    over two (from the node before) only to 3e-9: s(t) = s0 + 8 t + (3/3.5)(1 - cos 3.5 t) to 1e-12."""
    om = 3.5
    fast = dataclasses.replace(drive, speed=lambda t: (8.0 + 3.0 * np.sin(om * t), 3.0 * om * np.cos(om * t)))
    line = el_sim.Timeline(None, fast, np.arange(5.0), el_frame.arc_length(fast, np.arange(5.0)))
    for time in np.linspace(0.05, 4.5, 37):
        assert line.s(time) == pytest.approx(S0 + 8.0 * time + 3.0 / om * (1.0 - np.cos(om * time)), abs=1e-12)


@pytest.mark.slow  # imports numba and the elastic kernels (nothing compiles)
def test_a_compiled_run_reads_entries_typed_as_its_calls():
    """The entries the elastic engine compiles and caches, written out as numba types: the model record, then
    C-contiguous float64 arrays (1-D vectors, 2-D rows and channels, the 3-D spline coefficients), the tolerance and
    the traction's time step as float64 and its key as int64, in the order solve, rows and solve_traction take them."""
    import numba

    from symmech.trolley.elastic import kernels as ek
    from symmech.trolley.elastic.layout import MODEL

    f8, vec, mat, cube = numba.float64, numba.float64[::1], numba.float64[:, ::1], numba.float64[:, :, ::1]
    table, record = numba.types.Tuple((vec, cube)), MODEL.numba_type()
    assert el_compiled.ENGINE.entries() == {ek.solve: (record, table, vec, vec, f8, vec),
                                           ek.rows: (record, mat, mat, vec, mat),
                                           ek.solve_traction: (record, table, numba.int64, vec, vec, f8, vec, f8)}


def test_a_compiled_run_reads_the_start_record_and_table_of_the_run(drive, system):
    """The inputs of a compiled run at atol_q = 1e-7: the start's tolerances as documented (1e-7 on q, 1e-4 on q̇,
    1e-9 J on E_d), its q the quasi-static q at t[0] plus the given offsets, the model's record, and at the prescribed
    speed a table seeded at the output times whose channels are those at the arc length s0 + 8 t + 3 (1 - cos t)."""
    dq0 = np.linspace(1e-4, 2e-4, system.N)
    inputs = el_compiled.compiled_inputs(system, drive, GRID, 1e-2, 1e-7, dq0=dq0)  # a coarse table: not its test
    state = inputs.start.state
    np.testing.assert_array_equal(inputs.start.atol[state.slice("q")], 1e-7)
    np.testing.assert_allclose(inputs.start.atol[state.slice("qd")], 1e-4, rtol=1e-15)
    assert inputs.start.atol[state.slots.dissipated] == 1e-9
    quasi = system.quasi_static(inputs.start.line.state(GRID[0]))
    np.testing.assert_allclose(inputs.start.y0[state.slice("q")], quasi + dq0, rtol=0, atol=1e-15)
    assert inputs.record is system.record and inputs.frame.seed is GRID
    np.testing.assert_allclose(inputs.frame.at_outputs[0].lam, drive.frames(arc(GRID)).lam,
                               rtol=0, atol=1e-12)
    # with traction the table is in s over the span frame.reach gives the whole body's rigid body (mass, centre and
    # inertia of trolley, beam and tip: tests/test_elastic_frame.py holds reach to Newton), cut at the track's end
    tdrive = traction_drive(drive)
    traction = el_compiled.compiled_inputs(system, tdrive, GRID, 1e-2, 1e-7)
    start, span = traction.start, traction.frame.span
    assert start.atol[start.state.offset("s")] == start.atol[start.state.offset("speed")] == 1e-10  # as documented
    whole = partial(trolley_model.traction_acceleration, el_body.rigid_body(system.mdl))
    assert span == el_frame.reach(tdrive, whole, GRID) and span[0] < S0 < span[1] == drive.frames.plan.span[1]


def test_the_python_engine_stops_at_the_runs_time_budget(drive, system):
    """A run whose budget is spent (--max-time 0 s) stops at its first right-hand side, in one line that says where."""
    with Context(quiet=True, max_time=0.0).active():
        with pytest.raises(SymmechError) as err:
            el_sim.simulate(system, drive, GRID)
    assert str(err.value).endswith("over the time budget --max-time 0 s (elastic model, Python engine at t = 0 s); "
                                   "raise --max-time to go on")
