"""The exact free flight's compiled twin (free_flight_nb) against the scipy reference (free_flight) and closed
forms: special functions, the rotation record and state, the flight state, the gap and the next contact."""
import math

import mpmath
import numpy as np
import pytest
from scipy.special import ellipj, elliprf, elliprj

from symmech.grain import contact, flight, free_flight
from symmech.grain import free_flight_nb as nb
from test_grain_free_flight import SHAPES, start

# slow tier: compiling the twin costs ~5 s of CPU on a cold cache
pytestmark = pytest.mark.slow


def test_special_functions_match_scipy():
    ladder = np.empty(nb.LADDER_SIZE)
    for m in (0.0, 1e-12, 0.3, 0.9, 1 - 1e-6, 1 - 1e-11):
        nb.landen_ladder(m, ladder)
        for u in (-3.0, 0.1, 1.7, 5.0):
            np.testing.assert_allclose(nb.ellipj_on(u, m, ladder), ellipj(u, m), rtol=0, atol=2e-14)
    rng = np.random.default_rng(5)
    for x, y, z, p in rng.uniform(0.01, 3.0, (20, 4)):
        assert nb.carlson_rf(x, y, z) == pytest.approx(float(elliprf(x, y, z)), rel=1e-14)
        rf, rj = nb.carlson_rf_rj(x, y, z, p)
        assert rf == pytest.approx(float(elliprf(x, y, z)), rel=1e-14)
        assert rj == pytest.approx(float(elliprj(x, y, z, p)), rel=1e-14)
    assert nb.carlson_rf(0.0, 0.5, 1.0) == pytest.approx(float(elliprf(0.0, 0.5, 1.0)), rel=1e-14)


def test_closed_form_rc_on_both_sides_of_the_diagonal():
    """R_C against mpmath at 30 digits: below the diagonal (arctan), above it (the logarithm), on it, within 1e-9
    of it on both sides (where a naive form cancels), at x = 0 and with y a thousandth of x's square root."""
    mpmath.mp.dps = 30
    rng = np.random.default_rng(7)
    pairs = [tuple(rng.uniform(0.0, 2.0, 2) ** 4) for _ in range(200)]
    pairs += [(1.0, 1.0), (1.0, 1.0 + 1e-9), (1.0, 1.0 - 1e-9), (0.0, 2.0), (1e-30, 1.0), (1.0, 1e-30), (4.0, 2e-3)]
    for x, y in pairs:
        assert nb.carlson_rc(x, y) == pytest.approx(float(mpmath.elliprc(x, y)), rel=2e-15), (x, y)


def test_third_kind_integral_against_mpmath():
    """Pi(n; phi | m) for n <= 0 (the rotation's: n down to -100) and m up to 1 - 1e-9, against mpmath's."""
    mpmath.mp.dps = 30
    rng = np.random.default_rng(8)
    for n, phi, m in zip(-rng.uniform(0, 100, 300), rng.uniform(0, math.pi / 2, 300), rng.uniform(0, 1 - 1e-9, 300)):
        assert nb.third_kind(n, phi, m) == pytest.approx(float(mpmath.ellippi(n, phi, m)), rel=2e-14), (n, phi, m)


@pytest.mark.parametrize("shape", SHAPES)
def test_rotation_record_and_state_match_the_reference(shape):
    inertia, w0 = (np.array(x) for x in SHAPES[shape])
    q0 = start()
    ref = free_flight.ExactRotation(inertia, q0, w0, 0.25)
    rot, out = np.empty(free_flight.ROTATION.size), np.empty(7)
    nb.rotation_setup(inertia, q0, w0, 0.25, rot)
    own = np.ones(rot.size, bool)  # but the Landen ladder, the twin's own (the state below walks it)
    own[free_flight.ROTATION.slice("landen")] = False
    np.testing.assert_allclose(rot[own], ref.record()[own], rtol=1e-13, atol=1e-14)
    for t in np.linspace(0.25, 40.0, 9):
        nb.rotation_at(rot, t, out)
        q, w = ref.state(t)
        np.testing.assert_allclose(flight.rotation_matrix(out[:4]), flight.rotation_matrix(q), rtol=0, atol=1e-13)
        np.testing.assert_allclose(out[4:], w, rtol=0, atol=1e-13)


