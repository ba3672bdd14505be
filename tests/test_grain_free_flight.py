"""The exact free flight (free_flight, its compiled twin free_flight_nb) against DOP853, closed forms and the
gap's rate and curvature bound; the Python engine's impacts with it against the integrated reference flight."""
from dataclasses import replace

import numpy as np
import pytest

from symmech.core import pipeline
from symmech.grain import contact, flight, free_flight, motion

ASYMMETRIC = np.array([1.0, 2.0, 3.0])  # kg m^2
SHAPES = {  # inertia, body angular velocity [rad/s]
    "sphere": ([2.0, 2.0, 2.0], [1.0, 0.5, 0.3]),
    "prolate": ([3.0, 3.0, 1.0], [0.4, -0.5, 1.3]),
    "oblate": ([1.0, 1.0, 3.0], [1.0, 0.5, 0.3]),
    "circling largest": ([1.0, 2.0, 3.0], [0.1, 0.5, 1.3]),
    "circling smallest": ([1.0, 2.0, 3.0], [-1.0, 0.5, -0.3]),
    "permuted axes": ([3.0, 1.0, 2.0], [1.0, 0.5, 0.3]),
    "near middle axis": ([1.0, 2.0, 3.0], [0.05, 1.0, 0.05]),
    "on middle axis": ([1.0, 2.0, 3.0], [0.0, 2.0, 0.0]),
}


def start(seed=3):
    q = np.random.default_rng(seed).normal(size=4)
    return q / np.linalg.norm(q)


def dop853_deviation(inertia, w0, duration, rtol):
    """Largest deviation of the exact attitude (matrix entries) and body rate from DOP853's over ``duration``."""
    q0 = start()
    exact = free_flight.ExactRotation(inertia, q0, w0, 0.25)
    ref = flight.RotationFlight(inertia, q0, w0, 0.25, rtol, duration)
    t = np.linspace(0.25, 0.25 + duration, 41)
    (qe, we), (qr, wr) = exact.state(t), ref.state(t)
    return max(np.abs(flight.rotation_matrix(qe) - flight.rotation_matrix(qr)).max(), np.abs(we - wr).max())


@pytest.mark.parametrize("shape", SHAPES)
def test_each_shape_follows_dop853_over_a_period(shape):
    """Attitude and angular velocity within 1e-12 of DOP853 (rtol 1e-13) over 6 s (>= half a polhode period)."""
    inertia, w0 = (np.array(x) for x in SHAPES[shape])
    assert dop853_deviation(inertia, w0, 6.0, 1e-13) < 1e-12


@pytest.mark.slow
def test_over_100_periods_the_gap_to_dop853_is_dop853s_error():
    """Over 100 polhode periods (1100 s) the deviation from DOP853 shrinks as DOP853's tolerance does (rtol 1e-13:
    1.6e-10, scipy's floor 2.2e-14: 3.2e-11): it is the integrator's global error, not the closed form's."""
    w0 = np.array([1.0, 0.5, 0.3])
    exact = free_flight.ExactRotation(ASYMMETRIC, start(), w0, 0.25)
    duration = 100 * 4 * exact.K / exact.lam
    coarse = dop853_deviation(ASYMMETRIC, w0, duration, 1e-13)
    fine = dop853_deviation(ASYMMETRIC, w0, duration, 2.3e-14)
    assert fine < coarse / 2.5 and coarse < 1e-9


@pytest.mark.slow
def test_near_the_middle_axis_over_100_periods():
    """Spinning 1e-3 off the unstable middle axis, 100 polhode periods (5500 s): within 1e-8 of DOP853 at rtol
    1e-13 (the integrator's own error there is ~1e-9: it does not shrink monotonically with its tolerance)."""
    w0 = np.array([1e-3, 1.0, 1e-3])
    exact = free_flight.ExactRotation(ASYMMETRIC, start(), w0, 0.25)
    assert exact.k2 > 1 - 1e-5
    assert dop853_deviation(ASYMMETRIC, w0, 100 * 4 * exact.K / exact.lam, 1e-13) < 1e-8


