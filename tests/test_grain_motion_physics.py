"""Grain motion against physics that does not depend on the paper.

Expected values come from closed forms or independent integrations written here,
never from the code under test.
"""
import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from symmech.generated import grain_motion as gm
from symmech.grain import flight, motion, paper_mode
from symmech.grain.coulomb_law import ImpactLaw

G = 9.81
RADIUS = 1e-3


NO_ROTATION = motion.Effects(rotation=False)  # frozen: one instance serves every default


def sphere_model(gamma, e, freq=20.0, direction=(0.0, 0.0, 1.0), law=None, mu=0.5, phase=0.0,
                 effects=NO_ROTATION, g_k=(0.0, 0.0, -G)):
    w = 2 * math.pi * freq
    amp = gamma * G / w**2
    law = law or ImpactLaw("coulomb", e_n=e, e_t=0.0, mu=0.0, check_printed=False)
    return motion.Model((RADIUS,) * 3, 1e-6, g_k, flight.Vibration(amp, w, phase, direction), law, mu, effects)


def start(z=RADIUS, v=(0.0, 0.0, 0.0), w=(0.0, 0.0, 0.0), q=(1.0, 0.0, 0.0, 0.0)):
    return motion.State(0.0, np.array([0.0, 0.0, z]), np.array(v, float), np.array(q, float), np.array(w, float))


def numerics(model, **kw):
    T = model.period
    return motion.Numerics(tolerance=1e-11, scan_step=T / 40, sample_interval=T / 10, **kw)


def impact_phases(res, model):
    """Plate phase omega t + phase of every impact, in [0, 2 pi)."""
    vib = model.vibration
    return np.array([(vib.omega * i["t"] + vib.phase) % (2 * math.pi) for i in res.impacts])


# --------------------------------------------------------------------------- bouncing ball

def period1_start(gamma, e, freq=20.0):
    """Model whose plate phase is the period-1 impact phase at t = 0, and a state just after that impact."""
    phi = math.acos(math.pi * (1 - e) / ((1 + e) * gamma))
    model = sphere_model(gamma, e, freq, phase=phi)
    T = 1 / freq
    plate_v = model.vibration.amplitude * model.vibration.omega * math.cos(phi)
    # Absolute take-off speed g T / 2, perturbed by 5 % so the orbit has to attract.
    return model, start(v=(0.0, 0.0, 1.05 * G * T / 2 - plate_v)), phi


def test_period1_orbit_impact_phase():
    """cos(phi*) = pi (1 - e) / ((1 + e) Gamma) above Gamma = pi (1 - e)/(1 + e)."""
    e, gamma = 0.5, 1.3
    assert gamma > math.pi * (1 - e) / (1 + e)
    model, st, phi = period1_start(gamma, e)
    res = motion.simulate(model, numerics(model), st, 60.5 / 20.0)
    phases = impact_phases(res, model)
    assert len(phases) >= 50
    np.testing.assert_allclose(phases[-10:], phi, atol=1e-7)
    intervals = np.diff([i["t"] for i in res.impacts[-10:]])
    np.testing.assert_allclose(intervals, 1 / 20.0, rtol=1e-8)


def test_no_period1_orbit_below_onset():
    """Below Gamma = pi (1 - e)/(1 + e) no impact phase can satisfy the period-1 condition."""
    e = 0.5
    gamma = 0.9 * math.pi * (1 - e) / (1 + e)
    model = sphere_model(gamma, e)
    T = model.period
    res = motion.simulate(model, numerics(model), start(v=(0.0, 0.0, G * T / 2)), 40 * T)
    intervals = np.diff([i["t"] for i in res.impacts])
    assert not np.any(np.abs(intervals[-5:] - T) < 1e-3 * T)


def gamma_period_doubling(e):
    """Exact-map threshold: Gamma sin(phi*) = 1 + k^2, Gamma cos(phi*) = pi k, k = (1 - e)/(1 + e)."""
    k = (1 - e) / (1 + e)
    return math.hypot(1 + k * k, math.pi * k)


