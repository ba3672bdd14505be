"""Sliding regime: the grain stays on the plane and slides or rolls with Coulomb friction.

The paper defers this regime to another work; this is our model. Per unit mass,
in KXYZ, with the contact force ``(phi, n)`` (tangential, normal) acting at the
contact offset ``R`` from the centre:

  normal force     n(t) = a_sZ(t) - g_Z                      (>= 0 while on the plane)
  driving force    f(t) = g_t - a_s,t(t)                     (tangential, (2,))
  centre           v' = f + phi
  spin             w' = M (R x (phi, n))                     (w (3,) rad/s in KXYZ)
  contact slip     s = v + (w x R)_t,   s' = f + c + B phi,  B = (E - [R]x M [R]x)_tt

The mobility ``M`` (m times the inverse inertia, 1/m^2) says which rotations keep
the contact: a sphere rolls about any axis (``M = m I^-1``); any other ellipsoid
keeps its support height only when it turns about the normal (``M = m e_z e_z^T /
I_zz``; the tilting couples are workless constraint reactions, rocking is not
modelled); with the rotation effect off ``M = 0`` (a point mass). ``c`` is the
slip acceleration of a contact point carried round by the spin about the normal.

  slip   phi = -mu n s/|s|
  stick  phi = -B^-1 (f + c) while |phi| <= mu n (rolling without slip)

Regime changes are events of the integration located by root finding: the slip
speed reaching ``v_stop`` (then the remaining slip is removed by a friction
impulse, booked as sliding loss, and the contact sticks or slips on through zero),
the stick force reaching the friction cone, and lift-off (``n(t)`` reaching zero).
A slip starts where the stick force leaves the cone, against that force: along
``B^-1 (f + c)``, the one direction in which the friction force stays continuous
(``f + c`` itself only for an isotropic ``B``, a sphere). Along the way the work of
the surface on the grain and the energy dissipated by friction are integrated as
two quadrature states.

Stiffness: slipping, the friction force turns the slip direction back at a rate
``mu n |B| / |s|``; where ``B`` is anisotropic (an ellipsoid whose contact point is
off the vertical through its centre: ``B = E + (m / I_zz) rho rho^T``, ``rho`` the
horizontal offset turned by 90 degrees) the friction force also drives the slip
off its direction, so every slip that starts or stops at a speed near ``v_stop``
(~1e-11 m/s) is stiff by a factor ~1e11 and an explicit method stalls. Such a slip
is integrated with Radau (implicit, order 5) while its speed is below ``s_stiff =
tol^(1/2) v_scale`` (where DOP853's stability limit ~ |s| / (mu n |B|) binds; the
power is measured), with DOP853 above ``2 s_stiff`` (the switch is an event, the
band a hysteresis); stick phases, spheres and point masses always with DOP853.
This loop takes scipy's Radau; the compiled engine's holds its step after a Newton
failure (RADAU5's rule), so their stiff slips take different steps, within the tolerance.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from symmech.core import kinematics as kin
from symmech.core.scene import SymmechError
from symmech.grain import contact, flight, outcome
from symmech.grain.contact import first_root
from symmech.grain.vectors import SLIDE_STATE

# the state of a sliding phase is SLIDE_STATE (the compiled engine's too): its fields' slots
Z_R, Z_V, Z_W, Z_Q = (SLIDE_STATE.slice(name) for name in ("r", "v", "w", "q"))
Z_WORK, Z_LOSS = SLIDE_STATE.offset("work"), SLIDE_STATE.offset("loss")

MAX_RHS_PER_PHASE = 400_000  # step-count guard: right-hand sides per integration chunk
MAX_STALLED_EVENTS = 200  # stagnation guard: consecutive events that do not advance time
SLIP_STIFF_POWER = 0.5  # s_stiff = tol^power v_scale, measured (benchmarks/bench_grain_hard.py)


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

    def surface(self, t: float):
        """Surface velocity (3,) [m/s] and acceleration (3,) [m/s^2] at one time (scalar fast path)."""
        vib = self.vibration
        p = vib.omega * t + vib.phase
        d = np.asarray(vib.direction)
        return vib.amplitude * vib.omega * math.cos(p) * d, -vib.amplitude * vib.omega**2 * math.sin(p) * d


@dataclass(frozen=True)
class Body:
    """The sliding grain: semi-axes ``axes`` (3,) m, ``mass`` kg, principal ``inertia`` (3,) kg m^2, ``rotation``."""

    axes: tuple
    mass: float
    inertia: tuple
    rotation: bool

    @property
    def sphere(self) -> bool:
        return max(self.axes) == min(self.axes)

    def mobility(self, Q) -> np.ndarray:
        """M (3, 3) [1/m^2]: spin acceleration per unit torque per unit mass, for orientation Q (3, 3)."""
        if not self.rotation:
            return np.zeros((3, 3))
        if self.sphere:
            return self.mass / self.inertia[0] * np.eye(3)
        i_zz = float(Q[2] @ (np.asarray(self.inertia) * Q[2]))
        return np.diag([0.0, 0.0, self.mass / i_zz])

    def kinetic(self, Q, v, w) -> float:
        """Kinetic energy per unit mass [J/kg] of centre velocity v (3,) and spin w (3,) in KXYZ."""
        wb = Q.T @ w
        return 0.5 * float(v @ v) + 0.5 * float(wb @ (np.asarray(self.inertia) * wb)) / self.mass


@dataclass
class SlideResult:
    """End of a sliding phase: time ``t`` [s], tangential position ``r`` (2,) m and velocity ``v`` (2,) m/s,
    spin ``w`` (3,) rad/s in KXYZ, orientation ``q`` (4,), ``lifted`` (left the plane at ``t``), surface work
    ``work`` and friction loss ``dissipated`` [J], ``samples`` (times, r (n, 2), v (n, 2), q (n, 4), w (n, 3))."""

    t: float
    r: np.ndarray
    v: np.ndarray
    w: np.ndarray
    q: np.ndarray
    lifted: bool
    work: float
    dissipated: float
    samples: tuple


class _Contact:
    """Right-hand side, slip and stick force of the sliding ODE y = (r (2), v (2), w (3), q (4), W, D)."""

    def __init__(self, model: Sliding, body: Body, q0):
        self.model, self.body = model, body
        Q0 = flight.rotation_matrix(q0)
        self.R0 = contact.contact_offset(body.axes, Q0)
        # Turning about the normal keeps the body-frame normal, hence the body-frame contact point
        # (a sphere's contact point stays below the centre whatever it turns).
        self.R_body = None if body.sphere else Q0.T @ self.R0
        self.M = body.mobility(Q0)
        self.g = np.asarray(model.g_k, dtype=float)
        self.nfev = 0
        # Turning about the normal keeps |R_t|, hence the anisotropy of B, for the whole phase.
        eig = np.linalg.eigvalsh(self.B(self.R0))
        self.stiff_slip = bool(eig[1] - eig[0] > 1e-12 * eig[1])

    def geometry(self, y):
        """Contact offset R (3,), slip s (2,), slip acceleration of the carried contact point c (2,)."""
        w = y[Z_W]
        R = self.R0 if self.R_body is None else _rotate(y[Z_Q], self.R_body)
        wR = _cross(w, R)
        s = y[Z_V] + wR[:2]
        # The contact point turns with the spin about the normal: R' = w_z e_z x R.
        c = _cross(w, (-w[2] * R[1], w[2] * R[0], 0.0))[:2]
        return R, s, c

    def B(self, R) -> np.ndarray:
        Rx = kin.skew(R)
        return (np.eye(3) - Rx @ self.M @ Rx)[:2, :2]

    def stick_force(self, t, y):
        """(phi (2,) holding the slip at zero, n) at (t, y)."""
        _, acc = self.model.surface(t)
        R, _, c = self.geometry(y)
        f = self.g[:2] - acc[:2]
        return -np.linalg.solve(self.B(R), f + c), acc[2] - self.g[2]

    def slip_direction(self, t, y):
        """Direction (2,) in which a zero slip starts: against the stick force, along B^-1 (f + c)."""
        _, acc = self.model.surface(t)
        R, _, c = self.geometry(y)
        d = np.linalg.solve(self.B(R), self.g[:2] - acc[:2] + c)
        return d / max(np.hypot(*d), 1e-300)

    def rhs(self, t, y, stick: bool):
        self.nfev += 1
        if self.nfev > MAX_RHS_PER_PHASE:
            raise SymmechError(outcome.sliding_evaluations_error(t, MAX_RHS_PER_PHASE))
        vel, acc = self.model.surface(t)
        R, s, c = self.geometry(y)
        n = acc[2] - self.g[2]
        f = self.g[:2] - acc[:2]
        if stick:
            phi = -np.linalg.solve(self.B(R), f + c)
        else:
            speed = math.hypot(s[0], s[1])
            phi = -self.model.mu * n / speed * s if speed > 0.0 else np.zeros(2)
        force = (phi[0], phi[1], n)
        w0, w1, w2 = y[Z_W]
        q0, q1, q2, q3 = y[Z_Q]
        dq = 0.5 * np.array([-w0 * q1 - w1 * q2 - w2 * q3, w0 * q0 + w1 * q3 - w2 * q2,
                             w1 * q0 + w2 * q1 - w0 * q3, w2 * q0 + w0 * q2 - w1 * q1])  # (0, w) (x) q
        return np.concatenate([y[Z_V], f + phi, self.M @ _cross(R, force), dq,
                               [force[0] * vel[0] + force[1] * vel[1] + n * vel[2], -(phi[0] * s[0] + phi[1] * s[1])]])


def _cross(a, b) -> np.ndarray:
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _rotate(q, v) -> np.ndarray:
    """Vector v (3,) rotated by the quaternion q (4,) (normalised on the fly)."""
    u = q[1:]
    t = 2.0 * _cross(u, v)
    return v + (q[0] * t + _cross(u, t)) / float(q @ q)


def slide(model: Sliding, body: Body, t0: float, r0, v0, q0, w0, t_end: float, sample_times, step: float,
          tol: float, progress=None) -> SlideResult:
    """Accurate sliding from position ``r0``, velocity ``v0`` (2,), orientation ``q0`` (4,) and spin ``w0`` (3,)
    (rad/s, KXYZ) at ``t0`` until lift-off or ``t_end``.

    Events are located to ``tol`` (relative; lift-off times to ``tol * step``). ``progress(t)`` is called
    between integration chunks of one vibration scan window (it may raise to stop the run).
    """
    t_lift = first_root(model.normal, t0, t_end, step, tol * step) if model.normal(t0) > 0 else t0
    t_stop = t_end if t_lift is None else t_lift
    ode = _Contact(model, body, q0)
    y = SLIDE_STATE.pack(r=r0, v=v0, w=w0, q=q0, work=0.0, loss=0.0)
    sample_times = np.asarray(sample_times, dtype=float)
    # Velocity gained over one scan step: the scale of the slip-speed resolution and of atol.
    v_scale = (float(np.linalg.norm(model.g_k)) + float(np.abs(model.normal(t0)))) * step
    v_stop = tol * v_scale
    a_min = min(body.axes)
    atol = tol * v_scale * SLIDE_STATE.pack(r=(step, step), v=(1, 1), w=(1 / a_min,) * 3, q=(1 / v_scale,) * 4,
                                            work=v_scale, loss=v_scale)
    chunk = 40 * step
    # Slip speed below which an anisotropic slip goes implicit: the friction's turning rate ~ mu n / |s| makes
    # DOP853 stability-bound there (measured: 1.2e-6 m/s at tol 1e-9 costs DOP853's time within ~30 % where
    # DOP853 does not stall; tol^(1/8) v_scale, 2.8e-3 m/s, costs up to twice as much).
    s_stiff = tol**SLIP_STIFF_POWER * v_scale
    from scipy.integrate import solve_ivp  # here, not at import: a compiled run never loads scipy

    pieces, t, stalled, implicit = [], t0, 0, False
    stick, y = _settle(ode, t, y, v_stop)
    while t < t_stop:
        implicit = ode.stiff_slip and not stick and model.mu > 0.0 and (
            math.hypot(*ode.geometry(y)[1]) < (2.0 if implicit else 1.0) * s_stiff)
        events = _events(ode, y, stick, v_stop, implicit, s_stiff)
        ode.nfev = 0
        sol = solve_ivp(ode.rhs, (t, min(t_stop, t + chunk)), y, method="Radau" if implicit else "DOP853",
                        rtol=tol, atol=atol, events=events, dense_output=True, args=(stick,))
        if not sol.success:
            raise SymmechError(outcome.integration_failed_error("sliding integration", t, sol.message))
        stalled = stalled + 1 if sol.t[-1] <= t else 0
        if stalled > MAX_STALLED_EVENTS:
            raise SymmechError(outcome.sliding_stalled_error(t, MAX_STALLED_EVENTS))
        pieces.append((t, sol.t[-1], sol.sol))
        t, y = sol.t[-1], sol.y[:, -1].copy()
        if sol.status == 1 and len(sol.t_events) > 1 and sol.t_events[1].size:
            implicit = not implicit  # the slip speed left the hysteresis band [s_stiff, 2 s_stiff]
        elif sol.status == 1:  # the stick force reached the cone (slip starts), or the slip speed v_stop
            stick, y = _settle(ode, t, y, v_stop, may_stick=not stick)
        if progress is not None:
            progress(t)
    samples = _samples(pieces, sample_times[(sample_times >= t0) & (sample_times < t)])
    return SlideResult(t, y[Z_R], y[Z_V], y[Z_W], y[Z_Q] / np.linalg.norm(y[Z_Q]), t_lift is not None and
                       t >= t_lift, body.mass * y[Z_WORK], body.mass * y[Z_LOSS], samples)


def _settle(ode: _Contact, t, y, v_stop, may_stick: bool = True):
    """At a slip speed within ``v_stop``: remove the slip by a friction impulse and, unless the contact sticks,
    start slipping at ``2 v_stop`` along :meth:`_Contact.slip_direction` (so the slip speed has to come back
    down through ``v_stop`` to stop again; a slip that starts from exactly zero could chatter about it). The
    impulses are of order ``v_stop``; their kinetic-energy change is booked in D. Returns (stick, y)."""
    R, s, _ = ode.geometry(y)
    if ode.model.mu == 0.0 or math.hypot(*s) > 1.5 * v_stop:
        return False, y
    phi, n = ode.stick_force(t, y)
    stick = may_stick and math.hypot(*phi) <= ode.model.mu * n
    target = np.zeros(2) if stick else 2.0 * v_stop * ode.slip_direction(t, y)
    y = y.copy()
    Q = flight.rotation_matrix(y[Z_Q])
    before = ode.body.kinetic(Q, np.append(y[Z_V], 0.0), y[Z_W])
    dphi = np.linalg.solve(ode.B(R), target - s)
    y[Z_V] += dphi
    y[Z_W] += ode.M @ np.cross(R, np.append(dphi, 0.0))
    y[Z_LOSS] += before - ode.body.kinetic(Q, np.append(y[Z_V], 0.0), y[Z_W])
    return stick, y


def _events(ode: _Contact, y, stick: bool, v_stop, implicit: bool, s_stiff):
    """Terminal events of one phase: the stick or slip regime ending and, for an anisotropic slip, the slip speed
    leaving the band where the integrator changes (rising through 2 s_stiff when implicit, falling through
    s_stiff when explicit). None without friction (no stick or slip regime to change)."""
    if ode.model.mu == 0.0:
        return None
    if stick:
        return [_stick_ends(ode, ode.model.mu)]
    if not ode.stiff_slip:
        return [_slip_stops(ode, y, v_stop)]

    def switch(_t, y, *_):
        return math.hypot(*ode.geometry(y)[1]) - (2.0 if implicit else 1.0) * s_stiff
    switch.terminal, switch.direction = True, 1 if implicit else -1
    return [_slip_stops(ode, y, v_stop), switch]


def _slip_stops(ode: _Contact, y0, v_stop):
    """Event: the slip, projected on its direction at the start of the phase, comes down to ``v_stop``.
    Signed, so a step that carries the slip through zero still brackets the root; a slip that merely turns
    away also fires it, and the phase restarts with the new direction."""
    s0 = ode.geometry(y0)[1]
    ref = s0 / max(math.hypot(*s0), 1e-300)

    def stops(_t, y, *_):
        return float(ode.geometry(y)[1] @ ref) - v_stop
    stops.terminal, stops.direction = True, -1
    return stops


def _stick_ends(ode: _Contact, mu):
    def ends(t, y, *_):
        phi, n = ode.stick_force(t, y)
        return mu * n - math.hypot(*phi)
    ends.terminal, ends.direction = True, -1
    return ends


def _samples(pieces, times):
    """(t (n,), r (n, 2), v (n, 2), q (n, 4), w (n, 3)) from the dense outputs at sorted ``times``."""
    y = np.empty((len(times), SLIDE_STATE.size))
    for a, b, dense in pieces:
        inside = (times >= a) & (times <= b)
        if inside.any():
            y[inside] = dense(times[inside]).T
    q = y[:, Z_Q] / np.linalg.norm(y[:, Z_Q], axis=1, keepdims=True) if len(times) else y[:, Z_Q]
    return times, y[:, Z_R], y[:, Z_V], q, y[:, Z_W]


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
