"""The whole motion of a grain on an inclined vibrating surface (paper 1, eqs (61)-(64)), accurate mode.

One grain alternates between three regimes:

- flight: exact translation in the vibrating frame and torque-free rotation, integrated to a
  tolerance (:mod:`symmech.grain.flight`, the default and the reference) or exact
  (:mod:`symmech.grain.free_flight`, ``Numerics.flight = "exact"``), until the exact support
  distance of the ellipsoid reaches the plane (:mod:`symmech.grain.contact`);
- impact: the scene's impact law at the lowest point (:mod:`symmech.grain.coulomb_law`),
  only for a contact point approaching the plane faster than round-off;
- sliding: Coulomb stick/slip and rolling on the plane, spin kept
  (:mod:`symmech.grain.sliding`), until the normal force would become negative.

A flight that starts on the plane (after an impact or a lift-off) must first rise
above round-off before a contact can be found; one that does not within a scan
step, or a contact reached without approaching, is a grain resting on the plane:
it lands and slides. On a plane that accelerates away faster than gravity (normal
force negative) only the rotation of a tumbling ellipsoid can hold it there, at the
accumulation point of its ever smaller bounces (a rocking contact, not modelled): it
lands, giving up its tilting spin (counted in ``rocking_contacts``, warned), and
flies on. Lift-off after an impact is judged physically: the grain
flies when the normal velocity of its contact point after the impact exceeds
``rest_velocity`` (a bounce lower than that is the end of chattering: the
geometric series of ever smaller bounces is summed into sliding), or when the
surface accelerates away faster than gravity (normal force negative). Landing
is a plastic normal impulse at the contact point, which keeps the angular
momentum about it.

Every run returns an energy budget (absolute kinetic energy plus the potential
of gravity against the work of the surface and the losses in impacts, landings
and sliding; its residual measures the numerics), and has guards: a run that
stops advancing time raises ``SymmechError`` instead of hanging, and an optional
``on_step(t_now)`` callback is called at most every 0.2 s of wall time.

Paper mode (the printed fixed-step scheme) lives in :mod:`symmech.grain.paper_mode`.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field, replace
from functools import cached_property

import numpy as np

from symmech.core.scene import SymmechError
from symmech.grain import contact, flight, free_flight, outcome
from symmech.grain.coulomb_law import ImpactLaw, inverse_effective_mass, kinetic_energy, principal_inertia
from symmech.grain.sliding import Body, Sliding, slide

REGIMES = ("flight", "impact", "sliding")
FLIGHTS = ("auto", "dop853", "exact")  # Numerics.flight
EPS = float(np.finfo(float).eps)
PROGRESS_INTERVAL = 0.2  # s of wall time between two calls of on_step
ENERGY_TOLERANCE = 1e-6  # stated bound on the relative residual of the energy budget
ZENO_IMPACTS, ZENO_INTERVAL = 100, 1e-4  # this many impacts within this many periods: chattering
MAX_IDLE_STEPS = 1000  # stagnation guard: regime changes in a row that do not advance time
TRAJECTORY_COLUMNS = ("t", "x", "y", "z", "vx", "vy", "vz", "q0", "q1", "q2", "q3", "wx", "wy", "wz", "regime")


@dataclass(frozen=True)
class Effects:
    """Which effects the scene calls for; an effect that is off runs no code for it."""

    vibration: bool = True
    inclination: bool = True
    rotation: bool = True
    friction: bool = True


@dataclass(frozen=True)
class Model:
    """Physics of one scene: grain semi-axes ``axes`` (3,) m and ``mass`` kg, gravity ``g_k`` (3,) m/s^2
    in KXYZ, surface ``vibration``, impact ``law``, sliding friction coefficient ``mu``, ``effects``; an effect
    that is off has its parameters zeroed on construction (the vibration's amplitude, ``mu``)."""

    axes: tuple
    mass: float
    g_k: tuple
    vibration: flight.Vibration
    law: ImpactLaw
    mu: float
    effects: Effects = Effects()

    @cached_property  # every run asks for it (a few us each time)
    def inertia(self) -> np.ndarray:
        inertia = principal_inertia(self.axes, self.mass)
        inertia.flags.writeable = False  # shared by all its users
        return inertia

    def __post_init__(self):
        # A model is what runs: the parameters of switched-off effects are zeroed here, once, so that every
        # engine and the compiled loop's parameter vector read it as given (no code runs for them).
        if not self.effects.vibration:
            object.__setattr__(self, "vibration", replace(self.vibration, amplitude=0.0))
        if not self.effects.friction:
            object.__setattr__(self, "mu", 0.0)

    @property
    def sliding(self) -> Sliding:
        return Sliding(self.g_k, self.vibration, self.mu)

    @property
    def period(self) -> float:
        """Vibration period [s], or 1 s when the surface does not vibrate (a time scale only)."""
        return self.vibration.period


@dataclass(frozen=True)
class Numerics:
    """Numerical choices. Accurate mode: ``tolerance`` (relative; times to tolerance x scan step),
    ``scan_step`` [s] for root bracketing. Paper mode: step ``dt`` [s], ``nodes`` on the body surface,
    ``as_printed`` (printed (61), (63), (64) verbatim). Both: ``rest_velocity`` [m/s] below which a
    bounce ends in sliding, ``max_impacts``, ``sample_interval`` [s] of the trajectory file. ``engine``
    (accurate mode, read by the scene kind): "compiled" (:mod:`symmech.grain.motion_engine`), "python" (this loop) or
    "auto" (compiled when numba's cache holds it; ``motion_scene.choose_engine``). ``flight`` (both loops):
    "dop853" (the rotation integrated to ``tolerance``: the reference), "exact" (closed-form rotation,
    :mod:`symmech.grain.free_flight` here, its twin ``free_flight_nb`` in the compiled loop; contacts certified by
    the gap's curvature bound) or "auto" (the default: "exact" in the compiled loop where the gap does not depend
    on the attitude, a sphere or a grain with rotation off, else "dop853"; this loop, the reference, integrates)."""

    mode: str = "accurate"
    engine: str = "auto"
    tolerance: float = 1e-9
    scan_step: float = 1e-3
    dt: float = 1e-4
    nodes: int = 400
    as_printed: bool = False
    rest_velocity: float = 1e-5
    max_impacts: int = 100000
    sample_interval: float = 1e-3
    flight: str = "auto"

    def __post_init__(self):
        if self.flight not in FLIGHTS:
            raise ValueError(f"Numerics.flight must be one of {', '.join(map(repr, FLIGHTS))}, got {self.flight!r}")


@dataclass
class State:
    """Time ``t`` [s], relative centre position ``r`` and velocity ``v`` (3,) [m, m/s] in KXYZ,
    orientation quaternion ``q`` (4,), body-axis angular velocity ``w`` (3,) [rad/s]."""

    t: float
    r: np.ndarray
    v: np.ndarray
    q: np.ndarray
    w: np.ndarray

    def row(self, regime: str) -> list:
        Q = flight.rotation_matrix(self.q)
        return [self.t, *self.r, *self.v, *self.q, *(Q @ self.w), REGIMES.index(regime)]


class ImpactLog:
    """A run's impact log, read as :attr:`Motion.impacts`: the entries themselves (a list of dicts with the keys of
    :func:`impact_record`), or an engine's impact rows (n, width) with ``build``, the function that makes the entries
    of them, and ``t_column``, the column of the impact times [s]: built on first read (a dict per impact costs as
    much as the compiled loop's work for that impact, and holds the GIL)."""

    __slots__ = ("rows", "build", "t_column")

    def __init__(self, rows, build=None, t_column: int = 0):
        self.rows, self.build, self.t_column = rows, build, t_column

    def entries(self) -> list:
        """The entries (a list of dicts), built from the rows by ``build`` when there is one."""
        return self.rows if self.build is None else self.build(self.rows)

    def times(self) -> np.ndarray:
        """The impact times (n,) [s] in order; from the rows' column, no entry built."""
        if self.build is None:
            return np.array([i["t"] for i in self.rows], dtype=float)
        return self.rows[:, self.t_column].copy()


@dataclass
class Motion:
    """Result: ``trajectory`` (n, 15) with :data:`TRAJECTORY_COLUMNS`, ``impact_log`` (:class:`ImpactLog`, read
    as ``impacts``, a list of dicts), ``time_in`` seconds per regime, ``warnings``, the ``final`` state and the
    ``start`` state; ``extra`` goes into the summary as it is (accurate mode: ``landings`` and ``energy_budget``,
    the dict of :meth:`outcome.EnergyBudget.report`)."""

    trajectory: np.ndarray
    impact_log: ImpactLog
    time_in: dict
    warnings: list
    start: State
    final: State
    extra: dict = field(default_factory=dict)

    @cached_property
    def impacts(self) -> list:
        """The impact log, a dict per impact (the keys of :func:`impact_record`), built once on first read."""
        return self.impact_log.entries()

    def impact_times(self) -> np.ndarray:
        """The impact times (n,) [s] in order (from the compiled engine's rows: no log built)."""
        return self.impact_log.times()

    def transport_velocity(self) -> list:
        """Mean transport velocity along X and Y [m/s]: the net displacement over the duration."""
        return ((self.final.r[:2] - self.start.r[:2]) / (self.final.t - self.start.t)).tolist()

    def summary(self) -> dict:
        duration = self.final.t - self.start.t
        dissipated = sum(i["ke_before"] - i["ke_after"] for i in self.impacts)
        created = [i for i in self.impacts if not i["admissible"]]
        printed_bad = sum(1 for i in self.impacts if i["printed_admissible"] is False)
        printed_energy = sum(1 for i in self.impacts if i["printed_creates_energy"] is True)
        return {
            "duration_s": duration,
            "mean_transport_velocity_m_s": self.transport_velocity(),
            "bounces": len(self.impacts),
            "time_fraction": {k: v / duration for k, v in self.time_in.items()},
            "energy_dissipated_by_impacts_J": dissipated,
            "impacts_creating_energy": len(created),
            "impacts_where_printed_law_is_inadmissible": printed_bad,
            "impacts_where_printed_law_creates_energy": printed_energy,
            **self.extra,
            "warnings": self.warnings,
        }


class _Recorder:
    """Trajectory rows at a sample interval plus every event."""

    def __init__(self, interval: float):
        self.interval = interval
        self.rows: list = []

    def times(self, t0: float, t1: float) -> np.ndarray:
        k0 = np.ceil(t0 / self.interval - 1e-9)
        k1 = np.floor(t1 / self.interval - 1e-9)
        return np.arange(k0, k1 + 1) * self.interval

    def add(self, state: State, regime: str) -> None:
        self.rows.append(state.row(regime))

    def add_many(self, t, r, v, q, w_body, regime: str) -> None:
        """Rows for arrays t (n,), r, v (n, 3), q (n, 4), w_body (n, 3)."""
        if len(t) == 0:
            return
        w = np.einsum("nij,nj->ni", flight.rotation_matrix(q), w_body)
        code = np.full((len(t), 1), REGIMES.index(regime))
        self.rows.extend(np.hstack([np.asarray(t)[:, None], r, v, q, w, code]).tolist())


def impact_record(t: float, before: State, after: State, out: dict, i: int = 0) -> dict:
    """One line of the impact log (grain index ``i`` of a law result ``out``)."""
    return {"t": t, "r": before.r.tolist(), "v_before": before.v.tolist(), "v_after": after.v.tolist(),
            "w_before": before.w.tolist(), "w_after": after.w.tolist(),
            "impulse": out["impulse"][i].tolist(), "u_before": out["u_before"][i].tolist(),
            "u_after": out["u_after"][i].tolist(), "ke_before": float(out["ke_before"][i]),
            "ke_after": float(out["ke_after"][i]), "admissible": bool(out["admissible"][i]),
            "printed_admissible": out["printed_admissible"][i],
            "printed_creates_energy": out["printed_creates_energy"][i], "converged": bool(out["converged"][i])}


class Progress:
    """Calls ``on_step(t_now)`` at most every ``PROGRESS_INTERVAL`` seconds of wall time (always when ``final``)."""

    def __init__(self, on_step):
        self.on_step = on_step
        self.last = time.monotonic()

    def __call__(self, t_now: float, final: bool = False) -> None:
        if self.on_step is not None and (final or time.monotonic() - self.last >= PROGRESS_INTERVAL):
            self.last = time.monotonic()
            self.on_step(float(t_now))


def absolute_energy(model: Model, st: State) -> float:
    """Absolute energy [J] of the grain at ``st``: kinetic in the inertial frame plus the potential of gravity."""
    s = model.vibration.kinematics(st.t)
    v_abs = st.v + s[1]
    return (model.mass * (0.5 * float(v_abs @ v_abs) - float(np.asarray(model.g_k) @ (st.r + s[0])))
            + 0.5 * float(st.w @ (model.inertia * st.w)))


def surface_work(model: Model, t: float, P) -> float:
    """Work [J] of the moving surface through an impulse P (3,) [N s] on the grain at time t."""
    return float(np.asarray(P) @ model.vibration.kinematics(t)[1])


def simulate(model: Model, num: Numerics, start: State, t_end: float, on_step=None, reason: str = "") -> Motion:
    """Accurate mode from ``start`` to ``t_end`` [s]; the grain starts in flight (or on the plane at rest).
    ``extra`` names this engine ("python") and ``reason``, why the caller chose it.

    ``on_step(t_now: float) -> None`` (optional) is called with the simulated time [s] at most every
    0.2 s of wall time and once at the end; an exception it raises stops the run and propagates unchanged.
    """
    progress = Progress(on_step)
    rec = _Recorder(num.sample_interval)
    st = replace(start, r=np.array(start.r, float), v=np.array(start.v, float),
                 q=np.asarray(start.q, float) / np.linalg.norm(start.q), w=np.array(start.w, float))
    if not model.effects.rotation:
        st.w = np.zeros(3)
    budget = outcome.EnergyBudget(absolute_energy(model, st))
    on_plane = _gap(model, st) <= _gap_noise(model, st)
    time_in = dict.fromkeys(("flight", "sliding"), 0.0)
    impacts: list = []
    warnings: list = []
    regime, landings, rocking, idle = "flight", 0, 0, 0
    rec.add(st, regime)
    if on_plane and _contact_velocity(model, st) <= _velocity_noise(model, st) and model.sliding.normal(st.t) > 0:
        regime, on_plane = "sliding", False  # released on a plane that pushes: it slides from the start
        st = _land(model, st, budget)
    while st.t < t_end:
        progress(st.t)
        t_before = st.t
        if regime == "flight":
            st, status = _fly(model, num, st, t_end, rec, on_plane)
            time_in["flight"] += st.t - t_before
            if status == "end":
                break
            if status == "contact" and _contact_velocity(model, st) < -_velocity_noise(model, st):
                if len(impacts) >= num.max_impacts:
                    warnings.append(outcome.max_impacts_warning(st.t, num.max_impacts))
                    break
                st, u_n = _bounce(model, st, impacts, rec, budget, warnings)
            else:
                u_n = 0.0  # touching without approaching: resting on the plane
            # Resting (no separating velocity the numerics resolve) on a plane that pushes: slide.
            on_plane = True
            if u_n <= num.rest_velocity and model.sliding.normal(st.t) > 0:
                regime, on_plane, landings = "sliding", False, landings + 1
                st = _land(model, st, budget)
            elif status == "resting":
                # Held on a plane that accelerates away faster than gravity: only the tilting spin of a
                # tumbling ellipsoid (a rocking contact) can keep it there; rocking is not modelled.
                rocking += 1
                st = _land(model, st, budget)
        else:
            st, lifted = _slide(model, num, st, t_end, rec, budget, progress)
            time_in["sliding"] += st.t - t_before
            if lifted:
                regime, on_plane = "flight", True
        idle = idle + 1 if st.t == t_before else 0
        if idle > MAX_IDLE_STEPS:
            raise SymmechError(outcome.stalled_error(st.t, MAX_IDLE_STEPS, regime))
    progress(st.t, final=True)
    rec.add(st, regime)
    if rocking:
        warnings.append(outcome.rocking_warning(rocking))
    extra = {"landings": landings, "rocking_contacts": rocking,
             "energy_budget": budget.report(absolute_energy(model, st), ENERGY_TOLERANCE), "engine": "python",
             "engine_reason": reason}
    return Motion(np.array(rec.rows), ImpactLog(impacts), time_in, outcome.distinct(warnings), start, st, extra)


def _bounce(model: Model, st: State, impacts: list, rec: _Recorder, budget: outcome.EnergyBudget,
            warnings: list):
    """An impact at ``st``, logged and booked: (state after, normal contact velocity after [m/s]; zero when the
    impacts have become a chattering sequence too dense to follow, which is summed into sliding)."""
    before = st
    st, out = _impact(model, st, warnings)
    budget.work += surface_work(model, st.t, out["impulse"][0])
    budget.impacts += float(out["ke_before"][0] - out["ke_after"][0])
    rec.add(before, "impact")
    rec.add(st, "impact")
    impacts.append(impact_record(st.t, before, st, out))
    times = [i["t"] for i in impacts[-ZENO_IMPACTS:]]
    if len(times) == ZENO_IMPACTS and times[-1] - times[0] < ZENO_INTERVAL * model.period:
        warnings.append(outcome.chatter_warning(ZENO_IMPACTS, ZENO_INTERVAL))
        return st, 0.0
    return st, float(out["u_after"][0, 2])


def _impact(model: Model, st: State, warnings: list):
    """The scene's impact law at the lowest point: (state after, law output)."""
    Q = flight.rotation_matrix(st.q)
    out = model.law.apply(np.array([model.axes]), np.array([model.mass]), Q[None], st.v[None],
                          (Q @ st.w)[None], model.effects.rotation)
    warnings += out["warnings"]
    return State(st.t, st.r, out["v"][0], st.q, Q.T @ out["w"][0]), out


def _contact_velocity(model: Model, st: State) -> float:
    """Normal velocity [m/s] of the body point at the lowest point, relative to the surface."""
    Q = flight.rotation_matrix(st.q)
    return float(st.v[2] + np.cross(Q @ st.w, contact.contact_offset(model.axes, Q))[2])


def _gap(model: Model, st: State) -> float:
    """Height [m] of the lowest point above the plane."""
    return float(st.r[2] - contact.support_distance(model.axes, flight.rotation_matrix(st.q)))


def _gap_noise(model: Model, st: State) -> float:
    """Round-off level [m] of the gap: a flight from the plane has left it only once above this."""
    return 64 * EPS * (max(model.axes) + abs(st.r[2]) + model.vibration.amplitude)


def _velocity_noise(model: Model, st: State) -> float:
    """Round-off level [m/s] of a contact velocity: an impact must approach faster than this."""
    vib = model.vibration
    scale = np.linalg.norm(st.v) + np.linalg.norm(st.w) * max(model.axes) + vib.amplitude * vib.omega
    return 1e3 * EPS * scale


def _land(model: Model, st: State, budget: outcome.EnergyBudget) -> State:
    """Start sliding: a plastic normal impulse at the lowest point stops its normal velocity (angular momentum
    about the contact is kept); a non-spherical grain also gives up the tilting spin the sliding regime does not
    model. Both losses are booked as landing loss; the centre sits at the support height."""
    Q = flight.rotation_matrix(st.q)
    R = contact.contact_offset(model.axes, Q)
    w = Q @ st.w
    rotating = model.effects.rotation
    K = inverse_effective_mass(model.mass, model.inertia, Q, R) if rotating else np.eye(3) / model.mass
    P = np.array([0.0, 0.0, -_contact_velocity(model, st) / K[2, 2]])
    v = st.v + P / model.mass
    if rotating:
        w = w + Q @ ((Q.T @ np.cross(R, P)) / model.inertia)
        if max(model.axes) != min(model.axes):
            v[2], w[:2] = 0.0, 0.0
    v[2] = 0.0
    ke = kinetic_energy(model.mass, model.inertia, Q, np.stack([st.v, v]), np.stack([Q @ st.w, w]))
    budget.work += surface_work(model, st.t, model.mass * (v - st.v))
    budget.landings += float(ke[0] - ke[1])
    r = st.r.copy()
    r[2] = float(contact.support_distance(model.axes, Q))
    return State(st.t, r, v, st.q, Q.T @ w)


def _slide(model: Model, num: Numerics, st: State, t_end: float, rec: _Recorder, budget: outcome.EnergyBudget,
           progress):
    """One sliding phase from ``st``: (state at its end, lifted off)."""
    body = Body(model.axes, model.mass, tuple(model.inertia), model.effects.rotation)
    Q = flight.rotation_matrix(st.q)
    res = slide(model.sliding, body, st.t, st.r[:2], st.v[:2], st.q, Q @ st.w, t_end, rec.times(st.t, t_end),
                num.scan_step, num.tolerance, progress)
    ts, rs, vs, qs, ws = res.samples
    n = len(ts)
    w_body = np.einsum("nji,nj->ni", flight.rotation_matrix(qs), ws) if n else ws
    rec.add_many(ts, np.column_stack([rs, np.full(n, st.r[2])]), np.column_stack([vs, np.zeros(n)]),
                 qs, w_body, "sliding")
    budget.work += res.work
    budget.sliding += res.dissipated
    end = State(res.t, np.array([*res.r, st.r[2]]), np.array([*res.v, 0.0]), res.q,
                flight.rotation_matrix(res.q).T @ res.w)
    rec.add(end, "sliding")
    return end, res.lifted


def _fly(model: Model, num: Numerics, st: State, t_end: float, rec: _Recorder, on_plane: bool):
    """Fly from ``st`` until the first contact or ``t_end``: (state, "contact" | "end" | "resting").

    A flight that starts on the plane (after an impact or lift-off) first has to rise above round-off;
    "resting" says it does not within one scan step. A run that ends within that step ends in flight.
    """
    vib = model.vibration
    rotating = model.effects.rotation and np.any(st.w)
    exact = num.flight == "exact"
    if not rotating:
        rot = None
    elif exact:
        rot = free_flight.ExactRotation(model.inertia, st.q, st.w, st.t)
    else:
        rot = flight.RotationFlight(model.inertia, st.q, st.w, st.t, num.tolerance, model.period)

    def orient(t):
        if rotating:
            return rot.state(t)
        shape = np.shape(t)
        return np.broadcast_to(st.q, shape + (4,)), np.broadcast_to(st.w, shape + (3,))

    def gap(t):
        r, _ = flight.translate(st.r, st.v, model.g_k, vib, st.t, t)
        h = r[..., 2] - contact.support_distance(model.axes, flight.rotation_matrix(orient(t)[0]))
        return h if np.ndim(t) else float(h)

    def gap_and_rate(t):
        r, v = flight.translate(st.r, st.v, model.g_k, vib, st.t, t)
        q, w = orient(t)
        Q = flight.rotation_matrix(q)
        return float(r[2] - contact.support_distance(model.axes, Q)), float(
            free_flight.gap_rate(v[2], np.asarray(model.axes), Q[2], w))

    t_from = st.t
    if on_plane:
        t_from = _rise(gap, st.t, min(num.scan_step, t_end - st.t), _gap_noise(model, st))
        if t_from is None and t_end - st.t >= num.scan_step:
            return st, "resting"
        if t_from is None:  # the run ends before the rise is over: in flight, not resting (no landing at t_end)
            t_from = t_end
    xtol = num.tolerance * num.scan_step
    if exact:
        curvature = free_flight.gap_curvature_bound(model.g_k[2], vib, model.axes, model.inertia,
                                                    rot.max_rate if rotating else 0.0)
        tc = contact.first_contact(gap_and_rate, curvature, t_from, t_end, num.scan_step, xtol)
    else:
        tc = contact.first_root(gap, t_from, t_end, num.scan_step, xtol)
    t_stop = t_end if tc is None else tc
    ts = rec.times(st.t, t_stop)
    ts = np.append(ts[(ts > st.t) & (ts < t_stop)], t_stop)
    r, v = flight.translate(st.r, st.v, model.g_k, vib, st.t, ts)
    q, w = orient(ts)
    rec.add_many(ts[:-1], r[:-1], v[:-1], q[:-1], w[:-1], "flight")
    return State(t_stop, r[-1], v[-1], q[-1].copy(), w[-1].copy()), "end" if tc is None else "contact"


def _rise(gap, t0: float, span: float, noise: float):
    """The latest of ``t0 + span / 2^k`` where the gap exceeds ``noise`` [m], or None."""
    for k in range(64):
        t = t0 + span / 2.0**k
        if t <= t0:
            break
        if gap(t) > noise:
            return t
    return None
