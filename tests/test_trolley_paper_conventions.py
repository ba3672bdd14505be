"""The paper's conventions of the rigid trolley (symmech.trolley.model: paper_lstar, paper_lstar_derivative,
paper_case; small_angle_check's least squares) against closed forms (mutation testing).

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


class Curve:
    """A unit-speed track by hand: ``derivatives`` (collecting in ``seen`` the arc lengths at which the
    Frenet frame, derivatives up to the 4th, was evaluated), the Frenet frame, the front axle, the paper's Λ*."""

    def __init__(self):
        self.seen = []

    def derivatives(self, s, order):
        s = np.asarray(s, float)
        if order == 4:
            self.seen.append(s.ravel())
        return [np.stack(row, axis=-1) for row in self.rows(s, order)]

    def front(self, s):
        x0 = self.derivatives(s, 0)[0]
        def gap(d, x, k):
            return np.linalg.norm(self.derivatives(x + d, 0)[0] - x0[k]) - L
        return np.array([x + brentq(gap, L, 2 * L, args=(x, k), xtol=1e-15) for k, x in enumerate(s)])

    def lstar(self, s):
        """The paper's Λ* (n, 3, 3), from the printed matrix."""
        s = np.atleast_1d(np.asarray(s, float))
        t = self.frenet(s)[0][:, 0]
        rho = (self.derivatives(self.front(s), 0)[0] - self.derivatives(s, 0)[0]) / L
        out = []
        for ti, ri in zip(t, rho):
            psi, (x1, x2, x3) = np.arccos(np.clip(ti @ ri, -1, 1)), np.cross(ti, ri)
            c, sn = np.cos(psi), np.sin(psi)
            out.append(c * np.eye(3) + (1 - c) * np.outer([x1, x2, x3], [x1, x2, x3])
                       + sn * np.array([[0, x3, -x2], [-x3, 0, x1], [x2, -x1, 0]]))
        return np.array(out)


class Helix(Curve):
    """X = (R cos p, R sin p, λ p), p = s/r (λ = 0: a vertical circle, X2 up)."""

    def __init__(self, rise):
        super().__init__()
        self.rise, self.root = rise, np.hypot(R, rise)

    def rows(self, s, order):
        p, z = s / self.root, np.zeros_like(s)
        rows = [(R * np.cos(p), R * np.sin(p), self.rise * p)]
        for k in range(1, order + 1):  # a quarter turn per derivative
            rows.append((R * np.cos(p + k * np.pi / 2) / self.root**k, R * np.sin(p + k * np.pi / 2) / self.root**k,
                         z + (self.rise / self.root if k == 1 else 0.0)))
        return rows

    def frenet(self, s):
        """(t, n, b) as rows (n, 3, 3), Ω = [τ, 0, κ], Ω' = 0, each (n, 3)."""
        p = np.asarray(s, float) / self.root
        t = np.stack([-R * np.sin(p), R * np.cos(p), np.full_like(p, self.rise)], -1) / self.root
        n = np.stack([-np.cos(p), -np.sin(p), np.zeros_like(p)], -1)
        b = np.stack([self.rise * np.sin(p), -self.rise * np.cos(p), np.full_like(p, R)], -1) / self.root
        omega = np.broadcast_to(np.array([self.rise, 0.0, R]) / self.root**2, t.shape)
        return np.stack([t, n, b], -2), omega, np.zeros_like(t)

    def dlstar(self, s):
        """dΛ*/ds = (K Λ* - Λ* K)/r: the figure turns about X3 at 1/r rad/m."""
        K = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
        lstar = self.lstar(s)
        return (K @ lstar - lstar @ K) / self.root


class Catenary(Curve):
    """X = (asinh s, √(1 + s²), 0): κ = 1/(1 + s²), so Ω' = [0, 0, -2s/(1 + s²)²] is not zero."""

    def rows(self, s, order):
        w, z = 1 + s * s, np.zeros_like(s)
        x = [np.arcsinh(s), 1, -s, 2 * s * s - 1, -3 * s * (2 * s * s - 3)]
        y = [np.sqrt(w), s, 1, -3 * s, 3 * (4 * s * s - 1)]
        return [(x[0], y[0], z)] + [(x[k] * w ** (0.5 - k), y[k] * w ** (0.5 - k), z) for k in range(1, order + 1)]

    def frenet(self, s):
        s = np.asarray(s, float)
        w, z, one = 1 + s * s, np.zeros_like(s), np.ones_like(s)
        lam = np.stack([np.stack([one, s, z], -1) / np.sqrt(w)[:, None],
                        np.stack([-s, one, z], -1) / np.sqrt(w)[:, None], np.stack([z, z, one], -1)], -2)
        return lam, np.stack([z, z, 1 / w], -1), np.stack([z, z, -2 * s / w**2], -1)


