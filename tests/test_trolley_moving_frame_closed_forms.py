"""The rigid trolley's moving frames (symmech.trolley.model.moving_frame, plan_frames) against closed forms
(mutation testing of trolley_frames_raw/_plan/_grid).

References written in this file, not read off the code under test:
* Frenet frame: a curve given by its curvature κ(s) and torsion τ(s), its frame (t, N, B) and position
  integrated from the Frenet-Serret equations; then Λ = [t; N; B], Ω = [τ, 0, κ], Ω' = [τ', 0, κ'];
  the clothoid κ = s/A² (τ = 0) in closed form through its inflection at s = 0;
* twist frame (aircraft angles, y up): x1 = t, x3 = t × ŷ / |t × ŷ|, x2 = x3 × x1, then the roll θ1(s)
  about x1 (passive: x2 → cos θ1 x2 + sin θ1 x3); its Ω from 4th-order differences of that closed form,
  Ω̃ = -Λ' Λᵀ, and Ω' from differences of that Ω.
Tracks answer derivatives(s, order) with exactly order + 1 arrays, as symmech's tracks do.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from symmech.core.scene import SymmechError
from symmech.trolley import model

H = 1e-3  # difference step [m]: 4th-order error ~ H⁴ |Λ⁽⁵⁾| ≈ 1e-12


def _d4(f, s, h=H):
    """4th-order central difference of f (array-valued) at s."""
    return (f(s - 2 * h) - 8 * f(s - h) + 8 * f(s + h) - f(s + 2 * h)) / (12 * h)


def _vee_rate(lam_of, s):
    """Ω with Ω̃ = -Λ' Λᵀ (passive frames), Λ' by differences; (n, 3)."""
    w = -_d4(lam_of, s) @ np.swapaxes(lam_of(s), -1, -2)
    return np.stack([w[..., 2, 1], w[..., 0, 2], w[..., 1, 0]], axis=-1)


class FrenetSerret:
    """Curve with κ(s) = k0 + k1 sin s, τ(s) = t0 + t1 cos 2s [1/m] from s = -1 m: (X, t, N, B) integrated by
    DOP853 (rtol 1e-13); X0'…X0'''' written in the Frenet frame."""

    k0, k1, t0, t1 = 0.5, 0.2, 0.3, 0.1

    def kappa(self, s):
        return self.k0 + self.k1 * np.sin(s), self.k1 * np.cos(s), -self.k1 * np.sin(s)

    def tau(self, s):
        return self.t0 + self.t1 * np.cos(2 * s), -2 * self.t1 * np.sin(2 * s)

    def __init__(self, length=8.0):
        def rhs(s, y):
            x, t, n, b = y.reshape(4, 3)
            k, tau = self.kappa(s)[0], self.tau(s)[0]
            return np.concatenate([t, k * n, -k * t + tau * b, -tau * n])

        start = np.concatenate([np.zeros(3), np.eye(3).ravel()])
        self.sol = solve_ivp(rhs, (-1.0, length), start, method="DOP853", rtol=1e-13, atol=1e-13, dense_output=True)

    def frame(self, s):
        y = self.sol.sol(np.asarray(s, float)).T.reshape(-1, 4, 3)
        return y[:, 0], y[:, 1], y[:, 2], y[:, 3]

    def derivatives(self, s, order):
        x, t, n, b = self.frame(s)
        (k, dk, ddk), (tau, dtau) = self.kappa(s), self.tau(s)
        col = lambda a: np.asarray(a)[:, None]  # noqa: E731
        rows = [x, t, col(k) * n, col(-k**2) * t + col(dk) * n + col(k * tau) * b,
                col(-3 * k * dk) * t + col(ddk - k**3 - k * tau**2) * n + col(2 * dk * tau + k * dtau) * b]
        return rows[:order + 1]


def test_frenet_frame_of_a_curve_of_varying_curvature_and_torsion_is_the_integrated_one():
    curve = FrenetSerret()
    s = np.linspace(0.0, 7.5, 11)
    frame = model.moving_frame(curve, s, "frenet")
    _, t, n, b = curve.frame(s)
    np.testing.assert_allclose(frame.lam, np.stack([t, n, b], axis=-2), atol=1e-9)
    (k, dk, _), (tau, dtau) = curve.kappa(s), curve.tau(s)
    zero = np.zeros_like(s)
    np.testing.assert_allclose(frame.W, np.stack([tau, zero, k], -1), atol=1e-9)
    np.testing.assert_allclose(frame.dW, np.stack([dtau, zero, dk], -1), atol=1e-9)
    np.testing.assert_array_equal(frame.e, np.tile([1.0, 0.0, 0.0], (len(s), 1)))
    np.testing.assert_array_equal(frame.de, np.zeros((len(s), 3)))


class Spline(FrenetSerret):
    """The same curve with a speed of 1.02 and a tangential part in X0'' (and X0''') such as a spline's
    near-unit speed leaves."""

    def derivatives(self, s, order):
        rows = super().derivatives(s, order)
        t = rows[1]
        return [rows[0], 1.02 * t] + [r + 0.05 * t for r in rows[2:]]


def test_frenet_frame_ignores_the_tangential_part_of_the_second_derivative():
    s = np.linspace(0.5, 6.0, 7)
    exact = model.moving_frame(FrenetSerret(), s, "frenet")
    spline = model.moving_frame(Spline(), s, "frenet")
    np.testing.assert_allclose(spline.lam, exact.lam, atol=1e-12)
    np.testing.assert_allclose(spline.W[:, 2], exact.W[:, 2], atol=1e-12)  # κ = |X0'' - (X0''·t) t|


A = 1.3  # clothoid parameter [m]: κ = s / A²


class Clothoid:
    """Level clothoid (x-z plane, y up): heading φ = s²/(2A²), X0' = (cos φ, 0, sin φ); X0 itself (Fresnel
    integrals) is used by neither the Frenet frame nor its plan: zeros."""

    def derivatives(self, s, order):
        s = np.asarray(s, float)
        phi, dphi = s**2 / (2 * A**2), s / A**2
        c, n, z = np.cos(phi), np.sin(phi), np.zeros_like(s)
        rows = [np.stack([z, z, z], -1), np.stack([c, z, n], -1), np.stack([-n * dphi, z, c * dphi], -1),
                np.stack([-c * dphi**2 - n / A**2, z, -n * dphi**2 + c / A**2], -1),
                np.stack([n * dphi**3 - 3 * c * dphi / A**2, z, -c * dphi**3 - 3 * n * dphi / A**2], -1)]
        return rows[:order + 1]

    def twist(self, s):
        z = np.zeros(np.shape(s))
        return z, z, z


def test_frenet_frame_is_continued_through_the_clothoid_inflection_by_a_half_turn():
    """Beyond s = 0 the principal normal reverses; the plan rolls the frame there by 180° so the normal
    before, n = (sin φ, 0, -cos φ), goes on: Ω3 = -s/A², Ω3' = -1/A² on both sides."""
    plan = model.plan_frames(Clothoid(), -1.7, 2.31, "frenet", 1e-12)
    event, = plan.events
    # check samples 4.01/200 m apart, bisected down to 1e-9 m or until the middle falls where the Frenet frame
    # is undefined, κ = |s|/A² < 1e-9; the bracket holds the inflection and the event is its middle
    bracket = 4.01 / 200 / 2 ** event["bisections"]
    assert bracket <= 1e-9 or abs(event["s"]) < A**2 * 1e-9
    assert plan.rmf is None and abs(event["s"]) <= bracket / 2 and plan.at == [event["s"]]
    assert event["kind"] == "inflection (principal normal reverses)"
    assert abs(event["roll_deg"]) == pytest.approx(180.0, abs=1e-6) and plan.roll[0] == pytest.approx(
        -np.radians(event["roll_deg"]))
    s = np.array([-1.7, -0.9, -0.2, 0.3, 1.1, 2.3])
    frame = model.moving_frame(Clothoid(), s, "frenet", plan)
    phi = s**2 / (2 * A**2)
    zero, one = np.zeros_like(s), np.ones_like(s)
    t = np.stack([np.cos(phi), zero, np.sin(phi)], -1)
    n = np.stack([np.sin(phi), zero, -np.cos(phi)], -1)
    np.testing.assert_allclose(frame.lam, np.stack([t, n, np.cross(t, n)], axis=-2), atol=1e-12)
    np.testing.assert_allclose(frame.W, np.stack([zero, zero, -s / A**2], -1), atol=1e-12)
    np.testing.assert_allclose(frame.dW, np.stack([zero, zero, -one / A**2], -1), atol=1e-12)
    np.testing.assert_array_equal(frame.e, np.tile([1.0, 0.0, 0.0], (len(s), 1)))
    np.testing.assert_array_equal(frame.de, np.zeros((len(s), 3)))
    assert frame.info == {}
    assert plan.report() == {"mode": "frenet", "samples_checked": plan.checked, "discontinuities_resolved": 1,
                             "events": [event]}


