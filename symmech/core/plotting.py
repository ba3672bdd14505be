"""One plotting style for every scene kind: figures, labelled axes, PNG (and SVG) files.

Every plot of symmech goes through here, so that all of them read alike: each
axis names a quantity and its unit (``"t [s]"``; :func:`save` refuses a figure
with an unlabelled axis), and each figure is written in the formats the scene
asks for (``[output] formats``: PNG for a quick look, SVG for the HTML report).

Figures are drawn on matplotlib's ``Figure`` and written by the Agg canvas: no
pyplot, no backend and no window, in a terminal, a notebook or on a desktop alike.
:func:`draw` is the one loop of every kind over the plots its scene asks for.
"""
from __future__ import annotations

import re
from pathlib import Path
from typing import Callable

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


def save(fig, folder: Path, stem: str, formats: tuple[str, ...] = ("png",)) -> list[Path]:
    """Write ``stem.<format>`` into ``folder`` for each of ``formats``; returns the paths.

    A figure with an axis that does not name its quantity and unit is a bug: ValueError.
    """
    bad = unlabelled(fig)
    if bad:
        raise ValueError(f"plot {stem}: every axis needs 'quantity [unit]': " + "; ".join(bad))
    fig.tight_layout()
    paths = [Path(folder) / f"{stem}.{ext}" for ext in formats]
    for path in paths:
        fig.savefig(path, dpi=DPI, metadata={"Date": None} if path.suffix == ".svg" else None)
    return paths


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
