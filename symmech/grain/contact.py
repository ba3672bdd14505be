"""Contact between the ellipsoid and the plane z = 0 of KXYZ.

Accurate mode: the gap is ``h(t) = z_c(t) - |D Q(t)^T e_z|`` (exact support
distance of the ellipsoid, generated ``grain_motion.support_distance``); the
first contact is the first root of ``h`` found by scanning at a step and
refining to ``xtol`` seconds: by Newton's method on ``h`` and its exact rate in the exact
flight (:func:`first_contact`), by Brent's in the integrated reference flight
(:func:`first_root`). A grazing contact (``h`` dips below zero between two scan points) is
caught, in the exact flight, by a bound on the gap's curvature between two samples; in the
integrated flight, by minimising ``h`` around every discrete local minimum of the scan.

Paper mode, eq. (63): the surface of the body is a set of discrete nodes; the
contact test uses the node with the smallest z.
"""
from __future__ import annotations

import math

import numpy as np

from symmech.generated import grain_motion as gm
from symmech.numerics.newton import bracketed_root


def support_distance(axes, Q):
    """Centre height at contact |D n'| (...,) [m]; ``axes`` (..., 3) semi-axes [m], ``Q`` (..., 3, 3)."""
    axes = np.asarray(axes, dtype=float)
    n = np.asarray(Q)[..., 2, :]
    return gm.support_distance(axes[..., 0], axes[..., 1], axes[..., 2], n[..., 0], n[..., 1], n[..., 2])


def contact_offset(axes, Q):
    """Offset R (..., 3) [m] of the lowest point from the centre, in KXYZ."""
    axes = np.asarray(axes, dtype=float)
    Q = np.asarray(Q, dtype=float)
    n = Q[..., 2, :]
    body = gm.contact_offset_body(axes[..., 0], axes[..., 1], axes[..., 2], n[..., 0], n[..., 1], n[..., 2])
    return np.einsum("...ij,...j->...i", Q, body)


def first_root(h, t0: float, t1: float, step: float, xtol: float, window: int = 32):
    """First time in (t0, t1] where ``h`` reaches zero from above, or None; ``h(t0) > 0``.

    ``h`` maps an array of times to an array of values (it is scanned ``window``
    points at a time at spacing ``step``) and a float to a float (Brent refinement
    to ``xtol`` seconds). A start on the plane is the caller's to resolve: it must
    first find a time where the gap has risen above round-off (see ``motion``).
    """
    start = t0
    while True:
        ts = np.unique(np.minimum(start + step * np.arange(window + 1), t1))
        hs = np.asarray(h(ts), dtype=float)
        neg = np.flatnonzero(hs[1:] <= 0.0)
        stop = neg[0] + 1 if neg.size else len(ts)
        inner = np.arange(1, min(stop, len(ts) - 1))
        # a minimum between samples j and j + 1 of equal value (symmetric about their middle) is seen at j
        for j in inner[(hs[inner] < hs[inner - 1]) & (hs[inner] <= hs[inner + 1])]:
            root = _grazing(h, ts[j - 1], ts[j + 1], xtol)
            if root is not None:
                return root
        if neg.size:
            from scipy.optimize import brentq  # here, not at import: a compiled run never loads scipy.optimize

            return brentq(h, ts[stop - 1], ts[stop], xtol=xtol)
        if ts[-1] >= t1:
            return None
        start = ts[-2]  # overlap so a minimum at the window's edge is seen with both neighbours


def first_contact(gap_and_rate, curvature: float, t0: float, t1: float, step: float, xtol: float):
    """First time in (t0, t1] where the gap reaches zero, or None (``t0`` when ``h(t0) <= 0``);
    ``gap_and_rate(t) -> (h, h')`` floats [m, m/s]; ``curvature`` [m/s^2] bounds |h''| over the flight.

    From a sample a, the lower parabola ``h(a) + h'(a) s - curvature s^2 / 2`` proves h > 0 up to its first zero
    (:func:`clear_span`): the next sample is there, or ``step`` on when that is nearer. Between two positive
    samples a piece is cleared when the lower parabola from either end (from b: ``h(b) - h'(b) s - ...``) stays
    positive on it (concave: checked at its two ends), else halved, down to ``xtol``: a contact deeper than
    ``curvature xtol^2 / 8`` is never missed (docs/grain-motion.md). A sign change is refined by Newton's method on
    h and h', safeguarded by the bracket (:mod:`symmech.numerics.newton`), to ``xtol`` seconds.
    """
    root = bracketed_root(lambda t, _: gap_and_rate(t))
    a, (ha, da) = t0, gap_and_rate(t0)
    if ha <= 0.0:
        return t0  # already touching
    while a < t1:
        span = clear_span(ha, da, curvature)
        b = min(a + max(span, step), t1)
        hb, db = gap_and_rate(b)
        if hb <= 0.0:
            return root(a, b, ha, hb, xtol, None)
        pieces = [(a, b, ha, da, hb, db)] if span < b - a else []
        while pieces:
            lo, hi, h_lo, d_lo, h_hi, d_hi = pieces.pop()
            if hi - lo <= xtol or parabolas_clear(h_lo, d_lo, h_hi, d_hi, hi - lo, curvature):
                continue
            mid = 0.5 * (lo + hi)
            h_mid, d_mid = gap_and_rate(mid)
            if h_mid <= 0.0:
                return root(lo, mid, h_lo, h_mid, xtol, None)
            pieces += [(mid, hi, h_mid, d_mid, h_hi, d_hi), (lo, mid, h_lo, d_lo, h_mid, d_mid)]  # earlier first
        a, ha, da = b, hb, db
    return None


def clear_span(h: float, rate: float, curvature: float) -> float:
    """Time [s] over which the lower parabola ``h + rate s - curvature s^2 / 2`` (h > 0) stays positive."""
    if curvature > 0.0:
        return (rate + math.sqrt(rate * rate + 2.0 * curvature * h)) / curvature
    return h / -rate if rate < 0.0 else math.inf


def parabolas_clear(ha: float, da: float, hb: float, db: float, span: float, curvature: float) -> bool:
    """True when h > 0 on a piece of length ``span`` [s] is proven by the lower parabola from either end."""
    drop = 0.5 * curvature * span * span
    return min(ha, ha + da * span - drop) > 0.0 or min(hb, hb - db * span - drop) > 0.0


def _grazing(h, a: float, b: float, xtol: float):
    """Root of ``h`` in (a, b) when its minimum there is negative, else None."""
    from scipy.optimize import brentq, minimize_scalar

    res = minimize_scalar(h, bounds=(a, b), method="bounded", options={"xatol": xtol})
    if res.fun >= 0.0 or h(a) <= 0.0:
        return None
    return brentq(h, a, res.x, xtol=xtol)


def ellipsoid_nodes(axes, count: int) -> np.ndarray:
    """``count`` nodes (count, 3) [m] on the ellipsoid surface in body axes (Fibonacci lattice)."""
    k = np.arange(count) + 0.5
    z = 1.0 - 2.0 * k / count
    rho = np.sqrt(1.0 - z * z)
    ang = np.pi * (1.0 + 5.0**0.5) * k
    unit = np.stack([rho * np.cos(ang), rho * np.sin(ang), z], axis=-1)
    return unit * np.asarray(axes, dtype=float)
