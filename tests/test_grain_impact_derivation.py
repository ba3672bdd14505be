"""Grain impact derivations: generated code vs independent physics vs printed vs plain lambdify."""
import inspect

import numpy as np
import pytest
import sympy

from symmech.generated import grain_impact as g
from symmech.generated import grain_impact_printed as printed
from symmech.grain import derive

N = 1200


def rot_z(t):
    c, s = np.cos(t), np.sin(t)
    z, o = np.zeros_like(t), np.ones_like(t)
    return np.stack([np.stack([c, -s, z], -1), np.stack([s, c, z], -1), np.stack([z, z, o], -1)], -2)


def rot_x(t):
    c, s = np.cos(t), np.sin(t)
    z, o = np.zeros_like(t), np.ones_like(t)
    return np.stack([np.stack([o, z, z], -1), np.stack([z, c, -s], -1), np.stack([z, s, c], -1)], -2)


@pytest.fixture(scope="module")
def configs():
    """Seeded shapes: random, spheres, flat discs and needles; random and special orientations."""
    rng = np.random.default_rng(7)
    axes = np.exp(rng.uniform(np.log(1e-4), np.log(3e-3), (N, 3)))
    axes[:100] = axes[:100, :1]  # spheres
    axes[100:200] = axes[100:200] * np.array([1.0, 1.0, 1e-2])  # flat discs
    axes[200:300] = axes[200:300] * np.array([1.0, 1e-2, 1e-2])  # needles
    angles = np.column_stack([rng.uniform(-np.pi, np.pi, N), np.arccos(rng.uniform(-1, 1, N)),
                              rng.uniform(-np.pi, np.pi, N)])
    angles[300:340, 1] = 0.0  # gimbal lock: body Z' along the normal
    angles[340:380, 1] = np.pi
    angles[380:420, 1] = np.pi / 2
    return axes, angles


def independent(axes, angles):
    """Q, R, P and H by plain numpy: elementary rotations, Lagrange support point, unit impulses."""
    Q = rot_z(angles[:, 0]) @ rot_x(angles[:, 1]) @ rot_z(angles[:, 2])
    D2 = axes**2
    n_body = Q[:, 2, :]  # Q^T e_z
    x_body = -D2 * n_body / np.sqrt(np.sum(D2 * n_body**2, axis=1))[:, None]
    R = np.einsum("nij,nj->ni", Q, x_body)
    a2, b2, c2 = D2.T
    rho2 = np.column_stack([b2 + c2, a2 + c2, a2 + b2]) / 5
    P = np.einsum("nij,nj,nkj->nik", Q, rho2, Q)
    H = np.empty((len(axes), 3, 3))
    for k in range(3):  # response of the contact point to a unit impulse per unit mass along axis k
        t = np.zeros((len(axes), 3))
        t[:, k] = 1.0
        d_omega = np.linalg.solve(P, np.cross(R, t)[..., None])[..., 0]
        H[:, :, k] = t + np.cross(d_omega, R)
    return Q, R, P, H


def test_rotation_matches_elementary_rotations(configs):
    axes, angles = configs
    Q, *_ = independent(axes, angles)
    np.testing.assert_allclose(g.rotation(*angles.T), Q, atol=1e-15)


def test_contact_point_is_the_lowest_point(configs):
    axes, angles = configs
    R = g.contact_offset(*axes.T, *angles.T)
    Q = g.rotation(*angles.T)
    x_body = np.einsum("nji,nj->ni", Q, R)
    on_surface = np.sum((x_body / axes) ** 2, axis=1)
    np.testing.assert_allclose(on_surface, 1.0, rtol=1e-12)
    normal = np.einsum("nij,nj->ni", Q, x_body / axes**2)  # outward normal at K, surface frame
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    # x/a^2 amplifies rounding by up to (a/c)^2 = 1e4 for discs and needles.
    np.testing.assert_allclose(normal, np.tile([0, 0, -1.0], (N, 1)), atol=1e-9)
    np.testing.assert_allclose(g.contact_height(*axes.T, *angles.T), -R[:, 2], rtol=1e-13)


def test_H_generated_equals_unit_impulse_physics(configs):
    axes, angles = configs
    _, R, P, H = independent(axes, angles)
    np.testing.assert_allclose(g.inertia_ratio(*axes.T, *angles.T), P, rtol=1e-12, atol=1e-20)
    np.testing.assert_allclose(g.contact_offset(*axes.T, *angles.T), R, rtol=1e-12, atol=1e-18)
    Hg = g.H(*axes.T, *angles.T)
    scale = np.abs(H).max(axis=(1, 2))[:, None, None]
    assert np.max(np.abs(Hg - H) / scale) < 1e-9


def test_H_printed_transcription_agrees_given_the_true_inertia(configs):
    axes, angles = configs
    _, R, P, H = independent(axes, angles)
    Hp = printed.H(*R.T, P[:, 0, 0], P[:, 0, 1], P[:, 0, 2], P[:, 1, 1], P[:, 1, 2], P[:, 2, 2])
    scale = np.abs(H).max(axis=(1, 2))[:, None, None]
    assert np.max(np.abs(Hp - H) / scale) < 1e-8


def test_H_plain_lambdify_agrees(configs):
    axes, angles = configs
    f = sympy.lambdify([derive.a, derive.b, derive.c, derive.psi, derive.theta, derive.phi],
                       derive.reduction_tensor(), "numpy")
    Hl = np.moveaxis(np.array(f(*axes.T, *angles.T), dtype=float), -1, 0)
    Hg = g.H(*axes.T, *angles.T)
    np.testing.assert_allclose(Hg, Hl, rtol=1e-9, atol=1e-9)


