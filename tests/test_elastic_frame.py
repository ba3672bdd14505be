"""The frame state of the elastic trolley on a helix against the Frenet-Serret closed forms.

The track r(s) = (a sin(s/c), b s/c, a cos(s/c)), arc length s, c = √(a² + b²), axis up (X2): curvature
κ = a/c², torsion from B' = -τ N; with the Frenet frame (x1, x2, x3) = (T, N, B) and the speed V0(t), the
origin moves with v0 = V0 T, a0 = V̇0 T + V0² κ N, the frame turns with ω = V0 (τ T + κ B), ω̇ = V̇0 (τ T + κ B),
and "up" is ν = (T·X2, N·X2, B·X2)."""
import dataclasses
import sys
from functools import partial
from pathlib import Path

import numpy as np
import pytest

from symmech.trolley import model
from symmech.trolley.elastic import system as el, body as el_body, frame as el_frame, simulate as el_sim
from symmech.trolley.elastic import scene as elastic_scene

sys.path.insert(0, str(Path(__file__).parent))
from trolley_util import prepared, setup as scene_dict  # noqa: E402

pytestmark = pytest.mark.xdist_group("test_elastic_frame")

A, B = 7.0, 2.0
C = float(np.hypot(A, B))


def tnb(s):
    """T, N, B (3, 3) of the helix at s, written out."""
    u = s / C
    t = np.array([A * np.cos(u), B, -A * np.sin(u)]) / C
    n = np.array([-np.sin(u), 0.0, -np.cos(u)])
    return np.array([t, n, np.cross(t, n)])


