"""Printed vs derived for the roller section of seed 002: the fields φ0, ψ0 of the five roller DOFs."""
from __future__ import annotations


from symmech.core.errata import Check, NotCompared
from symmech.generated import trolley_elastic as gen
from symmech.generated import trolley_elastic_printed as printed
from symmech.trolley import SEED

ROLE = "errata"  # found by symmech.core.discovery

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


def not_compared() -> list[NotCompared]:
    why_general = ("a general integral identity over an unspecified body; the elastic model assembles it from "
                   "its own fields and is tested against closed forms and a symbolic Lagrange route instead")
    return [
        NotCompared(SEED, "ε, γ", "quadratic strain relations (1 -> 2 -> 3 -> 1)",
                    "stated for a general 3-D body; the beams use their inextensible-beam reduction ε11 = u1' + ½ w'²"),
        NotCompared(SEED, "(6)-(8)", "equations of motion with the inertia integrals", why_general),
        NotCompared(SEED, "(9)", "inertia integrals of the deformed body", why_general + "; Ĩ00 = -∫ r̃ r̃ dm "
                    "prints the dyadic where the skew product -∫ ř̃ ř̃ dm is meant (lost notation)"),
        NotCompared(SEED, "Π^P", "roller potential ½ q0ᵀ K0 q0 and damping D0",
                    "definitions only; K0 = Cᵀ diag(k) C follows from the derived roller matrix C"),
    ]
