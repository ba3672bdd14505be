"""The elastic trolley as a user capability: energy balance with the work of the track
forces, prescribed traction, the warnings where the model's assumptions fail, the bundled scene."""
import copy
import sys
from pathlib import Path

import numpy as np
import pytest

from symmech.core.schema import validate
from symmech.trolley.elastic import system as el, body as el_body, simulate as el_sim
from symmech.trolley.elastic import review, scene as elastic_scene

sys.path.insert(0, str(Path(__file__).parent))
from test_trolley_elastic import closed_form_roller_frequencies  # noqa: E402
from trolley_util import prepared, setup as scene_dict  # noqa: E402

G0 = 9.81
G_SCENE = 9.80665  # constants.g0 by default
TROLLEY = {"mass": 100.0, "com": [0.8, 0.5, 0.0], "inertia": [10.0, 20.0, 15.0, 0, 0, 0]}
HELIX = {"type": "helix", "radius": 7.0, "rise": 5 / (2 * np.pi)}


def elastic_run(data, elastic, case=1, comfort=None):
    """Result of the [elastic] table ``elastic`` on the trolley scene dict ``data``."""
    st = prepared(data)
    es = elastic_scene.prepare(validate(elastic_scene.SCHEMA, copy.deepcopy(elastic)), st.body,
                               elastic_scene.drive_of(st, case), st.t)
    return elastic_scene.run(es, comfort=comfort)


def rollers(k, c=2e3, **numerics):
    return {"rollers": {"stiffness": [k] * 5, "damping": [c] * 5}, "numerics": {"modal_samples": 0, **numerics}}


# ---------------------------------------------------------------- energy on a general track

# A catenary in the vertical plane, X0 = (20 asinh(s/20), sqrt(400 + s²), 0) (arc length s,
# curvature 20/(400 + s²)), with a twist 0.2 sin(s/5) rolling the frame: no uniform motion.
CATENARY = scene_dict(frame="twist", track={"type": "expression", "x": "20*asinh(s/20)", "y": "sqrt(400 + s**2)",
                                            "z": "0", "twist": "0.2*sin(s/5)"},
                      motion={"speed": "8 + 3*sin(t)"}, time={"t_end": 0.5, "steps": 5})


@pytest.mark.parametrize("damped", [False, True])
def test_energy_changes_by_the_work_of_the_track_forces(damped):
    """E(t) - E(0) = ∫ (F·v0 + M_O·ω) dt - dissipated, E = T + Π + V_g in the fixed frame.

    The work and the dissipation are integrated as states beside the motion; E is evaluated
    from the state alone, so the balance fails for any missing term (e.g. M_O·ω: O(10²) J here)."""
    c = (300.0,) * 5 if damped else (0.0,) * 5
    beam = el_body.Beam((0.5, 0.3, 0), (0, 1, 0), (1, 0, 0), 1.2, 4.0, (3e3, 5e3), modes=1, tip_mass=1.0,
                   damping_ratio=0.05 if damped else 0.0)
    mdl = el_body.ElasticModel(80.0, (0.8, 0.4, 0.1), (10.0, 20.0, 15.0, 0, 0, 0), 2.0, 1.0, G0,
                          el_body.Rollers((2e5, 2e5, 3e5, 2e5, 2e5), c), beams=(beam,), effects=el_body.Effects(damping=damped))
    system = el.System(mdl)
    kick = np.zeros(system.N)
    kick[[0, 2, 4, 5]] = [1e-3, 2e-3, -1e-3, 5e-3]
    drive = elastic_scene.drive_of(prepared(CATENARY), 1)
    # explicit: modes of 9-35 Hz, no stiffness to speak of (Radau needs ~10x the evaluations here)
    r = el_sim.simulate(system, drive, np.linspace(0.0, 0.5, 6), "DOP853", rtol=1e-9, dq0=kick)
    residual = np.abs(elastic_scene.energy_residual(r)).max()
    work = np.abs(r["work"]).max()
    assert work > 1e3  # the track does work: the energy is not conserved by itself
    assert np.abs(r["E"] - r["E"][0]).max() > 0.5 * work
    if damped:
        assert r["dissipated"][-1] > 1.0
        assert residual < 1e-7 * r["dissipated"][-1]
    else:
        assert r["dissipated"][-1] == 0.0
        assert residual < 1e-10 * work