def test_frame_state_on_a_helix_is_the_frenet_serret_motion():
    data = scene_dict(frame="frenet", track={"type": "expression", "x": f"{A}*sin(s/{C!r})", "y": f"{B}*s/{C!r}",
                                             "z": f"{A}*cos(s/{C!r})"},
                      motion={"speed": "3 + 2*t"}, time={"t_end": 1.0, "steps": 10})
    drive = elastic_scene.drive_of(prepared(data), 1)
    system = el.System(el_body.ElasticModel(100.0, (0, 0, 0), (1, 1, 1, 0, 0, 0), 2.0, 1.0, 9.81,
                                       el_body.Rollers((1e6,) * 5, (0.0,) * 5)))
    h = 1e-4
    for time, s in ((0.5, 1.3), (0.8, 4.0)):
        V, dV = 3 + 2 * time, 2.0
        frame = tnb(s)
        kappa = A / C ** 2
        tau = -(tnb(s + h)[2] - tnb(s - h)[2]) / (2 * h) @ frame[1]  # B' = -τ N
        fs = el_sim._state_at(drive, time, s)
        darboux = np.array([tau, 0.0, kappa])
        assert np.allclose(fs.v0, [V, 0, 0], rtol=0, atol=1e-9)
        assert np.allclose(fs.a0, [dV, V ** 2 * kappa, 0], rtol=0, atol=1e-7)
        assert np.allclose(fs.w, V * darboux, rtol=0, atol=1e-8)
        assert np.allclose(fs.dw, dV * darboux, rtol=0, atol=1e-7)
        assert np.allclose(fs.nu, frame[:, 1], rtol=0, atol=1e-9)
        # the vectorised frame_motion gives the same rows
        fr = drive.frames(np.array([s, s]))
        v0, a0, w, dw = el_frame.frame_motion(fr, np.array([V, 2 * V]), np.array([dV, 0.0]))
        assert np.allclose(v0, [[V, 0, 0], [2 * V, 0, 0]], rtol=0, atol=1e-9)
        assert np.allclose(a0, [[dV, V ** 2 * kappa, 0], [0, 4 * V ** 2 * kappa, 0]], rtol=0, atol=1e-7)
        assert np.allclose(w, [V * darboux, 2 * V * darboux], rtol=0, atol=1e-8)
        assert np.allclose(dw, [dV * darboux, 0 * darboux], rtol=0, atol=1e-7)
        # the compiled engine's channels: load a0 + g0 ν, ω, ω̇, v0, row by row
        channels = el_frame.frame_channels(fr, np.array([V, 2 * V]), np.array([dV, 0.0]), 9.81)
        expected = [[dV, V ** 2 * kappa, 0, *V * darboux, *dV * darboux, V, 0, 0],
                    [0, 4 * V ** 2 * kappa, 0, *2 * V * darboux, 0, 0, 0, 2 * V, 0, 0]]
        expected = np.array(expected) + np.r_[9.81 * frame[:, 1], np.zeros(9)]
        assert channels.shape == (2, 12)
        assert np.allclose(channels, expected, rtol=0, atol=1e-7)
    # over a run: the arc length s0 + 3 t + t² (Gauss-Legendre is exact on a polynomial), the channels at t[at],
    # the geometry per arc length (e = T, e' + Ω × e = κ N, ν, Ω = (τ, 0, κ), Ω' = 0 on a helix) and the table of a
    # run at a prescribed speed (its output times, the channels there, V0 and dV0)
    t = np.array([0.0, 0.25, 0.6, 1.0])
    s = drive.s0 + 3 * t + t ** 2
    taus = [-(tnb(x + h)[2] - tnb(x - h)[2]) / (2 * h) @ tnb(x)[1] for x in s]
    V, dV = 3 + 2 * t, np.full(t.size, 2.0)
    rows = np.array([[d, v * v * kappa, 0, v * tau, 0, v * kappa, d * tau, 0, d * kappa, v, 0, 0]
                     for v, d, tau in zip(V, dV, taus)])
    rows[:, :3] += 9.81 * np.array([tnb(x)[:, 1] for x in s])
    assert np.abs(el_frame.arc_length(drive, t) - s).max() < 1e-12
    assert np.allclose(el_frame.channels(drive, system.mdl.g0, t, slice(1, 3)), rows[1:3], rtol=0, atol=1e-7)
    geometry = el_frame.geometry(drive, s, slice(2, None))
    assert geometry.shape == (2, 15)
    assert np.allclose(geometry, [[1, 0, 0, 0, kappa, 0, *tnb(x)[:, 1], tau, 0, kappa, 0, 0, 0]
                                  for x, tau in zip(s[2:], taus[2:])], rtol=0, atol=1e-7)
    handed = []  # the arc lengths the frame is evaluated at: the outputs' once, as the table's seed too
    counted = dataclasses.replace(drive, frames=lambda x: handed.append(np.array(x)) or drive.frames(x))
    table = el_frame.tabulation(counted, system.mdl.g0, t, 1e-6)
    assert sum(np.array_equal(x, el_frame.arc_length(drive, t)) for x in handed) == 1
    assert table.seed is t and table.span == ()
    assert np.allclose(table.exact, rows, rtol=0, atol=1e-7)
    assert np.array_equal(table.at_outputs[1], V) and np.array_equal(table.at_outputs[2], dV)
    assert np.allclose(table.evaluate(t, slice(0, 2)), rows[:2], rtol=0, atol=1e-7)


def test_frame_turning_rate_follows_the_change_of_curvature():
    """A horizontal ellipse (curvature varying along s): ω̇ = V̇0 W + V0² dW/ds, dW/ds by central differences of
    ω/V0 along the track (frame_state and the vectorised frame_motion)."""
    data = scene_dict(frame="frenet", track={"type": "expression", "x": "6*sin(u)", "y": "0", "z": "3*cos(u)",
                                             "parameter": "u", "u_range": [0.0, 6.0]},
                      motion={"speed": "3 + 2*t"}, time={"t_end": 1.0, "steps": 10})
    drive = elastic_scene.drive_of(prepared(data), 1)
    time, s, h = 0.5, 2.0, 1e-4
    V, dV = 4.0, 2.0
    turn = [el_sim._state_at(drive, time, x).w / V for x in (s - h, s, s + h)]
    dW = (turn[2] - turn[0]) / (2 * h)
    assert np.abs(dW).max() > 0.01  # the curvature changes here (V0² dW ≈ 0.2 rad/s²)
    expected = dV * turn[1] + V ** 2 * dW
    assert np.allclose(el_sim._state_at(drive, time, s).dw, expected, rtol=0, atol=1e-6)
    fr = drive.frames(np.array([s]))
    assert np.allclose(el_frame.frame_motion(fr, np.array([V]), np.array([dV]))[3], [expected], rtol=0, atol=1e-6)