class ArcThenLine:
    """Level arc of radius 2 m (heading φ = s/2) up to s = 1 m, straight beyond (y up)."""

    BEND, END = 0.5, 1.0  # [1/m], [m]

    def derivatives(self, s, order):
        s = np.asarray(s, float)
        phi, bend, z = self.BEND * np.minimum(s, self.END), self.BEND * (s < self.END), np.zeros_like(s)
        c, n = np.cos(phi), np.sin(phi)
        rows = [np.stack([z, z, z], -1), np.stack([c, z, n], -1), np.stack([-n * bend, z, c * bend], -1),
                np.stack([-c * bend**2, z, -n * bend**2], -1), np.stack([n * bend**3, z, -c * bend**3], -1)]
        return rows[:order + 1]


@pytest.mark.filterwarnings("error")  # the refusal is the one message: no numpy warning of 0/0 before it
def test_frenet_frame_on_a_straight_line_is_refused_at_the_first_straight_arc_length():
    with pytest.raises(SymmechError) as err:
        model.moving_frame(ArcThenLine(), np.array([0.2, 0.6, 1.5, 2.0]), "frenet")
    assert str(err.value) == ('Frenet frame undefined: track curvature is zero at s = 1.5 m (straight piece or '
                              'inflection); use frame = "twist"')