@pytest.mark.slow  # ~20 s on the Python path; the default tier keeps test_membrane_energy_is_conserved_along_the_track
def test_energy_balance_includes_the_membrane_energy_of_a_held_beam():
    """A pinned beam with held ends (quartic membrane energy) across the trolley, kicked in its
    first mode: the membrane energy swings by ~1 J, the balance still closes to 1e-10 of the work."""
    from symmech.trolley.elastic import membrane

    beam = el_body.Beam((0.2, 0.3, -0.5), (0, 0, 1), (0, 1, 0), 1.0, 4.0, (3e3, 5e3), "pinned", 2, 0.0, 0.0, "held", 1e7)
    mdl = el_body.ElasticModel(80.0, (0.8, 0.4, 0.1), (10.0, 20.0, 15.0, 0, 0, 0), 2.0, 1.0, G0,
                          el_body.Rollers((2e5, 2e5, 3e5, 2e5, 2e5), (0.0,) * 5), beams=(beam,),
                          effects=el_body.Effects(damping=False))
    system = el.System(mdl)
    kick = np.zeros(system.N)
    kick[[0, 2, 5]] = [1e-3, 2e-3, 5e-2]
    drive = elastic_scene.drive_of(prepared(CATENARY), 1)
    r = el_sim.simulate(system, drive, np.linspace(0.0, 0.5, 6), "DOP853", rtol=1e-9, dq0=kick)
    swing = np.ptp([membrane.energy(system.inv.membrane, q) for q in r["q"]])
    assert swing > 0.1
    assert np.abs(elastic_scene.energy_residual(r)).max() < 1e-10 * np.abs(r["work"]).max()


# ---------------------------------------------------------------- traction

def test_traction_on_a_straight_level_track_follows_newton():
    """P0 = 200 + 100 t N on 100 kg from 5 m/s: V = 5 + (200 t + 50 t²)/100, s by one more
    integral. On rollers of stiffness k the body's pitch under the growing traction shifts
    its centre by O(1/k), so the speed error falls like 1/k."""
    data = scene_dict(trolley=TROLLEY, effects={"gravity": True, "local_curvature": False, "traction": True},
                      motion={"traction": "200 + 100*t", "initial_speed": 5.0}, time={"t_end": 2.0, "steps": 10})
    st = prepared(data)
    drive = elastic_scene.drive_of(st, 1)
    t = st.t
    V = 5.0 + (200 * t + 50 * t ** 2) / 100.0
    s = 5.0 * t + (100 * t ** 2 + 50 * t ** 3 / 3) / 100.0
    errors = []
    for k in (1e7, 1e8):
        mdl = el_body.ElasticModel(100.0, (0.8, 0.5, 0.0), (10.0, 20.0, 15.0, 0, 0, 0), 2.0, 1.0, G0,
                              el_body.Rollers((k,) * 5, (2e3,) * 5))
        r = el_sim.simulate(el.System(mdl), drive, t, rtol=1e-10)
        errors.append(np.abs(r["V0"] - V).max())
        assert np.abs(r["s"] - s).max() < 3 * errors[-1]
        assert np.abs(r["P"][:, 0] - (200 + 100 * t)).max() < 1e-9 * 400  # P0 is the prescribed traction
    assert errors[1] < 2e-7
    assert 8 < errors[0] / errors[1] < 12


def test_traction_runs_through_the_scene():
    data = scene_dict(trolley=TROLLEY, effects={"gravity": True, "local_curvature": False, "traction": True},
                      motion={"traction": "300", "initial_speed": 2.0}, time={"t_end": 1.0, "steps": 5})
    res = elastic_run(data, rollers(1e8))
    P = res.tables["elastic_reactions"]
    # constant traction from the quasi-static state: no vibration, V = 2 + 3 t exactly
    assert np.allclose(P.column("s"), 2.0 * P.column("t") + 1.5 * P.column("t") ** 2, rtol=0, atol=1e-9)
    assert np.allclose(P.column("P0"), 300.0, rtol=1e-9)


# ---------------------------------------------------------------- warnings

