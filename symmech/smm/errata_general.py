"""Printed general formulas of the SMM paper (seed 003, sections 2-3, Tables 1-2, Figs. 8-9)
against independent derivations, and the equations (1)-(11) on the bundled mechanisms.

Vector formulas: printed twins in ``smm_printed`` vs the definitions differentiated in
``smm_formulas`` at seeded random unit axes and vectors. Equations (1)-(11): the printed
matrix formula evaluated with the SMM's factors (L_a, m, L_c, c, L_b, mu) vs Lagrange's
equations linearised at equilibrium (:mod:`symmech.smm.lagrange`, no conjugate vectors),
with every parameter drawn in [0.5, 1.5] times its scene value. Both sides are generated
(the mechanism's ``smm_<name>`` and ``smm_errata`` of :mod:`symmech.smm.derive_errata`):
no sympy runs here, and the 200 samples are one batch call per quantity.
"""
from __future__ import annotations

import functools
import importlib
import inspect

import numpy as np

from symmech.core.errata import Check, NotCompared
from symmech.core.scene import scenes_folder
from symmech.generated import smm_errata
from symmech.generated import smm_formulas as derived
from symmech.generated import smm_printed as printed
from symmech.smm import SEED
from symmech.smm.build import load_mechanism

ROLE = "errata"  # found by symmech.core.discovery

SCENES = scenes_folder()


def _unit(rng, n, planar=False):
    v = rng.normal(size=(n, 3))
    if planar:
        v[:, 2] = 0.0
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def _vectors(rng, n, planar=False):
    x = {}
    for name, v in (("e", _unit(rng, n)), ("f", _unit(rng, n)), ("u", _unit(rng, n, planar)),
                    ("s", _unit(rng, n, planar)), ("p", rng.normal(size=(n, 3)))):
        x.update({f"{name}_{c}": v[:, i] for i, c in enumerate("xyz")})
    x["ell"] = rng.uniform(0.3, 3.0, n)
    return x


def _pendulum(rng, n):
    return {"c1": rng.uniform(1e3, 1e5, n), "L": rng.uniform(0.5, 2.0, n), "alpha": rng.uniform(0.1, 1.2, n),
            "beta": rng.uniform(0.1, 1.2, n), "ell": rng.uniform(0.3, 2.0, n), "m": rng.uniform(1.0, 50.0, n),
            "g": rng.uniform(9.7, 9.9, n), "Delta": rng.uniform(1e-3, 0.1, n)}


def _call(f, x):
    return f(*(x[p] for p in inspect.signature(f).parameters))


def _pair(name, derived_name=None):
    return (lambda x: _call(getattr(printed, name), x),
            lambda x: _call(getattr(derived, derived_name or name), x))


def _vector_checks() -> list[Check]:
    planar = functools.partial(_vectors, planar=True)
    rows = [
        ("Table 2", "conjugate vector projections for turns about i, j, k", _vectors, "table2_conjugates", None, ""),
        ("sec. 3 dl/dq", "spatial conjugate vector (e_y p_z - e_z p_y, ...)", _vectors, "spatial_conjugate", None, ""),
        ("sec. 3 d2l/dq2", "second derivative of a spring length by one turn", _vectors, "length_d2_turn", None,
         "l° points to the moving end (the paper's l = L_beta - L_alpha)"),
        ("sec. 3 d2l/dq1dq2", "mixed second derivative by two turns, indices as printed (p~2 twice)", _vectors,
         "length_d2_two_turns", None, "the first factor must be the conjugate of the other turn (next record)"),
        ("sec. 3 d2l/dq1dq2", "mixed second derivative, first factor read as p~1", _vectors,
         "length_d2_two_turns_read", "length_d2_two_turns",
         "the printed second term (e x f) x p + f x (e x p) equals e x (f x p) by the Jacobi identity"),
        ("sec. 3 d2l/ds2", "second derivative of a spring length by a slide, (1 - s~^2)/l", _vectors,
         "length_d2_slide", None, "s~ read as the component of s along l°"),
        ("Table 1", "inertia and gravity entries, set (p~, s), planar", planar, "table1_planar", None,
         "the slide s is carried by the turn (else j . d2r/dphi ds = 0, not -j . s~)"),
        ("Table 1", "spring-length entries (legible), set (p~, s), planar", planar, "table1_length", None,
         "upper signs of the printed +- for the moving end; p~ across l° for the printed p-bar"),
        ("sec. 3 omega_C", "d omega_C / d(alpha', beta', gamma') of the Euler-Krylov angles", _pendulum,
         "omega_c_rates", None, "the printed third rate reads beta'; gamma' by the sequence"),
        ("Fig. 8", "pendulum on a preloaded spring, C as printed (C2 read as C1)", _pendulum, "fig8_c", None,
         "the bracket repeats - m g L sin(alpha): gravity counted twice"),
        ("Fig. 8", "the same without the repeated - m g L sin(alpha)", _pendulum, "fig8_c_read", "fig8_c",
         "geometry read from the formula: the spring leaves the mass backwards at beta above the horizontal"),
        ("Fig. 9", "mass across a preloaded spring, C = C1 Delta / l", _pendulum, "fig9_c", None, ""),
    ]
    return [Check(SEED, eq, text, sample, *_pair(name, dname), note) for eq, text, sample, name, dname, note in rows]