def _twist_reference(t, roll):
    """Λ (n, 3, 3) of the twist frame from the unit tangent t (n, 3) and the roll θ1 (n,)."""
    up = np.array([0.0, 1.0, 0.0])
    x3 = np.cross(t, up)
    x3 /= np.linalg.norm(x3, axis=-1, keepdims=True)
    x2 = np.cross(x3, t)
    c, s = np.cos(roll)[:, None], np.sin(roll)[:, None]
    return np.stack([t, c * x2 + s * x3, -s * x2 + c * x3], axis=-2)


ROLL = (0.4, 1.1)  # θ1 = 0.4 sin(1.1 s) [rad]


def _roll(s):
    a, w = ROLL
    return a * np.sin(w * s), a * w * np.cos(w * s), -a * w * w * np.sin(w * s)


class RisingHelix:
    """Helix about the vertical y axis, radius 2 m, rise 0.5 m per radian, with the roll θ1(s)."""

    R, RISE = 2.0, 0.5
    ROOT = np.hypot(R, RISE)

    def unit_tangent(self, s):
        p = np.asarray(s, float) / self.ROOT
        return np.stack([-self.R * np.sin(p), self.RISE + 0 * p, self.R * np.cos(p)], -1) / self.ROOT

    def derivatives(self, s, order):
        p, r = np.asarray(s, float) / self.ROOT, self.ROOT
        c, n, z = np.cos(p), np.sin(p), np.zeros_like(p)
        rows = [np.stack([self.R * c, self.RISE * p, self.R * n], -1), self.unit_tangent(s),
                np.stack([-self.R * c, z, -self.R * n], -1) / r**2, np.stack([self.R * n, z, -self.R * c], -1) / r**3]
        return rows[:order + 1]

    def twist(self, s):
        return _roll(np.asarray(s, float))


class SlopedLine:
    """Straight line rising 0.3 m per metre along (1, 0.3, 0.5)/|.|, with the roll θ1(s)."""

    T = np.array([1.0, 0.3, 0.5]) / np.linalg.norm([1.0, 0.3, 0.5])

    def unit_tangent(self, s):
        return np.broadcast_to(self.T, np.shape(s) + (3,))

    def derivatives(self, s, order):
        s = np.asarray(s, float)
        return [s[:, None] * self.T, self.unit_tangent(s)] + [np.zeros((len(s), 3))] * (order - 1)

    def twist(self, s):
        return _roll(np.asarray(s, float))


class TwistedCurve(FrenetSerret):
    """The curve of varying curvature and torsion (its pitch θ2 and heading θ3 both vary, unlike the helix's),
    with the roll θ1(s); its tangent stays at least 35° from the vertical over s in [-1, 6] m."""

    def unit_tangent(self, s):
        return self.frame(s)[1]

    def twist(self, s):
        return _roll(np.asarray(s, float))


