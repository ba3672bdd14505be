"""The Chatterjee-Ruina impact law on a sphere and a point mass against the textbook closed forms.

A solid sphere of radius r touching the plane at R = (0, 0, -r) has the inverse effective mass
K = diag(7/(2m), 7/(2m), 1/m) (I = 2/5 m r²). With the contact velocity u (u_z < 0):
    sticking (|P_t| <= μ P_n):  P_n = -(1 + e_n) m u_z,  P_t = -(1 + e_t) u_t / K_t   (u_t+ = -e_t u_t)
    sliding:                    P_n the same,            P_t = -μ P_n u_t/|u_t|
and v+ = v + P/m, ω+ = ω + I⁻¹ (R × P). A point mass (rotation off) is the same with K_t = 1/m.
A contact point that is not approaching the plane gets no impulse."""
from fractions import Fraction

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from symmech.grain import contact
from symmech.grain.coulomb_law import (ImpactLaw, coulomb_impulse, inverse_effective_mass, kinetic_energy,
                                       principal_inertia)

R_BALL, M_BALL = 2e-3, 3e-5
I_BALL = 0.4 * M_BALL * R_BALL ** 2
# four grains: spinning and approaching, approaching obliquely, head-on, leaving the plane
V = np.array([[0.6, -0.3, -1.0], [-0.2, 0.5, -0.4], [0.0, 0.0, -0.7], [0.3, 0.1, 0.2]])
W = np.array([[40.0, -25.0, 60.0], [-10.0, 30.0, 0.0], [0.0, 0.0, 0.0], [5.0, 5.0, 5.0]])
N = len(V)
E_N, E_T = 0.5, 0.2


def closed_form(v, w, mu, rotation):
    """Impulse P (3,), v+, ω+ of one grain by the formulas of the module docstring, and whether it slides."""
    R = np.array([0.0, 0.0, -R_BALL])
    w = w if rotation else np.zeros(3)
    u = v + np.cross(w, R)
    if u[2] >= 0:
        return np.zeros(3), v, w, False
    k_t = (1 + M_BALL * R_BALL ** 2 / I_BALL) / M_BALL if rotation else 1 / M_BALL
    p_n = -(1 + E_N) * M_BALL * u[2]
    p_t = -(1 + E_T) * u[:2] / k_t
    slides = np.linalg.norm(p_t) > mu * p_n
    if slides:
        p_t = -mu * p_n * u[:2] / np.linalg.norm(u[:2])
    P = np.r_[p_t, p_n]
    return P, v + P / M_BALL, w + np.cross(R, P) / I_BALL if rotation else np.zeros(3), slides


