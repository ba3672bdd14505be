"""How well conditioned are the default grain scene's first 50 impacts (the grain FMU's accuracy target)?

The native compiled engine runs the bundled ``grain_default.toml`` over 0.5 s (113 impacts, its first landing at
0.0826 s after 13) at tolerances 1e-9, 1e-10 and 1e-11 and is compared with its own run at 1e-12, impact by
impact: the impact time and the centre at the impact. Were the impacts after the landing ill-conditioned (each
bounce multiplying an error, the landing's chatter amplifying it), no export could reproduce them within 1e-8 s;
the error at impact k against the tolerance says how much accuracy an exported model needs.

    python benchmarks/grain_conditioning.py
"""
from __future__ import annotations

import tempfile
import time
from pathlib import Path

import numpy as np

from symmech.core import pipeline
from symmech.core.scene import scenes_folder
from symmech.grain import motion_scene

TOLERANCES = (1e-9, 1e-10, 1e-11, 1e-12)
SHOWN = (1, 5, 8, 13, 14, 16, 21, 31, 41, 50)  # impact numbers printed (13: the landing, 14: the first after)


def impacts(tolerance: float, folder: Path) -> tuple[np.ndarray, np.ndarray]:
    """Impact times (n,) [s] and centres (n, 3) [m] of the default scene over 0.5 s at ``tolerance``."""
    text = (scenes_folder() / "grain_default.toml").read_text()
    text = text.replace("duration = 2.0 ", "duration = 0.5 ").replace("tolerance = 1e-9", f"tolerance = {tolerance!r}")
    path = folder / f"grain_{tolerance:g}.toml"
    path.write_text(text)
    run = motion_scene.simulate(pipeline.load(path).setup)
    return np.array([i["t"] for i in run.impacts]), np.array([i["r"] for i in run.impacts])


def main() -> None:
    with tempfile.TemporaryDirectory() as folder:
        runs = {}
        for tolerance in TOLERANCES:
            start = time.perf_counter()
            runs[tolerance] = impacts(tolerance, Path(folder))
            print(f"tolerance {tolerance:g}: {len(runs[tolerance][0])} impacts, {time.perf_counter() - start:.1f} s")
    ref_t, ref_r = runs[TOLERANCES[-1]]
    for tolerance in TOLERANCES[:-1]:
        t, r = runs[tolerance]
        n = min(50, len(t), len(ref_t))
        dt, dr = np.abs(t[:n] - ref_t[:n]), np.abs(r[:n] - ref_r[:n]).max(axis=1)
        print(f"tolerance {tolerance:g} against {TOLERANCES[-1]:g}, first {n} impacts: "
              f"time {dt.max():.2e} s, centre {dr.max():.2e} m")
        for k in (k for k in SHOWN if k <= n):
            print(f"  impact {k:2d} at {ref_t[k - 1]:.6f} s: time {dt[k - 1]:.2e} s, centre {dr[k - 1]:.2e} m")


if __name__ == "__main__":
    main()
