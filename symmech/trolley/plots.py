"""Plots of a trolley run (style from ``symmech.core.plotting``): track, reactions, overloads
(:data:`FIGURES`; the scene's ``[output]`` table chooses), and the precision study."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from symmech.core import plotting
from symmech.core.results import readable


# plot name -> its caption (a sentence; also the plot's description in the scene's `[output]` docs)
FIGURES = {"track": "The track's midline X0(s) and the centre-of-mass path of every case, in the fixed frame [m].",
           "reactions": "Rail reactions P0…P5 along the ride, one panel per case [N].",
           "overloads": "Overloads n1, n2, n3 along the ride against the comfort envelope (green band; red: "
                        "outside) [g].",
           "elastic_reactions": "Elastic model: rail reactions P0…P5 along the ride beside the rigid ones [N].",
           "elastic_deflections": "Elastic model: roller deflections and the elastic deflection of the report points "
                                  "along the ride [m].",
           "elastic_overloads": "Elastic model: overloads at the report points along the ride against the comfort "
                                "envelope [g].",
           "campbell": "Campbell diagram of the elastic model: natural frequencies against arc length and speed, "
                       "with the forcing frequencies [Hz]."}


def write_all(setup, res: dict, out: Path, output: dict) -> list[Path]:
    """The rigid model's figures of :data:`FIGURES` that ``output`` (the scene's ``[output]`` table)
    asks for (the elastic ones: :func:`elastic_figures`)."""
    return plotting.draw({"track": lambda: _track(setup, res), "reactions": lambda: _reactions(setup, res),
                          "overloads": lambda: _overloads(setup, res)}, output, out)


def _track(setup, res: dict):
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
    plotting.legend_beside(ax)
    return fig


def _reactions(setup, res: dict):
    fig, axes = plotting.figure(len(res), 1, sharex=True)
    for ax, (case, r) in zip(axes[:, 0], res.items()):
        for i in range(6):
            ax.plot(setup.t, r["P"][:, i], lw=1, label=f"P{i}")
        ax.set_ylabel(plotting.label(f"case {case}: reaction", "N"))
        plotting.legend_beside(ax)
        ax.grid(alpha=0.3)
    axes[-1, 0].set_xlabel(plotting.label("time t", "s"))
    return fig


def _overloads(setup, res: dict):
    """Overloads n (body axes, in units of g) of every case against the scene's comfort envelope band."""
    curves = {f"case {case}": r["overload"] for case, r in res.items()}
    return _envelope_panels(setup.t, curves, setup.comfort, "Overloads against the comfort envelope (red: outside)")


def _envelope_panels(t, curves: dict, comfort: dict, title: str):
    """One panel per body axis: each curve's overload (label -> (n, 3) [g]) over the comfort band, with the
    samples outside the band marked red."""
    fig, axes = plotting.figure(3, 1, height=2.7, sharex=True)
    for k, (ax, (axis, (lo, hi))) in enumerate(zip(axes[:, 0], comfort.items())):
        ax.axhspan(lo, hi, color="tab:green", alpha=0.12, label=f"comfort envelope [{lo:g}, {hi:g}] g")
        for label, overload in curves.items():
            n = overload[:, k]
            ax.plot(t, n, lw=1, label=label)
            outside = (n < lo) | (n > hi)
            if outside.any():
                ax.plot(t[outside], n[outside], ls="none", marker=".", ms=2, alpha=0.5, color="tab:red")
        ax.set_ylabel(plotting.label(f"overload n along {axis}", "g"))
        ax.grid(alpha=0.3)
        plotting.legend_beside(ax)
    axes[0, 0].set_title(title)
    axes[-1, 0].set_xlabel(plotting.label("time t", "s"))
    return fig


def work_precision(rows, path: Path) -> Path:
    """Log error vs log time, one line per (family, method); ``rows`` are
    (family, method, steps, fd_step, time_s, error); points are labelled by their knob.
    Writes ``path`` (PNG); returns it in a list."""
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
    plotting.legend_beside(ax)
    path = Path(path)
    return plotting.save(fig, path.parent, path.stem)