def _function(scene: str, key: str):
    """The generated function of quantity ``key`` of a bundled mechanism: its own module's (a, c, L_a,
    L_c) or, for what only the errata need, ``smm_errata``'s ``<scene>_<key>``."""
    own = importlib.import_module(f"symmech.generated.smm_{scene}")
    return getattr(own, key, None) or getattr(smm_errata, f"{scene}_{key}")


@functools.cache
def _nominal(scene: str) -> dict:
    """The bundled mechanism's parameter values by name, read once (several checks sample around them)."""
    return load_mechanism(SCENES / f"smm_{scene}.toml").values()


def _sampler(scene):
    def sample(rng, n):
        return {k: v * rng.uniform(0.5, 1.5, n) for k, v in _nominal(scene).items()}
    return sample


def _evaluate(scene, key, x):
    """``key`` at the n sampled parameter sets ``x``: shape (n,) + the quantity's shape."""
    return np.asarray(_call(_function(scene, key), x), dtype=float)


def _triple(L, d, literal_diagonal=False):
    """L diag(d) L^T for L (n, k, j) and the diagonals d (n, j); with ``literal_diagonal`` the printed index
    pair (kappa, kappa) of (1), (10): entry (kappa, lambda) = sum_j d_j L_kappa,j^2 for every lambda."""
    if literal_diagonal:
        row = np.einsum("nkj,nj,nkj->nk", L, d, L)
        return np.repeat(row[:, :, None], L.shape[1], axis=2)
    return np.einsum("nkj,nj,nlj->nkl", L, d, L)


def _formula(scene, what):
    """The printed formula ``what`` evaluated with the SMM factors of ``scene``."""
    def value(x):
        ev = functools.partial(_evaluate, scene)
        if what == "(1)":
            return np.diagonal(_triple(ev("L_a", x), ev("m_a", x)), axis1=1, axis2=2)
        if what == "(3)":
            return _triple(ev("L_a", x), ev("m_a", x))
        if what == "(9)":
            return _triple(ev("L_c", x), ev("c_d", x))
        if what == "(10) literal":
            return _triple(ev("L_b", x), ev("b_d", x), literal_diagonal=True)
        if what == "(10)":
            return _triple(ev("L_b", x), ev("b_d", x))
        return ev({"(7)": "c", "(11)": "graph_a"}[what], x)
    return value


def _lagrange(scene, key, pick=None):
    def value(x):
        out = _evaluate(scene, f"lagrange_{key}", x)
        return pick(out) if pick else out
    return value


