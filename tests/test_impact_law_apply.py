"""``ImpactLaw.apply`` on tilted ellipsoids against hand-written rigid-body relations.

An ellipsoid with semi-axes a (body) turned by Q touches the plane z = 0 at its lowest point
R = -A e_z / sqrt(e_zᵀ A e_z), A = Q diag(a²) Qᵀ; its inertia about the centre is I_K = Q diag(I) Qᵀ with
I = m/5 (b² + c², a² + c², a² + b²). An impulse P at R changes v by P/m and ω by I_K⁻¹ (R × P); the contact
velocity is u = v + ω × R. With K = E/m - [R]x I_K⁻¹ [R]x, u⁺ = u + K P.
- Chatterjee-Ruina with μ = ∞ (sticking, when that impulse pushes: P_n > 0): P = (1 + e_n) P_I + (1 + e_t) D,
  P_I = -u_n/K_nn e_z, D = -K⁻¹u - P_I, so u⁺ = -e_t u + (e_n - e_t) (-u_n/K_nn) K e_z (u⁺_n = -e_n u_n).
- The printed law (e, λ): u⁺_n = -e u_n and |u⁺_t| = (1 - λ) |u_t| (turned by the law's angle).
Every expected value is written here from those formulas; none comes from the code under test.
"""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from symmech.grain.coulomb_law import ImpactLaw

EZ = np.array([0.0, 0.0, 1.0])


def grains(n, seed):
    """n tilted ellipsoids (axes (n, 3) m, mass (n,) kg, Q (n, 3, 3)) and their velocities v, ω (n, 3)."""
    rng = np.random.default_rng(seed)
    axes = rng.uniform(0.5e-3, 3e-3, (n, 3))
    mass = rng.uniform(1e-6, 5e-5, n)
    Q = Rotation.random(n, random_state=seed).as_matrix()
    v = rng.normal(scale=0.3, size=(n, 3))
    w = rng.normal(scale=40.0, size=(n, 3))
    return axes, mass, Q, v, w


def by_hand(a, m, Q):
    """Contact offset R (3,), world inertia I_K (3, 3) and K (3, 3) of one grain."""
    A = Q @ np.diag(a**2) @ Q.T
    R = -A @ EZ / np.sqrt(EZ @ A @ EZ)
    I_K = Q @ np.diag(m / 5 * (np.sum(a**2) - a**2)) @ Q.T
    Rx = np.array([[0.0, -R[2], R[1]], [R[2], 0.0, -R[0]], [-R[1], R[0], 0.0]])
    return R, I_K, np.eye(3) / m - Rx @ np.linalg.solve(I_K, Rx)


def sticking_pushes(a, m, Q, v, w, e_n, e_t):
    """Whether the grain approaches the plane (u_n < 0) and its sticking impulse pushes (P_n > 0)."""
    R, _, K = by_hand(a, m, Q)
    u = v + np.cross(w, R)
    return u[2] < 0 and (1 + e_n) * -u[2] / K[2, 2] + (1 + e_t) * (-np.linalg.solve(K, u)[2] + u[2] / K[2, 2]) > 0


def test_sticking_law_on_tilted_ellipsoids_reverses_the_contact_velocity_by_the_closed_form():
    e_n, e_t = 0.6, 0.3
    axes, mass, Q, v, w = grains(40, 11)
    keep = [i for i in range(40) if sticking_pushes(axes[i], mass[i], Q[i], v[i], w[i], e_n, e_t)]
    axes, mass, Q, v, w = axes[keep], mass[keep], Q[keep], v[keep], w[keep]
    assert len(keep) > 10
    out = ImpactLaw("coulomb", e_n=e_n, e_t=e_t, check_printed=False).apply(axes, mass, Q, v, w, True)
    for i in range(len(mass)):
        R, I_K, K = by_hand(axes[i], mass[i], Q[i])
        u = v[i] + np.cross(w[i], R)
        P = out["impulse"][i]
        np.testing.assert_allclose(out["u_before"][i], u, rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(out["v"][i], v[i] + P / mass[i], rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(out["w"][i], w[i] + np.linalg.solve(I_K, np.cross(R, P)), rtol=1e-10, atol=1e-9)
        u_after = -e_t * u + (e_n - e_t) * (-u[2] / K[2, 2]) * K[:, 2]
        np.testing.assert_allclose(out["u_after"][i], u_after, rtol=1e-10, atol=1e-12 * np.abs(u).max())
        assert out["u_after"][i, 2] == pytest.approx(-e_n * u[2], rel=1e-10)
        ke = [0.5 * mass[i] * x @ x + 0.5 * y @ I_K @ y for x, y in ((v[i], w[i]), (out["v"][i], out["w"][i]))]
        np.testing.assert_allclose([out["ke_before"][i], out["ke_after"][i]], ke, rtol=1e-12)
    assert out["admissible"].all() and out["converged"].all() and out["warnings"] == []
    assert out["printed_admissible"] == out["printed_creates_energy"] == [None] * len(mass)
