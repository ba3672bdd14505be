"""A registered scene kind that exercises the pipeline machinery, not physics.

``fail`` says where the run goes wrong (in ``run``, half-way through writing the
plots, with a NaN, with an internal bug), ``hold`` keeps the run (or the plot
writing) busy until the file ``release`` appears, after touching ``ready`` — so
a test can interrupt it or start a second run at a known moment. ``file`` names
an extra output file, to check that files of an earlier scene do not survive.
Subprocess tests run ``python tests/probe_kind.py ARGS...`` (symmech's CLI with
this kind registered).
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from symmech.core import registry
from symmech.core.registry import Estimate, Kind
from symmech.core.results import Column, Result, Table
from symmech.core.scene import SceneError
from symmech.core.schema import Choice, Float, Int, Str, Table as Schema

SCHEMA = Schema("probe scene", {
    "kind": Choice("scene kind", choices=("probe",)),
    "rows": Int("rows of the table", lo=1, hi=1000, default=3),
    "fail": Choice("where the run fails", choices=("never", "run", "plots", "nan", "bug", "warn"),
                   default="never"),
    "hold": Choice("stage kept busy until `release` exists", choices=("none", "run", "plots"),
                   default="none"),
    "ready": Str("file touched when the held stage starts", default=""),
    "release": Str("file whose creation ends the held stage", default=""),
    "file": Str("name of an extra output file", pattern=r"[a-z]+\.txt", default="extra.txt"),
    "estimate": Float("announced run time", unit="s", lo=0.0, default=0.0),
})


def _prepare(resolved: dict) -> dict:
    if resolved["hold"] != "none" and not resolved["release"]:
        raise SceneError("release", "required when hold is set")
    return resolved


def _hold(setup: dict, stage: str, ctx=None) -> None:
    if setup["hold"] != stage:
        return
    Path(setup["ready"]).touch()
    while not Path(setup["release"]).exists():
        if ctx is not None:
            ctx.tick("probe")
        time.sleep(0.02)


def _run(setup: dict, ctx) -> Result:
    from symmech.generated import smm_double_pendulum  # noqa: F401  (a generated module used)

    if setup["fail"] == "run":
        raise SceneError("fail", "the probe failed as asked")
    if setup["fail"] == "bug":
        return 1 / 0
    if setup["fail"] == "warn":
        ctx.warn("the probe warns as asked")
    _hold(setup, "run", ctx)
    t = np.arange(setup["rows"], dtype=float)
    y = np.sin(t)
    if setup["fail"] == "nan":
        y[-1] = np.nan
    table = Table((Column("t", "s", "time"), Column("y", "m", "height")), np.column_stack([t, y]))

    def plots(folder: Path) -> list[Path]:
        first = folder / "a.png"
        first.write_bytes(b"png")
        _hold(setup, "plots")
        if setup["fail"] == "plots":
            raise SceneError("fail", "the probe failed while plotting")
        return [first]

    return Result("probe", {"rows": setup["rows"], "last": float(y[-1])}, tables={"series": table},
                  files={setup["file"]: "probe\n"}, plots=plots)


PROBE = Kind("probe", "pipeline test kind", SCHEMA, _prepare, _run,
             estimate=lambda setup: Estimate(setup["estimate"], "probe"), precision=_run)


def install(monkeypatch) -> None:
    """Register the probe beside the real kinds for one test."""
    registry.kinds()  # discover the real kinds before adding the test kind
    monkeypatch.setitem(registry._KINDS, "probe", PROBE)


if __name__ == "__main__":
    from symmech.cli import main

    registry.kinds()
    registry.register(PROBE)
    sys.exit(main(sys.argv[1:]))
