"""The elastic trolley integrated along the track: the timeline of a run (with traction too), the start
both engines share (:func:`prepare`), the solve (scipy's ``solve_ivp`` on
:class:`symmech.trolley.elastic.system.System`) and the outputs per row (reactions, energies, deflections)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from symmech.core import context
from symmech.core.layout import Layout
from symmech.core.scene import SymmechError
from symmech.trolley import model
from symmech.trolley.elastic.body import roller_forces
from symmech.trolley.elastic.frame import GAUSS_LEGENDRE, Drive, FrameState, arc_length, frame_motion, frame_state
from symmech.trolley.elastic.layout import N_ROLLER_DOFS, state as state_layout
from symmech.trolley.elastic.system import System

# ---------------------------------------------------------------- integration along the track

def _state_at(drive: Drive, t: float, s: float) -> FrameState:
    V0, dV0 = drive.speed(t)
    return frame_state(drive.frames(s), 0, float(V0), float(dV0))


class Timeline:
    """Arc length s(t) = s0 + ∫ V0 dt (from the arc lengths ``s_nodes`` (n,) [m] on the grid t [s] (n,),
    :func:`symmech.trolley.elastic.frame.arc_length`, None with traction; 8-point Gauss-Legendre from the last node)
    and the frame state at t, cached: implicit steps revisit their stage times."""

    def __init__(self, system: System, drive: Drive, t, s_nodes):
        self.system, self.drive, self.t, self.s_nodes = system, drive, np.asarray(t, dtype=float), s_nodes
        self.cache: dict = {}

    def _integral(self, a, b):
        x, w = GAUSS_LEGENDRE
        mid, half = (a + b) / 2, (b - a) / 2
        return float(sum(wi * float(self.drive.speed(mid + half * xi)[0]) for xi, wi in zip(x, w)) * half)

    def s(self, time: float) -> float:
        k = max(int(np.searchsorted(self.t, time, side="right")) - 1, 0)
        return self.s_nodes[k] + self._integral(self.t[k], time)

    def state(self, time: float) -> FrameState:
        if time not in self.cache:
            if len(self.cache) > 64:
                self.cache.clear()
            self.cache[time] = _state_at(self.drive, time, self.s(time))
        return self.cache[time]

    def traction_states(self, s: float, V0: float) -> tuple[FrameState, FrameState]:
        """Frame states at arc length s [m], speed V0 [m/s] with V̇0 = 0 and 1 m/s² (the
        equations are affine in V̇0), cached by s."""
        if s not in self.cache:
            if len(self.cache) > 64:
                self.cache.clear()
            self.cache[s] = self.drive.frames(s)
        fr = self.cache[s]
        return frame_state(fr, 0, V0, 0.0), frame_state(fr, 0, V0, 1.0)

    def traction_step(self, time: float, y):
        """(frame state, q̈, V̇0) with traction: M q̈ + b V̇0 = -R0 and F1 = P0(t, V0) solved together
        (b = ∂R/∂V̇0, F1 the x1 resultant of (8), affine in q̈ and V̇0)."""
        system, N = self.system, self.system.N
        y = state_layout(N, True).unpack(y)
        q, qd, s, V0 = y["q"], y["qd"], y["s"], y["speed"]
        fs0, fs1 = self.traction_states(float(s), float(V0))
        zero = np.zeros(N)
        R0 = system.evaluate(fs0, q, qd, zero)
        F0 = system.resultants(fs0, q, qd, zero)[0][0]
        _, A = system.coefficients(q)
        lhs = np.zeros((N + 1, N + 1))
        lhs[:N, :N] = system.mass(q)
        lhs[:N, N] = system.evaluate(fs1, q, qd, zero) - R0
        lhs[N, :N] = A @ system.inv.S1[:, 0]
        lhs[N, N] = system.resultants(fs1, q, qd, zero)[0][0] - F0
        x = np.linalg.solve(lhs, np.r_[-R0, float(self.drive.traction(time, V0)) - F0])
        return frame_state(self.cache[float(s)], 0, V0, x[N]), x[:N], x[N]


def traction_start(line: Timeline, t0: float) -> np.ndarray:
    """The quasi-static q (N,) at t0 [s] with traction: under the acceleration of the whole body by P0 along a
    level x1, at s0 and the initial speed."""
    system, drive = line.system, line.drive
    fs, _ = line.traction_states(drive.s0, drive.v_initial)
    dv = float(drive.traction(t0, drive.v_initial)) / system.inv.mass - system.mdl.g0 * fs.nu[0]
    return system.quasi_static(frame_state(line.cache[drive.s0], 0, drive.v_initial, dv))


@dataclass(frozen=True)
class Start:
    """What a run of either engine starts from: its :class:`Timeline`, the layout of its state
    (layout.STATE, with traction layout.TRACTION_STATE, sized for the model), the start state y0 and the absolute
    tolerances atol of the state's slots (both of that layout)."""

    line: Timeline
    state: Layout
    y0: np.ndarray
    atol: np.ndarray