@pytest.mark.parametrize("factor, period", [(0.98, 1), (1.02, 2)])
def test_period_doubling_threshold(factor, period):
    """Period 1 just below the exact-map threshold, period 2 just above (tolerance +-2 % in Gamma)."""
    e = 0.5
    gamma = factor * gamma_period_doubling(e)
    phi = math.acos(min(1.0, math.pi * (1 - e) / ((1 + e) * gamma)))
    model = sphere_model(gamma, e, phase=phi)
    T = model.period
    plate_v = model.vibration.amplitude * model.vibration.omega * math.cos(phi)
    res = motion.simulate(model, numerics(model), start(v=(0.0, 0.0, 1.02 * G * T / 2 - plate_v)), 400.5 * T)
    phases = impact_phases(res, model)[-20:]
    spread_1 = np.ptp(phases)
    spread_2 = max(np.ptp(phases[::2]), np.ptp(phases[1::2]))
    if period == 1:
        assert spread_1 < 1e-3
    else:
        assert spread_1 > 1e-2 and spread_2 < 1e-3


# --------------------------------------------------------------------------- conveying

def conveying_model(gamma_v, angle_deg=30.0, freq=25.0):
    w = 2 * math.pi * freq
    gam = math.radians(angle_deg)
    amp = gamma_v * G / (w**2 * math.sin(gam))
    law = ImpactLaw("printed", e=0.0, lam=1.0)  # plastic landing, tangential slip killed
    vib = flight.Vibration(amp, w, 0.0, (math.cos(gam), 0.0, math.sin(gam)))
    return motion.Model((RADIUS,) * 3, 1e-6, (0.0, 0.0, -G), vib, law, 1e6, motion.Effects(rotation=False)), gam


def liftoffs(res):
    """Times where a sliding row is followed by a flight row."""
    reg = res.trajectory[:, -1]
    idx = np.flatnonzero((reg[:-1] == 2) & (reg[1:] == 0))
    return res.trajectory[idx, 0]


def test_point_mass_conveying_liftoff_and_mean_velocity():
    gamma_v = 1.5
    model, gam = conveying_model(gamma_v)
    T = model.period
    res = motion.simulate(model, numerics(model), start(), 8 * T)
    lifts = liftoffs(res)
    assert len(lifts) >= 6
    phase = (model.vibration.omega * lifts) % (2 * math.pi)
    np.testing.assert_allclose(np.sin(phase), 1 / gamma_v, atol=1e-8)
    # Classical flight: sin p0 - sin(p0 + P) + P cos p0 - P^2 sin(p0)/2 = 0, relative drift cot(gamma) g tau^2/2.
    p0 = math.asin(1 / gamma_v)
    Phi = brentq(lambda P: math.sin(p0) - math.sin(p0 + P) + P * math.cos(p0) - P * P * math.sin(p0) / 2,
                 0.1, 2 * math.pi)
    tau = Phi / model.vibration.omega
    expected = G * tau**2 / (2 * math.tan(gam)) / T
    x = np.interp(lifts, res.trajectory[:, 0], res.trajectory[:, 1])
    measured = (x[-1] - x[1]) / (lifts[-1] - lifts[1])
    assert measured == pytest.approx(expected, rel=1e-6)


def test_conveying_just_below_and_above_liftoff():
    """Gamma_v = 0.99: the grain never leaves the plane; Gamma_v = 1.01: it lifts off once per period."""
    below, _ = conveying_model(0.99)
    res = motion.simulate(below, numerics(below), start(), 4 * below.period)
    assert len(liftoffs(res)) == 0 and res.time_in["flight"] == 0.0
    above, _ = conveying_model(1.01)
    res = motion.simulate(above, numerics(above), start(), 4 * above.period)
    assert len(liftoffs(res)) == 4


