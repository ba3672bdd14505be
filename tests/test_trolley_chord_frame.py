"""The case-2 body frame of the rigid trolley (symmech.trolley.model: chord_point, chord_rotation,
local_curvature_frame, _stencil, _weights) against independent references (mutation testing).

On a circular helix (radius R, rise λ per radian, r² = R² + λ², X2 up) the front axle's arc
length s_A = s + Δ solves 2 R² (1 - cos(Δ/r)) + (λ Δ / r)² = l² (found here by bisection); the body
frame Λ̄ is the moving frame turned by the smallest rotation taking the tangent t onto the chord
direction c: written here with the twist frame's x3 = t × up / |t × up|, x2 = x3 × t rolled by θ1(s),
and its Ω̄, Ω̄' compared with differences of that frame (ω̃ = -Λ̄' Λ̄ᵀ). Difference weights against
the textbook ones; stencils exact on polynomials of their degree.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from symmech.core.scene import SymmechError
from symmech.trolley import model

R, RISE = 2.0, 0.5
ROOT = np.hypot(R, RISE)
KAPPA, TAU = R / ROOT**2, RISE / ROOT**2
UP = np.array([0.0, 1.0, 0.0])
AXLES = 1.3


class Helix:
    """The helix X = (R cos p, R sin p, λ p), p = s / r, its arc-length derivatives written by hand, and
    an optional roll θ1(s) = a sin(b s)."""

    def __init__(self, roll=(0.0, 0.0)):
        self.roll = roll

    def derivatives(self, s, order):
        p = np.asarray(s, float) / ROOT
        c, n, z = np.cos(p), np.sin(p), np.zeros_like(p)
        rows = [(R * c, R * n, RISE * p)]
        for k in range(1, order + 1):  # d^k/ds^k of (R cos p, R sin p): a quarter turn per order
            rows.append((R * np.cos(p + k * np.pi / 2) / ROOT**k, R * np.sin(p + k * np.pi / 2) / ROOT**k,
                         z + (RISE / ROOT if k == 1 else 0.0)))
        return [np.stack(row, axis=-1) for row in rows]

    def twist(self, s):
        a, b = self.roll
        s = np.asarray(s, float)
        return a * np.sin(b * s), a * b * np.cos(b * s), -a * b * b * np.sin(b * s)


def _front(s, l=AXLES):
    def gap(d):
        return 2 * R**2 * (1 - np.cos(d / ROOT)) + (RISE * d / ROOT) ** 2 - l * l
    return np.array([x + brentq(gap, 0.5 * l, 2 * l, xtol=1e-15) for x in np.atleast_1d(s)])


def _rodrigues(axis, angle):
    k = axis / np.linalg.norm(axis)
    cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * cross + (1 - np.cos(angle)) * cross @ cross


def _body_frame(track, s, mode, extra_roll=lambda x: 0.0):
    """Λ̄ (n, 3, 3): the twist or Frenet frame turned by the smallest rotation taking t onto the chord;
    ``extra_roll(s)`` [rad] added to the twist."""
    out = []
    for x in np.atleast_1d(s):
        x0, t, d2 = (v[0] for v in track.derivatives(np.array([x]), 2))
        if mode == "frenet":
            x2 = d2 / np.linalg.norm(d2)
        else:
            x3 = np.cross(t, UP) / np.linalg.norm(np.cross(t, UP))
            roll = track.twist(x)[0] + extra_roll(x)
            x2 = np.cos(roll) * np.cross(x3, t) + np.sin(roll) * x3
        c = track.derivatives(_front(x), 0)[0][0] - x0
        c /= np.linalg.norm(c)
        turn = _rodrigues(np.cross(t, c), np.arccos(t @ c))
        bar2 = turn @ x2
        out.append(np.stack([c, bar2, np.cross(c, bar2)]))
    return np.array(out)


def _d1(f, s, h):
    """f' by 4th-order central differences."""
    return (f(s - 2 * h) - 8 * f(s - h) + 8 * f(s + h) - f(s + 2 * h)) / (12 * h)


def _omega(lam_of, s, h=1e-3):
    """Ω̄ from ω̃ = -Λ̄' Λ̄ᵀ."""
    w = -_d1(lam_of, s, h) @ np.swapaxes(lam_of(s), -1, -2)
    return np.stack([w[..., 2, 1], w[..., 0, 2], w[..., 1, 0]], -1)


