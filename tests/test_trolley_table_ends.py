"""A motion may use a point-table track from its first point to its last.

The case 2 differences for Λ*', Λ*'' are one-sided at the ends of the run's arc-length
range; references are the closed form of a catenary y = a cosh(x / a), by arc length
x = a asinh(s / a), y = sqrt(a² + s²), curvature κ = a / (a² + s²), and the exact
symbolic Λ*', Λ*'' of that expression (scene.exact_lstar_derivatives).
"""
import math

import numpy as np
import pytest

from symmech.core.scene import SceneError
from symmech.trolley import model, scene
from trolley_util import compute, prepared, setup

A = 10.0  # m, catenary parameter
CATENARY = {"type": "expression", "x": f"{A}*asinh(s/{A})", "y": f"sqrt({A}**2 + s**2)", "z": "0"}


def _catenary_table(spacing, length=15.0):
    """Points of the catenary every ``spacing`` [m] of arc length from its vertex (s = 0)."""
    return [[A * math.asinh(s / A), math.sqrt(A * A + s * s), 0.0] for s in np.arange(0.0, length + 1e-9, spacing)]


def _length(points):
    return prepared(setup(track={"type": "table", "points": points}, motion={"speed": "1"},
                          time={"t_end": 1.0, "steps": 2})).track.length


def test_issue_scene_runs_from_the_first_point_of_the_table():
    """The issue's table (x = 2i, y = 0.05 i², 12 points) at 4 m/s for 2 s from s = 0: refused
    before (stencils at s = -0.04 m); it runs in both cases and both frames."""
    pts = [[2.0 * i, 0.05 * i * i, 0.0] for i in range(12)]
    for frame in ("twist", "frenet"):
        st, res = compute(setup(track={"type": "table", "points": pts}, frame=frame, motion={"speed": "4"},
                                time={"t_end": 2.0, "steps": 20}, effects={"local_curvature": True}))
        assert st.plan.span == (0.0, pytest.approx(8.0, rel=1e-12))
        for case in (1, 2):
            assert np.all(np.isfinite(res[case]["P"]))
    # at rest on the first point the span widens to two stencils on the table, not half of them before it
    st = prepared(setup(track={"type": "table", "points": pts}, motion={"speed": "0"},
                        time={"t_end": 1.0, "steps": 2}, effects={"local_curvature": True}))
    assert st.plan.span == (0.0, pytest.approx(2 * (st.fd_order + 1) * 0.02, rel=1e-12))


def test_one_sided_stencils_at_the_ends_match_the_exact_derivatives(monkeypatch):
    """Catenary expression track, case 2, Frenet frame, s from 0 to 8 m: no stencil node of the
    rear axle leaves [0, 8] m, and Ω̄, Ω̄' agree with those from the exact symbolic Λ*', Λ*''.
    Error bound: truncation (6 nodes, h = 0.02 m) ~h⁴ |Λ*⁽⁶⁾| ≪ 1e-12, rounding ~ ε Σ|w| / h²
    ≈ 2e-16 · 53 / 4e-4 ≈ 3e-11 1/m² against |Ω̄'| ≈ 6e-3 1/m²: 1e-10 1/m², 1e-12 1/m."""
    st = prepared(setup(track=CATENARY, frame="frenet", motion={"speed": "4"}, time={"t_end": 2.0, "steps": 20},
                        effects={"local_curvature": True, "gravity": False}))
    s = scene.arc_length(st)
    assert st.plan.span == (0.0, pytest.approx(8.0, rel=1e-12))
    exact = model.local_curvature_frame(st.track, s, st.body.l, st.frame, derivatives=scene.exact_lstar_derivatives(st),
                                        plan=st.plan)
    # the moving frame is evaluated at the rear axle, i.e. at every stencil node
    base, seen = model.moving_frame, []
    monkeypatch.setattr(model, "moving_frame", lambda track, x, *a, **k: (seen.append(x), base(track, x, *a, **k))[1])
    got = model.local_curvature_frame(st.track, s, st.body.l, st.frame, st.fd_order, st.fd_step, plan=st.plan)
    nodes = np.concatenate([np.ravel(x) for x in seen])
    assert nodes.min() >= 0.0 and nodes.max() <= 8.0 * (1 + 1e-12)
    assert np.abs(exact.dW).max() > 5e-3  # Λ* varies along the catenary (the test can fail)
    np.testing.assert_allclose(got.dW, exact.dW, rtol=0, atol=1e-10)
    np.testing.assert_allclose(got.W, exact.W, rtol=0, atol=1e-12)


@pytest.mark.parametrize("order", [2, 4])
def test_one_sided_weights_are_exact_for_polynomials(order):
    """On order + 2 nodes the forward and backward weights differentiate polynomials of degree
    order + 1 exactly (to rounding), one degree more than the central ones: the one-sided
    stencil at an end of the span is no less accurate than the central one inside."""
    coef = np.arange(1.0, order + 3)

    def fun(x):
        return np.polyval(coef, x)[:, None, None] * np.ones((1, 3, 3))

    s = np.array([0.0, 1e-3, 0.999, 1.0])  # near both ends of the span (0, 1): no room for the central nodes
    d1, d2 = model._stencil(fun, s, 0.05, order, (0.0, 1.0))
    np.testing.assert_allclose(d1[:, 0, 0], np.polyval(np.polyder(coef), s), rtol=1e-9)
    np.testing.assert_allclose(d2[:, 0, 0], np.polyval(np.polyder(coef, 2), s), rtol=1e-8)
    central = model._stencil(fun, np.array([0.5]), 0.05, order, (0.0, 1.0))[0][0, 0, 0]
    assert abs(central - np.polyval(np.polyder(coef), 0.5)) > 1e-6  # the central one is not exact there


