"""Frames that flipped silently, noisy point tables, twist with Frenet, NaN speed."""
import math

import numpy as np
import pytest

from symmech.core.scene import SceneError
from trolley_util import compute, prepared, setup

G = 9.80665


def _continuous(lam, W, s):
    """Neighbouring frames turn by no more than their angular velocity predicts (x 1.5)."""
    rel = lam[1:] @ np.swapaxes(lam[:-1], 1, 2)
    turn = np.arccos(np.clip((np.trace(rel, axis1=1, axis2=2) - 1) / 2, -1, 1))
    rate = np.linalg.norm(W, axis=1)
    return np.all(turn <= 1.5 * np.diff(s) * np.maximum(rate[1:], rate[:-1]) + 1e-9)


def test_twist_frame_through_a_vertical_tangent_between_samples_stays_upright():
    """Vertical loop R = 8 m at 5 m/s; the vertical tangent (s = 4π m) falls between samples.
    The aircraft angles roll the frame by 180°; the plan rolls it back, so the rider keeps
    n2 = v²/(g R) + cos(s/R) all round (it changed sign beyond the vertical before)."""
    r0, v = 8.0, 5.0
    loop = {"type": "expression", "x": f"{r0}*sin(s/{r0})", "y": f"{r0} - {r0}*cos(s/{r0})", "z": "0"}
    st, res = compute(setup(track=loop, motion={"speed": str(v)}, time={"t_end": 4.0, "steps": 7}))
    report = st.plan.report()
    assert report["discontinuities_resolved"] == 1
    event = report["events"][0]
    assert event["s"] == pytest.approx(4 * math.pi, abs=0.02) and abs(event["roll_deg"]) == pytest.approx(180, abs=1e-6)
    s = res[1]["s"]
    np.testing.assert_allclose(res[1]["overload"][:, 1], v**2 / (G * r0) + np.cos(s / r0), atol=1e-9)
    assert _continuous(res[1]["lam"], res[1]["omega"] / v, s)


def test_frenet_frame_at_an_inflection_between_coarse_samples_is_continued():
    """S curve z = 0.2 u³ sampled every 2.5 m: the inflection falls between samples; before, the
    principal normal flipped silently there (a2 jumped sign; normals of neighbours at -0.79)."""
    track = {"type": "expression", "parameter": "u", "x": "u", "y": "0", "z": "0.2*u**3", "u_range": [-3.0, 3.0]}
    base = setup(track=track, motion={"speed": "1", "s0": 1.0}, time={"t_end": 10.0, "steps": 4},
                 effects={"gravity": False})
    st, res = compute({**base, "frame": "frenet"})
    events = st.plan.report()["events"]
    assert [e["kind"] for e in events] == ["inflection (principal normal reverses)"]
    assert events[0]["s"] == pytest.approx(6.71843, abs=1e-4)
    _, twist = compute(base)
    a2, a3 = res[1]["a"][:, 1], twist[1]["a"][:, 2]
    np.testing.assert_allclose(a2, np.sign(a2[0] * a3[0]) * a3, atol=1e-9)
    n = res[1]["lam"][:, 1]
    assert np.all((n[1:] * n[:-1]).sum(1) > 0)


def test_near_straight_track_gets_a_rotation_minimising_frame_not_a_spinning_frenet_frame():
    """A 1 µm corkscrew on a straight line: the Frenet normal spins once per 2π m; the frame
    used keeps x2 up (rotation-minimising from the upward normal) and says so."""
    track = {"type": "expression", "x": "s", "y": "1e-6*cos(s)", "z": "1e-6*sin(s)"}
    st, res = compute(setup(track=track, frame="frenet", trolley={"com": [1.0, 0.5, 0.0]}))
    report = st.plan.report()
    assert report["mode"] == "rotation-minimising" and "upward normal" in report["events"][0]["action"]
    np.testing.assert_allclose(res[1]["lam"][:, 1], np.broadcast_to([0, 1, 0], (21, 3)), atol=1e-5)
    # Static weight shares of a straight track (as test_straight_track_reactions_are_static_weight_shares).
    w = 100.0 * G
    np.testing.assert_allclose(res[1]["P"][:, 3], w * 0.5, rtol=1e-4)


def test_bundled_tracks_have_continuous_frames():
    from badinput import bundled

    for name, mode in (("trolley_helix", "frenet"), ("trolley_table_hill", "twist")):
        st = prepared(bundled(name))
        report = st.plan.report()
        assert report["mode"] == mode and report["discontinuities_resolved"] == 0 and report["samples_checked"] >= 201