# --------------------------------------------------------------------------- rotation

def test_torque_free_flight_conserves_energy_and_momentum_and_solves_euler():
    inertia = np.array([1.0, 2.0, 3.5]) * 1e-9
    q0 = np.array([0.9, 0.1, -0.3, 0.2])
    q0 /= np.linalg.norm(q0)
    w0 = np.array([30.0, -5.0, 12.0])
    rot = flight.RotationFlight(inertia, q0, w0, 0.0, 1e-11, 0.05)
    ts = np.linspace(0, 0.5, 11)
    q, w = rot.state(ts)
    inv = gm.rotation_invariants(*inertia, *w.T, *q.T)
    energy, L = inv[:, 0], inv[:, 1:]
    np.testing.assert_allclose(L, np.broadcast_to(L[0], L.shape), rtol=0, atol=1e-9 * np.linalg.norm(L[0]))
    np.testing.assert_allclose(energy, energy[0], rtol=1e-9)

    # Independent: Euler's equations written out, integrated by scipy's Radau.
    def euler(_t, y):
        a, b, c = inertia
        return [(b - c) / a * y[1] * y[2], (c - a) / b * y[2] * y[0], (a - b) / c * y[0] * y[1]]
    ref = solve_ivp(euler, (0, 0.5), w0, method="Radau", rtol=1e-12, atol=1e-12, t_eval=ts)
    np.testing.assert_allclose(w, ref.y.T, rtol=0, atol=1e-7 * np.linalg.norm(w0))


# --------------------------------------------------------------------------- references and convergence

def bouncing_reference(model, st, t_end):
    """Impact times of a ball on a vibrating plate: solve_ivp with terminal events, Newton restitution."""
    vib, e, times = model.vibration, model.law.e_n, []
    t, y = 0.0, np.array([st.r[2], st.v[2]])
    while t < t_end:
        def rhs(s, yy):
            return [yy[1], -G + vib.amplitude * vib.omega**2 * vib.direction[2] * math.sin(vib.omega * s + vib.phase)]

        def hit(s, yy):
            return yy[0] - RADIUS
        hit.terminal, hit.direction = True, -1
        sol = solve_ivp(rhs, (t, t_end), y, method="DOP853", rtol=1e-13, atol=1e-15, events=hit)
        if sol.status != 1:
            break
        t = sol.t_events[0][0]
        z, vz = sol.y_events[0][0]
        times.append(t)
        y = np.array([RADIUS, -e * vz])
        t = t + 1e-12  # leave the event surface
    return np.array(times)


def test_accurate_mode_matches_solve_ivp_reference_with_events():
    model, st, _ = period1_start(1.2, 0.6)
    model = replace(model, vibration=replace(model.vibration, phase=0.3))
    res = motion.simulate(model, numerics(model), st, 10 * model.period)
    ref = bouncing_reference(model, st, 10 * model.period)
    got = np.array([i["t"] for i in res.impacts])
    assert len(got) == len(ref) >= 5
    np.testing.assert_allclose(got, ref, atol=1e-9)


def test_paper_mode_converges_at_first_order():
    """Flight of a sphere over a vibrating plate: error of the fixed-step scheme ~ dt^p, p fitted."""
    model = sphere_model(3.0, 0.5)
    T = model.period
    st = start(z=5e-3, v=(0.02, 0.0, 0.05))
    exact = flight.translate(st.r, st.v, model.g_k, model.vibration, 0.0, T / 2)[0]
    dts, errs = [], []
    for steps in (100, 200, 400, 800):
        num = motion.Numerics(mode="paper", dt=T / steps, nodes=50, sample_interval=T)
        res = paper_mode.simulate(model, num, st, T / 2)
        assert len(res.impacts) == 0
        dts.append(T / steps)
        errs.append(np.linalg.norm(res.final.r - exact))
    order = np.polyfit(np.log(dts), np.log(errs), 1)[0]
    assert 0.9 < order < 1.1