def test_table_from_its_first_point_to_its_last_gives_the_catenary_curvature():
    """A table of the catenary every 0.5 m, the rear axle from its first point to its last
    (case 1) and the front axle to its last (case 2): the curvature of the frame equals
    κ = a/(a² + s²) to 2e-5 1/m (measured 1.2e-5 at s = 0, the fit's worst point), at least 8 times (measured 14)
    closer at twice the density (the quintic's end error falls like h³ or faster); case 2's
    Ω̄, Ω̄' equal the expression track's exact ones to 2e-6 1/m, 1e-5 1/m² (measured 6e-7, 5.8e-6
    at s = 0)."""
    errors = []
    for spacing in (0.5, 0.25):
        pts = _catenary_table(spacing)
        length, t_end = _length(pts), 3.0
        st, res = compute(setup(track={"type": "table", "points": pts}, frame="frenet",
                                motion={"speed": repr(length / t_end)}, time={"t_end": t_end, "steps": 30},
                                effects={"gravity": False}))
        s = res[1]["s"]
        assert s[0] == 0.0 and s[-1] == pytest.approx(length, rel=1e-12)
        errors.append(np.abs(res[1]["frame"].W[:, 2] - A / (A * A + s * s)).max())
    assert errors[0] < 2e-5 and errors[1] < errors[0] / 8

    pts = _catenary_table(0.5)
    end = _length(pts) - 2.3  # the front axle 2 m ahead ends 0.3 m before the end of the table
    over = {"frame": "frenet", "motion": {"speed": repr(end / 3.0)}, "time": {"t_end": 3.0, "steps": 30},
            "effects": {"gravity": False, "local_curvature": True}}
    st, res = compute(setup(track={"type": "table", "points": pts}, **over))
    exact_st = prepared(setup(track=CATENARY, **over))
    s = res[2]["s"]
    exact = model.local_curvature_frame(exact_st.track, s, exact_st.body.l, "frenet", plan=exact_st.plan,
                                        derivatives=scene.exact_lstar_derivatives(exact_st))
    np.testing.assert_allclose(res[2]["frame"].W, exact.W, rtol=0, atol=2e-6)
    np.testing.assert_allclose(res[2]["frame"].dW, exact.dW, rtol=0, atol=1e-5)


def test_motion_that_really_leaves_the_table_is_refused():
    """0.1 % beyond the last point (case 1), or the front axle beyond it (case 2): refused
    before the run, naming motion.speed."""
    pts = _catenary_table(0.5)
    length = _length(pts)
    with pytest.raises(SceneError, match="motion.speed.*leaves the track table"):
        prepared(setup(track={"type": "table", "points": pts}, motion={"speed": repr(1.001 * length / 2)},
                       time={"t_end": 2.0, "steps": 20}))
    with pytest.raises(SceneError, match="motion.speed.*leaves the track table"):
        prepared(setup(track={"type": "table", "points": pts}, motion={"speed": repr((length - 1.9) / 2)},
                       time={"t_end": 2.0, "steps": 20}, effects={"local_curvature": True}))
    with pytest.raises(SceneError, match="s from -2 to 0 m"):
        prepared(setup(track={"type": "table", "points": pts}, motion={"speed": "-1"},
                       time={"t_end": 2.0, "steps": 20}))


def test_frenet_warning_on_a_straight_table_names_points_on_the_track():
    """A straight table from s = 0: the rotation-minimising frame is announced from s = 0 m
    (before: s = -0.04 m, off the track)."""
    pts = [[2.0 * i, 0.0, 0.0] for i in range(12)]
    st = prepared(setup(track={"type": "table", "points": pts}, frame="frenet", motion={"speed": "4"},
                        time={"t_end": 2.0, "steps": 20}))
    note, = st.notes
    assert "at s = 0 m" in note and "on [0, 8] m" in note


@pytest.mark.parametrize("local_curvature", [False, True])
def test_traction_from_the_first_point_of_a_level_straight_table(local_curvature):
    """P0 = 50 N on 100 kg from rest at s = 0 of a level straight table (refused before: the
    stencils reached s = -0.04 m): s = P0 t²/(2m), V0 = P0 t/m (1e-12); the range the run may
    reach ends at the table's end, less 1.05 times the axle distance in case 2."""
    pts = [[2.0 * i, 0.0, 0.0] for i in range(12)]
    st, res = compute(setup(track={"type": "table", "points": pts}, motion={"traction": "50"},
                            time={"t_end": 4.0, "steps": 8},
                            effects={"traction": True, "local_curvature": local_curvature}))
    t = st.t
    np.testing.assert_allclose(res[1]["s"], 50 * t**2 / 200, rtol=0, atol=1e-12)
    np.testing.assert_allclose(res[1]["V0"], 50 * t / 100, rtol=0, atol=1e-12)
    assert st.plan.span == (0.0, pytest.approx(22.0 - (2.1 if local_curvature else 0.0), rel=1e-9))
