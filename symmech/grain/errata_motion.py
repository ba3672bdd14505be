"""Printed (61)-(63) of paper 1 against the derivations, evaluated numerically.

Inputs: alpha, beta the rises of the X and Y axes above the horizontal (the
paper's words); delta, the steepest slope, follows from them:
cos(delta) = sqrt(1 - sin^2 alpha - sin^2 beta).
"""
from __future__ import annotations

import numpy as np

from symmech.core.errata import Check, NotCompared
from symmech.generated import grain_motion as gm
from symmech.generated import grain_motion_printed as gp
from symmech.grain import SEED

ROLE = "errata"  # found by symmech.core.discovery



def _angles(rng, n):
    alpha = rng.uniform(-0.5, 0.5, n)
    beta = rng.uniform(-0.5, 0.5, n)
    delta = np.arccos(np.sqrt(1 - np.sin(alpha) ** 2 - np.sin(beta) ** 2))
    return {"g": rng.uniform(9.0, 10.0, n), "alpha": alpha, "beta": beta, "delta": delta}


def _step_inputs(rng, n):
    x = {k: rng.normal(size=n) for k in ("vx", "vy", "vz", "x", "y", "z", "ax", "ay", "az")}
    x["dt"] = rng.uniform(1e-4, 1e-2, n)
    return x


def _derived_step(x):
    """One semi-implicit Euler step of r'' = g_K - a_s on a horizontal surface."""
    acc = gm.gravity(9.81, 0.0, 0.0) - np.stack([x["ax"], x["ay"], x["az"]], -1)
    v = np.stack([x["vx"], x["vy"], x["vz"]], -1) + acc * x["dt"][:, None]
    r = np.stack([x["x"], x["y"], x["z"]], -1) + v * x["dt"][:, None]
    return np.concatenate([v, r], axis=1)


def _printed_step(x):
    out = gp.flight_step(x["vx"], x["vy"], x["vz"], x["x"], x["y"], x["z"], x["ax"], x["ay"], x["az"],
                         9.81, 0.0, 0.0, 0.0, x["dt"])
    return out.reshape(len(x["dt"]), 6)


def _contact_inputs(rng, n):
    axes = rng.uniform(0.5e-3, 5e-3, (n, 3))
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    Q = gm.rotation_matrix(q[:, 0], q[:, 1], q[:, 2], q[:, 3])
    n_body = Q[:, 2, :]
    kc = np.einsum("nij,nj->ni", Q, gm.contact_offset_body(*axes.T, *n_body.T))
    return {"z_c": rng.uniform(0.0, 1e-2, n), "KC_x": kc[:, 0], "KC_y": kc[:, 1], "KC_z": kc[:, 2]}


def checks() -> list[Check]:
    return [
        Check(SEED, "(61)", "gravity components in the surface frame",
              _angles,
              lambda x: gp.gravity(x["g"], x["alpha"], x["beta"], x["delta"]),
              lambda x: gm.gravity(x["g"], x["alpha"], x["beta"]),
              note="derived g_K = -g (sin alpha, sin beta, cos delta) from the definition of alpha, beta; "
                   "printed X uses beta and Y is tg(alpha) cos(beta) cos(delta)"),
        Check(SEED, "(61)", "magnitude of the printed gravity vector (must equal g)",
              _angles,
              lambda x: np.linalg.norm(gp.gravity(x["g"], x["alpha"], x["beta"], x["delta"]), axis=-1),
              lambda x: x["g"],
              note="the printed components are not a projection of g: |g_printed| != g off the axes"),
        Check(SEED, "(61)", "velocity/position step on a horizontal surface (sign of the surface acceleration)",
              _step_inputs, _printed_step, _derived_step,
              note="relative motion in the vibrating frame is r'' = g - a_surface; (61) adds a_surface"),
        Check(SEED, "(63)", "contact gap z_c - |KC| versus the height of the lowest point z_c + KC_z",
              _contact_inputs,
              lambda x: gp.contact_gap(x["z_c"], x["KC_x"], x["KC_y"], x["KC_z"]),
              lambda x: x["z_c"] + x["KC_z"],
              note="|KC| >= -KC_z: the printed test fires early whenever K is not straight below C"),
    ]


def not_compared() -> list[NotCompared]:
    rows = [
        ("(62)", "Euler angles advanced with constant rates in flight", "not a formula to compare with a "
         "derivation: it breaks the conservation of angular momentum of an asymmetric grain by > 10 % "
         "(tests/test_grain_motion_physics.py), which is why paper mode does not converge on an ellipsoid"),
        ("(64)", "contact condition z_c' > 0", "a sign test; the exact contact root replaces it in accurate mode"),
    ]
    return [NotCompared(SEED, eq, text, why) for eq, text, why in rows]
