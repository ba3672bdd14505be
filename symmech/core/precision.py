"""Work-precision diagrams: what accuracy costs in time.

A study is a list of rows ``{"method", "knob", "value", "error", "seconds"}``;
:func:`write` saves them as CSV and draws log10(error) against log10(seconds),
one line per method, one marker per knob value.
"""
from __future__ import annotations

import csv
import time
from pathlib import Path

import numpy as np

FIELDS = ("method", "knob", "value", "error", "seconds")
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


def write(rows: list[dict], out: Path, name: str, title: str, reference: str) -> list[Path]:
    """Write ``name``.csv, ``name``.png and ``name``.svg into ``out``; returns the CSV and PNG paths."""
    from symmech.core import plotting

    out = Path(out)
    csv_path, png_path = out / f"{name}.csv", out / f"{name}.png"
    with csv_path.open("w", newline="") as fh:
        fh.write(f"# reference: {reference}\n")
        writer = csv.DictWriter(fh, fieldnames=FIELDS)
        writer.writeheader()
        for row in rows:
            writer.writerow({k: row[k] for k in FIELDS})
    fig, axes = plotting.figure(1, 1, width=7.0, height=5.0)
    ax = axes[0, 0]
    for method in dict.fromkeys(r["method"] for r in rows):
        mine = [r for r in rows if r["method"] == method]
        ax.loglog([r["seconds"] for r in mine], [max(r["error"], ERROR_FLOOR) for r in mine],
                  "o-", label=method)
    plotting.set_labels(ax, ("wall time per solve", "s"), ("relative error", "1"))
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.text(0.01, 0.01, f"reference: {reference}", fontsize=7)
    plotting.save(fig, out, name)
    return [csv_path, png_path]
