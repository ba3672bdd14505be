"""Layer 1: the grain-motion formulas (61)-(64) of paper 1 transcribed as printed.

Transcribed from the paper, symbols as printed:

(61)  x'_c(s) = x'_c + sum_k (x''_vb(t_k) - g sin(beta)) dt
      y'_c(s) = y'_c + sum_k (y''_vb(t_k) - g tg(alpha) cos(beta) cos(delta)) dt
      z'_c(s) = z'_c + sum_k (z''_vb(t_k) - g cos(delta)) dt
      x_c(s) = x_c(0) + sum_k x'_c(k) dt   (and y, z alike: the updated velocity is used)
(62)  theta(s) = theta(0) + theta' s dt, psi(s) = psi(0) + psi' s dt, phi(s) = phi(0) + phi' s dt
(63)  contact when z_c(s) <= |KC(s)|, K the surface node with the smallest z_k
(64)  lift-off after an impact when z'_c > 0

x''_vb etc. are the projections of the surface acceleration on KXYZ; delta is the
angle of steepest slope, alpha and beta the slopes of the longitudinal and
transverse axes. One step of (61) is emitted (the sums are these steps repeated).
"""
from __future__ import annotations

import sympy as sp

from symmech.core.derivation import ModuleSpec, NamedMatrix, args_of

ROLE = "printed"  # found by symmech.core.discovery

g = sp.Symbol("g", positive=True)
alpha, beta, delta, dt = sp.symbols("alpha beta delta dt", real=True)
vx, vy, vz, x, y, z = sp.symbols("vx vy vz x y z", real=True)
ax, ay, az = sp.symbols("ax_vb ay_vb az_vb", real=True)
th, ps, ph, th_d, ps_d, ph_d, s = sp.symbols("theta psi phi theta_d psi_d phi_d s", real=True)
zc, kx, ky, kz = sp.symbols("z_c KC_x KC_y KC_z", real=True)

_ANGLES = [(g, "gravitational acceleration", "m/s^2"),
           (alpha, "slope of the longitudinal axis (as printed)", "rad"),
           (beta, "slope of the transverse axis (as printed)", "rad"),
           (delta, "angle of steepest slope (as printed)", "rad")]


def gravity_printed() -> sp.Matrix:
    """The gravity terms of (61), as printed, (3,) m/s^2."""
    return sp.Matrix([-g * sp.sin(beta), -g * sp.tan(alpha) * sp.cos(beta) * sp.cos(delta),
                      -g * sp.cos(delta)])


def step_printed() -> sp.Matrix:
    """One step of (61): rows new velocity, new position (position uses the new velocity), (2, 3)."""
    v_new = sp.Matrix([vx, vy, vz]) + (sp.Matrix([ax, ay, az]) + gravity_printed()) * dt
    r_new = sp.Matrix([x, y, z]) + v_new * dt
    return sp.Matrix.vstack(v_new.T, r_new.T)


def euler_printed() -> sp.Matrix:
    """(62): Euler angles after s steps with the rates constant, (3,) rad, order theta, psi, phi."""
    return sp.Matrix([th + th_d * s * dt, ps + ps_d * s * dt, ph + ph_d * s * dt])


def contact_gap_printed() -> sp.Matrix:
    """(63) as a gap: z_c - |KC|; contact when <= 0, (1,) m."""
    return sp.Matrix([zc - sp.sqrt(kx**2 + ky**2 + kz**2)])


def module_specs() -> list[ModuleSpec]:
    state = [(vx, "relative velocity X", "m/s"), (vy, "relative velocity Y", "m/s"),
             (vz, "relative velocity Z", "m/s"), (x, "relative position X", "m"),
             (y, "relative position Y", "m"), (z, "relative position Z", "m"),
             (ax, "surface acceleration X at t_k", "m/s^2"), (ay, "surface acceleration Y at t_k", "m/s^2"),
             (az, "surface acceleration Z at t_k", "m/s^2")]
    functions = [
        NamedMatrix("gravity", gravity_printed(), args_of(_ANGLES),
                    "gravity terms of (61) as printed", "m/s^2", "61"),
        NamedMatrix("flight_step", step_printed(),
                    args_of(state + _ANGLES + [(dt, "time step", "s")]),
                    "one step of (61) as printed: new velocity, new position (rows)", "m/s, m", "61"),
        NamedMatrix("euler_angles", euler_printed(),
                    args_of([(th, "nutation angle at lift-off", "rad"), (ps, "precession angle at lift-off", "rad"),
                             (ph, "spin angle at lift-off", "rad"), (th_d, "nutation rate", "rad/s"),
                             (ps_d, "precession rate", "rad/s"), (ph_d, "spin rate", "rad/s"),
                             (s, "step number", "1"), (dt, "time step", "s")]),
                    "Euler angles with constant rates (62), order theta, psi, phi", "rad", "62"),
        NamedMatrix("contact_gap", contact_gap_printed(),
                    args_of([(zc, "centre height z_c", "m"), (kx, "KC, X component", "m"),
                             (ky, "KC, Y component", "m"), (kz, "KC, Z component", "m")]),
                    "contact test (63) as a gap z_c - |KC| (contact when <= 0)", "m", "63"),
    ]
    return [ModuleSpec("grain_motion_printed", "Grain motion formulas (61)-(63) of paper 1, as printed.",
                       "symmech.grain.printed_motion (paper 1, seed 000, eqs (61)-(63))", functions)]
