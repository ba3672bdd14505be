"""The printed impact law with a tangential reversal (lambda > 1, the Coulomb law's e_t = lambda - 1 > 0)
against eq. (19), written out here.

Needle-shaped ellipsoids (a 10-50 times b, c) turned at random touch the plane z = 0 at their lowest point
R = -A e_z / sqrt(e_zᵀ A e_z), A = Q diag(a²) Qᵀ; with I_K = Q diag(m/5 (b² + c², a² + c², a² + b²)) Qᵀ the
reduction tensor is H = E - m [R]x I_K⁻¹ [R]x, so that m (u⁺ - u) = H T. Eq. (19) with (14)-(18) asks for
an angle mu and an impulse T with T_y cos mu = T_x sin mu (18) and
H T = m ((1 - lambda) |u_t| cos mu, (1 - lambda) |u_t| sin mu, -e u_z) - m u.
The residual below is that equation's, relative to m |u|; none of it comes from the code under test.
"""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from symmech.grain.impact import solve_robust_batch

EZ = np.array([0.0, 0.0, 1.0])


def needles(n, seed):
    """H (n, 3, 3), mass (n,) kg and approaching contact velocities u (n, 3) m/s of n tilted needles."""
    rng = np.random.default_rng(seed)
    axes = np.column_stack([rng.uniform(2e-3, 5e-3, n), rng.uniform(1e-4, 2e-4, (n, 2))])
    mass = rng.uniform(1e-6, 5e-5, n)
    Q = Rotation.random(n, random_state=seed).as_matrix()
    H = np.empty((n, 3, 3))
    for i in range(n):
        A = Q[i] @ np.diag(axes[i] ** 2) @ Q[i].T
        R = -A @ EZ / np.sqrt(EZ @ A @ EZ)
        I_K = Q[i] @ np.diag(mass[i] / 5 * (np.sum(axes[i] ** 2) - axes[i] ** 2)) @ Q[i].T
        Rx = np.array([[0.0, -R[2], R[1]], [R[2], 0.0, -R[0]], [-R[1], R[0], 0.0]])
        H[i] = np.eye(3) - mass[i] * Rx @ np.linalg.solve(I_K, Rx)
    u = rng.normal(size=(n, 3))
    u[:, 2] = -np.abs(u[:, 2])
    return H, mass, u


def residual_of_19(H, m, e, lam, u, T, mu):
    """|H T - m du(mu)| plus the violation of (18), over m |u|, per impact (n,)."""
    speed = (1 - lam) * np.hypot(u[:, 0], u[:, 1])
    after = np.column_stack([speed * np.cos(mu), speed * np.sin(mu), -e * u[:, 2]])
    r = np.einsum("nij,nj->ni", H, T) - m[:, None] * (after - u)
    off_line = np.abs(T[:, 1] * np.cos(mu) - T[:, 0] * np.sin(mu))
    return (np.linalg.norm(r, axis=1) + off_line) / (m * np.linalg.norm(u, axis=1))


@pytest.mark.parametrize("e_t", [0.3, 0.7, 1.0])
def test_a_tangential_reversal_solves_19_to_rounding_on_needles(e_t):
    """lambda = 1 + e_t: the contact point leaves along the line of its impulse at e_t times its tangential
    speed. Treating every such impact as stuck (a signed speed test) left a median residual of 0.3-1."""
    H, m, u = needles(200, 3)
    e = 0.5
    out = solve_robust_batch(H, m, e, 1 + e_t, u)
    residual = residual_of_19(H, m, e, 1 + e_t, u, out.T, out.mu)
    assert np.max(residual) < 1e-12
    np.testing.assert_array_less(out.residual, 1e-12)  # and the solver says so itself
    after = u + np.einsum("nij,nj->ni", H, out.T) / m[:, None]
    np.testing.assert_allclose(np.hypot(after[:, 0], after[:, 1]), e_t * np.hypot(u[:, 0], u[:, 1]), rtol=1e-10)
    np.testing.assert_allclose(after[:, 2], -e * u[:, 2], rtol=1e-10)


@pytest.mark.parametrize("lam", [0.0, 0.4, 0.9])
def test_lambda_and_two_minus_lambda_give_the_same_impulse(lam):
    """(1 - lambda) |u_t| (cos mu, sin mu) at 2 - lambda and mu + pi is the same velocity, and (18) holds for
    mu and mu + pi alike: the two laws have the same solutions, so the same impulse and verdicts."""
    H, m, u = needles(100, 5)
    a = solve_robust_batch(H, m, 0.5, lam, u)
    b = solve_robust_batch(H, m, 0.5, 2 - lam, u)
    scale = np.abs(a.T).max(axis=1, keepdims=True)
    np.testing.assert_allclose(b.T / scale, a.T / scale, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(b.admissible, a.admissible)
    np.testing.assert_array_equal(b.energy_created, a.energy_created)
    turned = np.mod(b.mu - a.mu, 2 * np.pi)
    assert np.max(np.abs(turned - np.pi)) < 1e-10


@pytest.mark.slow  # compiles the compiled engine's printed-law solver (~20 s on a cold numba cache)
def test_the_compiled_engine_solves_a_tangential_reversal_to_rounding_too():
    from symmech.grain.motion_engine import impact_law

    H, m, u = needles(50, 3)
    e, lam = 0.5, 1.7
    upper = np.triu_indices(3)  # the compiled law takes H by its upper triangle
    T = np.array([impact_law.printed_impulse(tuple(H[i][upper]), m[i], e, lam, u[i])[0] for i in range(len(m))])
    mu = np.arctan2(T[:, 1], T[:, 0])  # (18) fixes the line of T; (19) then holds for mu or mu + pi
    residual = np.minimum(residual_of_19(H, m, e, lam, u, T, mu), residual_of_19(H, m, e, lam, u, T, mu + np.pi))
    assert np.max(residual) < 1e-12
