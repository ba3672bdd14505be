"""Exact torque-free rotation of the grain and the closed-form contact gap of its free flight.

The rotation is Jacobi's solution, computed as Celledoni, Fassò, Säfström and Zanna (SIAM J. Sci. Comput.
30, 2008) do: the body angular momentum ``m = I w`` in Jacobi elliptic functions, the attitude a rotation
about the constant spatial angular momentum ``L`` (docs/grain-motion.md gives the derivation and names).
In the *Euler frame* (a, b, c), an even permutation of the body axes with ``c`` the axis the polhode
circles, and ``o`` / ``mid`` the other extreme / the middle axis:

- ``m_o = Mo cn(u)``, ``m_mid = Mmid sn(u)``, ``m_c = Mc dn(u)``, ``u = u0 + lam tau``, modulus ``k2``;
- the attitude ``Q(tau) = U Rz(phi(tau)) Rx(theta) Rz(psi) Pi``: ``theta``, ``psi`` are the z-x-z angles of
  ``m/|m|`` (closed form in ``m``), ``Pi`` the permutation, ``U`` fixed, and
  ``phi = M tau / I_c + C (Pi(n; am u) - Pi(n; am u0))``, an incomplete elliptic integral of the third kind
  (Carlson's R_F, R_J) with ``n <= 0``; a symmetric grain (``n = 0``) precesses regularly, ``phi = M tau/I_o``;
- a rotation about a fixed axis (a sphere, or ``w`` along a principal axis) is ``q0 (x) exp(w tau / 2)``.

Energy and angular momentum are constants of the closed form (exact to round-off). The Python side uses
scipy's ``ellipj``, ``ellipk``, ``elliprf``, ``elliprj``; the compiled twin is :mod:`symmech.grain.free_flight_nb`.

The gap of the flight, ``h(t) = z(t) - |D n(t)|`` with ``n = Q^T e_z`` (body axes) and ``D`` the semi-axes,
is closed form in ``t``, and so is its rate (:func:`gap_rate`); its curvature obeys a bound constant over the
flight (:func:`gap_curvature_bound`), which :func:`symmech.grain.contact.first_contact` uses so that no
grazing contact is missed.
"""
from __future__ import annotations

import math

import numpy as np

from symmech.core.layout import Field, Layout
from symmech.grain import flight

LADDER = 17  # the Landen ladder's slots: steps, scale and at most 15 ratios
# The compiled twin's records (float64 vectors), one per flight.
FLIGHT = Layout("FreeFlight", (
    Field("t0", "s", "start of the flight"),
    Field("r0", "m", "centre position relative to the surface at t0, KXYZ", (3,)),
    Field("v0", "m/s", "centre velocity relative to the surface at t0, KXYZ", (3,)),
    Field("g", "m/s^2", "gravity in KXYZ", (3,)),
    Field("amplitude", "m", "surface vibration amplitude"),
    Field("omega", "rad/s", "surface vibration angular frequency"),
    Field("phase", "rad", "surface phase at t0, reduced to [0, 2 pi)"),
    Field("direction", "1", "unit direction of the surface vibration", (3,)),
    Field("axes", "m", "semi-axes of the ellipsoid", (3,)),
))
ROTATION = Layout("FreeRotation", (
    Field("t0", "s", "start of the rotation"),
    Field("q0", "1", "attitude quaternion at t0", (4,)),
    Field("w0", "rad/s", "body angular velocity at t0", (3,)),
    Field("inertia", "kg m^2", "principal moments", (3,)),
    Field("fixed_axis", "1", "1: rotation about a fixed axis (sphere, or w0 along a principal axis)"),
    Field("frame", "1", "body axes a, b, c of the Euler frame (c: the axis the polhode circles)", (3,)),
    Field("o_first", "1", "1: a is the other extreme axis o, b the middle one; 0: the reverse"),
    Field("mo", "kg m^2/s", "amplitude of m_o = mo cn(u)"),
    Field("mmid", "kg m^2/s", "signed amplitude of m_mid = mmid sn(u)"),
    Field("mc", "kg m^2/s", "signed amplitude of m_c = mc dn(u)"),
    Field("lam", "1/s", "rate of the elliptic argument u"),
    Field("k2", "1", "elliptic parameter m = k^2"),
    Field("K", "1", "complete elliptic integral of the first kind K(k2)"),
    Field("n", "1", "characteristic of the third-kind integral (<= 0)"),
    Field("u0", "1", "elliptic argument at t0"),
    Field("momentum", "kg m^2/s", "|L|"),
    Field("precession", "rad/s", "C lam = |L| (I_c - I_o) / (I_c I_o)"),
    Field("pi_complete", "1", "complete third-kind integral Pi(n | k2)"),
    Field("pi0", "1", "Pi(n; am u0 | k2)"),
    Field("q_fixed", "1", "quaternion of U, the fixed rotation taking e_z to L", (4,)),
    Field("q_frame", "1", "quaternion of the permutation Pi, body to Euler frame", (4,)),
    Field("max_rate", "rad/s", "bound on |w| over the whole motion"),
    Field("landen", "1", "the descending Landen ladder of k2 that the compiled twin's ellipj_on walks back (steps N, "
                         "scale 2^N a_N, c_i / a_i); 0 in record(): scipy's ellipj needs none", (LADDER,)),
))


