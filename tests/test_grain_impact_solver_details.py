"""Impact solvers in detail: the descent's stop rule, start and batch scaling, the golden section's
printed rules, the scipy baseline's tolerance, Euler-rate warnings and argument checks.

References are independent: the corrected functional summed by hand from H (generated), the
closed-form sphere impact, brackets that must contain a known minimum.
"""
import re
from fractions import Fraction

import numpy as np
import pytest

from symmech.generated import grain_impact as g
from symmech.generated import grain_impact_printed as printed
from symmech.grain.body import Ellipsoid, rotation
from symmech.grain.impact import (DescentOptions, ImpactError, _golden_section, _trig_roots, euler_rates,
                                  reduction_tensor,
                                  residual_19, solve_descent_batch, solve_impact, solve_robust_batch, solve_scipy)

GRAIN = Ellipsoid(2e-3, 1.5e-3, 1e-3, 1e-5)
BALL = Ellipsoid(1e-3, 1e-3, 1e-3, 2e-5)
SPHERE_H = np.diag([3.5, 3.5, 1.0])  # a solid sphere's H: 1 + R^2/rho^2 = 7/2 tangentially


def corrected_phi(H, m, e, lam, uK0, T, mu):
    """Sum of squared residuals of (19), H (T_x, T_x tan mu, T_z) - m du_K(mu), over (m |u_K(0)|)^2."""
    speed = (1 - lam) * np.hypot(uK0[0], uK0[1])
    du = np.array([speed * np.cos(mu), speed * np.sin(mu), -e * uK0[2]]) - uK0
    r = H @ np.array([T[0], T[0] * np.tan(mu), T[2]]) - m * du
    return r @ r / (m * np.linalg.norm(uK0)) ** 2


def grain_impact(angles=(0.3, 0.7, 1.1), v=(0.3, 0.1, -0.5), w=(1.0, 2.0, 3.0)):
    """H and u_K(0) of GRAIN at the given orientation and velocities."""
    H = g.H(GRAIN.a, GRAIN.b, GRAIN.c, *angles)
    R = g.contact_offset(GRAIN.a, GRAIN.b, GRAIN.c, *angles)
    return H, np.asarray(v) + np.cross(w, R)


# --------------------------------------------------------------------------- descent


def test_descent_options_refuse_each_knob_alone():
    DescentOptions(max_steps=1, line_iterations=1)  # the smallest admissible counts
    for bad in ({"max_steps": 0}, {"line_iterations": 0}):
        with pytest.raises(ValueError, match=r"^descent max_steps and line_iterations must be >= 1$"):
            DescentOptions(**bad)
    for bad in ({"tol": 0.0}, {"step_max": 0.0}, {"line_tol": 0.0}):
        with pytest.raises(ValueError, match=r"^descent tol, step_max and line_tol must be > 0$"):
            DescentOptions(**bad)


def test_descent_defaults_to_the_printed_method():
    H, uK0 = grain_impact()
    default = solve_descent_batch(H[None], GRAIN.mass, 0.5, 0.3, uK0[None])
    printed = solve_descent_batch(H[None], GRAIN.mass, 0.5, 0.3, uK0[None], "paper")
    for a, b in zip(default, printed):
        np.testing.assert_array_equal(a, b)
    assert default[2][0] == 1 and default[3][0]  # Phi (24) goes negative at once: one step, stopped
    with pytest.raises(ValueError, match="unknown descent variant 'steepest'"):
        solve_descent_batch(H[None], GRAIN.mass, 0.5, 0.3, uK0[None], "steepest")