def _noisy_circle(noise, seed=1):
    radius = 30.0
    ang = np.arange(0.0, 2.0, 1 / radius)
    pts = np.stack([radius * np.sin(ang), 0 * ang, radius - radius * np.cos(ang)], 1)
    return radius, (pts + np.random.default_rng(seed).normal(scale=noise, size=pts.shape)).tolist()


@pytest.mark.parametrize("smoothing, max_error, warned", [(0.0, None, True), (0.035, 0.01, False)])
def test_noisy_table_is_smoothed_or_warned(smoothing, max_error, warned):
    """A circle R = 30 m measured every 1 m with 1 cm noise; a3 = v²/R = 3.33 m/s² exactly.
    Interpolated, the peak lateral acceleration is off by > 100 % (before: no warning)."""
    radius, pts = _noisy_circle(0.01)
    v = 10.0
    st, res = compute(setup(track={"type": "table", "points": pts, "smoothing": smoothing},
                            motion={"speed": str(v), "s0": 5.0}, time={"t_end": 4.0, "steps": 200},
                            effects={"gravity": False}))
    err = abs(np.abs(res[1]["a"][:, 2]).max() / (v**2 / radius) - 1)
    assert st.track.noise["point_noise_m"] == pytest.approx(0.01, rel=0.3)
    assert any("dominated by noise" in n for n in st.notes) == warned
    if warned:  # the curvature error as a percentage of the largest curvature
        noise = st.track.noise
        percent = 100 * noise["curvature_error_per_m"] / noise["curvature_max_per_m"]
        assert f"({percent:.0f} %)" in next(n for n in st.notes if "dominated by noise" in n)
    if max_error is None:
        assert err > 1.0
    else:
        assert err < max_error


def test_twist_with_frenet_frame_is_refused():
    data = setup(frame="frenet", track={"type": "helix", "radius": 7.0, "rise": 0.8, "twist": "0.1*s"})
    with pytest.raises(SceneError, match="cannot be honoured") as info:
        prepared(data)
    assert info.value.field == "track.twist"


def test_nan_speed_names_the_speed_field_and_time():
    """sqrt(5 - t) is complex beyond t = 5 s (before: "the track curls back")."""
    with pytest.raises(SceneError) as info:
        prepared(setup(motion={"speed": "sqrt(5 - t)"}, time={"t_end": 10.0, "steps": 100}))
    assert info.value.field == "motion.speed"
    assert "t = 5 s" in str(info.value)


def test_docs_say_what_a2_is():
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "docs" / "scenes-trolley.md").read_text()
    assert "normal acceleration of O is κ V0 instead of κ V0² (at t = 10 s: a2" not in text
    assert "a2 is\n   the x2 component of the acceleration of the centre of mass" in text


def test_docs_field_tables_are_generated_from_the_schema():
    from pathlib import Path

    from symmech.core.schema import markdown
    from symmech.trolley.schema import SCHEMA

    text = (Path(__file__).resolve().parents[1] / "docs" / "scenes-trolley.md").read_text()
    assert "<!-- schema:begin -->\n" + markdown(SCHEMA) + "\n<!-- schema:end -->" in text


def test_curvature_jump_in_a_table_is_measured_and_warned():
    """Straight line then a circular arc R = 30 m, exact points 1 m apart: the quintic fit
    overshoots the arc's curvature by 8.9 % (a3 peaks at 1.089 v²/R); the data's three-point
    curvatures never exceed 1/R, so the overshoot is found and warned (before: silent)."""
    radius, v = 30.0, 10.0
    line = [[x, 0.0, 0.0] for x in np.arange(-30.0, 0.0, 1.0)]
    arc = [[radius * math.sin(a), 0.0, radius - radius * math.cos(a)] for a in np.arange(0.0, 1.0, 1 / radius)]
    st, res = compute(setup(track={"type": "table", "points": line + arc}, motion={"speed": str(v), "s0": 5.0},
                            time={"t_end": 4.0, "steps": 400}, effects={"gravity": False}))
    peak = np.abs(res[1]["a"][:, 2]).max() / (v**2 / radius) - 1
    assert peak == pytest.approx(0.089, abs=0.005)
    assert st.track.noise["curvature_overshoot"] == pytest.approx(peak, abs=0.01)
    assert any("overshoots the three-point curvature of the points by 8.9 %" in n for n in st.notes)
    _, smooth = _noisy_circle(0.0)
    st = prepared(setup(track={"type": "table", "points": smooth}, motion={"speed": "1", "s0": 5.0}))
    assert st.track.noise["curvature_overshoot"] < 1e-6 and not st.notes


