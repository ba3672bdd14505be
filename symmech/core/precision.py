"""Work-precision diagrams: what accuracy costs in time.

A study is a list of rows ``{"method", "knob", "value", "error", "seconds"}``.
A kind's ``precision`` returns :func:`result`: a table with units and the diagram,
written by the pipeline like any run. The diagram draws log10(error) against
log10(seconds), one line per method, one marker per knob value.
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from symmech.core.results import Column, Result, Table

ERROR_FLOOR = 1e-17  # errors below double precision are drawn at this floor


def best_time(fn, repeats: int = 5, min_seconds: float = 0.02):
    """Smallest wall time per call of ``fn()`` over up to ``repeats`` batches [s], and its last result.

    A call slower than 0.5 s is timed once: its noise is small against its length.
    """
    result, best = None, np.inf
    for _ in range(repeats):
        calls, start = 0, time.perf_counter()
        while True:
            result = fn()
            calls += 1
            elapsed = time.perf_counter() - start
            if elapsed >= min_seconds:
                break
        best = min(best, elapsed / calls)
        if best > 0.5:
            break
    return best, result


COLUMNS = (Column("value", "1", "the knob's setting"),
           Column("error", "1", "relative error against the reference"),
           Column("seconds", "s", "best wall time per call"))


def result(kind: str, rows: list[dict], name: str, title: str, reference: str) -> Result:
    """A study as a :class:`Result` for the pipeline: table ``name`` (value, error, seconds;
    text columns method and knob), the reference in the summary, the diagram as its plot."""
    table = Table(COLUMNS, [[r["value"], r["error"], r["seconds"]] for r in rows], doc=title,
                  text={"method": [r["method"] for r in rows], "knob": [r["knob"] for r in rows]})
    return Result(kind, {"study": "precision", "reference": reference}, tables={name: table},
                  plots=lambda folder: diagram(rows, Path(folder), name, title, reference))


def diagram(rows: list[dict], folder: Path, name: str, title: str, reference: str,
            chosen: list[dict] = ()) -> list[Path]:
    """log error against log time, one line per method, as ``name``.png in ``folder``; the
    ``chosen`` rows (a run's own setting) ringed."""
    from symmech.core import plotting

    fig, axes = plotting.figure(1, 1, width=7.0, height=5.0)
    ax = axes[0, 0]
    for method in dict.fromkeys(r["method"] for r in rows):
        mine = [r for r in rows if r["method"] == method]
        ax.loglog([r["seconds"] for r in mine], [max(r["error"], ERROR_FLOOR) for r in mine],
                  "o-", label=method)
    if chosen:
        ax.loglog([r["seconds"] for r in chosen], [max(r["error"], ERROR_FLOOR) for r in chosen], "o", ms=16,
                  mfc="none", mec="red", mew=2, label="this run's setting")
    plotting.set_labels(ax, ("wall time per solve", "s"), ("relative error", "1"))
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    plotting.legend_beside(ax)
    fig.text(0.01, 0.01, f"reference: {reference}", fontsize=7)
    return plotting.save(fig, folder, name)
