"""Independent event-driven reference for a point-mass grain on a vibrating incline (tests only).

Flight: r'' = g_K - s''(t) until the relative height returns to the radius (plastic, frictionless
landing: the normal velocity stops). Sliding: v' = f - mu n v/|v| with stick while |f| <= mu n,
lift-off when n(t) = 0. Written directly with solve_ivp and terminal events (DOP853, rtol 1e-12),
sharing no code with symmech's integrators (only the model builders used by the tests and the benchmark).
"""
import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from symmech.generated import grain_motion as gm
from symmech.grain import flight, motion
from symmech.grain.coulomb_law import ImpactLaw

G = 9.81
RADIUS = 1e-3


def sphere(mu=0.4, amplitude=0.0, freq=25.0, direction=(0.0, 0.0, 1.0), g_k=(0.0, 0.0, -G), rotation=True,
           law=None, phase=0.0):
    vib = flight.Vibration(amplitude, 2 * math.pi * freq, phase, direction)
    law = law or ImpactLaw("coulomb", e_n=0.0, e_t=-1.0, check_printed=False)
    return motion.Model((RADIUS,) * 3, 1e-6, g_k, vib, law, mu, motion.Effects(rotation=rotation))


def on_plane(v=(0.0, 0.0, 0.0), w=(0.0, 0.0, 0.0), z=RADIUS, t=0.0):
    return motion.State(t, np.array([0.0, 0.0, z]), np.array(v, float), np.array([1.0, 0, 0, 0]), np.array(w, float))


def conveyor(phase, mu=0.4, rotation=False):
    """Point mass (a rolling sphere with ``rotation``) on a 3 degree incline, 30 degree throw at Gamma_v = 1.3:
    lift-off once a period."""
    gam = math.radians(30)
    w = 2 * math.pi * 25
    amp = 1.3 * G / (w**2 * math.sin(gam))
    return sphere(mu=mu, amplitude=amp, direction=(math.cos(gam), 0.0, math.sin(gam)),
                  g_k=tuple(gm.gravity(G, math.radians(3), 0.0)), rotation=rotation, phase=phase)


def population(n, seed):
    """Surface phases (n,) [rad] and start velocities (n, 2) [m/s]: along X up to 5 cm/s, sideways 1-5 cm/s."""
    rng = np.random.default_rng(seed)
    side = rng.uniform(0.01, 0.05, n) * rng.choice([-1, 1], n)
    return rng.uniform(0, 2 * math.pi, n), np.column_stack([rng.uniform(-0.05, 0.05, n), side])


def surface_acc(vib, t):
    return -vib.amplitude * vib.omega**2 * math.sin(vib.omega * t + vib.phase) * np.asarray(vib.direction)


