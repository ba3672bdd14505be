"""Printed matrices of section 5 vs the SMM derivation of the reconstructed examples.

Inputs are the bundled scenes' parameters, each drawn uniformly in [0.5, 1.5]
times its nominal value; both sides are generated modules (``smm_printed`` and
``smm_<example>``), evaluated at run time.
"""
from __future__ import annotations

import importlib
import inspect

import numpy as np

from symmech.core.errata import Check, NotCompared
from symmech.core.scene import scenes_folder
from symmech.smm import EX52_LC_ENTRIES, SEED
from symmech.smm.build import load_mechanism

ROLE = "errata"  # found by symmech.core.discovery

SCENES = scenes_folder()


def _nominal(scene: str) -> dict:
    return load_mechanism(SCENES / f"smm_{scene}.toml").values()


def _sampler(scene: str):
    nominal = _nominal(scene)

    def sample(rng, n):
        return {k: v * rng.uniform(0.5, 1.5, n) for k, v in nominal.items()}
    return sample


def _call(module: str, name: str, x: dict, pick=None):
    f = getattr(importlib.import_module(f"symmech.generated.{module}"), name)
    out = f(*(x[p] for p in inspect.signature(f).parameters))
    return out if pick is None else pick(out)


def checks() -> list[Check]:
    rows, cols = zip(*EX52_LC_ENTRIES)
    note = "geometry reconstructed from the text and the printed matrices (docs/smm.md)"
    return [
        Check(SEED, "5.1 (a)", "rotor boom: inertia matrix", _sampler("rotor_boom"),
              lambda x: _call("smm_printed", "ex51_a", x), lambda x: _call("smm_rotor_boom", "a", x), note),
        Check(SEED, "5.1 (L_c)", "rotor boom: rope column c_1 of (L_c)", _sampler("rotor_boom"),
              lambda x: _call("smm_printed", "ex51_Lc_rope", x),
              lambda x: _call("smm_rotor_boom", "L_c", x, lambda L: L[..., :, 0]), note),
        Check(SEED, "5.2 (L_a)", "excavator: (L_a) in coordinate form", _sampler("excavator"),
              lambda x: _call("smm_printed", "ex52_La", x), lambda x: _call("smm_excavator", "L_a", x), note),
        Check(SEED, "5.2 (L_c)", "excavator: legible entries of (L_c)", _sampler("excavator"),
              lambda x: _call("smm_printed", "ex52_Lc", x),
              lambda x: _call("smm_excavator", "L_c", x, lambda L: L[..., list(rows), list(cols)]), note),
        Check(SEED, "5.3 (L_c)", "spatial boom: legible rows beta1, psi1, phi1 of (L_c)", _sampler("spatial_boom"),
              lambda x: _call("smm_printed", "ex53_Lc", x), lambda x: _call("smm_spatial_boom", "L_c", x, _ex53_rows),
              note + "; the paper projects on the direction to the anchor (rope shortening), symmech "
              "measures elongation: rope columns compared with opposite sign, which leaves c unchanged"),
    ]


def _ex53_rows(L):
    """Scene rows (phi1, beta1, psi1, phi2) x columns (c1, c1p, c2, cK) -> the printed layout:
    rows beta1, psi1, phi1; columns c1, c1', c_K, c2; rope columns as shortening."""
    return L[..., [1, 2, 0], :][..., [0, 1, 3, 2]] * np.array([-1.0, -1.0, 1.0, 1.0])


def not_compared() -> list[NotCompared]:
    """Printed entries of section 5 that the OCR leaves unreadable or whose figure is missing."""
    rows = [
        ("5.1 (L_a)", "rows phi1, phi2 over I1, m2, I2", "garbled: the conjugate vectors lost their bars and the "
         "1 entries of I1, I2 are missing; (a) = (L_a)(m)(L_a)^T is compared instead"),
        ("5.1 (m)", "diagonal of I1, m2, I2", "garbled (I2 printed off the diagonal)"),
        ("5.1 (c)", "stiffnesses c1..c4", "garbled (rows of unequal length)"),
        ("5.1 (L_c) c2-c4", "columns with l2, z1, R", "illegible, and Fig. 12 is missing: the scene assumes one "
         "drive spring (docs/smm.md)"),
        ("5.2 (L_c) phi3", "entries of c1, c2 in row phi3", "illegible (l2 - l2 cos beta, -l2 sin beta)"),
        ("5.3 (L_a)", "rows phi2, phi1, beta1, psi1 over m1, J, m2", "rows shifted and one sign inconsistent "
         "with any right-handed rotation"),
        ("5.3 (L_c) phi2", "row phi2: L1z cos delta sin(beta - delta - Sigma), a2 sin Theta",
         "unreadable angle sum; the derivation gives -(L1 + a2) cos delta sin beta for the ropes"),
        ("5.3 last matrix", "unlabelled matrix over phi1, beta1, psi1, phi2, z2", "no label or caption survives"),
    ]
    return [NotCompared(SEED, eq, text, why) for eq, text, why in rows]
