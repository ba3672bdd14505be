"""Hard cases: tight curves, high and zero speed, inflection, twist; bad scene input via the CLI."""
import math

import numpy as np
import pytest

from symmech.cli import main
from symmech.core.scene import SymmechError
from trolley_util import compute, setup

G = 9.80665


def _run(data):
    from symmech.core import pipeline

    return pipeline.load(data).run()


def circle(radius):
    return {"type": "expression", "x": f"{radius}*sin(s/{radius})", "y": "0",
            "z": f"{radius} - {radius}*cos(s/{radius})"}


def test_tight_curvature_reports_small_angle_correction_out_of_range(tmp_path):
    """Horizontal circle of radius 1.2 m with l = 2 m: chord angle asin(l / 2R) = 0.99 rad."""
    data = setup(track=circle(1.2), effects={"local_curvature": True}, motion={"speed": "2"})
    result = _run(data)
    summary = result.summary
    case2 = summary["cases"]["case2"]
    assert case2["chord_angle_max_rad"] == pytest.approx(math.asin(1.0 / 1.2), rel=1e-9)
    assert case2["small_angle_defect_max"] > 0.1
    assert any("small-angle correction (13)-(14) is out of its range" in w for w in result.warnings)
    assert np.all(np.isfinite(result.tables["case2"].data))


def test_gentle_curvature_keeps_small_angle_correction_in_range(tmp_path):
    result = _run(setup(track=circle(200.0), effects={"local_curvature": True}))
    assert result.summary["cases"]["case2"]["small_angle_defect_max"] < 1e-4
    assert not any("small-angle" in w for w in result.warnings)


def test_curve_tighter_than_half_axle_distance_is_a_clear_error():
    with pytest.raises(SymmechError, match="no front-axle point A at chord distance l = 2 m"):
        compute(setup(track=circle(0.9), effects={"local_curvature": True}))


def test_very_high_speed_stays_finite_and_exact():
    v, radius = 3000.0, 50.0
    st, res = compute(setup(track=circle(radius), motion={"speed": str(v)}, effects={"gravity": False,
                                                                                       "local_curvature": True}))
    for case in (1, 2):
        assert np.all(np.isfinite(res[case]["P"]))
    # Lateral (x3) acceleration of O in case 1: v²/R toward the centre.
    assert res[1]["a"][0, 2] == pytest.approx(v**2 / radius, rel=1e-10)
    np.testing.assert_allclose(np.linalg.norm(res[2]["a"], axis=1), v**2 / radius, rtol=1e-6)


def test_zero_speed_gives_static_reactions_in_both_conventions():
    helix = {"type": "helix", "radius": 7.0, "rise": 0.8}
    data = setup(frame="frenet", track=helix, motion={"speed": "0"}, effects={"local_curvature": True},
                 trolley={"com": [1.0, 0.5, 0.0]})
    for conventions in ("physics", "paper"):
        st, res = compute(data, conventions)
        for case in (1, 2):
            r = res[case]
            assert np.all(np.isfinite(r["P"]))
            force = np.stack([r["P"][:, 0], r["P"][:, 1:4].sum(1), r["P"][:, 4:].sum(1)], 1)
            if conventions == "physics":
                np.testing.assert_allclose(np.linalg.norm(force, axis=1), 100.0 * G, rtol=1e-10)


def test_inflection_point_in_twist_frame_has_no_nan_and_frenet_is_continued():
    """y = 0, z = S curve: curvature vanishes at the inflection u = 0. The Frenet normal
    reverses there; the frame is continued (reported), so its x2 stays the twist frame's x3
    up to one sign, and the normal acceleration changes sign smoothly."""
    track = {"type": "expression", "parameter": "u", "x": "u", "y": "0", "z": "0.2*u**3",
             "u_range": [-3.0, 3.0]}
    data = setup(track=track, motion={"speed": "1"}, time={"t_end": 2.0, "steps": 200},
                 effects={"local_curvature": True})
    s_inflection = 6.7184  # arc length from u = -3 to u = 0
    motion = {"speed": "1", "s0": s_inflection - 1.0}
    st, res = compute({**data, "motion": motion})
    for case in (1, 2):
        assert np.all(np.isfinite(res[case]["P"]))
        assert np.all(np.isfinite(res[case]["overload"]))
    # At the inflection (s where u = 0) the lateral acceleration changes sign.
    a3 = res[1]["a"][:, 2]
    assert a3.min() < 0 < a3.max()
    st_f, res_f = compute({**data, "frame": "frenet", "motion": motion})
    assert st_f.plan.events, "the inflection is reported"
    a2 = res_f[1]["a"][:, 1]
    sign = np.sign(a2[0] * a3[0])
    np.testing.assert_allclose(a2, sign * a3, atol=1e-6)


