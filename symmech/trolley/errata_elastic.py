"""Printed vs derived for the roller section of seed 002: the fields φ0, ψ0 of the five roller DOFs."""
from __future__ import annotations

import numpy as np

from symmech.core.errata import Check
from symmech.generated import trolley_elastic as gen
from symmech.generated import trolley_elastic_printed as printed

SEED = "002_7fa2a0a5477072ec.txt"
_NAMES = ("φ0_2", "φ0_3", "φ0_4", "φ0_5", "φ0_6", "ψ0_44", "ψ0_45", "ψ0_46", "ψ0_55", "ψ0_56", "ψ0_66")


def _points(rng, n):
    return {f"r{i}": rng.uniform(-2, 2, n) for i in (1, 2, 3)}


def _field(fun, col):
    return lambda x: fun(x["r1"], x["r2"], x["r3"])[:, :, col]


def checks() -> list[Check]:
    notes = {"ψ0_44": "the printed [0, -x3, -x2] swaps the components: the second derivative of the "
                      "roll turn is e1 × (e1 × r) = [0, -x2, -x3]",
             "φ0_6": "printed with a fourth component 0 (dropped in the transcription)"}
    return [Check(SEED, "roller ũ", f"field {name} of the roller DOFs from the expanded rotation sequence",
                  _points, _field(printed.rigid_fields, col), _field(gen.rigid_fields, col), notes.get(name, ""))
            for col, name in enumerate(_NAMES)]
