"""Trolley kinematics and reactions against closed-form physics (independent of the paper)."""
import math

import numpy as np
import pytest

from symmech.trolley import model
from trolley_util import compute, setup

G = 9.80665


def vertical_helix(radius, rise):
    """Helix about the vertical X2 axis, parametrized by arc length."""
    root = math.hypot(radius, rise)
    return {"type": "expression", "x": f"{radius}*cos(s/{root})", "y": f"{rise}*s/{root}",
            "z": f"{radius}*sin(s/{root})"}


def test_vertical_helix_constant_speed_closed_form():
    R, lam, v = 5.0, 0.8, 12.0
    st, res = compute(setup(frame="frenet", track=vertical_helix(R, lam), motion={"speed": str(v)}))
    r = res[1]
    kappa = R / (R**2 + lam**2)
    lam_bar, R_bar = lam / math.hypot(R, lam), R / math.hypot(R, lam)
    np.testing.assert_allclose(r["a"], np.broadcast_to([0.0, kappa * v**2, 0.0], r["a"].shape), atol=1e-9)
    # Contact force per unit mass = a + g ν; ν = up in (t, n, b): (λ̄, 0, ±R̄).
    per_mass = np.stack([r["P"][:, 0], r["P"][:, 1:4].sum(1), r["P"][:, 4:].sum(1)], 1) / 100.0
    np.testing.assert_allclose(np.linalg.norm(per_mass, axis=1), math.hypot(kappa * v**2, G), rtol=1e-10)
    np.testing.assert_allclose(r["P"][:, 0] / 100.0, G * lam_bar, rtol=1e-10)
    np.testing.assert_allclose(r["overload"][:, 1], kappa * v**2 / G, rtol=1e-10)
    np.testing.assert_allclose(np.abs(r["overload"][:, 2]), R_bar, rtol=1e-10)


@pytest.mark.parametrize("v", [5.0, 15.0])
def test_vertical_loop_top_and_bottom_overloads(v):
    r0 = 8.0
    loop = {"type": "expression", "x": f"{r0}*sin(s/{r0})", "y": f"{r0} - {r0}*cos(s/{r0})", "z": "0"}
    # One step from the bottom (s = 0) to the top (s = π r).
    t_top = math.pi * r0 / v
    st, res = compute(setup(frame="frenet", track=loop, motion={"speed": str(v)},
                            time={"t_end": t_top, "steps": 1}))
    n = res[1]["overload"]
    assert n[0, 1] == pytest.approx(1 + v**2 / (G * r0), rel=1e-10)  # bottom: pressed into the seat
    assert n[1, 1] == pytest.approx(v**2 / (G * r0) - 1, rel=1e-10)  # top: weight partly cancels
    np.testing.assert_allclose(n[:, [0, 2]], 0.0, atol=1e-10)


def test_straight_track_reactions_are_static_weight_shares():
    m, x1c, ah, l = 80.0, 0.7, 0.6, 2.5
    st, res = compute(setup(trolley={"mass": m, "com": [x1c, 0.4, 0.0], "axle_distance": l, "half_gauge": ah},
                            motion={"speed": "4"}))
    w = m * G
    expected = [0.0, w * (1 - x1c / l) / 2, w * (1 - x1c / l) / 2, w * x1c / l, 0.0, 0.0]
    np.testing.assert_allclose(res[1]["P"], np.broadcast_to(expected, res[1]["P"].shape), atol=1e-9)


def test_lateral_com_shifts_load_between_rear_rollers():
    """B at x3 = -a carries more when the centre of mass sits at x3 < 0."""
    m, ah = 50.0, 0.5
    st, res = compute(setup(trolley={"mass": m, "com": [0.0, 0.0, -0.2], "axle_distance": 2.0, "half_gauge": ah}))
    P = res[1]["P"][0]
    assert P[1] == pytest.approx(m * G * (0.5 + 0.2 / (2 * ah)), rel=1e-12)
    assert P[2] == pytest.approx(m * G * (0.5 - 0.2 / (2 * ah)), rel=1e-12)