def test_printed_descent_stop_rule_is_relative_to_the_momentum():
    """Phi (24) at the start is 0.67 m|u_K(0)| here: tol = 1 stops before any step, tol = 0.5 after one
    (Phi then goes negative); the same for a mass 10^8 times larger."""
    H, uK0 = grain_impact()
    e, lam = 0.5, 0.3
    for m in (GRAIN.mass, 1e3):
        start = (0.0, -m * (1 + e) * uK0[2] / H[2, 2], np.arctan2(uK0[1], uK0[0]))
        phi0 = printed.functional(*start, H[0, 0], H[0, 1], H[0, 2], H[1, 1], H[1, 2], H[2, 2], m, lam, e, *uK0)
        assert phi0 / (m * np.linalg.norm(uK0)) == pytest.approx(0.672, abs=1e-3)
        for tol, steps in ((1.0, 0), (0.5, 1)):
            out = solve_descent_batch(H[None], m, e, lam, uK0[None], "paper", DescentOptions(tol=tol))
            assert out[2][0] == steps and out[3][0]
        # stopped at once, the answer is the documented start
        T, mu, _, _ = solve_descent_batch(H[None], m, e, lam, uK0[None], "paper", DescentOptions(tol=1.0))
        np.testing.assert_allclose(T[0], [0.0, 0.0, start[1]], rtol=1e-15, atol=0)
        assert mu[0] == start[2]


def test_descent_starts_on_a_head_on_sphere_impact():
    """Head-on sphere: the start T = (0, 0, m(1+e)|u_z|/h_zz) solves (19) exactly, so no step is taken."""
    m, e, uz = BALL.mass, 0.4, -1.5
    for variant in ("paper", "paper-corrected"):
        T, mu, steps, stopped = solve_descent_batch(SPHERE_H[None], m, e, 0.3, np.array([[0.0, 0.0, uz]]),
                                                    variant)
        assert steps[0] == 0 and stopped[0]
        np.testing.assert_allclose(T[0], [0.0, 0.0, m * (1 + e) * 1.5], rtol=1e-15, atol=0)


def test_corrected_descent_stops_at_the_first_step_below_its_tolerance():
    """Stop rule Phi <= delta, delta = tol for the squared, dimensionless functional (Phi summed by hand)."""
    H, uK0 = grain_impact()
    m, e, lam, tol = GRAIN.mass, 0.5, 0.3, 0.1
    T, mu, steps, stopped = solve_descent_batch(H[None], m, e, lam, uK0[None], "paper-corrected",
                                                DescentOptions(tol=tol, line_iterations=20))
    assert stopped[0] and 1 < steps[0] < 1000
    assert corrected_phi(H, m, e, lam, uK0, T[0], mu[0]) <= tol
    before = solve_descent_batch(H[None], m, e, lam, uK0[None], "paper-corrected",
                                 DescentOptions(tol=tol, max_steps=int(steps[0]) - 1, line_iterations=20))
    assert not before[3][0] and before[2][0] == steps[0] - 1
    assert corrected_phi(H, m, e, lam, uK0, before[0][0], before[1][0]) > tol


def test_corrected_descent_scales_each_impact_of_a_batch_by_its_own_momentum():
    """Two impacts 100x apart in speed: the batch gives what each gives alone."""
    H, uK0 = grain_impact()
    Hs, us = np.stack([H, H]), np.stack([uK0, 100 * uK0])
    options = DescentOptions(max_steps=10, line_iterations=30)
    Tb, mub, stepsb, _ = solve_descent_batch(Hs, GRAIN.mass, 0.5, 0.3, us, "paper-corrected", options)
    for k in range(2):
        T, mu, steps, _ = solve_descent_batch(Hs[k:k + 1], GRAIN.mass, 0.5, 0.3, us[k:k + 1],
                                              "paper-corrected", options)
        np.testing.assert_allclose(Tb[k], T[0], rtol=1e-12)
        assert mub[k] == pytest.approx(mu[0], abs=1e-12) and stepsb[k] == steps[0]
    np.testing.assert_allclose(Tb[1], 100 * Tb[0], rtol=1e-6)  # the law is linear in u_K(0)


def test_descent_counts_only_the_steps_of_active_impacts():
    """A batch of a head-on sphere (solved at the start) and an oblique grain: 0 steps and all of them."""
    H, uK0 = grain_impact()
    T, mu, steps, stopped = solve_descent_batch(np.stack([SPHERE_H, H]), GRAIN.mass, 0.4, 0.25,
                                                np.stack([[0.0, 0.0, -1.5], uK0]), "paper-corrected",
                                                DescentOptions(max_steps=5, tol=1e-20, line_iterations=30))
    assert list(steps) == [0, 5] and list(stopped) == [True, False]
    np.testing.assert_allclose(T[0], [0.0, 0.0, GRAIN.mass * 1.4 * 1.5], rtol=1e-15, atol=0)


