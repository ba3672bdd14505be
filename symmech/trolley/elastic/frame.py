"""The elastic trolley's frame along the track (the rigid model's frames, :class:`symmech.trolley.model.TrackFrames`,
built by the scene and held by the :class:`Drive`; this module evaluates them, it does not make them): the
prescribed or driven motion along the midline, the frame's a0, ω, ω̇ at a point of it, and what a compiled run
tabulates of it (:func:`tabulation`: the exact channels in t, or the geometry in s over the arc lengths a
traction run visits, :func:`reach`, and their spline table, :func:`frame_table`).

**The frame table.** The compiled engine's right-hand side needs, at any stage time t, the load a0 + g0 ν, ω, ω̇
and v0 (body components). They come from Python (``model.moving_frame`` or ``local_curvature_frame`` of any
track, the user's V0(t)) and cannot be called per stage, so :func:`frame_table` tabulates these 12 channels once
per run, vectorised, as a cubic spline in t (scipy's ``CubicSpline``, evaluated in the kernels) within a bound of
the exact values between its nodes (:data:`INTERP_FRACTION` x rtol of the channel group's scale, at least
:data:`INTERP_FLOOR`): the exact frame at the output times (the outputs use it) seeds it, every 2^j-th of those
times its nodes when that meets the bound at the others, else every interval halved until the spline at each
midpoint does; the reached error is returned and reported. Where the exact values carry rounding noise that no
refinement removes (case 2's second differences of Λ*: ~1e-9 of the channel scale on the bundled helix), the
refinement stops once a halving increases an error within :data:`INTERP_NOISE` or two rounds no longer reduce it
4x, provided the error is at most INTERP_NOISE; otherwise the run falls back to the Python engine and says why.
With traction s is a state, so the run tabulates the frame's geometry in s instead (:func:`geometry`, the same
checked spline) over the arc lengths the run visits (:func:`reach`)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from symmech.core.layout import Field, Layout
from symmech.trolley import model
from symmech.trolley.elastic.layout import CH_AT, G_AT

# ---------------------------------------------------------------- frame along the track

@dataclass(frozen=True)
class Drive:
    """The motion of the frame: the frame along the track, ``frames(s)`` -> ``model.Frame`` at the arc lengths s
    (k,) [m] (the rigid model's :class:`symmech.trolley.model.TrackFrames`, built by the scene: its track, frame
    mode, case, difference settings and frame plan), speed(t) -> (V0 [m/s], dV0 [m/s²]) and the start s0 [m].
    With ``traction`` (t, V0) -> P0 [N] instead of a speed, s and V0 are coordinates (from ``v_initial``
    [m/s]) and the x1 balance of the whole body, F1 = P0, is their equation."""

    frames: model.TrackFrames
    speed: object
    s0: float = 0.0
    traction: object = None
    v_initial: float = 0.0


@dataclass(frozen=True)
class FrameState:
    """Track frame at one instant, body-frame components: velocity v0 [m/s] and acceleration
    a0 [m/s²] of O, ω [rad/s], ω̇ [rad/s²], upward unit vector ν."""

    v0: np.ndarray
    a0: np.ndarray
    w: np.ndarray
    dw: np.ndarray
    nu: np.ndarray


def frame_motion(fr: model.Frame, V0, dV0) -> tuple:
    """v0, a0, ω, ω̇ (k, 3) of the frame fr (k rows) at speeds V0 [m/s] and rates dV0 [m/s²] (k,): the
    vectorised :func:`frame_state` without ν."""
    V, dV = V0[:, None], dV0[:, None]
    return V * fr.e, dV * fr.e + V ** 2 * (fr.de + np.cross(fr.W, fr.e)), V * fr.W, dV * fr.W + V ** 2 * fr.dW


def frame_channels(fr: model.Frame, V0, dV0, g0: float) -> np.ndarray:
    """The frame fr's channels (k, 12) at speeds V0 [m/s] and rates dV0 [m/s²] (k,), in the order of the compiled
    engine's layout :data:`symmech.trolley.elastic.layout.CHANNELS`: load a0 + g0 ν, ω, ω̇, v0."""
    v0, a0, w, dw = frame_motion(fr, V0, dV0)
    return np.column_stack([a0 + g0 * fr.lam[:, :, 1], w, dw, v0])


