"""What a run returns: named tables with units, a JSON summary, plots and extra files.

A kind's ``run`` computes and returns a :class:`Result`; it writes nothing. The
pipeline (``symmech.core.pipeline``) checks every number finite, writes the
tables as CSV with units in the headers, the summary as strict JSON, the extra
files and the plots into a temporary folder, and renames it into place. The
Python API hands the same Result to the user (``Result.tables[name].column(...)``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from symmech.core.scene import SymmechError


@dataclass(frozen=True)
class Column:
    """One column of a table: name (an identifier), SI unit ("1" if dimensionless), meaning."""

    name: str
    unit: str
    doc: str = ""

    @property
    def header(self) -> str:
        """CSV header cell, e.g. ``t [s]``."""
        return f"{self.name} [{self.unit}]"


@dataclass(frozen=True)
class Table:
    """Rows of numbers under named columns; ``data`` has shape (rows, len(columns)).

    ``text`` optionally holds string columns by name (e.g. a regime or a solver
    status per row), written after the numeric ones.
    """

    columns: tuple[Column, ...]
    data: np.ndarray
    doc: str = ""
    text: dict[str, list[str]] = field(default_factory=dict)

    def __post_init__(self):
        data = np.asarray(self.data, dtype=float)
        if data.ndim == 1 and len(self.columns) == 1:
            data = data[:, None]
        if data.ndim != 2 or data.shape[1] != len(self.columns):
            raise ValueError(f"table data of shape {data.shape} for {len(self.columns)} columns")
        object.__setattr__(self, "data", data)
        object.__setattr__(self, "columns", tuple(self.columns))

    def column(self, name: str) -> np.ndarray:
        for i, c in enumerate(self.columns):
            if c.name == name:
                return self.data[:, i]
        raise KeyError(name)


@dataclass
class Result:
    """The outcome of one run.

    kind      the scene kind
    summary   JSON-able dict of scalars, lists and dicts (finite numbers only)
    tables    name -> Table, written as ``name.csv``
    files     name -> text or bytes written verbatim (e.g. ``matrices.json``)
    plots     callable(folder) -> list of written paths, called by the pipeline
              unless plots are off; draws only what the scene asks for
    warnings  one line each, echoed on stderr and stored in the summary
    """

    kind: str
    summary: dict
    tables: dict[str, Table] = field(default_factory=dict)
    files: dict[str, str | bytes] = field(default_factory=dict)
    plots: Callable[[Path], list[Path]] | None = None
    warnings: list[str] = field(default_factory=list)

    def check_finite(self) -> None:
        """SymmechError naming the quantity (and the row's first-column value) of any NaN/Inf."""
        for name, table in self.tables.items():
            bad = ~np.isfinite(table.data)
            if bad.any():
                row, col = map(int, np.argwhere(bad)[0])
                first = table.columns[0]
                raise SymmechError(
                    f"non-finite result: {name}.{table.columns[col].name} = {table.data[row, col]} "
                    f"at {first.name} = {table.data[row, 0]:g} {first.unit} (row {row})")
        _check_json_finite(self.summary, "summary")


def _check_json_finite(value, path: str) -> None:
    if isinstance(value, dict):
        for k, v in value.items():
            _check_json_finite(v, f"{path}.{k}")
    elif isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            _check_json_finite(v, f"{path}[{i}]")
    elif isinstance(value, (float, np.floating)) and not math.isfinite(value):
        raise SymmechError(f"non-finite result: {path} = {value}")