# --------------------------------------------------------------------------- golden section


def test_golden_section_brackets_a_minimum_away_from_zero():
    """Brackets [2, 3] and [-7, -1]: the initial golden points measure from lo, not from 0."""
    lo, hi = np.array([2.0, -7.0]), np.array([3.0, -1.0])
    target = np.array([2.3, -6.5])
    for iterations in (1, 2, 30):
        a, b = _golden_section(lambda x: (x - target) ** 2, lo, hi, iterations, 0.0)
        assert np.all((a <= target) & (target <= b))
        np.testing.assert_allclose(b - a, (hi - lo) * ((np.sqrt(5) - 1) / 2) ** iterations, rtol=1e-9)


def test_golden_section_stops_each_bracket_at_its_own_width():
    """eps = 1e-4: brackets of width 1 and 1e-3 stop after their own counts, each keeping its minimum."""
    lo, hi = np.zeros(2), np.array([1.0, 1e-3])
    target = np.array([0.37, 6e-4])
    a, b = _golden_section(lambda x: (x - target) ** 2, lo, hi, 100, 1e-4)
    ratio = (np.sqrt(5) - 1) / 2
    expected = np.ceil(np.log(1e-4 / (hi - lo)) / np.log(ratio))  # first count with width <= eps
    np.testing.assert_allclose(b - a, (hi - lo) * ratio ** expected, rtol=1e-9)
    assert np.all((a <= target) & (target <= b))


def test_golden_section_keeps_the_left_bracket_on_ties():
    """(34): xi(l1) <= xi(l2) keeps [lo, l2]; on a flat function the bracket closes on lo."""
    a, b = _golden_section(lambda x: np.zeros_like(x), np.array([1.0]), np.array([2.0]), 50, 0.0)
    assert a[0] == 1.0 and b[0] - 1.0 < 1e-9


# --------------------------------------------------------------------------- scipy baseline


def test_scipy_baseline_passes_its_tolerance_to_hybr():
    """A loose xtol stops hybr earlier, with a larger residual, than a tight one."""
    H, uK0 = grain_impact()
    loose = solve_scipy(H, GRAIN.mass, 0.5, 0.3, uK0, xtol=1e-2)
    tight = solve_scipy(H, GRAIN.mass, 0.5, 0.3, uK0, xtol=1e-13)
    assert loose[2] < tight[2]
    assert np.linalg.norm(loose[0] - tight[0]) > 1e-9 * np.linalg.norm(tight[0])


def test_scipy_baseline_solves_the_sphere_closed_form():
    v, e, lam = np.array([0.6, -0.8, -1.5]), 0.4, 0.25
    T, mu, _, ok = solve_scipy(SPHERE_H, BALL.mass, e, lam, v)
    assert ok
    np.testing.assert_allclose(T, [-2 / 7 * BALL.mass * lam * 0.6, 2 / 7 * BALL.mass * lam * 0.8,
                                   BALL.mass * (1 + e) * 1.5], rtol=1e-10)
    assert mu == pytest.approx(np.arctan2(-0.8, 0.6), abs=1e-10)


# --------------------------------------------------------------------------- one impact


def test_euler_rate_warnings_name_sin_theta_and_the_amplification():
    omega = np.array([0.3, -1.2, 4.0])
    rates, warning = euler_rates(rotation([0.2, 0.9, 0.8]), omega)
    assert warning is None and rates.shape == (3,)
    theta = 3e-3
    rates, warning = euler_rates(rotation([0.2, theta, 0.8]), omega)
    assert warning == (f"near gimbal lock: sin(theta) = {np.sin(theta):.2e}; Euler rates are amplified by "
                       f"1/sin(theta) = {1 / np.sin(theta):.3g}, use the angular velocity instead")
    rates, warning = euler_rates(rotation([0.0, 0.0, 0.8]), omega)
    assert rates is None
    assert warning == ("gimbal lock: sin(theta) = 0.00e+00; the Euler rates psi' and phi' are undefined "
                       "(only psi' + phi' is), the angular velocity is reported instead")