def test_twist_is_honoured_on_a_table_track():
    """A horizontal circle R = 30 m given as a table, banked by θ1 = atan(v²/(g R)): no lateral
    load (before: a twist on a table was refused)."""
    radius, v = 30.0, 12.0
    _, pts = _noisy_circle(0.0)
    bank = math.atan(v**2 / (G * radius))
    st, res = compute(setup(track={"type": "table", "points": pts, "twist": repr(bank)},
                            motion={"speed": str(v), "s0": 5.0}, time={"t_end": 3.0, "steps": 30}))
    np.testing.assert_allclose(res[1]["overload"][:, 2], 0.0, atol=1e-4)
    np.testing.assert_allclose(res[1]["overload"][:, 1], math.hypot(1.0, v**2 / (G * radius)), rtol=1e-4)


def test_a_number_is_a_constant_expression():
    st = prepared(setup(motion={"speed": 10}, track={"type": "expression", "x": "s", "y": "0", "z": "0",
                                                   "twist": 0.25}))
    assert st.speed[0](np.array([1.0]))[0] == 10.0 and st.track.twist(np.array([3.0]))[0][0] == 0.25


@pytest.mark.slow
def test_a_speed_law_is_differentiated_once():
    """A run needs V0 and its rate only: 36 nested sines, whose first derivative has ~700 nodes and whose second
    would exceed the 20000 a derivative may have, are accepted; the rate is the chain rule's product of cosines."""
    depth = 36
    st = prepared(setup(motion={"speed": "10 + " + "sin(" * depth + "t" + ")" * depth},
                        time={"t_end": 2.0, "steps": 4}))
    inner, rate = st.t.copy(), np.ones_like(st.t)
    for _ in range(depth):
        rate *= np.cos(inner)
        inner = np.sin(inner)
    np.testing.assert_allclose(st.speed[0](st.t), 10.0 + inner, rtol=1e-14)
    np.testing.assert_allclose(st.speed[1](st.t), rate, rtol=1e-12, atol=1e-15)
    assert rate[1] > 0.1  # the rate at t = 0.5 s is not negligible (the test can fail)


def test_rotation_minimising_frame_has_no_roll_and_its_stated_angular_velocity():
    """Forced on the helix (min_curvature above κ): x1 = t, Ω1 = 0, and Ω, Ω' agree with
    differences of the frame itself (-Λ' Λᵀ = Ω̌ for a passive Λ); |a| of O stays κ v²."""
    from symmech.trolley import model

    helix = {"type": "helix", "radius": 7.0, "rise": 0.8}
    v = 6.0
    st, res = compute(setup(frame="frenet", track=helix, motion={"speed": str(v)}, numerics={"min_curvature": 1.0},
                            effects={"gravity": False}))
    assert st.plan.report()["mode"] == "rotation-minimising"
    s = np.linspace(5.0, 15.0, 11)
    h = 1e-4
    frame = model.moving_frame(st.track, s, "frenet", st.plan)
    plus, minus = (model.moving_frame(st.track, s + d, "frenet", st.plan) for d in (h, -h))
    skew = -((plus.lam - minus.lam) / (2 * h)) @ np.swapaxes(frame.lam, 1, 2)
    omega = np.stack([skew[:, 2, 1], skew[:, 0, 2], skew[:, 1, 0]], axis=1)
    np.testing.assert_allclose(omega, frame.W, atol=1e-6)
    np.testing.assert_allclose(frame.W[:, 0], 0.0, atol=0)
    np.testing.assert_allclose((plus.W - minus.W) / (2 * h), frame.dW, atol=1e-6)
    kappa = 7.0 / (49.0 + 0.64)
    np.testing.assert_allclose(np.linalg.norm(res[1]["a"], axis=1), kappa * v**2, rtol=1e-9)


def test_a_check_sample_on_the_vertical_tangent_does_not_stop_a_run_that_misses_it():
    """The check grid (201 samples over [-0.04, 25.17] m) lands on s = 4π exactly; the run's
    samples do not, so the run goes on with the frame rolled back beyond the vertical."""
    loop = {"type": "expression", "x": "8*sin(s/8)", "y": "8 - 8*cos(s/8)", "z": "0"}
    span = 2 * (4 * math.pi + 0.04) - 0.04
    st, res = compute(setup(track=loop, motion={"speed": repr(span - 0.04)}, time={"t_end": 1.0, "steps": 3}))
    event = st.plan.report()["events"][0]
    assert event["s"] == pytest.approx(4 * math.pi, abs=3e-3)
    np.testing.assert_allclose(res[1]["overload"][:, 1], res[1]["V0"] ** 2 / (G * 8.0)
                               + np.cos(res[1]["s"] / 8.0), atol=1e-9)