def test_case_two_moves_the_frame_of_the_chord_between_the_axles():
    """With local curvature (case 2) the frame is the rigid model's chord frame for the trolley's axle distance,
    difference order and step; on the ellipse it differs from the tangent frame of case 1."""
    data = scene_dict(frame="frenet", track={"type": "expression", "x": "6*sin(u)", "y": "0", "z": "3*cos(u)",
                                             "parameter": "u", "u_range": [0.0, 6.0]},
                      motion={"speed": "3 + 2*t"}, time={"t_end": 1.0, "steps": 10})
    setup = prepared(data)
    l = 1.5
    setup.body = dataclasses.replace(setup.body, l=l)
    drive = elastic_scene.drive_of(setup, 2)
    s = np.array([2.0, 3.5])
    chord = model.local_curvature_frame(setup.track, s, l, "frenet", setup.fd_order, setup.fd_step, plan=setup.plan)
    tangent = elastic_scene.drive_of(setup, 1).frames(s)
    assert np.abs(chord.W - tangent.W).max() > 1e-3
    fs = el_sim._state_at(drive, 0.5, s[1])  # V0 = 4 m/s
    for got, ref in ((fs.v0, 4.0 * chord.e[1]), (fs.w, 4.0 * chord.W[1]), (fs.nu, chord.lam[1, :, 1])):
        assert np.allclose(got, ref, rtol=0, atol=1e-12)


def test_frame_keeps_its_plan_through_a_straight_point():
    """A horizontal sine x3 = sin(x1) is straight at x1 = 0 and π (no Frenet frame): the scene's frame plan turns it
    into the rotation-minimising frame started from the upward normal, which stays up on a level track, ν = x2, in
    both cases (Frenet's ν would be ±x3, flipping at the inflection)."""
    data = scene_dict(frame="frenet", track={"type": "expression", "x": "u", "y": "0", "z": "sin(u)",
                                             "parameter": "u", "u_range": [0.0, 6.0]},
                      motion={"speed": "3"}, time={"t_end": 1.0, "steps": 10})
    setup = prepared(data)
    for case in (1, 2):
        drive = elastic_scene.drive_of(setup, case)
        for s in (1.0, 5.0, 6.5):
            assert np.allclose(el_sim._state_at(drive, 0.0, s).nu, [0.0, 1.0, 0.0], rtol=0, atol=1e-9)


def _level_traction(traction: str, t_end: float, steps: int, initial_speed: float = 5.0):
    """A 100 kg trolley on a straight level track under the traction P0(t, v) [N] from initial_speed [m/s]: the prepared scene,
    its drive and the elastic model (its rigid body: 100 kg)."""
    data = scene_dict(trolley={"mass": 100.0, "com": [0.8, 0.5, 0.0], "inertia": [10.0, 20.0, 15.0, 0, 0, 0]},
                      effects={"gravity": True, "local_curvature": False, "traction": True},
                      motion={"traction": traction, "initial_speed": initial_speed}, time={"t_end": t_end, "steps": steps})
    st = prepared(data)
    mdl = el_body.ElasticModel(100.0, (0.8, 0.5, 0.0), (10.0, 20.0, 15.0, 0, 0, 0), 2.0, 1.0, 9.81,
                               el_body.Rollers((1e8,) * 5, (2e3,) * 5))
    return st, elastic_scene.drive_of(st, 1), mdl

