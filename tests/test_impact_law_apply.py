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
import dataclasses
from fractions import Fraction

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from symmech.grain import body, coulomb_law
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


def test_printed_law_on_tilted_ellipsoids_restitutes_the_contact_velocity_as_printed():
    """Printed law with rotation: u⁺_n = -e u_n, |u⁺_t| = (1 - λ) |u_t|, and the impulse moves v and ω as a rigid
    body's; each approaching grain's verdict is logged, the grain leaving gets none and no impulse; the same
    without ``check_printed`` (a flag of the Coulomb law)."""
    e, lam = 0.5, 0.4
    axes, mass, Q, v, w = grains(12, 3)
    out = ImpactLaw("printed", e=e, lam=lam).apply(axes, mass, Q, v, w, True)
    hit = 0
    for i in range(len(mass)):
        R, I_K, K = by_hand(axes[i], mass[i], Q[i])
        u = v[i] + np.cross(w[i], R)
        P, u_after = out["impulse"][i], out["u_after"][i]
        np.testing.assert_allclose(out["v"][i], v[i] + P / mass[i], rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(out["w"][i], w[i] + np.linalg.solve(I_K, np.cross(R, P)), rtol=1e-10, atol=1e-9)
        np.testing.assert_allclose(u_after, u + K @ P, rtol=1e-9, atol=1e-12 * np.abs(u).max())
        if u[2] >= 0:
            assert not P.any() and out["printed_admissible"][i] is None and out["printed_creates_energy"][i] is None
            continue
        hit += 1
        assert u_after[2] == pytest.approx(-e * u[2], rel=1e-9)
        assert np.hypot(*u_after[:2]) == pytest.approx((1 - lam) * np.hypot(*u[:2]), rel=1e-9)
        gains = out["ke_after"][i] > out["ke_before"][i] * (1 + 1e-9)
        assert out["admissible"][i] == (not gains) and out["printed_creates_energy"][i] == gains
        assert out["printed_admissible"][i] in (True, False) and out["converged"][i]
    assert 0 < hit < len(mass)
    # check_printed only adds the printed verdict to the Coulomb law: the printed law itself is solved without it
    unchecked = ImpactLaw("printed", e=e, lam=lam, check_printed=False).apply(axes, mass, Q, v, w, True)
    for key in ("impulse", "v", "w", "printed_admissible", "printed_creates_energy", "converged"):
        np.testing.assert_array_equal(unchecked[key], out[key])


def test_needle_gaining_energy_under_the_printed_law_is_flagged_with_its_energies():
    """A tumbling needle (5:1:1) under the printed law e = λ = 0.9 gains kinetic energy (the printed law has no
    admissible root there): both warnings, the energies by hand (½ m v² + ½ ωᵀ I_K ω)."""
    axes, m = np.array([[5e-3, 1e-3, 1e-3]]), np.array([1e-6])
    q0 = np.array([-0.529, 0.693, -0.481, 0.091])
    Q = Rotation.from_quat(np.r_[q0[1:], q0[0]]).as_matrix()[None]
    v, w = np.array([[0.01, 0.084, -0.3]]), np.array([[43.5, 3.4, -2.4]])
    out = ImpactLaw("printed", e=0.9, lam=0.9).apply(axes, m, Q, v, w, True)
    _, I_K, _ = by_hand(axes[0], m[0], Q[0])
    ke0, ke1 = (0.5 * m[0] * x @ x + 0.5 * y @ I_K @ y for x, y in ((v[0], w[0]), (out["v"][0], out["w"][0])))
    assert ke1 > 1.04 * ke0
    assert out["warnings"] == ["printed impact law: no admissible root; the one used creates kinetic energy",
                               f"impact law 'printed' created energy: {ke0:.6g} J -> {ke1:.6g} J"]
    assert not out["admissible"][0] and out["printed_admissible"] == [False] and out["printed_creates_energy"] == [True]


@pytest.mark.parametrize("rotation", [True, False])
def test_a_contact_point_sliding_along_the_plane_gets_no_impulse(rotation):
    """u_n = 0 exactly with a tangential slip: not approaching, so no impulse, even for μ = ∞ (whose sticking
    impulse would stop the slip). Nor does a grain at rest on the plane (the second): 0 J before and after, which
    creates no energy. The spins come as exact rationals (a scene's sympy constants): read as the floats they equal."""
    axes, mass, Q = np.full((2, 3), 2e-3), np.array([3e-5, 3e-5]), np.broadcast_to(np.eye(3), (2, 3, 3))
    v, w = np.array([[0.3, -0.1, 0.0], [0.0, 0.0, 0.0]]), np.array([[0.0, 0.0, 20.0], [0.0, 0.0, 0.0]])
    spins = [[Fraction(x) for x in row] for row in w.tolist()]
    out = ImpactLaw("coulomb", e_n=0.5, e_t=0.2, check_printed=False).apply(axes, mass, Q, v, spins, rotation)
    assert not out["impulse"].any()
    np.testing.assert_array_equal(out["v"], v)
    np.testing.assert_array_equal(out["w"], w if rotation else np.zeros((2, 3)))
    assert out["ke_before"][1] == out["ke_after"][1] == 0.0
    assert out["admissible"].tolist() == [True, True] and out["warnings"] == []


def test_the_printed_verdict_is_given_only_for_a_rotating_grain():
    """A point mass (rotation off) gets no printed-law verdict: None, and the Coulomb impulse by the closed form
    P_n = -(1 + e_n) m u_n, P_t = -(1 + e_t) m u_t (μ = ∞)."""
    axes, mass, Q = np.full((2, 3), 2e-3), np.array([3e-5, 1e-5]), np.broadcast_to(np.eye(3), (2, 3, 3))
    v, w = np.array([[0.3, -0.1, -0.5], [0.0, 0.2, -0.1]]), np.array([[40.0, 0.0, 20.0], [0.0, 0.0, 0.0]])
    out = ImpactLaw("coulomb", e_n=0.5, e_t=0.2, check_printed=True).apply(axes, mass, Q, v, w, False)
    assert out["printed_admissible"] == out["printed_creates_energy"] == [None, None]
    np.testing.assert_allclose(out["impulse"], -mass[:, None] * v * [1.2, 1.2, 1.5], rtol=1e-12)


def test_the_printed_verdict_beside_the_coulomb_law_is_the_printed_laws_with_e_n_and_one_plus_e_t():
    """With check_printed, the Coulomb law logs the verdict of the printed law with e = e_n, λ = 1 + e_t: the verdict
    the printed law itself gets (its energy gain checked by hand above), which differs from λ = 2 + e_t or e = λ = 0
    on these grains. The needle gains energy under e = λ = 0.9, i.e. e_n = 0.9, e_t = -0.1."""
    e_n, e_t = 0.9, 0.6
    axes, mass, Q, v, w = grains(40, 3)
    checked = ImpactLaw("coulomb", e_n=e_n, e_t=e_t, mu=0.3).apply(axes, mass, Q, v, w, True)
    printed = ImpactLaw("printed", e=e_n, lam=1 + e_t).apply(axes, mass, Q, v, w, True)
    for i in range(len(mass)):
        R, I_K, _ = by_hand(axes[i], mass[i], Q[i])
        if (v[i] + np.cross(w[i], R))[2] < 0:
            ke = [0.5 * mass[i] * x @ x + 0.5 * y @ I_K @ y
                  for x, y in ((v[i], w[i]), (printed["v"][i], printed["w"][i]))]
            assert printed["printed_creates_energy"][i] == (ke[1] > ke[0] * (1 + 1e-9))
    assert checked["printed_admissible"] == printed["printed_admissible"]
    assert checked["printed_creates_energy"] == printed["printed_creates_energy"]
    assert checked["printed_admissible"].count(False) == 2
    needle = (np.array([[5e-3, 1e-3, 1e-3]]), np.array([1e-6]),
              Rotation.from_quat([0.693, -0.481, 0.091, -0.529]).as_matrix()[None], np.array([[0.01, 0.084, -0.3]]),
              np.array([[43.5, 3.4, -2.4]]))
    out = ImpactLaw("coulomb", e_n=0.9, e_t=-0.1, mu=0.3).apply(*needle, True)
    assert out["printed_admissible"] == [False] and out["printed_creates_energy"] == [True]
    assert out["admissible"][0] and out["warnings"] == []  # the Coulomb law itself never gains


def test_grazing_ellipsoid_under_the_printed_law_is_pulled_into_the_plane_and_says_so():
    """A tilted ellipsoid (2, 1.5, 1 mm) grazing the plane (u_n = -1e-6 m/s, slipping at 0.54 m/s), printed law
    e = 0.5, λ = 0.3: the only roots pull it into the plane (P_z < 0), no energy gained; the law still holds
    (u⁺_n = -e u_n, |u⁺_t| = (1 - λ)|u_t|) and it is converged."""
    axes, mass = np.array([[2e-3, 1.5e-3, 1e-3]]), np.array([1e-5])
    Q = body.rotation([0.3, 0.7, 1.1])[None]
    v, w = np.array([[0.5, 0.2, -1e-6]]), np.zeros((1, 3))
    out = ImpactLaw("printed", e=0.5, lam=0.3).apply(axes, mass, Q, v, w, True)
    assert out["impulse"][0, 2] < 0
    assert out["warnings"] == ["printed impact law: no admissible root; the one used pulls the grain into the plane "
                               "(T_z < 0)"]
    assert out["printed_admissible"] == [False] and out["printed_creates_energy"] == [False]
    assert out["admissible"][0] and out["converged"][0]
    u_after = out["u_after"][0]
    assert u_after[2] == pytest.approx(0.5e-6, rel=1e-6)
    assert np.hypot(*u_after[:2]) == pytest.approx(0.7 * np.hypot(0.5, 0.2), rel=1e-9)


def test_a_printed_solve_left_with_a_residual_is_not_converged_and_says_so(monkeypatch):
    """The printed law's solver returns the relative residual of (19) it reached; at or above 1e-8 the impact is
    not converged and a warning gives the residual. The solver leaves none on a sphere, so its residuals are set
    here: 1e-8 exactly, 3e-8 and 0 for three spheres hitting the plane (which the printed law never makes gain
    energy: no other warning)."""
    real = coulomb_law.solve_robust_batch

    def left_with_residuals(*args, **kwargs):
        return dataclasses.replace(real(*args, **kwargs), residual=np.array([1e-8, 3e-8, 0.0]))

    monkeypatch.setattr(coulomb_law, "solve_robust_batch", left_with_residuals)
    axes, mass, Q = np.full((3, 3), 2e-3), np.full(3, 3e-5), np.broadcast_to(np.eye(3), (3, 3, 3))
    v, w = np.array([[0.3, -0.1, -0.5], [0.0, 0.2, -0.1], [0.0, 0.0, -1.0]]), np.full((3, 3), 10.0)
    out = ImpactLaw("printed", e=0.5, lam=0.3).apply(axes, mass, Q, v, w, True)
    assert out["converged"].tolist() == [False, False, True]
    assert out["warnings"] == ["printed impact law: no solution of (19) (relative residual 1e-08)",
                               "printed impact law: no solution of (19) (relative residual 3e-08)"]
