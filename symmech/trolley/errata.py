"""Printed vs derived for the trolley paper (seed 002): formulas and Tables 1, 2."""
from __future__ import annotations

import functools

import numpy as np

from symmech.core.errata import Check, NotCompared
from symmech.generated import trolley_dynamics as dyn
from symmech.generated import trolley_frame as frm
from symmech.generated import trolley_printed as printed
from symmech.trolley import SEED

ROLE = "errata"  # found by symmech.core.discovery

HELIX = {"R": 7.0, "lam": 5 / (2 * np.pi)}


def _angles(rng, n):
    return {f"th{i}": rng.uniform(-np.pi, np.pi, n) for i in (1, 2, 3)}


def _th(x):
    return x["th1"], x["th2"], x["th3"]


def _chord_inputs(rng, n):
    x = _angles(rng, n)
    x.update({f"dX{i}": rng.uniform(-2, 2, n) for i in (1, 2, 3)})
    return x


def _tangent_chord(rng, n):
    """Unit tangent t and unit chord ρ at angle Ψ ∈ [0.01, 0.6] rad (fixed frame)."""
    t = rng.normal(size=(n, 3))
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    side = np.cross(t, rng.normal(size=(n, 3)))
    side /= np.linalg.norm(side, axis=1, keepdims=True)
    psi = rng.uniform(0.01, 0.6, n)
    rho = np.cos(psi)[:, None] * t + np.sin(psi)[:, None] * side
    return {**{f"t{i + 1}": t[:, i] for i in range(3)}, **{f"rho{i + 1}": rho[:, i] for i in range(3)}, "psi": psi}


def _vec(x, name):
    return np.stack([x[f"{name}{i}"] for i in (1, 2, 3)], axis=-1)


def _lstar_as_used(x):
    xi = np.cross(_vec(x, "t"), _vec(x, "rho"))
    return printed.rodrigues(x["psi"], xi[:, 0], xi[:, 1], xi[:, 2])


def _lstar_derived(x):
    xi = np.cross(_vec(x, "t"), _vec(x, "rho"))
    xi /= np.linalg.norm(xi, axis=1, keepdims=True)
    return frm.rodrigues(x["psi"], xi[:, 0], xi[:, 1], xi[:, 2])


def _unit_axis(rng, n):
    xi = rng.normal(size=(n, 3))
    xi /= np.linalg.norm(xi, axis=1, keepdims=True)
    return {"psi": rng.uniform(-np.pi, np.pi, n), "xi1": xi[:, 0], "xi2": xi[:, 1], "xi3": xi[:, 2]}


@functools.lru_cache(maxsize=1)
def _helix_track():
    from symmech.trolley import track

    return track.build({"type": "helix", "radius": HELIX["R"], "rise": HELIX["lam"], "twist": "0"})


def _helix_points(rng, n):
    return {"s": rng.uniform(0, 200, n), "V0": rng.uniform(0.5, 50, n)}


def _helix_phi(x):
    return x["s"] / np.hypot(HELIX["R"], HELIX["lam"])


def _helix_frenet(x):
    from symmech.trolley import model

    return model.moving_frame(_helix_track(), x["s"], "frenet")


@functools.lru_cache(maxsize=2)
def _paper_example(conventions: str):
    """Results of the bundled paper example in ``conventions``, per case."""
    import copy

    from symmech.core import pipeline
    from symmech.trolley import scene, tables

    setup = pipeline.load(copy.deepcopy(tables.PAPER_EXAMPLE)).setup
    return setup, scene.compute(setup, conventions)


def _table_value(conventions: str, rounded: bool):
    from symmech.trolley import scene, tables

    def value(x):
        setup, res = _paper_example(conventions)
        out = []
        for i in x["entry"]:
            _, q, case, time_, _, decimals = tables.entries()[int(i)]
            k = int(round(time_ / (setup.t[1] - setup.t[0])))
            v = float(scene.quantity(res[case], q)[k])
            out.append(round(v, decimals) if rounded else v)
        return np.array(out)
    return value


def _table_entries(rng, n):
    from symmech.trolley import tables

    count = len(tables.entries())
    idx = np.arange(n) % count
    return {"entry": idx, "case": np.array([tables.entries()[i][2] for i in idx]),
            "t": np.array([tables.entries()[i][3] for i in idx])}


def _printed_table(x):
    from symmech.trolley import tables

    return np.array([tables.entries()[int(i)][4] for i in x["entry"]])


