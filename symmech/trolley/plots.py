"""Plots of a trolley run (matplotlib, Agg backend): track, reactions, overloads."""
from __future__ import annotations

from pathlib import Path

import numpy as np


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def write_all(setup, res: dict, out: Path) -> list[Path]:
    """``track.png`` (3-D midline and centre-of-mass path), ``reactions.png``, ``overloads.png``."""
    plt = _pyplot()
    files = []
    first = res[1]
    s = first["s"]
    span = np.linspace(s.min(), s.max() + setup.body.l, 600)
    mid = setup.track.derivatives(span, 0)[0]
    fig = plt.figure(figsize=(7, 6))
    ax = fig.add_subplot(projection="3d")
    # Fixed frame has X2 up: draw X1, X3 horizontal and X2 vertical.
    ax.plot(mid[:, 0], mid[:, 2], mid[:, 1], color="0.4", lw=1, label="midline X0(s)")
    for case, r in res.items():
        path = setup.track.derivatives(r["s"], 0)[0] + np.einsum("nji,j->ni", r["lam"], np.asarray(setup.body.r))
        ax.plot(path[:, 0], path[:, 2], path[:, 1], lw=1, label=f"centre of mass, case {case}")
    ax.set_xlabel("X1 [m]")
    ax.set_ylabel("X3 [m]")
    ax.set_zlabel("X2 (up) [m]")
    ax.legend(loc="upper left", fontsize=8)
    files.append(_save(fig, out / "track.png", plt))

    fig, axes = plt.subplots(len(res), 1, figsize=(8, 3.2 * len(res)), squeeze=False, sharex=True)
    for ax, (case, r) in zip(axes[:, 0], res.items()):
        for i in range(6):
            ax.plot(setup.t, r["P"][:, i], lw=1, label=f"P{i}")
        ax.set_ylabel(f"case {case}: reaction [N]")
        ax.legend(ncol=6, fontsize=8)
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel("t [s]")
    files.append(_save(fig, out / "reactions.png", plt))

    fig, axes = plt.subplots(3, 1, figsize=(8, 8), sharex=True)
    for i, (ax, (axis, (lo, hi))) in enumerate(zip(axes, setup.comfort.items())):
        ax.axhspan(lo, hi, color="tab:green", alpha=0.12, label="comfort envelope")
        for case, r in res.items():
            ax.plot(setup.t, r["overload"][:, i], lw=1, label=f"case {case}")
        ax.set_ylabel(f"n along {axis} [g]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    axes[-1].set_xlabel("t [s]")
    files.append(_save(fig, out / "overloads.png", plt))
    return files


def _save(fig, path: Path, plt) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def work_precision(rows, path: Path) -> Path:
    """Log error vs log time, one line per (family, method); ``rows`` are
    (family, method, steps, fd_step, time_s, error); points are labelled by their knob."""
    plt = _pyplot()
    fig, ax = plt.subplots(figsize=(7, 5))
    for family, method in dict.fromkeys((r[0], r[1]) for r in rows):
        # In knob order: more steps, or a smaller difference step, along each line.
        pts = sorted(((r[4], max(r[5], 1e-16), r[3] if r[3] != "" else r[2])
                      for r in rows if (r[0], r[1]) == (family, method)),
                     key=lambda p: -p[2] if family == "physics" else p[2])
        ax.loglog([p[0] for p in pts], [p[1] for p in pts], marker="o", label=f"{family}: {method}")
        for t, e, knob in pts:
            ax.annotate(f"{knob:g}", (t, e), fontsize=6)
    ax.set_xlabel("time per run [s]")
    ax.set_ylabel("max |P - P_exact| [N]")
    ax.set_title("case 2 reactions: derivatives of Λ* (labels: steps or fd_step [m])")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    return _save(fig, path, plt)