def test_traction_reach_is_the_rigid_run_widened_by_a_tenth_of_its_span():
    """P0 = 200 + 100 t N on 100 kg from 5 m/s on a straight level track: s = 5 t + (100 t² + 50 t³/3)/100 (Newton),
    0 to 15.333 m over 2 s; a traction run's table spans that, widened by a tenth of it on each side (within the
    frame plan's span), with 16 arc lengths, where e = (1, 0, 0), no curvature, ν = (0, 1, 0), no turning."""
    st, drive, mdl = _level_traction("200 + 100*t", t_end=2.0, steps=10)
    end = 5.0 * 2.0 + (100 * 4.0 + 50 * 8.0 / 3) / 100.0
    plan = drive.frames.plan.span  # +-20 km: it leaves the span alone
    table = el_frame.tabulation(drive, mdl.g0, st.t, 1e-6, partial(model.traction_acceleration, el_body.rigid_body(mdl)))
    assert table.span == pytest.approx((max(-0.1 * end, plan[0]), min(1.1 * end, plan[1])), rel=1e-6, abs=1e-9)
    assert np.array_equal(table.seed, np.linspace(*table.span, 16)) and table.exact is None
    assert np.allclose(table.evaluate(table.seed, slice(3, 5)), [[1, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0]] * 2,
                       rtol=0, atol=1e-12)


def test_traction_reach_sees_a_turn_between_two_outputs():
    """P0 = -50 - 50 v N on 100 kg from 1 m/s on a straight level track: v = -1 + 2 exp(-t/2), s = -t + 4 (1 -
    exp(-t/2)) (Newton) turns back at t = 2 ln 2 s, s = 2 - 2 ln 2 m, between the outputs at 1 and 2 s; the table
    spans 0 to that widened by a tenth of it on each side (0.1 of 0.61 m: more than the 1 mm floor), not the
    outputs' 0 to s(1) = 0.574 m. The compiled run's own check puts a turn where the speed's linear interpolation
    does: exact under a constant deceleration (s = 5 t - t²/2 turns at 12.5 m between 10/3 and 20/3 s)."""
    from symmech.trolley.elastic import compiled as el_compiled

    st, drive, mdl = _level_traction("-50 - 50*v", t_end=3.0, steps=3, initial_speed=1.0)
    assert np.allclose(st.t, [0, 1, 2, 3], rtol=0, atol=1e-12)
    top = 2 - 2 * np.log(2)
    lo, hi = el_frame.reach(drive, partial(model.traction_acceleration, el_body.rigid_body(mdl)), st.t)
    assert (lo, hi) == pytest.approx((-0.1 * top, 1.1 * top), rel=0, abs=1e-5)
    t = np.array([0, 10 / 3, 20 / 3, 10])
    assert el_compiled.turning_points(t, 5 * t - t ** 2 / 2, 5.0 - t) == pytest.approx([12.5], rel=1e-12)
    assert el_compiled.turning_points(t, t, np.ones(4)).size == 0


def test_geometry_error_scales_add_the_turning_rate_where_it_enters_beside():
    """Two rows of geometry channels written out: |e| = 1, |e' + Ω × e| = 0.5 (then 0.3), |ν| = 1, |Ω| = 2 (then
    1), |Ω'| = 1 (then 3) 1/m²: the scales are each group's largest norm, e' + Ω × e against 0.5 + 2 = 2.5 (it enters
    a0 beside Ω, per V0²) and Ω' against 3 + 2² = 7 (it enters ω̇ beside Ω²), three columns a group."""
    g = np.zeros((2, 15))
    g[:, 0:3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]          # e
    g[:, 3:6] = [[0.3, 0.4, 0.0], [0.0, 0.0, 0.3]]          # e' + Ω × e
    g[:, 6:9] = [[0.0, 1.0, 0.0], [0.0, 0.0, -1.0]]         # ν
    g[:, 9:12] = [[0.0, 0.0, 2.0], [1.0, 0.0, 0.0]]         # Ω
    g[:, 12:15] = [[0.6, 0.8, 0.0], [0.0, -3.0, 0.0]]       # Ω'
    np.testing.assert_array_equal(el_frame.geometry_scales(g), np.repeat([1.0, 2.5, 1.0, 2.0, 7.0], 3))