def test_case2_tends_to_case1_as_axle_distance_vanishes():
    helix = {"type": "helix", "radius": 7.0, "rise": 0.8}
    errs = []
    for l in (0.04, 0.02, 0.01):
        st, res = compute(setup(frame="frenet", track=helix, motion={"speed": "3*t + 7*sin(t/2)"},
                                trolley={"com": [1.0, 0.5, 0.0], "axle_distance": l},
                                effects={"local_curvature": True}, numerics={"fd_step": l / 20}))
        scale = np.abs(res[1]["a"]).max()
        errs.append(max(np.abs(res[2]["a"] - res[1]["a"]).max(), np.abs(res[2]["V"] - res[1]["V"]).max()) / scale)
    assert errs[-1] < 2e-3
    # First order in l: halving l halves the difference.
    assert errs[0] / errs[1] == pytest.approx(2.0, rel=0.05)
    assert errs[1] / errs[2] == pytest.approx(2.0, rel=0.05)


def test_helix_chord_rotation_is_constant_in_the_moving_frame():
    st, res = compute(setup(frame="frenet", track={"type": "helix", "radius": 7.0, "rise": 0.8},
                            effects={"local_curvature": True}))
    fr = res[2]["frame"]
    np.testing.assert_allclose(fr.de, 0.0, atol=1e-8)
    base = fr.info["base"]
    lstar = fr.lam @ np.swapaxes(base.lam, 1, 2)
    np.testing.assert_allclose(fr.W, np.einsum("nij,nj->ni", lstar, base.W), atol=1e-9)


def test_twist_rate_on_straight_track_spins_the_body():
    """θ1 = c s on a straight track: ω1 = c V0, centripetal a2 = -(c V0)² h for a point at x2 = h."""
    c, v, h = 0.3, 6.0, 0.5
    st, res = compute(setup(track={"type": "expression", "x": "s", "y": "0", "z": "0", "twist": f"{c}*s"},
                            motion={"speed": str(v)}, trolley={"com": [0.0, h, 0.0]},
                            effects={"gravity": False}))
    r = res[1]
    np.testing.assert_allclose(r["omega"], np.broadcast_to([c * v, 0, 0], r["omega"].shape), atol=1e-12)
    np.testing.assert_allclose(r["a"], np.broadcast_to([0, -(c * v) ** 2 * h, 0], r["a"].shape), atol=1e-10)


def test_traction_on_a_slope_integrates_the_speed():
    """Straight slope of angle β, constant traction F: V0 = v0 + (F/m - g sin β) t."""
    beta, m, F, v0 = 0.1, 100.0, 300.0, 2.0
    slope = {"type": "expression", "x": f"s*{math.cos(beta)}", "y": f"s*{math.sin(beta)}", "z": "0"}
    st, res = compute(setup(track=slope, trolley={"mass": m}, effects={"traction": True},
                            motion={"traction": str(F), "initial_speed": v0}))
    r = res[1]
    expected = v0 + (F / m - G * math.sin(beta)) * st.t
    np.testing.assert_allclose(r["V0"], expected, rtol=1e-9)
    np.testing.assert_allclose(r["P"][:, 0], F, rtol=1e-9)


def test_traction_matches_speed_driven_run_on_a_helix():
    """Feeding back the traction a speed-driven run needs recovers its speed."""
    helix = {"type": "helix", "radius": 7.0, "rise": 0.8}
    base = setup(frame="frenet", track=helix, trolley={"com": [1.0, 0.5, 0.0]}, time={"t_end": 3.0, "steps": 30})
    st, res = compute({**base, "motion": {"speed": "5 + 2*t"}})
    # P0 from an independent closed form is unavailable; check self-consistency of P0 -> V0 instead.
    from scipy.interpolate import CubicSpline

    p0 = CubicSpline(st.t, res[1]["P"][:, 0])
    coeffs = np.polynomial.polynomial.polyfit(st.t, res[1]["P"][:, 0], 8)
    expr = " + ".join(f"({float(c)!r})*t**{k}" for k, c in enumerate(coeffs))
    assert np.abs(np.polynomial.polynomial.polyval(st.t, coeffs) - p0(st.t)).max() < 1e-3 * np.abs(p0(st.t)).max()
    st2, res2 = compute({**base, "effects": {"traction": True},
                         "motion": {"traction": expr, "initial_speed": 5.0}})
    np.testing.assert_allclose(res2[1]["V0"], 5 + 2 * st.t, rtol=1e-4)


def test_gravity_free_variant_matches_full_model_with_zero_gravity():
    rng = np.random.default_rng(7)
    args = [rng.uniform(1, 5, 10)] + list(rng.normal(size=(18, 10)))
    body = [rng.uniform(1, 3, 10), rng.uniform(0.5, 1, 10)]
    nu = list(rng.normal(size=(3, 10)))
    full = model.dyn.reactions(*args, *nu, 0.0, *body)
    np.testing.assert_allclose(model.dyn.reactions_no_gravity(*args, *body), full, atol=1e-12)
    # The variant carries no gravity terms at all.
    import inspect

    params = inspect.signature(model.dyn.reactions_no_gravity).parameters
    assert not {"g0", "nu1", "nu2", "nu3"} & set(params)
    assert len(params) == len(inspect.signature(model.dyn.reactions).parameters) - 4


