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
# the schema checked and its validator built once: jsonschema.validate does both on every call (~50 ms, ~10x a
# validation)
jsonschema.validators.validator_for(SCHEMA).check_schema(SCHEMA)
VALIDATOR = jsonschema.validators.validator_for(SCHEMA)(SCHEMA)
HEADER = re.compile(r"[A-Za-z_][A-Za-z0-9_]* \[[^\]]+\]")


def _no_constants(name):
    raise AssertionError(f"summary.json holds {name}: not strict JSON")


def assert_valid_output(folder: Path) -> dict:
    """The folder holds exactly a schema-valid strict-JSON summary and the files it lists;
    every table's CSV has the headers ``name [unit]`` and row count the summary describes,
    and finite numbers. Returns the summary."""
    folder = Path(folder)
    summary = json.loads((folder / "summary.json").read_text(), parse_constant=_no_constants)
    VALIDATOR.validate(summary)
    assert summary["kind"] in (summary["scene"]["kind"], f"{summary['scene']['kind']}_sweep")  # a run, a sweep
    assert sorted(p.name for p in folder.iterdir()) == sorted(summary["files"] + ["summary.json"])
    for name, table in summary["tables"].items():
        assert f"{name}.csv" in summary["files"]
        _check_csv(folder / f"{name}.csv", table)
    return summary


def _check_csv(path: Path, table: dict) -> None:
    """Headers ``name [unit]`` as the summary describes them, then text columns; finite numbers."""
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    numeric = [f"{c['name']} [{c['unit']}]" for c in table["columns"]]
    assert rows[0] == numeric + table["text_columns"], f"{path.name}: headers {rows[0]}"
    assert all(HEADER.fullmatch(cell) for cell in numeric), numeric
    assert len(rows) == table["rows"] + 1, f"{path.name}: {len(rows) - 1} rows, summary says {table['rows']}"
    for row in rows[1:]:
        assert len(row) == len(rows[0]), f"{path.name}: ragged row {row}"
        assert all(math.isfinite(float(row[i])) for i in range(len(numeric))), f"{path.name}: {row}"
