"""The compiled loop with the exact flight (``Numerics.flight = "exact"``: closed-form rotation, the contact
certified by the gap's curvature bound) against the compiled loop's DOP853 flight at a tight tolerance, the Python
loop's exact flight, and closed forms: the default scene, a sphere, a tumbling asymmetric ellipsoid and a
near-grazing contact."""
import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.optimize import brentq

from grain_sliding_reference import conveyor, on_plane
from test_grain_compiled import assert_same, both
from test_grain_hard_cases import CROP, sweep_grain
from test_grain_regimes import default_scene
from symmech.grain import flight, motion
from symmech.grain.coulomb_law import ImpactLaw
from symmech.grain.motion_engine import driver as compiled

G = 9.81
pytestmark = [pytest.mark.slow, pytest.mark.compiled_engine]  # the engine's build: slow tier (conftest.py)


def impact_times(engine, model, num, start, t_end):
    return np.array([i["t"] for i in engine.simulate(model, num, start, t_end).impacts])


def exact_and_dop853(model, num, start, t_end, reference_tolerance):
    """Impact times of the compiled loop: exact flight at ``num``'s tolerance, DOP853 at ``reference_tolerance``."""
    exact = impact_times(compiled, model, replace(num, flight="exact"), start, t_end)
    ref = impact_times(compiled, model, replace(num, flight="dop853", tolerance=reference_tolerance), start, t_end)
    return exact, ref


def vibrating_sphere():
    """Sphere (1 mm) on a vertically vibrating plate near its period-1 orbit (Gamma = 1.3, e = 0.5)."""
    e, gamma, freq = 0.5, 1.3, 20.0
    w = 2 * math.pi * freq
    phi = math.acos(math.pi * (1 - e) / ((1 + e) * gamma))
    vib = flight.Vibration(gamma * G / w**2, w, phi, (0.0, 0.0, 1.0))
    law = ImpactLaw("coulomb", e_n=e, e_t=0.0, mu=0.0, check_printed=False)
    model = motion.Model((1e-3,) * 3, 1e-6, (0.0, 0.0, -G), vib, law, 0.5, motion.Effects(rotation=False))
    v0 = 1.05 * G / freq / 2 - vib.amplitude * w * math.cos(phi)
    return model, motion.State(0.0, np.array([0.0, 0.0, 1e-3]), np.array([0.0, 0.0, v0]),
                               np.array([1.0, 0, 0, 0]), np.zeros(3))


def tumbling_ellipsoid():
    """The vibrating sphere's plate with an asymmetric ellipsoid (3.5, 1.6, 1.4) mm spinning at (40, 60, 90) rad/s,
    restitution 0.9."""
    model, st = vibrating_sphere()
    axes = (3.5e-3, 1.6e-3, 1.4e-3)
    model = replace(model, axes=axes, mass=1300 * 4 / 3 * math.pi * math.prod(axes),
                    law=replace(model.law, e_n=0.9), effects=motion.Effects(rotation=True))
    return model, replace(st, r=np.array([0.0, 0.0, 4e-3]), w=np.array([40.0, 60.0, 90.0]))


@pytest.mark.parametrize("duration", [0.1, 0.4])
def test_default_scene_impacts_are_those_of_dop853_at_a_tight_tolerance(tmp_path, duration):
    """The default scene (tolerance 1e-9) with the exact flight: the impact sequence of the compiled DOP853 flight
    at rtol 1e-12 within 2e-9 periods, as the Python loop's exact flight (tests/test_grain_free_flight.py)."""
    sc = default_scene(tmp_path, duration)
    exact, ref = exact_and_dop853(sc.model, sc.numerics, sc.start, sc.duration, 1e-12)
    assert len(exact) == len(ref) >= (10 if duration < 0.2 else 90)
    np.testing.assert_allclose(exact, ref, rtol=0, atol=2e-9 * sc.model.period)