def frame_state(fr: model.Frame, i: int, V0: float, dV0: float) -> FrameState:
    e, W = fr.e[i], fr.W[i]
    return FrameState(V0 * e, dV0 * e + V0 ** 2 * (fr.de[i] + np.cross(W, e)), V0 * W,
                      dV0 * W + V0 ** 2 * fr.dW[i], fr.lam[i, :, 1])


# ---------------------------------------------------------------- what the compiled engine tabulates

GAUSS_LEGENDRE = np.polynomial.legendre.leggauss(8)  # nodes and weights of the arc length per interval


def arc_length(drive: Drive, t) -> np.ndarray:
    """s on the grid t (n,): s0 + ∫ V0 dt, 8-point Gauss-Legendre per step [m]."""
    nodes, weights = GAUSS_LEGENDRE
    mid, half = (t[1:] + t[:-1]) / 2, (t[1:] - t[:-1]) / 2
    x = mid[:, None] + half[:, None] * nodes
    v = np.broadcast_to(np.asarray(drive.speed(x)[0], dtype=float), x.shape)
    return drive.s0 + np.concatenate([[0.0], np.cumsum((v * weights).sum(axis=1) * half)])


def channels(drive: Drive, g0: float, t, at=slice(None)) -> np.ndarray:
    """The exact frame channels (k, 12) at the times t[at] (t increasing from the drive's start time, t[0]
    where s = s0) [s] under the gravity g0 [m/s²]: :func:`frame_channels`, vectorised."""
    s = arc_length(drive, t)[at]
    V0, dV0 = (np.broadcast_to(np.asarray(x, float), t.shape)[at] for x in drive.speed(t))
    return frame_channels(drive.frames(s), V0, dV0, g0)


def geometry(drive: Drive, s, at=slice(None)) -> np.ndarray:
    """The geometry channels (k, 15) of the frame at the arc lengths s[at] [m] (columns of
    :data:`symmech.trolley.elastic.layout.GEOMETRY`): e, e' + Ω × e, ν, Ω, Ω'."""
    fr = drive.frames(np.asarray(s, float)[at])
    return np.column_stack([fr.e, fr.de + np.cross(fr.W, fr.e), fr.lam[:, :, 1], fr.W, fr.dW])



# Interpolation error bound: a fraction of rtol of each channel group's scale, never below rounding.
INTERP_FRACTION = 1e-3
INTERP_FLOOR = 1e-13
# Largest relative error accepted when refinement stops reducing it (noise in the exact frame values).
INTERP_NOISE = 1e-8
MAX_TABLE_NODES = 1 << 20
STALL_ROUNDS = 2


def _scales(ch: np.ndarray) -> np.ndarray:
    """Error scale (12,) of each channel: its group's largest norm; ω̇ against |ω̇| + |ω|² (it enters
    B = skew(ω̇) + skew(ω)²); a group that is zero everywhere is exact (scale 0 accepts 0 error only)."""
    norm = lambda j: float(np.linalg.norm(ch[:, j:j + 3], axis=1).max())  # noqa: E731
    groups = [norm(CH_AT.load), norm(CH_AT.omega), norm(CH_AT.domega) + norm(CH_AT.omega) ** 2, norm(CH_AT.v0)]
    return np.repeat(groups, 3)


@dataclass(frozen=True)
class Table:
    """The spline table of the frame channels: nodes (n,) [s], coefficients (4, n - 1, 12), the largest error
    between its nodes (at the output times it skips or the interval midpoints) relative to the channel scale,
    the bound it met, and whether it stopped on noise."""

    nodes: np.ndarray
    coef: np.ndarray
    error: float
    bound: float
    noise: bool


def _subsampled(t, ch: np.ndarray, k: int, bound: float, scales) -> Table:
    """The spline through every k-th output time t (and the last) and its largest error at the times it skips,
    from the exact channels ch (len(t), c) there."""
    keep = np.zeros(t.size, bool)
    keep[::k] = keep[-1] = True
    spline = CubicSpline(t[keep], ch[keep], axis=0)
    scale = scales(ch)
    worst = np.abs(spline(t[~keep]) - ch[~keep]) / np.where(scale > 0, scale, 1.0)
    return Table(t[keep], np.ascontiguousarray(spline.c), float(worst.max()), bound, False)