def test_solve_impact_refuses_each_argument_alone():
    v, w, Q = np.array([0.3, 0.1, -0.5]), np.zeros(3), rotation([0.3, 0.7, 1.1])
    with pytest.raises(ValueError, match=re.escape(
            "unknown solver 'newton'; choose one of robust, paper, paper-corrected, scipy")):
        solve_impact(GRAIN, Q, v, w, 0.5, 0.3, solver="newton")
    for e, lam in ((1.5, 0.3), (-0.1, 0.3), (0.5, 1.2), (0.5, -0.2)):
        with pytest.raises(ValueError, match=re.escape(f"e = {e} and lambda = {lam} must lie in [0, 1]")):
            solve_impact(GRAIN, Q, v, w, e, lam)


def test_robust_solver_polishes_roots_to_rounding():
    """The default Newton tolerance (1e-14 rad) leaves the residual of (19) at rounding level."""
    rng = np.random.default_rng(11)
    worst = 0.0
    for _ in range(50):
        angles = [rng.uniform(-3, 3), np.arccos(rng.uniform(-1, 1)), rng.uniform(-3, 3)]
        v = np.array([*rng.normal(size=2), -abs(rng.normal()) - 0.1])
        r = solve_impact(GRAIN, rotation(angles), v, np.zeros(3), 0.5, 0.3)
        worst = max(worst, r.residual)
    assert worst < 1e-14


def test_solve_impact_admits_the_ends_of_the_ranges():
    """e = 1 and lambda = 1 are admissible: the sphere's closed form with them."""
    v = np.array([0.6, -0.8, -1.5])
    r = solve_impact(BALL, np.eye(3), v, np.zeros(3), 1.0, 1.0)
    np.testing.assert_allclose(r.T, [-2 / 7 * BALL.mass * 0.6, 2 / 7 * BALL.mass * 0.8, 2 * BALL.mass * 1.5],
                               rtol=1e-12)
    assert r.ke_after < r.ke_before  # the slip is lost, the normal speed is kept


def test_contact_point_at_rest_along_the_normal_is_refused():
    """u_Kz(0) = 0 exactly: no impact (the message names the normal velocity and the bound)."""
    for uz, shown in ((0.0, "0"), (1e-3, "0.001")):
        with pytest.raises(ImpactError, match=re.escape(
                f"the contact point is not approaching the plane: u_Kz(0) = {shown} m/s must be < 0")):
            solve_impact(BALL, np.eye(3), np.array([0.5, 0.2, uz]), np.zeros(3), 0.5, 0.3)


def test_scipy_baseline_reports_a_converged_sphere_impact_admissible():
    v = np.array([0.6, -0.8, -1.5])
    r = solve_impact(BALL, np.eye(3), v, np.zeros(3), 0.4, 0.25, solver="scipy")
    assert r.converged and r.admissible and r.warnings == []
    np.testing.assert_allclose(r.T, [-2 / 7 * BALL.mass * 0.25 * 0.6, 2 / 7 * BALL.mass * 0.25 * 0.8,
                                     BALL.mass * 1.4 * 1.5], rtol=1e-10)



def impact_roots_by_scan(H, m, e, lam, uK0, samples=20001):
    """Roots of det[H d(mu), H e_z, du_K(mu)] = 0 by sign changes on a grid, refined by bisection."""
    def F(mu):
        speed = (1 - lam) * np.hypot(uK0[0], uK0[1])
        du = np.stack([speed * np.cos(mu) - uK0[0], speed * np.sin(mu) - uK0[1],
                       np.full_like(mu, -(1 + e) * uK0[2])], axis=-1)
        d = np.stack([np.cos(mu), np.sin(mu), np.zeros_like(mu)], axis=-1)
        return np.linalg.det(np.stack([d @ H.T, np.broadcast_to(H[:, 2], du.shape), du], axis=-1))

    grid = np.linspace(-np.pi, np.pi, samples)
    values = F(grid)
    roots = []
    for k in np.flatnonzero(np.sign(values[:-1]) != np.sign(values[1:])):
        lo, hi = grid[k], grid[k + 1]
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if np.sign(F(np.array([mid]))[0]) == np.sign(F(np.array([lo]))[0]) else (lo, mid)
        roots.append(0.5 * (lo + hi))
    return np.array(roots)


