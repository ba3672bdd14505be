"""One plotting style for every scene kind: figures, labelled axes, PNG (and SVG) files.

Every plot of symmech goes through here, so that all of them read alike: each
axis names a quantity and its unit (``"t [s]"``; :func:`save` refuses a figure
with an unlabelled axis, or with a legend over data), shown in a readable scale of it (:func:`readable_units`:
deflections in mm, reactions in kN; the data stay SI), and each figure is written
in the formats the scene asks for (``[output] formats``: PNG for a quick look, SVG
for the HTML report).

Figures are drawn on matplotlib's ``Figure`` and written by the Agg canvas: no
pyplot, no backend and no window, in a terminal, a notebook or on a desktop alike.
:func:`draw` is the one loop of every kind over the plots its scene asks for.
"""
from __future__ import annotations

import re
from pathlib import Path
from collections.abc import Callable

from symmech.core import units

DPI = 110
FORMATS = ("png", "svg")  # formats a scene may ask for
_UNIT = re.compile(r"\[[^\]]+\]\s*$")


def label(quantity: str, unit: str) -> str:
    """Axis text ``"quantity [unit]"``; ``unit`` is SI, ``"1"`` for a dimensionless quantity."""
    return f"{quantity} [{unit}]"


def figure(rows: int = 1, cols: int = 1, *, width: float = 8.0, height: float = 3.2, **kwargs):
    """A figure and a (rows, cols) array of axes; ``height`` [in] per row, ``width`` [in] in all."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height * rows))
    return fig, fig.subplots(rows, cols, squeeze=False, **kwargs)


def figure_3d(width: float = 7.0, height: float = 6.0):
    """A figure with one 3-D axes."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height))
    return fig, fig.add_subplot(projection="3d")


def set_labels(ax, x: tuple[str, str], y: tuple[str, str], z: tuple[str, str] | None = None) -> None:
    """Label ``ax`` with (quantity, unit) pairs."""
    ax.set_xlabel(label(*x))
    ax.set_ylabel(label(*y))
    if z is not None:
        ax.set_zlabel(label(*z))


def legend_beside(ax, ncol: int = 1) -> None:
    """The axes' legend to their right, outside the data (none when no artist is labelled)."""
    handles, names = ax.get_legend_handles_labels()
    if handles:
        ax.legend(handles, names, fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0,
                  ncol=ncol)


def legend_below(ax, ncol: int = 2) -> None:
    """The axes' legend under them, outside the data (none when no artist is labelled)."""
    handles, names = ax.get_legend_handles_labels()
    if handles:
        ax.legend(handles, names, fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=ncol,
                  frameon=False)


def unlabelled(fig) -> list[str]:
    """Descriptions of the visible axes of ``fig`` whose x, y (or z) label lacks a ``[unit]``."""
    def labelled(axes, name):
        return any(_UNIT.search(getattr(a, f"get_{name}label")()) for a in axes)

    bad = []
    for i, ax in enumerate(fig.axes):
        if not ax.get_visible() or not ax.axison:
            continue
        if ax.get_label() == "<colorbar>":  # one long axis, labelled by the colorbar's label
            if not (_UNIT.search(ax.get_xlabel()) or _UNIT.search(ax.get_ylabel())):
                bad.append(f"axes {i} (colorbar): label {ax.get_ylabel() or ax.get_xlabel()!r}")
            continue
        # axes sharing x (or y) are labelled once, on the outer one
        checks = {"x": ax.get_shared_x_axes().get_siblings(ax), "y": ax.get_shared_y_axes().get_siblings(ax)}
        if hasattr(ax, "get_zlabel"):
            checks["z"] = [ax]
        for name, axes in checks.items():
            if not labelled(axes, name):
                text = getattr(ax, f"get_{name}label")()
                bad.append(f"axes {i} ({ax.get_title() or 'untitled'}): {name} label {text!r}")
    return bad


def covering_legends(fig) -> list[str]:
    """Descriptions of the legends of ``fig`` drawn over the data area of a visible axes (its own or a
    neighbour's): they hide curves; :func:`legend_beside` and :func:`legend_below` put them outside."""
    areas = [(j, ax.get_window_extent()) for j, ax in enumerate(fig.axes) if ax.get_visible()]
    bad = []
    for i, ax in enumerate(fig.axes):
        legend = ax.get_legend()
        if legend is None or not ax.get_visible():
            continue
        box = legend.get_window_extent()
        bad += [f"axes {i} ({ax.get_title() or 'untitled'}): legend over the data of axes {j}"
                for j, area in areas if box.overlaps(area)]
    return bad


