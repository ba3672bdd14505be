"""The modes of the elastic model say what they are and keep their identity.

A designed crossing: a cantilever rooted at the centre of a level circle (R = 2 m), along x1,
flapwise (plane 1, along the vertical rotation axis x2) softer than in-plane (plane 2, x3):
EI = 0.5 and 1 N m². The frame turns at Ω = V0/R; by Southwell the flapwise ω² grows as
ω0² + 1.193 Ω² and the in-plane one as ω0² + 0.193 Ω², so with the speed ramped from 0 to
6 m/s the first flapwise frequency (0.28 Hz at rest) overtakes the first in-plane one (0.40 Hz)
at Ω ≈ 1.76 rad/s. A table sorted by size swaps them there; tracked by shape, each mode_id
stays on its plane and follows the rotating cantilever's frequency (reference: the
independent Ritz solution of tests/test_trolley_elastic_modal.py).
"""
import numpy as np
import pytest

from symmech.trolley import plots
from symmech.trolley.elastic import system as el, frame as el_frame, simulate as el_sim, scene as elastic_scene, modal
from test_trolley_elastic_modal import CIRCLE, EI, L, R, RHO_A, rotating_cantilever
from trolley_util import prepared, setup

T_END, V_END, SAMPLES = 20.0, 6.0, 25


def _scene():
    data = setup(track=CIRCLE, trolley={"mass": 100.0, "com": [0.0, 0.0, 0.0], "inertia": [10.0, 20.0, 15.0, 0, 0, 0]},
                 motion={"speed": f"{V_END / T_END!r}*t"}, time={"t_end": T_END, "steps": 40},
                 effects={"gravity": False})
    data["elastic"] = {"effects": {"rollers": False},
                       "beams": [{"root": [0.0, 0.0, R], "axis": [1.0, 0.0, 0.0], "plane": [0.0, 1.0, 0.0],
                                  "length": L, "mass_per_length": RHO_A, "ei": list(EI)}],
                       "points": [{"name": "tip", "beam": 0, "xi": 1.0}],
                       "numerics": {"modal_samples": SAMPLES}}
    return data


@pytest.fixture(scope="module")
def tracked():
    st = prepared(_scene()).elastic
    r = el_sim.simulate(st.system, st.drive, st.t, st.method, 1e-4)  # the modes start Newton from r['q']
    modes = elastic_scene._modes(st, r)
    return st, r, modes, elastic_scene._modes_table(modes, st.names)


def _first_of_plane(modes, plane):
    """mode_id (0-based) dominated by the first mode of ``plane`` at the first sample."""
    k, = np.flatnonzero((modes["plane"][0] == plane) & (modes["mode_number"][0] == 1))
    return k


def test_a_crossing_keeps_each_mode_on_its_plane_and_on_the_rotating_cantilevers_curve(tracked):
    """Each tracked first mode stays on its plane (group participation 1 to 1e-9 at every
    sample: the planes are decoupled here) and equals the rotating cantilever's frequency at
    Ω = V0/R to 2e-3 (the deflection by the angular acceleration 0.15 rad/s² shifts the
    in-plane one by ~1e-4); the two curves do cross, so a table sorted by size would be off by
    up to 30 % there."""
    _, _, modes, _ = tracked
    flap, lag = _first_of_plane(modes, 1), _first_of_plane(modes, 2)
    omega = modes["V0"] / R
    for k, plane, ei, in_plane in ((flap, 1, EI[0], False), (lag, 2, EI[1], True)):
        assert np.all(modes["plane"][:, k] == plane) and np.all(modes["mode_number"][:, k] == 1)
        assert np.all(modes["beam"][:, k] == 0) and np.all(modes["dof"][:, k] == 0)
        np.testing.assert_allclose(modes["group_participation"][:, k], 1.0, atol=1e-9)
        assert np.all(modes["participation"][:, k] > 0.99)
        reference = [rotating_cantilever(ei, w, in_plane)[0] for w in omega]
        np.testing.assert_allclose(modes["f"][:, k], reference, rtol=2e-3)
    gap = modes["f"][:, flap] - modes["f"][:, lag]
    assert gap[0] < -0.1 and gap[-1] > 0.1  # Hz: flapwise below at rest, above at 6 m/s
    sorted_f = np.sort(modes["f"], axis=1)
    assert np.abs(sorted_f[:, flap] / modes["f"][:, flap] - 1).max() > 0.2
    assert modes["mac_min"].min() > 0.99


def test_the_table_and_the_campbell_plot_follow_the_identity(tracked):
    """The modes table: one row per sample and mode_id, the component text naming the plane;
    the tip's shape of the flapwise mode is along x2 only, the in-plane one along x3 only, with
    a sign that never flips along the track (phase continued from sample to sample); the
    Campbell plot draws each mode_id as one line through the tracked frequencies."""
    st, _, modes, table = tracked
    n = st.system.N
    flap, lag = _first_of_plane(modes, 1), _first_of_plane(modes, 2)
    assert table.data.shape[0] == SAMPLES * n
    np.testing.assert_array_equal(table.column("mode_id"), np.tile(np.arange(1, n + 1), SAMPLES))
    for k, name, along, across in ((flap, "beam0_plane1_mode1", 2, 3), (lag, "beam0_plane2_mode1", 3, 2)):
        rows = table.column("mode_id") == k + 1
        assert {table.text["component"][i] for i in np.flatnonzero(rows)} == {name}
        np.testing.assert_allclose(table.column("f")[rows], modes["f"][:, k], rtol=0, atol=0)
        shape = table.column(f"shape_tip_{along}")[rows]
        assert np.abs(shape).min() > 1.0 and (np.all(shape > 0) or np.all(shape < 0))
        assert np.abs(table.column(f"shape_tip_{across}")[rows]).max() < 1e-9 * np.abs(shape).max()
    fig = plots.campbell(modes)
    lines = fig.axes[0].lines
    order = np.argsort(modes["s"])
    for k in (flap, lag):
        np.testing.assert_array_equal(lines[k].get_ydata(), modes["f"][order, k])


