"""Plots of a mechanism run (style from ``symmech.core.plotting``).

``modes_and_responses`` draws the mode shapes on the mechanism's geometry (links,
springs and dampers, centres of mass; a spatial mechanism in a top and a side
projection), each titled by its frequency, and the frequency and free responses
(:data:`FIGURES`; the scene's ``[output]`` table chooses); ``precision_plot`` draws the
eigen-solver study.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from symmech.core import plotting

MODES_SHOWN = 6
MODES_PER_ROW = 3  # panels wide enough to read at a report's width
# largest drawn displacement as a share of the mechanism's extent
MODE_SCALE = 0.15


def _frequency_text(i: int, omega) -> str:
    w = omega[i]
    return f"mode {i + 1}: " + ("unstable" if w is None else f"f = {w / (2 * math.pi):.4g} Hz")


def _draw(ax, m, at, color: str) -> None:
    """The mechanism with point positions ``at(name) -> (2,)``: links solid, springs/dampers dotted."""
    for p in m.points.values():
        if p.parent is not None:
            xy = np.array([at(p.parent), at(p.name)])
            ax.plot(xy[:, 0], xy[:, 1], "-", color=color, lw=1.5)
    for link in m.springs + m.dampers:
        xy = np.array([at(link.a), at(link.b)])
        ax.plot(xy[:, 0], xy[:, 1], ":", color=color, lw=1)
    for bd in m.bodies:
        ax.plot(*at(bd.com), "o", color=color, ms=5)


# plot name -> its caption (a sentence; also the plot's description in the scene's `[output]` docs)
FIGURES = {"modes": "The lowest mode shapes (up to six), each in colour over the mechanism's equilibrium geometry "
                    "(grey) and titled by its frequency [Hz].",
           "frequency_response": "Frequency response under the scene's [forcing]: amplitude of each coordinate "
                                 "(translations in m, rotations in rad) against the forcing frequency [Hz].",
           "free_response": "Free response from the scene's [initial] state: each coordinate (translations in m, rotations "
                            "in rad) against time [s]."}


def modes_and_responses(m, md, omega, response, out: Path, output: dict) -> list[str]:
    """The figures of :data:`FIGURES` that ``output`` (the scene's ``[output]`` table) asks for and
    the run computed; returns file names."""
    def frf():
        if "frf" in response:
            omegas, H = response["frf"]
            # in Hz, as the modes' legend: a peak sits at its mode's frequency
            return _curves(m, omegas / (2 * math.pi), np.maximum(np.abs(H), 1e-300), True,
                           ("forcing frequency f = ω/2π", "Hz"), "amplitude |q| under the scene's forcing",
                           "frequency response")

    def free():
        if "free" in response:
            t, q = response["free"]
            return _curves(m, t, q, False, ("time t", "s"), "coordinate q", "free response")

    figures = {"modes": lambda: _modes(m, md, omega), "frequency_response": frf, "free_response": free}
    return [p.name for p in plotting.draw(figures, output, out)]


def _modes(m, md, omega):
    from symmech.smm import forms
    from symmech.smm.model import NumericArith

    g = forms.Geometry(m, NumericArith(m.values()))
    kins = {p: forms.chain_kinematics(g, p, False) for p in m.points}
    pos = {p: np.array(k.r, float) for p, k in kins.items()}
    shown = min(len(omega), MODES_SHOWN)
    disps = [{p: np.array([sum(md.shapes[g.index[a], i] * d[j] for a, d in k.D.items()) for j in range(3)])
              for p, k in kins.items()} for i in range(shown)]
    spatial = any(abs(v[2]) > 0 for v in pos.values()) or any(abs(v[2]) > 0 for d in disps for v in d.values())
    # a spatial mechanism is drawn in two projections: top (x-y) and side (x-z)
    views = [(0, 1, "top view"), (0, 2, "side view")] if spatial else [(0, 1, "")]
    span = max(1e-9, float(np.ptp(np.array(list(pos.values())), axis=0).max()))
    # rows of MODES_PER_ROW panels per view; titles name the frequencies, so no legend covers a shape
    cols = min(shown, MODES_PER_ROW)
    rows = math.ceil(shown / cols)
    fig, axes = plotting.figure(len(views) * rows, cols, width=3.6 * cols, height=3.4)
    for ax in axes.flat:
        ax.set_visible(False)
    for first, (h, v, view) in zip(range(0, len(views) * rows, rows), views):
        for i in range(shown):
            ax = axes[first + i // cols, i % cols]
            ax.set_visible(True)
            disp = disps[i]
            amp = max(1e-300, max(np.linalg.norm(d) for d in disp.values()))
            scale = MODE_SCALE * span / amp
            _draw(ax, m, lambda n: pos[n][[h, v]], "0.7")
            _draw(ax, m, lambda n: (pos[n] + scale * disp[n])[[h, v]], f"C{i}")
            ax.set_title(_frequency_text(i, omega) + (f" ({view})" if view else ""), fontsize=9)
            plotting.set_labels(ax, ("x", "m"), ("y" if v == 1 else "z", "m"))
            ax.set_aspect("equal", adjustable="datalim")
            ax.tick_params(labelsize=7)
    fig.suptitle(f"{m.name}: mode shapes in colour over the equilibrium in grey (displacement scaled to "
                 f"{MODE_SCALE:.0%} of the extent)", fontsize=10)
    return fig


def _curves(m, x, ys, log: bool, xlabel: tuple, quantity: str, title: str):
    """One curve per coordinate (first eight) against x (``xlabel``: (quantity, unit)), one panel per coordinate
    unit (translations in m, rotations in rad), each labelled ``quantity [unit]``; ``ys`` is (len(x), n)."""
    shown = m.coordinates[:8]
    panels = {unit: [j for j, co in enumerate(shown) if co.unit == unit] for unit in dict.fromkeys(co.unit
                                                                                                 for co in shown)}
    fig, axes = plotting.figure(len(panels), 1, width=7.5, height=4.0 if len(panels) == 1 else 3.0, sharex=True)
    for ax, (unit, columns) in zip(axes[:, 0], panels.items()):
        for j in columns:
            (ax.semilogy if log else ax.plot)(x, ys[:, j], label=shown[j].name)
        plotting.set_labels(ax, xlabel, (quantity, unit))
        plotting.legend_beside(ax)
    axes[0, 0].set_title(f"{m.name}: {title}")
    fig.tight_layout()
    return fig


def precision_plot(out: Path, points, modes_n: int, title: str) -> list[Path]:
    """Error vs time of eigen-solvers; ``points`` are (method name, seconds, relative error)."""
    fig, axes = plotting.figure(1, 1, width=6.0, height=4.0)
    ax = axes[0, 0]
    for name, sec, err in points:
        ax.loglog(sec, max(err, 1e-17), "o")
        ax.annotate(name, (sec, max(err, 1e-17)), fontsize=7)
    plotting.set_labels(ax, ("time", "s"), (f"max relative error of the lowest {modes_n} omega^2", "1"))
    ax.set_title(title, fontsize=9)
    return plotting.save(fig, out, "precision")