def _rigid_body(rng, n):
    """A body of random mass, offset centre of mass, positive definite central inertia and motion."""
    x = {"m": rng.uniform(10, 1000, n)}
    x.update({f"{v}{i}": rng.normal(scale=s, size=n) for v, s in (("r", 1.0), ("a0", 5.0), ("w", 2.0), ("dw", 3.0))
              for i in (1, 2, 3)})
    a = rng.normal(size=(n, 3, 3))
    inertia = a @ np.swapaxes(a, 1, 2) + 3 * np.eye(3)  # positive definite
    for key, (i, j) in zip(("I11", "I22", "I33", "I12", "I23", "I13"), ((0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2))):
        x[key] = inertia[:, i, j] * x["m"] / 10
    return x


def _call(f, x):
    import inspect

    return f(*(x[p] for p in inspect.signature(f).parameters))


def checks() -> list[Check]:
    out = [Check(SEED, "(11)", "rigid-body equations with the static moment L0 = m r and I00 about O", _rigid_body,
                 lambda x: _call(printed.rigid_body_equations, x), lambda x: _call(dyn.newton_euler, x),
                 "Ľ read as the cross-product matrix; derived: Newton and Euler for the centre of mass"),
           Check(SEED, "Λ", "rotation matrix Λ(θ1, θ2, θ3)", _angles,
                 lambda x: printed.Lambda(*_th(x)), lambda x: frm.Lambda(*_th(x)))]
    for i in (1, 2, 3):
        name = f"dLambda_dth{i}"
        out.append(Check(SEED, "(13)", f"∂Λ/∂θ{i}", _angles,
                         lambda x, n=name: getattr(printed, n)(*_th(x)),
                         lambda x, n=name: getattr(frm, n)(*_th(x))))
    out += [
        Check(SEED, "ω = A θ̇", "matrix A of the angular velocity", _angles,
              lambda x: printed.A(*_th(x)), lambda x: frm.A(*_th(x))),
        Check(SEED, "(14)", "coefficients l_ij of the system for Δθ", _chord_inputs,
              lambda x: printed.chord_coefficients(*_th(x), x["dX1"], x["dX2"], x["dX3"]),
              lambda x: frm.chord_coefficients(*_th(x), x["dX1"], x["dX2"], x["dX3"])),
        Check(SEED, "Λ*", "Rodrigues matrix Λ* for a unit axis ξ", _unit_axis,
              lambda x: printed.rodrigues(x["psi"], x["xi1"], x["xi2"], x["xi3"]),
              lambda x: frm.rodrigues(x["psi"], x["xi1"], x["xi2"], x["xi3"])),
        Check(SEED, "Λ*", "Λ* with ξ = t × ρ as the example builds it (|ξ| = sin Ψ, not 1)", _tangent_chord,
              _lstar_as_used, _lstar_derived,
              note="the printed ξ = t × ρ is not a unit vector, so Λ* is not a rotation; paper conventions "
                   "keep it (it is needed for Table 1, 2), the default normalizes ξ in the moving frame"),
        Check(SEED, "Λ (helix)", "helix Λ = [t n b]ᵀ", _helix_points,
              lambda x: printed.helix_Lambda(_helix_phi(x), HELIX["R"], HELIX["lam"]),
              lambda x: _helix_frenet(x).lam),
        Check(SEED, "ω (helix)", "helix angular velocity ω = ϰ t + κ b", _helix_points,
              lambda x: np.broadcast_to(printed.helix_omega(HELIX["R"], HELIX["lam"]), (len(x["s"]), 3)),
              lambda x: x["V0"][:, None] * _helix_frenet(x).W,
              note="printed without the speed factor: ω = V0 (ϰ t + κ b); the paper's tables use the printed "
                   "form, so its normal acceleration is κ V0 instead of κ V0²"),
        Check(SEED, "Tables 1-2", "printed entries vs paper conventions, rounded to the printed digits",
              _table_entries, _printed_table, _table_value("paper", True),
              note="Table 2, P0, case 2, t = 5 s repeats the case 1 value; all other entries reproduce"),
        Check(SEED, "Tables 1-2", "printed entries vs the physically consistent model", _table_entries,
              _printed_table, _table_value("physics", False),
              note="differences come from the paper's conventions (ω without V0, unnormalized ξ)"),
    ]
    return out


def not_compared() -> list[NotCompared]:
    rows = [
        ("(12)", "theta-bar = theta + Delta theta", "a definition used by (13)-(14)"),
    ]
    return [NotCompared(SEED, eq, text, why) for eq, text, why in rows]