def test_every_root_and_its_verdict_is_reported():
    """A needle whose every root gains kinetic energy (one also pulls): the roots, impulses, energy
    changes and verdicts of the report against a scan of the determinant and hand bookkeeping."""
    axes = (0.00042210527493724, 0.00014656591496351, 0.00260300938619162)
    angles = (2.885620771885198, 2.481953019198422, 0.11515564447430515)
    uK0, e, lam = np.array([1.6508745196647576, -1.443837672820786, -0.6270921245645246]), 0.9165, 0.0104
    body = Ellipsoid(*axes, 1e-5)
    H = g.H(*axes, *angles)
    r = solve_impact(body, rotation(angles), uK0, np.zeros(3), e, lam)
    scanned = impact_roots_by_scan(H, body.mass, e, lam, uK0)
    assert len(r.roots) == len(scanned) == 4
    np.testing.assert_allclose(sorted(root["mu"] for root in r.roots), np.sort(scanned), atol=1e-9)
    speed = (1 - lam) * np.hypot(*uK0[:2])
    for root in r.roots:
        assert set(root) == {"mu", "T", "delta_ke", "creates_energy", "pulling"}
        mu, T = root["mu"], np.array(root["T"])
        uK1 = np.array([speed * np.cos(mu), speed * np.sin(mu), -e * uK0[2]])
        np.testing.assert_allclose(H @ T, body.mass * (uK1 - uK0), rtol=1e-10, atol=1e-12 * body.mass)
        assert root["delta_ke"] == pytest.approx(0.5 * T @ (uK0 + uK1), rel=1e-9)
        assert root["creates_energy"] == (root["delta_ke"] > 0) and root["pulling"] == (T[2] < 0)
    assert [root["creates_energy"] for root in r.roots] == [True] * 4
    assert [root["pulling"] for root in r.roots].count(True) == 1
    least = min(r.roots, key=lambda root: (root["pulling"], np.hypot(*root["T"][:2])))
    assert not r.admissible and r.warnings[0] == (
        "no admissible root of the printed impact law: the least-impulse root creates kinetic energy "
        f"(+{least['delta_ke']:.3g} J)")
    inertia = rotation(angles) @ np.diag(body.inertia) @ rotation(angles).T
    ke0 = 0.5 * body.mass * uK0 @ uK0
    ke1 = 0.5 * body.mass * r.v_c_after @ r.v_c_after + 0.5 * r.omega_after @ inertia @ r.omega_after
    assert ke1 > 1.02 * ke0
    assert r.warnings[1:] == [f"the impact creates kinetic energy: {ke0:.6g} J -> {ke1:.6g} J"]


def test_pulling_root_is_reported_with_its_normal_impulse():
    """A grazing ellipsoid: the least-impulse root pulls it into the plane (T_z < 0), the warning says so."""
    r = solve_impact(GRAIN, rotation([0.3, 0.7, 1.1]), np.array([0.5, 0.2, -1e-6]), np.zeros(3), 0.5, 0.3)
    chosen = [root for root in r.roots if np.allclose(root["T"], r.T, rtol=0, atol=0)]
    assert len(chosen) == 1 and chosen[0]["pulling"] and r.T[2] < 0
    assert [root["pulling"] for root in r.roots] == [bool(root["T"][2] < 0) for root in r.roots]
    assert r.warnings[0] == ("no admissible root of the printed impact law: the least-impulse root "
                             f"pulls the grain into the plane (T_z = {r.T[2]:.3g} N s)")