@pytest.mark.parametrize("l", [AXLES, 2 * R])
def test_front_axle_point_is_the_first_at_chord_distance_l_found_by_newton(l):
    """The first root, also for l = 2 R (the chord there 79° off the tangent at A, beyond it the helix
    reaches chord l again after a turn), in a few Newton steps (each evaluates the track once)."""
    track, calls = Helix(), []
    exact = track.derivatives
    track.derivatives = lambda s, order: (calls.append(order), exact(s, order))[1]
    s = np.array([0.0, 0.7, 5.0])
    np.testing.assert_allclose(model.chord_point(track, s, l), _front(s, l), rtol=0, atol=1e-12)
    assert len(calls) <= 10
    assert model.chord_point(Helix(), 0.7, l) == pytest.approx(_front(0.7, l)[0], abs=1e-12)  # a scalar s


def test_front_axle_newton_stops_once_the_chord_is_within_its_tolerance():
    """The iteration stops at the first |f| = | |X0(s_A) - X0(s)|² - l² | ≤ 1e-12 l², the bound included: on the
    straight track X0 = (s, s / 10⁶, 0) with l = 10⁶ m, the first guess s_A = l misses l² by exactly 1 m² =
    1e-12 l² (10¹² + 1 and 1e-12 · 10⁶ · 10⁶ = 1 are exact in binary), so one Newton step is taken and no more;
    it lands on the root l / √(1 + 10⁻¹²) to round-off."""
    class Slope:
        def derivatives(self, s, order):
            s = np.asarray(s, float)
            return [np.stack([s, s / 1e6, 0 * s], -1), np.stack([1 + 0 * s, 1e-6 + 0 * s, 0 * s], -1)][:order + 1]

    track, steps = Slope(), []
    exact = track.derivatives
    track.derivatives = lambda s, order: (steps.append(order), exact(s, order))[1]
    l = 1e6
    assert 1e-12 * l * l == 1.0 and (l * l + 1.0) - l * l == 1.0
    assert model.chord_point(track, np.array([0.0]), l)[0] == pytest.approx(l / np.sqrt(1 + 1e-12), rel=1e-15)
    assert steps.count(1) == 1


def test_no_front_axle_point_when_the_track_curls_back_within_l():
    """A straight run into a level circle of radius R: from s = -3 m the chord 4.5 m reaches the circle,
    from s = 0.5 m on the circle no point is that far (the diameter is 4 m)."""
    class Curl(Helix):
        def derivatives(self, s, order):
            s = np.asarray(s, float)
            th = np.maximum(s, 0.0) / R
            x = np.stack([np.minimum(s, 0.0) + R * np.sin(th), 0 * s, R * (1 - np.cos(th))], -1)
            return [x, np.stack([np.cos(th), 0 * s, np.sin(th)], -1)][:order + 1]
    assert model.chord_point(Curl(), np.array([-3.0]), 4.5) > 0.0
    with pytest.raises(SymmechError, match=r"^no front-axle point A at chord distance l = 4\.5 m from s = 0\.5 m "
                                           r"\(the track curls back within the axle distance\)$"):
        model.chord_point(Curl(), np.array([-3.0, 0.5]), 4.5)


class Hook:
    """A level hook (X2 up): straight along X1 up to s = 0.1 m, a half circle of radius 0.3 m, straight
    back along -X1 at X3 = 0.6 m; arc-length derivatives written by hand, no twist."""

    D, RADIUS = 0.1, 0.3

    def derivatives(self, s, order):
        s = np.asarray(s, float)
        th = np.clip((s - self.D) / self.RADIUS, 0.0, np.pi)
        on_arc = ((s > self.D) & (s < self.D + np.pi * self.RADIUS))[..., None]
        back = np.maximum(s - self.D - np.pi * self.RADIUS, 0.0)
        x = np.stack([np.minimum(s, self.D) + self.RADIUS * np.sin(th) - back, 0 * s,
                      self.RADIUS * (1 - np.cos(th))], -1)
        t = np.stack([np.cos(th), 0 * s, np.sin(th)], -1)
        d2 = np.where(on_arc, np.stack([-np.sin(th), 0 * s, np.cos(th)], -1) / self.RADIUS, 0.0)
        d3 = np.where(on_arc, np.stack([-np.cos(th), 0 * s, -np.sin(th)], -1) / self.RADIUS**2, 0.0)
        return [x, t, d2, d3, 0 * x][:order + 1]

    def twist(self, s):
        z = np.zeros(np.shape(s))
        return z, z, z