def test_rotation_warning_only_past_the_threshold():
    """Helix at 8 m/s: the roller rotations scale like 1/k (about 1e-5 rad at 1e7 N/m, 1e-2 at 1e4)."""
    data = scene_dict(frame="frenet", track=HELIX, trolley=TROLLEY, motion={"speed": "8"},
                      time={"t_end": 0.5, "steps": 5})
    stiff = elastic_run(data, rollers(1e7, small_rotation=0.005))
    soft = elastic_run(data, rollers(1e4, 63.0, small_rotation=0.005))
    assert stiff.summary["elastic"]["max_roller_rotation_rad"] < 1e-4
    assert soft.summary["elastic"]["max_roller_rotation_rad"] > 0.005
    assert not [w for w in stiff.warnings if "roller rotation" in w]
    assert [w for w in soft.warnings if "roller rotation" in w]
    # the soft trolley lags the rigid one where P3 crosses zero: opposite signs
    assert not [w for w in stiff.warnings if "opposite sign" in w]
    assert [w for w in soft.warnings if w.startswith("elastic: P3 has the opposite sign")]


def test_sign_change_warning():
    """Straight level track, centre of mass 0.8 m ahead of O (l = 2 m) and 0.5 m up: the front
    axle carries m (g 0.8 - a1 0.5)/l, negative when a1 = 20 cos 2t exceeds 15.7 m/s²; at a
    constant speed it is m g 0.8/l throughout."""
    base = scene_dict(trolley=TROLLEY, time={"t_end": 1.0, "steps": 10})
    steady = elastic_run({**base, "motion": {"speed": "10"}}, rollers(1e7))
    surging = elastic_run({**base, "motion": {"speed": "10 + 10*sin(2*t)"}}, rollers(1e7))
    P3 = steady.tables["elastic_reactions"].column("P3")
    assert np.allclose(P3, 100 * G_SCENE * 0.8 / 2.0, rtol=1e-5)
    assert not [w for w in steady.warnings if "sign" in w]
    assert [w for w in surging.warnings if w.startswith("elastic: P3 changes sign")]
    # the lift-off is a failed check too, naming the reaction; the steady ride's check passes
    kept, lifted = (review.contact_check(res.tables["elastic_reactions"]) for res in (steady, surging))
    assert (kept.verdict, kept.value) == ("pass", 0.0)
    assert (lifted.verdict, lifted.value) == ("fail", 1.0) and lifted.what.endswith("(lift-off: P3)")
    t = surging.tables["elastic_reactions"].column("t")
    rigid = 100 * (G_SCENE * 0.8 - 20 * np.cos(2 * t) * 0.5) / 2.0
    assert np.abs(surging.tables["elastic_reactions"].column("P3_rigid") - rigid).max() < 1e-9 * 1000


@pytest.mark.parametrize("x2, warned", [((-1.5, 6.0), False), ((-1.5, 0.9), True)])
def test_comfort_warning_at_a_report_point(x2, warned):
    """At rest on a straight level track a seat on the trolley carries 1 g along x2 (and the
    0.8 m/s² of the speed ramp, 0.0816 g, along x1): inside the default envelope, outside
    one that ends at 0.9 g."""
    data = scene_dict(trolley=TROLLEY, motion={"speed": "0.8*t"}, time={"t_end": 0.2, "steps": 2})
    comfort = {"x1": (-2.0, 2.0), "x2": x2, "x3": (-2.0, 2.0)}
    res = elastic_run(data, {**rollers(1e9), "points": [{"name": "seat", "at": [1.0, 0.5, 0.0]}]}, comfort=comfort)
    seat = res.summary["elastic"]["comfort"]["seat"]
    assert seat["x2"]["min_g"] == pytest.approx(1.0, abs=1e-6)
    assert seat["x1"]["max_g"] == pytest.approx(0.8 / G_SCENE, abs=1e-6)
    assert bool(seat["x2"]["samples_outside"]) == warned
    assert bool([w for w in res.warnings if w.startswith("elastic: overload of point seat along x2")]) == warned


def test_opposite_sign_warning_logic():
    """The rule itself on made-up histories: a sign differing from the rigid one counts only
    beyond 1e-3 of the largest rigid reaction."""
    setup = elastic_scene.Setup(el.System(el_body.ElasticModel(1.0, (0, 0, 0), (1, 1, 1, 0, 0, 0), 2.0, 1.0, 0.0, None,
                                                          effects=el_body.Effects(rollers=False))),
                                None, None, None, [], "Radau", 1e-7, 0, 0.05, 0.1)
    t = np.linspace(0.0, 1.0, 5)
    rigid = np.tile([0.0, 100.0, 100.0, 50.0, 10.0, 10.0], (5, 1))
    for shift, warned in ((0.05, False), (-0.2, True)):
        P = rigid.copy()
        P[3, 4] = shift
        got = elastic_scene._warnings(setup, {"t": t, "P": P, "P_rigid": rigid, "q": np.zeros((5, 0))}, None)
        assert bool([w for w in got if w.startswith("elastic: P4 has the opposite sign")]) == warned


