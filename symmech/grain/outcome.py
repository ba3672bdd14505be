"""What a run of either accurate-mode engine reports beside its trajectory, written once for both (the Python loop
of :mod:`symmech.grain.motion`, the compiled engine of :mod:`symmech.grain.motion_engine`): the energy budget, and
the texts of its warnings and errors. Paper mode shares the warnings' de-duplication."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class EnergyBudget:
    """Energy bookkeeping [J] of one run: the absolute energy at the start (kinetic in the inertial frame plus the
    potential of gravity) against the work of the surface and the losses in impacts, landings and sliding."""

    start: float
    work: float = 0.0
    impacts: float = 0.0
    landings: float = 0.0
    sliding: float = 0.0

    def report(self, end: float, tolerance: float) -> dict:
        """The summary's ``energy_budget`` for the absolute energy ``end`` [J] at the end: the parts, the residual
        of the balance and its size relative to the largest part, beside the stated ``tolerance``."""
        residual = end - self.start - (self.work - self.impacts - self.landings - self.sliding)
        scale = max(abs(self.start), abs(end), abs(self.work), self.impacts + self.landings + self.sliding)
        parts = (self.start, end, self.work, self.impacts, self.landings, self.sliding, residual,
                 abs(residual) / scale if scale > 0 else 0.0)
        return {**{k: float(v) for k, v in zip(BUDGET_KEYS, parts)}, "tolerance": tolerance}


BUDGET_KEYS = ("start_J", "end_J", "input_by_surface_J", "lost_in_impacts_J", "lost_at_landings_J",
               "lost_in_sliding_J", "residual_J", "relative_residual")


def budget_reports(start, end, work, impacts, landings, sliding, tolerance: float) -> list:
    """:meth:`EnergyBudget.report` of n runs at once (a population's results, built in bulk), from their parts (each
    an array (n,) [J]): the same operations element by element, the largest part chosen as Python's ``max`` does
    (a NaN first stays), so each dict equals the report of that run alone."""
    residual = end - start - (work - impacts - landings - sliding)
    scale = np.abs(start)
    for part in (np.abs(end), np.abs(work), impacts + landings + sliding):
        scale = np.where(part > scale, part, scale)
    relative = np.divide(np.abs(residual), scale, out=np.zeros_like(scale), where=scale > 0)
    columns = (start, end, work, impacts, landings, sliding, residual, relative)
    return [{**dict(zip(BUDGET_KEYS, row)), "tolerance": tolerance} for row in zip(*(c.tolist() for c in columns))]


def distinct(warnings: list) -> list:
    """The warnings in their first order, each once."""
    return list(dict.fromkeys(warnings))


# --------------------------------------------------------------------------- warnings


def max_impacts_warning(t: float, max_impacts: int) -> str:
    return f"stopped at t = {t:.6g} s after numerics.max_impacts = {max_impacts} impacts"


def chatter_warning(impacts: int, periods: float) -> str:
    return f"{impacts} impacts within {periods:g} periods: chattering summed into sliding"


def rocking_warning(count: int) -> str:
    """The warning of ``count`` rocking contacts."""
    return (f"{count} rocking contact(s): a tumbling ellipsoid held on the plane by its spin while the surface "
            "accelerates away; rocking is not modelled, so its tilting spin was dropped (booked as landing loss) "
            "and it flew on")


def printed_inadmissible_warning(creates_energy: bool) -> str:
    """The printed law had no admissible root; the one used creates energy or pulls the grain into the plane."""
    reason = "creates kinetic energy" if creates_energy else "pulls the grain into the plane (T_z < 0)"
    return f"printed impact law: no admissible root; the one used {reason}"


def printed_residual_warning(residual: float) -> str:
    return f"printed impact law: no solution of (19) (relative residual {residual:.3g})"


def energy_created_warning(law: str, before: float, after: float) -> str:
    """Impact law ``law`` raised the kinetic energy from ``before`` to ``after`` [J]."""
    return f"impact law '{law}' created energy: {before:.6g} J -> {after:.6g} J"


# --------------------------------------------------------------------------- errors


def stalled_error(t: float, idle_steps: int, regime: str) -> str:
    return (f"grain: the simulation stopped advancing at t = {t:.9g} s ({idle_steps} regime changes without "
            f"advancing time, {regime} regime)")


def sliding_stalled_error(t: float, events: int) -> str:
    return f"sliding stagnates at t = {t:.9g} s: {events} regime changes without advancing time"


def sliding_evaluations_error(t: float, evaluations: int) -> str:
    return f"sliding integration stagnates at t = {t:.9g} s (more than {evaluations} evaluations in one chunk)"


def integration_failed_error(what: str, t: float, why: str) -> str:
    """``what`` ("sliding integration", "torque-free rotation") failed at t [s] for the solver's reason ``why``."""
    return f"{what} failed at t = {t:.9g} s: {why}"