def test_solve_impact_runs_the_corrected_descent_with_the_options_given():
    """Three steps of the corrected descent do not solve (19): the result says so, with its residual."""
    Q, v, w = rotation([0.3, 0.7, 1.1]), np.array([0.3, 0.1, -0.5]), np.array([1.0, 2.0, 3.0])
    r = solve_impact(GRAIN, Q, v, w, 0.5, 0.3, solver="paper-corrected",
                     descent=DescentOptions(max_steps=3, line_iterations=20))
    assert r.solver == "paper-corrected" and r.iterations == 3 and not r.converged and not r.admissible
    H, uK0 = grain_impact()
    # T lies on the line of mu (T_y = T_x tan mu), so the residual is the root of the corrected Phi
    assert r.residual == pytest.approx(np.sqrt(corrected_phi(H, GRAIN.mass, 0.5, 0.3, uK0, r.T, r.mu)), rel=1e-9)
    assert r.warnings == [f"solver 'paper-corrected' did not solve (19): relative residual {r.residual:.3g}"]


def test_reduction_tensor_of_a_sphere_is_seven_halves_tangentially():
    """A solid sphere: H = 1 + R^2/rho^2 along the plane (rho^2 = 2/5 R^2), 1 along the normal, at any
    orientation; a batch of orientations gives one H each."""
    Q = rotation(np.array([[0.3, 0.7, 1.1], [2.0, 0.1, -1.0], [0.0, np.pi / 2, 0.4]]))
    H = reduction_tensor(BALL, Q)
    assert H.shape == (3, 3, 3)
    np.testing.assert_allclose(H, np.broadcast_to(SPHERE_H, (3, 3, 3)), atol=1e-12)
    np.testing.assert_allclose(reduction_tensor(BALL, Q[1]), SPHERE_H, atol=1e-12)


def trig_roots_by_scan(k, samples=2001):
    """Roots in [-pi, pi) of k0 + k1c cos + k1s sin + k2c cos 2mu + k2s sin 2mu, by brentq on sign changes."""
    from scipy.optimize import brentq

    def F(mu):
        return k[0] + k[1] * np.cos(mu) + k[2] * np.sin(mu) + k[3] * np.cos(2 * mu) + k[4] * np.sin(2 * mu)

    grid = np.linspace(-np.pi, np.pi, samples) + 1e-3  # no grid point on mu = pi
    values = F(grid)
    roots = [brentq(F, grid[i], grid[i + 1], xtol=1e-15)
             for i in np.flatnonzero(np.sign(values[:-1]) * np.sign(values[1:]) < 0)]
    return np.sort(np.mod(np.array(roots) + np.pi, 2 * np.pi) - np.pi)


def test_companion_eigenvalues_are_the_roots_before_any_polish():
    """Random trigonometric polynomials (and one with a root at mu = pi, the shift's pole): with no Newton
    polish the companion matrix's real eigenvalues already give every root; the polish then converges
    quadratically (a second sweep finds nothing to correct)."""
    rng = np.random.default_rng(3)
    k = rng.normal(size=(60, 5))
    k[0] = [1.0, 1.0, 0.3, 0.0, 0.2]  # F(pi) = k0 - k1c + k2c = 0
    raw, none = _trig_roots(k, 1e-14, max_iter=0)
    polished, sweeps = _trig_roots(k, 1e-14)
    assert none == 0 and 1 <= sweeps <= 3
    np.testing.assert_array_equal(np.isnan(_trig_roots(1e6 * k, 1e-14)[0]), np.isnan(polished))  # scale-free
    for i in range(len(k)):
        scanned = trig_roots_by_scan(k[i])
        for roots, tol in ((raw[i], 1e-8), (polished[i], 1e-13)):
            found = np.sort(roots[~np.isnan(roots)])
            assert len(found) == len(scanned), i
            np.testing.assert_allclose(found, scanned, atol=tol)


