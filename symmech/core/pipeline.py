"""Load, validate, run and write a scene: the one path behind ``symmech run`` and the API.

Order of work (nothing is computed or written before the scene is fully valid):
read TOML -> registry kind -> schema.validate -> kind.prepare -> estimate ->
kind.run -> Result.check_finite -> write into a temporary folder beside ``out``
-> rename into place. A failed run leaves the previous ``out`` untouched.
"""
from __future__ import annotations

import csv
import json
import os
import shutil
import sys
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from symmech import __version__
from symmech.core import registry
from symmech.core.context import Context
from symmech.core.results import Result
from symmech.core.scene import SymmechError, read_toml
from symmech.core.schema import validate


@dataclass
class Scene:
    """A validated scene: its kind, the resolved fields (defaults filled in) and the setup."""

    kind: registry.Kind
    resolved: dict
    setup: Any
    source: str = "<dict>"

    def estimate(self) -> registry.Estimate | None:
        return self.kind.estimate(self.setup) if self.kind.estimate else None

    def run(self, ctx: Context | None = None) -> Result:
        """Compute (no files written); raises SymmechError on a non-finite result."""
        ctx = ctx or Context(quiet=True)
        cost = self.estimate()
        if cost is not None and cost.seconds > ctx.max_time:
            raise SymmechError(f"estimated run time {cost.seconds:.3g} s ({cost.what}) exceeds "
                               f"--max-time {ctx.max_time:g} s; raise --max-time to run it")
        result = self.kind.run(self.setup, ctx)
        result.warnings = list(ctx.warnings) + [w for w in result.warnings if w not in ctx.warnings]
        result.check_finite()
        return result


def load(source) -> Scene:
    """A validated :class:`Scene` from a TOML path or a dict (as TOML would give)."""
    if isinstance(source, dict):
        data, name = source, "<dict>"
    else:
        data, name = read_toml(source), str(source)
    if not isinstance(data, dict):
        raise SymmechError("a scene must be a table of fields")
    kind = registry.get(data.get("kind"))
    resolved = validate(kind.schema, data)
    return Scene(kind, resolved, kind.prepare(resolved), name)


def write(result: Result, out: Path, scene: Scene, plots: bool = True) -> Path:
    """Write ``result`` into a fresh temporary folder beside ``out``, then rename it into place."""
    out = Path(out)
    parent = out.resolve().parent
    parent.mkdir(parents=True, exist_ok=True)
    if out.exists() and not out.is_dir():
        raise SymmechError(f"--out {out} exists and is not a folder")
    tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.", suffix=".partial", dir=parent))
    try:
        for name, table in result.tables.items():
            _write_csv(tmp / f"{name}.csv", table)
        for name, content in result.files.items():
            mode = "wb" if isinstance(content, bytes) else "w"
            with open(tmp / name, mode) as fh:
                fh.write(content)
        files = [f"{n}.csv" for n in result.tables] + list(result.files)
        if plots and result.plots is not None:
            files += [Path(p).name for p in result.plots(tmp)]
        summary = {"symmech_version": __version__, "kind": result.kind, "scene_file": scene.source,
                   "status": "ok", **result.summary, "warnings": result.warnings, "files": files,
                   "scene": scene.resolved}
        text = json.dumps(summary, indent=2, allow_nan=False, default=_json_default)
        (tmp / "summary.json").write_text(text + "\n")
        _replace_dir(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return out


def _json_default(value):
    import numpy as np

    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"summary value of type {type(value).__name__} is not JSON")


def _write_csv(path: Path, table) -> None:
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow([c.header for c in table.columns] + list(table.text))
        text_columns = list(table.text.values())
        for i, row in enumerate(table.data):
            w.writerow([repr(float(x)) for x in row] + [col[i] for col in text_columns])


def _replace_dir(new: Path, out: Path) -> None:
    """Move ``new`` to ``out``; an existing ``out`` is moved aside first and removed after."""
    if out.exists():
        old = Path(tempfile.mkdtemp(prefix=f".{out.name}.", suffix=".old", dir=out.resolve().parent))
        os.rename(out, old / "x")
        os.rename(new, out)
        shutil.rmtree(old, ignore_errors=True)
    else:
        os.rename(new, out)


def run_to(source, out: Path, ctx: Context, plots: bool = True) -> tuple[Scene, Result]:
    """Validate ``source``, run it and write the outputs atomically to ``out``."""
    scene = load(source)
    result = scene.run(ctx)
    write(result, out, scene, plots=plots)
    for warning in result.warnings:
        print(f"symmech: warning: {warning}", file=sys.stderr)
    return scene, result
