"""Paper mode: the printed fixed-step scheme (61)-(64), vectorised over many grains.

Per step dt, for every grain in flight:

- (61) velocity then position (the position update uses the new velocity):
  corrected ``v += (g_K - a_s(t_k)) dt`` (relative motion in the vibrating frame);
  as printed ``v += (a_s(t_k) + g_printed) dt`` (sign of the surface acceleration and
  gravity components as printed, see ``symmech errata``);
- (62) Euler angles advance with the constant rates obtained at the last impact
  (exact only for regular precession: the error for an asymmetric body does not
  vanish with dt, measured in the tests). The angles are those of a per-grain chart
  ``Q = C Rot(psi, theta, phi)``: ``C`` is the identity (the paper's angles) until
  |sin theta| falls below ``CHART_SIN`` where the rates of (62) become singular (the
  bundled orientation theta = 0 is exactly singular); then the chart is turned so that
  the grain sits at theta = pi/2 in it. Body rates, hence (62), do not depend on ``C``;
  the output is the orientation Q itself;
- (63) contact test over ``nodes`` discrete surface nodes: corrected, the lowest
  node reaches the plane (``z_c + min_k z_k <= 0``); as printed ``z_c <= |KC|``;
- impact at the step time with the scene's impact law (applied at the exact lowest
  point of the ellipsoid); corrected, the centre is put back to the height at which
  the lowest node touches the plane (as printed, the step's penetration stays);
- (64) lift-off test: corrected, the contact point separates (normal velocity after
  the impact above ``rest_velocity`` and above 2 g dt, the smallest bounce the step
  resolves); as printed, ``z'_c > 0``. Otherwise the grain
  slides (explicit Euler steps of :mod:`symmech.grain.sliding`) until the normal force
  would become negative. Paper-mode sliding is that of a point mass (the paper defers
  the sliding regime; its scheme has no rolling contact, and on the discrete nodes a
  rolling body would be a bumpy wheel): a landing drops the grain's spin. This is an
  assumption of the mode, not physics: the kinetic energy of the dropped spin is summed
  per grain and reported (``spin_energy_dropped_J`` and a warning in the summary).

Grains share the surface and the impact law; they differ in shape, mass and state.
"""
from __future__ import annotations


import numpy as np

from symmech.generated import grain_motion as gm
from symmech.generated import grain_motion_printed as gp
from symmech.grain import contact
from symmech.grain.body import euler_from_matrix
from symmech.grain.coulomb_law import principal_inertia
from symmech.grain.body import rotation as euler_rotation
from symmech.grain.motion import ImpactLog, Model, Motion, Numerics, Progress, State, impact_record
from symmech.grain.outcome import distinct
from symmech.grain.flight import quaternion_from_matrix
from symmech.grain.sliding import slide_step

CHART_SIN = 0.1  # |sin theta| below which the angle chart is turned (rates amplified by at most 10)


