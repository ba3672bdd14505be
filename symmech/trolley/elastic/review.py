"""Headline, checks and sampling warning of the elastic trolley model, read off its Result.

What a person reads first about an elastic run (amplification of each reaction, largest
deflections, lowest natural frequency and the forcing nearest to it) and the verdicts on it
are taken from the tables the run writes, so they are the numbers of its CSV files.
"""
from __future__ import annotations

import math

import numpy as np

from symmech.core import units
from symmech.core.results import Check, Headline, Result, at_most, within
from symmech.trolley.elastic.scene import DEFLECTIONS, FORCING, Setup, sign_changes

ENERGY_TOLERANCE_PER_RTOL = 10.0  # relative energy residual allowed per unit of the integration's rtol
LIGHT_DAMPING = 0.1  # a mode damped less rings for several periods: the outputs must be able to show it
SAMPLES_PER_PERIOD = 4  # output samples per period of such a mode, to see its peaks and troughs
SAMPLING = "elastic: output samples per period of the highest lightly damped mode"


def review(setup: Setup, result: Result) -> tuple[list[Headline], list[Check], list[str]]:
    """(headline, checks, warnings) of an elastic run; nothing when no elastic effect is on."""
    if setup.system is None:
        return [], [], []
    tables = result.tables
    headline = _amplification(tables["elastic_reactions"]) + _deflections(setup, tables)
    checks = [at_most("elastic: energy balance closes (relative residual)",
                      result.summary["elastic"]["energy_residual_relative"], ENERGY_TOLERANCE_PER_RTOL * setup.rtol)]
    checks += [within(f"elastic: overload of {name} along {axis} in the comfort envelope", c["min_g"], c["max_g"],
                      tuple(c["envelope_g"]), "g")
               for name, axes in result.summary["elastic"].get("comfort", {}).items() for axis, c in axes.items()]
    if setup.system.rollers_on:
        checks.append(at_most("elastic: roller rotation within the small-rotation range",
                              result.summary["elastic"]["max_roller_rotation_rad"], setup.small_rotation, "rad",
                              otherwise="warn"))
        checks.append(contact_check(tables["elastic_reactions"]))
    warnings = []
    if "modes" in tables:
        headline += _frequencies(tables["modes"])
        sampling, warning = _sampling(setup, tables["modes"])
        checks += [c for c in (_resonance(setup, tables["modes"]), sampling) if c is not None]
        warnings += [warning] if warning else []
    return headline, checks, warnings


def contact_check(reactions) -> Check:
    """The rollers stay pressed: how many of P1…P5 change sign (a roller pressing on one side only would lift
    off), a failed check beside the warnings that say when."""
    P, P_rigid = (np.column_stack([reactions.column(f"P{i}{tail}") for i in range(6)]) for tail in ("", "_rigid"))
    lifted = [i for i, (kind, _) in sign_changes(P, P_rigid).items() if kind == "lift-off"]
    what = "elastic: rollers pressed, no reaction changing sign" + (
        f" (lift-off: {', '.join(f'P{i}' for i in lifted)})" if lifted else "")
    return at_most(what, len(lifted), 0)


def _amplification(reactions) -> list[Headline]:
    out = []
    for i in range(6):
        peak, rigid = (float(np.abs(reactions.column(f"P{i}{tail}")).max()) for tail in ("", "_rigid"))
        if rigid > 0:
            out.append(Headline(f"dynamic amplification of P{i}", peak / rigid, "1",
                                f"peak |P{i}| elastic {units.format(peak, 'N')} / rigid {units.format(rigid, 'N')}, "
                                "both carrying the beams and tip masses (the case rows: the rigid trolley alone)"))
    return out


def _deflections(setup: Setup, tables) -> list[Headline]:
    t = setup.t
    out = []
    if "roller_deflections" in tables:
        d = np.abs(tables["roller_deflections"].select([c.name for c in DEFLECTIONS]))
        i, j = np.unravel_index(np.argmax(d), d.shape)
        out.append(Headline("largest roller deflection", d[i, j], "m", f"roller of P{j + 1}", f"t = {t[i]:.4g} s"))
    for name in setup.names:
        e = np.linalg.norm(np.column_stack([tables["points"].column(f"{name}_e{k}") for k in (1, 2, 3)]), axis=1)
        i = int(np.argmax(e))
        if e[i] == 0:
            continue  # a point of the rigid trolley: nothing to deflect
        out.append(Headline(f"largest body deflection at {name}", e[i], "m",
                            "length of the elastic deflection of the body at the point", f"t = {t[i]:.4g} s"))
    return out


