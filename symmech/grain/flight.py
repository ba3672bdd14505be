"""Flight of the grain between contacts, in the vibrating surface frame KXYZ.

Translation is exact: ``r'' = g_K - s''(t)`` integrated in closed form
(generated ``grain_motion.flight_translation``; the ``_rigid`` variant when the
vibration effect is off), evaluated in the local time ``t - t0`` from the last
event with the surface phase at ``t0`` reduced to [0, 2 pi): the expanded
absolute-time form cancels terms of size ``g t^2`` and loses ~1e-8 m at t = 1e4 s.
Rotation is torque-free: body angular velocity ``w``
(3,) rad/s obeys Euler's equations and the orientation is a unit quaternion
``q`` (4,) (no Euler-angle singularity); both are integrated to a tolerance with
DOP853 and dense output. Angular momentum ``Q I w`` and energy ``w.I w/2`` are
conserved by the exact motion; the tests measure the drift.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from symmech.generated import grain_motion as gm
from symmech.grain.vectors import ROTATION

# a flight's rotation state is ROTATION (the compiled engine's too): the slots of q and w
RO_Q, RO_W = ROTATION.slice("q"), ROTATION.slice("w")


@dataclass(frozen=True)
class Vibration:
    """Harmonic surface displacement ``s(t) = A d sin(omega t + phase)``; ``d`` (3,) unit vector in KXYZ."""

    amplitude: float
    omega: float
    phase: float
    direction: tuple

    def kinematics(self, t):
        """Rows displacement [m], velocity [m/s], acceleration [m/s^2] at ``t`` (...,) -> (..., 3, 3)."""
        return gm.surface_kinematics(self.amplitude, self.omega, self.phase, *self.direction, t)

    @property
    def off(self) -> bool:
        return self.amplitude == 0.0

    @property
    def period(self) -> float:
        """Vibration period [s], or 1 s when the surface does not vibrate (a time scale only)."""
        return 2 * np.pi / self.omega if not self.off else 1.0

    def phase_at(self, t):
        """Surface phase ``omega t + phase`` reduced to [0, 2 pi) [rad]."""
        return np.mod(self.omega * np.asarray(t, dtype=float) + self.phase, 2 * np.pi)


def translate(r0, v0, g_k, vib: Vibration, t0, t):
    """Relative centre position and velocity at ``t`` from ``(r0, v0)`` at ``t0``: two (..., 3) arrays [m, m/s]."""
    cols = [c for x in (r0, v0, g_k) for c in np.moveaxis(np.asarray(x, dtype=float), -1, 0)]
    tau = np.asarray(t, dtype=float) - t0
    if vib.off:
        out = gm.flight_translation_rigid(*cols, 0.0, tau)
    else:
        out = gm.flight_translation(*cols, vib.amplitude, vib.omega, vib.phase_at(t0),
                                    *vib.direction, 0.0, tau)
    return out[..., 0, :], out[..., 1, :]


def rotation_matrix(q):
    """Q (..., 3, 3) of quaternions ``q`` (..., 4); body axes as columns in KXYZ."""
    q = np.asarray(q, dtype=float)
    return gm.rotation_matrix(q[..., 0], q[..., 1], q[..., 2], q[..., 3])


def quaternion_from_matrix(Q) -> np.ndarray:
    """Unit quaternion (4,) with positive scalar part for a rotation matrix Q (3, 3) (Shepperd's method)."""
    Q = np.asarray(Q, dtype=float)
    tr = np.trace(Q)
    k = int(np.argmax([tr, Q[0, 0], Q[1, 1], Q[2, 2]]))
    if k == 0:
        s = 2.0 * np.sqrt(1.0 + tr)
        q = [s / 4, (Q[2, 1] - Q[1, 2]) / s, (Q[0, 2] - Q[2, 0]) / s, (Q[1, 0] - Q[0, 1]) / s]
    else:
        i, j, m = (k - 1), k % 3, (k + 1) % 3
        s = 2.0 * np.sqrt(1.0 + Q[i, i] - Q[j, j] - Q[m, m])
        q = np.empty(4)
        q[0] = (Q[m, j] - Q[j, m]) / s
        q[1 + i] = s / 4
        q[1 + j] = (Q[j, i] + Q[i, j]) / s
        q[1 + m] = (Q[m, i] + Q[i, m]) / s
    q = np.asarray(q, dtype=float)
    return q if q[0] >= 0 else -q


class RotationFlight:
    """Torque-free rotation from ``(q0, w0)`` at ``t0``, evaluated at any later time to tolerance ``tol``.

    Integrates ``q' = q (x) (0, w)/2``, ``I w' = -w x I w`` with DOP853 in chunks
    of ``chunk`` seconds, keeping dense output. ``inertia`` (3,) kg m^2 principal
    moments; ``w0`` (3,) rad/s in body axes.
    """

    def __init__(self, inertia, q0, w0, t0: float, tol: float, chunk: float):
        self.inertia = np.asarray(inertia, dtype=float)
        self.tol = tol
        self.chunk = chunk
        self.t0 = t0
        self._pieces: list = []  # (t_start, t_end, dense)
        self._end = t0
        self._y_end = ROTATION.pack(q=q0, w=w0)
        self.static = not np.any(w0)

    def _rhs(self, _t, y):
        q, w = y[RO_Q], y[RO_W]
        return np.concatenate([gm.quaternion_rate(*q, *w), gm.euler_equations(*self.inertia, *w)])

    def _extend(self, t: float) -> None:
        from scipy.integrate import solve_ivp  # here, not at import: a compiled run never loads scipy

        while self._end < t:
            t_next = max(t, self._end + self.chunk)
            sol = solve_ivp(self._rhs, (self._end, t_next), self._y_end, method="DOP853",
                            rtol=self.tol, atol=self.tol * 1e-3, dense_output=True)
            if not sol.success:
                raise RuntimeError(f"torque-free rotation did not integrate: {sol.message}")
            self._pieces.append((self._end, t_next, sol.sol))
            self._end, self._y_end = t_next, sol.y[:, -1]

    def state(self, t):
        """(q (..., 4), w (..., 3)) at times ``t >= t0`` (scalar or array); q renormalised."""
        t = np.asarray(t, dtype=float)
        if self.static:
            q, w = self._y_end[RO_Q], self._y_end[RO_W]
            return np.broadcast_to(q, t.shape + q.shape).copy(), np.broadcast_to(w, t.shape + w.shape).copy()
        self._extend(float(t.max()))
        if not self._pieces:  # asked at t0 only, before the first chunk (no piece would fill y): the start state
            return (np.broadcast_to(self._y_end[RO_Q], t.shape + (4,)).copy(),
                    np.broadcast_to(self._y_end[RO_W], t.shape + (3,)).copy())
        y = np.empty((ROTATION.size,) + t.shape)
        for start, end, dense in self._pieces:
            inside = (t >= start) & (t <= end)
            if inside.any():
                y[:, inside] = dense(t[inside])
        y = np.moveaxis(y, 0, -1)
        q = y[..., RO_Q] / np.linalg.norm(y[..., RO_Q], axis=-1, keepdims=True)
        return q, y[..., RO_W]


def bounces(v0: float, e: float, g: float, v_rest: float, span: float) -> float:
    """Bounces of a sequence launched at ``v0`` [m/s] off a still surface with restitution ``e`` under the normal
    gravity ``g`` [m/s^2], until the contact leaves slower than ``v_rest`` [m/s] or ``span`` [s] ends (the estimate
    of a run's impacts)."""
    if v0 <= v_rest or e == 0.0:
        return 1.0
    count = math.log(v_rest / v0) / math.log(e) if e < 1.0 else math.inf
    # k bounces last 2 v0 (1 - e^k) / (g (1 - e)); a sequence longer than span is cut there.
    fits = 1.0 - span * g * (1.0 - e) / (2.0 * v0)
    if fits > 0.0:
        count = min(count, math.log(fits) / math.log(e) if e < 1.0 else span * g / (2.0 * v0))
    return 1.0 + count
