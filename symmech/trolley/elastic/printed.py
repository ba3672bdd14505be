"""Layer 1: the roller section of seed 002 as printed (fields φ0, ψ0 after (14)), typed in by hand.

The plain-text rendering prints φ0_6 with four components ([-x2, x1, 0, 0]ᵀ); the
fourth is dropped here (a 3-vector field cannot have it). ``symmech errata`` compares
the rest with :func:`symmech.trolley.elastic.derive.rigid_fields`.
"""
from __future__ import annotations

import sympy as sp

from symmech.core.derivation import ModuleSpec, NamedMatrix
from symmech.trolley.derive import SOURCE
from symmech.trolley.elastic.derive import X, X_ARGS

ROLE = "printed"  # found by symmech.core.discovery

x1, x2, x3 = X

# Columns φ0_2 … φ0_6, then ψ0_44, ψ0_45, ψ0_46, ψ0_55, ψ0_56, ψ0_66 (printed order).
FIELDS = sp.Matrix.hstack(
    sp.Matrix([0, 1, 0]), sp.Matrix([0, 0, 1]), sp.Matrix([0, -x3, x2]), sp.Matrix([x3, 0, -x1]),
    sp.Matrix([-x2, x1, 0]),
    sp.Matrix([0, -x3, -x2]), sp.Matrix([x2, 0, 0]), sp.Matrix([x3, 0, 0]), sp.Matrix([-x1, 0, -x3]),
    sp.Matrix([0, 0, x2]), sp.Matrix([-x1, -x2, 0]),
)


def module_specs() -> list[ModuleSpec]:
    return [ModuleSpec("trolley_elastic_printed", "The roller-section fields φ0, ψ0 of seed 002 as printed.", SOURCE,
                       [NamedMatrix("rigid_fields", FIELDS, X_ARGS, "printed [φ0_2 … φ0_6 | ψ0_44 … ψ0_66]",
                                    "1 (translations), m (rotations)", "ũ (roller section)")])]