def test_chord_pointing_backwards_is_refused_at_the_first_such_arc_length():
    """From s = 0 the front axle (l = 1 m) is reached on the way back, at X1 = -0.8 m: behind O."""
    s = np.array([-3.0, 0.0, 0.05])
    np.testing.assert_allclose(model.chord_point(Hook(), s, 1.0), [-2.0, 0.1 + 0.3 * np.pi + 0.9, 0.1 + 0.3 * np.pi
                                                                     + 0.85], atol=1e-9)
    with pytest.raises(SymmechError, match=r"^the chord O -> A points backwards at s = 0 m$"):
        model.chord_rotation(Hook(), s, 1.0, "twist")
    lstar, _, _ = model.chord_rotation(Hook(), s[:1], 1.0, "twist")
    np.testing.assert_allclose(lstar, np.eye(3)[None], atol=1e-12)


@pytest.mark.parametrize("mode", ["frenet", "twist"])
def test_chord_rotation_turns_x1_onto_the_chord_by_the_smallest_rotation(mode):
    track = Helix((0.4, 1.1))
    s = np.array([0.2, 1.5, 3.0])
    lstar, chord, base = model.chord_rotation(track, s, AXLES, mode)
    x0 = track.derivatives(s, 0)[0]
    np.testing.assert_allclose(chord, track.derivatives(_front(s), 0)[0] - x0, atol=1e-10)
    np.testing.assert_allclose(np.linalg.norm(chord, axis=-1), AXLES, rtol=1e-10)
    np.testing.assert_allclose(lstar @ base.lam, _body_frame(track, s, mode), atol=1e-9)


@pytest.mark.parametrize("mode, roll", [("frenet", (0.0, 0.0)), ("twist", (0.4, 1.1))])
def test_local_curvature_frame_matches_differences_of_the_body_frame(mode, roll):
    track = Helix(roll)
    s = np.array([0.3, 1.9, 4.0])
    frame = model.local_curvature_frame(track, s, AXLES, mode)
    lam = _body_frame(track, s, mode)
    np.testing.assert_allclose(frame.lam, lam, atol=1e-9)
    t = track.derivatives(s, 1)[1]
    np.testing.assert_allclose(frame.e, np.einsum("nij,nj->ni", lam, t), atol=1e-9)

    def e_of(x):
        return np.einsum("nij,nj->ni", _body_frame(track, x, mode), track.derivatives(x, 1)[1])
    np.testing.assert_allclose(frame.de, _d1(e_of, s, 1e-3), atol=1e-7)
    W = _omega(lambda x: _body_frame(track, x, mode), s)
    np.testing.assert_allclose(frame.W, W, atol=1e-7)
    dW = _d1(lambda x: _omega(lambda y: _body_frame(track, y, mode), x), s, 1e-2)
    np.testing.assert_allclose(frame.dW, dW, atol=1e-6)
    c = track.derivatives(_front(s), 0)[0] - track.derivatives(s, 0)[0]
    np.testing.assert_allclose(frame.info["psi"], np.arccos((t * c).sum(-1) / AXLES), atol=1e-9)
    np.testing.assert_allclose(frame.info["chord"], c, atol=1e-10)
    if mode == "frenet":  # on a helix the chord keeps its place in the Frenet frame: Ω̄ = Λ* [τ, 0, κ]
        lstar = lam @ np.swapaxes(frame.info["base"].lam, -1, -2)
        np.testing.assert_allclose(frame.W, lstar @ np.array([TAU, 0.0, KAPPA]), atol=1e-9)
        np.testing.assert_allclose(frame.dW, 0.0, atol=1e-8)
        np.testing.assert_allclose(frame.de, 0.0, atol=1e-9)