@pytest.mark.parametrize("w0", [[1.0, 0.5, 0.3], [1e-3, 1.0, 1e-3]], ids=["asymmetric", "near middle axis"])
def test_restarting_each_period_agrees_with_one_flight_over_100_periods(w0):
    """The flow property the event loop relies on (each flight restarts from the last state): 100 restarts one
    polhode period apart end within 1e-12 (attitude matrix, body rate) of one evaluation at 100 periods."""
    one = free_flight.ExactRotation(ASYMMETRIC, start(), np.array(w0), 0.0)
    period = 4 * one.K / one.lam
    q, w = start(), np.array(w0)
    for k in range(100):
        q, w = free_flight.ExactRotation(ASYMMETRIC, q, w, k * period).state((k + 1) * period)
    q_one, w_one = one.state(100 * period)
    assert np.abs(flight.rotation_matrix(q) - flight.rotation_matrix(q_one)).max() < 1e-12
    assert np.abs(w - w_one).max() < 1e-12 * np.linalg.norm(w0)


def test_symmetric_grain_precesses_regularly():
    """Closed form of the symmetric top: w_perp turns at Omega = (I3 - I1) w3 / I1 in the body, w3 constant,
    and the symmetry axis precesses about L at |L| / I1 on a cone of constant angle."""
    inertia, w0 = np.array([1.0, 1.0, 3.0]), np.array([1.0, 0.5, 0.3])
    rot = free_flight.ExactRotation(inertia, start(), w0, 0.0)
    t = np.linspace(0.0, 7.0, 29)
    q, w = rot.state(t)
    Omega = (inertia[2] - inertia[0]) * w0[2] / inertia[0]
    turned = (w0[0] + 1j * w0[1]) * np.exp(1j * Omega * t)
    np.testing.assert_allclose(w[:, 0] + 1j * w[:, 1], turned, rtol=0, atol=1e-14)
    np.testing.assert_allclose(w[:, 2], w0[2], rtol=0, atol=1e-15)
    Q = flight.rotation_matrix(q)
    L = Q[0] @ (inertia * w0)
    axis = Q[:, :, 2]  # the symmetry axis in space
    along = axis @ L / np.linalg.norm(L)
    np.testing.assert_allclose(along, along[0], rtol=0, atol=1e-14)
    perp = axis - along[:, None] * L / np.linalg.norm(L)
    angle = np.unwrap(np.arctan2(np.cross(perp[0], perp) @ L / np.linalg.norm(L), perp @ perp[0]))
    np.testing.assert_allclose(angle, np.linalg.norm(L) / inertia[0] * t, rtol=0, atol=1e-12)


@pytest.mark.parametrize("w0", [[1.0, 0.5, 0.3], [1e-3, 1.0, 1e-3]], ids=["asymmetric", "near middle axis"])
def test_energy_and_angular_momentum_exact_to_round_off_over_100_periods(w0):
    rot = free_flight.ExactRotation(ASYMMETRIC, start(), np.array(w0), 0.0)
    t = np.linspace(0.0, 100 * 4 * rot.K / rot.lam, 401)
    q, w = rot.state(t)
    L = np.einsum("nij,nj->ni", flight.rotation_matrix(q), ASYMMETRIC * w)
    energy = 0.5 * np.sum(ASYMMETRIC * w * w, axis=-1)
    assert np.abs(L - L[0]).max() < 5e-15 * np.linalg.norm(L[0])
    assert np.abs(energy / energy[0] - 1).max() < 5e-15


def random_flight(rng):
    """A tumbling ellipsoid over a plate vibrating in a random direction: (translate(t), rotation, model data)."""
    axes = rng.uniform(1e-3, 4e-3, 3)
    inertia = 1e-3 * (np.sum(axes**2) - axes**2) / 5
    d = rng.normal(size=3)
    vib = flight.Vibration(rng.uniform(0, 1e-3), rng.uniform(50, 300), rng.uniform(0, 6), tuple(d / np.linalg.norm(d)))
    g, t0 = rng.normal(size=3) * 5, rng.uniform(0, 1)
    r0, v0 = np.array([0, 0, 5e-3]), rng.normal(size=3) * 0.3
    rot = free_flight.ExactRotation(inertia, start(int(rng.integers(1000))), rng.normal(size=3) * 200, t0)
    return (lambda t: flight.translate(r0, v0, g, vib, t0, t)), rot, (axes, inertia, vib, g)


def gap_and_rate(translate, rot, axes, t):
    (r, v), (q, w) = translate(t), rot.state(t)
    Q = flight.rotation_matrix(q)
    return r[..., 2] - contact.support_distance(axes, Q), free_flight.gap_rate(v[..., 2], axes, Q[..., 2, :], w)


