"""Charts of a trolley design sweep (:mod:`symmech.trolley.sweep`): one per design number that varies over the
plane, a heat map over x and y or a line over x alone, each with the same best point (the decision's) starred,
the points that are not admissible hatched and labelled with what limits them, and the legend beside the data,
never on it."""
from __future__ import annotations

import numpy as np

from symmech.core import plotting
from symmech.core import sweep as core_sweep


def plots(values, axes, table, ok: np.ndarray, why: list, best: int | None, charts: list, folder) -> list:
    """The charts ``charts`` ((column, title, unit) triples) of the sweep ``table`` into ``folder``: ``values``
    the swept values along x and y ([nan] without y), ``axes`` (name, unit, log) of x and y if swept, ``ok``
    (n,) the admissible points, ``why`` (n lists of (label, sentence)) what limits the others, ``best`` the
    flat index of the best point (None: no admissible point)."""
    xs, ys = values
    shape = (len(xs), len(ys))
    (x_name, x_unit, x_log), *rest = axes
    labels = [", ".join(dict.fromkeys(label for label, _ in w)) for w in why]
    written = []
    for name, title, unit in charts:
        z = table.column(name).reshape(shape)
        fig, grid = plotting.figure(width=7.5, height=5.2)
        ax = grid[0, 0]
        if rest:
            (y_name, y_unit, y_log), = rest
            xe, ye = core_sweep.edges(xs, x_log), core_sweep.edges(ys, y_log)
            _plane(fig, ax, xe, ye, z, ok.reshape(shape), title, unit)
            core_sweep.cell_labels(ax, core_sweep.centres(xe, x_log), core_sweep.centres(ye, y_log), labels,
                                   shape)
            if best is not None:
                i, j = np.unravel_index(best, shape)
                ax.plot(xs[i], ys[j], "*", color="gold", ms=16, mec="k", clip_on=False,
                        label="best admissible point")
            plotting.set_labels(ax, (x_name, x_unit), (y_name, y_unit))
            ax.set_xlim(xe[0], xe[-1])
            ax.set_ylim(ye[0], ye[-1])
            for (_, _, log), scale in zip(axes, (ax.set_xscale, ax.set_yscale)):
                if log:
                    scale("log")
        else:
            core_sweep.line(ax, xs, z[:, 0], ok, labels, best, x_log, title)
            plotting.set_labels(ax, (x_name, x_unit), (title, unit))
        ax.set_title(title, fontsize=10)
        plotting.legend_below(ax, ncol=3)
        fig.tight_layout()
        written += plotting.save(fig, folder, f"sweep_{name}")
    return written


def _plane(fig, ax, xe, ye, z, ok, title, unit) -> None:
    """Heat map of z (nx, ny) over the cells with edges xe (nx + 1,) and ye (ny + 1,), with the border of the
    admissible points ``ok`` drawn around them and the others hatched."""
    mesh = ax.pcolormesh(xe, ye, z.T, shading="flat", cmap="viridis")
    fig.colorbar(mesh, ax=ax, label=plotting.label(title, unit))
    core_sweep.region_border(ax, xe, ye, ok, "admissible region border")
    if not ok.all():
        ax.pcolor(xe, ye, np.ma.masked_where(ok.T, ~ok.T), shading="flat", hatch="//", facecolor="none",
                  edgecolor="0.3", linewidth=0.0, label="not admissible (labelled: why)")