def test_local_curvature_frame_at_the_ends_of_the_span_and_with_given_derivatives():
    track = Helix((0.4, 1.1))
    lo, hi = 0.5, 3.0
    plan = model.FramePlan("twist", np.zeros(0), np.zeros(0), span=(lo, hi))
    s = np.array([lo, lo + 2e-3, 1.7, hi - 1e-3, hi])
    frame = model.local_curvature_frame(track, s, AXLES, "twist", fd_order=4, fd_step=1e-2, plan=plan)
    W = _omega(lambda x: _body_frame(track, x, "twist"), s)
    dW = _d1(lambda x: _omega(lambda y: _body_frame(track, y, "twist"), x), s, 1e-2)
    np.testing.assert_allclose(frame.W, W, atol=1e-6)
    np.testing.assert_allclose(frame.dW, dW, atol=1e-4)

    def lstar(x):
        x = np.atleast_1d(x)
        return _body_frame(track, x, "twist") @ np.swapaxes(model.moving_frame(track, x, "twist").lam, -1, -2)

    def derivatives(x, xa):
        np.testing.assert_allclose(xa, _front(x), atol=1e-10)
        h = 1e-3
        d1 = _d1(lstar, x, h)
        d2 = (-lstar(x - 2 * h) + 16 * lstar(x - h) - 30 * lstar(x) + 16 * lstar(x + h) - lstar(x + 2 * h)) \
            / (12 * h * h)
        return d1, d2
    given = model.local_curvature_frame(track, s, AXLES, "twist", derivatives=derivatives, plan=plan)
    np.testing.assert_allclose(given.W, W, atol=1e-7)
    np.testing.assert_allclose(given.dW, dW, atol=1e-6)


def test_local_curvature_frame_follows_the_plans_rolls():
    """A plan that rolls the twist frame by 0.3 rad beyond s = 1 m: the body frame and its rates are
    those of the twist θ1 + 0.3 there."""
    track = Helix((0.4, 1.1))
    plan = model.FramePlan("twist", np.array([1.0]), np.array([0.3]))
    s = np.array([0.3, 1.9, 4.0])
    frame = model.local_curvature_frame(track, s, AXLES, "twist", plan=plan)

    def lam_of(x):
        return _body_frame(track, x, "twist", lambda y: 0.3 * (y > 1.0))
    np.testing.assert_allclose(frame.lam, lam_of(s), atol=1e-9)
    np.testing.assert_allclose(frame.W, _omega(lam_of, s), atol=1e-7)
    np.testing.assert_allclose(frame.dW, _d1(lambda x: _omega(lam_of, x), s, 1e-2), atol=1e-6)


@pytest.mark.parametrize("nodes, k, weights", [
    ([-1, 0, 1], 1, [-0.5, 0.0, 0.5]), ([-1, 0, 1], 2, [1.0, -2.0, 1.0]),
    ([-2, -1, 0, 1, 2], 1, [1 / 12, -2 / 3, 0.0, 2 / 3, -1 / 12]),
    ([-2, -1, 0, 1, 2], 2, [-1 / 12, 4 / 3, -5 / 2, 4 / 3, -1 / 12]),
    ([0, 1, 2], 1, [-1.5, 2.0, -0.5]), ([-2, -1, 0], 1, [0.5, -2.0, 1.5]),
    ([0, 1, 2, 3], 2, [2.0, -5.0, 4.0, -1.0])])
def test_difference_weights_are_the_textbook_ones(nodes, k, weights):
    np.testing.assert_allclose(model._weights(nodes, k), weights, atol=1e-12)


