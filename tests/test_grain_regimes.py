"""Regime changes of the grain motion: impacts need an approaching contact, flight in local
time, spin kept through landing and sliding with a closing energy budget, sliding without stalls or drift
against an independent event-driven integration, progress callbacks.

Expected values come from closed forms, mpmath or independent integrations written here.
"""
import math
import time
from dataclasses import replace

import mpmath
import numpy as np
import pytest

from grain_sliding_reference import RADIUS, conveyor, on_plane, population, reference, sphere
from symmech.core import pipeline
from symmech.core.scene import SymmechError
from symmech.generated import grain_motion as gm
from symmech.grain import flight, motion, motion_scene, paper_mode

G = 9.81


def default_scene(tmp_path, duration, **replace_text):
    text = open("scenes/grain_default.toml").read().replace("duration = 2.0", f"duration = {duration}")
    for old, new in replace_text.items():
        text = text.replace(old, new)
    path = tmp_path / "scene.toml"
    path.write_text(text)
    return pipeline.load(path).setup


def numerics(model, **kw):
    T = model.period
    return motion.Numerics(tolerance=1e-10, scan_step=T / 40, sample_interval=T / 4, **kw)


# --------------------------------------------------------------------------- 1. impacts approach


def test_default_scene_impacts_approach_and_the_energy_budget_closes(tmp_path):
    """Before: 9 of the ~143 impacts of the first 0.6 s had a separating contact and zero impulse (noise roots).
    Energy: input by the surface = change of energy + losses in impacts, landings and sliding."""
    res = motion_scene.simulate(default_scene(tmp_path, 0.6))
    assert len(res.impacts) > 100
    u_n = np.array([i["u_before"][2] for i in res.impacts])
    P_n = np.array([i["impulse"][2] for i in res.impacts])
    assert np.all(u_n < -1e-9) and np.all(P_n > 0)
    # Every impact is a real one: no two within 1e-9 s.
    assert np.min(np.diff([i["t"] for i in res.impacts])) > 1e-9
    b = res.extra["energy_budget"]
    assert b["input_by_surface_J"] > 0 and b["lost_in_impacts_J"] > 0 and b["lost_in_sliding_J"] > 0
    assert b["relative_residual"] < 1e-8 <= b["tolerance"]
    assert res.summary()["energy_budget"] is b


def test_grain_resting_on_the_plane_slides_and_never_impacts():
    """A sphere released on an incline rolls without slipping (2/7 tan(0.2) < mu): x = -5/14 g sin(0.2) t^2."""
    model = sphere(mu=0.5, g_k=tuple(gm.gravity(G, 0.2, 0.0)))
    res = motion.simulate(model, numerics(model), on_plane(), 0.5)
    assert res.impacts == [] and res.time_in["sliding"] == 0.5
    np.testing.assert_allclose(res.final.r, [-5 / 14 * G * math.sin(0.2) * 0.25, 0.0, RADIUS], rtol=1e-9)


# --------------------------------------------------------------------------- 2. flight in local time


@pytest.mark.parametrize("t0", [0.0, 1e4])
def test_flight_translation_is_exact_at_large_times(t0):
    """Against mpmath at 40 digits: before, 2.7e-8 m at t = 1e4 s (absolute-time cancellation)."""
    vib = flight.Vibration(1e-3, 2 * math.pi * 25, 0.4, (0.6, 0.0, 0.8))
    g_k = gm.gravity(G, 0.05, -0.02)
    r0, v0 = np.array([0.01, -0.02, 2e-3]), np.array([0.1, -0.02, 0.3])
    tau = 0.0371
    got, _ = flight.translate(r0, v0, g_k, vib, t0, t0 + tau)
    mpmath.mp.dps = 40
    T0, T = mpmath.mpf(t0), mpmath.mpf(t0 + tau)  # the float times exactly
    om, ph, A = mpmath.mpf(vib.omega), mpmath.mpf(vib.phase), mpmath.mpf(vib.amplitude)
    bracket = mpmath.sin(om * T + ph) - mpmath.sin(om * T0 + ph) - om * (T - T0) * mpmath.cos(om * T0 + ph)
    for k in range(3):
        exact = (mpmath.mpf(r0[k]) + mpmath.mpf(v0[k]) * (T - T0) + mpmath.mpf(g_k[k]) * (T - T0) ** 2 / 2
                 - A * mpmath.mpf(vib.direction[k]) * bracket)
        assert abs(got[k] - float(exact)) < 2e-11


# --------------------------------------------------------------------------- 4. spin and energy


def test_sliding_sphere_starts_rolling_at_five_sevenths_of_its_speed():
    """Classical: a sphere launched without spin on a still plate rolls at 5/7 v0 after 2 v0 / (7 mu g);
    before, the spin was dropped and the sphere stopped."""
    mu, v0 = 0.3, 0.05
    model = sphere(mu=mu)
    res = motion.simulate(model, numerics(model), on_plane(v=(v0, 0.0, 0.0)), 0.1)
    t_roll = 2 * v0 / (7 * mu * G)
    np.testing.assert_allclose(res.final.v, [5 * v0 / 7, 0.0, 0.0], atol=1e-9)
    x_roll = v0 * t_roll - mu * G * t_roll**2 / 2
    assert res.final.r[0] == pytest.approx(x_roll + 5 * v0 / 7 * (0.1 - t_roll), abs=1e-9)
    w = flight.rotation_matrix(res.final.q) @ res.final.w
    np.testing.assert_allclose(w, [0.0, 5 * v0 / 7 / RADIUS, 0.0], atol=1e-6)
    budget = res.extra["energy_budget"]
    assert budget["lost_in_sliding_J"] == pytest.approx(0.5 * 1e-6 * v0**2 * 2 / 7, rel=1e-8)
    assert budget["relative_residual"] < 1e-9


