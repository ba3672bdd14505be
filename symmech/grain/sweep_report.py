"""The answer of a grain sweep (:mod:`symmech.grain.sweep`) and its charts: which operating points are eligible
(the scene's ``[sweep.constraints]`` kept, no grain failed or warned there), the best eligible one (two
populations: the least overlap of their X velocities, ties to the larger |Δv_x|; one: the fastest transport),
what limits the others, and heat maps that all star that same point, hatch and label the points that are not
eligible, keep their cells within the swept range and state a quantity that does not vary instead of colouring
it."""
from __future__ import annotations

import numpy as np

from symmech.core import plotting
from symmech.core import sweep as core_sweep
from symmech.core import units
from symmech.core.results import Check, Headline

# the swept fields' names on charts and in answers
NAMES = {"vibration.amplitude": "vibration amplitude", "vibration.frequency": "vibration frequency",
         "vibration.angle_deg": "vibration angle", "vibration.phase_deg": "vibration phase",
         "surface.alpha_deg": "surface slope α", "surface.beta_deg": "surface tilt β",
         "sliding.friction": "sliding friction", "impact.e_n": "normal restitution e_n",
         "impact.e_t": "tangential restitution e_t", "impact.mu": "impact friction μ", "impact.e": "restitution e",
         "impact.lambda": "impact law λ"}
# a mean velocity or fraction whose spread over the plane is below this fraction of its size (plus, for a velocity,
# FLAT_ATOL: far below the grain engine's event and step tolerances) is stated, not charted
FLAT_RTOL = 1e-3
FLAT_ATOL = {"m/s": 1e-9}


def reasons(names: list[str], stats: list[dict], constraints: dict | None, failed: list, warned: list,
            shape: tuple[int, int]) -> list[list[tuple[str, str]]]:
    """Per point (x-major) why it is not eligible, as (chart label, sentence) pairs; empty: eligible.
    ``stats``: per population the statistics (nx, ny) arrays; ``failed``, ``warned``: (population, i, j, grain,
    message) of the grains that stopped or warned."""
    why = [[] for _ in range(int(np.prod(shape)))]
    for label, grains in (("failed grain", failed), ("warned grain", warned)):
        for name, i, j, g, msg in grains:
            text = msg if isinstance(msg, str) else msg[0]
            why[i * shape[1] + j].append((label, f"{name} grain {g}: {text}"))
    c = constraints or {}
    for name, st in zip(names, stats):
        if c.get("population") not in (None, name):
            continue
        for k, (v, hop) in enumerate(zip(st["mean_vx"].ravel(), st["hop_fraction"].ravel())):
            if c.get("min_mean_vx") is not None and not v >= c["min_mean_vx"]:
                why[k].append(("too slow", f"{name} moves at {units.format(v, 'm/s')} < "
                                           f"{units.format(c['min_mean_vx'], 'm/s')}"))
            lo, hi = c.get("hop_fraction_min"), c.get("hop_fraction_max")
            if (lo is not None and not hop >= lo) or (hi is not None and not hop <= hi):
                why[k].append(("hops", f"{name}'s hop fraction {hop:.2f} outside [{lo or 0:g}, "
                                       f"{1 if hi is None else hi:g}]"))
    return [list(dict.fromkeys(w)) for w in why]


def best(ok: np.ndarray, names: list[str], stats: list[dict], sep: dict | None) -> int | None:
    """The flat index of the best eligible point: with two populations (``sep``, the separation) the least
    overlap, ties to the larger |Δv_x|; with one the largest mean X velocity. None when no point is eligible."""
    if not ok.any():
        return None
    if sep is not None:
        order = np.lexsort((-np.abs(sep["delta_vx"].ravel()), sep["overlap"].ravel()))
    else:
        order = np.argsort(-stats[0]["mean_vx"].ravel(), kind="stable")
    return int(next(k for k in order if ok[k]))


def describe(axes: list[tuple], values: list[np.ndarray], mask: np.ndarray) -> str:
    """The range of each swept quantity over the points ``mask`` (n,), x-major over ``values`` (xs[, ys]);
    ``axes``: (name, unit, log) of x and y if swept."""
    grids = np.meshgrid(*values, indexing="ij")
    parts = []
    for (name, unit, _), grid in zip(axes, grids):
        lo, hi = grid.ravel()[mask].min(), grid.ravel()[mask].max()
        parts.append(f"{name} {units.format(lo, unit)}" + ("" if lo == hi else f" … {units.format(hi, unit)}"))
    return ", ".join(parts)


