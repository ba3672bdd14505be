"""The whole motion of a grain on an inclined vibrating surface (paper 1, eqs (61)-(64)), accurate mode.

One grain alternates between three regimes:

- flight: exact translation in the vibrating frame and torque-free rotation to a
  tolerance (:mod:`symmech.grain.flight`), until the exact support distance of the
  ellipsoid reaches the plane (:mod:`symmech.grain.contact`);
- impact: the scene's impact law at the lowest point (:mod:`symmech.grain.coulomb_law`);
- sliding: Coulomb stick/slip on the plane (:mod:`symmech.grain.sliding`) until the
  normal force would become negative.

A contact reached without ever separating (a rocking body that presses on the
plane right after an impact) is persistent contact: the grain lands and slides.
Lift-off after an impact is judged physically: the grain flies when the normal
velocity of its contact point after the impact exceeds ``rest_velocity`` (a
bounce lower than that is the end of chattering: the geometric series of ever
smaller bounces is summed into sliding), or when the surface accelerates away
faster than gravity (normal force negative). Otherwise it slides.

Paper mode (the printed fixed-step scheme) lives in :mod:`symmech.grain.paper_mode`.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from symmech.grain import contact, flight
from symmech.grain.coulomb_law import ImpactLaw, principal_inertia
from symmech.grain.sliding import Sliding, slide

REGIMES = ("flight", "impact", "sliding")
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
    in KXYZ, surface ``vibration``, impact ``law``, sliding friction coefficient ``mu``, ``effects``."""

    axes: tuple
    mass: float
    g_k: tuple
    vibration: flight.Vibration
    law: ImpactLaw
    mu: float
    effects: Effects = Effects()

    @property
    def inertia(self) -> np.ndarray:
        return principal_inertia(self.axes, self.mass)

    def active(self) -> "Model":
        """The model the simulation runs: parameters of switched-off effects zeroed (no code runs for them)."""
        vib = self.vibration if self.effects.vibration else replace(self.vibration, amplitude=0.0)
        return replace(self, vibration=vib, mu=self.mu if self.effects.friction else 0.0)

    @property
    def sliding(self) -> Sliding:
        return Sliding(self.g_k, self.vibration, self.mu)

    @property
    def period(self) -> float:
        """Vibration period [s], or 1 s when the surface does not vibrate (a time scale only)."""
        return 2 * np.pi / self.vibration.omega if not self.vibration.off else 1.0


@dataclass(frozen=True)
class Numerics:
    """Numerical choices. Accurate mode: ``tolerance`` (relative; times to tolerance x scan step),
    ``scan_step`` [s] for root bracketing. Paper mode: step ``dt`` [s], ``nodes`` on the body surface,
    ``as_printed`` (printed (61), (63), (64) verbatim). Both: ``rest_velocity`` [m/s] below which a
    bounce ends in sliding, ``max_impacts``, ``sample_interval`` [s] of the trajectory file."""

    mode: str = "accurate"
    tolerance: float = 1e-9
    scan_step: float = 1e-3
    dt: float = 1e-4
    nodes: int = 400
    as_printed: bool = False
    rest_velocity: float = 1e-5
    max_impacts: int = 100000
    sample_interval: float = 1e-3


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