def _siblings(ax, name: str) -> list:
    if name == "z":
        return [ax]
    return getattr(ax, f"get_shared_{name}_axes")().get_siblings(ax)


def readable_units(fig) -> None:
    """Show each linear axis of ``fig`` labelled in an SI unit in a readable scale of it
    (:func:`symmech.core.units.scale` of the axis limits): tick labels divided by the factor and
    the label's unit rewritten, e.g. ``"d [m]"`` with ticks 0.0002 -> ``"d [mm]"`` with ticks 0.2."""
    from matplotlib.ticker import FuncFormatter

    for ax in fig.axes:  # a colour bar too: its long axis carries its label
        for name in ("x", "y", "z") if hasattr(ax, "get_zlabel") else ("x", "y"):
            if getattr(ax, f"get_{name}scale")() != "linear":
                continue
            labelled = [a for a in _siblings(ax, name) if _UNIT.search(getattr(a, f"get_{name}label")())]
            if not labelled:
                continue
            text = getattr(labelled[0], f"get_{name}label")()
            unit = _UNIT.search(text).group(0).strip()[1:-1]
            factor, shown = units.scale(max(abs(v) for v in getattr(ax, f"get_{name}lim")()), unit)
            if factor == 1.0:
                continue  # already readable, or a unit without prefixes (a rewritten label lands here too)
            getattr(ax, f"{name}axis").set_major_formatter(FuncFormatter(lambda v, _, f=factor: f"{v / f:g}"))
            for a in labelled:
                label_text = getattr(a, f"get_{name}label")()
                getattr(a, f"set_{name}label")(_UNIT.sub(f"[{shown}]", label_text))


def save(fig, folder: Path, stem: str, formats: tuple[str, ...] = ("png",)) -> list[Path]:
    """Write ``stem.<format>`` into ``folder`` for each of ``formats``; returns the paths.

    A figure with an axis that does not name its quantity and unit, or with a legend over data, is a bug:
    ValueError. Axes in SI units are shown in a readable scale (:func:`readable_units`).
    """
    bad = unlabelled(fig)
    if bad:
        raise ValueError(f"plot {stem}: every axis needs 'quantity [unit]': " + "; ".join(bad))
    readable_units(fig)
    fig.tight_layout()
    bad = covering_legends(fig)
    if bad:
        raise ValueError(f"plot {stem}: a legend hides data (plotting.legend_beside): " + "; ".join(bad))
    paths = [Path(folder) / f"{stem}.{ext}" for ext in formats]
    for path in paths:
        # the tight box holds what sits outside the axes (legends beside them, labels over an end cell) uncut
        fig.savefig(path, dpi=DPI, bbox_inches="tight", metadata={"Date": None} if path.suffix == ".svg" else None)
    return paths


def captions(descriptions: dict[str, str], output: dict) -> dict[str, str]:
    """{plot name: caption sentence} of the plots of a kind (``descriptions``, as its ``[output]`` docs) that the
    scene's resolved ``[output]`` table asks for; a run records them as ``summary["captions"]`` for the report."""
    return {name: descriptions[name] for name in output["plots"] if name in descriptions}


def draw(figures: dict[str, Callable[[], object]], output: dict, folder: Path) -> list[Path]:
    """Build and save the figures a scene asks for.

    ``figures`` maps each plot name of a kind to a zero-argument builder returning a Figure
    (or None when there is nothing to draw); ``output`` is the scene's resolved ``[output]``
    table (:func:`symmech.core.schema.plot_output`): ``plots`` (names, in order) and
    ``formats``. Only the asked figures are built, so an unasked plot costs nothing; an asked
    name that ``figures`` does not build belongs to another part of the kind's run (e.g. the
    elastic model's figures beside the rigid ones) and is left to that part.
    """
    files = []
    for name in (n for n in output["plots"] if n in figures):
        fig = figures[name]()
        if fig is not None:
            files += save(fig, folder, name, tuple(output["formats"]))
    return files