@pytest.mark.parametrize("order", [2, 4])
def test_stencil_is_exact_on_polynomials_and_keeps_its_nodes_in_the_span(order):
    """Entries polynomial of degree ``order``: every stencil (order + 1 central, order + 2 one-sided
    nodes) differentiates them exactly."""
    coef = np.arange(1.0, 10.0).reshape(3, 3)
    seen = []

    def poly(x, k):
        return [x**order - 0.5 * x + 0.25, order * x**(order - 1) - 0.5, order * (order - 1) * x**(order - 2)][k]

    def fun(x):
        seen.append(np.array(x))
        return coef * poly(x, 0)[:, None, None] + np.eye(3) * (x * x)[:, None, None]

    def check(s, d1, d2):
        np.testing.assert_allclose(d1, coef * poly(s, 1)[:, None, None] + np.eye(3) * (2 * s)[:, None, None],
                                   rtol=1e-7, atol=1e-7)
        np.testing.assert_allclose(d2, coef * poly(s, 2)[:, None, None] + 2 * np.eye(3), rtol=1e-4, atol=1e-4)

    lo, hi = -1.0, 2.0
    s = np.array([lo, -0.99, 0.3, 1.995, hi])
    check(s, *model._stencil(fun, s, 0.02, order, (lo, hi)))
    nodes = np.concatenate(seen)
    assert nodes.min() >= lo and nodes.max() <= hi
    # a span shorter than the stencil: the step shrinks to (hi - lo) / (2 (order + 1)), nodes stay inside
    seen.clear()
    short = np.array([0.0, 0.05, 0.1])
    check(short, *model._stencil(fun, short, 1.0, order, (0.0, 0.1)))
    nodes = np.concatenate(seen)
    assert nodes.min() >= 0.0 and nodes.max() <= 0.1 + 1e-15
    # no span: central differences with the step given, exact as well
    seen.clear()
    check(s, *model._stencil(fun, s, 0.1, order))
    np.testing.assert_allclose(np.sort(np.unique(np.round(np.concatenate(seen).reshape(-1, s.size) - s, 12))),
                               0.1 * np.arange(-(order // 2), order // 2 + 1), atol=1e-12)


def _aircraft(th):
    """Λ = R1(θ1) R3(θ3) R2(θ2) (yaw θ2 about X2, pitch θ3, roll θ1), passive elementary rotations."""
    def elementary(axis, angle):
        out = np.eye(3)
        i, j = (axis + 1) % 3, (axis + 2) % 3
        out[i, i], out[i, j], out[j, i], out[j, j] = np.cos(angle), np.sin(angle), -np.sin(angle), np.cos(angle)
        return out
    return elementary(0, th[0]) @ elementary(2, th[2]) @ elementary(1, th[1])


@pytest.mark.parametrize("chord_dir", [(1.0, 0.12, -0.2), (1.0, 0.15, 0.0)])
def test_small_angle_check_solves_the_linearised_chord_condition(chord_dir):
    """(13), (14) written here: Δθ the minimum-norm least-squares solution of Λ̄ ΔR̄ = [l, 0, 0] with
    Λ̄ = Λ + Σ ∂Λ/∂θi Δθi (∂Λ/∂θi by central differences), the defect max|Λ̄ Λ̄ᵀ - E|; the angles are
    read back off Λ (θ2 and θ3 away from zero, θ1 = 0.2 rad)."""
    l = 1.5
    thetas = [(0.2, 0.5, -0.3), (-0.25, 2.6, 0.4)]
    lams = np.array([_aircraft(th) for th in thetas])
    # the chord given in body components (a small turn off x1), passed in fixed components
    local = np.array(chord_dir) / np.linalg.norm(chord_dir) * l
    chords = np.array([lam.T @ local for lam in lams])
    base = model.Frame(lams, *(np.zeros((2, 3)),) * 4)
    defect, dtheta = model.small_angle_check(base, chords, l)
    for k, (th, dx) in enumerate(zip(thetas, chords)):
        h = 1e-6
        partial = [(_aircraft(np.add(th, h * e)) - _aircraft(np.subtract(th, h * e))) / (2 * h) for e in np.eye(3)]
        coef = np.stack([p @ dx for p in partial], -1)
        rhs = np.array([l, 0.0, 0.0]) - _aircraft(th) @ dx
        ref = np.linalg.lstsq(coef, rhs, rcond=1e-6)[0]  # rank 2: a turn about the chord leaves it
        np.testing.assert_allclose(dtheta[k], ref, atol=1e-7)
        bar = _aircraft(th) + sum(p * d for p, d in zip(partial, ref))
        assert defect[k] == pytest.approx(np.abs(bar @ bar.T - np.eye(3)).max(), abs=1e-7)
        assert defect[k] > 1e-3  # a turn of ~0.1 rad: the first-order Λ̄ is visibly not orthogonal


@pytest.mark.parametrize("up", [1.0, -1.0])
def test_small_angle_check_at_a_vertical_tangent_with_rounding(up):
    """x1 vertical: sin θ3 = ±1, which a frame carrying rounding passes by a few ulps (the pitch is then
    still ±π/2, not NaN)."""
    lam = np.array([[[0.0, up, 0.0], [-up, 0.0, 0.0], [0.0, 0.0, 1.0]]])
    chord = lam[0].T @ np.array([1.4, 0.1, -0.05])
    exact, dtheta = model.small_angle_check(model.Frame(lam, *(np.zeros((1, 3)),) * 4), chord[None], 1.5)
    rounded, dtheta_rounded = model.small_angle_check(model.Frame(lam * (1 + 4e-16), *(np.zeros((1, 3)),) * 4),
                                                      chord[None], 1.5)
    assert np.isfinite(exact).all() and np.isfinite(dtheta).all()
    np.testing.assert_allclose(rounded, exact, atol=1e-9)
    np.testing.assert_allclose(dtheta_rounded, dtheta, atol=1e-9)