def test_the_gap_rate_and_the_curvature_bound_on_random_flights():
    """h' is the derivative of h (central differences, 1e-6 relative); |h''| (central differences of the exact
    h') never exceeds gap_curvature_bound, which is no wild overestimate either (worst ratio above 0.05)."""
    rng = np.random.default_rng(7)
    worst, dt = 0.0, 1e-7
    for _ in range(60):
        translate, rot, (axes, inertia, vib, g) = random_flight(rng)
        ts = rot.t0 + rng.uniform(0, 3, 40)
        (h_minus, d_minus), (h, d), (h_plus, d_plus) = (gap_and_rate(translate, rot, axes, ts + k * dt)
                                                          for k in (-1, 0, 1))
        np.testing.assert_allclose((h_plus - h_minus) / (2 * dt), d, rtol=1e-6, atol=1e-9)
        curvature = np.abs(d_plus - d_minus) / (2 * dt)
        bound = free_flight.gap_curvature_bound(g[2], vib, axes, inertia, rot.max_rate)
        assert curvature.max() <= bound
        worst = max(worst, curvature.max() / bound)
    assert worst > 0.05


def grazing_flight(depth):
    """Ellipsoid (2, 1, 1) mm, long axis horizontal, spinning at 50 rad/s about its horizontal body y axis, no
    gravity, no vibration, centre held at 2 mm - depth: the long axis reaches below the plane by ``depth`` for a
    moment. The closed form of the first contact: sin^2(omega t) = (z^2 - c^2) / (a^2 - c^2)."""
    axes, z0, omega, inertia = np.array([2e-3, 1e-3, 1e-3]), 2e-3 - depth, 50.0, np.array([1.0, 2.5, 2.5])
    rot = free_flight.ExactRotation(inertia, np.array([1.0, 0, 0, 0]), np.array([0, omega, 0]), 0.0)
    vib = flight.Vibration(0.0, 1.0, 0.0, (0.0, 0.0, 1.0))

    def gap(t):
        h, d = gap_and_rate(lambda t: (np.array([0, 0, z0]), np.zeros(3)), rot, axes, t)
        return float(h), float(d)

    exact = np.arcsin(np.sqrt(min(1.0, (z0**2 - axes[1] ** 2) / (axes[0] ** 2 - axes[1] ** 2)))) / omega
    return gap, free_flight.gap_curvature_bound(0.0, vib, axes, inertia, rot.max_rate), exact


def test_a_grazing_contact_the_scan_steps_over_is_found():
    gap, curvature, exact = grazing_flight(depth=1e-7)
    step = 0.004  # samples at 0, 4, 8 ... ms; the contact lasts ~0.5 ms around pi / 100 s
    samples = np.array([gap(t)[0] for t in np.arange(0.0, 0.06, step)])
    assert samples.min() > 0  # a scan for sign changes misses it
    found = contact.first_contact(gap, curvature, 0.0, 0.06, step, 1e-13)
    assert found == pytest.approx(exact, abs=1e-12)
    gap_miss, curvature_miss, _ = grazing_flight(depth=-1e-7)  # 0.1 um short of touching: no contact
    assert contact.first_contact(gap_miss, curvature_miss, 0.0, 0.06, step, 1e-13) is None
    assert contact.first_contact(gap, curvature, 0.0314, 0.06, step, 1e-13) == 0.0314  # starts inside: now


def default_scene(tmp_path, duration):
    text = open("scenes/grain_default.toml").read().replace("duration = 2.0", f"duration = {duration}")
    path = tmp_path / "scene.toml"
    path.write_text(text)
    return pipeline.load(path).setup


def impact_times(sc, flight_kind, tolerance):
    res = motion.simulate(sc.model, replace(sc.numerics, flight=flight_kind, tolerance=tolerance), sc.start,
                          sc.duration)
    return np.array([i["t"] for i in res.impacts])


@pytest.mark.parametrize("duration", [0.05, pytest.param(0.4, marks=pytest.mark.slow)])
def test_python_engine_impacts_on_the_default_scene_unchanged_by_the_exact_flight(tmp_path, duration):
    """The default scene (tolerance 1e-9) with the exact flight: the impact sequence of DOP853 at rtol 1e-12
    within 2e-9 periods (measured 4.6e-10 over the 93 impacts of 0.4 s, where DOP853 at the scene's 1e-9 is
    6.1e-8 periods off)."""
    sc = default_scene(tmp_path, duration)
    exact, ref = impact_times(sc, "exact", 1e-9), impact_times(sc, "dop853", 1e-12)
    assert len(exact) == len(ref) >= (3 if duration < 0.1 else 90)
    np.testing.assert_allclose(exact, ref, rtol=0, atol=2e-9 * sc.model.period)