def answer(axes, values, why, k_best, names, stats, sep, precision, half_width) -> tuple:
    """(headline, checks, warnings, limited_by) of the sweep: the best point with its intervals and why, the
    eligible region, the grains needed for ± ``half_width`` m/s, what limits the rest."""
    ok = np.array([not w for w in why])
    headline = []
    if k_best is not None:
        where = describe(axes, values, np.arange(ok.size) == k_best)
        if sep is not None:
            lo, hi = sep["overlap_lo"].ravel()[k_best], sep["overlap_hi"].ravel()[k_best]
            headline.append(Headline("best operating point: least overlap", float(sep["overlap"].ravel()[k_best]),
                                     "1", f"95 % interval [{lo:.3g}, {hi:.3g}]; the least overlap of the X velocities "
                                     f"of {names[0]} and {names[1]} among the {int(ok.sum())} eligible points",
                                     where))
            dv = [sep[f"delta_vx{end}"].ravel()[k_best] for end in ("", "_lo", "_hi")]
            headline.append(Headline(f"Δv_x there ({names[0]} − {names[1]})", float(dv[0]), "m/s",
                                     f"95 % interval [{units.format(dv[1], 'm/s')}, {units.format(dv[2], 'm/s')}]: "
                                     f"{names[0] if dv[0] > 0 else names[1]} leads", where))
        else:
            st = stats[0]
            headline.append(Headline("best operating point: fastest transport", float(st["mean_vx"].ravel()[k_best]),
                                     "m/s", f"95 % interval [{units.format(st['mean_vx_lo'].ravel()[k_best], 'm/s')}, "
                                     f"{units.format(st['mean_vx_hi'].ravel()[k_best], 'm/s')}]", where))
    headline.append(Headline("eligible operating points", float(ok.sum()), "1",
                             f"of {ok.size}: " + (describe(axes, values, ok) if ok.any() else "none"), ""))
    needed = (precision.get("delta_vx_at_best") or {}).get("grains_needed")
    if needed is not None:
        measured = "Δv_x" if sep is not None else f"{names[0]}'s mean X velocity"  # one population: no difference
        headline.append(Headline("grains per population needed", float(needed), "1",
                                 f"for {measured} at the best point to ± {units.format(half_width, 'm/s')} (95 %)",
                                 ""))
    limited = {}
    for k, w in enumerate(why):
        for label, sentence in w:
            limited.setdefault(label, [k, sentence, []])[2].append(k)
    limited_by = [{"reason": label, "points": len(set(ks)), "where": describe(axes, values, np.isin(
        np.arange(ok.size), ks)), "first": first} for label, (_, first, ks) in limited.items()]
    checks = [Check("operating points eligible (constraints kept, no grain failed or warned)", float(ok.sum()), "1",
                    "> 0", "pass" if ok.any() else "fail")]
    warnings = [f"{c['points']} of {ok.size} point(s) limited by {c['reason']} at {c['where']}; first: {c['first']}"
                for c in limited_by]
    return headline, checks, warnings, limited_by


def charts(names, stats, sep) -> list[tuple[str, np.ndarray, str, str, bool]]:
    """(file stem, values (nx, ny), title, unit, diverging) of every chart."""
    out = [(f"{n}_mean_vx", st["mean_vx"], f"{n}: mean transport velocity", "m/s", False)
           for n, st in zip(names, stats)]
    out += [(f"{n}_hop_fraction", st["hop_fraction"], f"{n}: fraction of grains hopping", "1", False)
            for n, st in zip(names, stats)]
    if sep is not None:
        out.append(("separation_overlap", sep["overlap"], "overlap of the X-velocity distributions (1 = inseparable)",
                    "1", False))
        out.append(("separation_delta_vx", sep["delta_vx"], f"Δv_x = {names[0]} − {names[1]} (> 0: {names[0]} "
                    "leads)", "m/s", True))
    return out


def flat(charts_: list) -> dict:
    """The charts' quantities too flat to chart, stated: {stem: statement}."""
    return {stem: statement for stem, z, title, unit, _ in charts_
            for statement in [core_sweep.flat_statement(z.ravel(), title, unit, FLAT_RTOL, FLAT_ATOL.get(unit, 0.0))]
            if statement}


