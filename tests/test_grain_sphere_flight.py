"""The compiled loop's default flight for grains whose gap does not depend on their attitude (a sphere, a grain with
rotation off): the closed form, checked against the parabola-minus-sine gap solved here by scipy's brentq, a
constant-rate rotation, and the DOP853 flight kept selectable; the population call against grain-by-grain runs."""
import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.optimize import brentq

from test_grain_compiled_exact_flight import vibrating_sphere
from symmech.grain import motion, motion_scene
from symmech.grain.motion_engine import driver as compiled
from symmech.grain.motion_engine.layouts import PARAMS

pytestmark = [pytest.mark.slow, pytest.mark.compiled_engine]  # the engine's build: slow tier (conftest.py)
PERIODS = 20.5


def parabola_minus_sine(model, start, t_end, xtol=1e-15):
    """Impact times of a sphere of radius a on the plate s(t) = A sin(omega t + phase) (vertical): between impacts
    the gap is z_abs(t) - s(t) - a, z_abs a parabola under gravity; scanned at T/400, brentq; the relative normal
    velocity reversed times e at each impact. Independent of the engine's kernels."""
    vib, e, g, a = model.vibration, model.law.e_n, -model.g_k[2], model.axes[0]
    A, w, ph = vib.amplitude, vib.omega, vib.phase
    step = model.period / 400
    t0, z0, v0, times = start.t, float(start.r[2]), float(start.v[2]), []
    while True:
        za, va = z0 + A * math.sin(w * t0 + ph), v0 + A * w * math.cos(w * t0 + ph)  # absolute at t0

        def gap(t, t0=t0, za=za, va=va):
            tau = t - t0
            return za + va * tau - 0.5 * g * tau * tau - A * math.sin(w * t + ph) - a
        lo = t0 + 1e-3 * step  # off the plate
        while lo < t_end and gap(min(lo + step, t_end)) > 0.0:
            lo += step
        if lo >= t_end:
            return np.array(times)
        tc = brentq(gap, lo, min(lo + step, t_end), xtol=xtol, rtol=4 * np.finfo(float).eps)
        times.append(tc)
        t0, z0, v0 = tc, a, -e * (va - g * (tc - t0) - A * w * math.cos(w * tc + ph))


def sphere_numerics(model, **kwargs):
    T = model.period
    return motion.Numerics(scan_step=T / 40, sample_interval=T / 4, tolerance=1e-10, engine="compiled", **kwargs)


def quaternion_of_constant_rate(q0, w_body, tau):
    """q0 (x) (cos(|w| tau / 2), sin(|w| tau / 2) w / |w|): the attitude after tau [s] at the body rate w."""
    rate = np.linalg.norm(w_body)
    c, s = math.cos(0.5 * rate * tau), math.sin(0.5 * rate * tau)
    p = np.array([c, *(s * np.asarray(w_body) / rate)])
    a0, a = q0[0], np.asarray(q0[1:])
    b0, b = p[0], p[1:]
    return np.array([a0 * b0 - a @ b, *(a0 * b + b0 * a + np.cross(a, b))])


@pytest.mark.parametrize("spin", [False, True])
def test_sphere_impact_times_are_the_parabola_minus_sine(spin):
    """Default numerics (``flight = "auto"``): a sphere with rotation off, and one spinning at (30, -50, 70) rad/s
    (frictionless impacts through its centre leave the spin alone): 20 impact times within 1e-12 of the period
    of the closed form solved by brentq; the spinning sphere's attitude at the end that of a constant-rate
    rotation (1e-12), its rate unchanged (1e-12 relative: each impact's arithmetic)."""
    model, start = vibrating_sphere()
    w0 = np.array([30.0, -50.0, 70.0])
    if spin:
        model = replace(model, effects=motion.Effects(rotation=True))
        start = replace(start, w=w0)
    t_end = PERIODS * model.period
    run = compiled.simulate(model, sphere_numerics(model), start, t_end)
    got, ref = np.array([i["t"] for i in run.impacts]), parabola_minus_sine(model, start, t_end)
    assert len(ref) == 20 and len(got) == len(ref)
    assert np.max(np.abs(got - ref)) <= 1e-12 * model.period
    if spin:
        assert np.max(np.abs(run.final.w - w0)) <= 1e-12 * np.linalg.norm(w0)
        expected = quaternion_of_constant_rate(start.q, w0, run.final.t - start.t)
        assert np.max(np.abs(run.final.q - expected)) <= 1e-12


