"""Plots of the grain kinds (style from ``symmech.core.plotting``).

``motion_plots`` draws the figures of a grain run named in :data:`MOTION`,
``impact_plots`` the figure of one impact (:data:`IMPACT`); a scene's ``[output]``
table chooses which of them are drawn and in which formats.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from symmech.core import plotting
from symmech.generated import grain_impact as gen
from symmech.grain.vectors import TRAJECTORY_ROW

# plot name -> its caption (a sentence; also the plot's description in the scene's `[output]` docs)
MOTION = {"path": "The grain's path: side view relative to the surface, and its centre height over time with the "
                  "impacts marked [m].",
          "velocity": "Centre velocity of the grain relative to the surface over time, the normal velocity just "
                      "after each impact marked [m/s].",
          "phase": "Phase portrait of the normal motion: centre height [m] against normal velocity [m/s]."}
IMPACT = {"impact": "The impact's scalar equation F(μ) with its roots (o admissible, x not), and a top view of the "
                    "slip before and after and of the tangential impulse."}


def _impact_states(result) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Impact times [s] (n,), positions [m] (n, 3), velocities before and after [m/s] (n, 3)."""
    if not result.impacts:
        empty = np.zeros((0, 3))
        return np.zeros(0), empty, empty, empty
    return tuple(np.array([i[k] for i in result.impacts], float) for k in ("t", "r", "v_before", "v_after"))


def motion_plots(sc, result, out: Path, output: dict) -> list[Path]:
    """The figures of :data:`MOTION` that ``output`` (the scene's ``[output]`` table) asks for,
    of a grain run, relative to the surface frame."""
    tr = TRAJECTORY_ROW.split(result.trajectory)  # t (n, 1), r, v (n, 3) relative to the surface
    t, r, v = tr["t"][:, 0], tr["r"], tr["v"]
    hits, r_hit, v_before, v_after = _impact_states(result)
    impact_style = {"ls": "none", "marker": "o", "ms": 3, "mfc": "none", "color": "tab:red"}

    def path():
        s = sc.model.vibration.kinematics(t)[..., 0, :]  # surface displacement (n, 3) [m]
        fig, axes = plotting.figure(2, 1, height=3.0)
        side, height = axes[:, 0]
        side.plot(r[:, 0] + s[:, 0], r[:, 2] + s[:, 2], lw=0.8, label="centre of mass")
        side.plot(r[:, 0] + s[:, 0], s[:, 2], lw=0.8, color="k", label="surface under the grain")
        plotting.set_labels(side, ("X along the surface", "m"), ("Z", "m"))
        side.set_title("Side view (surface frame at its rest position)")
        plotting.legend_beside(side)
        height.plot(t, r[:, 2], lw=0.8, label="centre height above the surface")
        height.plot(hits, r_hit[:, 2], **impact_style, label=f"impacts ({hits.size})")
        plotting.set_labels(height, ("time t", "s"), ("relative height z", "m"))
        plotting.legend_beside(height)
        return fig

    def velocity():
        fig, axes = plotting.figure(1, 1, height=4.0)
        ax = axes[0, 0]
        for k, name in enumerate(("v_x", "v_y", "v_z")):
            ax.plot(t, v[:, k], lw=0.8, label=f"{name} (relative)")
        ax.plot(hits, v_after[:, 2], **impact_style, label=f"v_z just after each impact ({hits.size})")
        plotting.set_labels(ax, ("time t", "s"), ("centre velocity relative to the surface", "m/s"))
        ax.set_title("Centre velocity relative to the surface")
        plotting.legend_beside(ax)
        return fig

    def phase():
        fig, axes = plotting.figure(1, 1, width=6.0, height=5.0)
        ax = axes[0, 0]
        ax.plot(r[:, 2], v[:, 2], lw=0.6, color="tab:blue", label="flight and sliding")
        ax.plot(r_hit[:, 2], v_before[:, 2], ls="none", marker="v", ms=4, color="tab:red",
                label="just before impact")
        ax.plot(r_hit[:, 2], v_after[:, 2], ls="none", marker="^", ms=4, color="tab:green",
                label="just after impact")
        plotting.set_labels(ax, ("relative height z", "m"), ("normal velocity v_z", "m/s"))
        ax.set_title("Phase portrait of the normal motion")
        ax.grid(alpha=0.3)
        plotting.legend_beside(ax)
        return fig

    return plotting.draw({"path": path, "velocity": velocity, "phase": phase}, output, out)


def impact_plots(H, sc, result, out: Path, output: dict) -> list[Path]:
    """The figure of :data:`IMPACT` if ``output`` (the scene's ``[output]`` table) asks for it."""
    return plotting.draw({"impact": lambda: _impact_figure(H, sc, result)}, output, out)


def _impact_figure(H, sc, result):
    """F(mu) with every root marked by verdict, and a top view of slip and impulse."""
    uK0 = result.uK_before
    k = gen.mu_equation(H[0, 0], H[0, 1], H[0, 2], H[1, 1], H[1, 2], H[2, 2], sc.lam, sc.e, *uK0)
    mu = np.linspace(-np.pi, np.pi, 721)
    F = k[0] + k[1] * np.cos(mu) + k[2] * np.sin(mu) + k[3] * np.cos(2 * mu) + k[4] * np.sin(2 * mu)
    fig, axes = plotting.figure(1, 2, width=11.0, height=4.5)
    left, right = axes[0]
    left.plot(np.degrees(mu), F, "k-", lw=1)
    left.axhline(0, color="0.6", lw=0.8)
    for root in result.roots:
        bad = root["creates_energy"] or root["pulling"]
        left.plot(np.degrees(root["mu"]), 0, "x" if bad else "o", ms=9, color="tab:red" if bad else "tab:green")
    left.plot(np.degrees(result.mu), 0, "s", mfc="none", ms=14, color="tab:blue", label="chosen root")
    # F = det[H d, H e_z, du_K]: H is dimensionless, du_K a velocity
    plotting.set_labels(left, ("slip angle μ", "deg"), ("F(μ)", "m/s"))
    left.set_title("exact scalar equation: o admissible, x not")
    plotting.legend_beside(left)
    scale = max(np.hypot(*uK0[:2]), 1e-12)
    t_scale = max(np.hypot(*result.T[:2]), 1e-30)
    for vec, label, color in ((uK0[:2] / scale, "slip before", "tab:orange"),
                              (result.uK_after[:2] / scale, "slip after", "tab:green"),
                              (result.T[:2] / t_scale, "tangential impulse (unit)", "tab:blue")):
        right.annotate("", xy=vec, xytext=(0, 0), arrowprops={"arrowstyle": "->", "color": color, "lw": 2})
        right.plot([], [], color=color, label=label)
    right.set(xlim=(-1.2, 1.2), ylim=(-1.2, 1.2), aspect="equal", title="contact point, top view")
    plotting.set_labels(right, ("X / |V_K(0)|", "1"), ("Y / |V_K(0)|", "1"))
    plotting.legend_beside(right)
    right.grid(alpha=0.3)
    return fig