def test_H_is_symmetric_and_at_least_identity(configs):
    axes, angles = configs
    H = g.H(*axes.T, *angles.T)
    scale = np.abs(H).max(axis=(1, 2))
    # Needles (radii of gyration 1:100) amplify rounding in P^-1 by ~1e4.
    assert np.max(np.abs(H - np.swapaxes(H, 1, 2)).max(axis=(1, 2)) / scale) < 1e-10
    eig = np.linalg.eigvalsh(H)
    # R itself is an eigenvector with eigenvalue 1 (an impulse along R spins nothing).
    np.testing.assert_allclose(eig[:, 0], 1.0, atol=1e-9)
    assert np.all(eig[:, 1:] >= 1.0 - 1e-9)


def test_sphere_H_is_diag_seven_halves():
    """Solid sphere: the tangential effective mass is 2/7 m, the normal one m."""
    H = g.H(1e-3, 1e-3, 1e-3, 0.4, 1.3, -2.0)
    np.testing.assert_allclose(H, np.diag([3.5, 3.5, 1.0]), atol=1e-12)


def test_euler_rate_matrix_matches_finite_differences():
    rng = np.random.default_rng(3)
    for _ in range(20):
        angles = np.array([rng.uniform(-3, 3), rng.uniform(0.2, 2.9), rng.uniform(-3, 3)])
        rates = rng.normal(size=3)  # (theta', psi', phi')
        dt = 1e-6
        order = np.array([rates[1], rates[0], rates[2]])  # psi, theta, phi order
        Qp, Qm = g.rotation(*(angles + dt * order)), g.rotation(*(angles - dt * order))
        Q = g.rotation(*angles)
        skew = Q.T @ (Qp - Qm) / (2 * dt)
        omega_body = np.array([skew[2, 1], skew[0, 2], skew[1, 0]])
        W = g.euler_rate_matrix(angles[1], angles[2])
        np.testing.assert_allclose(W @ rates, omega_body, rtol=1e-7, atol=1e-8)


def test_gradient_of_the_printed_functional_matches_finite_differences():
    """functional_gradient, the errata's reference for (25)-(27), is the gradient of the printed (24) in
    (T_x, T_z, mu): central differences of printed.functional, step 1e-6 of each variable's scale."""
    rng = np.random.default_rng(5)
    A = rng.normal(size=(3, 3))
    H = np.eye(3) + A @ A.T
    h = (H[0, 0], H[0, 1], H[0, 2], H[1, 1], H[1, 2], H[2, 2])
    m, lam, e, u = 1e-5, 0.3, 0.6, (0.4, -0.2, -0.7)
    for x in rng.normal(size=(10, 3)) * np.array([m, m, 0.5]):
        grad = printed.functional_gradient(*x, *h, m, lam, e, *u)
        for k, step in enumerate((1e-6 * m, 1e-6 * m, 1e-6)):
            up, down = x.copy(), x.copy()
            up[k] += step
            down[k] -= step
            difference = (printed.functional(*up, *h, m, lam, e, *u) - printed.functional(*down, *h, m, lam, e, *u))
            assert grad[k] == pytest.approx(difference.item() / (2 * step), rel=1e-7, abs=1e-9 * m)


def test_mu_equation_is_the_determinant_condition():
    """F(mu) from the generated coefficients equals det[H d, H e_z, du(mu)] evaluated directly."""
    rng = np.random.default_rng(11)
    A = rng.normal(size=(3, 3))
    H = np.eye(3) + A @ A.T
    lam, e, u = 0.3, 0.6, np.array([0.4, -0.2, -0.7])
    k = g.mu_equation(H[0, 0], H[0, 1], H[0, 2], H[1, 1], H[1, 2], H[2, 2], lam, e, *u)
    for mu in np.linspace(-3, 3, 13):
        d = np.array([np.cos(mu), np.sin(mu), 0.0])
        speed = (1 - lam) * np.hypot(u[0], u[1])
        du = np.array([speed * np.cos(mu) - u[0], speed * np.sin(mu) - u[1], -(1 + e) * u[2]])
        direct = np.linalg.det(np.column_stack([H @ d, H[:, 2], du]))
        F = k[0] + k[1] * np.cos(mu) + k[2] * np.sin(mu) + k[3] * np.cos(2 * mu) + k[4] * np.sin(2 * mu)
        assert F == pytest.approx(direct, rel=1e-12, abs=1e-14)


def test_mu_equation_is_a_velocity():
    """det[H d, H e_z, du]: H and d are dimensionless, du is a velocity, so the coefficients are in m/s:
    scaling the contact velocity by s scales every coefficient by s (H fixed), and the generated docstring says so."""
    rng = np.random.default_rng(12)
    A = rng.normal(size=(3, 3))
    H = np.eye(3) + A @ A.T
    h = (H[0, 0], H[0, 1], H[0, 2], H[1, 1], H[1, 2], H[2, 2])
    u = np.array([0.4, -0.2, -0.7])
    k = g.mu_equation(*h, 0.3, 0.6, *u)
    np.testing.assert_allclose(g.mu_equation(*h, 0.3, 0.6, *(2.5 * u)), 2.5 * k, rtol=1e-13, atol=1e-15)
    # the docstring's content, not its layout (Python 3.13 strips the common indentation of docstrings)
    returns = inspect.cleandoc(g.mu_equation.__doc__).split("Returns\n-------\n")[1]
    assert [line.strip() for line in returns.splitlines()] == ["numpy.ndarray, shape (..., 5)", "[m/s]"]
