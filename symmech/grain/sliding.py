"""Sliding regime: the grain stays on the plane and slides with Coulomb friction.

The paper defers this regime to another work; this is our model. While sliding,
the grain keeps the orientation it landed with and does not rotate (the impact
that could not lift it off is taken to have stopped its spin; rocking and rolling
of the ellipsoid are not modelled), so its centre stays at the support height
and only the tangential motion (x, y) evolves. Per unit mass, in KXYZ:

  normal force     n(t) = a_sZ(t) - g_Z                      (>= 0 while on the plane)
  driving force    f(t) = g_t - a_s,t(t)                     (tangential, (2,))
  slip             v' = f - mu n v/|v|
  stick            v = 0 while |f| <= mu n; slip starts in the direction of f when |f| > mu n
                   (below the slip-speed resolution v_eps, friction holds min(mu n, |f|))

The grain leaves the plane (flight with zero relative normal velocity) when
``n(t)`` would become negative. With the friction effect off (mu = 0) the
tangential motion is the exact free motion of the flight module.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from symmech.grain import flight
from symmech.grain.contact import first_root


@dataclass(frozen=True)
class Sliding:
    """Forces on a sliding grain: gravity ``g_k`` (3,) m/s^2, surface ``vibration``, friction coefficient ``mu``."""

    g_k: tuple
    vibration: flight.Vibration
    mu: float

    def normal(self, t):
        """Normal force per unit mass n(t) (...,) [m/s^2]."""
        return self.vibration.kinematics(t)[..., 2, 2] - self.g_k[2]

    def drive(self, t):
        """Tangential driving force per unit mass f(t) (..., 2) [m/s^2]."""
        return np.asarray(self.g_k[:2]) - self.vibration.kinematics(t)[..., 2, :2]

    def forces(self, t):
        """(f (..., 2), n (...,)) from one evaluation of the surface kinematics."""
        acc = self.vibration.kinematics(t)[..., 2, :]
        return np.asarray(self.g_k[:2]) - acc[..., :2], acc[..., 2] - self.g_k[2]

    def sticks(self, t) -> bool:
        return float(np.linalg.norm(self.drive(t))) <= self.mu * float(self.normal(t))


@dataclass
class SlideResult:
    """End of a sliding phase: time ``t`` [s], tangential position ``r`` (2,) m and velocity ``v`` (2,) m/s,
    ``lifted`` (left the plane at ``t``), and ``samples`` (times, r (n, 2), v (n, 2)) at the requested times."""

    t: float
    r: np.ndarray
    v: np.ndarray
    lifted: bool
    samples: tuple


def slide(model: Sliding, t0: float, r0, v0, t_end: float, sample_times, step: float, tol: float) -> SlideResult:
    """Accurate sliding from ``(r0, v0)`` (2,) at ``t0`` until lift-off or ``t_end``.

    Events (lift-off, stick, slip onset) are roots located with ``first_root`` /
    solve_ivp events to ``tol`` (relative; times to ``tol * step``).
    """
    xtol = tol * step
    t_lift = first_root(model.normal, t0, t_end, step, xtol) if model.normal(t0) > 0 else t0
    t_stop = t_end if t_lift is None else t_lift
    r, v, t = np.asarray(r0, dtype=float), np.asarray(v0, dtype=float), t0
    sample_times = np.asarray(sample_times, dtype=float)
    out_t, out_r, out_v = [], [], []
    # Velocity gained over one scan step: the scale of the slip-speed resolution and of atol.
    v_scale = (float(np.linalg.norm(model.drive(t0))) + abs(model.g_k[2])) * step
    v_eps = tol * v_scale
    atol = tol * v_scale * np.array([step, step, 1.0, 1.0])
    while t < t_stop:
        take = sample_times[(sample_times >= t) & (sample_times < t_stop)]
        if model.mu == 0.0:
            g3 = np.array([*model.g_k[:2], 0.0])
            rs, vs = flight.translate(np.append(r, 0.0), np.append(v, 0.0), g3, model.vibration, t, take)
            out_t.append(take), out_r.append(rs[..., :2]), out_v.append(vs[..., :2])
            re, ve = flight.translate(np.append(r, 0.0), np.append(v, 0.0), g3, model.vibration, t, t_stop)
            r, v, t = re[:2], ve[:2], t_stop
        elif np.linalg.norm(v) <= v_eps and model.sticks(t):
            t_slip = first_root(lambda s: model.mu * model.normal(s) - np.linalg.norm(model.drive(s), axis=-1),
                                t, t_stop, step, xtol)
            t_next = t_stop if t_slip is None else t_slip
            if t_next <= t:  # on the verge of slipping: start now
                t, r, v = _slip(model, t, r, v, t_stop, take, v_eps, tol, atol, out_t, out_r, out_v)
                continue
            take = take[take < t_next]
            out_t.append(take), out_r.append(np.tile(r, (take.size, 1))), out_v.append(np.zeros((take.size, 2)))
            v, t = np.zeros(2), t_next
        else:
            t, r, v = _slip(model, t, r, v, t_stop, take, v_eps, tol, atol, out_t, out_r, out_v)
    samples = tuple(np.concatenate(x) if x else np.zeros((0,) + s) for x, s in
                    ((out_t, ()), (out_r, (2,)), (out_v, (2,))))
    return SlideResult(t, r, v, t_lift is not None and t >= t_lift, samples)


def _slip(model: Sliding, t, r, v, t_stop, take, v_eps, tol, atol, out_t, out_r, out_v):
    """Integrate slipping until the slip speed drops to ``v_eps`` (then stick or reverse) or ``t_stop``."""

    def rhs(s, y):
        vel = y[2:]
        f, n = model.forces(s)
        speed = np.hypot(*vel)
        if speed > v_eps:
            return np.concatenate([vel, f - model.mu * n * vel / speed])
        # At (numerically) zero slip, static friction holds as much of f as it can.
        fn = np.hypot(*f)
        return np.concatenate([vel, f * (1.0 - min(model.mu * n, fn) / max(fn, 1e-300))])

    def stops(_s, y):
        return np.hypot(*y[2:]) - v_eps
    stops.terminal, stops.direction = True, -1

    sol = solve_ivp(rhs, (t, t_stop), np.concatenate([r, v]), method="DOP853", rtol=tol,
                    atol=atol, events=stops, dense_output=True)
    if not sol.success:
        raise RuntimeError(f"sliding integration failed: {sol.message}")
    t_end = sol.t[-1]
    take = take[take <= t_end]
    if take.size:
        y = sol.sol(take)
        out_t.append(take), out_r.append(y[:2].T), out_v.append(y[2:].T)
    y = sol.y[:, -1]
    v = y[2:] if sol.status == 0 else np.zeros(2)
    # A zero speed that does not stick restarts slipping along the driving force.
    if sol.status == 1 and not model.sticks(t_end):
        v = np.zeros(2)
        t_end = np.nextafter(t_end, np.inf)
    return t_end, y[:2], v


def slide_step(model: Sliding, t, v, dt: float):
    """Paper-mode explicit step of the tangential velocity for many grains: v (n, 2) -> (n, 2).

    A slip velocity that would reverse within the step, with ``|f| <= mu n``, sticks (v = 0).
    """
    f = model.drive(t)
    n = model.normal(t)
    speed = np.linalg.norm(v, axis=-1, keepdims=True)
    fnorm = np.linalg.norm(f)
    direction = np.where(speed > 0, v / np.where(speed > 0, speed, 1.0), f / max(fnorm, 1e-300))
    v_new = v + (f - model.mu * n * direction) * dt
    stick = (np.einsum("ij,ij->i", v_new, direction) <= 0) & (fnorm <= model.mu * n)
    return np.where(stick[:, None], 0.0, v_new)
