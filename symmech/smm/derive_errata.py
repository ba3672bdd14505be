"""Layer 1: the matrices the SMM errata's equations (1)-(11) are compared with, derived in codegen.

:mod:`symmech.smm.errata_general` evaluates the printed equations with the SMM's factors and compares
them with Lagrange's equations linearised at equilibrium (:mod:`symmech.smm.lagrange`) on three bundled
mechanisms. Their own modules ``smm_<name>`` hold a, c, L_a and L_c; the module ``smm_errata`` holds
the rest the checks evaluate: the factors' diagonals, the damping factor, the graph form's a (eq. (11))
and Lagrange's a, b, c, each as ``<mechanism>_<quantity>`` with the scene's parameters as arguments.
The errata then run no sympy, and no mechanism run loads this module.
"""
from __future__ import annotations

import sympy

from symmech.core.derivation import ModuleSpec, NamedMatrix
from symmech.smm import lagrange
from symmech.smm.build import load_mechanism
from symmech.smm.derive import SCENES, SOURCE, matrices, parameter_args

ROLE = "derivation"  # found by symmech.core.discovery

# mechanism -> the quantities its equation checks evaluate beyond those of its own module
CHECKED = {"excavator": ("m_a", "graph_a", "lagrange_a"),
           "rotor_boom": ("m_a", "c_d", "L_b", "b_d", "lagrange_a", "lagrange_b", "lagrange_c"),
           "spatial_boom": ("m_a", "c_d", "lagrange_a", "lagrange_c")}

_INERTIA = "kg, kg m, kg m^2 by coordinate kinds"
_MEANING = {
    "m_a": ("diagonal of (m): the mass or moment of inertia of each column of (L_a)", "kg or kg m^2", "(3)"),
    "c_d": ("diagonal of (c) of the springs: the stiffness of each column of (L_c)", "N/m or N m", "(9)"),
    "L_b": ("damping transformation matrix (L_b): rows coordinates, columns dampers", "m or 1", "(10)"),
    "b_d": ("viscosity of each column of (L_b)", "N s/m or N m s", "(10)"),
    "graph_a": ("inertia matrix (a) by the graph form: (L_a) from structural matrices", _INERTIA, "(11), (3)"),
    "lagrange_a": ("inertia matrix d2T/dq'dq' by Lagrange's route (positions by rotation matrices)", _INERTIA,
                   "(1), (3)"),
    "lagrange_b": ("damping matrix d2Phi/dq'dq' of Rayleigh's function", "N s/m, N s, N m s by coordinate kinds",
                   "(10)"),
    "lagrange_c": ("stiffness matrix d2Pi/dq dq at equilibrium by Lagrange's route", "N/m, N, N m by coordinate kinds",
                   "(7), (9)"),
}


def named_matrices(scene: str) -> list[NamedMatrix]:
    """The quantities :data:`CHECKED` lists for the bundled mechanism ``scene``; diagonals as columns
    (shape (k,)), matrices (coordinates x coordinates or x columns)."""
    m = load_mechanism(SCENES / f"smm_{scene}.toml")
    smm, lag, graph = matrices(m), lagrange.matrices(m), matrices(m, form="graph")
    parts = {k: sympy.Matrix([smm[k][i, i] for i in range(smm[k].rows)]) for k in ("m_a", "c_d", "b_d")}
    parts.update({f"lagrange_{k}": lag[k] for k in "abc"}, L_b=smm["L_b"], graph_a=graph["a"])
    args = parameter_args(m)
    return [NamedMatrix(f"{scene}_{key}", parts[key], args, f"{m.name}: {_MEANING[key][0]}", *_MEANING[key][1:])
            for key in CHECKED[scene]]


def module_specs() -> list[ModuleSpec]:
    functions = tuple(f for scene in CHECKED for f in named_matrices(scene))
    return [ModuleSpec("smm_errata", "The SMM factors and Lagrange's matrices of the bundled mechanisms that the "
                       "errata compare with the printed equations (1)-(11).", SOURCE, functions)]
