"""Plots of a trolley run (style from ``symmech.core.plotting``): track, reactions, overloads."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from symmech.core import plotting


def write_all(setup, res: dict, out: Path) -> list[Path]:
    """``track`` (3-D midline and centre-of-mass path), ``reactions``, ``overloads`` (PNG + SVG each)."""
    files = []
    first = res[1]
    s = first["s"]
    span = np.linspace(s.min(), s.max() + setup.body.l, 600)
    mid = setup.track.derivatives(span, 0)[0]
    fig, ax = plotting.figure_3d()
    # Fixed frame has X2 up: draw X1, X3 horizontal and X2 vertical.
    ax.plot(mid[:, 0], mid[:, 2], mid[:, 1], color="0.4", lw=1, label="midline X0(s)")
    for case, r in res.items():
        path = setup.track.derivatives(r["s"], 0)[0] + np.einsum("nji,j->ni", r["lam"], np.asarray(setup.body.r))
        ax.plot(path[:, 0], path[:, 2], path[:, 1], lw=1, label=f"centre of mass, case {case}")
    plotting.set_labels(ax, ("X1", "m"), ("X3", "m"), ("X2 (up)", "m"))
    ax.legend(loc="upper left", fontsize=8)
    files += plotting.save(fig, out, "track")

    fig, axes = plotting.figure(len(res), 1, sharex=True)
    for ax, (case, r) in zip(axes[:, 0], res.items()):
        for i in range(6):
            ax.plot(setup.t, r["P"][:, i], lw=1, label=f"P{i}")
        ax.set_ylabel(plotting.label(f"case {case}: reaction", "N"))
        ax.legend(ncol=6, fontsize=8)
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel(plotting.label("time t", "s"))
    files += plotting.save(fig, out, "reactions")
    files += overloads(setup, res, out)
    return files


def overloads(setup, res: dict, out: Path) -> list[Path]:
    """Overloads n (body axes, in units of g) of every case against the scene's comfort envelope band."""
    fig, axes = plotting.figure(3, 1, height=2.7, sharex=True)
    for i, (ax, (axis, (lo, hi))) in enumerate(zip(axes[:, 0], setup.comfort.items())):
        ax.axhspan(lo, hi, color="tab:green", alpha=0.12, label=f"comfort envelope [{lo:g}, {hi:g}] g")
        for case, r in res.items():
            n = r["overload"][:, i]
            ax.plot(setup.t, n, lw=1, label=f"case {case}")
            outside = (n < lo) | (n > hi)
            if outside.any():
                ax.plot(setup.t[outside], n[outside], ls="none", marker=".", ms=2, alpha=0.5, color="tab:red")
        ax.set_ylabel(plotting.label(f"overload n along {axis}", "g"))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper right")
    axes[0, 0].set_title("Overloads against the comfort envelope (red: outside)")
    axes[-1, 0].set_xlabel(plotting.label("time t", "s"))
    return plotting.save(fig, out, "overloads")


def work_precision(rows, path: Path) -> Path:
    """Log error vs log time, one line per (family, method); ``rows`` are
    (family, method, steps, fd_step, time_s, error); points are labelled by their knob.
    Writes ``path`` (PNG) and its SVG twin; returns both paths."""
    fig, axes = plotting.figure(1, 1, width=7.0, height=5.0)
    ax = axes[0, 0]
    for family, method in dict.fromkeys((r[0], r[1]) for r in rows):
        # In knob order: more steps, or a smaller difference step, along each line.
        pts = sorted(((r[4], max(r[5], 1e-16), r[3] if r[3] != "" else r[2])
                      for r in rows if (r[0], r[1]) == (family, method)),
                     key=lambda p: -p[2] if family == "physics" else p[2])
        ax.loglog([p[0] for p in pts], [p[1] for p in pts], marker="o", label=f"{family}: {method}")
        for t, e, knob in pts:
            ax.annotate(f"{knob:g}", (t, e), fontsize=6)
    plotting.set_labels(ax, ("time per run", "s"), ("max |P - P_exact|", "N"))
    ax.set_title("case 2 reactions: derivatives of Λ* (labels: steps or fd_step [m])")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=8)
    path = Path(path)
    return plotting.save(fig, path.parent, path.stem)


