"""Kinematics and reactions of the rigid trolley along a track (numpy + generated code).

Arrays have a leading axis of n samples along the track. Frames are passive
(fixed -> body components). The default is the physically consistent model:

* case 1: body frame = moving frame Ox1x2x3 (tangent x1; twist or Frenet);
* case 2: body frame Ox̄1x̄2x̄3 turned by the exact rotation Λ* that puts x̄1 on
  the chord O -> A (local curvature between the axles);
* ω = V0 Ω, ω̇ = V̇0 Ω + V0² Ω' with Ω the angular velocity per unit length,
  including the rate of Λ* itself in case 2.

:func:`paper_case` reproduces the paper's example with its own conventions
(see docs/scenes-trolley.md, "paper conventions").
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from symmech.core import kinematics as kin
from symmech.core.scene import SymmechError
from symmech.generated import trolley_dynamics as dyn
from symmech.generated import trolley_frame as frm
from symmech.generated import trolley_printed as printed

# Tangent closer than this to vertical makes the aircraft angles singular.
GIMBAL_MARGIN = 1e-9
# Frenet frame: curvature below this [1/m] counts as zero.
KAPPA_MIN = 1e-9


@dataclass(frozen=True)
class Body:
    """Rigid body on the trolley: mass [kg], centre of mass r [m] (body frame),
    central inertia [I11, I22, I33, I12, I23, I13] [kg m²], axle distance l [m],
    half gauge ah [m], gravitational acceleration g0 [m/s²] (0 without gravity)."""

    m: float
    r: tuple
    inertia: tuple
    l: float
    ah: float
    g0: float


@dataclass
class Frame:
    """Body frame along s: ``lam`` (n, 3, 3) fixed -> body; ``e``, ``de`` (n, 3) the
    direction of V0 in body components and its s-derivative [1/m]; ``W``, ``dW`` (n, 3)
    angular velocity per unit length [rad/m] and its s-derivative [rad/m²]."""

    lam: np.ndarray
    e: np.ndarray
    de: np.ndarray
    W: np.ndarray
    dW: np.ndarray
    info: dict = field(default_factory=dict)


def _cols(v):
    """Split (..., 3) into three (...) arrays for the generated functions."""
    return [v[..., 0], v[..., 1], v[..., 2]]


def _mv(m, v):
    """Matrix (..., 3, 3) times vector (..., 3)."""
    return np.einsum("...ij,...j->...i", m, v)


def _first_bad(s, bad):
    return float(np.asarray(s)[np.argmax(bad)])


def moving_frame(track, s, mode: str, plan: FramePlan | None = None) -> Frame:
    """Case 1 frame: x1 along the tangent; ``mode`` "twist" (aircraft angles with the
    track's θ1(s)) or "frenet" (x2 along the principal normal). ``plan`` (from
    :func:`plan_frames`) makes the frame continuous: rolls after the discontinuities it
    found, or the rotation-minimising frame where the Frenet frame is undefined."""
    s = np.asarray(s, dtype=float)
    if plan is not None and plan.rmf is not None:
        return plan.rmf.frame(track, s)
    frame, bad, why = _raw_frame(track, s, mode)
    if np.any(bad):
        raise SymmechError(why.format(s=_first_bad(s, bad)))
    return plan.continue_rolls(s, frame) if plan is not None else frame


def _raw_frame(track, s, mode):
    """(Frame, invalid mask, message with {s}) without raising: the pointwise moving frame."""
    X = track.derivatives(s, 4 if mode == "frenet" else 3)
    t = X[1] / np.linalg.norm(X[1], axis=-1, keepdims=True)
    e = np.zeros(s.shape + (3,))
    e[..., 0] = 1.0
    with np.errstate(all="ignore"):
        if mode == "frenet":
            # Remove the tangential part a spline's near-unit speed leaves in X0''.
            normal = X[2] - (X[2] * t).sum(-1, keepdims=True) * t
            cross = np.cross(t, normal)
            kappa = np.linalg.norm(normal, axis=-1)
            n = normal / kappa[..., None]
            tau = (cross * X[3]).sum(-1) / kappa**2
            lam = np.stack([t, n, np.cross(t, n)], axis=-2)
            dkappa = (normal * X[3]).sum(-1) / kappa
            dtau = (cross * X[4]).sum(-1) / kappa**2 - 2 * tau * dkappa / kappa
            zero = np.zeros_like(kappa)
            frame = Frame(lam, e, np.zeros_like(e), np.stack([tau, zero, kappa], axis=-1),
                          np.stack([dtau, zero, dkappa], axis=-1))
            return frame, kappa < KAPPA_MIN, ("Frenet frame undefined: track curvature is zero at s = {s:.6g} m "
                                              "(straight piece or inflection); use frame = \"twist\"")
        bad = np.abs(t[..., 1]) > 1 - GIMBAL_MARGIN
        ang = frm.angles_from_tangent(*_cols(t), *_cols(X[2]), *_cols(X[3]))
        th1, dth1, ddth1 = track.twist(s)
        th = (th1, ang[..., 0], ang[..., 1])
        dth = (dth1, ang[..., 2], ang[..., 3])
        ddth = (ddth1, ang[..., 4], ang[..., 5])
        frame = Frame(frm.Lambda(*th), e, np.zeros_like(e), frm.omega_per_length(*th, *dth),
                      frm.omega_per_length_rate(*th, *dth, *ddth))
    return frame, bad, ("track tangent is vertical at s = {s:.6g} m: the aircraft angles θ2, θ3 are singular "
                        "there; use frame = \"frenet\"")


@dataclass
class FramePlan:
    """How the moving frame is kept continuous over the arc lengths a run visits.

    ``at`` (k,) [m] are the frame discontinuities found, ``roll`` (k,) [rad] the roll
    about x1 added beyond each (cumulative), ``rmf`` a :class:`RotationMinimising`
    frame replacing the Frenet frame, ``events`` what was found and done, ``checked``
    the number of arc lengths at which the frame was compared with its neighbours,
    ``span`` (lo, hi) [m] the rear-axle arc lengths on which difference stencils may
    evaluate the frame (the run's own range: one-sided stencils at its ends).
    """

    mode: str
    at: np.ndarray
    roll: np.ndarray
    rmf: RotationMinimising | None = None
    events: list = field(default_factory=list)
    checked: int = 0
    span: tuple = (-math.inf, math.inf)

    def continue_rolls(self, s, frame: Frame) -> Frame:
        if not len(self.at):
            return frame
        delta = np.concatenate([[0.0], np.cumsum(self.roll)])[np.searchsorted(self.at, s)]
        rot = kin.elementary(0, delta)
        return Frame(rot @ frame.lam, frame.e, frame.de, _mv(rot, frame.W), _mv(rot, frame.dW), frame.info)

    def report(self) -> dict:
        return {"mode": "rotation-minimising" if self.rmf is not None else self.mode,
                "samples_checked": self.checked, "discontinuities_resolved": len(self.at), "events": self.events}


# Frame continuity: the largest predicted turn between check samples [rad], the factor by
# which an observed turn may exceed the predicted one, the bisection resolution
# (relative) and a bound on the check samples.
CHECK_TURN = 0.2
JUMP_FACTOR = 1.5
JUMP_RESOLUTION = 1e-9
MAX_CHECKS = 200_000
RMF_NODES = 50_000  # double-reflection nodes (a Python loop: ~1 s)


def plan_frames(track, lo: float, hi: float, mode: str, min_curvature: float) -> FramePlan:
    """Check the moving frame over s ∈ [lo, hi] [m] and plan how it stays continuous.

    Samples are refined until the frame turns by at most ``CHECK_TURN`` between
    neighbours as predicted by its angular velocity per length; a turn beyond
    ``JUMP_FACTOR`` times the prediction is bisected down to ``JUMP_RESOLUTION`` — a
    jump that persists is a discontinuity (a vertical tangent of the twist frame, an
    inflection of the Frenet frame), resolved by rolling the frame beyond it back onto
    its limit before. With ``mode`` "frenet" and a curvature below ``min_curvature``
    [1/m] anywhere, the Frenet frame is meaningless and the rotation-minimising frame
    is used instead.
    """
    s = _check_grid(track, lo, hi, mode)
    plan = FramePlan(mode, np.zeros(0), np.zeros(0), checked=len(s))
    if mode == "frenet":
        X = track.derivatives(s, 2)
        t = X[1] / np.linalg.norm(X[1], axis=-1, keepdims=True)
        kappa = np.linalg.norm(X[2] - (X[2] * t).sum(-1, keepdims=True) * t, axis=-1)
        if kappa.min() < min_curvature:
            k = int(np.argmin(kappa))
            plan.rmf = RotationMinimising(track, s, min_curvature)
            plan.events.append({"s": float(s[k]), "kind": "Frenet frame undefined",
                                "action": f"curvature {kappa[k]:.3g} 1/m < min_curvature {min_curvature:g} 1/m: "
                                          f"rotation-minimising frame on [{lo:.6g}, {hi:.6g}] m, started from "
                                          f"{plan.rmf.start}"})
            return plan
    # A check sample exactly at a singular point (not a run sample) moves off it a little.
    bad = _raw_frame(track, s, mode)[1]
    s[bad] += 0.01 * np.diff(s).min()
    frame = moving_frame(track, s, mode)
    turn, predicted = _turns(frame, s)
    for k in np.nonzero(turn > JUMP_FACTOR * predicted + 1e-12)[0]:
        event = _bisect_jump(track, mode, s[k], s[k + 1], frame, k)
        plan.events.append(event)
        if "roll_deg" in event:
            plan.at = np.append(plan.at, event["s"])
            plan.roll = np.append(plan.roll, -np.radians(event["roll_deg"]))
    return plan


def _check_grid(track, lo, hi, mode):
    """Arc lengths over [lo, hi] at which the predicted turn between neighbours is small."""
    s = np.linspace(lo, hi, 201)
    while len(s) < MAX_CHECKS:
        frame, _, _ = _raw_frame(track, s, mode)
        rate = np.nan_to_num(np.linalg.norm(frame.W, axis=-1), nan=0.0, posinf=0.0)
        steps = np.ceil(np.diff(s) * np.maximum(rate[1:], rate[:-1]) / CHECK_TURN).astype(int)
        steps = np.clip(steps, 1, 1000)
        if steps.max() <= 1:
            break
        if steps.sum() > MAX_CHECKS:  # refine where needed, within the budget
            steps = np.maximum(1, (steps * (MAX_CHECKS / steps.sum())).astype(int))
        s = np.concatenate([np.linspace(a, b, n + 1)[:-1] for a, b, n in zip(s[:-1], s[1:], steps)] + [s[-1:]])
    return s


def _turns(frame: Frame, s):
    """Turn angle between neighbouring frames [rad] and the one predicted by |Ω| Δs."""
    turn = _angle(frame.lam[1:] @ np.swapaxes(frame.lam[:-1], -1, -2))
    rate = np.linalg.norm(frame.W, axis=-1)
    return turn, np.abs(np.diff(s)) * np.maximum(rate[1:], rate[:-1])


def _bisect_jump(track, mode, a, b, frame, k) -> dict:
    """Locate a suspected frame jump in [a, b] by bisection; the event found."""
    lam_a, lam_b = frame.lam[k], frame.lam[k + 1]
    w_a, w_b = np.linalg.norm(frame.W[k]), np.linalg.norm(frame.W[k + 1])
    steps = 0
    while b - a > JUMP_RESOLUTION * max(1.0, abs(a)):
        m = 0.5 * (a + b)
        fm, bad, _ = _raw_frame(track, np.array([m]), mode)
        if bad[0] or not np.all(np.isfinite(fm.lam)):
            break  # at the singular point itself: the interval is as small as the frame allows
        lam_m, w_m = fm.lam[0], np.linalg.norm(fm.W[0])
        left = _angle(lam_m @ lam_a.T) - JUMP_FACTOR * (m - a) * max(w_a, w_m)
        right = _angle(lam_b @ lam_m.T) - JUMP_FACTOR * (b - m) * max(w_m, w_b)
        if max(left, right) <= 1e-12:
            return {"s": float(m), "kind": "fast turn",
                    "action": f"resolved by refinement to {b - a:.3g} m: no discontinuity"}
        if left >= right:
            b, lam_b, w_b = m, lam_m, w_m
        else:
            a, lam_a, w_a = m, lam_m, w_m
        steps += 1
    jump = lam_b @ lam_a.T
    bend = float(np.arccos(np.clip(jump[0, 0], -1.0, 1.0)))
    if bend > JUMP_FACTOR * (b - a) * max(w_a, w_b) + 1e-6:
        raise SymmechError(f"the track tangent jumps by {np.degrees(bend):.3g} deg near s = {a:.9g} m: "
                           "the track is not smooth there")
    roll = float(np.degrees(np.arctan2(jump[1, 2], jump[1, 1])))
    kind = "vertical tangent (aircraft angles)" if mode == "twist" else "inflection (principal normal reverses)"
    return {"s": float(0.5 * (a + b)), "kind": kind, "roll_deg": roll, "bisections": steps,
            "action": f"frame rolls by {roll:.1f} deg within {b - a:.3g} m; the frame beyond is rolled back by "
                      f"{-roll:.1f} deg to stay continuous"}


def _angle(rot):
    """Rotation angle [rad] of rotation matrices (..., 3, 3) as atan2(sin, cos): arccos of the trace
    would read a product of equal frames' rounding as a turn of ~1e-8 rad (a jump on a straight track)."""
    return np.arctan2(np.linalg.norm(kin.vee(rot), axis=-1), (np.trace(rot, axis1=-2, axis2=-1) - 1) / 2)


class RotationMinimising:
    """Rotation-minimising (parallel-transport) frame: x1 = t, x2 = n carried without roll.

    Built by double reflection (Wang et al. 2008) on nodes over the checked range; at
    any arc length the preceding node's normal is carried by one more double
    reflection. Angular velocity per length Ω = [0, -X0''·x3, X0''·x2] and its
    derivative [0, -X0'''·x3, X0'''·x2] (unit speed, no roll).
    """

    def __init__(self, track, s, min_curvature: float):
        fine = np.linspace(s[0], s[-1], min(max(20 * len(s), 2001), RMF_NODES))
        X = track.derivatives(fine, 2)
        t = X[1] / np.linalg.norm(X[1], axis=-1, keepdims=True)
        kappa = np.linalg.norm(np.cross(t, X[2]), axis=-1)
        if kappa[0] >= min_curvature:
            r = X[2][0] - (X[2][0] @ t[0]) * t[0]
            self.start = f"the principal normal at s = {fine[0]:.6g} m"
        else:
            up = np.array([0.0, 1.0, 0.0]) if abs(t[0, 1]) < 0.9 else np.array([1.0, 0.0, 0.0])
            r = up - (up @ t[0]) * t[0]
            self.start = f"the upward normal at s = {fine[0]:.6g} m"
        normals = np.empty_like(t)
        normals[0] = r / np.linalg.norm(r)
        for j in range(len(fine) - 1):
            normals[j + 1] = _reflect(X[0][j], X[0][j + 1], t[j], t[j + 1], normals[j])
        self.nodes, self.points, self.tangents, self.normals = fine, X[0], t, normals

    def frame(self, track, s) -> Frame:
        X = track.derivatives(s, 3)
        t = X[1] / np.linalg.norm(X[1], axis=-1, keepdims=True)
        j = np.clip(np.searchsorted(self.nodes, s) - 1, 0, len(self.nodes) - 1)
        n = _reflect(self.points[j], X[0], self.tangents[j], t, self.normals[j])
        n = n - (n * t).sum(-1, keepdims=True) * t
        n /= np.linalg.norm(n, axis=-1, keepdims=True)
        b = np.cross(t, n)
        zero = np.zeros(s.shape)
        W = np.stack([zero, -(X[2] * b).sum(-1), (X[2] * n).sum(-1)], axis=-1)
        dW = np.stack([zero, -(X[3] * b).sum(-1), (X[3] * n).sum(-1)], axis=-1)
        e = np.zeros(s.shape + (3,))
        e[..., 0] = 1.0
        return Frame(np.stack([t, n, b], axis=-2), e, np.zeros_like(e), W, dW)


def _reflect(x0, x1, t0, t1, r0):
    """Double reflection: the normal r0 at (x0, t0) carried to (x1, t1); arrays (..., 3)."""
    def mirror(v, *vectors):
        c = (v * v).sum(-1, keepdims=True)
        scale = np.where(c > 0, 2 / np.where(c > 0, c, 1.0), 0.0)
        return [u - scale * (v * u).sum(-1, keepdims=True) * v for u in vectors]

    r_l, t_l = mirror(x1 - x0, r0, t0)
    return mirror(t1 - t_l, r_l)[0]


def chord_point(track, s, l: float) -> np.ndarray:
    """s_A with |X0(s_A) - X0(s)| = l, s_A > s (the front axle on the midline) [m]."""
    s = np.asarray(s, dtype=float)
    x0 = track.derivatives(s, 0)[0]
    sa = s + l  # the chord is never longer than the arc, so the root is at or beyond s + l
    for _ in range(60):
        xa, ta = track.derivatives(sa, 1)
        d = xa - x0
        f = (d * d).sum(-1) - l * l
        slope = 2 * (d * ta).sum(-1)
        ok = slope > 1e-3 * l
        step = np.where(ok, -f / np.where(ok, slope, 1.0), l)
        sa = sa + np.clip(step, -0.5 * l, l)
        if np.all(np.abs(f) <= 1e-12 * l * l) and np.all(ok):
            break
    xa = track.derivatives(sa, 0)[0]
    err = np.abs(np.linalg.norm(xa - x0, axis=-1) - l)
    if not np.all(err <= 1e-9 * l) or not np.all(sa > s):
        bad = ~(err <= 1e-9 * l) | ~(sa > s)
        raise SymmechError(f"no front-axle point A at chord distance l = {l:g} m from s = {_first_bad(s, bad):.6g} m "
                           "(the track curls back within the axle distance)")
    return sa


def chord_rotation(track, s, l: float, mode: str, plan=None):
    """Λ* (n, 3, 3) turning x1 onto the chord, the chord ΔR̄ (n, 3) and the moving frame."""
    base = moving_frame(track, s, mode, plan)
    sa = chord_point(track, s, l)
    chord = track.derivatives(sa, 0)[0] - track.derivatives(s, 0)[0]
    rho = _mv(base.lam, chord) / l
    if np.any(rho[..., 0] <= 0):
        raise SymmechError(f"the chord O -> A points backwards at s = {_first_bad(s, rho[..., 0] <= 0):.6g} m")
    return frm.chord_rotation(*_cols(rho)), chord, base


def _weights(nodes, k: int) -> np.ndarray:
    """Weights of the k-th derivative on the integer ``nodes`` (unit step): exact for
    polynomials of degree < len(nodes)."""
    nodes = np.asarray(nodes, dtype=float)
    rhs = np.zeros(len(nodes))
    rhs[k] = math.factorial(k)
    return np.linalg.solve(np.vander(nodes, increasing=True).T, rhs)


def _stencil(fun, s, h, order: int, span=(-math.inf, math.inf)):
    """First and second s-derivatives of the matrix function ``fun`` (n, 3, 3) by differences
    of ``order`` 2 or 4; ``h`` is a step [m], scalar or of the shape of s.

    Every node lies in ``span`` = (lo, hi) [m] (s itself must): central differences where
    s ± (order/2) h fit, else one-sided ones on order + 2 nodes (truncation error no worse
    than the central one's); h shrinks where the span is too short for them.
    """
    s = np.asarray(s, dtype=float)
    lo, hi = span
    n = order + 2
    h = np.minimum(np.broadcast_to(np.asarray(h, dtype=float), s.shape), (hi - lo) / (2 * (n - 1)))
    half = order // 2
    forward, backward = s - half * h < lo, s + half * h > hi
    layouts = [(mask, nodes) for mask, nodes in ((~forward & ~backward, np.arange(-half, half + 1)),
                                                 (forward, np.arange(n)), (backward & ~forward, np.arange(1 - n, 1)))
               if mask.any()]
    d1 = np.empty(s.shape + (3, 3))
    d2 = np.empty_like(d1)
    if not layouts:
        return d1, d2
    # every node of every layout in one call: fun's cost (a case-2 frame) is mostly per call
    values = fun(np.concatenate([s[mask] + k * h[mask] for mask, nodes in layouts for k in nodes]))
    start = 0
    for mask, nodes in layouts:
        m = np.count_nonzero(mask)
        at = [values[start + i * m:start + (i + 1) * m] for i in range(len(nodes))]
        start += m * len(nodes)
        hm = h[mask][..., None, None]
        d1[mask] = sum(w * v for w, v in zip(_weights(nodes, 1), at)) / hm
        d2[mask] = sum(w * v for w, v in zip(_weights(nodes, 2), at)) / hm**2
    return d1, d2


def local_curvature_frame(track, s, l: float, mode: str, fd_order: int = 4, fd_step: float = 1e-3,
                          derivatives=None, plan=None) -> Frame:
    """Case 2 frame (physically consistent): Λ̄ = Λ* Λ with the exact chord rotation Λ*.

    Λ*' and Λ*'' (s-derivatives) come from differences of order ``fd_order`` with step
    ``fd_step`` [m] (central; one-sided at the ends of ``plan.span``), or from
    ``derivatives(s, s_A) -> (Λ*', Λ*'')`` when given; the body's angular velocity per unit
    length is Ω̄ = Λ* Ω + vee(-Λ*' Λ*ᵀ).
    """
    s = np.asarray(s, dtype=float)
    lstar, chord, base = chord_rotation(track, s, l, mode, plan)
    if derivatives is None:
        d1, d2 = _stencil(lambda x: chord_rotation(track, x, l, mode, plan)[0], s, fd_step, fd_order, _span(plan))
    else:
        d1, d2 = derivatives(s, chord_point(track, s, l))
    lt = np.swapaxes(lstar, -1, -2)
    w_rel = kin.vee(-d1 @ lt)
    dw_rel = kin.vee(-(d2 @ lt + d1 @ np.swapaxes(d1, -1, -2)))
    W = _mv(lstar, base.W) + w_rel
    dW = _mv(d1, base.W) + _mv(lstar, base.dW) + dw_rel
    info = {"psi": np.arccos(np.clip(lstar[..., 0, 0], -1, 1)), "chord": chord, "base": base}
    return Frame(lstar @ base.lam, lstar[..., :, 0], d1[..., :, 0], W, dW, info)


def track_frame(track, s, l: float, mode: str, local_curvature: bool, fd_order: int = 4, fd_step: float = 1e-3,
                plan=None) -> Frame:
    """The frame at the arc lengths s (k,) [m]: case 2 (:func:`local_curvature_frame`, the chord of length l [m],
    its differences of order ``fd_order`` with step ``fd_step`` [m]) when ``local_curvature``, else case 1
    (:func:`moving_frame`)."""
    if not local_curvature:
        return moving_frame(track, s, mode, plan)
    return local_curvature_frame(track, s, l, mode, fd_order, fd_step, plan=plan)


@dataclass(frozen=True)
class TrackFrames:
    """The frame along a track as a function of the arc length, with a run's settings fixed: called with s (k,)
    [m] it is :func:`track_frame` there (case 2 when ``local_curvature``: the chord of length l [m], differences
    of order ``fd_order`` with step ``fd_step`` [m]; ``plan`` the :class:`FramePlan` keeping it continuous). A
    scene builds it once; whatever evaluates the frame along the way (a rigid run, the elastic model's frame
    table) is handed it."""

    track: object
    l: float
    mode: str
    local_curvature: bool
    fd_order: int = 4
    fd_step: float = 1e-3
    plan: FramePlan | None = None

    def __call__(self, s) -> Frame:
        return track_frame(self.track, np.atleast_1d(np.asarray(s, dtype=float)), self.l, self.mode,
                           self.local_curvature, self.fd_order, self.fd_step, self.plan)


def small_angle_check(base: Frame, chord: np.ndarray, l: float) -> np.ndarray:
    """Orthogonality defect max|Λ̄ Λ̄ᵀ - E| of the first-order Λ̄ (13) with Δθ from (14), shape (n,).

    The aircraft angles are read off the moving frame Λ; the defect is O(Δθ²) and
    says when the small-angle correction is out of its range. Returns (defect, Δθ).
    """
    lam = base.lam
    th = (np.arctan2(-lam[..., 2, 1], lam[..., 1, 1]), np.arctan2(-lam[..., 0, 2], lam[..., 0, 0]),
          np.arcsin(np.clip(lam[..., 0, 1], -1, 1)))
    coef = frm.chord_coefficients(*th, *_cols(chord))
    rhs = np.stack([l - coef[..., 0, 0], -coef[..., 1, 0], -coef[..., 2, 0]], axis=-1)
    # (14) is rank-deficient when the chord has no x3 component (l21 = l30 = 0 and the
    # roll about the chord is free): take the minimum-norm least-squares Δθ.
    dtheta = (np.linalg.pinv(coef[..., 1:], rcond=1e-10) @ rhs[..., None])[..., 0]
    bar = frm.Lambda_bar_linear(*th, *_cols(dtheta))
    return np.abs(bar @ np.swapaxes(bar, -1, -2) - np.eye(3)).max(axis=(-1, -2)), dtheta


def point_coefficients(frame: Frame, body: Body):
    """α, β (n, 3) of the centre of mass: V = V0 α, a = V̇0 α + V0² β [1, 1/m]."""
    coef = dyn.point_coefficients(*_cols(frame.e), *_cols(frame.de), *_cols(frame.W), *_cols(frame.dW), *body.r)
    return coef[..., :3], coef[..., 3:]


def traction_acceleration(body: Body, frame: Frame, P0, V0):
    """V̇0 (k,) [m/s²] of the rigid ``body`` driven along the track by the traction P0 [N] at the speed V0 [m/s]
    on the frame at k arc lengths: the x1 balance m a1 = P0 - m g0 ν1 with a1 = α1 V̇0 + β1 V0²
    (:func:`point_coefficients`)."""
    alpha, beta = point_coefficients(frame, body)
    return (P0 / body.m - body.g0 * frame.lam[:, 0, 1] - beta[:, 0] * V0 ** 2) / alpha[:, 0]


def body_motion(frame: Frame, V0, dV0, body: Body) -> dict:
    """V, a (n, 3) of the centre of mass, ω, ω̇, reactions P (n, 6) and overloads (n, 3) [g].

    V0 [m/s] and dV0 [m/s²] have shape (n,).
    """
    V0, dV0 = np.asarray(V0, dtype=float), np.asarray(dV0, dtype=float)
    alpha, beta = point_coefficients(frame, body)
    V = V0[..., None] * alpha
    a = dV0[..., None] * alpha + (V0**2)[..., None] * beta
    w = V0[..., None] * frame.W
    dw = dV0[..., None] * frame.W + (V0**2)[..., None] * frame.dW
    return _dynamics(V, a, w, dw, frame.lam, body)


def _dynamics(V, a, w, dw, lam, body: Body) -> dict:
    nu = lam[..., :, 1]
    common = (body.m, *body.r, *body.inertia, *_cols(a), *_cols(w), *_cols(dw))
    if body.g0 > 0:
        P = dyn.reactions(*common, *_cols(nu), body.g0, body.l, body.ah)
    else:
        P = dyn.reactions_no_gravity(*common, body.l, body.ah)
    g_ref = body.g0 if body.g0 > 0 else 9.80665
    overload = (a + body.g0 * nu) / g_ref
    return {"V": V, "a": a, "omega": w, "omega_dot": dw, "P": P, "overload": overload, "lam": lam}


def paper_lstar(track, s, l: float, mode: str, plan=None):
    """Λ* of the helix example as the paper builds it: ξ = t × ρ in fixed-frame
    components, not normalized (|ξ| = sin Ψ), in the printed Rodrigues matrix."""
    base = moving_frame(track, s, mode, plan)
    sa = chord_point(track, s, l)
    rho = (track.derivatives(sa, 0)[0] - track.derivatives(s, 0)[0]) / l
    t = base.lam[..., 0, :]
    psi = np.arccos(np.clip((t * rho).sum(-1), -1, 1))
    xi = np.cross(t, rho)
    return printed.rodrigues(psi, *_cols(xi)), base


def paper_case(track, s, V0, dV0, body: Body, mode: str, local_curvature: bool,
               derivative: str = "backward", dlstar=None, plan=None) -> dict:
    """The paper's example computation (Tables 1, 2), on a time grid (s, V0, dV0 of shape (n,)).

    Conventions (physically inconsistent ones marked *):
    * ω = Ω, the angular velocity per unit length, used as rad/s (no factor V0), and
      ω̇ = Ω' V0 (zero on the helix);
    * a0 = V̇0 + ω × V0 (so the normal acceleration is κ V0, not κ V0²);
    * case 2: Λ* from :func:`paper_lstar`; V0* = Λ* V0, ω* = Λ* ω,
      V̇0* = Λ̇* V0 + Λ* V̇0, ω̇* = Λ̇* ω + Λ* ω̇ with Λ̇* = dΛ*/ds |V0|;
    * dΛ*/ds by a backward difference between successive grid points (``derivative``
      = "backward"), or "central2"/"central4" with step |V0| Δt, or given as ``dlstar``.
    """
    base = moving_frame(track, s, mode, plan)
    V0, dV0 = np.asarray(V0, dtype=float), np.asarray(dV0, dtype=float)
    W, dW = base.W, base.dW * V0[..., None]
    vel = np.zeros(V0.shape + (3,))
    vel[..., 0] = V0
    dvel = np.zeros_like(vel)
    dvel[..., 0] = dV0
    lam = base.lam
    if local_curvature:
        lstar, _ = paper_lstar(track, s, body.l, mode, plan)
        if dlstar is None:
            dlstar = paper_lstar_derivative(track, s, body.l, mode, lstar, derivative, plan)
        rate = dlstar * V0[..., None, None]
        vel, dvel = _mv(lstar, vel), _mv(rate, vel) + _mv(lstar, dvel)
        W, dW = _mv(lstar, W), _mv(rate, W) + _mv(lstar, dW)
        lam = lstar @ lam
    r = np.asarray(body.r, dtype=float)
    V = vel + np.cross(W, r)
    a = dvel + np.cross(W, vel) + np.cross(dW, r) + np.cross(W, np.cross(W, r))
    return _dynamics(V, a, W, dW, lam, body)


def paper_lstar_derivative(track, s, l, mode, lstar, method: str, plan=None):
    """dΛ*/ds on the grid s (n,) by ``method``: "backward" (the paper's), "central2", "central4"."""
    fun = lambda x: paper_lstar(track, x, l, mode, plan)[0]  # noqa: E731
    ds = np.diff(s)
    if method == "backward":
        out = np.empty_like(lstar)
        out[1:] = (lstar[1:] - lstar[:-1]) / np.where(ds > 0, ds, 1.0)[:, None, None]
        out[1:][ds <= 0] = 0.0
        out[0] = out[1] if len(s) > 1 else 0.0
        return out
    h = np.concatenate([ds[:1], ds]) if len(s) > 1 else np.array([1e-3])
    h = np.maximum(h, 1e-6 * l)
    order = {"central2": 2, "central4": 4}[method]
    return _stencil(fun, s, h, order, _span(plan))[0]


def _span(plan) -> tuple:
    return plan.span if plan is not None else (-math.inf, math.inf)