def test_a_frame_table_whose_error_equals_its_bound_meets_it():
    """Channels zero at nine output times but one, d, at the second: the spline through every 2nd or 4th of them
    is zero, so its error at the times it skips is d / scale (scale 1); with d exactly the bound max(1e-3 rtol,
    1e-13) the bound is met (≤, as between the halving rounds' nodes), and the coarsest such spline, through t[::4],
    is the table, with no further evaluation of the frame."""
    t = np.linspace(0.0, 1.0, 9)
    rtol = 1e-3
    bound = max(el_frame.INTERP_FRACTION * rtol, el_frame.INTERP_FLOOR)
    ch = np.zeros((9, 2))
    ch[1, 0] = bound

    calls = []

    def evaluate(x, at=slice(None)):  # the frame between the outputs: zero there
        calls.append(x)
        return np.zeros((np.asarray(x)[at].size, 2))

    table = el_frame.frame_table(t, rtol, evaluate, ch, scales=lambda c: np.ones(c.shape[1]))
    assert not calls
    np.testing.assert_array_equal(table.nodes, t[::4])
    assert table.error == table.bound == bound and not table.noise
    # seven zero channels at the integer times 0..6: every 4th of them (and the last) meets any bound, 2 k = 8 = 7 + 1
    # nodes being enough for k = 4; the nodes are float times, as the kernels read them
    coarse = el_frame.frame_table(np.arange(7), rtol, evaluate, np.zeros((7, 2)), scales=lambda c: np.ones(c.shape[1]))
    assert coarse.nodes.dtype == np.float64 and np.array_equal(coarse.nodes, [0.0, 4.0, 6.0]) and not calls


def test_a_frame_table_halved_once_to_its_bound_meets_it():
    """Two outputs with zero channels (no coarser spline to try): the straight spline between them is zero, and the
    exact channels at the midpoint are the bound itself, which meets it: the two outputs are the table."""
    rtol = 1e-3
    bound = max(el_frame.INTERP_FRACTION * rtol, el_frame.INTERP_FLOOR)

    def evaluate(x, at=slice(None)):
        return np.full((np.asarray(x)[at].size, 2), bound)

    table = el_frame.frame_table(np.array([0.0, 1.0]), rtol, evaluate, np.zeros((2, 2)),
                                 scales=lambda c: np.ones(c.shape[1]))
    np.testing.assert_array_equal(table.nodes, [0.0, 1.0])
    assert table.error == table.bound == bound and not table.noise


def test_a_frame_table_of_noise_gives_up_after_its_stall_rounds():
    """Channels of noise of unit amplitude (unit scale) between two outputs: no halving gains 4x, so after the first
    round (the best so far) the table gives up once STALL_ROUNDS more rounds did not; noise far above INTERP_NOISE
    makes no table (None)."""
    rng = np.random.default_rng(3)
    rounds = []

    def evaluate(x, at=slice(None)):
        rounds.append(np.asarray(x)[at].size)
        return rng.uniform(-1.0, 1.0, (np.asarray(x)[at].size, 2))

    table = el_frame.frame_table(np.array([0.0, 1.0]), 1e-3, evaluate, rng.uniform(-1.0, 1.0, (2, 2)),
                                 scales=lambda c: np.ones(c.shape[1]))
    assert table is None and rounds == [1, 2, 4][:1 + el_frame.STALL_ROUNDS]
