"""The elastic trolley compiled: the assembly of :class:`symmech.trolley.elastic.system.System` in numba
(:mod:`symmech.trolley.elastic.kernels`), integrated by the toolkit's Radau IIA with the analytic Jacobian;
this module drives it (:func:`simulate`, the same contract and outputs as the Python engine's) and builds
numba's cache once (:func:`warm`).

**The frame along the track.** The right-hand side needs, at any stage time t, the load a0 + g0 ν, ω,
ω̇ and v0 (body components). They come from Python (``model.moving_frame`` or ``local_curvature_frame``
of any track, the user's V0(t)) and cannot be called per stage, so :func:`frame_table` tabulates these 12
channels once per run, vectorised, as a cubic spline in t (scipy's ``CubicSpline``, evaluated in the
kernels) within a bound of the exact values between its nodes (:data:`INTERP_FRACTION` x rtol of the
channel group's scale, at least :data:`INTERP_FLOOR`): the exact frame at the output times (the outputs use
it) seeds it, every 2^j-th of those times its nodes when that meets the bound at the others, else every
interval halved until the spline at each midpoint does; the reached error is returned and reported. Where
the exact values carry rounding noise that no refinement removes (case 2's second differences of Λ*: ~1e-9
of the channel scale on the bundled helix), the refinement stops once a halving increases an error within
:data:`INTERP_NOISE` or two rounds no longer reduce it 4x, provided the error is at most INTERP_NOISE;
otherwise the run falls back to the Python engine and says why (:func:`simulate`).

**Steps.** The Python engine bounds its steps by the output spacing; this one does not: the outputs come
from Radau's collocation polynomial (scipy's dense output), whose error on the bundled scene stays within
the tolerance (benchmarks/README.md), so a fine output grid costs output rows, not steps.

**Traction.** s is a state, so the run tabulates the frame's geometry in s instead
(``frame.geometry``, the same checked spline) over the arc lengths the run visits (``frame.reach``), and calls
the user's P0(t, V0) back per stage (:data:`symmech.trolley.elastic.kernels.TRACTIONS`).
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from symmech.numerics import build
from symmech.trolley.elastic import frame as el_frame, simulate as el_sim
from symmech.trolley.elastic.layout import CH_AT, G_AT, LAYOUTS, MODEL, N_CHANNELS, N_GEOMETRY, state as state_layout  # noqa: F401 (LAYOUTS: the engine protocol reads it here)

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
    (``frame.channels``; ``frame.geometry`` on s with traction, then with :func:`geometry_scales` as
    ``scales``)."""
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


def simulate(system, drive, t, rtol: float = 1e-8, atol_q: float = 1e-12, dq0=None, dqd0=None,
             reason: str = "") -> dict:
    """:func:`symmech.trolley.elastic.simulate.simulate` by Radau on the compiled assembly (the same state,
    tolerances and outputs; the steps are not bound by the output spacing: the outputs come from the
    collocation polynomial, within the tolerance of the steps, benchmarks/README.md). What the run reads is
    made in one pass (``simulate.compiled_inputs``: the start, the model's record, the exact frame); ``engine``
    / ``engine_reason`` name what ran: this engine and ``reason`` (why the caller chose it), or the Python engine
    and why when the frame cannot be tabulated within its bound (:func:`frame_table`) or, with traction, the
    run leaves the table; ``frame_table_nodes`` and ``frame_interpolation_error`` (relative to the channel
    scales) what the table reached."""
    t = np.asarray(t, dtype=float)
    inputs = el_sim.compiled_inputs(system, drive, t, atol_q, dq0, dqd0)
    table = tabulate(inputs, float(rtol))
    if drive.traction is not None:
        solved, why = _traction_run(drive, t, float(rtol), inputs, table)
    else:
        solved, why = _prescribed_run(drive, t, float(rtol), inputs, table)
    if solved is None:
        return el_sim.simulate(system, drive, t, "Radau", rtol, atol_q, dq0, dqd0, fallback=why)
    (s, V0, dV0, Y, fr, steps, nfev) = solved
    report = {"nfev": nfev, "njev": -1, "steps": steps, "engine": "compiled", "engine_reason": reason,
              "frame_table_nodes": table.nodes.size, "frame_interpolation_error": table.error}
    return el_sim.outputs(system, drive, t, s, V0, dV0, Y, rows=row_terms, frame=fr, run=report)