def frame_table(t, rtol: float, evaluate, ch=None, scales=_scales) -> Table | None:
    """The frame channels over [t[0], t[-1]] as a cubic spline within max(INTERP_FRACTION rtol, INTERP_FLOOR)
    of the channel scale of the exact values between its nodes. The exact channels at the output times t
    (``ch`` (len(t), 12), computed when None; the outputs need them anyway) seed it: the spline through
    every 2^j-th of them that meets the bound at all the times it skips, j as large as it does from j = 1 on,
    is the table, at no further frame evaluation. Otherwise every interval of t is halved until the spline at
    each interval midpoint meets the bound (halved locally, a spline converges slowly: its end conditions
    reach several intervals in); the spline through every second output time counts as the round before.
    When a halving increased an error already within INTERP_NOISE, or STALL_ROUNDS rounds no longer reduced
    it 4x (noise in the exact values: halving then only interpolates it), the best table so far if its error
    is at most INTERP_NOISE. None when neither is reached within MAX_TABLE_NODES nodes (the caller then runs
    the Python engine). ``evaluate(x, at)`` (k, c) gives the exact channels at x[at]
    (:func:`channels`; :func:`geometry` on s with traction, then with :func:`geometry_scales` as ``scales``)."""
    bound = max(INTERP_FRACTION * rtol, INTERP_FLOOR)
    nodes = np.asarray(t, float)
    ch = evaluate(nodes) if ch is None else ch
    best, since, k = None, 0, 2
    while 2 * k <= nodes.size + 1:  # coarser, while the spline through fewer nodes still meets the bound
        table = _subsampled(nodes, ch, k, bound, scales)
        if table.error > bound:
            break
        best, k = table, 2 * k
    if best is not None:
        return best
    best = table if k == 2 and nodes.size >= 3 else None
    while True:
        every = np.empty(2 * nodes.size - 1)
        every[0::2], every[1::2] = nodes, (nodes[1:] + nodes[:-1]) / 2
        mid = evaluate(every, slice(1, None, 2))
        scale = scales(np.concatenate([ch, mid]))
        spline = CubicSpline(nodes, ch, axis=0)
        worst = (np.abs(spline(every[1::2]) - mid) / np.where(scale > 0, scale, 1.0)).max(axis=1)
        table = Table(nodes, np.ascontiguousarray(spline.c), float(worst.max()), bound, False)
        if table.error <= bound:
            return table
        # a smooth channel loses 16x per halving; rounds that do not gain 4x meet noise (or a kink), and a
        # round that loses once the error is down to noise is noise outright: halving only interpolates it
        worse = best is not None and table.error > best.error and best.error <= INTERP_NOISE
        since = 0 if best is None or table.error < 0.25 * best.error else since + 1
        best = table if best is None or table.error < best.error else best
        if worse or since >= STALL_ROUNDS or 2 * nodes.size > MAX_TABLE_NODES:
            return Table(best.nodes, best.coef, best.error, bound, True) if best.error <= INTERP_NOISE else None
        merged = np.empty((every.size, ch.shape[1]))
        merged[0::2], merged[1::2] = ch, mid
        nodes, ch = every, merged


def geometry_scales(g: np.ndarray) -> np.ndarray:
    """Error scale (15,) of each geometry channel: its group's largest norm; e' + Ω × e against it + |Ω|, Ω'
    against |Ω'| + |Ω|² (the terms they enter a0 and ω̇ beside, per V0²)."""
    norm = lambda j: float(np.linalg.norm(g[:, j:j + 3], axis=1).max())  # noqa: E731
    om = norm(G_AT.om)
    return np.repeat([norm(G_AT.e), norm(G_AT.k) + om, norm(G_AT.nu), om, norm(G_AT.dom) + om ** 2], 3)