def elastic(setup, r: dict, modes: dict | None, comfort: dict | None, out: Path) -> list[Path]:
    """Plots of the elastic model (``r`` from :func:`symmech.trolley.elastic.simulate`):
    ``elastic_reactions`` (elastic beside rigid), ``elastic_deflections`` (rollers and report
    points), ``elastic_overloads`` (report points against the comfort envelope), ``campbell``
    (natural frequencies against position and speed, with the forcing frequencies)."""
    t = r["t"]
    fig, axes = plotting.figure(6, 1, height=1.8, sharex=True)
    for i, ax in enumerate(axes[:, 0]):
        ax.plot(t, r["P_rigid"][:, i], color="0.5", lw=1, ls="--", label="rigid")
        ax.plot(t, r["P"][:, i], lw=1, label="elastic")
        ax.set_ylabel(plotting.label(f"P{i}", "N"))
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8, ncol=2)
    axes[-1, 0].set_xlabel(plotting.label("time t", "s"))
    files = plotting.save(fig, out, "elastic_reactions")
    files += _deflections(setup, r, out)
    if setup.names and comfort:
        files += _point_overloads(setup, r, comfort, out)
    if modes is not None:
        files += campbell(modes, out)
    return files


def _deflections(setup, r, out: Path) -> list[Path]:
    fig, axes = plotting.figure(2, 1, sharex=True)
    if setup.system.rollers_on:
        for i in range(5):
            axes[0, 0].plot(r["t"], r["deflection"][:, i], lw=1, label=f"roller of P{i + 1}")
        axes[0, 0].legend(fontsize=8, ncol=5)
    axes[0, 0].set_ylabel(plotting.label("roller deflection d", "m"))
    for j, name in enumerate(setup.names):
        for k in range(3):
            axes[1, 0].plot(r["t"], r["probe_elastic"][:, j, k], lw=1, label=f"{name} e{k + 1}")
    if setup.names:
        axes[1, 0].legend(fontsize=8, ncol=3)
    axes[1, 0].set_ylabel(plotting.label("elastic deflection", "m"))
    axes[1, 0].set_xlabel(plotting.label("time t", "s"))
    for ax in axes[:, 0]:
        ax.grid(alpha=0.3)
    return plotting.save(fig, out, "elastic_deflections")


def _point_overloads(setup, r, comfort: dict, out: Path) -> list[Path]:
    fig, axes = plotting.figure(3, 1, height=2.7, sharex=True)
    for k, (ax, (axis, (lo, hi))) in enumerate(zip(axes[:, 0], comfort.items())):
        ax.axhspan(lo, hi, color="tab:green", alpha=0.12, label=f"comfort envelope [{lo:g}, {hi:g}] g")
        for j, name in enumerate(setup.names):
            ax.plot(r["t"], r["probe_overload"][:, j, k], lw=1, label=name)
        ax.set_ylabel(plotting.label(f"overload n along {axis}", "g"))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper right")
    axes[0, 0].set_title("Overloads at the report points (elastic model)")
    axes[-1, 0].set_xlabel(plotting.label("time t", "s"))
    return plotting.save(fig, out, "elastic_overloads")


def campbell(modes: dict, out: Path) -> list[Path]:
    """Natural frequencies of the linearisation against arc length and against speed, with
    the forcing frequencies (dashed) that a natural frequency should keep away from."""
    from symmech.trolley.elastic_scene import FORCING

    fig, axes = plotting.figure(1, 2, width=11.0, height=4.5, sharey=True)
    for ax, key, quantity in ((axes[0, 0], "s", ("arc length s", "m")), (axes[0, 1], "V0", ("speed V0", "m/s"))):
        x = modes[key]
        order = np.argsort(x)
        for k in range(modes["f"].shape[1]):
            ax.plot(x[order], modes["f"][order, k], marker=".", lw=0.8, color="tab:blue",
                    label="natural frequencies" if k == 0 else None)
        for j, (_, doc) in enumerate(FORCING):
            ax.plot(x[order], modes["forcing"][order, j], ls="--", lw=1, label=doc)
        plotting.set_labels(ax, quantity, ("frequency f", "Hz"))
        ax.set_yscale("log")
        natural = modes["f"][modes["f"] > 0]
        if natural.size:  # forcing frequencies far below every mode are of no interest
            ax.set_ylim(natural.min() / 20, natural.max() * 2)
        ax.grid(alpha=0.3, which="both")
    axes[0, 0].legend(fontsize=7)
    axes[0, 0].set_title("Campbell diagram along the track")
    return plotting.save(fig, out, "campbell")
