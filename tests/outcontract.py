"""The output contract (docs/outputs.md) as one check: ``assert_valid_output(folder)``."""
from __future__ import annotations

import csv
import importlib.resources
import json
import math
import re
from pathlib import Path

import jsonschema

SCHEMA = json.loads(importlib.resources.files("symmech.core").joinpath("output_schema.json").read_text())
HEADER = re.compile(r"[A-Za-z_][A-Za-z0-9_]* \[[^\]]+\]")


def _no_constants(name):
    raise AssertionError(f"summary.json holds {name}: not strict JSON")


def assert_valid_output(folder: Path) -> dict:
    """The folder holds exactly a schema-valid strict-JSON summary and the files it lists,
    CSV headers carry units and every number is finite. Returns the summary."""
    folder = Path(folder)
    summary = json.loads((folder / "summary.json").read_text(), parse_constant=_no_constants)
    jsonschema.validate(summary, SCHEMA)
    assert summary["scene"]["kind"] == summary["kind"]
    assert sorted(p.name for p in folder.iterdir()) == sorted(summary["files"] + ["summary.json"])
    for name in summary["files"]:
        if name.endswith(".csv"):
            _check_csv(folder / name)
    return summary


def _check_csv(path: Path) -> None:
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    assert rows, f"{path.name} is empty"
    numeric = [i for i, cell in enumerate(rows[0]) if HEADER.fullmatch(cell)]
    assert numeric and numeric == list(range(len(numeric))), f"{path.name}: headers {rows[0]}"
    for row in rows[1:]:
        assert len(row) == len(rows[0]), f"{path.name}: ragged row {row}"
        assert all(math.isfinite(float(row[i])) for i in numeric), f"{path.name}: {row}"