def prepare(line: Timeline, atol_q: float, dq0=None, dqd0=None) -> Start:
    """The :class:`Start` of a run on the grid ``line.t`` [s] (n,): y0 is the quasi-static q at t[0]
    (:func:`traction_start` with traction) plus the offsets ``dq0``, ``dqd0`` of coordinates and rates,
    E_d = W = 0 [J]; with ``drive.traction`` also s0 [m] and the initial speed [m/s]. atol: ``atol_q`` on q
    [m, rad], 1e3 atol_q on q̇, 1e-9 J on E_d, :data:`WORK_ATOL` on W, 1e-10 on s [m] and V0 [m/s]. Both engines
    start here."""
    system, drive = line.system, line.drive
    traction = drive.traction is not None
    state = state_layout(system.N, traction)
    q0 = traction_start(line, line.t[0]) if traction else system.quasi_static(line.state(line.t[0]))
    zero = np.zeros(system.N)
    y0 = {"q": q0 + (zero if dq0 is None else dq0), "qd": zero if dqd0 is None else dqd0, "dissipated": 0.0,
          "work": 0.0}
    atol = {"q": np.full(system.N, atol_q), "qd": np.full(system.N, atol_q * 1e3), "dissipated": 1e-9,
            "work": WORK_ATOL}
    if traction:
        y0.update(s=drive.s0, speed=drive.v_initial)
        atol.update(s=1e-10, speed=1e-10)
    return Start(line, state, state.pack(**y0), state.pack(**atol))


def _dissipation(system: System, qd) -> float:
    """Power of the damping forces [W] (beam d_ij and roller dampers)."""
    power = qd @ system.inv.D @ qd
    if system.rollers_on and system.mdl.effects.damping:
        dd = system.C @ qd[:N_ROLLER_DOFS]
        power += float(np.asarray(system.mdl.rollers.damping) @ (dd * dd))
    return float(power)


WORK_ATOL = 1e-5  # J, absolute tolerance of the work of the track forces
# Wall time per output step of this (Python) engine [s] (bundled trolley_elastic_helix on 2 shared cores: ~0.1 s;
# stiff rollers and undamped beams take more): the estimates of a run, of a sweep, of a fallback to it
SECONDS_PER_STEP = 0.1


def integration_failed(t_reached: float, why: str) -> SymmechError:
    """The error of a failed elastic solve, either engine: the last output time reached [s] and the solver's
    reason."""
    return SymmechError(f"elastic trolley: integration failed after t = {t_reached:.6g} s ({why})")


