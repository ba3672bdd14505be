"""The elastic trolley compiled: the assembly of :class:`symmech.trolley.elastic.system.System` in numba
(:mod:`symmech.trolley.elastic.kernels`), integrated by the toolkit's Radau IIA with the analytic Jacobian;
this module drives it (:func:`simulate`, the same contract and outputs as the Python engine's; :class:`Run`, its
inputs by name, and ``RUNNER`` for the engine protocol) and builds numba's cache once (``ENGINE``).

**The way in.** A run reads what :func:`compiled_inputs` makes in one pass: the frame along the track first (its
arc lengths at the outputs, ``frame.arc_length``, and its spline table, ``frame.tabulation``: in t at a prescribed
speed, in s over the span a traction run visits; the table's bound and its refinement in
:mod:`symmech.trolley.elastic.frame`), then the start both engines share (``simulate.prepare``, on the timeline of
those arc lengths) and the model's record (``System.record``, packed once per system); :func:`simulate` hands them
to the kernels' solve and makes the outputs once, on the way out.

**Steps.** The Python engine bounds its steps by the output spacing; this one does not: the outputs come
from Radau's collocation polynomial (scipy's dense output), whose error on the bundled scene stays within
the tolerance (benchmarks/README.md), so a fine output grid costs output rows, not steps.

**Traction.** s is a state, so the kernels read the frame's geometry table in s, and call the user's P0(t, V0)
back per stage (:data:`symmech.trolley.elastic.kernels.TRACTIONS`).
"""
from __future__ import annotations

import itertools
from contextlib import contextmanager
from dataclasses import dataclass
from functools import partial

import numpy as np

from symmech.numerics import build
from symmech.trolley import model
from symmech.trolley.elastic import frame as el_frame, simulate as el_sim
from symmech.trolley.elastic.layout import LAYOUTS, MODEL, state as state_layout  # noqa: F401 (LAYOUTS: the engine protocol reads it here)


@dataclass(frozen=True)
class Run:
    """A run of this engine, its inputs by name (the engine protocol's run, ``engines.Engine.run``): those of
    :func:`simulate`."""

    system: object  # symmech.trolley.elastic.system.System
    drive: object  # symmech.trolley.elastic.frame.Drive
    t: object  # output times (n,) [s]
    rtol: float = 1e-8
    atol_q: float = 1e-12
    dq0: object = None
    dqd0: object = None
    reason: str = ""


class Runner:
    """This engine's side of the protocol's run (:class:`symmech.core.engines.Runner`)."""

    def simulate(self, inputs: Run) -> dict:
        """:func:`simulate` of the inputs."""
        return simulate(inputs.system, inputs.drive, inputs.t, inputs.rtol, inputs.atol_q, inputs.dq0, inputs.dqd0,
                        inputs.reason)


RUNNER = Runner()


def simulate(system, drive, t, rtol: float = 1e-8, atol_q: float = 1e-12, dq0=None, dqd0=None,
             reason: str = "") -> dict:
    """:func:`symmech.trolley.elastic.simulate.simulate` by Radau on the compiled assembly (the same state,
    tolerances and outputs; the steps are not bound by the output spacing: the outputs come from the
    collocation polynomial, within the tolerance of the steps, benchmarks/README.md). What the run reads is
    made in one pass (:func:`compiled_inputs`: the frame's table, the start, the model's record) and handed
    to the kernels' solve; ``engine`` / ``engine_reason`` name what ran: this engine and ``reason`` (why the caller
    chose it), or the Python engine and why when the frame cannot be tabulated within its bound
    (``frame.frame_table``) or, with traction, the run leaves the table; ``frame_table_nodes`` and
    ``frame_interpolation_error`` (relative to the channel scales) what the table reached."""
    from symmech.trolley.elastic import kernels as ek  # numba: imported by a run, not by choosing the engine or its estimate
    t, rtol = np.asarray(t, dtype=float), float(rtol)
    inputs = compiled_inputs(system, drive, t, rtol, atol_q, dq0, dqd0)
    start, frame, solved = inputs.start, inputs.frame, None
    if frame.table is not None:
        spline = (frame.table.nodes, frame.table.coef)
        if drive.traction is None:
            Y, steps, nfev, status = ek.solve(inputs.record, spline, start.y0, t, rtol, start.atol)
        else:
            with _traction(drive.traction) as key:
                Y, dV0, steps, nfev, status = ek.solve_traction(inputs.record, spline, key, start.y0, t, rtol,
                                                                 start.atol, _max_step(t))
        _check(status, Y, t)
        solved = _prescribed(start, frame) if drive.traction is None else _driven(start, frame, t, Y, dV0)
    if solved is None:
        return el_sim.simulate(system, drive, t, "Radau", rtol, atol_q, dq0, dqd0, fallback=_why_not(drive, frame))
    s, V0, dV0, fr = solved
    report = {"nfev": nfev, "njev": -1, "steps": steps, "engine": "compiled", "engine_reason": reason,
              "frame_table_nodes": frame.table.nodes.size, "frame_interpolation_error": frame.table.error}
    return el_sim.outputs(system, drive, t, s, V0, dV0, Y, rows=row_terms, frame=fr, run=report)