@pytest.mark.parametrize("rotation", [True, False])
@pytest.mark.parametrize("mu", [np.inf, 2.0, 0.4, 0.1, 0.0])
def test_sphere_sticks_or_slides_as_the_closed_forms_say(rotation, mu):
    """μ = 0.4 makes the point mass slide and the spinning sphere stick (|P_t|/P_n 0.54 and 1.08 against 0.16
    and 0.31); the head-on grain never gets a tangential impulse, whatever μ."""
    law = ImpactLaw("coulomb", e_n=E_N, e_t=E_T, mu=mu, check_printed=False)
    out = law.apply(np.full((N, 3), R_BALL), np.full(N, M_BALL), np.broadcast_to(np.eye(3), (N, 3, 3)), V, W,
                    rotation)
    u_before, u_after = out["u_before"], out["u_after"]
    regimes = []
    for i in range(N):
        P, v_after, w_after, slides = closed_form(V[i], W[i], mu, rotation)
        regimes.append(slides)
        np.testing.assert_allclose(out["impulse"][i], P, rtol=1e-12, atol=1e-18)
        np.testing.assert_allclose(out["v"][i], v_after, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(out["w"][i], w_after, rtol=1e-12, atol=1e-12)
        if i == N - 1:
            continue
        assert u_after[i, 2] == pytest.approx(-E_N * u_before[i, 2], rel=1e-12)  # restitution along n
        if slides:  # on the friction cone, against the slip
            assert np.linalg.norm(P[:2]) == pytest.approx(mu * P[2], rel=1e-12, abs=1e-18)
        else:  # inside the cone: the tangential contact velocity reversed by e_t
            np.testing.assert_allclose(u_after[i, :2], -E_T * u_before[i, :2], rtol=1e-10, atol=1e-12)
    assert not out["impulse"][2, :2].any()
    if mu == 0.4:
        assert regimes == [not rotation, not rotation, False, False]
    # energy: ½ m v² + ½ I ω², less after than before for the grains that hit
    omega = W if rotation else np.zeros((N, 3))
    ke = [0.5 * M_BALL * (v @ v) + 0.5 * I_BALL * (w @ w) for v, w in zip(V, omega)]
    np.testing.assert_allclose(out["ke_before"], ke, rtol=1e-12)
    assert np.all(out["ke_after"][:-1] < out["ke_before"][:-1]) and out["ke_after"][-1] == out["ke_before"][-1]
    assert out["admissible"].all() and out["converged"].all() and out["warnings"] == []


def test_printed_law_on_a_point_mass_and_its_check_on_a_sphere():
    """Printed law, rotation off: u_n+ = -e u_n, u_t+ = (1 - λ) u_t; checked beside the Coulomb law on a
    spinning sphere, the printed law is admissible for each approaching grain and not evaluated for the other."""
    e, lam = 0.4, 0.7
    axes, mass, Q = np.full((N, 3), R_BALL), np.full(N, M_BALL), np.broadcast_to(np.eye(3), (N, 3, 3))
    out = ImpactLaw("printed", e=e, lam=lam).apply(axes, mass, Q, V, W, rotation=False)
    np.testing.assert_allclose(out["v"][:-1], V[:-1] * [1 - lam, 1 - lam, -e], rtol=1e-12)
    np.testing.assert_array_equal(out["v"][-1], V[-1])
    assert not out["w"].any()
    checked = ImpactLaw("coulomb", e_n=E_N, e_t=E_T, mu=0.1, check_printed=True).apply(axes, mass, Q, V, W, True)
    assert checked["printed_admissible"] == [True, True, True, None]
    assert checked["printed_creates_energy"] == [False, False, False, None]


def test_kinetic_energy_and_principal_inertia_of_an_ellipsoid():
    a, b, c, m = 3e-3, 2e-3, 1e-3, 4e-5
    inertia = principal_inertia(np.array([a, b, c]), m)
    np.testing.assert_allclose(inertia, [m * (b * b + c * c) / 5, m * (a * a + c * c) / 5, m * (a * a + b * b) / 5],
                               rtol=1e-15)
    angle = 0.7  # body axes turned about Z: ω in KXYZ has components along the body axes ω_body = Qᵀ ω
    Q = np.array([[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0], [0, 0, 1]])
    v, w = np.array([0.3, -0.2, 0.5]), np.array([10.0, 20.0, -30.0])
    wb = Q.T @ w
    expected = 0.5 * m * (v @ v) + 0.5 * (inertia * wb) @ wb
    assert kinetic_energy(m, inertia, Q, v, w) == pytest.approx(expected, rel=1e-14)
    # single-precision axes and mass (inputs the API takes) are read in double: the closed form of the stored
    # values to round-off, not to float32's 1e-8
    a, b, c, m = (float(np.float32(x)) for x in (a, b, c, m))
    np.testing.assert_allclose(principal_inertia(np.float32([a, b, c]), np.float32(m)),
                               [m * (b * b + c * c) / 5, m * (a * a + c * c) / 5, m * (a * a + b * b) / 5], rtol=1e-15)


def test_inverse_effective_mass_of_a_sphere_given_in_exact_rationals():
    """A solid sphere touching at R = (0, 0, -r): K = diag(1/m + r²/I, 1/m + r²/I, 1/m) with I = 2/5 m r², so
    K_tt = 7 / (2 m); mass and inertia as exact rationals (a scene's sympy constants) give a float array."""
    m, r = Fraction(3, 100000), Fraction(1, 500)
    K = inverse_effective_mass(m, [Fraction(2, 5) * m * r * r] * 3, np.eye(3), [0.0, 0.0, -float(r)])
    assert K.dtype == np.float64
    np.testing.assert_allclose(K, np.diag([7 / (2 * 3e-5), 7 / (2 * 3e-5), 1 / 3e-5]), rtol=1e-15, atol=1e-10)


def test_sliding_impulse_of_tilted_ellipsoids_lies_on_the_friction_cone():
    """Non-spherical grains (K couples normal and tangential): the sticking candidate
    P^ = (1 + e_n) P_I + (1 + e_t) D (P_I = -u_n/K_nn n, D = -K⁻¹u - P_I) is kept inside the cone;
    outside it P = (1 + e_n) P_I + κ D with |P_t| = μ P_n exactly. Also the law of one grain, unbatched."""
    rng = np.random.default_rng(5)
    n, mu = 200, 0.15
    axes = rng.uniform(0.5e-3, 4e-3, (n, 3))
    mass = rng.uniform(1e-6, 1e-4, n)
    Q = Rotation.random(n, random_state=5).as_matrix()
    K = inverse_effective_mass(mass, principal_inertia(axes, mass), Q, contact.contact_offset(axes, Q))
    u = rng.normal(size=(n, 3))
    u[:, 2] = -np.abs(u[:, 2]) - 0.1
    P = coulomb_impulse(K, u, E_N, E_T, mu)
    sliding = 0
    for i in range(n):
        p_i = np.r_[0.0, 0.0, -u[i, 2] / K[i, 2, 2]]
        d = -np.linalg.solve(K[i], u[i]) - p_i
        candidate = (1 + E_N) * p_i + (1 + E_T) * d
        if np.linalg.norm(candidate[:2]) <= mu * candidate[2]:
            np.testing.assert_allclose(P[i], candidate, rtol=1e-12, atol=1e-12 * np.abs(candidate).max())
            continue
        sliding += 1
        rest = P[i] - (1 + E_N) * p_i  # along D
        assert np.linalg.norm(np.cross(rest, d)) < 1e-10 * np.linalg.norm(rest) * np.linalg.norm(d)
        assert rest @ d > 0
        assert np.linalg.norm(P[i, :2]) == pytest.approx(mu * P[i, 2], rel=1e-10)
        assert abs(d[2]) > 1e-3 * np.linalg.norm(d)  # the normal-tangential coupling a sphere lacks
    assert sliding > n // 4
    np.testing.assert_allclose(coulomb_impulse(K[0], u[0], E_N, E_T, mu), P[0], rtol=1e-14)
