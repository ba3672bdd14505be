"""The compiled accurate-mode grain (symmech.grain.motion_engine) against the Python loop (the reference) and
closed forms: same events (impact times, impulses, regime sequence), same final state, same log.

The first run on a machine compiles the loop (about a minute of CPU; cached beside the module after that).
"""
import dataclasses
import math
import pickle
from dataclasses import replace

import numpy as np
import pytest

from grain_sliding_reference import conveyor, on_plane, sphere
from test_grain_hard_cases import CROP, WEED, sweep_grain
from test_grain_motion_hops import lift_off_at_the_end, midway_dip
from test_grain_regimes import default_scene
from symmech.core import sample
from symmech.core.scene import SceneError
from symmech.grain import contact, flight, motion, motion_scene
from symmech.grain.motion_engine import driver as compiled, kinematics, layouts as compiled_layout, slip
from symmech.grain.motion_engine.layouts import S_AT
from symmech.grain.coulomb_law import ImpactLaw

G = 9.81
EPS = float(np.finfo(float).eps)
# slow tier: the engine's build is ~70 s of CPU, more than a third of the default suite's budget (conftest.py)
pytestmark = [pytest.mark.slow, pytest.mark.compiled_engine]


def both(model, num, start, t_end):
    return compiled.simulate(model, num, start, t_end), motion.simulate(model, num, start, t_end)


def impact_time_tolerances(p, t_tol, gap_length):
    """Per impact of ``p``: t_tol [s] (the root finder's share) plus the gap's round-off over the contact's
    approach speed. The gap is computed from positions of size ``gap_length`` [m] to a few eps * gap_length, and
    a root moves by that error over |g'| = |u_n| (the contact point's normal velocity before the impact): in a
    chattering tail |u_n| falls to 1e-7 m/s and the two loops' impact times part by 1e-11 s (the tumbling crop
    grain: |dt| * |u_n| <= 3 eps * gap_length in its tail, 47 eps * gap_length where xtol dominates). 16 eps
    * gap_length is the bound; ``gap_length = 0`` leaves t_tol alone."""
    return np.array([t_tol + 16 * EPS * gap_length / max(abs(i["u_before"][2]), 1e-300) if gap_length else t_tol
                     for i in p.impacts])


def assert_same(c, p, t_tol, state_rtol, gap_length=0.0, final_rtol=None):
    """Same event log and regimes; event times to t_tol [s] (impact times to ``impact_time_tolerances``);
    impulses and velocities to state_rtol, the final state to final_rtol (default state_rtol)."""
    assert len(c.impacts) == len(p.impacts)
    assert c.extra["landings"] == p.extra["landings"]
    assert c.warnings == p.warnings
    assert c.trajectory.shape == p.trajectory.shape
    assert np.array_equal(c.trajectory[:, -1], p.trajectory[:, -1])  # the regime of every row
    at_impact = impact_time_tolerances(p, t_tol, gap_length)
    rows = p.trajectory[:, 0]
    row_tol = np.full(rows.shape, t_tol)
    for i, tol in zip(p.impacts, at_impact):  # an impact's rows (before and after) carry its time
        row_tol[rows == i["t"]] = tol
    assert np.all(np.abs(c.trajectory[:, 0] - rows) <= row_tol)
    # Impulses and velocities to state_rtol of their largest value in the run (a bounce at the end of a
    # chattering sequence is 1e-6 of the first; its relative error is that much larger).
    scales = {k: max((np.abs(i[k]).max() for i in p.impacts), default=1.0) for k in ("impulse", "v_after", "w_after")}
    for a, b, tol in zip(c.impacts, p.impacts, at_impact):
        assert abs(a["t"] - b["t"]) <= tol
        for key, scale in scales.items():
            assert np.abs(np.subtract(a[key], b[key])).max() <= state_rtol * scale
        for key in ("admissible", "printed_admissible", "printed_creates_energy", "converged"):
            assert a[key] == b[key]
    for key in ("r", "v", "q", "w"):
        x, y = getattr(c.final, key), getattr(p.final, key)
        assert np.linalg.norm(x - y) <= (final_rtol or state_rtol) * max(np.linalg.norm(y), 1e-3)
    assert c.final.t == pytest.approx(p.final.t, abs=t_tol)
    for k in p.time_in:  # durations: back-to-back phases telescope to their last event's time
        assert c.time_in[k] == pytest.approx(p.time_in[k], abs=max(at_impact, default=t_tol))


