"""One plotting style for every scene kind: figures, labelled axes, PNG + SVG files.

Every plot of symmech goes through here, so that all of them read alike: each
axis names a quantity and its unit (``"t [s]"``; :func:`save` refuses a figure
with an unlabelled axis), and each figure is written twice, as PNG (for a quick
look) and SVG (inlined by the HTML report).

The backend is matplotlib's choice (a notebook's inline backend, a GUI on a
desktop); only without a display and outside a notebook do we select Agg, so a
headless run never tries to open a window.
"""
from __future__ import annotations

import os
import re
import sys
from pathlib import Path

DPI = 110
FORMATS = ("png", "svg")
_UNIT = re.compile(r"\[[^\]]+\]\s*$")


def _headless() -> bool:
    if "ipykernel" in sys.modules or os.environ.get("MPLBACKEND"):
        return False
    if sys.platform in ("win32", "darwin"):
        return False
    return not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def pyplot():
    """``matplotlib.pyplot``, with Agg selected only on a headless machine outside a notebook."""
    import matplotlib

    if _headless():
        matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def label(quantity: str, unit: str) -> str:
    """Axis text ``"quantity [unit]"``; ``unit`` is SI, ``"1"`` for a dimensionless quantity."""
    return f"{quantity} [{unit}]"


def figure(rows: int = 1, cols: int = 1, *, width: float = 8.0, height: float = 3.2, **kwargs):
    """A figure and a (rows, cols) array of axes; ``height`` [in] per row, ``width`` [in] in all."""
    plt = pyplot()
    fig, axes = plt.subplots(rows, cols, figsize=(width, height * rows), squeeze=False, **kwargs)
    return fig, axes


def figure_3d(width: float = 7.0, height: float = 6.0):
    """A figure with one 3-D axes."""
    fig = pyplot().figure(figsize=(width, height))
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


def save(fig, folder: Path, stem: str) -> list[Path]:
    """Write ``stem.png`` and ``stem.svg`` into ``folder``, close ``fig``; returns both paths.

    A figure with an axis that does not name its quantity and unit is a bug: ValueError.
    """
    bad = unlabelled(fig)
    if bad:
        pyplot().close(fig)
        raise ValueError(f"plot {stem}: every axis needs 'quantity [unit]': " + "; ".join(bad))
    fig.tight_layout()
    paths = [Path(folder) / f"{stem}.{ext}" for ext in FORMATS]
    for path in paths:
        fig.savefig(path, dpi=DPI, metadata={"Date": None} if path.suffix == ".svg" else None)
    pyplot().close(fig)
    return paths