def _prescribed_run(drive, t, rtol: float, inputs, table) -> tuple[tuple | None, str]:
    """The compiled run at the prescribed speed on the frame ``table`` (:func:`tabulate`): ((s, V0, dV0 (n,), the
    states Y (n, layout.state), the frame at the outputs, steps, evaluations), "") or (None, why it cannot run)."""
    from symmech.trolley.elastic import kernels as ek  # numba: imported by a run, not by choosing the engine or its estimate
    if table is None:
        return None, (f"the frame along the track could not be tabulated within {INTERP_NOISE:g} of its scale on "
                      f"{MAX_TABLE_NODES} nodes (a non-smooth track or speed): the Python engine evaluates it exactly")
    start, (fr, V0, dV0, _) = inputs.start, inputs.frame.at_outputs
    Y, steps, nfev, status = ek.solve(inputs.record, (table.nodes, table.coef), start.y0, t, rtol, start.atol)
    _check(status, Y, t)
    return (start.line.s_nodes, V0, dV0, Y, fr, steps, nfev), ""


def row_terms(system, fr, V0, dV0, Y, height) -> dict:
    """:func:`symmech.trolley.elastic.simulate.row_terms` by ``kernels.rows`` on the model's record (the
    potential Π per row in Python)."""
    from symmech.trolley.elastic import kernels as ek  # numba: imported by a run, not by choosing the engine or its estimate
    chs = el_frame.frame_channels(fr, V0, dV0, system.mdl.g0)
    nu = np.ascontiguousarray(fr.lam[:, :, 1])
    keys = ("qdd", "F", "M", "rr", "v", "acc", "h", "E")
    terms = ek.rows(system.record, chs, nu, np.ascontiguousarray(height, float), np.ascontiguousarray(Y))
    res = dict(zip(keys, terms))
    pi = system.potential(Y[:, state_layout(system.N, False).slice("q")])
    res["h"] += pi
    res["E"] += pi
    return res


# --------------------------------------------------------------------------- traction

def geometry_scales(g: np.ndarray) -> np.ndarray:
    """Error scale (15,) of each geometry channel: its group's largest norm; e' + Ω × e against it + |Ω|, Ω'
    against |Ω'| + |Ω|² (the terms they enter a0 and ω̇ beside, per V0²)."""
    norm = lambda j: float(np.linalg.norm(g[:, j:j + 3], axis=1).max())  # noqa: E731
    om = norm(G_AT.om)
    return np.repeat([norm(G_AT.e), norm(G_AT.k) + om, norm(G_AT.nu), om, norm(G_AT.dom) + om ** 2], 3)


def tabulate(inputs, rtol: float) -> Table | None:
    """The frame table a compiled run on ``inputs`` (``simulate.compiled_inputs``) reads, and its export: the frame
    channels in t (:func:`frame_table` seeded by the exact channels at the outputs) or, with traction, the
    geometry channels in s over ``inputs.frame.span`` (scaled by :func:`geometry_scales`); None when it cannot be
    tabulated within its bound."""
    frame = inputs.frame
    if frame.span:
        return frame_table(frame.seed, rtol, frame.evaluate, scales=geometry_scales)
    return frame_table(frame.seed, rtol, frame.evaluate, frame.exact)


_KEYS = itertools.count()