@dataclass(frozen=True)
class Tabulation:
    """What a compiled run tabulates of the frame (:func:`tabulation`): the nodes that seed its table (the output
    times t [s]; with traction arc lengths over ``span`` [m]), ``evaluate(x, at)`` the exact channels at x[at]
    (:func:`channels`, with traction :func:`geometry`), the spline ``table`` (:func:`frame_table`; None when it
    cannot be tabulated within its bound), and at the prescribed speed the exact channels at the seed (k, 12) and
    the exact frame at the outputs with V0 [m/s], dV0 [m/s²] (k,) and those channels."""

    seed: np.ndarray
    evaluate: object
    table: Table | None
    exact: np.ndarray | None = None
    at_outputs: tuple | None = None
    span: tuple = ()


def tabulation(drive: Drive, g0: float, t, rtol: float, accelerate=None) -> Tabulation:
    """The :class:`Tabulation` of a run under the gravity g0 [m/s²] at relative tolerance rtol on the output
    times t [s] (k,): its channels in t at the arc lengths :func:`arc_length` gives, the table seeded by the
    exact channels at the outputs; or, with traction (``accelerate`` the rigid body's of the same mass, as
    :func:`reach` takes it), its geometry on max(k, 16) arc lengths over the span :func:`reach` finds, scaled by
    :func:`geometry_scales`."""
    if accelerate is None:
        V0, dV0 = (np.broadcast_to(np.asarray(x, float), t.shape).copy() for x in drive.speed(t))
        fr = drive.frames(arc_length(drive, t))
        ch = frame_channels(fr, V0, dV0, g0)
        evaluate = lambda x, at=slice(None): channels(drive, g0, x, at)  # noqa: E731
        return Tabulation(t, evaluate, frame_table(t, rtol, evaluate, ch), ch, (fr, V0, dV0, ch))
    span = reach(drive, accelerate, t)
    seed = np.linspace(*span, max(t.size, 16))
    evaluate = lambda x, at=slice(None): geometry(drive, x, at)  # noqa: E731
    return Tabulation(seed, evaluate, frame_table(seed, rtol, evaluate, scales=geometry_scales), span=span)


REACH_MARGIN = 0.1  # of the rigid run's span of s, on each side of it: the elastic speed differs by ~1e-7
# The state of the rigid body's run that finds the arc lengths a traction run visits (:func:`reach`).
REACH = Layout("ElasticReach", (Field("s", "m", "arc length of O"), Field("speed", "m/s", "speed V0 of O")))
RE_AT = REACH.slots


def reach(drive: Drive, accelerate, t) -> tuple[float, float]:
    """The arc lengths [m] a traction run on the output times t [s] visits: those of the rigid body (the whole
    elastic body's mass, centre and inertia, ``body.rigid_body``) under the same traction, whose V̇0 [m/s²] at a
    frame, P0 [N] and V0 [m/s] is ``accelerate(frame, P0, V0)`` (``model.traction_acceleration`` of that body),
    (DOP853 at rtol 1e-6) at the output times and where it turns back between them (its speed through zero),
    widened by :data:`REACH_MARGIN` of their span (at least 1 mm) and kept within the frame plan's span."""
    from scipy.integrate import solve_ivp

    def rates(time, y):
        v = y[RE_AT.speed]
        return REACH.pack(s=v, speed=accelerate(drive.frames(y[REACH.slice("s")]), float(drive.traction(time, v)), v)[0])

    def turn(time, y):  # s is extreme between the outputs where the speed passes through zero
        return y[RE_AT.speed]

    sol = solve_ivp(rates, (t[0], t[-1]), REACH.pack(s=drive.s0, speed=drive.v_initial), method="DOP853", t_eval=t,
                    rtol=1e-6, events=turn)
    s = np.concatenate([sol.y[RE_AT.s], sol.y_events[0].reshape(-1, REACH.size)[:, RE_AT.s]]) if sol.status == 0 else np.array([drive.s0])
    pad = max(REACH_MARGIN * np.ptp(s), 1e-3)
    lo, hi = float(s.min()) - pad, float(s.max()) + pad
    span = getattr(drive.frames.plan, "span", None)
    return (max(lo, span[0]), min(hi, span[1])) if span else (lo, hi)