def test_rms_shape_of_a_lone_cantilever_mode():
    """A rigid trolley with one cantilever: the shape at the tip relative to the mass-weighted
    RMS displacement √(xᴴMx/m) of the whole body (trolley 100 kg at rest, beam 2 kg) is
    |φ(L)| / √(∫ φ² ρA dx / m) for the first Ritz-converged cantilever mode: the exact mode
    φ = cosh βx − cos βx − σ (sinh βx − sin βx), βL = 1.8751, has ∫0^L φ² dx = L φ(L)² / 4."""
    st = prepared(_scene()).elastic
    system = st.system
    fs = el_frame.frame_state(st.drive.frames(np.array([0.0])), 0, 0.0, 0.0)
    q = np.zeros(system.N)
    _, _, X = system.linear_modes(fs, q, shapes=True)
    X = modal.start_phase(system.mass(q), X)  # real shapes: the largest component real
    shapes = elastic_scene._probe_shapes(system, q, system.mass(q), X)
    total = system.inv.mass
    expected = 1.0 / np.sqrt(RHO_A * L / 4 / total)
    assert np.abs(shapes[0]).max() == pytest.approx(expected, rel=1e-5)
    share = modal.participation(modal.components(system), system.mass(q), X)
    np.testing.assert_allclose(share.sum(axis=0), 1.0, rtol=1e-12)


def test_roller_modes_name_their_dofs_and_shares_of_the_closed_form():
    """Rollers alone on a straight level track, no gravity (q = 0): bounce/pitch involve u2, θ3
    only and lateral/roll/yaw u3, θ1, θ2 (the closed-form eigenproblems of
    tests/test_trolley_elastic.py). Each mode's dominant DOF lies in its own set, and the
    bounce/pitch shares equal v_a² M_aa / Σ v_b² M_bb of the closed-form eigenvectors v (M_aa:
    m and the pitch inertia about O) to 1e-9."""
    import scipy.linalg
    from test_trolley_elastic import roller_model, straight

    k, com, inertia = (1e6, 1e6, 2e6, 1.5e6, 1e6), (0.8, 0.5, 0.0), (20.0, 30.0, 25.0)
    system = el.System(roller_model(0.0, k, com=com, inertia=inertia + (0, 0, 0)))
    fs = el_sim._state_at(straight(10.0), 0.0, 0.0)
    q = np.zeros(system.N)
    omega, _, X = system.linear_modes(fs, q, shapes=True)
    comp = modal.components(system)
    share = modal.participation(comp, system.mass(q), X)
    m, c = 100.0, np.asarray(com)
    pitch_inertia = inertia[2] + m * (c @ c - c[2] ** 2)
    Mv = np.array([[m, m * c[0]], [m * c[0], pitch_inertia]])
    Kv = np.array([[k[0] + k[1] + k[2], k[2] * 2.0], [k[2] * 2.0, k[2] * 4.0]])
    w2, v = scipy.linalg.eigh(Kv, Mv)
    for j in range(2):
        mode = int(np.argmin(np.abs(omega - np.sqrt(w2[j]))))
        assert abs(omega[mode] / np.sqrt(w2[j]) - 1) < 1e-12
        weight = v[:, j] ** 2 * np.array([m, pitch_inertia])
        np.testing.assert_allclose(share[[0, 4], mode], weight / weight.sum(), rtol=1e-9)
        assert comp.dof[np.argmax(share[:, mode])] in (1, 5) and share[[1, 2, 3], mode].max() < 1e-20
    lateral = [i for i in range(5) if share[[1, 2, 3], i].sum() > 0.5]
    assert len(lateral) == 3 and all(comp.dof[np.argmax(share[:, i])] in (2, 3, 4) for i in lateral)
    assert comp.labels[:5] == ("roller_u2", "roller_u3", "roller_th1", "roller_th2", "roller_th3")


def test_track_follows_a_permutation_and_flags_shapes_it_cannot_match():
    """Synthetic samples, M = E: new vectors that are the old ones permuted and turned by
    complex phases are matched back (order = the permutation, phases undone to 1e-15); three
    shapes mixed evenly (the 3-point DFT / √3, every MAC 1/3) give a matched MAC of 1/3 and the
    scene's tracking warning, which the crossing above (MAC > 0.99) does not raise."""
    eye = np.eye(3)
    turned = eye[:, [2, 0, 1]] * np.exp(1j * np.array([0.3, -2.0, 1.1]))
    order, shapes, worst = modal.track([(eye, eye), (eye, turned)])
    np.testing.assert_array_equal(order[1], [1, 2, 0])
    np.testing.assert_allclose(shapes[1], eye, atol=1e-15)
    np.testing.assert_allclose(worst, [1.0], rtol=1e-15)
    dft = np.exp(2j * np.pi * np.outer(range(3), range(3)) / 3) / np.sqrt(3)
    _, _, worst = modal.track([(eye, eye), (eye, dft)])
    np.testing.assert_allclose(worst, [1 / 3], rtol=1e-12)
    modes = {"t": np.array([0.0, 2.0]), "mac_min": worst, "curvature_shift": np.zeros((2, 3))}
    warning, = elastic_scene._mode_warnings(modes)
    assert "between t = 0 s and 2 s (a matched MAC of 0.33)" in warning


def test_the_crossing_raises_no_mode_warning(tracked):
    assert elastic_scene._mode_warnings(tracked[2]) == []