def test_landing_keeps_the_angular_momentum_about_the_contact():
    """A spinning sphere dropped plastically: the landing impulse is normal, so the horizontal angular momentum
    about the contact point, m R_KC x v + I w, carries into sliding."""
    model = sphere(mu=0.2)
    st = on_plane(v=(0.02, 0.0, -0.05), w=(0.0, 40.0, 0.0))
    res = motion.simulate(model, numerics(model), st, 2e-4)
    m, I = 1e-6, 0.4 * 1e-6 * RADIUS**2
    r_kc = np.array([0.0, 0.0, RADIUS])

    def h_k(v, w):
        return m * np.cross(r_kc, v) + I * w
    w_end = flight.rotation_matrix(res.final.q) @ res.final.w
    # Sliding friction over 2e-4 s changes it only through the friction couple at K (zero about K).
    np.testing.assert_allclose(h_k(res.final.v, w_end)[:2], h_k(np.array([0.02, 0, 0]), st.w)[:2], rtol=1e-9)
    assert w_end[1] > 30.0  # the spin survives


# --------------------------------------------------------------------------- 5. sliding: no stall, no drift


def check_population(n, seed, t_end):
    cpu, worst = [], 0.0
    for phase, v0 in zip(*population(n, seed)):
        model = conveyor(phase)
        start = time.process_time()
        res = motion.simulate(model, replace(numerics(model), tolerance=1e-11), on_plane(v=(*v0, 0.0)), t_end)
        cpu.append(time.process_time() - start)
        r_ref, _ = reference(model.g_k, model.vibration, model.mu, RADIUS, v0, t_end)
        worst = max(worst, abs(res.final.r[0] - r_ref[0]) / abs(r_ref[0]), abs(res.final.r[1] - r_ref[1]))
    return np.array(cpu), worst


def test_sideways_sliding_population_matches_event_driven_reference():
    """8 grains (the slow test runs 50): before, ~6 % stalled (one 280 CPU-s for 0.5 s) and the transport
    velocity was off by 6e-4 relative."""
    cpu, worst = check_population(8, 5, 0.2)
    assert cpu.max() < 5.0
    assert worst < 1e-7  # relative transport distance along X; absolute [m] across


@pytest.mark.slow
def test_sideways_sliding_population_of_fifty():
    cpu, worst = check_population(50, 7, 0.5)
    assert cpu.max() < 10.0
    assert worst < 1e-7


def test_steep_downhill_scene_finishes(tmp_path):
    sc = default_scene(tmp_path, 0.25, **{"alpha_deg = 3.0": "alpha_deg = -37.7",
                                          "velocity = [0.0, 0.0, 0.0]": "velocity = [0.0, 0.03, 0.0]"})
    start = time.process_time()
    res = motion_scene.simulate(sc)
    assert time.process_time() - start < 10.0
    assert res.final.t == 0.25 and res.final.r[0] > 0.1  # down the slope (g_X > 0)


# --------------------------------------------------------------------------- 6. progress


def test_progress_is_reported_and_an_exception_in_it_stops_the_run(monkeypatch):
    monkeypatch.setattr(motion, "PROGRESS_INTERVAL", 0.0)
    model = conveyor(0.3)
    seen = []
    motion.simulate(model, numerics(model), on_plane(v=(0.0, 0.02, 0.0)), 0.2, on_step=seen.append)
    assert len(seen) > 10 and seen == sorted(seen) and 0.0 <= seen[0] and seen[-1] <= 0.2

    class Budget(Exception):
        pass

    def stop(t_now):
        if t_now > 0.05:
            raise Budget(t_now)
    with pytest.raises(Budget) as info:
        motion.simulate(model, numerics(model), on_plane(v=(0.0, 0.02, 0.0)), 0.2, on_step=stop)
    assert 0.05 < info.value.args[0] < 0.1
    with pytest.raises(Budget) as info:  # paper mode: the same contract
        paper_mode.simulate(model, numerics(model, mode="paper", dt=1e-4, nodes=20), on_plane(), 0.2,
                            on_step=stop)
    assert 0.05 < info.value.args[0] < 0.051


def test_stagnating_sliding_is_an_error_not_a_hang(monkeypatch):
    """The step-count guard: a sliding phase that needs more right-hand sides than allowed raises."""
    from symmech.grain import sliding
    monkeypatch.setattr(sliding, "MAX_RHS_PER_PHASE", 50)
    model = conveyor(0.3)
    with pytest.raises(SymmechError, match="stagnates"):
        motion.simulate(model, numerics(model), on_plane(v=(0.0, 0.02, 0.0)), 0.2)