def elastic_figures(setup, r: dict, modes: dict | None, comfort: dict | None) -> dict:
    """Builders of the elastic model's figures (``r`` from :func:`symmech.trolley.elastic.simulate.simulate`),
    named as in :data:`FIGURES`; a builder returns None when its figure has nothing to show."""
    return {"elastic_reactions": lambda: _elastic_reactions(r),
            "elastic_deflections": lambda: _deflections(setup, r),
            "elastic_overloads": lambda: _point_overloads(setup, r, comfort) if setup.names and comfort else None,
            "campbell": lambda: campbell(modes) if modes is not None else None}


def _elastic_reactions(r: dict):
    t = r["t"]
    fig, axes = plotting.figure(6, 1, height=1.8, sharex=True)
    for i, ax in enumerate(axes[:, 0]):
        ax.plot(t, r["P_rigid"][:, i], color="0.5", lw=1, ls="--", label="rigid")
        ax.plot(t, r["P"][:, i], lw=1, label="elastic")
        ax.set_ylabel(plotting.label(f"P{i}", "N"))
        ax.grid(alpha=0.3)
    plotting.legend_beside(axes[0, 0])
    axes[-1, 0].set_xlabel(plotting.label("time t", "s"))
    return fig


def _deflections(setup, r):
    fig, axes = plotting.figure(2, 1, sharex=True)
    if setup.system.rollers_on:
        for i in range(5):
            axes[0, 0].plot(r["t"], r["deflection"][:, i], lw=1, label=f"roller of P{i + 1}")
        plotting.legend_beside(axes[0, 0])
    axes[0, 0].set_ylabel(plotting.label("roller deflection d", "m"))
    for j, name in enumerate(setup.names):
        for k in range(3):
            axes[1, 0].plot(r["t"], r["probe_elastic"][:, j, k], lw=1, label=f"{name} e{k + 1}")
    if setup.names:
        plotting.legend_beside(axes[1, 0])
    axes[1, 0].set_ylabel(plotting.label("elastic deflection", "m"))
    axes[1, 0].set_xlabel(plotting.label("time t", "s"))
    for ax in axes[:, 0]:
        ax.grid(alpha=0.3)
    return fig


def _point_overloads(setup, r, comfort: dict):
    curves = {name: r["probe_overload"][:, j] for j, name in enumerate(setup.names)}
    return _envelope_panels(r["t"], curves, comfort, "Overloads at the report points (elastic model, red: outside)")


def campbell(modes: dict):
    """Natural frequencies of the linearisation against arc length and against speed, one line
    per tracked mode (``mode_id``: crossings keep their identity), coloured by the beam plane or
    the rollers dominating it at the first sample, with the forcing frequencies (black, dashed
    and dotted) that a natural frequency should keep away from."""
    from symmech.trolley.elastic.body import FORCING

    fig, axes = plotting.figure(1, 2, width=11.0, height=4.5, sharey=True)
    groups = [label.rsplit("_mode", 1)[0] if label.startswith("beam") else "rollers" for label in modes["label"][0]]
    colours = {g: f"C{i % 10}" for i, g in enumerate(dict.fromkeys(groups))}
    natural = modes["f"][modes["f"] > 0]
    # forcing frequencies far below every mode are of no interest: neither drawn nor in the legend
    low, high = (natural.min() / 20, natural.max() * 2) if natural.size else (0.0, np.inf)
    for ax, key, quantity in ((axes[0, 0], "s", ("arc length s", "m")), (axes[0, 1], "V0", ("speed V0", "m/s"))):
        x = modes[key]
        order = np.argsort(x)
        for k, group in enumerate(groups):
            ax.plot(x[order], modes["f"][order, k], marker=".", lw=0.8, color=colours[group],
                    label=readable(group) if groups.index(group) == k else None)
        for j, ((_, doc), style) in enumerate(zip(FORCING, ("--", ":", "-."))):
            forcing = modes["forcing"][order, j]
            if np.any((forcing >= low) & (forcing <= high)):
                ax.plot(x[order], forcing, ls=style, lw=1, color="k", label=doc)
        plotting.set_labels(ax, quantity, ("frequency f", "Hz"))
        ax.set_yscale("log")
        if natural.size:
            ax.set_ylim(low, high)
        ax.grid(alpha=0.3, which="both")
    plotting.legend_beside(axes[0, 1])  # the same lines on both panels: one legend, beside the right one
    axes[0, 0].set_title("Campbell diagram along the track")
    return fig
