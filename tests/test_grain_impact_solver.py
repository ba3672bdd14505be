"""Impact solvers: the printed law enforced exactly, closed forms, invariants and hard cases."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symmech.generated import grain_impact as g
from symmech.grain.body import Ellipsoid, euler_from_matrix, rotation
from symmech.grain.impact import (DescentOptions, ImpactError, _golden_section, solve_descent_batch,
                                  solve_impact, solve_robust_batch, solve_scipy)

GRAIN = Ellipsoid(2e-3, 1.5e-3, 1e-3, 1e-5)


def kinetic_energy(body, Q, v, w):
    """Independent: I = Q diag(J) Q^T in the surface frame."""
    inertia = Q @ np.diag(body.inertia) @ Q.T
    return 0.5 * body.mass * v @ v + 0.5 * w @ inertia @ w


def random_impacts(n, seed):
    rng = np.random.default_rng(seed)
    axes = np.exp(rng.uniform(np.log(1e-4), np.log(3e-3), (n, 3)))
    angles = np.column_stack([rng.uniform(-np.pi, np.pi, n), np.arccos(rng.uniform(-1, 1, n)),
                              rng.uniform(-np.pi, np.pi, n)])
    u = rng.normal(size=(n, 3))
    u[:, 2] = -np.abs(u[:, 2]) - 1e-3
    return axes, angles, u, rng.uniform(0, 1, n), rng.uniform(0, 1, n)


def check_law(body, Q, v, w, e, lam, r):
    """The rigid-body update reproduces the velocities that (14)-(18) impose at K."""
    R = g.contact_offset(body.a, body.b, body.c, *euler_from_matrix(Q))
    uK0 = v + np.cross(w, R)
    uK1 = r.v_c_after + np.cross(r.omega_after, R)
    scale = np.linalg.norm(uK0)
    assert uK1[2] == pytest.approx(-e * uK0[2], abs=1e-12 * scale)  # (14)
    assert np.hypot(*uK1[:2]) == pytest.approx((1 - lam) * np.hypot(*uK0[:2]), abs=1e-12 * scale)  # (17)
    if np.hypot(*uK1[:2]) > 1e-9 * scale:  # (15)-(16), (18): T_t collinear with the new slip
        assert abs(r.T[0] * uK1[1] - r.T[1] * uK1[0]) <= 1e-10 * np.linalg.norm(r.T) * scale
    assert r.ke_after - r.ke_before == pytest.approx(0.5 * r.T @ (uK0 + uK1), abs=1e-12 * r.ke_before)
    assert r.ke_after == pytest.approx(kinetic_energy(body, Q, r.v_c_after, r.omega_after), rel=1e-12)


def test_robust_solution_enforces_the_law_at_random_impacts():
    axes, angles, u, e, lam = random_impacts(300, 5)
    rng = np.random.default_rng(6)
    for k in range(300):
        body = Ellipsoid(*axes[k], 1e-5)
        Q = rotation(angles[k])
        w = rng.normal(scale=50.0, size=3)
        R = g.contact_offset(*axes[k], *angles[k])
        v = u[k] - np.cross(w, R)  # so that the contact point approaches with u[k]
        r = solve_impact(body, Q, v, w, e[k], lam[k])
        assert r.converged and r.residual < 1e-12
        check_law(body, Q, v, w, e[k], lam[k], r)


def test_every_scipy_root_is_found_by_the_robust_solver():
    axes, angles, u, e, lam = random_impacts(400, 8)
    H = g.H(*axes.T, *angles.T)
    batch = solve_robust_batch(H, 1.0, e, lam, u)
    found = 0
    for k in range(400):
        T, mu, _, ok = solve_scipy(H[k], 1.0, e[k], lam[k], u[k])
        residual = np.linalg.norm(H[k] @ T - ((1 - lam[k]) * np.hypot(*u[k, :2]) * np.array(
            [np.cos(mu), np.sin(mu), 0]) + np.array([0, 0, -e[k] * u[k, 2]]) - u[k]))
        if ok and residual < 1e-10:
            found += 1
            assert np.min(np.linalg.norm(batch.roots_T[k] - T, axis=1)) < 1e-9 * np.linalg.norm(T)
    assert found > 300


def test_sphere_closed_form():
    """Sphere: T_z = m(1+e)|u_z|, T_t = -(2/7) m lambda V0 along the incoming slip."""
    ball = Ellipsoid(1e-3, 1e-3, 1e-3, 2e-5)
    v, e, lam = np.array([0.6, -0.8, -1.5]), 0.4, 0.25
    r = solve_impact(ball, rotation([0.2, 1.0, -0.4]), v, np.zeros(3), e, lam)
    slip = v[:2] / np.linalg.norm(v[:2])
    np.testing.assert_allclose(r.T[2], ball.mass * (1 + e) * 1.5, rtol=1e-13)
    np.testing.assert_allclose(r.T[:2], -2 / 7 * ball.mass * lam * 1.0 * slip, rtol=1e-12)
    assert r.mu == pytest.approx(np.arctan2(slip[1], slip[0]), abs=1e-12)
    assert r.admissible


@settings(max_examples=200, deadline=None, derandomize=True)
@given(radius=st.floats(1e-4, 1e-2), e=st.floats(0, 1), lam=st.floats(0, 1),
       vx=st.floats(-5, 5), vy=st.floats(-5, 5), vz=st.floats(-5, -1e-3),
       wx=st.floats(-100, 100), wy=st.floats(-100, 100), wz=st.floats(-100, 100))
def test_sphere_never_creates_energy(radius, e, lam, vx, vy, vz, wx, wy, wz):
    ball = Ellipsoid(radius, radius, radius, 1e-5)
    w = np.array([wx, wy, wz])
    v = np.array([vx, vy, vz]) - np.cross(w, [0, 0, -radius])
    r = solve_impact(ball, np.eye(3), v, w, e, lam)
    assert r.admissible
    assert r.ke_after <= r.ke_before * (1 + 1e-9)


def test_printed_law_can_create_energy_for_non_spherical_grains():
    """Seeded search: for some ellipsoids every root of the printed law gains kinetic energy."""
    axes, angles, u, e, lam = random_impacts(20000, 21)
    H = g.H(*axes.T, *angles.T)
    batch = solve_robust_batch(H, 1.0, e, lam, u)
    gaining = np.flatnonzero(batch.energy_created)
    assert 0.005 < len(gaining) / 20000 < 0.1  # about 2 % of random impacts
    k = int(gaining[0])
    body = Ellipsoid(*axes[k], 1e-5)
    R = g.contact_offset(*axes[k], *angles[k])
    r = solve_impact(body, rotation(angles[k]), u[k], np.zeros(3), e[k], lam[k])
    assert not r.admissible
    assert any("creates kinetic energy" in w for w in r.warnings)
    # Independent energy bookkeeping confirms the gain.
    Q = rotation(angles[k])
    gained = kinetic_energy(body, Q, r.v_c_after, r.omega_after) - kinetic_energy(body, Q, u[k], np.zeros(3))
    assert gained > 0
    assert R.shape == (3,)


def test_zero_tangential_speed():
    """No incoming slip: T from one linear solve, mu defined, no NaN; law still enforced."""
    Q = rotation([0.3, 0.7, 1.1])
    R = g.contact_offset(GRAIN.a, GRAIN.b, GRAIN.c, 0.3, 0.7, 1.1)
    w = np.array([0.0, 0.0, 0.0])
    r = solve_impact(GRAIN, Q, np.array([0.0, 0.0, -0.8]), w, 0.5, 0.3)
    assert np.all(np.isfinite(r.T)) and np.isfinite(r.mu)
    check_law(GRAIN, Q, np.array([0.0, 0.0, -0.8]), w, 0.5, 0.3, r)
    assert R[2] < 0


def test_full_stick_lambda_one():
    Q = rotation([1.0, 0.4, -0.3])
    v, w = np.array([0.7, 0.2, -0.4]), np.array([5.0, -3.0, 1.0])
    r = solve_impact(GRAIN, Q, v, w, 0.3, 1.0)
    np.testing.assert_allclose(r.uK_after[:2], 0.0, atol=1e-14)
    check_law(GRAIN, Q, v, w, 0.3, 1.0, r)


def test_mu_near_ninety_degrees():
    """Slip along Y: mu = +-90 deg where tan(mu) in (19) is infinite; the robust path is exact."""
    ball = Ellipsoid(1e-3, 1e-3, 1e-3, 1e-5)
    v = np.array([1e-12, 0.9, -0.5])
    r = solve_impact(ball, np.eye(3), v, np.zeros(3), 0.5, 0.3)
    assert abs(abs(r.mu) - np.pi / 2) < 1e-9
    assert r.residual < 1e-13
    check_law(ball, np.eye(3), v, np.zeros(3), 0.5, 0.3, r)
    # The printed descent works in tan(mu) and cannot get there.
    paper = solve_impact(ball, np.eye(3), v, np.zeros(3), 0.5, 0.3, solver="paper")
    assert not paper.converged


def test_grazing_impact_is_finite_and_flagged():
    """Normal approach speed -> 0 with slip: T stays finite, the law holds, and it is flagged.

    A sphere needs a friction impulse with almost no normal impulse (warned); this
    ellipsoid needs an impulse that pulls it into the plane (inadmissible).
    """
    ball = Ellipsoid(1e-3, 1e-3, 1e-3, 1e-5)
    Q = rotation([0.3, 0.7, 1.1])
    for uz in (-1e-3, -1e-6, -1e-9):
        v = np.array([0.5, 0.2, uz])
        for body in (ball, GRAIN):
            r = solve_impact(body, Q, v, np.zeros(3), 0.5, 0.3)
            assert np.all(np.isfinite(r.T)) and r.residual < 1e-10
            check_law(body, Q, v, np.zeros(3), 0.5, 0.3, r)
            if body is ball:
                assert any("grazing" in w for w in r.warnings)
            else:
                assert not r.admissible and any("pulls the grain" in w for w in r.warnings)
    with pytest.raises(ImpactError, match="not approaching"):
        solve_impact(GRAIN, Q, np.array([0.5, 0.2, 1e-3]), np.zeros(3), 0.5, 0.3)


def test_gimbal_lock_reports_angular_velocity_not_euler_rates():
    from symmech.grain.impact import euler_rates

    Q = rotation([0.0, 0.0, 0.8])  # theta = 0: the grain lies flat
    v, w = np.array([0.4, 0.1, -0.6]), np.array([0.0, 0.0, 4.0])
    r = solve_impact(GRAIN, Q, v, w, 0.5, 0.3)
    assert r.converged
    rates, warning = euler_rates(Q, r.omega_after)
    assert rates is None and "gimbal lock" in warning
    near = rotation([0.2, 1e-4, 0.8])
    rates, warning = euler_rates(near, r.omega_after)
    assert "near gimbal lock" in warning
    # The rates still reproduce the angular velocity through W.
    theta, phi = euler_from_matrix(near)[1:]
    np.testing.assert_allclose(g.euler_rate_matrix(theta, phi) @ rates, near.T @ r.omega_after, rtol=1e-9)


@pytest.mark.parametrize("axes", [(1e-3, 1e-3, 1e-3), (3e-3, 3e-3, 3e-5), (3e-3, 3e-5, 3e-5),
                                  (1e-2, 1e-4, 1e-3)], ids=["sphere", "flat", "needle", "plank"])
def test_extreme_aspect_ratios(axes):
    body = Ellipsoid(*axes, 1e-5)
    rng = np.random.default_rng(4)
    for _ in range(20):
        angles = [rng.uniform(-3, 3), np.arccos(rng.uniform(-1, 1)), rng.uniform(-3, 3)]
        Q = rotation(angles)
        v, w = np.array([0.4, -0.3, -0.7]), rng.normal(scale=10, size=3)
        R = g.contact_offset(*axes, *angles)
        if (v + np.cross(w, R))[2] >= 0:
            continue
        r = solve_impact(body, Q, v, w, 0.6, 0.2)
        assert r.residual < 1e-9
        check_law(body, Q, v, w, 0.6, 0.2, r)


def test_paper_descent_as_printed_stops_with_a_wrong_answer():
    """Phi (24) is the sum of the residuals: it goes negative at once and the stop rule fires."""
    r = solve_impact(GRAIN, rotation([0.3, 0.7, 1.1]), [0.3, 0.1, -0.5], [1, 2, 3], 0.5, 0.3, solver="paper")
    assert r.iterations == 1
    assert not r.converged and r.residual > 1.0
    assert any("did not solve (19)" in w for w in r.warnings)


def test_corrected_descent_converges_to_the_robust_root():
    Q = rotation([0.3, 0.7, 1.1])
    robust = solve_impact(GRAIN, Q, [0.3, 0.1, -0.5], [1, 2, 3], 0.5, 0.3)
    H = g.H(GRAIN.a, GRAIN.b, GRAIN.c, *euler_from_matrix(Q))
    errors = []
    for steps in (30, 300):
        T, mu, done, _ = solve_descent_batch(H[None], GRAIN.mass, 0.5, 0.3, robust.uK_before[None],
                                             "paper-corrected", DescentOptions(max_steps=steps))
        errors.append(np.linalg.norm(T[0] - robust.T) / np.linalg.norm(robust.T))
    assert errors[1] < 1e-3 < errors[0]


def test_golden_section_contracts_by_the_golden_ratio():
    """The bracket keeps the minimum and shrinks by 0.618 per iteration (fitted rate)."""
    targets = np.random.default_rng(2).uniform(0, 1, 500)
    iterations = np.arange(4, 40, 5)
    widths = []
    for r in iterations:
        lo, hi = _golden_section(lambda x: (x - targets) ** 2, np.zeros(500), np.ones(500), int(r), 0.0)
        assert np.all((lo <= targets) & (targets <= hi))
        widths.append(np.max(hi - lo))
    rate = np.exp(np.polyfit(iterations, np.log(widths), 1)[0])
    assert rate == pytest.approx((np.sqrt(5) - 1) / 2, rel=1e-3)
