"""The elastic trolley's frame along the track (the rigid model's frames, :mod:`symmech.trolley.model`): the
prescribed or driven motion along the midline, the frame's a0, ω, ω̇ at a point of it, and what a compiled run
tabulates of it (:func:`tabulation`: the exact channels in t, or the geometry in s over the arc lengths a
traction run visits, :func:`reach`)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from symmech.core.layout import Field, Layout
from symmech.trolley import model

# ---------------------------------------------------------------- frame along the track

@dataclass(frozen=True)
class Drive:
    """The motion of the frame: track, frame mode ("twist", "frenet"), case 2
    (``local_curvature``) or 1, speed(t) -> (V0 [m/s], dV0 [m/s²]), start s0 [m], the
    case-2 difference order and step [m], and the rigid setup's frame plan. With
    ``traction`` (t, V0) -> P0 [N] instead of a speed, s and V0 are coordinates (from
    ``v_initial`` [m/s]) and the x1 balance of the whole body, F1 = P0, is their equation."""

    track: object
    frame: str
    local_curvature: bool
    speed: object
    s0: float = 0.0
    fd_order: int = 4
    fd_step: float = 1e-3
    plan: object = None  # model.FramePlan keeping the frame continuous (from the trolley setup)
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


def frames(drive: Drive, s, l: float) -> model.Frame:
    s = np.atleast_1d(np.asarray(s, dtype=float))
    return model.track_frame(drive.track, s, l, drive.frame, drive.local_curvature, drive.fd_order, drive.fd_step,
                             drive.plan)


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


def channels(drive: Drive, mdl, t, at=slice(None)) -> np.ndarray:
    """The exact frame channels (k, 12) at the times t[at] (t increasing from the drive's start time, t[0]
    where s = s0) [s] of the model ``mdl`` (its l [m] and g0 [m/s²]): :func:`frame_channels`, vectorised."""
    s = arc_length(drive, t)[at]
    V0, dV0 = (np.broadcast_to(np.asarray(x, float), t.shape)[at] for x in drive.speed(t))
    return frame_channels(frames(drive, s, mdl.l), V0, dV0, mdl.g0)


def geometry(drive: Drive, mdl, s, at=slice(None)) -> np.ndarray:
    """The geometry channels (k, 15) of the frame at the arc lengths s[at] [m] (columns of
    :data:`symmech.trolley.elastic.layout.GEOMETRY`): e, e' + Ω × e, ν, Ω, Ω'."""
    fr = frames(drive, np.asarray(s, float)[at], mdl.l)
    return np.column_stack([fr.e, fr.de + np.cross(fr.W, fr.e), fr.lam[:, :, 1], fr.W, fr.dW])


@dataclass(frozen=True)
class Tabulation:
    """What a compiled run tabulates of the frame (:func:`tabulation`): the nodes that seed its table (the output
    times t [s]; with traction arc lengths over ``span`` [m]), ``evaluate(x, at)`` the exact channels at x[at]
    (:func:`channels`, with traction :func:`geometry`), and at the prescribed speed the exact channels at the
    seed (k, 12) and the exact frame at the outputs with V0 [m/s], dV0 [m/s²] (k,) and those channels."""

    seed: np.ndarray
    evaluate: object
    exact: np.ndarray | None = None
    at_outputs: tuple | None = None
    span: tuple = ()


def tabulation(drive: Drive, mdl, t, s, rigid: model.Body | None = None) -> Tabulation:
    """The :class:`Tabulation` of a run of the model ``mdl`` (its l [m], g0 [m/s²]) on the output times t [s]
    (k,) at the arc lengths s [m] (k,) (:func:`arc_length`) or, with traction (``rigid`` the rigid body of the
    same mass), of its geometry on max(k, 16) arc lengths over the span :func:`reach` finds."""
    if rigid is not None:
        span = reach(drive, rigid, t)
        return Tabulation(np.linspace(*span, max(t.size, 16)), lambda x, at=slice(None): geometry(drive, mdl, x, at),
                          span=span)
    V0, dV0 = (np.broadcast_to(np.asarray(x, float), t.shape).copy() for x in drive.speed(t))
    fr = frames(drive, s, mdl.l)
    ch = frame_channels(fr, V0, dV0, mdl.g0)
    return Tabulation(t, lambda x, at=slice(None): channels(drive, mdl, x, at), ch, (fr, V0, dV0, ch))


REACH_MARGIN = 0.1  # of the rigid run's span of s, on each side of it: the elastic speed differs by ~1e-7
# The state of the rigid body's run that finds the arc lengths a traction run visits (:func:`reach`).
REACH = Layout("ElasticReach", (Field("s", "m", "arc length of O"), Field("speed", "m/s", "speed V0 of O")))
RE_AT = REACH.slots


def reach(drive: Drive, body: model.Body, t) -> tuple[float, float]:
    """The arc lengths [m] a traction run on the output times t [s] visits: those of the rigid ``body`` (the
    whole elastic body's mass, centre and inertia, ``body.rigid_body``) under the same traction (DOP853 at rtol
    1e-6) at the output times and where it turns back between them (its speed through zero), widened by :data:`REACH_MARGIN` of their span (at least 1 mm) and kept within the frame plan's span."""
    from scipy.integrate import solve_ivp

    def rates(time, y):
        fr = frames(drive, y[REACH.slice("s")], body.l)
        alpha, beta = (c[0] for c in model.point_coefficients(fr, body))
        v = y[RE_AT.speed]
        p0 = float(drive.traction(time, v))
        return REACH.pack(s=v, speed=(p0 / body.m - body.g0 * fr.lam[0, 0, 1] - beta[0] * v ** 2) / alpha[0])

    def turn(time, y):  # s is extreme between the outputs where the speed passes through zero
        return y[RE_AT.speed]

    sol = solve_ivp(rates, (t[0], t[-1]), REACH.pack(s=drive.s0, speed=drive.v_initial), method="DOP853", t_eval=t,
                    rtol=1e-6, events=turn)
    s = np.concatenate([sol.y[RE_AT.s], sol.y_events[0].reshape(-1, REACH.size)[:, RE_AT.s]]) if sol.status == 0 else np.array([drive.s0])
    pad = max(REACH_MARGIN * np.ptp(s), 1e-3)
    lo, hi = float(s.min()) - pad, float(s.max()) + pad
    span = getattr(drive.plan, "span", None)
    return (max(lo, span[0]), min(hi, span[1])) if span else (lo, hi)