class Line(Curve):
    """X = s u, u = (0.6, 0.8, 0): no Frenet frame; the rotation-minimising frame started from the upward
    normal is constant, rows u, (e2 - 0.8 u)/0.6, u × x2. Its chord lies along t, and t·ρ exceeds 1 by
    rounding at some s."""

    U = np.array([0.6, 0.8, 0.0])

    def rows(self, s, order):
        z = np.zeros_like(s)
        return [tuple(s * c for c in self.U), tuple(z + c for c in self.U)] + [(z, z, z)] * (order - 1)

    def frame(self):
        x2 = (np.array([0.0, 1.0, 0.0]) - 0.8 * self.U) / 0.6
        return np.stack([self.U, x2, np.cross(self.U, x2)])


HELIX, CIRCLE, CATENARY, LINE = Helix(0.5), Helix(0.0), Catenary(), Line()


@pytest.mark.parametrize("track", [HELIX, CIRCLE], ids=["helix", "circle"])
def test_paper_lstar_is_the_printed_rodrigues_of_the_unnormalised_axis(track):
    """s = 0 on the circle is a vertical tangent: the Frenet frame holds there (the twist frame would not)."""
    s = np.array([0.0, 0.8, 2.5])
    lstar, base = model.paper_lstar(track, s, L, "frenet")
    np.testing.assert_allclose(lstar, track.lstar(s), atol=1e-12)
    np.testing.assert_allclose(base.lam, track.frenet(s)[0], atol=1e-12)
    np.testing.assert_allclose(model.paper_lstar(track, s[1], L, "frenet")[0], lstar[1], atol=1e-15)  # a scalar s
    if track is CIRCLE:  # ψ = asin(l/2R) about e3, |ξ| = sin ψ: the printed matrix is not a rotation
        c, sn = np.sqrt(1 - (L / (2 * R)) ** 2), L / (2 * R)
        closed = [[c, sn * sn, 0], [-sn * sn, c, 0], [0, 0, c + (1 - c) * sn * sn]]
        np.testing.assert_allclose(lstar, np.broadcast_to(closed, lstar.shape), atol=1e-12)


def test_paper_lstar_derivative_by_central_differences_against_the_turning_helix():
    """central2 and central4 with the grid's step (0.05 m; 1 mm for a single point): errors of order h² and
    h⁴ against the exact (K Λ* - Λ* K)/r, central2 the test's own difference of the printed Λ*; inside a
    plan's span the frame is evaluated at no arc length outside it."""
    s = np.linspace(0.5, 2.0, 31)
    exact = HELIX.dlstar(s)
    assert np.abs(exact).max() > 5e-3
    lstar = HELIX.lstar(s)
    central2 = model.paper_lstar_derivative(HELIX, s, L, "frenet", lstar, "central2")
    err2 = np.abs(central2 - exact).max()
    err4 = np.abs(model.paper_lstar_derivative(HELIX, s, L, "frenet", lstar, "central4") - exact).max()
    assert 1e-6 < err2 < 1e-4 and err4 < 1e-8
    for grid, h in ((s, 0.05), (s[:2], 0.05), (s[:1], 1e-3)):
        own = (HELIX.lstar(grid + h) - HELIX.lstar(grid - h)) / (2 * h)
        np.testing.assert_allclose(model.paper_lstar_derivative(HELIX, grid, L, "frenet", lstar[:len(grid)],
                                                                "central2"), own, atol=1e-11)
    plan = model.FramePlan("frenet", np.zeros(0), np.zeros(0), span=(0.5, 2.0))
    HELIX.seen.clear()
    spanned = model.paper_lstar_derivative(HELIX, s, L, "frenet", lstar, "central4", plan)
    np.testing.assert_allclose(spanned, exact, atol=1e-7)
    nodes = np.concatenate(HELIX.seen)
    assert nodes.min() >= 0.5 and nodes.max() <= 2.0 + 1e-12


def test_paper_lstar_derivative_backward_is_the_papers_difference_between_grid_points():
    """(Λ*_k - Λ*_(k-1)) / (s_k - s_(k-1)): dΛ*/ds at the midpoints to O(Δs²), zero where s does not
    advance, the first row as the second (also on two points); a single point has none."""
    s = np.array([0.0, 0.1, 0.3, 0.3, 0.6])
    lstar = HELIX.lstar(s)
    out = model.paper_lstar_derivative(HELIX, s, L, "frenet", lstar, "backward")
    mid = HELIX.dlstar((s[1:] + s[:-1]) / 2)
    advances = s[1:] > s[:-1]
    np.testing.assert_allclose(out[1:][advances], mid[advances], atol=1e-5)
    assert np.abs(out[1:][~advances]).max() == 0.0
    np.testing.assert_array_equal(out[0], out[1])
    two = model.paper_lstar_derivative(HELIX, s[:2], L, "frenet", lstar[:2], "backward")
    np.testing.assert_allclose(two, [mid[0], mid[0]], atol=1e-5)
    np.testing.assert_array_equal(model.paper_lstar_derivative(HELIX, s[:1], L, "frenet", lstar[:1], "backward"),
                                  np.zeros((1, 3, 3)))