def flight_records(rng):
    """A random tumbling ellipsoid's flight over a vibrating plate: (state (14,), parameters, FLIGHT, ROTATION)."""
    axes = rng.uniform(1e-3, 4e-3, 3)
    inertia = 1e-3 * (np.sum(axes**2) - axes**2) / 5
    d = rng.normal(size=3)
    vib = flight.Vibration(rng.uniform(0, 1e-3), rng.uniform(50, 300), rng.uniform(0, 6), tuple(d / np.linalg.norm(d)))
    g = np.array([0.5, -0.2, -9.81])
    q = start(int(rng.integers(1000)))
    state = np.array([rng.uniform(0, 1), 0.0, 0.0, 6e-3, *rng.normal(size=2) * 0.1, 0.3, *q,
                      *rng.normal(size=3) * 100])
    fl, rot = np.empty(free_flight.FLIGHT.size), np.empty(free_flight.ROTATION.size)
    nb.flight_setup(state, g, vib.amplitude, vib.omega, vib.phase, np.array(vib.direction), axes, inertia, fl, rot)
    return state, (axes, inertia, vib, g), fl, rot


def test_flight_state_and_gap_match_the_reference():
    rng = np.random.default_rng(11)
    out, buf = np.empty(14), np.empty((1, 2, 3))
    for _ in range(10):
        state, (axes, inertia, vib, g), fl, rot = flight_records(rng)
        ref = free_flight.ExactRotation(inertia, state[7:11], state[11:14], state[0])
        for t in state[0] + np.array([0.0, 1e-3, 0.02, 0.1]):
            nb.flight_state(t, fl, rot, out)
            r, v = flight.translate(state[1:4], state[4:7], g, vib, state[0], t)
            q, w = ref.state(t)
            np.testing.assert_allclose(out[1:7], np.concatenate([r, v]), rtol=1e-14, atol=1e-16)
            np.testing.assert_allclose(out[11:], w, rtol=0, atol=1e-11)
            h, rate = nb.gap(t, fl, rot, buf)
            Q = flight.rotation_matrix(q)
            # the attitude's round-off: phi up to ~10 rad, known to ~1e-14 relative (both Pi's against mpmath),
            # times semi-axes up to 4 mm
            assert h == pytest.approx(r[2] - contact.support_distance(axes, Q), abs=2e-16)
            assert rate == pytest.approx(free_flight.gap_rate(v[2], axes, Q[2], w), rel=1e-11, abs=1e-15)
        assert nb.gap_curvature_bound(fl, rot) == pytest.approx(
            free_flight.gap_curvature_bound(g[2], vib, axes, inertia, ref.max_rate), rel=1e-14)


def test_next_contact_is_the_reference_first_contact():
    """The compiled certified search finds the Python search's contact (same bound, same Brent) to 1e-12 s."""
    rng = np.random.default_rng(12)
    buf = np.empty((1, 2, 3))
    for _ in range(10):
        state, (axes, inertia, vib, g), fl, rot = flight_records(rng)
        ref = free_flight.ExactRotation(inertia, state[7:11], state[11:14], state[0])

        def gap(t):
            (r, v), (q, w) = flight.translate(state[1:4], state[4:7], g, vib, state[0], t), ref.state(t)
            Q = flight.rotation_matrix(q)
            return float(r[2] - contact.support_distance(axes, Q)), float(free_flight.gap_rate(v[2], axes, Q[2], w))

        t0, step = state[0], 2e-3
        curvature = free_flight.gap_curvature_bound(g[2], vib, axes, inertia, ref.max_rate)
        expected = contact.first_contact(gap, curvature, t0, t0 + 1.0, step, 1e-13)
        got = nb.next_contact(fl, rot, t0, t0 + 1.0, step, 1e-13, buf)
        assert expected is not None and got == pytest.approx(expected, abs=1e-12)


def test_next_contact_finds_the_grazing_contact_a_scan_misses():
    """As test_grain_free_flight's grazing case: the long axis dips 0.1 um below the plane for ~0.5 ms between
    two 4 ms samples; closed form sin^2(omega t) = (z^2 - c^2) / (a^2 - c^2); 0.1 um short: no contact."""
    buf, axes = np.empty((1, 2, 3)), np.array([2e-3, 1e-3, 1e-3])
    fl, rot = np.empty(free_flight.FLIGHT.size), np.empty(free_flight.ROTATION.size)
    for depth in (1e-7, -1e-7):
        z0 = 2e-3 - depth
        state = np.array([0.1, 0.0, 0.0, z0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 50.0, 0.0])
        nb.flight_setup(state, np.zeros(3), 0.0, 1.0, 0.0, np.array([0.0, 0.0, 1.0]), axes,
                        np.array([1.0, 2.5, 2.5]), fl, rot)
        got = nb.next_contact(fl, rot, 0.1, 0.16, 0.004, 1e-13, buf)
        if depth > 0:
            exact = math.asin(math.sqrt((z0**2 - axes[1] ** 2) / (axes[0] ** 2 - axes[1] ** 2))) / 50.0
            assert got - 0.1 == pytest.approx(exact, abs=1e-12)
            assert nb.next_contact(fl, rot, 0.1 + math.pi / 100, 0.16, 0.004, 1e-13, buf) == 0.1 + math.pi / 100
        else:
            assert math.isnan(got)
