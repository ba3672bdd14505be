"""The paper's conventions of the rigid trolley (symmech.trolley.model: paper_lstar, paper_lstar_derivative,
paper_case; small_angle_check's least squares) against closed forms (issue 23 item 1, mutation testing).

The paper's Λ* is its printed Rodrigues matrix cE + (1 - c) ξξᵀ + s[[0, ξ3, -ξ2], [-ξ3, 0, ξ1], [ξ2, -ξ1, 0]]
(c, s of ψ = acos(t·ρ)) of the unnormalised axis ξ = t × ρ in fixed components, ρ the unit chord. On a helix
X = (R cos p, R sin p, λ p), p = s/r, r² = R² + λ², the whole figure turns about X3 by 1/r rad per metre of s,
and the printed matrix turns with it, so dΛ*/ds = (K Λ* - Λ* K)/r with K = [e3]×; on a vertical circle
(λ = 0) ξ = sin ψ e3 with ψ = asin(l/2R) at every s, so Λ* is constant. The front axle of a helix is found
by bisection on 2R²(1 - cos(Δ/r)) + (λΔ/r)² = l², its Frenet frame is (t, n, b) with Ω = [τ, 0, κ], κ = R/r²,
τ = λ/r². paper_case's kinematics in the paper's conventions (ω = Ω used as rad/s, a0 = V̇0 + ω × V0,
V0* = Λ* V0, ω* = Λ* ω, V̇0* = Λ̇* V0 + Λ* V̇0, ω̇* = Λ̇* ω + Λ* ω̇, Λ̇* = dΛ*/ds V0) are written out here.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from symmech.core.scene import SymmechError
from symmech.trolley import model

R, L = 2.0, 1.3
BODY = model.Body(m=80.0, r=(0.7, 0.4, -0.3), inertia=(5.0, 6.0, 7.0, 0.0, 0.0, 0.0), l=L, ah=0.9, g0=9.81)


class Helix:
    """X = (R cos p, R sin p, λ p), p = s/r (λ = 0: a vertical circle, X2 up); derivatives by hand. ``seen``
    collects the arc lengths at which the Frenet frame (derivatives up to the 4th) was evaluated."""

    def __init__(self, rise):
        self.rise, self.root = rise, np.hypot(R, rise)
        self.seen = []

    def derivatives(self, s, order):
        s = np.asarray(s, float)
        if order == 4:
            self.seen.append(s.ravel())
        p, z = s / self.root, np.zeros_like(s)
        rows = [(R * np.cos(p), R * np.sin(p), self.rise * p)]
        for k in range(1, order + 1):  # a quarter turn per derivative
            rows.append((R * np.cos(p + k * np.pi / 2) / self.root**k, R * np.sin(p + k * np.pi / 2) / self.root**k,
                         z + (self.rise / self.root if k == 1 else 0.0)))
        return [np.stack(row, axis=-1) for row in rows]

    def frenet(self, s):
        """(t, n, b) as rows (n, 3, 3) and Ω = [τ, 0, κ]."""
        p = np.asarray(s, float) / self.root
        t = np.stack([-R * np.sin(p), R * np.cos(p), np.full_like(p, self.rise)], -1) / self.root
        n = np.stack([-np.cos(p), -np.sin(p), np.zeros_like(p)], -1)
        b = np.stack([self.rise * np.sin(p), -self.rise * np.cos(p), np.full_like(p, R)], -1) / self.root
        return np.stack([t, n, b], -2), np.array([self.rise, 0.0, R]) / self.root**2

    def front(self, s):
        def gap(d):
            return 2 * R**2 * (1 - np.cos(d / self.root)) + (self.rise * d / self.root) ** 2 - L * L
        return np.array([x + brentq(gap, 0.5 * L, 2 * L, xtol=1e-15) for x in np.atleast_1d(s)])

    def lstar(self, s):
        """The paper's Λ* (n, 3, 3), from the printed matrix."""
        s = np.atleast_1d(np.asarray(s, float))
        t = self.frenet(s)[0][:, 0]
        rho = (self.derivatives(self.front(s), 0)[0] - self.derivatives(s, 0)[0]) / L
        out = []
        for ti, ri in zip(t, rho):
            psi, (x1, x2, x3) = np.arccos(ti @ ri), np.cross(ti, ri)
            c, sn = np.cos(psi), np.sin(psi)
            out.append(c * np.eye(3) + (1 - c) * np.outer([x1, x2, x3], [x1, x2, x3])
                       + sn * np.array([[0, x3, -x2], [-x3, 0, x1], [x2, -x1, 0]]))
        return np.array(out)

    def dlstar(self, s):
        """dΛ*/ds = (K Λ* - Λ* K)/r: the figure turns about X3 at 1/r rad/m."""
        K = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
        lstar = self.lstar(s)
        return (K @ lstar - lstar @ K) / self.root