def simulate(system: System, drive: Drive, t, method: str = "Radau", rtol: float = 1e-8,
             atol_q: float = 1e-12, dq0=None, dqd0=None, analytic_jacobian: bool = True, fallback: str = "",
             reason: str = "") -> dict:
    """Integrate the relative motion on the grid t [s] (n,) from the quasi-static state at t[0]
    (plus the offsets ``dq0``, ``dqd0`` of coordinates and rates, when given).

    y = [q, q̇, E_d, W] (layout.STATE): the coordinates, their rates, the dissipated energy and the work of
    the track forces [J]; with ``drive.traction`` also [s, V0] (layout.TRACTION_STATE). The prescribed frame follows s(t) of
    :class:`Timeline`. Implicit methods ("Radau", "BDF") use the analytic Jacobian (prescribed
    speed; with traction scipy differences the right-hand side, as without ``analytic_jacobian``).
    Returns a dict of arrays with a leading axis n (see :func:`outputs`), ``engine`` "python" and
    ``engine_reason`` why it ran: ``fallback`` or ``reason`` (the caller's choice of it).

    The run's context (:func:`symmech.core.context.active`), when there is one, is ticked at every
    right-hand side: ``--max-time`` holds here too. ``fallback`` (why this engine runs in place of the compiled
    one) re-estimates against what is left of it and says so (:meth:`~symmech.core.context.Context.fallback`)."""
    from scipy.integrate import solve_ivp

    t = np.asarray(t, dtype=float)
    ctx = context.active()
    if ctx is not None and fallback:
        ctx.fallback(f"elastic model on the Python engine: {fallback}", SECONDS_PER_STEP * (t.size - 1))
    s_nodes = arc_length(drive, t) if drive.traction is None else None
    start = prepare(Timeline(system, drive, t, s_nodes), atol_q, dq0, dqd0)
    line, st, traction = start.line, start.state, drive.traction is not None
    iq, iqd = st.slice("q"), st.slice("qd")

    def rhs(time, y):
        if ctx is not None:
            ctx.tick(f"elastic model, Python engine at t = {time:.6g} s")
        q, qd = y[iq], y[iqd]
        rates = {}
        if traction:
            fs, qdd, dv = line.traction_step(time, y)
            rates.update(s=y[st.offset("speed")], speed=dv)
        else:
            fs = line.state(time)
            qdd = system.accelerations(fs, q, qd)
        return st.pack(q=qd, qd=qdd, dissipated=_dissipation(system, qd),
                       work=system.track_power(fs, q, qd, qdd), **rates)

    def jac(time, y):
        fs = line.state(time)
        q, qd = y[iq], y[iqd]
        qdd = system.accelerations(fs, q, qd)
        _, M, Rq, Rqd = system.evaluate(fs, q, qd, qdd, jacobian=True)
        out = np.zeros((st.size, st.size))
        out[iq, iqd] = np.eye(system.N)
        out[iqd, iq] = -np.linalg.solve(M, Rq)
        out[iqd, iqd] = -np.linalg.solve(M, Rqd)
        return out

    # the work of the track forces is under step control too (left out, the stiff start transient
    # goes unresolved and the reactions lose two digits), at 1e-5 J: tighter costs steps on stiff
    # rollers (10 kg on 1e8 N/m: 1761 evaluations at 1e-5 J, 2175 at 1e-9 J) for no gain in P
    kw = {"jac": jac} if analytic_jacobian and not traction and method in ("Radau", "BDF", "LSODA") else {}
    # Steps no longer than the output spacing: the outputs come from the dense output, whose
    # interpolation error the step control does not see (Radau's steps grow to ~0.3 s here).
    step = float(np.min(np.diff(t))) if len(t) > 1 else np.inf
    sol = solve_ivp(rhs, (t[0], t[-1]), start.y0, method=method, t_eval=t, rtol=rtol, atol=start.atol, max_step=step,
                    **kw)
    if sol.status != 0 or not np.all(np.isfinite(sol.y)):
        raise integration_failed(sol.t[-1], sol.message)
    Y = sol.y.T
    if traction:
        s, V0 = Y[:, st.offset("s")], Y[:, st.offset("speed")]
        dV0 = np.array([line.traction_step(ti, yi)[2] for ti, yi in zip(t, Y)])
    else:
        s = line.s_nodes
        speed = [drive.speed(ti) for ti in t]
        V0, dV0 = (np.array([float(v[k]) for v in speed]) for k in (0, 1))
    return outputs(system, drive, t, s, V0, dV0, Y, run={"nfev": sol.nfev, "njev": sol.njev, "engine": "python",
                                                          "engine_reason": fallback or reason})