def caption(title: str, axes: list[tuple]) -> str:
    """A chart's caption, as a sentence (``axes``: (name, unit, log) of the swept fields)."""
    over = " and ".join(name for name, _, _ in axes)
    what = title[:1].upper() + title[1:]  # "Crop: mean transport velocity", "Δv_x = crop − weed ..."
    if len(axes) < 2:
        return (f"{what}, along {over}. The star is the best eligible operating point; the green band holds the "
                "eligible points, the others are labelled with what limits them.")
    return (f"{what}, over {over}. The star is the best eligible operating point; hatched cells are not eligible, "
            "labelled with what limits them; dotted lines are the throw number Γ.")


def plots(axes, values, gamma, charts_, why, k_best, folder) -> list:
    """Heat maps over the plane (two swept fields; ``axes``: their (name, unit, log)), the same best point
    starred on each, the points that are not eligible hatched and labelled, Γ = A ω²/g (``gamma`` (nx, ny))
    contoured."""
    if len(axes) < 2:
        return _lines(axes[0], values[0], charts_, why, k_best, folder)
    xs, ys = values
    xe, ye = (core_sweep.edges(v, log) for v, (_, _, log) in zip(values, axes))
    shape = (len(xs), len(ys))
    bad = np.array([bool(w) for w in why]).reshape(shape)
    labels = [", ".join(dict.fromkeys(label for label, _ in w)) for w in why]
    written = []
    for stem, z, title, unit, diverging in charts_:
        fig, grid = plotting.figure(width=7.5, height=5.2)
        ax = grid[0, 0]
        span = np.nanmax(np.abs(z)) if diverging and np.isfinite(z).any() else None
        mesh = ax.pcolormesh(xe, ye, z.T, shading="flat", cmap="RdBu_r" if diverging else "viridis",
                             vmin=-span if span else None, vmax=span)
        fig.colorbar(mesh, ax=ax, label=plotting.label(title, unit))
        if len(xs) > 1 and len(ys) > 1:
            lines = ax.contour(xs, ys, gamma.T, colors="0.2", linewidths=0.6, linestyles="dotted")
            ax.clabel(lines, fmt="Γ=%.2g", fontsize=7)
        core_sweep.region_border(ax, xe, ye, ~bad, "eligible region border")
        if bad.any():
            ax.pcolor(xe, ye, np.ma.masked_where(~bad.T, bad.T), shading="flat", hatch="//", facecolor="none",
                      edgecolor="0.3", linewidth=0.0, label="not eligible (labelled: why)")
            core_sweep.cell_labels(ax, *(core_sweep.centres(e, log) for e, (_, _, log) in zip((xe, ye), axes)),
                                   labels, shape)
        if k_best is not None:
            i, j = np.unravel_index(k_best, shape)
            ax.plot(xs[i], ys[j], "*", color="gold", ms=16, mec="k", clip_on=False, label="best operating point")
        plotting.set_labels(ax, *((name, unit) for name, unit, _ in axes))
        ax.set_xlim(xe[0], xe[-1])
        ax.set_ylim(ye[0], ye[-1])
        ax.set_title(title, fontsize=10)
        plotting.legend_below(ax)
        fig.tight_layout()
        written += plotting.save(fig, folder, stem)
    return written


def _lines(axis: tuple, xs: np.ndarray, charts_: list, why: list, k_best: int | None, folder) -> list:
    """A sweep along one axis (``axis``: its (name, unit, log); ``xs`` (n,) its values): one line chart per
    quantity of ``charts_``, the eligible points' cells shaded, the others labelled, the best point starred."""
    name, x_unit, log = axis
    ok = np.array([not w for w in why])
    labels = [", ".join(dict.fromkeys(label for label, _ in w)) for w in why]
    written = []
    for stem, z, title, unit, _ in charts_:
        fig, grid = plotting.figure(width=7.5, height=5.2)
        ax = grid[0, 0]
        core_sweep.line(ax, xs, z.ravel(), ok, labels, k_best, log, title, "eligible")
        plotting.set_labels(ax, (name, x_unit), (title, unit))
        ax.set_title(title, fontsize=10)
        plotting.legend_below(ax, ncol=3)
        written += plotting.save(fig, folder, stem)
    return written