HELIX, CIRCLE = Helix(0.5), Helix(0.0)


@pytest.mark.parametrize("track", [HELIX, CIRCLE], ids=["helix", "circle"])
def test_paper_lstar_is_the_printed_rodrigues_of_the_unnormalised_axis(track):
    """s = 0 on the circle is a vertical tangent: the Frenet frame holds there (the twist frame would not)."""
    s = np.array([0.0, 0.8, 2.5])
    lstar, base = model.paper_lstar(track, s, L, "frenet")
    np.testing.assert_allclose(lstar, track.lstar(s), atol=1e-12)
    np.testing.assert_allclose(base.lam, track.frenet(s)[0], atol=1e-12)
    if track is CIRCLE:  # ψ = asin(l/2R) about e3, |ξ| = sin ψ: the printed matrix is not a rotation
        c, sn = np.sqrt(1 - (L / (2 * R)) ** 2), L / (2 * R)
        closed = [[c, sn * sn, 0], [-sn * sn, c, 0], [0, 0, c + (1 - c) * sn * sn]]
        np.testing.assert_allclose(lstar, np.broadcast_to(closed, lstar.shape), atol=1e-12)


def test_paper_lstar_derivative_by_central_differences_against_the_turning_helix():
    """central2 and central4 with the grid's step (0.05 m): errors of order h² and h⁴ against the exact
    (K Λ* - Λ* K)/r; inside a plan's span the frame is evaluated at no arc length outside it."""
    s = np.linspace(0.5, 2.0, 31)
    exact = HELIX.dlstar(s)
    assert np.abs(exact).max() > 5e-3
    lstar = HELIX.lstar(s)
    err2 = np.abs(model.paper_lstar_derivative(HELIX, s, L, "frenet", lstar, "central2") - exact).max()
    err4 = np.abs(model.paper_lstar_derivative(HELIX, s, L, "frenet", lstar, "central4") - exact).max()
    assert 1e-6 < err2 < 1e-4 and err4 < 1e-8
    plan = model.FramePlan("frenet", np.zeros(0), np.zeros(0), span=(0.5, 2.0))
    HELIX.seen.clear()
    spanned = model.paper_lstar_derivative(HELIX, s, L, "frenet", lstar, "central4", plan)
    np.testing.assert_allclose(spanned, exact, atol=1e-7)
    nodes = np.concatenate(HELIX.seen)
    assert nodes.min() >= 0.5 and nodes.max() <= 2.0 + 1e-12


def test_paper_lstar_derivative_backward_is_the_papers_difference_between_grid_points():
    """(Λ*_k - Λ*_(k-1)) / (s_k - s_(k-1)), zero where s does not advance, the first row as the second;
    a single point has none."""
    rng = np.random.default_rng(7)
    s = np.array([0.0, 0.1, 0.3, 0.3, 0.6])
    lstar = rng.normal(size=(5, 3, 3))
    out = model.paper_lstar_derivative(HELIX, s, L, "frenet", lstar, "backward")
    ref = np.array([(lstar[k] - lstar[k - 1]) / (s[k] - s[k - 1]) if s[k] > s[k - 1] else np.zeros((3, 3))
                    for k in range(1, 5)])
    np.testing.assert_allclose(out[1:], ref, rtol=1e-14)
    np.testing.assert_allclose(out[0], ref[0], rtol=1e-14)
    np.testing.assert_array_equal(model.paper_lstar_derivative(HELIX, s[:1], L, "frenet", lstar[:1], "backward"),
                                  np.zeros((1, 3, 3)))