def test_auto_flies_in_closed_form_where_the_gap_ignores_the_attitude(tmp_path):
    """``flight = "auto"`` packs the closed form for a sphere (rotating or not) and for an ellipsoid with rotation
    off, the DOP853 flight for a rotating ellipsoid; "dop853" and "exact" are kept as asked."""
    sphere, _ = vibrating_sphere()
    ellipsoid = replace(sphere, axes=(3e-3, 2e-3, 1e-3))
    num = motion.Numerics()

    def closed_form(model, num=num):
        return PARAMS.unpack(compiled.pack(model, num))["exact_flight"] == 1.0
    on = motion.Effects(rotation=True)
    assert closed_form(sphere) and closed_form(replace(sphere, effects=on)) and closed_form(ellipsoid)
    assert not closed_form(replace(ellipsoid, effects=on))
    assert not closed_form(sphere, replace(num, flight="dop853"))
    assert closed_form(replace(ellipsoid, effects=on), replace(num, flight="exact"))
    with pytest.raises(ValueError, match="'auto', 'dop853', 'exact'"):
        motion.Numerics(flight="rk4")


def test_dop853_flight_stays_selectable_and_agrees():
    """The reference path, asked for: the same 20 impacts as the closed form within 1e-12 of the period."""
    model, start = vibrating_sphere()
    t_end = PERIODS * model.period
    auto = compiled.simulate(model, sphere_numerics(model), start, t_end)
    dop = compiled.simulate(model, sphere_numerics(model, flight="dop853"), start, t_end)
    a, d = np.array([i["t"] for i in auto.impacts]), np.array([i["t"] for i in dop.impacts])
    assert len(a) == len(d) == 20
    assert np.max(np.abs(a - d)) <= 1e-12 * model.period
    assert not np.array_equal(a, d)  # two paths, not one run twice


def test_an_ellipsoid_with_rotation_off_flies_in_closed_form_as_dop853_does():
    """A tilted ellipsoid (3, 2, 1) mm with rotation off keeps its attitude, so its gap is the centre's height less a
    constant support: the default closed form and the DOP853 flight give the same impacts within 1e-12 of the
    period, and the attitude stays the start's."""
    model, start = vibrating_sphere()
    model = replace(model, axes=(3e-3, 2e-3, 1e-3))
    q = np.array([0.9, 0.3, -0.2, 0.1])
    start = replace(start, r=np.array([0.0, 0.0, 3e-3]), q=q / np.linalg.norm(q))
    t_end = PERIODS * model.period
    auto = compiled.simulate(model, sphere_numerics(model), start, t_end)
    dop = compiled.simulate(model, sphere_numerics(model, flight="dop853"), start, t_end)
    a, d = np.array([i["t"] for i in auto.impacts]), np.array([i["t"] for i in dop.impacts])
    assert len(a) == len(d) >= 15
    assert np.max(np.abs(a - d)) <= 1e-12 * model.period
    assert np.max(np.abs(auto.final.q - start.q)) <= 1e-15


def population(n):
    """n spheres started at their own heights and speeds (seeded), as scenes of the default numerics."""
    model, start = vibrating_sphere()
    rng = np.random.default_rng(7)
    scenes = []
    for _ in range(n):
        st = replace(start, r=start.r + np.array([0.0, 0.0, rng.uniform(0, 3e-4)]), v=start.v * rng.uniform(0.97, 1.03))
        scenes.append(motion_scene.GrainScene(model, sphere_numerics(model), st, PERIODS * model.period, (0.0, 0.0),
                                              {}, {}))
    return scenes


@pytest.mark.parametrize("n, workers", [(5, 1), (40, 2)])
def test_population_call_equals_grain_by_grain(n, workers):
    """``motion_scene.simulate_many`` (one packing, the grains in one compiled call per thread) gives each grain bit
    for bit what ``motion_scene.simulate`` gives it: trajectory, impact log, final state, time in flight, energy
    budget, engine."""
    scenes = population(n)
    many = motion_scene.simulate_many(scenes, workers=workers)
    times = [m.impact_times() for m in many]  # read from the rows: the logs not built yet
    assert len({t[0] for t in times}) == n  # the grains differ
    for sc, m, t in zip(scenes, many, times):
        one = motion_scene.simulate(sc)
        assert t.tolist() == [i["t"] for i in one.impacts] == one.impact_times().tolist()
        assert np.array_equal(m.trajectory, one.trajectory)
        assert m.impacts == one.impacts
        assert np.array_equal(m.final.r, one.final.r) and m.final.t == one.final.t
        assert m.time_in == one.time_in and m.warnings == one.warnings
        assert m.extra == one.extra