@pytest.mark.parametrize("ratio, warned, softness", [(1.0, True, 1e-3), (0.5, False, 1.0)])
def test_resonance_warning_at_the_axle_passing_frequency(ratio, warned, softness):
    """Straight level track at constant V0: the only forcing is the axle passing V0/l (no
    rotation, no curvature). V0 = ratio · l · f_bounce with f_bounce the lowest closed-form
    roller frequency: within 10 % at ratio 1 (rollers 1000 times softer: a forcing below 1 Hz counts),
    nowhere near any mode at 0.5."""
    k = tuple(softness * x for x in (1e5, 1e5, 2e5, 1.5e5, 1e5))
    vertical, lateral = closed_form_roller_frequencies(100.0, (0.8, 0.5, 0.0), (10.0, 20.0, 15.0), k, 2.0, 1.0, 0.0)
    f = np.sort(np.r_[vertical, lateral]) / (2 * np.pi)
    speed = float(ratio * 2.0 * f[0])
    # without gravity the quasi-static state is q = 0, where the closed form holds exactly
    data = scene_dict(trolley=TROLLEY, motion={"speed": f"{speed!r}"}, time={"t_end": 0.2, "steps": 2},
                      effects={"gravity": False})
    res = elastic_run(data, {"rollers": {"stiffness": list(k)}, "effects": {"damping": False},
                             "numerics": {"modal_samples": 2}})
    modes = res.tables["modes"]
    assert np.allclose(modes.column("f").reshape(2, 5), f, rtol=1e-9)
    assert np.allclose(modes.column("forcing_axle"), speed / 2.0, rtol=1e-12)
    assert np.all(modes.column("forcing_rotation") == 0) and np.all(modes.column("forcing_curvature") == 0)
    assert bool([w for w in res.warnings if "axle passing" in w]) == warned
    assert len([w for w in res.warnings if "natural frequency" in w]) == warned


def test_forcing_frequencies_of_a_sinusoidal_curvature():
    """Ω = Ω0 sin(2π s/λ) e3 at V0: the curvature forcing peaks at V0/λ, the rotation one at V0 Ω0/2π."""
    lam, omega0, V0 = 12.0, 0.1, 15.0
    s = np.linspace(0.0, lam, 401)
    W = np.zeros((401, 3))
    dW = np.zeros((401, 3))
    W[:, 2] = omega0 * np.sin(2 * np.pi * s / lam)
    dW[:, 2] = omega0 * 2 * np.pi / lam * np.cos(2 * np.pi * s / lam)
    f = elastic_scene.forcing_frequencies(2.0, np.full(401, V0), W, dW, omega0)
    assert np.allclose(f[:, 0], V0 / 2.0)
    assert f[:, 1].max() == pytest.approx(V0 * omega0 / (2 * np.pi), rel=1e-12)
    assert f[:, 2].max() == pytest.approx(V0 / lam, rel=1e-12)


# ---------------------------------------------------------------- rigid limit, the paper's body