def reference(g_k, vib, mu, radius, v0, t_end, rtol=1e-12):
    """Final tangential position (2,) and velocity (2,) from the plane at rest height with velocity v0 (2,)."""
    g = np.asarray(g_k, dtype=float)

    def normal(t):
        return surface_acc(vib, t)[2] - g[2]

    def drive(t):
        return g[:2] - surface_acc(vib, t)[:2]

    t, r, v, on_plane = 0.0, np.zeros(2), np.array(v0, dtype=float), True
    while t < t_end:
        if not on_plane:
            def fly(s, y):
                return np.concatenate([y[3:], g - surface_acc(vib, s)])

            def land(_s, y):  # 1e-13 m below: the start on the plane is not itself a landing
                return y[2] - radius + 1e-13
            land.terminal, land.direction = True, -1
            sol = solve_ivp(fly, (t, t_end), [*r, radius, *v, 0.0], method="DOP853", rtol=rtol, atol=1e-15,
                            events=land)
            t, r, v, on_plane = sol.t[-1], sol.y[:2, -1], sol.y[3:5, -1], True
            continue
        # Lift-off: first zero of n after t (scanned at 1/200 period, refined by brentq).
        grid = np.arange(t, t_end + 1e-3, 2 * math.pi / vib.omega / 200)
        grid = np.minimum(grid, t_end)
        n_vals = np.array([normal(s) for s in grid])
        down = np.flatnonzero((n_vals[:-1] > 0) & (n_vals[1:] <= 0))
        t_lift = brentq(normal, grid[down[0]], grid[down[0] + 1], xtol=1e-15) if down.size else t_end
        if normal(t) <= 0:
            t_lift = t
        unstuck = False  # slip onset just located: slip, whatever round-off says at the root
        while t < t_lift:
            speed = math.hypot(*v)
            if speed < 1e-12 and not unstuck and np.linalg.norm(drive(t)) <= mu * normal(t):
                ok = [s for s in grid if s > t and s <= t_lift]
                vals = [mu * normal(s) - np.linalg.norm(drive(s)) for s in ok]
                cross = next((i for i, x in enumerate(vals) if x < 0), None)
                if cross is None:
                    t = t_lift
                else:
                    lo = t if cross == 0 else ok[cross - 1]
                    t = brentq(lambda s: mu * normal(s) - np.linalg.norm(drive(s)), lo, ok[cross], xtol=1e-15)
                v, unstuck = np.zeros(2), True
                continue
            unstuck = False
            ref = v / speed if speed > 0 else drive(t) / np.linalg.norm(drive(t))

            def slip(s, y):
                vel = y[2:]
                sp = math.hypot(*vel)
                return np.concatenate([vel, drive(s) - mu * normal(s) * (vel / sp if sp > 0 else ref)])

            def stops(_s, y):
                return y[2:] @ ref
            stops.terminal, stops.direction = True, -1
            sol = solve_ivp(slip, (t, t_lift), [*r, *v], method="DOP853", rtol=rtol, atol=1e-15, events=stops)
            t, r, v = sol.t[-1], sol.y[:2, -1], sol.y[2:, -1]
            if sol.status == 1 and math.hypot(*v) < 1e-9:
                v = np.zeros(2)
        on_plane = t >= t_end
    return r, v


def turning_ellipsoid(g_k, vib, mu, k, rho0, t_end, h):
    """Moreau-Jean time stepping of an ellipsoid that slides on the plane turning about the normal only.

    Per unit mass: v' = f + phi, w' = k (rho x phi)_z, psi' = w, slip s = v + w e_z x rho, rho = Rot(psi) rho0
    the horizontal offset (2,) [m] of the contact point, k = m / I_zz [1/m^2]. Each step of h [s] applies the
    friction impulse that solves the cone exactly (stick when the sticking impulse is inside it; otherwise the
    impulse on the cone opposite to the slip after the step). First order in h; starts at rest at t = 0.
    Returns the tangential position (2,) and the spin [rad/s] at t_end.
    """
    g = np.asarray(g_k, dtype=float)
    x, v, w, psi = np.zeros(2), np.zeros(2), 0.0, 0.0

    def solve(a, b, jr, s):
        """(a E + b W)^-1 s with W = E + k jr jr^T (Sherman-Morrison)."""
        return (s - b * k * (jr @ s) / (a + b + b * k * (jr @ jr)) * jr) / (a + b)
    for i in range(int(round(t_end / h))):
        t = (i + 0.5) * h
        a = surface_acc(vib, t)
        cone = mu * (a[2] - g[2]) * h
        c, s = math.cos(psi + 0.5 * h * w), math.sin(psi + 0.5 * h * w)
        jr = np.array([-(s * rho0[0] + c * rho0[1]), c * rho0[0] - s * rho0[1]])  # e_z x rho
        v_free = v + h * (g[:2] - a[:2])
        s_free = v_free + w * jr
        P = -solve(0.0, 1.0, jr, s_free)
        if math.hypot(*P) > cone:
            lam = brentq(lambda lm: math.hypot(*solve(lm, cone, jr, s_free)) - 1.0, 0.0, math.hypot(*s_free))
            P = -cone * solve(lam, cone, jr, s_free)
        v = v_free + P
        w += k * float(jr @ P)
        psi += h * w
        x += h * v
    return x, w
