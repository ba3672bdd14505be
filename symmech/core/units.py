"""Readable units: the one place that picks a decimal prefix for an SI quantity.

Tables and CSV files keep plain SI; what a person reads (plot axes, the headline block
of ``symmech run``, the report) shows 0.23 mm rather than 0.00023 m. :func:`scale`
picks the prefix for a magnitude, :func:`format` writes one value with it; the
plotting style (:mod:`symmech.core.plotting`) rescales every axis through :func:`scale`.
"""
from __future__ import annotations

import math
import re

# Prefixes by power of ten, and the powers each SI unit may take (a unit not listed keeps its scale).
PREFIX = {-9: "n", -6: "µ", -3: "m", 0: "", 3: "k", 6: "M", 9: "G"}
# Lengths stop at mm and angles at mrad, as on an engineering drawing.
POWERS = {"m": (-3, 0, 3), "s": (-3, 0), "rad": (-3, 0), "N": (-6, -3, 0, 3, 6), "J": (-9, -6, -3, 0, 3, 6),
          "W": (-3, 0, 3, 6), "Pa": (0, 3, 6, 9), "Hz": (0, 3, 6)}
# A product or quotient of SI symbols ("m/s", "N m", "N s/m"), its leading one without a power
# (a prefix on "m^2" would scale by 1e-6); anything else ("m or rad") keeps its scale.
_SYMBOL = r"(?:kg|m|s|rad|N|J|W|Pa|Hz|K|A|V)"
_UNIT = re.compile(rf"^({_SYMBOL})(?:[ /*·]{_SYMBOL}(?:\^-?\d+)?)*$")


def scale(magnitude: float, unit: str) -> tuple[float, str]:
    """(factor, readable unit) for values of about ``magnitude`` in SI ``unit``: shown value = SI / factor.

    The prefix puts ``magnitude`` in [1, 1000) as far as the unit's prefixes reach,
    e.g. ``scale(2.3e-4, "m") == (1e-3, "mm")``, ``scale(23000, "N") == (1e3, "kN")``.
    """
    head = _UNIT.match(unit)
    powers = POWERS.get(head.group(1)) if head else None
    if not powers or not math.isfinite(magnitude) or magnitude <= 0:
        return 1.0, unit
    wanted = 3 * math.floor(math.log10(magnitude) / 3)
    power = min(max(wanted, powers[0]), powers[-1])
    return 10.0 ** power, PREFIX[power] + unit


def format(value: float, unit: str, digits: int = 3) -> str:
    """``value`` [SI ``unit``] as text in its readable unit, ``digits`` significant: ``"0.235 mm"``."""
    factor, shown = scale(abs(value), unit)
    number = f"{value / factor:.{digits}g}"
    return number if shown == "1" else f"{number} {shown}"