def even_frame(c: int) -> tuple:
    """The Euler frame's body axes (a, b, c): the even permutation of (0, 1, 2) ending in ``c``."""
    return (c + 1) % 3, (c + 2) % 3, c


def circled_axis(inertia, m) -> int:
    """The body axis the polhode of momentum ``m`` (3,) circles: the largest moment when ``|m|^2 > 2 E I_mid``,
    else the smallest; the distinct axis of a symmetric body. ``inertia`` (3,) kg m^2."""
    lo, mid, hi = np.argsort(inertia, kind="stable")
    if inertia[lo] == inertia[mid]:
        return int(hi)
    if inertia[mid] == inertia[hi]:
        return int(lo)
    # sign of |m|^2 - 2 E I_mid summed without cancellation
    excess = sum(m[i] ** 2 * (inertia[i] - inertia[mid]) / inertia[i] for i in range(3))
    return int(hi) if excess > 0 else int(lo)


def _quaternion_product(p, q):
    """Hamilton product of quaternions (..., 4) (scalar first)."""
    p0, p1, p2, p3 = np.moveaxis(p, -1, 0)
    q0, q1, q2, q3 = np.moveaxis(q, -1, 0)
    return np.stack([p0 * q0 - p1 * q1 - p2 * q2 - p3 * q3, p0 * q1 + p1 * q0 + p2 * q3 - p3 * q2,
                     p0 * q2 - p1 * q3 + p2 * q0 + p3 * q1, p0 * q3 + p1 * q2 - p2 * q1 + p3 * q0], axis=-1)


def incomplete_third_kind(n, phi, k2):
    """Legendre's Pi(n; phi | k2) for |phi| <= pi/2 (Carlson: s R_F + n s^3 R_J / 3), any array shapes."""
    from scipy.special import elliprf, elliprj

    s, c = np.sin(phi), np.cos(phi)
    delta = 1.0 - k2 * s * s
    return s * elliprf(c * c, delta, 1.0) + n / 3.0 * s**3 * elliprj(c * c, delta, 1.0, 1.0 - n * s * s)