def test_ellipsoid_default_scene_matches_the_python_loop(tmp_path):
    """Default scene, 0.4 s: ~100 impacts, landings, sliding with spin, lift-offs, the printed law's verdict
    at every impact. Both loops integrate with DOP853 and locate roots with Brent: impact times agree to
    1e-11 s (measured 1.2e-13 s over 143 impacts in 0.6 s) and the state to 1e-7 relative."""
    sc = default_scene(tmp_path, 0.4)
    c, p = both(sc.model, sc.numerics, sc.start, 0.4)
    assert len(p.impacts) > 80 and p.extra["landings"] >= 5 and p.time_in["sliding"] > 0.05
    assert_same(c, p, 1e-11, 1e-7)
    bc, bp = c.extra["energy_budget"], p.extra["energy_budget"]
    assert bc["relative_residual"] < 1e-8
    for key in ("input_by_surface_J", "lost_in_impacts_J", "lost_at_landings_J", "lost_in_sliding_J", "end_J"):
        assert bc[key] == pytest.approx(bp[key], rel=1e-6, abs=1e-15)
    assert bc["start_J"] == pytest.approx(bp["start_J"], rel=1e-14)  # the same state, energies in numba / numpy


def test_ellipsoid_printed_law_matches_the_python_loop(tmp_path):
    """The printed law solved exactly at every impact (companion-matrix roots), 0.2 s."""
    sc = default_scene(tmp_path, 0.2)
    model = replace(sc.model, law=ImpactLaw("printed", e=0.4, lam=0.3))
    c, p = both(model, sc.numerics, sc.start, 0.2)
    assert len(p.impacts) > 20
    assert_same(c, p, 1e-11, 1e-7)


def test_sphere_drop_on_a_still_plate_hits_at_the_closed_form_times():
    """Point-mass sphere dropped from h with e = 0.5: t_1 = sqrt(2h/g), t_(k+1) = t_k + 2 e^k v_1 / g,
    impulse m (1 + e) e^(k-1) v_1; independent of the Python loop."""
    e, h, radius, m = 0.5, 0.02, 1e-3, 1e-6
    law = ImpactLaw("coulomb", e_n=e, e_t=0.0, mu=0.0, check_printed=False)
    model = replace(sphere(law=law, rotation=False), mass=m)
    start = on_plane(z=radius + h)
    num = motion.Numerics(tolerance=1e-12, scan_step=1e-3, sample_interval=0.01, rest_velocity=1e-3)
    res = compiled.simulate(model, num, start, 0.6)
    v1 = math.sqrt(2 * G * h)
    t = [math.sqrt(2 * h / G)]
    for k in range(1, 8):
        t.append(t[-1] + 2 * e**k * v1 / G)
    got = [i["t"] for i in res.impacts[:8]]
    assert np.max(np.abs(np.subtract(got, t))) < 1e-12
    for k, i in enumerate(res.impacts[:8]):
        assert i["impulse"][2] == pytest.approx(m * (1 + e) * e**k * v1, rel=1e-9)


def test_rolling_sphere_conveyor_matches_the_python_loop():
    """Sphere with spin on the 30 degree conveyor (lift-off every period, sliding, stick and slip), 4 periods.

    The final state to 1e-6: where the stick force reaches the cone (t = 0.11786 s, and near 0.157 s) a slip
    starts at 2 v_stop (5.4e-12 m/s) along the drive. Its component across the drive is zero in exact arithmetic;
    a round-off residue of ~1e-18 m/s, which the two loops' stick phases leave or not depending on the machine's
    rounding, excites the friction's relaxation across the slip (rate mu n K / |s|): DOP853 then crawls at its
    stable step, ~1.5e-9 s, where without the residue it takes one step of 3.8e-5 s (to the chunk's end), and its
    error over those steps reaches 3e-8 and 1e-7 of |w| at the two starts (measured on an AVX-512 machine: the
    compiled loop's final w 1.4e-7 from the Python loop's and from the converged run at tol 1e-13, the Python
    loop's 1.7e-10)."""
    model = conveyor(0.7, rotation=True)
    T = model.period
    num = motion.Numerics(tolerance=1e-10, scan_step=T / 40, sample_interval=T / 20)
    start = on_plane(v=(0.03, -0.02, 0.0), w=(0.0, 0.0, 5.0))
    c, p = both(model, num, start, 4 * T)
    assert p.extra["landings"] >= 3 and p.time_in["sliding"] > 0.5 * T
    assert_same(c, p, 1e-11, 1e-7, final_rtol=1e-6)