def test_local_curvature_off_gives_only_case1_equal_to_full_model_case1():
    helix = {"type": "helix", "radius": 7.0, "rise": 0.8}
    inertia = {"inertia": [10.0, 20.0, 15.0, 0, 0, 0]}
    on = setup(frame="frenet", track=helix, trolley=inertia, effects={"local_curvature": True})
    # with an [elastic] table too: its drive follows case 1's frame
    off = setup(frame="frenet", track=helix, trolley=inertia, effects={"local_curvature": False},
                elastic={"rollers": {"stiffness": [1e7] * 5, "damping": [3e3] * 5}})
    _, r_on = compute(on)
    st, r_off = compute(off)
    assert set(r_off) == {1}
    np.testing.assert_array_equal(r_off[1]["P"], r_on[1]["P"])
    drive = st.elastic.drive.frames(r_off[1]["s"]).lam
    np.testing.assert_array_equal(drive, r_off[1]["frame"].lam)
    assert np.abs(drive - r_on[2]["frame"].lam).max() > 0.1  # the chord turns case 2's frame by ~κ l / 2


def test_rigid_body_inertia_adds_gyroscopic_moment():
    """Straight track with roll rate: I ω̇ = 0, ω × I ω = 0 for ω along x1 → unchanged; a pitching
    ω̇ about x3 from a vertical circle changes P3 by I33 ω̇3 / l."""
    r0, v = 10.0, 5.0
    circle = {"type": "expression", "x": f"{r0}*sin(s/{r0})", "y": f"{r0} - {r0}*cos(s/{r0})", "z": "0"}
    base = setup(frame="frenet", track=circle, motion={"speed": f"{v} + t"}, effects={"gravity": False})
    _, plain = compute(base)
    # A flat disc (I33 = I11 + I22, admissible): ω stays along x3, so only I33 ω̇3 adds.
    _, spun = compute({**base, "trolley": {**base["trolley"], "inertia": [20.0, 20.0, 40.0, 0, 0, 0]}})
    dw3 = 1.0 / r0  # ω3 = V0/r0, ω̇3 = V̇0/r0
    np.testing.assert_allclose(spun[1]["P"][:, 3] - plain[1]["P"][:, 3], 40.0 * dw3 / 2.0, rtol=1e-10)


def test_reactions_balance_force_and_moment_at_the_stated_points():
    """Reassemble P0…P5 at O, B = (0, 0, -a), C = (0, 0, a), A = (l, 0, 0) and compare with
    (11) evaluated directly: F = m (a + g0 ν), M = r × F + I ω̇ + ω × I ω."""
    rng = np.random.default_rng(11)
    n = 50
    m, g0, l, ah = 70.0, 9.81, 2.2, 0.7
    r = rng.normal(size=3)
    inertia = np.array([5.0, 7.0, 9.0, 0.5, -0.4, 0.3])
    acc, w, dw = rng.normal(size=(3, n, 3)) * 5
    nu = rng.normal(size=(n, 3))
    nu /= np.linalg.norm(nu, axis=1, keepdims=True)
    P = model.dyn.reactions(m, *r, *inertia, *acc.T, *w.T, *dw.T, *nu.T, g0, l, ah)
    i11, i22, i33, i12, i23, i13 = inertia
    icm = np.array([[i11, i12, i13], [i12, i22, i23], [i13, i23, i33]])
    F = m * (acc + g0 * nu)
    M = np.cross(r, F) + dw @ icm + np.cross(w, w @ icm)
    zero = np.zeros(n)
    forces = [(np.zeros(3), np.stack([P[:, 0], zero, zero], 1)), (np.array([0, 0, -ah]), np.stack([zero, P[:, 1], zero], 1)),
              (np.array([0, 0, ah]), np.stack([zero, P[:, 2], zero], 1)), (np.array([l, 0, 0]), np.stack([zero, P[:, 3], P[:, 5]], 1)),
              (np.zeros(3), np.stack([zero, zero, P[:, 4]], 1))]
    np.testing.assert_allclose(sum(f for _, f in forces), F, atol=1e-9)
    np.testing.assert_allclose(sum(np.cross(p, f) for p, f in forces), M, atol=1e-9)