@dataclass(frozen=True)
class Inputs:
    """What a run reads, made in one pass (:func:`compiled_inputs`): its start (``simulate.Start``), the model
    record (``System.record``) and what it tabulates of the frame with its spline table (``frame.Tabulation``;
    with traction over the span ``frame.reach`` finds)."""

    start: el_sim.Start
    record: object
    frame: el_frame.Tabulation


def compiled_inputs(system, drive, t, rtol: float, atol_q: float, dq0=None, dqd0=None) -> Inputs:
    """The :class:`Inputs` of a run on the grid t [s] (n,) at relative tolerance ``rtol`` (the frame table's bound)
    and the keywords of ``simulate.prepare``: the frame first (its arc lengths at t and its table), then the start
    on the timeline of those arc lengths."""
    prescribed = drive.traction is None  # with traction s is a state: no arc lengths on the grid
    accelerate = None if prescribed else partial(model.traction_acceleration, system.rigid)
    s_nodes = el_frame.arc_length(drive, t) if prescribed else None
    frame = el_frame.tabulation(drive, system.mdl.g0, t, rtol, accelerate)
    line = el_sim.Timeline(system, drive, t, s_nodes)
    return Inputs(el_sim.prepare(line, atol_q, dq0, dqd0), system.record, frame)


def _prescribed(start, frame) -> tuple:
    """(s, V0, dV0 (n,), the frame at the outputs) of a run at the prescribed speed: its timeline's arc lengths and
    the exact frame its table was seeded with."""
    fr, V0, dV0, _ = frame.at_outputs
    return start.line.s_nodes, V0, dV0, fr


def _driven(start, frame, t, Y, dV0) -> tuple | None:
    """(s, V0, dV0 (n,), no frame) of a traction run with the states Y (n, layout.TRACTION_STATE), or None when it
    left the table's arc lengths (at an output or where it turns back between two: :func:`turning_points`)."""
    s, speed = Y[:, start.state.offset("s")], Y[:, start.state.offset("speed")]
    visited = np.concatenate([s, turning_points(t, s, speed)])
    nodes = frame.table.nodes
    return None if visited.min() < nodes[0] or visited.max() > nodes[-1] else (s, speed, dV0, None)


def _why_not(drive, frame) -> str:
    """Why a run falls back to the Python engine: the frame cannot be tabulated, or a traction run left its table."""
    if drive.traction is None:
        return (f"the frame along the track could not be tabulated within {el_frame.INTERP_NOISE:g} of its scale on "
                f"{el_frame.MAX_TABLE_NODES} nodes (a non-smooth track or speed): the Python engine evaluates it exactly")
    return (f"the frame along the track could not be tabulated in s within {el_frame.INTERP_NOISE:g} of its scale, or the "
            f"run left the tabulated s in [{frame.span[0]:.6g}, {frame.span[1]:.6g}] m: the Python engine "
            "evaluates it exactly")


_KEYS = itertools.count()


@contextmanager
def _traction(law):
    """The key under which the kernels call the traction law P0(t, V0) [N] back during one run: one per run, so
    that concurrent runs (threads) each find their own."""
    from symmech.trolley.elastic import kernels as ek  # numba: imported by a run, not by choosing the engine or its estimate
    key = next(_KEYS)
    ek.TRACTIONS[key] = law
    try:
        yield key
    finally:
        del ek.TRACTIONS[key]


def _max_step(t) -> float:
    """A traction run's largest step [s]: the smallest spacing of the output times t [s], as the Python engine's."""
    return float(np.min(np.diff(t))) if len(t) > 1 else np.inf


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
    model record's from its layout (:data:`symmech.trolley.elastic.layout.MODEL`), then C-contiguous float64
    arrays (vectors, rows, a spline table's knots and coefficients), float64 scalars and the traction's int64 key."""
    # numba: imported by a run, not by choosing the engine or its estimate
    import numba
    from symmech.trolley.elastic import kernels as ek
    f8, vec, mat, cube = numba.float64, numba.float64[::1], numba.float64[:, ::1], numba.float64[:, :, ::1]
    mdl, table = MODEL.numba_type(), numba.types.Tuple((vec, cube))
    return {ek.solve: (mdl, table, vec, vec, f8, vec),  # spline, y0, t, rtol, atol
            ek.rows: (mdl, mat, mat, vec, mat),  # channels, nu, height, Y
            ek.solve_traction: (mdl, table, numba.int64, vec, vec, f8, vec, f8)}  # spline, key, y0, t, rtol, atol, max step


ENGINE = build.Engine("elastic", "symmech.trolley.elastic.kernels", _entry_signatures, COLD_COMPILE_SECONDS)