def simulate_batch(model: Model, num: Numerics, axes, mass, r0, v0, angles0, w0, t_end: float,
                   record: bool = False, alpha_beta=(0.0, 0.0), on_step=None):
    """Paper-mode run of n grains from t = 0 to ``t_end``.

    axes (n, 3) m, mass (n,) kg, r0, v0 (n, 3) relative centre position/velocity [m, m/s],
    angles0 (n, 3) Euler angles (psi, theta, phi) [rad], w0 (n, 3) body rates [rad/s].
    ``alpha_beta`` are the inclination angles [rad] for the printed gravity (as printed only).
    Returns (r, v, impacts per grain (n,), records) where records (if ``record``) holds the
    trajectory rows, impact log and regime times of grain 0. ``on_step(t_now)``: as in accurate mode.
    """
    progress = Progress(on_step)
    axes = np.asarray(axes, dtype=float)
    mass = np.asarray(mass, dtype=float)
    n = len(mass)
    r, v = np.array(r0, dtype=float), np.array(v0, dtype=float)
    ang = np.array(angles0, dtype=float)
    Q = euler_rotation(ang)
    chart = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
    _rechart(chart, ang, Q, np.arange(n))
    ang_liftoff, steps_since = ang.copy(), np.zeros(n)  # (62) counts steps s from the last impact
    rotation = model.effects.rotation
    w_body = np.array(w0, dtype=float) if rotation else np.zeros((n, 3))
    rates = gm.euler_rates(*ang.T, *w_body.T)
    nodes = contact.ellipsoid_nodes(np.ones(3), num.nodes)[None] * axes[:, None, :]  # (n, N, 3)
    sliding = np.zeros(n, dtype=bool)
    count = np.zeros(n, dtype=int)
    vib = model.vibration
    slide_model = model.sliding
    warnings: list = []
    if num.as_printed:
        a, b = alpha_beta
        delta = np.arccos(np.sqrt(max(1.0 - np.sin(a) ** 2 - np.sin(b) ** 2, 0.0)))
        g_step = gp.gravity(float(np.linalg.norm(model.g_k)), a, b, delta)
    # A bounce shorter than about two steps cannot be resolved by the fixed step: it ends in sliding.
    rest = max(num.rest_velocity, 2.0 * float(np.linalg.norm(model.g_k)) * num.dt)
    rec_rows, rec_impacts, time_in = [], [], {"flight": 0.0, "sliding": 0.0}
    spin_dropped = np.zeros(n)  # kinetic energy [J] of the spin dropped at landings, per grain
    inertia = principal_inertia(axes, mass)
    steps = int(round(t_end / num.dt))
    every = max(1, int(round(num.sample_interval / num.dt)))
    for k in range(1, steps + 1):
        t = k * num.dt
        progress(t)
        a_s = vib.kinematics(t)[2]
        fl = ~sliding
        if record:
            time_in["sliding" if sliding[0] else "flight"] += num.dt
        if fl.any():
            acc = (a_s + g_step) if num.as_printed else (np.asarray(model.g_k) - a_s)
            v[fl] += acc * num.dt
            r[fl] += v[fl] * num.dt
            if rotation:
                steps_since[fl] += 1
                a0, rt = ang_liftoff[fl], rates[fl]
                theta, psi, phi = np.moveaxis(gp.euler_angles(a0[:, 1], a0[:, 0], a0[:, 2], rt[:, 1], rt[:, 0],
                                                              rt[:, 2], steps_since[fl], num.dt), -1, 0)
                ang[fl] = np.stack([psi, theta, phi], axis=-1)
                Q[fl] = chart[fl] @ euler_rotation(ang[fl])
            hit = _contacts(model, num, Q, nodes, r, v, w_body, fl, rotation)
            if hit.any():
                idx = np.flatnonzero(hit)
                count[idx] += 1
                before_v, before_w = v[idx].copy(), w_body[idx].copy()
                w_k = np.einsum("nij,nj->ni", Q[idx], w_body[idx])
                out = model.law.apply(axes[idx], mass[idx], Q[idx], v[idx], w_k, rotation)
                warnings += out["warnings"]
                v[idx] = out["v"]
                w_body[idx] = np.einsum("nji,nj->ni", Q[idx], out["w"])
                lifted = out["v"][:, 2] > 0.0 if num.as_printed else out["u_after"][:, 2] > rest
                if not num.as_printed:
                    # The impact happens on the plane: undo the penetration of the step.
                    r[idx, 2] = _node_support(Q[idx], nodes[idx])
                land = idx[~lifted]
                sliding[land] = True
                v[land, 2] = 0.0
                spin_dropped[land] += 0.5 * np.einsum("ni,ni->n", inertia[land] * w_body[land], w_body[land])
                w_body[land] = 0.0
                r[land, 2] = _node_support(Q[land], nodes[land])
                if rotation:
                    _rechart(chart, ang, Q, idx)
                    rates[idx] = gm.euler_rates(*ang[idx].T, *w_body[idx].T)
                    ang_liftoff[idx], steps_since[idx] = ang[idx], 0
                if record and hit[0]:
                    q = quaternion_from_matrix(Q[0])
                    b_state = State(t, r[0].copy(), before_v[0], q, before_w[0])
                    a_state = State(t, r[0].copy(), v[0].copy(), q, w_body[0].copy())
                    rec_impacts.append(impact_record(t, b_state, a_state, out, 0))
                    rec_rows += [b_state.row("impact"), a_state.row("impact")]
        if sliding.any():
            n_force = slide_model.normal(t)
            if n_force < 0:
                sliding[:] = False
            else:
                sl = sliding
                v[sl, :2] = slide_step(slide_model, t, v[sl, :2], num.dt)
                r[sl, :2] += v[sl, :2] * num.dt
        if record and k % every == 0:
            q = quaternion_from_matrix(Q[0])
            rec_rows.append(State(t, r[0].copy(), v[0].copy(), q, w_body[0].copy())
                            .row("sliding" if sliding[0] else "flight"))
    if spin_dropped.any():
        warnings.append(f"paper mode: {int(np.count_nonzero(spin_dropped))} grain(s) lost spin at landings "
                        f"(up to {spin_dropped.max():.3g} J of kinetic energy): its sliding is a point mass's")
    return r, v, count, {"rows": rec_rows, "impacts": rec_impacts, "time_in": time_in,
                         "warnings": distinct(warnings), "Q": Q, "w_body": w_body, "spin_dropped": spin_dropped}