def _traction_run(drive, t, rtol: float, inputs, table) -> tuple[tuple | None, str]:
    """The compiled run with traction: y = [q, q̇, E_d, W, s, V0] (layout.TRACTION_STATE), the frame's geometry
    ``table`` tabulated in s over the span ``frame.reach`` found, P0(t, V0) called back in Python per stage; Radau
    with the analytic Jacobian (``kernels._jac_traction``). ((s, V0, dV0, Y as :func:`_prescribed_run`'s, no frame,
    steps, evaluations), "") or (None, why it cannot run: the geometry cannot be tabulated, or the run leaves the
    table)."""
    from symmech.trolley.elastic import kernels as ek  # numba: imported by a run, not by choosing the engine or its estimate
    why = (f"the frame along the track could not be tabulated in s within {INTERP_NOISE:g} of its scale, or the "
           f"run left the tabulated s in [{inputs.frame.span[0]:.6g}, {inputs.frame.span[1]:.6g}] m: the Python engine "
           "evaluates it exactly")
    if table is None:
        return None, why
    start = inputs.start
    step = float(np.min(np.diff(t))) if len(t) > 1 else np.inf
    key = next(_KEYS)  # one per run: concurrent runs (threads) each find their own P0
    ek.TRACTIONS[key] = drive.traction
    try:
        Y, dV0, steps, nfev, status = ek.solve_traction(inputs.record, (table.nodes, table.coef), key, start.y0, t,
                                                         rtol, start.atol, step)
    finally:
        del ek.TRACTIONS[key]
    _check(status, Y, t)
    s, speed = Y[:, start.state.offset("s")], Y[:, start.state.offset("speed")]
    visited = np.concatenate([s, turning_points(t, s, speed)])
    if visited.min() < table.nodes[0] or visited.max() > table.nodes[-1]:
        return None, why
    return (s, speed, dV0, Y, None, steps, nfev), ""


def turning_points(t, s, v):
    """Where the run turns back between two outputs (its speed v [m/s] changes sign from t_k to t_k+1 [s]), the
    arc length [m] at the turn as the speed's linear interpolation puts it (exact under a constant acceleration):
    s_k + v_k tau / 2 with tau = h v_k / (v_k - v_k+1). Shape (number of turns,)."""
    k = np.flatnonzero(v[:-1] * v[1:] < 0)
    tau = np.diff(t)[k] * v[k] / (v[k] - v[k + 1])
    return s[k] + v[k] * tau / 2


def _check(status, Y, t) -> None:
    """SymmechError when the compiled solve failed or reached no finite state."""
    from symmech.numerics import ode  # numba: imported by a run, not by choosing the engine or its estimate
    if status != ode.SUCCESS or not np.all(np.isfinite(Y)):
        last = t[np.flatnonzero(np.isfinite(Y).all(axis=1))[-1]]
        why = ode.STEP_TOO_SMALL_TEXT if status == ode.STEP_TOO_SMALL else "no finite state"
        raise el_sim.integration_failed(last, f"compiled Radau: {why}")


# --------------------------------------------------------------------------- building the cache once

# first compile: 119 s of CPU (62 s before the traction entry), 412 s wall at load 9.5 on 2 cores
# (benchmarks/README.md)
COLD_COMPILE_SECONDS = 130.0


def _entry_signatures() -> dict:
    """The cached entries and the argument types :func:`simulate` and :func:`row_terms` call them with: the
    model record's from its layout (:data:`symmech.trolley.elastic.layout.MODEL`), the rest from small arrays."""
    # numba: imported by a run, not by choosing the engine or its estimate
    import numba
    from symmech.trolley.elastic import kernels as ek
    mdl = MODEL.numba_type()
    tab = (np.zeros(2), np.zeros((4, 1, N_CHANNELS)))
    solve = (tab, np.zeros(4), np.zeros(2), 1e-8, np.zeros(4))
    rows = (np.zeros((2, N_CHANNELS)), np.zeros((2, 3)), np.zeros(2), np.zeros((2, 4)))
    traction = ((np.zeros(2), np.zeros((4, 1, N_GEOMETRY))), 1, np.zeros(6), np.zeros(2), 1e-8, np.zeros(6), 1.0)
    return {entry: (mdl, *(numba.typeof(a) for a in args))
            for entry, args in ((ek.solve, solve), (ek.rows, rows), (ek.solve_traction, traction))}


ENGINE = build.Engine("elastic", "symmech.trolley.elastic.kernels", _entry_signatures, COLD_COMPILE_SECONDS)