def test_newton_polishes_every_row_of_near_double_roots():
    """cos mu = 1 - x and cos 2mu = 1 - x with x = 1e-10: roots 1.4e-5 and 7e-6 rad from their doubles,
    against the closed forms 2 asin(sqrt(x/2)) and asin(sqrt(x/2)) (and pi minus it); with F flat there
    rounding bounds the roots at ~1e-12, which only a polish of every row reaches."""
    x = 1e-10
    k = np.array([[-(1 - x), 1.0, 0.0, 0.0, 0.0], [-(1 - x), 0.0, 0.0, 1.0, 0.0]])
    roots, sweeps = _trig_roots(k, 1e-14)
    assert 1 <= sweeps <= 3
    half = np.sqrt((1 + k[0, 0]) / 2)  # (1 - cos)/2 of the stored coefficient, exact in floats
    np.testing.assert_allclose(np.sort(roots[0][:2]), [-2 * np.arcsin(half), 2 * np.arcsin(half)], atol=1e-15)
    assert np.isnan(roots[0][2:]).all()
    near = np.arcsin(half)
    np.testing.assert_allclose(np.sort(roots[1]), [near - np.pi, -near, near, np.pi - near], atol=5e-12)


def test_chosen_root_has_the_least_tangential_impulse_of_the_best_class():
    """300 random impacts: among the roots, by hand, the admissible ones (no energy gained beyond 1e-9 of
    the kinetic energy, T_z not below -1e-12 |T|) come first, then the energy-creating, then the pulling;
    within the class the least |T_t| = hypot(T_x, T_y) is chosen. The mass, 10³ kg, makes impulses of order
    10³ N s: the classes must come first whatever the impulses' unit."""
    rng = np.random.default_rng(5)
    n = 300
    axes = np.exp(rng.uniform(np.log(1e-4), np.log(3e-3), (n, 3)))
    angles = np.column_stack([rng.uniform(-np.pi, np.pi, n), np.arccos(rng.uniform(-1, 1, n)),
                              rng.uniform(-np.pi, np.pi, n)])
    u = rng.normal(size=(n, 3))
    u[:, 2] = -np.abs(u[:, 2]) - 1e-3
    e, lam = rng.uniform(0, 1, n), rng.uniform(0, 1, n)
    H = g.H(*axes.T, *angles.T)
    m = 1e3
    batch = solve_robust_batch(H, m, e, lam, u)
    classes = set()
    for i in range(n):
        ok = ~np.isnan(batch.roots_mu[i])
        T = batch.roots_T[i][ok]
        uK1 = np.stack([(1 - lam[i]) * np.hypot(*u[i, :2]) * np.cos(batch.roots_mu[i][ok]),
                        (1 - lam[i]) * np.hypot(*u[i, :2]) * np.sin(batch.roots_mu[i][ok]),
                        np.full(ok.sum(), -e[i] * u[i, 2])], axis=1)
        np.testing.assert_allclose(np.einsum("ij,kj->ki", H[i], T) / m, uK1 - u[i], atol=1e-12)
        gain = 0.5 * np.sum(T * (u[i] + uK1), axis=1) > 1e-9 * 0.5 * m * u[i] @ u[i]
        pull = T[:, 2] < -1e-12 * np.linalg.norm(T, axis=1)
        rank = np.where(pull, 2, np.where(gain, 1, 0))
        best = np.flatnonzero(rank == rank.min())
        expected = T[best[np.argmin(np.hypot(T[best, 0], T[best, 1]))]]
        np.testing.assert_allclose(batch.T[i], expected, rtol=1e-12, atol=0)
        assert batch.admissible[i] == (rank.min() == 0)
        chosen = uK1[np.flatnonzero((T == batch.T[i]).all(axis=1))[0]]
        np.testing.assert_allclose(batch.uK_after[i], chosen, rtol=1e-12, atol=0)
        assert batch.residual[i] < 1e-12 and np.isnan(batch.roots_delta_ke[i][~ok]).all()
        classes.add((rank.min(), len(best) > 1))
    assert {(0, True), (1, True)} <= classes  # choices within the admissible and within the gaining roots