@pytest.mark.parametrize("track", [RisingHelix(), SlopedLine(), TwistedCurve()], ids=["helix", "line", "curve"])
def test_twist_frame_matches_the_aircraft_angle_frame_and_its_differences(track):
    s = np.linspace(-1.0, 6.0, 8)
    frame = model.moving_frame(track, s, "twist")

    def lam_of(x):
        return _twist_reference(track.unit_tangent(x), _roll(x)[0])

    np.testing.assert_allclose(frame.lam, lam_of(s), atol=1e-12)
    np.testing.assert_allclose(frame.W, _vee_rate(lam_of, s), atol=1e-9)
    np.testing.assert_allclose(frame.dW, _d4(lambda x: _vee_rate(lam_of, x), s, 1e-2), atol=1e-7)
    if isinstance(track, SlopedLine):  # Ω = [θ1', 0, 0] exactly on a straight line
        _, d1, d2 = _roll(s)
        np.testing.assert_allclose(frame.W, np.stack([d1, 0 * s, 0 * s], -1), atol=1e-14)
        np.testing.assert_allclose(frame.dW, np.stack([d2, 0 * s, 0 * s], -1), atol=1e-14)
    np.testing.assert_array_equal(frame.e, np.tile([1.0, 0.0, 0.0], (len(s), 1)))
    np.testing.assert_array_equal(frame.de, np.zeros((len(s), 3)))


class VerticalLoop:
    """Loop of radius 8 m in the vertical x-y plane: t = (cos φ, sin φ, 0), φ = s/R, vertical at s = πR/2."""

    R = 8.0

    def derivatives(self, s, order):
        phi, r = np.asarray(s, float) / self.R, self.R
        c, n, z = np.cos(phi), np.sin(phi), np.zeros_like(phi)
        rows = [np.stack([r * n, r - r * c, z], -1), np.stack([c, n, z], -1), np.stack([-n, c, z], -1) / r,
                np.stack([-c, -n, z], -1) / r**2]
        return rows[:order + 1]

    def twist(self, s):
        z = np.zeros(np.shape(s))
        return z, z, z


def test_twist_frame_through_a_vertical_tangent_is_rolled_back_to_stay_upright():
    """The aircraft angles turn x3 over at the vertical tangent (x3 = sign(cos φ) z); the plan rolls the
    frame beyond it by 180°, so x3 = z, x2 = (-sin φ, cos φ, 0) all round, Ω = [0, 0, 1/R], Ω' = 0."""
    loop = VerticalLoop()
    plan = model.plan_frames(loop, 0.0, 20.0, "twist", 0.0)
    event, = plan.events
    assert event["kind"] == "vertical tangent (aircraft angles)" and abs(event["roll_deg"]) == pytest.approx(180.0)
    assert plan.roll == pytest.approx([-np.radians(event["roll_deg"])])
    # bisection of a check interval of 0.1 m, stopped next to the vertical tangent (|t_y| > 1 - 1e-9 within
    # 3.6e-4 m of it): the bracket still holds it and the event is its middle
    assert 4 <= event["bisections"] <= 10
    bracket = 0.1 / 2 ** event["bisections"]
    assert abs(event["s"] - np.pi * loop.R / 2) <= bracket / 2 and plan.at == pytest.approx([event["s"]], abs=0)
    roll = event["roll_deg"]
    assert event["action"] == (f"frame rolls by {roll:.1f} deg within {bracket:.3g} m; the frame beyond is rolled "
                               f"back by {-roll:.1f} deg to stay continuous")
    s = np.array([1.0, 12.0, 12.8, 19.0])
    frame = model.moving_frame(loop, s, "twist", plan)
    phi, z = s / loop.R, np.zeros_like(s)
    lam = np.stack([np.stack([np.cos(phi), np.sin(phi), z], -1), np.stack([-np.sin(phi), np.cos(phi), z], -1),
                    np.tile([0.0, 0.0, 1.0], (len(s), 1))], axis=-2)
    np.testing.assert_allclose(frame.lam, lam, atol=1e-12)
    np.testing.assert_allclose(frame.W, np.tile([0.0, 0.0, 1 / loop.R], (len(s), 1)), atol=1e-12)
    np.testing.assert_allclose(frame.dW, np.zeros((len(s), 3)), atol=1e-12)
    with pytest.raises(SymmechError) as err:
        model.moving_frame(loop, np.array([1.0, np.pi * loop.R / 2]), "twist")
    assert str(err.value) == ('track tangent is vertical at s = 12.5664 m: the aircraft angles θ2, θ3 are singular '
                              'there; use frame = "frenet"')