@pytest.mark.slow  # two 10 s rides with rollers of 1e8-1e9 N/m; the default tier keeps test_rigid_limit_on_the_paper_helix
def test_rigid_limit_with_the_papers_point_mass():
    """The paper's body (100 kg at c = (1, 0.5, 0), no inertia) as the tip mass of a mast of
    0.5 m rooted at (1, 0, 0) on a trolley of 1e-9 kg; the mast (ρA = 1e-4 kg/m, tip stiffness
    3EI/L³ = k) and the rollers stiffen together. On the paper's helix (V0 = 3t + 7 sin(t/2)),
    after the start transient, the reactions approach the rigid model's with the error ~ 1/k;
    the extra 5e-5 kg of mast and trolley move the rigid reactions by < 1e-6 (relative)."""
    from symmech.trolley import model
    from test_trolley_elastic import helix

    t = np.linspace(0.0, 10.0, 21)
    late = t >= 5.0
    drive = helix()
    L = 0.5
    paper = None
    errors = []
    for k in (1e8, 1e9):
        mast = el_body.Beam((1.0, 0.0, 0.0), (0, 1, 0), (1, 0, 0), L, 1e-4, (k * L ** 3 / 3,) * 2, "cantilever", 2, 100.0,
                       0.05)
        mdl = el_body.ElasticModel(1e-9, (0.0, 0.0, 0.0), (0.0,) * 6, 2.0, 1.0, G0, el_body.Rollers((k,) * 5, (2000.0,) * 5),
                              (mast,))
        r = el_sim.simulate(el.System(mdl), drive, t)
        if paper is None:
            body = model.Body(100.0, (1.0, 0.5, 0.0), (0.0,) * 6, 2.0, 1.0, G0)
            paper = model.body_motion(drive.frames(r["s"]), r["V0"], r["dV0"], body)["P"]
            scale = np.abs(paper[late]).max()
            assert np.abs(r["P_rigid"] - paper).max() < 1e-6 * scale
        errors.append(np.abs(r["P"][late] - r["P_rigid"][late]).max() / scale)
        assert np.abs(r["P"][late] - paper[late]).max() < (errors[-1] + 1e-6) * scale
    assert errors[1] < 3e-6
    assert 9 < errors[0] / errors[1] < 11


@pytest.mark.slow  # ~15 s of CPU, the reference at rtol 1e-11 most of it
def test_work_precision_of_the_elastic_model():
    """`bench precision` on an elastic scene: Radau's error falls with rtol and reaches 1e-7 of
    the reactions at rtol 1e-8 against the rtol-1e-11 reference; BDF, DOP853 are listed too."""
    from symmech.core.context import Context

    data = scene_dict(frame="frenet", track=HELIX, trolley=TROLLEY, motion={"speed": "8"},
                      time={"t_end": 0.5, "steps": 5})
    st = prepared(data)
    es = elastic_scene.prepare(validate(elastic_scene.SCHEMA, rollers(1e6)), st.body, elastic_scene.drive_of(st, 1),
                               st.t)
    res = elastic_scene.precision(es, Context(quiet=True))
    table = res.tables["precision_elastic"]
    methods = table.text["method"]
    radau = np.array([e for m, e in zip(methods, table.column("error")) if m == "Radau, analytic J"])
    assert len(radau) == 3 and np.all(np.diff(radau) < 0) and radau[-1] < 1e-7
    assert {"BDF, analytic J", "Radau, FD J", "DOP853"} <= set(methods)
    assert np.all(table.column("seconds") > 0)


@pytest.mark.slow  # the whole bundled ride on the Python engine (~7 s of CPU); its 100-step contract is default
def test_bundled_scene_runs_with_the_elastic_tables_plots_and_summary(tmp_path):
    """`symmech run scenes/trolley_elastic_helix.toml`: the rigid case tables and the elastic ones
    side by side; the elastic P*_rigid equal the rigid case 1 of the whole body (mast included)."""
    from symmech.core import pipeline
    from symmech.core.context import Context

    sc = pipeline.load(str(Path(__file__).resolve().parents[1] / "scenes" / "trolley_elastic_helix.toml"))
    assert "elastic model" in sc.estimate().what
    res = sc.run(Context(quiet=True))
    assert {"case1", "case1_overload", "elastic_reactions", "roller_deflections", "points", "energy",
            "modes"} <= set(res.tables)
    info = res.summary["elastic"]
    assert set(info["dynamic_amplification"]) == {f"P{i}" for i in range(6)}
    assert info["energy_residual_relative"] < 1e-6
    assert set(info["comfort"]) == {"tip", "seat"}
    P = res.tables["elastic_reactions"]
    # 100 kg trolley + 6 kg mast + 2 kg tip: the whole body's vertical reactions exceed the trolley's
    rigid = res.tables["case1"]
    assert np.all(sum(P.column(f"P{i}_rigid") for i in (1, 2, 3)) > sum(rigid.column(f"P{i}") for i in (1, 2, 3)))
    files = {p.name for p in res.plots(tmp_path)}
    assert {"campbell.png", "elastic_reactions.png", "elastic_deflections.png", "elastic_overloads.png",
            "reactions.png"} <= files