def test_batch_on_threads_equals_one_by_one(tmp_path):
    """simulate_many (threads; the loop releases the GIL) gives each grain bit for bit its serial result; the
    ahead-of-time build exports ``run`` and ``run_many`` for the signatures simulate and simulate_many call."""
    sc = default_scene(tmp_path, 0.08)
    starts = [replace(sc.start, v=np.array([0.01 * k, 0.0, 0.0])) for k in range(4)]
    models = [replace(sc.model, mu=0.3 + 0.1 * k) for k in range(4)]
    many = compiled.simulate_many(models, sc.numerics, starts, 0.08, workers=2)
    assert len({len(res.impacts) for res in many}) > 1  # the grains differ
    for res, model, start in zip(many, models, starts):
        one = compiled.simulate(model, sc.numerics, start, 0.08)
        assert np.array_equal(res.trajectory, one.trajectory)
        assert [i["t"] for i in res.impacts] == [i["t"] for i in one.impacts]
        assert res.extra == one.extra and res.warnings == one.warnings  # the energy budget and counts too
    # what the ahead-of-time build exports: the loop's two entries, each for the argument types its caller passes
    exports = compiled.ENGINE.ahead.exports()
    assert sorted(exports) == ["run", "run_many"]
    assert [exports[name][0].__name__ for name in ("run", "run_many")] == ["run", "run_many"]
    assert exports["run"][1].args == compiled.entry_signature()
    assert exports["run_many"][1].args == compiled.many_signature()


def test_impact_log_built_on_first_use_is_the_same_everywhere(tmp_path):
    """The deferred impact log: the public motion.Motion, its log a list of dicts with the Python loop's keys and
    value types, the same after pickling (before and after first use), through dataclasses.replace and asdict."""
    sc = default_scene(tmp_path, 0.05)
    c, p = both(sc.model, sc.numerics, sc.start, 0.05)
    before = pickle.loads(pickle.dumps(c))
    log = c.impacts
    assert type(c) is type(p) is motion.Motion
    assert type(log) is list and len(log) == len(p.impacts) >= 3 and c.impacts is log
    for a, b in zip(log, p.impacts):
        assert list(a) == list(b) and [type(v) for v in a.values()] == [type(v) for v in b.values()]
    assert before.impacts == pickle.loads(pickle.dumps(c)).impacts == dataclasses.asdict(c)["impact_log"].entries() == log
    assert dataclasses.replace(c, warnings=[]).impacts == log


def test_parameter_vector_layout():
    """pack fills every field of the declared layout by name; a Model zeroes on construction the parameters of
    what is switched off (pack reads the model as given)."""
    vib = flight.Vibration(1.1e-3, 2 * math.pi * 23.0, 0.7, (0.6, 0.0, 0.8))
    law = ImpactLaw("printed", e_n=0.41, e_t=-0.31, mu=0.52, e=0.43, lam=1.37, check_printed=True)
    model = motion.Model((3e-3, 2e-3, 1e-3), 2.5e-5, (0.5, -0.2, -9.7), vib, law, 0.33)
    num = motion.Numerics(tolerance=1e-8, scan_step=2e-4, rest_velocity=3e-5, max_impacts=77, sample_interval=5e-3)
    p = compiled.pack(model, num)
    assert p.shape == (32,)
    expected = {"axes": model.axes, "mass": 2.5e-5, "inertia": model.inertia, "g": model.g_k, "amplitude": 1.1e-3,
                "omega": 2 * math.pi * 23.0, "phase": 0.7, "direction": vib.direction, "law": compiled.LAW_PRINTED,
                "e_n": 0.41, "e_t": -0.31, "mu_impact": 0.52, "e": 0.43, "lam": 1.37, "check_printed": 1.0, "mu": 0.33,
                "rotation": 1.0, "tolerance": 1e-8, "scan_step": 2e-4, "rest_velocity": 3e-5, "max_impacts": 77.0,
                "sample_interval": 5e-3, "period": 1 / 23.0, "exact_flight": 0.0}
    got = compiled_layout.PARAMS.unpack(p)
    assert got.keys() == expected.keys()
    for name, values in expected.items():
        np.testing.assert_allclose(got[name], values, rtol=1e-15, err_msg=name)
    off = replace(model, effects=motion.Effects(vibration=False, friction=False, rotation=False))
    got = compiled_layout.PARAMS.unpack(compiled.pack(off, num))
    assert got["amplitude"] == got["mu"] == got["rotation"] == 0.0 and got["period"] == 1.0
    assert off.vibration.amplitude == off.mu == 0.0 and model.vibration.amplitude == 1.1e-3 and model.mu == 0.33
    assert got["omega"] == 2 * math.pi * 23.0 and got["mu_impact"] == 0.52
    assert compiled_layout.PARAMS.unpack(compiled.pack(model, replace(num, flight="exact")))["exact_flight"] == 1.0