def _node_support(Q, nodes):
    """Centre height (n,) [m] at which the lowest node touches the plane."""
    return -np.min((nodes @ Q[:, 2, :, None])[..., 0], axis=1)


def _rechart(chart, ang, Q, idx) -> None:
    """For grains ``idx`` whose chart angle theta is within ``CHART_SIN`` of gimbal lock, turn the chart
    (n, 3, 3) in place so that the orientation Q (n, 3, 3) has angles (0, pi/2, 0) in it."""
    near = idx[np.abs(np.sin(ang[idx, 1])) < CHART_SIN]
    if near.size:
        ang[near] = [0.0, np.pi / 2, 0.0]
        chart[near] = Q[near] @ np.swapaxes(euler_rotation(ang[near]), -1, -2)


def _contacts(model: Model, num: Numerics, Q, nodes, r, v, w_body, fl, rotation: bool):
    """Grains in flight whose contact test (63) fires while the lowest node approaches the plane."""
    z = (nodes @ Q[:, 2, :, None])[..., 0]  # node heights above the centre (n, N)
    low = np.argmin(z, axis=1)
    KC = (Q @ nodes[np.arange(len(low)), low][..., None])[..., 0]  # lowest node offset in KXYZ (n, 3)
    if num.as_printed:
        gap = gp.contact_gap(r[:, 2], KC[:, 0], KC[:, 1], KC[:, 2])
    else:
        gap = r[:, 2] + KC[:, 2]
    w = np.einsum("nij,nj->ni", Q, w_body) if rotation else np.zeros_like(v)
    u_n = v[:, 2] + np.cross(w, KC)[:, 2]
    return fl & (gap <= 0.0) & (u_n < 0.0)


def simulate(model: Model, num: Numerics, start: State, t_end: float, alpha_beta=(0.0, 0.0),
             on_step=None) -> Motion:
    """Paper mode for one grain from ``start`` (at t = 0) to ``t_end``; same result type and progress callback
    as accurate mode."""
    from symmech.grain import flight

    Q0 = flight.rotation_matrix(start.q)
    r, v, _, rec = simulate_batch(model, num, np.array([model.axes]), np.array([model.mass]),
                                  start.r[None], start.v[None], euler_from_matrix(Q0)[None], start.w[None],
                                  t_end, record=True, alpha_beta=alpha_beta, on_step=on_step)
    rows = [start.row("flight")] + rec["rows"]
    final = State(t_end, r[0], v[0], quaternion_from_matrix(rec["Q"][0]), rec["w_body"][0])
    return Motion(np.array(rows), ImpactLog(rec["impacts"]), rec["time_in"], rec["warnings"], start, final,
                  {"spin_energy_dropped_J": float(rec["spin_dropped"][0])})