def _paper_kinematics(lam, W, dW, V0, dV0, lstar=None, dlstar=None):
    """V, a, ω, ω̇, Λ̄ in the paper's conventions, from the frame's Ω and Ω' (per unit length)."""
    r = np.array(BODY.r)
    vel, dvel, dW = V0[:, None] * [1.0, 0, 0], dV0[:, None] * [1.0, 0, 0], dW * V0[:, None]
    if lstar is not None:
        rate = dlstar * V0[:, None, None]
        vel, dvel = np.einsum("nij,nj->ni", lstar, vel), np.einsum("nij,nj->ni", rate, vel) + np.einsum(
            "nij,nj->ni", lstar, dvel)
        W, dW = np.einsum("nij,nj->ni", lstar, W), np.einsum("nij,nj->ni", rate, W) + np.einsum(
            "nij,nj->ni", lstar, dW)
        lam = lstar @ lam
    V = vel + np.cross(W, r)
    a = dvel + np.cross(W, vel) + np.cross(dW, r) + np.cross(W, np.cross(W, r))
    return V, a, W, dW, lam


def _check(out, ref):
    for key, value in zip(("V", "a", "omega", "omega_dot", "lam"), ref):
        np.testing.assert_allclose(out[key], value, atol=1e-10, err_msg=key)


@pytest.mark.parametrize("track", [HELIX, CIRCLE, CATENARY], ids=["helix", "circle", "catenary"])
def test_paper_case_kinematics_in_the_papers_conventions(track):
    """Case 1, case 2 with Λ̇* given, and case 2 by default (the backward difference; on the circle Λ* is
    constant, so zero, and s = 0 is a vertical tangent); case 1 with a plan rolling the frame by 0.3 rad
    beyond s = 1 m."""
    s = np.linspace(0.0, 1.5, 7)
    V0, dV0 = 5.0 + 2.0 * s, 1.5 - s
    lam, W, dW = track.frenet(s)
    _check(model.paper_case(track, s, V0, dV0, BODY, "frenet", False), _paper_kinematics(lam, W, dW, V0, dV0))
    given = 0.02 * np.random.default_rng(3).normal(size=(len(s), 3, 3))
    _check(model.paper_case(track, s, V0, dV0, BODY, "frenet", True, dlstar=given),
           _paper_kinematics(lam, W, dW, V0, dV0, track.lstar(s), given))
    if track is CIRCLE:
        still = _paper_kinematics(lam, W, dW, V0, dV0, track.lstar(s), np.zeros((len(s), 3, 3)))
        _check(model.paper_case(track, s, V0, dV0, BODY, "frenet", True), still)
        _check(model.paper_case(track, s, V0, dV0, BODY, "frenet", True, derivative="central4"), still)
    roll = np.where(s > 1.0, 0.3, 0.0)
    c, sn = np.cos(roll)[:, None, None], np.sin(roll)[:, None, None]
    turn = np.zeros((len(s), 3, 3))
    turn[:, 0, 0], turn[:, 1:, 1:] = 1.0, np.block([[c, sn], [-sn, c]])
    plan = model.FramePlan("frenet", np.array([1.0]), np.array([0.3]))
    _check(model.paper_case(track, s, V0, dV0, BODY, "frenet", False, plan=plan),
           _paper_kinematics(turn @ lam, np.einsum("nij,nj->ni", turn, W), np.einsum("nij,nj->ni", turn, dW),
                             V0, dV0))


@pytest.mark.parametrize("derivative", ["backward", "central2"])
def test_paper_case_on_a_straight_track_through_the_plans_rotation_minimising_frame(derivative):
    """No Frenet frame on a line: the plan's rotation-minimising frame (constant, Ω = 0) carries case 1 and
    the paper's Λ* (the chord along t: ψ = 0, ξ = 0, Λ* = E), so both cases give V = V0 e1, a = V̇0 e1."""
    s = np.linspace(0.0, 2.0, 5)
    V0, dV0 = 4.0 + s, 0.5 * s
    plan = model.FramePlan("frenet", np.zeros(0), np.zeros(0), rmf=model.RotationMinimising(LINE, s, 1e-6))
    still = np.zeros((len(s), 3))
    ref = _paper_kinematics(np.broadcast_to(LINE.frame(), (len(s), 3, 3)), still, still, V0, dV0)
    for case2 in (False, True):
        _check(model.paper_case(LINE, s, V0, dV0, BODY, "frenet", case2, derivative, plan=plan), ref)
    with pytest.raises(SymmechError, match="Frenet frame undefined"):
        model.paper_case(LINE, s, V0, dV0, BODY, "frenet", True, derivative)