def test_twist_frame_keeps_upright_through_two_vertical_tangents_by_cumulative_rolls():
    """Beyond the second vertical tangent (s = 3πR/2) the rolls add up to a whole turn: the raw frame."""
    loop = VerticalLoop()
    plan = model.plan_frames(loop, 0.0, 45.0, "twist", 0.0)
    assert plan.at == pytest.approx([np.pi * loop.R / 2, 3 * np.pi * loop.R / 2], abs=2e-3)
    assert np.abs(plan.roll) == pytest.approx([np.pi, np.pi])
    s = np.array([2.0, 12.0, 20.0, 37.0, 38.0, 44.0])
    frame = model.moving_frame(loop, s, "twist", plan)
    phi, z = s / loop.R, np.zeros_like(s)
    np.testing.assert_allclose(frame.lam[:, 1], np.stack([-np.sin(phi), np.cos(phi), z], -1), atol=1e-12)
    np.testing.assert_allclose(frame.lam[:, 2], np.tile([0.0, 0.0, 1.0], (len(s), 1)), atol=1e-12)
    np.testing.assert_allclose(frame.W, np.tile([0.0, 0.0, 1 / loop.R], (len(s), 1)), atol=1e-12)


class Kink:
    """Straight line along ``before`` turning to ``after`` at s = 1 m (no curvature on either side), rolling
    at ``roll_rate`` [rad/m] about it."""

    def __init__(self, before, after, roll_rate):
        self.before, self.after = (np.asarray(d, float) / np.linalg.norm(d) for d in (before, after))
        self.roll_rate = roll_rate

    def derivatives(self, s, order):
        s = np.asarray(s, float)
        t = np.where((s < 1.0)[:, None], self.before, self.after)
        return [s[:, None] * t, t] + [np.zeros_like(t)] * (order - 1)

    def twist(self, s):
        s = np.asarray(s, float)
        return self.roll_rate * s, np.full_like(s, self.roll_rate), np.zeros_like(s)


@pytest.mark.parametrize("after, roll_rate, degrees", [
    ((np.cos(np.radians(30)), 0.0, np.sin(np.radians(30))), 0.0, "30"),
    ((np.cos(np.radians(30)), 0.0, np.sin(np.radians(30))), 1.0, "30"),
    # a cusp: the tangent reverses; with this direction t_a·t_b rounds to -1 - 2e-16
    ((-1.0, -1.0, -3.0), 0.0, "180"),
], ids=["kink", "kink_rolling", "cusp"])
def test_a_kink_in_the_track_is_refused_with_its_angle_and_place(after, roll_rate, degrees):
    """The frame's turn over the last 1e-9 m, 1.5 x 1e-9 m x 1 rad/m at most, is no kink's 30° or 180°."""
    before = (1.0, 0.0, 0.0) if degrees == "30" else (1.0, 1.0, 3.0)
    with pytest.raises(SymmechError, match=rf"tangent jumps by {degrees} deg near s = (1|0\.99999999\d*) m: the "
                                           "track is not smooth there"):
        model.plan_frames(Kink(before, after, roll_rate), 0.0, 2.0, "twist", 0.0)


class HiddenRoll(SlopedLine):
    """Straight line whose roll θ1 turns by 0.5 rad within a few 1e-4 m around s0 = 1.005 m, between check
    samples 0.01 m apart: θ1' = c exp(-((s - s0)/w)²), θ1 = c w √π/2 (1 + erf((s - s0)/w))."""

    S0, WIDTH, TOTAL = 1.005, 1e-4, 0.5

    def twist(self, s):
        from scipy.special import erf

        x = (np.asarray(s, float) - self.S0) / self.WIDTH
        c = self.TOTAL / (self.WIDTH * np.sqrt(np.pi))
        bump = c * np.exp(-x * x)
        return 0.5 * self.TOTAL * (1 + erf(x)), bump, -2 * x / self.WIDTH * bump