def test_scene_engine_option_selects_the_loop_and_is_validated(tmp_path):
    sc = default_scene(tmp_path, 0.05)
    assert sc.numerics.engine == "auto"
    python = default_scene(tmp_path, 0.05, **{'mode = "accurate"': 'mode = "accurate"\nengine = "python"'})
    assert python.numerics.engine == "python"
    seen = []
    c = motion_scene.simulate(sc, on_step=seen.append)
    p = motion_scene.simulate(python)
    assert seen[-1] == pytest.approx(0.05) and len(c.impacts) == len(p.impacts) >= 3
    assert (c.extra["engine"], p.extra["engine"]) == ("compiled", "python")  # auto, on a built engine: compiled
    with pytest.raises(SceneError, match="numerics.engine"):
        default_scene(tmp_path, 0.05, **{'mode = "accurate"': 'mode = "accurate"\nengine = "fortran"'})


@pytest.mark.parametrize("fields, amplitude, frequency, t_end", [
    (CROP, 0.6e-3, 18.0, 0.12), (WEED, 1.0e-3, 18.0, 0.3), (CROP, 1.0e-3, 32.0, 0.04)])
def test_hard_sweep_grains_match_the_python_loop(fields, amplitude, frequency, t_end):
    """The grains of tests/test_grain_hard_cases.py: an ellipsoid slipping from rest while turning about the
    normal (crop, weed: stiff slip, integrated by the compiled Radau) and a tumbling one held on the plane by
    its spin (crop at 32 Hz: one rocking contact, landed and flown on in the compiled loop; it also slides).

    Both loops integrate the stiff slips with Radau IIA to the same tolerance ``tol`` (1e-9), the compiled
    one with the analytic Jacobian, the Python one with scipy's finite differences: their Newton iterates,
    hence steps, differ, and so do the results, by the integration error, not by round-off. Each step holds
    the error to tol relative (position to tol * v_scale * scan_step absolute); over the ~100 steps of a run
    the states differ by up to 100 tol relative (measured 1.2e-9) and event times by up to 100 tol *
    scan_step (7.8e-11 s at 32 Hz; measured 3.6e-12 s); the energy quadratures to 1000 tol relative
    (measured 1.6e-10)."""
    sc = sweep_grain(fields, amplitude, frequency, t_end)
    tol, step = sc.numerics.tolerance, sc.numerics.scan_step
    c, p = both(sc.model, sc.numerics, sc.start, t_end)
    assert_same(c, p, 100 * tol * step, 100 * tol)
    assert c.extra["rocking_contacts"] == p.extra["rocking_contacts"] == (1 if frequency == 32.0 else 0)
    assert c.extra["implicit_slip_steps"] > 0  # every slip from rest of these tilted grains turns stiff at once
    bc, bp = c.extra["energy_budget"], p.extra["energy_budget"]
    for key in ("input_by_surface_J", "lost_in_impacts_J", "lost_at_landings_J", "lost_in_sliding_J"):
        assert bc[key] == pytest.approx(bp[key], rel=1000 * tol, abs=1e-15)