def _equation_checks() -> list[Check]:
    diag = functools.partial(np.diagonal, axis1=1, axis2=2)
    rows = [
        ("(1)", "A_lambda lambda (diagonal inertia coefficients), rotor boom", "rotor_boom", "(1)", "a", diag, ""),
        ("(3)", "(a) = (L_a)(m)(L_a)^T, excavator", "excavator", "(3)", "a", None, ""),
        ("(3) sec. 3", "(a) with the rotational rows J_x, J_y, J_z, spatial boom", "spatial_boom", "(3)", "a", None,
         "the spatial A_kappa lambda of section 3 with the Kronecker terms"),
        ("(7)", "c with the preload and gravity terms, spatial boom", "spatial_boom", "(7)", "c", None, ""),
        ("(9)", "(c) = (L_c)(c)(L_c)^T, rotor boom (no preload, no gravity)", "rotor_boom", "(9)", "c", None, ""),
        ("(9)", "(c) = (L_c)(c)(L_c)^T, spatial boom (preloaded ropes, gravity)", "spatial_boom", "(9)", "c", None,
         "the paper states (9) only for Delta_i << l and drops the gravity terms of (7): the difference is "
         "the preload and gravity stiffness"),
        ("(10)", "B_kappa lambda as printed (both factors d e_j / d q_kappa), rotor boom", "rotor_boom",
         "(10) literal", "b", None, "read with d e_j / d q_lambda in the second factor it agrees (next record)"),
        ("(10)", "B_kappa lambda with d e_j / d q_lambda in the second factor, rotor boom", "rotor_boom", "(10)",
         "b", None, ""),
        ("(11)", "graph form (L_a) = (q_G)(x_m, y_m)(m_G)^T, through (3), excavator", "excavator", "(11)", "a",
         None, ""),
    ]
    return [Check(SEED, eq, text, _sampler(scene), _formula(scene, what), _lagrange(scene, key, pick),
                  "derived: Lagrange's equations linearised at equilibrium" + (f"; {note}" if note else ""))
            for eq, text, scene, what, key, pick, note in rows]


def checks() -> list[Check]:
    return _vector_checks() + _equation_checks()


def not_compared() -> list[NotCompared]:
    rows = [
        ("(1) indices", "A_lambda lambda is printed with one index pair: only the diagonal is defined",
         "compared on the diagonal (record (1)); (3) gives the whole matrix"),
        ("(2)", "dr/dS = dP/dphi . S = ... = S~ P chain", "garbled: the equalities mix a scalar and vectors"),
        ("(4)", "Pi = 1/2 sum c_i f_i^2 + sum P_v y_v", "a definition; its derivatives are (5)-(7), compared"),
        ("(5)", "equilibrium conditions sum c_i Delta_i dl_i/dq + sum P_v j . dr_v/dq = 0",
         "every bundled mechanism is drawn at equilibrium, where both sides vanish; (5) is checked against a "
         "direct minimisation of Pi by tests/test_smm_spatial_eq.py"),
        ("(6)", "dPi/dq at any q, free index printed i = 1..k and sums to n, m",
         "index misprints only (the free index is kappa; the sums run over N springs and n bodies as in (5)); "
         "the same expression as (5) at the drawn configuration"),
        ("(8)", "dl_i/dq = -+ p~ . l° = ... determinant form", "the same quantity as the Table 1 and section 3 "
         "first derivatives, compared there; the determinant rows are garbled"),
        ("(9) matrices", "(L_c) and (L'_c) definitions", "definitions of the factors used by (9)"),
        ("sec. 3 omega_A, omega_B", "angular velocity projections of the Euler-Krylov angles",
         "garbled: omega_A appears in the definition of omega_B and gamma is lost"),
        ("(11) Fig. 4 example", "(L_a)_x and (L_c)_x products with the structural matrices of Fig. 4",
         "Fig. 4 is missing: the vertex coordinates x1..x5 cannot be assigned"),
        ("Figs. 2-7, 10-11", "(L_c), (L_a) tables of the model examples", "the figures are missing: numbers "
         "(0.5, 0.87, ...) without the geometry they belong to"),
        ("(c)(alpha) = E", "check by the influence-coefficient matrix", "a procedure, not a formula; "
         "verified on mechanisms by tests/test_smm_closed_form.py"),
    ]
    return [NotCompared(SEED, eq, text, why) for eq, text, why in rows]