def test_a_fast_roll_between_check_samples_is_bisected_and_found_continuous():
    plan = model.plan_frames(HiddenRoll(), 0.0, 2.0, "twist", 0.0)
    event, = plan.events
    # resolved at the first middle: the check samples are 0.01 m apart
    assert event["kind"] == "fast turn" and event["action"] == "resolved by refinement to 0.01 m: no discontinuity"
    assert abs(event["s"] - HiddenRoll.S0) < 4 * HiddenRoll.WIDTH and len(plan.at) == 0 and len(plan.roll) == 0
    s = np.array([0.5, 1.0049, 1.0051, 1.5])
    np.testing.assert_allclose(model.moving_frame(HiddenRoll(), s, "twist", plan).lam,
                               _twist_reference(SlopedLine().unit_tangent(s), HiddenRoll().twist(s)[0]), atol=1e-12)


class LevelLine(SlopedLine):
    """The sloped line without roll: the twist frame is the same matrix everywhere (up to rounding)."""

    def twist(self, s):
        z = np.zeros(np.shape(s))
        return z, z, z


def test_a_straight_sloped_track_has_no_frame_discontinuity():
    """Ω = 0: neighbouring frames equal to rounding must read as no turn (arccos of their trace read ~1e-8 rad
    and reported 200 "vertical tangents" with a roll of 0 deg)."""
    plan = model.plan_frames(LevelLine(), 0.0, 2.0, "twist", 0.0)
    assert plan.events == [] and len(plan.at) == 0 and plan.checked == 201
    frame = model.moving_frame(LevelLine(), np.linspace(0.0, 2.0, 5), "twist")
    turn, predicted = model._turns(frame, np.linspace(0.0, 2.0, 5))
    assert np.all(turn < 1e-15) and np.all(predicted == 0.0)


def test_turns_between_neighbouring_frames_and_their_prediction():
    """On the loop (Ω = [0, 0, 1/R]) neighbours turn by |Δs|/R about x3, also with s running backwards; the
    prediction |Δs| max(|Ω_k|, |Ω_k+1|) on the Frenet-Serret curve, |Ω| = √(τ² + κ²)."""
    loop = VerticalLoop()
    s = np.array([0.0, 0.5, 1.5, 1.7, 0.2, 9.0])
    turn, predicted = model._turns(model.moving_frame(loop, s, "twist"), s)
    np.testing.assert_allclose(turn, np.abs(np.diff(s)) / loop.R, rtol=1e-12)
    np.testing.assert_allclose(predicted, np.abs(np.diff(s)) / loop.R, rtol=1e-12)
    curve = FrenetSerret()
    s = np.array([0.3, 1.9, 1.2, 4.0])
    _, predicted = model._turns(model.moving_frame(curve, s, "frenet"), s)
    rate = np.hypot(curve.kappa(s)[0], curve.tau(s)[0])
    np.testing.assert_allclose(predicted, np.abs(np.diff(s)) * np.maximum(rate[1:], rate[:-1]), rtol=1e-9)


class LevelCircle:
    """Level circle of radius 0.02 m (x-z plane, y up): the twist frame turns at 1/R = 50 rad/m."""

    R = 0.02

    def derivatives(self, s, order):
        phi, r = np.asarray(s, float) / self.R, self.R
        c, n, z = np.cos(phi), np.sin(phi), np.zeros_like(phi)
        rows = [r * np.stack([n, z, 1 - c], -1), np.stack([c, z, n], -1), np.stack([-n, z, c], -1) / r,
                np.stack([-c, z, -n], -1) / r**2]
        return rows[:order + 1]

    def twist(self, s):
        z = np.zeros(np.shape(s))
        return z, z, z


def _refined(s, rate):
    """Each interval of s cut into ceil(Δs max(rate) / 0.2) equal parts, at least one (rate: the closed-form |Ω|
    at s)."""
    r = rate(s)
    parts = np.maximum(1, np.ceil(np.diff(s) * np.maximum(r[1:], r[:-1]) / model.CHECK_TURN).astype(int))
    return np.concatenate([np.linspace(a, b, n + 1)[:-1] for a, b, n in zip(s[:-1], s[1:], parts)] + [s[-1:]])


class UpLoop(VerticalLoop):
    """The loop started at its vertical tangent: t = (0, 1, 0) exactly at s = 0, where the twist frame's Ω is
    infinite."""

    def derivatives(self, s, order):
        return super().derivatives(np.asarray(s, float) + np.pi * self.R / 2, order)