class ExactRotation:
    """Torque-free rotation from quaternion ``q0`` (4,) and body angular velocity ``w0`` (3,) rad/s at ``t0`` [s]
    of a body with principal moments ``inertia`` (3,) kg m^2; ``state(t)`` at any time, no integration."""

    def __init__(self, inertia, q0, w0, t0: float):
        from scipy.special import ellipk

        self.inertia = np.asarray(inertia, dtype=float)
        self.q0 = np.asarray(q0, dtype=float) / np.linalg.norm(q0)
        self.w0 = np.asarray(w0, dtype=float)
        self.t0 = float(t0)
        I, m = self.inertia, self.inertia * self.w0
        self.momentum = float(np.linalg.norm(m))
        self.fixed_axis = bool(np.all(np.cross(self.w0, m) == 0.0) or I[0] == I[1] == I[2])
        # |w| <= sqrt(2 E / I_min) and |w| <= |m| / I_min along the whole motion
        self.max_rate = float(min(math.sqrt(float(m @ self.w0) / I.min()), self.momentum / I.min()))
        if self.fixed_axis:
            return
        c = circled_axis(I, m)
        self.frame = np.array(even_frame(c))
        Ia, Ib, Ic = I[self.frame]
        o_first = abs(Ia - Ic) > abs(Ib - Ic) if Ia != Ib else True  # o: the other extreme moment
        o, mid = (self.frame[0], self.frame[1]) if o_first else (self.frame[1], self.frame[0])
        self.o_first = o_first
        Io, Imid = I[o], I[mid]
        d_c = sum(m[i] ** 2 * (Ic - I[i]) / I[i] for i in range(3) if i != c)  # 2 E I_c - M^2
        d_o = sum(m[i] ** 2 * (I[i] - Io) / I[i] for i in range(3) if i != o)  # M^2 - 2 E I_o
        self.lam = math.sqrt((Ic - Imid) * d_o / (Io * Imid * Ic))
        self.k2 = min((Imid - Io) * d_c / ((Ic - Imid) * d_o), 1.0 - 2.0**-52) if Imid != Io else 0.0
        sign_c = 1.0 if m[c] >= 0 else -1.0
        parity = 1.0 if o_first else -1.0
        self.mo = math.sqrt(Io * d_c / (Ic - Io))
        self.mmid = parity * math.copysign(1.0, Ic - Io) * sign_c * math.sqrt(Imid * d_c / (Ic - Imid))
        self.mc = sign_c * math.sqrt(Ic * d_o / (Ic - Io))
        self.n = Ic * (Io - Imid) / (Io * (Ic - Imid))
        self.K = float(ellipk(self.k2))
        self.u0 = self._argument(m[mid] / self.mmid if self.mmid else 0.0, m[o] / self.mo if self.mo else 1.0)
        self.precession = self.momentum * (Ic - Io) / (Ic * Io)  # C lam
        self.pi_complete = float(incomplete_third_kind(self.n, np.pi / 2, self.k2))
        self.pi0 = float(self._elliptic(np.asarray(self.u0))[3])  # Pi(n; am u0): phi(0) = 0
        q_tilt = self._tilt(self._euler(np.zeros(()))[0])
        # U = Q0 Pi^T (Rx Rz)^T (phi = 0 at t0): the fixed rotation taking e_z to L
        self.q_frame = self._permutation_quaternion()
        conj = np.array([1.0, -1.0, -1.0, -1.0])
        self.q_fixed = _quaternion_product(_quaternion_product(self.q0, self.q_frame * conj), q_tilt * conj)

    def record(self) -> np.ndarray:
        """The constants as a :data:`ROTATION` vector: what the compiled twin's ``rotation_setup`` writes, but its
        own Landen ladder (zeros here)."""
        values = {"t0": self.t0, "q0": self.q0, "w0": self.w0, "inertia": self.inertia,
                  "fixed_axis": float(self.fixed_axis), "max_rate": self.max_rate}
        if self.fixed_axis:
            rest = {f.name: np.zeros(f.shape) for f in ROTATION.fields if f.name not in values}
        else:
            rest = {"frame": self.frame.astype(float), "o_first": float(self.o_first), "q_fixed": self.q_fixed,
                    "q_frame": self.q_frame, "landen": np.zeros(LADDER), **{name: getattr(self, name) for name in (
                        "mo", "mmid", "mc", "lam", "k2", "K", "n", "u0", "momentum", "precession",
                        "pi_complete", "pi0")}}
        return ROTATION.pack(**values, **rest)

    def _argument(self, sn0, cn0) -> float:
        """u0 with sn(u0) = sn0, cn(u0) = cn0: Legendre's F(am) (Carlson's R_F), continued past +-pi/2."""
        from scipy.special import elliprf

        am = math.atan2(sn0, cn0)
        folded = math.copysign(math.pi, am) - am if abs(am) > math.pi / 2 else am
        s, c = math.sin(folded), math.cos(folded)
        f = s * float(elliprf(c * c, 1.0 - self.k2 * s * s, 1.0))
        return math.copysign(2.0 * self.K, am) - f if abs(am) > math.pi / 2 else f

    def _elliptic(self, u):
        """sn, cn, dn of ``u`` (...,) and Pi(n; am u | k2), the argument reduced to |u| <= K first
        (u = ur + 2 K j: am(u) = am(ur) + j pi, sn and cn change sign with j)."""
        from scipy.special import ellipj

        j = np.floor((u + self.K) / (2.0 * self.K))
        sn, cn, dn, am = ellipj(u - 2.0 * self.K * j, self.k2)
        flip = 1.0 - 2.0 * np.mod(j, 2.0)
        third = 2.0 * j * self.pi_complete + incomplete_third_kind(self.n, am, self.k2) if self.n else 0.0 * u
        return sn * flip, cn * flip, dn, third

    def _euler(self, tau):
        """Momentum in the Euler frame (..., 3) [kg m^2/s] and the angle phi (...,) [rad] at ``tau = t - t0``."""
        sn, cn, dn, third = self._elliptic(self.u0 + self.lam * tau)
        m_o, m_mid, m_c = self.mo * cn, self.mmid * sn, self.mc * dn
        m_ab = (m_o, m_mid) if self.o_first else (m_mid, m_o)
        if self.n == 0.0:  # symmetric: regular precession about L
            phi = self.momentum * tau / self.inertia[self.frame[0 if self.o_first else 1]]
        else:
            phi = self.momentum * tau / self.inertia[self.frame[2]] + self.precession / self.lam * (third - self.pi0)
        return np.stack([*m_ab, m_c], axis=-1), phi

    def _tilt(self, m):
        """Quaternion (..., 4) of Rx(theta) Rz(psi), the z-x-z angles of m (..., 3) in the Euler frame."""
        M = self.momentum
        rho = np.hypot(m[..., 0], m[..., 1])
        up = m[..., 2] >= 0
        big = np.sqrt((M + np.abs(m[..., 2])) / (2 * M))
        small = rho / (2 * M * big)
        ct2, st2 = np.where(up, big, small), np.where(up, small, big)
        half = 0.5 * np.arctan2(m[..., 0], m[..., 1])
        cp2, sp2 = np.cos(half), np.sin(half)
        return np.stack([ct2 * cp2, st2 * cp2, -st2 * sp2, ct2 * sp2], axis=-1)

    def _permutation_quaternion(self) -> np.ndarray:
        """Quaternion of Pi, body axes to the Euler frame's: row j picks body axis ``frame[j]``."""
        P = np.zeros((3, 3))
        P[[0, 1, 2], self.frame] = 1.0
        return flight.quaternion_from_matrix(P)

    def state(self, t):
        """(q (..., 4), w (..., 3) rad/s in body axes) at times ``t`` [s] (scalar or array)."""
        tau = np.asarray(t, dtype=float) - self.t0
        if self.fixed_axis:
            rate = float(np.linalg.norm(self.w0))
            axis = self.w0 / rate if rate else self.w0
            half = 0.5 * rate * tau[..., None]
            turn = np.concatenate([np.cos(half), np.sin(half) * axis], axis=-1)
            return _quaternion_product(self.q0, turn), np.broadcast_to(self.w0, tau.shape + (3,)).copy()
        m_frame, phi = self._euler(tau)
        about_l = np.stack([np.cos(phi / 2), 0 * phi, 0 * phi, np.sin(phi / 2)], axis=-1)
        q = _quaternion_product(_quaternion_product(_quaternion_product(self.q_fixed, about_l),
                                                    self._tilt(m_frame)), self.q_frame)
        m = np.empty_like(m_frame)
        m[..., self.frame] = m_frame
        return q, m / self.inertia


def gap_rate(vz, axes, n, w):
    """The gap's rate h' [m/s] (...,): centre's relative normal velocity ``vz`` (...,) [m/s] less the support
    distance's rate (D^2 n).(n x w)/|D n|; ``n`` (..., 3) body components of e_z, ``w`` (..., 3) body rate."""
    d2n = np.square(axes) * n
    return vz - np.sum(d2n * np.cross(n, w), axis=-1) / np.sqrt(np.sum(d2n * n, axis=-1))


def gap_curvature_bound(g_z: float, vibration: flight.Vibration, axes, inertia, max_rate: float) -> float:
    """Bound [m/s^2] on |h''| over the whole flight (docs/grain-motion.md): |z''| <= |g_z| + A omega^2 |d_z|
    and |s''| <= (a_max^2 / a_min + a_max (1 + I_max / I_min)) |w|max^2 (0 for a sphere: s = a)."""
    vib = vibration
    a_max, a_min = max(axes), min(axes)
    spin = (a_max**2 / a_min + a_max * (1.0 + max(inertia) / min(inertia))) * max_rate**2 if a_max > a_min else 0.0
    return abs(g_z) + vib.amplitude * vib.omega**2 * abs(vib.direction[2]) + spin