def row_terms(system: System, fr: model.Frame, V0, dV0, Y, height) -> dict:
    """Per output row (frame fr, speeds V0, dV0, heights of O (n,) [m], states Y (n, layout.state)): q̈ (n, N), the
    resultants F, M (n, 3), the coefficient vectors of r̃, its rate and acceleration (n, F), the Jacobi
    energy h and the total energy E (n,) [J]. The compiled engine computes the same in numba
    (:func:`symmech.trolley.elastic.compiled.row_terms`)."""
    N, n = system.N, len(V0)
    st = state_layout(N, False)  # the first fields of either state
    q, qd = Y[:, st.slice("q")], Y[:, st.slice("qd")]
    res = {k: np.zeros((n,) + shape) for k, shape in (("qdd", (N,)), ("F", (3,)), ("M", (3,)), ("rr", (system.F,)),
                                                     ("v", (system.F,)), ("acc", (system.F,)), ("h", ()), ("E", ()))}
    for i in range(n):
        fs = frame_state(fr, i, V0[i], dV0[i])
        qdd = system.accelerations(fs, q[i], qd[i])
        res["qdd"][i] = qdd
        res["F"][i], res["M"][i] = system.resultants(fs, q[i], qd[i], qdd)
        rr, A = system.coefficients(q[i])
        res["rr"][i], res["v"][i], res["acc"][i] = rr, qd[i] @ A, qdd @ A + system.quadratic_rates(qd[i])
        res["h"][i] = system.jacobi_energy(fs, q[i], qd[i])
        res["E"][i] = system.total_energy(fs, q[i], qd[i], height[i])
    return res


def outputs(system: System, drive: Drive, t, s, V0, dV0, Y, rows=row_terms, frame=None, run=None) -> dict:
    """Per output time (arrays (n,) of t, s, V0, dV0 and the states Y (n, layout.state)): q, q̇, q̈,
    reactions P (n, 6), resultants F, M (n, 3), roller deflections (n, 5), probe displacements
    (total and elastic) and overloads (n, n_probes, 3) [m, g], the Jacobi energy h, the total
    energy E (fixed frame), the dissipated energy and the work of the track forces [J], and the
    rigid model's reactions and overloads of the centre of mass beside them. ``rows`` computes the
    per-row terms (:func:`row_terms` or the compiled engine's); ``frame``: the frame at s when the caller has
    it (``drive.frames``); ``run``: what the engine reports of its run (evaluations, steps, its name), as it is."""
    N, inv = system.N, system.inv
    st = state_layout(N, False)  # the first fields of either state
    q, qd = Y[:, st.slice("q")], Y[:, st.slice("qd")]
    ed, work = Y[:, st.offset("dissipated")], Y[:, st.offset("work")]
    fr = drive.frames(s) if frame is None else frame
    _, a0, w, dw = frame_motion(fr, V0, dV0)
    height = drive.frames.track.derivatives(s, 0)[0][:, 1]
    res = rows(system, fr, V0, dV0, Y, height)
    if system.rollers_on:
        d = q[:, :N_ROLLER_DOFS] @ system.C.T
        force, _ = roller_forces(system.mdl.rollers, d, qd[:, :N_ROLLER_DOFS] @ system.C.T, system.mdl.effects.damping)
        res["P"] = np.column_stack([res["F"][:, 0], force])
        res["deflection"] = d
        res["M_contacts"] = system.contact_moment(q, force)
    else:
        res["P"] = np.linalg.solve(system.reaction_system, np.column_stack([res["F"], res["M"]]).T).T
        res["deflection"], res["M_contacts"] = np.zeros((len(t), 5)), np.zeros((len(t), 3))
    g_ref = system.mdl.g0 if system.mdl.g0 > 0 else 9.80665
    pos, vel, ddu = (np.einsum("nk,kpi->npi", res[key], inv.probe_fields) for key in ("rr", "v", "acc"))
    a = a0[:, None] + np.cross(dw[:, None], pos) + np.cross(w[:, None], np.cross(w[:, None], pos)) + \
        2 * np.cross(w[:, None], vel) + ddu
    res["probe_displacement"] = pos - inv.probe_points
    res["probe_elastic"] = np.einsum("nk,kpi->npi", np.where(system.beam_fields, res["rr"], 0.0), inv.probe_fields)
    res["probe_overload"] = (a + system.mdl.g0 * fr.lam[:, None, :, 1]) / g_ref
    for key in ("rr", "v", "acc"):
        del res[key]
    rigid = model.body_motion(fr, V0, dV0, system.rigid)
    res.update(t=t, s=s, V0=V0, dV0=dV0, q=q, qd=qd, dissipated=ed, work=work, names=list(inv.names),
               P_rigid=rigid["P"], overload_rigid=rigid["overload"], W=fr.W, dW=fr.dW, **(run or {}))
    return res