class TightArcThenLine(ArcThenLine):
    """Level arc of radius 2 cm up to s = 0.5 m (heading φ = 50 s), straight beyond: the arc's intervals are
    refined, the line's (Ω = 0 in the twist frame) are kept whole."""

    BEND, END = 50.0, 0.5

    def twist(self, s):
        z = np.zeros(np.shape(s))
        return z, z, z


@pytest.mark.parametrize("track, mode, lo, hi, rate", [
    (LevelCircle(), "twist", 0.0, 2.0, lambda s: np.full_like(s, 50.0)),
    (TightArcThenLine(), "twist", 0.0, 2.0, lambda s: np.where(s < 0.5, 50.0, 0.0)),
    (Clothoid(), "frenet", 0.1, 30.0, lambda s: s / A**2),
    # samples where the frame is undefined (Ω NaN or infinite) count as not turning: at s = 0 (a sample)
    (Clothoid(), "frenet", -25.0, 25.0, lambda s: np.abs(s) / A**2),
    (UpLoop(), "twist", 0.0, 50.0, lambda s: np.where(s == 0, 0.0, 1 / VerticalLoop.R)),
], ids=["circle", "arc_then_line", "clothoid", "inflection_sample", "vertical_sample"])
def test_check_grid_refines_until_the_predicted_turn_is_at_most_0_2_rad(track, mode, lo, hi, rate):
    """One refinement of the 201 even samples suffices (|Ω| is monotone between them)."""
    grid = model._check_grid(track, lo, hi, mode)
    expected = _refined(np.linspace(lo, hi, 201), rate)
    assert len(grid) == len(expected)
    np.testing.assert_allclose(grid, expected, rtol=1e-13, atol=1e-13)
    r = rate(grid)
    assert np.all(np.diff(grid) * np.maximum(r[1:], r[:-1]) <= model.CHECK_TURN * (1 + 1e-9))
    if isinstance(track, LevelCircle):
        assert len(grid) == 601  # 0.01 m x 50 rad/m = 0.5 rad: every interval in three


class RollingLoop(VerticalLoop):
    """The loop with a roll at 50 rad/m before s1 (``before``) or beyond it: θ1 = 50 min(s - s1, 0) or
    50 max(s - s1, 0). Near the vertical tangent (s = 12.566 m) the check samples where the roll runs have
    |Ω| ≈ 50 rad/m, those where it does not 1/R."""

    def __init__(self, s1, before):
        self.s1, self.before = s1, before

    def twist(self, s):
        x = np.asarray(s, float) - self.s1
        on = (x < 0) if self.before else (x > 0)
        return 50.0 * np.where(on, x, 0.0), np.where(on, 50.0, 0.0), np.zeros_like(x)


@pytest.mark.parametrize("s1, before", [(12.499, True), (12.601, False)], ids=["roll_before", "roll_beyond"])
def test_a_vertical_tangent_next_to_a_fast_roll_is_still_found(s1, before):
    """The tangent falls in the check interval [12.5, 12.6] m, whose ends turn at 1/R; its neighbours beyond
    turn at 50 rad/m: predicting the interval's turn from them (1.5 x 0.05 m x 50 rad/m > π) would take the
    half turn of the aircraft angles for a fast continuous turn and leave the frame flipped."""
    plan = model.plan_frames(RollingLoop(s1, before), 12.0, 32.0, "twist", 0.0)
    jumps = [e for e in plan.events if "roll_deg" in e]
    assert len(jumps) == 1 and jumps[0]["kind"] == "vertical tangent (aircraft angles)"
    assert plan.at == pytest.approx([np.pi * VerticalLoop.R / 2], abs=1e-3)


class ShiftedClothoid(Clothoid):
    """Clothoid of parameter 0.1 m with its inflection at s = 1.5 m: κ = 100 (s - 1.5) [1/m]; the Frenet
    frame is undefined only within 1e-11 m of the inflection, so bisection stops at its resolution."""

    S0, A = 1.5, 0.1

    def derivatives(self, s, order):
        u = (np.asarray(s, float) - self.S0) * (A / self.A)  # the clothoid above, heading u²/(2A²) = x²/(2·0.1²)
        return [r * (A / self.A) ** (k - 1) if k > 1 else r for k, r in enumerate(super().derivatives(u, order))]