def test_default_scene_compiled_exact_flight_is_the_python_exact_flight(tmp_path):
    """The compiled and the Python loop on the exact flight (scipy's elliptic functions there, the AGM and
    Carlson's duplication here), 0.4 s: the same 93 impacts, times within 10 x the contact's time tolerance
    (tolerance x scan step; measured 5.5 x in the chattering runs, where Brent's last steps differ), the same
    landings and final state; DOP853 at the scene's tolerance is 240 times farther off (6.1e-8 periods)."""
    sc = default_scene(tmp_path, 0.4)
    num = replace(sc.numerics, flight="exact")
    got = compiled.simulate(sc.model, num, sc.start, sc.duration)
    ref = motion.simulate(sc.model, num, sc.start, sc.duration)
    assert len(got.impacts) == len(ref.impacts) >= 90
    np.testing.assert_allclose([i["t"] for i in got.impacts], [i["t"] for i in ref.impacts], rtol=0,
                               atol=10 * num.tolerance * num.scan_step)
    assert got.extra["landings"] == ref.extra["landings"]
    assert got.trajectory.shape == ref.trajectory.shape
    np.testing.assert_array_equal(got.trajectory[:, -1], ref.trajectory[:, -1])  # the regime of every row
    np.testing.assert_allclose(got.final.r, ref.final.r, rtol=0, atol=1e-10)
    np.testing.assert_allclose(got.final.q, ref.final.q, rtol=0, atol=1e-8)


def printed_law_default_scene(tmp_path):
    sc = default_scene(tmp_path, 0.2)
    return replace(sc.model, law=ImpactLaw("printed", e=0.4, lam=0.3)), sc.numerics, sc.start, 0.2


def rolling_conveyor(tmp_path):
    model = conveyor(0.7, rotation=True)
    T = model.period
    num = motion.Numerics(tolerance=1e-10, scan_step=T / 40, sample_interval=T / 20)
    return model, num, on_plane(v=(0.03, -0.02, 0.0), w=(0.0, 0.0, 5.0)), 4 * T


def rocking_crop(tmp_path):
    sc = sweep_grain(CROP, 1.0e-3, 32.0, 0.04)
    return sc.model, sc.numerics, sc.start, 0.04


@pytest.mark.parametrize("case, state_rtol", [(printed_law_default_scene, 1e-7), (rocking_crop, 1e-7),
                                              (rolling_conveyor, 1e-6)])
def test_the_compiled_exact_flight_runs_every_regime_as_the_python_one(tmp_path, case, state_rtol):
    """Through landings, slides, lift-offs and a rocking contact (the tumbling crop grain at 32 Hz), with the
    printed law's verdicts: the compiled and the Python loop on the exact flight log the same events, rows and
    regimes, event times within 1e-11 s, and an impact's within the gap's round-off over its approach speed
    (``impact_time_tolerances``: the crop grain's chattering tail, 17 impacts down to |u_n| = 6.7e-8 m/s, parts
    the two loops by 2.7e-11 s on one machine, 5.1e-12 on another), states within ``state_rtol`` (the tests of the
    DOP853 flight's; the spinning sphere's stick-slip phases amplify round-off: 1.6e-7 measured, 3e-8 between the
    two loops' DOP853 flights)."""
    model, num, start, t_end = case(tmp_path)
    c, p = both(model, replace(num, flight="exact"), start, t_end)
    assert len(p.impacts) + p.extra["landings"] + p.extra["rocking_contacts"] >= 4
    assert c.extra["rocking_contacts"] == p.extra["rocking_contacts"]
    assert_same(c, p, 1e-11, state_rtol, gap_length=max(model.axes))


def test_sphere_on_a_vibrating_plate_bounces_as_with_dop853():
    """20 impacts of the period-1 orbit: the same with the exact flight as with DOP853 (no rotation: the same
    parabola, only the contact search differs), within 1e-12 periods."""
    model, st = vibrating_sphere()
    T = model.period
    num = motion.Numerics(tolerance=1e-10, scan_step=T / 40, sample_interval=T)
    exact, ref = exact_and_dop853(model, num, st, 20.5 * T, 1e-10)
    assert len(exact) == len(ref) == 20
    np.testing.assert_allclose(exact, ref, rtol=0, atol=1e-12 * T)


def test_sphere_drop_on_a_still_plate_hits_at_the_closed_form_times():
    """Point mass dropped from h with e = 0.5 on the exact flight: t_1 = sqrt(2h/g), t_(k+1) = t_k + 2 e^k v_1 / g."""
    e, h, radius = 0.5, 0.02, 1e-3
    law = ImpactLaw("coulomb", e_n=e, e_t=0.0, mu=0.0, check_printed=False)
    vib = flight.Vibration(0.0, 2 * math.pi * 25.0, 0.0, (0.0, 0.0, 1.0))
    model = motion.Model((radius,) * 3, 1e-6, (0.0, 0.0, -G), vib, law, 0.4, motion.Effects(rotation=False))
    start = motion.State(0.0, np.array([0.0, 0.0, radius + h]), np.zeros(3), np.array([1.0, 0, 0, 0]), np.zeros(3))
    num = motion.Numerics(tolerance=1e-12, scan_step=1e-3, sample_interval=0.01, rest_velocity=1e-3, flight="exact")
    got = impact_times(compiled, model, num, start, 0.6)[:8]
    v1 = math.sqrt(2 * G * h)
    expected = np.cumsum([math.sqrt(2 * h / G)] + [2 * e**k * v1 / G for k in range(1, 8)])
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)