@dataclass
class Motion:
    """Result: ``trajectory`` (n, 15) with :data:`TRAJECTORY_COLUMNS`, ``impacts`` (list of dicts),
    ``time_in`` seconds per regime, ``warnings``, the ``final`` state and the ``start`` state."""

    trajectory: np.ndarray
    impacts: list
    time_in: dict
    warnings: list
    start: State
    final: State
    extra: dict = field(default_factory=dict)

    def summary(self) -> dict:
        duration = self.final.t - self.start.t
        dissipated = sum(i["ke_before"] - i["ke_after"] for i in self.impacts)
        created = [i for i in self.impacts if not i["admissible"]]
        printed_bad = sum(1 for i in self.impacts if i["printed_admissible"] is False)
        printed_energy = sum(1 for i in self.impacts if i["printed_creates_energy"] is True)
        return {
            "duration_s": duration,
            "mean_transport_velocity_m_s": ((self.final.r[:2] - self.start.r[:2]) / duration).tolist(),
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


def simulate(model: Model, num: Numerics, start: State, t_end: float, on_step=None) -> Motion:
    """Accurate mode from ``start`` to ``t_end``; the grain starts in flight (or on the plane at rest).

    ``on_step(t)``, if given, is called at every regime phase (progress, time budget, stagnation)."""
    model = model.active()
    rec = _Recorder(num.sample_interval)
    st = replace(start, r=np.array(start.r, float), v=np.array(start.v, float),
                 q=np.asarray(start.q, float) / np.linalg.norm(start.q), w=np.array(start.w, float))
    if not model.effects.rotation:
        st.w = np.zeros(3)
    time_in = dict.fromkeys(("flight", "sliding"), 0.0)
    impacts: list = []
    warnings: list = []
    regime = "flight"
    rec.add(st, regime)
    while st.t < t_end:
        if on_step is not None:
            on_step(st.t)
        if regime == "flight":
            t0 = st.t
            st, hit = _fly(model, num, st, t_end, rec)
            time_in["flight"] += st.t - t0
            if not hit:
                break
            if st.t == t0:
                # The grain never left the plane (a rocking body pressing on it): persistent contact.
                regime = "sliding"
                st = _land(model, st)
                continue
            if len(impacts) >= num.max_impacts:
                warnings.append(f"stopped at t = {st.t:.6g} s after numerics.max_impacts = {num.max_impacts} impacts")
                break
            before = st
            Q = flight.rotation_matrix(st.q)
            out = model.law.apply(np.array([model.axes]), np.array([model.mass]), Q[None], st.v[None],
                                  (Q @ st.w)[None], model.effects.rotation)
            warnings += out["warnings"]
            st = State(st.t, st.r, out["v"][0], st.q, Q.T @ out["w"][0])
            rec.add(before, "impact")
            rec.add(st, "impact")
            impacts.append(impact_record(st.t, before, st, out))
            if out["u_after"][0, 2] <= num.rest_velocity and model.sliding.normal(st.t) > 0:
                regime = "sliding"
                st = _land(model, st)
        else:
            t0 = st.t
            res = slide(model.sliding, st.t, st.r[:2], st.v[:2], t_end, rec.times(st.t, t_end), num.scan_step, num.tolerance)
            ts, rs, vs = res.samples
            n = len(ts)
            rec.add_many(ts, np.column_stack([rs, np.full(n, st.r[2])]), np.column_stack([vs, np.zeros(n)]),
                         np.tile(st.q, (n, 1)), np.zeros((n, 3)), "sliding")
            time_in["sliding"] += res.t - t0
            st = State(res.t, np.array([*res.r, st.r[2]]), np.array([*res.v, 0.0]), st.q, st.w)
            rec.add(st, "sliding")
            if res.lifted:
                regime = "flight"
    rec.add(st, regime)
    return Motion(np.array(rec.rows), impacts, time_in, _unique(warnings), start, st)


def _land(model: Model, st: State) -> State:
    """Start sliding: normal velocity and spin stop, the centre sits at the support height."""
    Q = flight.rotation_matrix(st.q)
    r = st.r.copy()
    r[2] = float(contact.support_distance(model.axes, Q))
    return State(st.t, r, np.array([st.v[0], st.v[1], 0.0]), st.q, np.zeros(3))


def _fly(model: Model, num: Numerics, st: State, t_end: float, rec: _Recorder):
    """Fly from ``st`` until the first contact (state at contact, True) or ``t_end`` (state, False)."""
    vib = model.vibration
    rotating = model.effects.rotation and np.any(st.w)
    rot = flight.RotationFlight(model.inertia, st.q, st.w, st.t, num.tolerance, model.period) if rotating else None

    def orient(t):
        if rotating:
            return rot.state(t)
        shape = np.shape(t)
        return np.broadcast_to(st.q, shape + (4,)), np.broadcast_to(st.w, shape + (3,))

    def gap(t):
        r, _ = flight.translate(st.r, st.v, model.g_k, vib, st.t, t)
        h = r[..., 2] - contact.support_distance(model.axes, flight.rotation_matrix(orient(t)[0]))
        return h if np.ndim(t) else float(h)

    tc = contact.first_root(gap, st.t, t_end, num.scan_step, num.tolerance * num.scan_step)
    t_stop = t_end if tc is None else tc
    ts = rec.times(st.t, t_stop)
    ts = np.append(ts[(ts > st.t) & (ts < t_stop)], t_stop)
    r, v = flight.translate(st.r, st.v, model.g_k, vib, st.t, ts)
    q, w = orient(ts)
    rec.add_many(ts[:-1], r[:-1], v[:-1], q[:-1], w[:-1], "flight")
    return State(t_stop, r[-1], v[-1], q[-1].copy(), w[-1].copy()), tc is not None


def _unique(items: list) -> list:
    return list(dict.fromkeys(items))