def _paper_kinematics(lam, W, V0, dV0, lstar=None, dlstar=None):
    """V, a, ω, ω̇, Λ̄ in the paper's conventions (the helix's and circle's Ω' = 0)."""
    r = np.array(BODY.r)
    vel, dvel, dW = V0[:, None] * [1.0, 0, 0], dV0[:, None] * [1.0, 0, 0], np.zeros_like(W)
    if lstar is not None:
        rate = dlstar * V0[:, None, None]
        vel, dvel = np.einsum("nij,nj->ni", lstar, vel), np.einsum("nij,nj->ni", rate, vel) + np.einsum(
            "nij,nj->ni", lstar, dvel)
        W, dW = np.einsum("nij,nj->ni", lstar, W), np.einsum("nij,nj->ni", rate, W)
        lam = lstar @ lam
    V = vel + np.cross(W, r)
    a = dvel + np.cross(W, vel) + np.cross(dW, r) + np.cross(W, np.cross(W, r))
    return V, a, W, dW, lam


@pytest.mark.parametrize("track", [HELIX, CIRCLE], ids=["helix", "circle"])
def test_paper_case_kinematics_in_the_papers_conventions(track):
    """Case 1, case 2 with Λ̇* given, and case 2 by default (the backward difference; on the circle Λ* is
    constant, so zero, and s = 0 is a vertical tangent); case 1 with a plan rolling the frame by 0.3 rad
    beyond s = 1 m."""
    s = np.linspace(0.0, 1.5, 7)
    V0, dV0 = 5.0 + 2.0 * s, 1.5 - s
    lam, omega = track.frenet(s)
    W = np.broadcast_to(omega, (len(s), 3))
    keys = ("V", "a", "omega", "omega_dot", "lam")

    def check(out, ref):
        for key, value in zip(keys, ref):
            np.testing.assert_allclose(out[key], value, atol=1e-10, err_msg=key)

    check(model.paper_case(track, s, V0, dV0, BODY, "frenet", False), _paper_kinematics(lam, W, V0, dV0))
    given = 0.02 * np.random.default_rng(3).normal(size=(len(s), 3, 3))
    check(model.paper_case(track, s, V0, dV0, BODY, "frenet", True, dlstar=given),
          _paper_kinematics(lam, W, V0, dV0, track.lstar(s), given))
    if track is CIRCLE:
        check(model.paper_case(track, s, V0, dV0, BODY, "frenet", True),
              _paper_kinematics(lam, W, V0, dV0, track.lstar(s), np.zeros((len(s), 3, 3))))
        central = model.paper_case(track, s, V0, dV0, BODY, "frenet", True, derivative="central4")
        check(central, _paper_kinematics(lam, W, V0, dV0, track.lstar(s), np.zeros((len(s), 3, 3))))
    roll = np.where(s > 1.0, 0.3, 0.0)
    c, sn = np.cos(roll)[:, None, None], np.sin(roll)[:, None, None]
    turn = np.zeros((len(s), 3, 3))
    turn[:, 0, 0], turn[:, 1:, 1:] = 1.0, np.block([[c, sn], [-sn, c]])
    plan = model.FramePlan("frenet", np.array([1.0]), np.array([0.3]))
    check(model.paper_case(track, s, V0, dV0, BODY, "frenet", False, plan=plan),
          _paper_kinematics(turn @ lam, np.einsum("nij,j->ni", turn, omega), V0, dV0))