def test_an_inflection_is_bisected_down_to_1e_9_relative():
    """The bracket ends at most 1e-9 max(1, |s|) = 1.5e-9 m wide, and more than half that."""
    plan = model.plan_frames(ShiftedClothoid(), 1.0, 2.3, "frenet", 1e-12)
    event, = plan.events
    grid = model._check_grid(ShiftedClothoid(), 1.0, 2.3, "frenet")
    k = np.searchsorted(grid, 1.5) - 1
    bracket = (grid[k + 1] - grid[k]) / 2 ** event["bisections"]
    assert 0.75e-9 < bracket <= 1.5e-9 and abs(event["s"] - 1.5) <= bracket / 2
    assert f"within {bracket:.3g} m" in event["action"] and abs(event["roll_deg"]) == pytest.approx(180.0)


class TightHelix:
    """Helix of radius 5 cm and rise 2 cm per radian about the horizontal z axis: its Frenet frame turns at
    √(κ² + τ²) = 1/√(R² + λ²) = 18.57 rad/m; its twist frame faster where the tangent is steep."""

    R, RISE = 0.05, 0.02
    ROOT = np.hypot(R, RISE)

    def derivatives(self, s, order):
        p, r = np.asarray(s, float) / self.ROOT, self.ROOT
        c, n, z = np.cos(p), np.sin(p), np.zeros_like(p)
        rows = [np.stack([self.R * c, self.R * n, self.RISE * p], -1),
                np.stack([-self.R * n, self.R * c, self.RISE + z], -1) / r,
                np.stack([-self.R * c, -self.R * n, z], -1) / r**2, np.stack([self.R * n, -self.R * c, z], -1) / r**3,
                np.stack([self.R * c, self.R * n, z], -1) / r**4]
        return rows[:order + 1]


def test_a_frenet_plan_checks_the_frenet_frame_on_its_own_grid():
    """0.015 m x 18.57 rad/m = 0.28 rad: each of the 200 intervals in two, 401 samples, no event."""
    plan = model.plan_frames(TightHelix(), 0.0, 3.0, "frenet", 1e-6)
    expected = _refined(np.linspace(0.0, 3.0, 201), lambda s: np.full_like(s, 1 / TightHelix.ROOT))
    assert plan.checked == len(expected) == 401 and plan.events == [] and plan.rmf is None
    assert plan.report() == {"mode": "frenet", "samples_checked": 401, "discontinuities_resolved": 0, "events": []}


@pytest.mark.parametrize("above", [False, True], ids=["frenet_kept", "rotation_minimising"])
def test_a_frenet_plan_compares_the_curvature_at_its_check_samples_with_min_curvature(above):
    """On the curve of speed 1.02 with a tangential part in X0'' (κ = 0.5 + 0.2 sin s, its 201 check samples
    0.0375 m apart, none refined): a min_curvature 1e-6 above the samples' least κ gives the rotation-minimising
    frame, started at that sample; 1e-6 below keeps the Frenet frame."""
    grid = np.linspace(0.0, 7.5, 201)
    kappa = FrenetSerret().kappa(grid)[0]
    plan = model.plan_frames(Spline(), 0.0, 7.5, "frenet", kappa.min() + (1e-6 if above else -1e-6))
    assert (plan.rmf is not None) == above and plan.checked == 201
    if above:
        assert plan.events[0]["s"] == grid[np.argmin(kappa)] and plan.events[0]["kind"] == "Frenet frame undefined"


class SmallLoop(VerticalLoop):
    R = 0.05  # a check spacing of 0.8 mm: a shift of 0.01 m / spacing would be 13 m


@pytest.mark.parametrize("loop", [VerticalLoop(), SmallLoop()], ids=["R8", "R0.05"])
def test_a_check_sample_on_the_vertical_tangent_moves_off_it_and_the_tangent_is_found_once(loop):
    """Over [0, πR] the 201 check samples (Δs = πR/200, one per 0.16 rad at most: no refinement) put the 101st
    on the vertical tangent at πR/2, where the twist frame is undefined; it moves off by 1 % of the spacing,
    and the tangent is still the plan's one event, within its bisection bracket."""
    plan = model.plan_frames(loop, 0.0, np.pi * loop.R, "twist", 0.0)
    assert plan.checked == 201
    event, = plan.events
    assert event["kind"] == "vertical tangent (aircraft angles)" and abs(event["roll_deg"]) == pytest.approx(180.0)
    assert abs(event["s"] - np.pi * loop.R / 2) <= 0.5 * np.pi * loop.R / 200 / 2 ** event["bisections"]