def test_tumbling_asymmetric_ellipsoid_bounces_as_with_dop853_and_the_python_exact_flight():
    """An asymmetric ellipsoid tumbling about no principal axis, 21 impacts in 20 periods, a chaotic sequence (a
    difference grows ~10x an impact). Against DOP853 at rtol 1e-13, at the same tolerance 1e-10: the exact flight
    is at every impact at least 10x closer than DOP853 (measured 145-600x), the first 8 impacts within 2e-10
    periods; the Python loop's exact flight is at every impact 4x closer still to the compiled one (measured
    4.6-40x: the two differ by their elliptic functions' round-off, 2.8e-16 periods at the first impact, where
    the reference is 1.5e-15 off, and chaos amplifies both alike)."""
    model, st = tumbling_ellipsoid()
    T = model.period
    num = motion.Numerics(tolerance=1e-10, scan_step=T / 40, sample_interval=T)
    exact, ref = exact_and_dop853(model, num, st, 20.5 * T, 1e-13)
    dop853 = impact_times(compiled, model, num, st, 20.5 * T)
    assert len(exact) == len(ref) == len(dop853) >= 20
    exact_error, dop853_error = np.abs(exact - ref), np.abs(dop853 - ref)
    assert np.all(exact_error <= dop853_error / 10)
    assert exact_error[:8].max() <= 2e-10 * T
    python = impact_times(motion, model, replace(num, flight="exact"), st, 20.5 * T)
    assert len(python) == len(exact)
    assert np.all(np.abs(python - exact) <= exact_error / 4)


def grazing(depth):
    """Prolate ellipsoid (2, 1, 1) mm, long axis horizontal, spinning at 200 rad/s about its horizontal body y
    axis, thrown up so that its long axis stands vertical at the top of its flight, its tip ``depth`` [m] below
    the still plate then; and the independent closed form of its gap [m] at t [s]."""
    a, c, w = 2e-3, 1e-3, 200.0
    top = math.pi / 2 / w
    law = ImpactLaw("coulomb", e_n=0.5, e_t=0.0, mu=0.0, check_printed=False)
    vib = flight.Vibration(0.0, 2 * math.pi * 25.0, 0.0, (0.0, 0.0, 1.0))
    model = motion.Model((a, c, c), 1e-5, (0.0, 0.0, -G), vib, law, 0.0,
                         motion.Effects(vibration=False, friction=False))
    z0, v0 = a - depth - G * top**2 / 2, G * top
    start = motion.State(0.0, np.array([0.0, 0.0, z0]), np.array([0.0, 0.0, v0]), np.array([1.0, 0, 0, 0]),
                         np.array([0.0, w, 0.0]))

    def gap(t):
        return z0 + v0 * t - G * t**2 / 2 - np.sqrt(a**2 * np.sin(w * t) ** 2 + c**2 * np.cos(w * t) ** 2)
    return model, start, gap, top


@pytest.mark.parametrize("depth", [1e-7, -1e-7])
def test_a_near_grazing_contact_is_found_or_passed_as_the_closed_form_says(depth):
    """The tip dips 0.1 um below the plate for ~0.1 ms (found, between scan points 1 ms apart) or passes 0.1 um
    above it (no contact until the grain falls back): the first impact at the closed form's first root, by both
    flights; any later ones where DOP853 at rtol 1e-12 puts them."""
    model, start, gap, top = grazing(depth)
    t = np.linspace(0.0, 0.03, 300001)
    first = np.argmax(gap(t) <= 0.0)
    expected = brentq(gap, t[first - 1], t[first], xtol=1e-15)
    assert (expected < top) == (depth > 0)
    num = motion.Numerics(tolerance=1e-10, scan_step=1e-3, sample_interval=1e-2)
    exact, ref = exact_and_dop853(model, num, start, 0.04, 1e-12)
    assert len(exact) == len(ref) >= 1
    assert exact[0] == pytest.approx(expected, abs=1e-12)
    assert ref[0] == pytest.approx(expected, abs=1e-12)
    np.testing.assert_allclose(exact, ref, rtol=0, atol=1e-9)