def test_banked_turn_twist_cancels_lateral_overload():
    """Horizontal circle banked by θ1 = atan(v²/(gR)): the rider feels no lateral load."""
    radius, v = 30.0, 12.0
    bank = math.atan(v**2 / (G * radius))
    track = {**circle(radius), "twist": repr(bank)}
    st, res = compute(setup(track=track, motion={"speed": str(v)}))
    n = res[1]["overload"]
    np.testing.assert_allclose(n[:, 2], 0.0, atol=1e-10)
    np.testing.assert_allclose(n[:, 1], math.hypot(1.0, v**2 / (G * radius)), rtol=1e-10)


def test_vertical_tangent_in_twist_frame_is_a_clear_error():
    loop = {"type": "expression", "x": "8*sin(s/8)", "y": "8 - 8*cos(s/8)", "z": "0"}
    with pytest.raises(SymmechError, match="track tangent is vertical"):
        compute(setup(track=loop, motion={"speed": "4*pi"}, time={"t_end": 1.0, "steps": 4}))


def _cli(tmp_path, text, capsys):
    path = tmp_path / "scene.toml"
    path.write_text(text)
    code = main(["run", str(path), "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    return code, err


BASE = """
kind = "trolley"
[track]
{track}
[trolley]
mass = {mass}
com = [0.0, 0.0, 0.0]
axle_distance = 2.0
half_gauge = 1.0
[motion]
speed = "5"
[time]
t_end = 1.0
steps = 10
[effects]
{effects}
"""
LINE = 'type = "expression"\nx = "s"\ny = "0"\nz = "0"'


def _table(points):
    return 'type = "table"\npoints = [' + ", ".join(f"[{x!r}, {y!r}, {z!r}]" for x, y, z in points) + "]"


@pytest.mark.parametrize("track, mass, effects, expected", [
    (LINE, "-5.0", "gravity = true", "scene field 'trolley.mass': -5 kg is outside [0.001, 1e+07] kg"),
    (LINE, "100.0", "wind = true", "scene field 'effects.wind': unknown field"),
    (_table([(i, 0.0, 0.0) for i in range(5)] + [(4.0, 0.0, 3.0), (4.0, 0.0, 6.0), (4.0, 0.0, 9.0)]), "100.0",
     "gravity = true", "scene field 'track.points': track is not smooth: it turns by 90.0 deg at point 4"),
    (_table([(10 * math.cos(a), 0.0, 10 * math.sin(a)) for a in np.linspace(0, 2 * math.pi + 0.6, 60)]),
     "100.0", "gravity = true", "scene field 'track.points': track intersects itself"),
    ('type = "expression"\nx = "s"\ny = "q*s"\nz = "0"', "100.0", "gravity = true",
     "scene field 'track.y': unknown name 'q'"),
    ('type = "expression"\nx = "2*s"\ny = "0"\nz = "0"', "100.0", "gravity = true",
     "scene field 'track.x': |dX0/ds| deviates from 1"),
])
def test_bad_scene_input_is_one_line_error(tmp_path, capsys, track, mass, effects, expected):
    code, err = _cli(tmp_path, BASE.format(track=track, mass=mass, effects=effects), capsys)
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("symmech: error: ")
    assert expected in lines[0]
    assert "Traceback" not in err


def test_table_track_follows_a_sampled_circle():
    """A table sampled from a horizontal circle gives its curvature back: a3 = v²/R."""
    radius, v = 20.0, 6.0
    pts = [[radius * math.sin(a), 0.0, radius - radius * math.cos(a)] for a in np.linspace(0, 2.0, 41)]
    st, res = compute(setup(track={"type": "table", "points": pts}, motion={"speed": str(v), "s0": 5.0},
                            time={"t_end": 3.0, "steps": 30}, effects={"gravity": False}))
    np.testing.assert_allclose(res[1]["a"][:, 2], v**2 / radius, rtol=1e-4)
    np.testing.assert_allclose(res[1]["a"][:, :2], 0.0, atol=1e-4 * v**2 / radius)


def test_motion_leaving_a_table_track_is_a_clear_error():
    pts = [[float(i), 0.0, 0.0] for i in range(10)]
    with pytest.raises(SymmechError, match="the motion leaves the track table"):
        compute(setup(track={"type": "table", "points": pts}, motion={"speed": "10"}))


def test_parameter_u_track_gets_arc_length_and_curvature_right():
    """Horizontal circle traced at a non-uniform rate u ↦ angle u + u²/4: |a3| = v²/R, s(u) = R (u + u²/4)."""
    radius, v = 15.0, 4.0
    track = {"type": "expression", "parameter": "u", "u_range": [0.0, 2.0],
             "x": f"{radius}*sin(u + u**2/4)", "y": "0", "z": f"{radius} - {radius}*cos(u + u**2/4)"}
    st, res = compute(setup(track=track, motion={"speed": str(v)}, time={"t_end": 5.0, "steps": 50},
                            effects={"gravity": False}))
    assert st.track.length == pytest.approx(radius * 3.0, rel=1e-12)
    np.testing.assert_allclose(res[1]["a"][:, 2], v**2 / radius, rtol=1e-8)
    np.testing.assert_allclose(res[1]["a"][:, :2], 0.0, atol=1e-8)