def test_full_stick_reports_the_impulse_direction():
    """lambda = 1 (no slip after): mu is immaterial to the law and reported as the direction of T_t,
    or 0 for a head-on sphere (T_t = 0); the law holds and the residual is at rounding. e and lambda come as
    exact rationals (as a scene's sympy constants may): read as the floats they equal."""
    H = np.stack([g.H(GRAIN.a, GRAIN.b, GRAIN.c, 0.3, 0.7, 1.1), SPHERE_H])
    u = np.array([[0.3, 0.1, -0.5], [0.0, 0.0, -1.5]])
    batch = solve_robust_batch(H, [GRAIN.mass, BALL.mass], Fraction(1, 2), Fraction(1), u)
    T0 = GRAIN.mass * np.linalg.solve(H[0], np.array([0.0, 0.0, -0.5 * -0.5]) - u[0])  # u_K after: (0, 0, -e u_z)
    np.testing.assert_allclose(batch.T[0], T0, rtol=1e-12)
    assert batch.mu[0] == pytest.approx(np.arctan2(T0[1], T0[0]), abs=1e-12)
    np.testing.assert_allclose(batch.T[1], [0.0, 0.0, BALL.mass * 1.5 * 1.5], rtol=1e-15, atol=1e-30)
    assert batch.mu[1] == 0.0
    assert (batch.residual < 1e-14).all()


def test_residual_of_19_counts_the_normal_error_and_the_line_violation_per_impact():
    """A sphere's exact impulse, pushed by delta along the normal (row 0) and across the line of mu (row 1,
    u_K(0) ten times larger): residuals delta / (m |u_K(0)|) each (H_zz = 1; (18) counts |T x d|)."""
    m, e, lam = BALL.mass, 0.4, 0.25
    u = np.array([[0.6, -0.8, -1.5], [6.0, -8.0, -15.0]])
    mu = np.full(2, np.arctan2(-0.8, 0.6))
    T = np.array([[-2 / 7 * lam * 0.6, 2 / 7 * lam * 0.8, (1 + e) * 1.5]]) * m * np.array([[1.0], [10.0]])
    delta = np.array([3e-9, 5e-9])
    T[0, 2] += delta[0]
    T[1, :2] += delta[1] * np.array([-np.sin(mu[1]), np.cos(mu[1])])
    np.testing.assert_allclose(residual_19(np.stack([SPHERE_H, SPHERE_H]), m, e, lam, u, T, mu),
                               delta / (m * np.linalg.norm(u, axis=1)), rtol=1e-6)


def test_energy_conserving_sphere_impact_is_not_flagged():
    """e = 1, lambda = 0: the sphere keeps |u_t| and reverses u_n, so its kinetic energy is kept (to
    rounding): admissible, no warning."""
    v = np.array([0.6, -0.8, -1.5])
    r = solve_impact(BALL, np.eye(3), v, np.zeros(3), 1.0, 0.0)
    assert r.ke_before == pytest.approx(0.5 * BALL.mass * v @ v, rel=1e-15)
    assert r.ke_after == pytest.approx(r.ke_before, rel=1e-12)
    assert r.admissible and r.warnings == []


def test_grazing_warning_names_both_impulses_past_ten_to_one():
    """Sphere: |T_t| / T_z = (2/7) lambda V0 / ((1 + e) |u_z|); 10.5 warns (with both impulses), 9.5 does not."""
    m, e, lam, vt = BALL.mass, 0.5, 0.3, np.array([0.5, 0.2])
    for ratio in (10.5, 9.5):
        uz = 2 / 7 * lam * np.hypot(*vt) / ((1 + e) * ratio)
        r = solve_impact(BALL, np.eye(3), np.array([*vt, -uz]), np.zeros(3), e, lam)
        Tt, Tz = 2 / 7 * m * lam * np.hypot(*vt), m * (1 + e) * uz
        assert np.hypot(*r.T[:2]) == pytest.approx(Tt, rel=1e-12) and r.T[2] == pytest.approx(Tz, rel=1e-12)
        grazing = (f"tangential impulse {Tt:.3g} N s exceeds 10x the normal impulse {Tz:.3g} N s (grazing impact: "
                   "the printed law demands friction without normal load)")
        assert r.warnings == ([grazing] if ratio > 10 else [])