def test_slip_onset_direction_of_a_turning_ellipsoid():
    """Slip from rest starts against the stick force, along B^-1 (f + c) (sliding._Contact.slip_direction),
    not along f + c: the compiled settle impulse, checked on the crop grain at its first slip onset."""
    sc = sweep_grain(CROP, 0.6e-3, 18.0, 0.12)
    m = sc.model
    Q0 = flight.rotation_matrix(sc.start.q)
    p = compiled.pack(m, sc.numerics)
    sp = slip.slide_params(p, Q0, kinematics.contact_offset(p, Q0), m.mu)
    sp[S_AT.v_stop] = 1e-11
    rho = contact.contact_offset(m.axes, Q0)
    k = m.mass / float(Q0[2] @ (m.inertia * Q0[2]))
    B = np.eye(2) + k * np.outer([-rho[1], rho[0]], [-rho[1], rho[0]])  # E + (m / I_zz) rho_perp rho_perp^T
    t = 0.013
    z = np.zeros(13)
    z[7:11] = sc.start.q  # at rest, no spin: c = 0
    stick, z1 = slip.settle(t, z, sp, False)
    s = slip.geometry(z1, sp)[1]
    f = np.asarray(m.g_k[:2]) - slip.slide_surface(sp, t)[1][:2]
    d = np.linalg.solve(B, f)
    assert not stick and np.linalg.norm(s) == pytest.approx(2e-11, rel=1e-9)
    np.testing.assert_allclose(s / np.linalg.norm(s), d / np.linalg.norm(d), atol=1e-9)
    # f + c is another direction (1.9e-3 rad away here), far outside the 1e-9 above
    assert abs(d[0] * f[1] - d[1] * f[0]) > 1e-3 * np.linalg.norm(d) * np.linalg.norm(f)


def test_planar_length_is_hypot_within_two_ulp_and_at_the_extremes():
    """The slip's |(x, y)| (sqrt of the sum of squares) against math.hypot: within 2 ulp on 10^4 random pairs over
    40 decades, exact on Pythagorean triples, and where a square would under- or overflow (hypot's own answer)."""
    rng = np.random.default_rng(4)
    for x, y in rng.normal(size=(10000, 2)) * 10.0 ** rng.uniform(-20, 20, (10000, 1)):
        assert slip.planar_length(x, y) == pytest.approx(math.hypot(x, y), rel=2 * EPS, abs=0)
    assert slip.planar_length(3.0, -4.0) == 5.0 and slip.planar_length(0.0, 0.0) == 0.0
    for scale in (1e-160, 1e-300, 1e160, 1e300):
        assert slip.planar_length(3 * scale, 4 * scale) == math.hypot(3 * scale, 4 * scale)
        assert slip.planar_length(3 * scale, 4 * scale) == pytest.approx(5 * scale, rel=EPS)


def test_cold_cache_is_announced_in_the_estimate(tmp_path, monkeypatch):
    """A run that will compile the engine says so, and its estimate carries the one-off compile time."""
    sc = default_scene(tmp_path, 0.05, **{'mode = "accurate"': 'mode = "accurate"\nengine = "compiled"'})
    compiled.simulate(sc.model, sc.numerics, sc.start, 0.01)
    assert not compiled.ENGINE.cold()  # compiled (or loaded) in this process: cached for this source
    monkeypatch.setattr(sample, "slowdown", lambda: 1.0)  # as on an idle core
    monkeypatch.setattr(compiled.ENGINE, "needs_compile", lambda: False)
    warm = motion_scene.estimate(sc)
    monkeypatch.setattr(compiled.ENGINE, "needs_compile", lambda: True)
    cold = motion_scene.estimate(sc)
    assert warm.once == 0.0 and "compiling" not in warm.what
    assert cold.once == compiled.COLD_COMPILE_SECONDS == pytest.approx(cold.seconds - warm.seconds, rel=1e-12)
    assert "compiling the grain engine once, ~80 s; later runs start in ~1 s" in cold.what
    python = motion_scene.estimate(replace(sc, numerics=replace(sc.numerics, engine="python")))
    assert warm.seconds == pytest.approx(python.seconds / motion_scene.COMPILED_SPEEDUP, rel=1e-12)


def test_a_lift_off_whose_dip_lies_midway_between_two_scan_points_is_found():
    """The compiled scan as the Python one (tests/test_grain_motion_hops.py): a dip below zero between two
    equal samples is a contact."""
    midway_dip(compiled.simulate)


def test_a_run_that_ends_just_after_a_lift_off_ends_in_flight():
    """The compiled loop as the Python one (tests/test_grain_motion_hops.py): no landing at the end of a run that
    ends less than a scan step after a lift-off."""
    lift_off_at_the_end(compiled.simulate)