def _per_sample(modes, name: str) -> np.ndarray:
    """(samples, N) of a column of the modes table (one row per sample and mode_id, samples outer)."""
    return modes.column(name).reshape(-1, int(modes.column("mode_id").max()))


def _forcing(modes) -> np.ndarray:
    """(samples, 3) forcing frequencies [Hz] of :data:`FORCING`; zero where undefined."""
    return np.column_stack([_per_sample(modes, f"forcing_{name}")[:, 0] for name, _ in FORCING])


def _frequencies(modes) -> list[Headline]:
    """The lowest natural frequency (with the tracked mode it belongs to), and the forcing frequency
    that comes nearest to that mode."""
    f, zeta, forcing = _per_sample(modes, "f"), _per_sample(modes, "zeta"), _forcing(modes)
    if not (f > 0).any():
        return []  # no oscillating mode (every one overdamped or rigid)
    i, k = np.unravel_index(np.argmin(np.where(f > 0, f, np.inf)), f.shape)
    t, s = _per_sample(modes, "t")[:, 0], _per_sample(modes, "s")[:, 0]
    component = modes.text["component"][i * f.shape[1] + k]
    out = [Headline("lowest natural frequency", f[i, k], "Hz",
                    f"mode_id {k + 1} ({component}), damping ratio {zeta[i, k]:.3g}",
                    f"t = {t[i]:.4g} s, s = {s[i]:.4g} m")]
    gap = np.where((forcing > 0) & (f[:, k:k + 1] > 0), np.abs(forcing - f[:, k:k + 1]), np.inf)
    if np.isfinite(gap).any():
        n, j = np.unravel_index(np.argmin(gap), gap.shape)
        out.append(Headline("forcing frequency nearest to it", forcing[n, j], "Hz",
                            f"{FORCING[j][1]}; {100 * forcing[n, j] / f[n, k]:.3g} % of mode_id {k + 1} there",
                            f"t = {t[n]:.4g} s, s = {s[n]:.4g} m"))
    return out


def _resonance(setup: Setup, modes) -> Check | None:
    """Closest relative distance |f - f_forcing| / f_forcing of any natural to any (defined) forcing frequency."""
    f, forcing = _per_sample(modes, "f")[:, :, None], _forcing(modes)[:, None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        distance = np.where(forcing > 0, np.abs(f - forcing) / forcing, np.inf)
    closest = float(distance.min())
    if not math.isfinite(closest):
        return None
    return Check("elastic: natural frequencies away from the forcing frequencies (relative distance)", closest,
                 "1", f">= {setup.resonance_band:g}", "pass" if closest >= setup.resonance_band else "warn")


def _sampling(setup: Setup, modes) -> tuple[Check | None, str | None]:
    """Can the time series show the lightly damped modes? Samples per period of the highest one."""
    f, zeta = _per_sample(modes, "f"), _per_sample(modes, "zeta")
    top = float(np.where((zeta < LIGHT_DAMPING) & (f > 0), f, 0.0).max())
    if top == 0:
        return None, None
    rate = (len(setup.t) - 1) / (setup.t[-1] - setup.t[0])
    per_period = rate / top
    threshold = f">= {SAMPLES_PER_PERIOD} (mode at {top:.4g} Hz, damping < {LIGHT_DAMPING:g})"
    check = Check(SAMPLING, per_period, "1", threshold, "pass" if per_period >= SAMPLES_PER_PERIOD else "warn")
    if check.verdict == "pass":
        return check, None
    steps = math.ceil(SAMPLES_PER_PERIOD * top * (setup.t[-1] - setup.t[0]))
    return check, (f"elastic: the outputs are sampled at {rate:.3g} Hz, too coarse to show the mode at {top:.4g} Hz "
                   f"(damping ratio below {LIGHT_DAMPING:g}) the model computes: set time.steps >= {steps} for "
                   f"{SAMPLES_PER_PERIOD} samples per period")
