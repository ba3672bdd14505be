"""What a run returns: named tables with units, a JSON summary, its headline and checks, plots and extra files.

A kind's ``run`` computes and returns a :class:`Result`; it writes nothing. The
pipeline (``symmech.core.pipeline``) checks every number finite, writes the
tables as CSV with units in the headers, the summary as strict JSON, the extra
files and the plots into a temporary folder, and renames it into place. The
Python API hands the same Result to the user (``Result.tables[name].column(...)``).
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from collections.abc import Callable

import numpy as np

from symmech.core import units
from symmech.core.scene import SymmechError

VERDICTS = {"pass": "✓", "warn": "!", "fail": "✗"}


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

    ``grid`` declares a long table: {dimension: key column}, outermost first, the rows running over every
    combination of the key columns' values in row-major order (one row per instant and mode: ``{"t": "t",
    "mode": "mode_id"}``). Its :meth:`to_xarray` has those dimensions.
    """

    columns: tuple[Column, ...]
    data: np.ndarray
    doc: str = ""
    text: dict[str, list[str]] = field(default_factory=dict)
    grid: dict[str, str] = field(default_factory=dict)

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

    def select(self, names) -> np.ndarray:
        """The columns ``names`` side by side (rows, len(names)); KeyError for an unknown name."""
        return np.column_stack([self.column(name) for name in names])

    def to_xarray(self, index: bool = True):
        """The table as an ``xarray.Dataset``, one variable per column with ``units`` and
        ``long_name`` attrs. ``index``: the first column is the coordinate (a time series,
        dimension named after it), or for a long table (``grid``) the grid's dimensions, each with its key
        column's values as coordinate and the text columns as coordinates over them (``ds.f.sel(mode=1)``);
        otherwise every column is a variable over ``row``."""
        import xarray as xr

        if index and self.grid:
            return self._grid_dataset()
        first = self.columns[0].name
        dim = first if index else "row"
        variables = {c.name: (dim, self.data[:, i], {"units": c.unit, "long_name": c.doc or c.name})
                     for i, c in enumerate(self.columns) if not (index and i == 0)}
        variables.update({name: (dim, np.asarray(values, dtype=str)) for name, values in self.text.items()})
        coords = {first: (first, self.data[:, 0], {"units": self.columns[0].unit,
                                                   "long_name": self.columns[0].doc or first})} if index else {}
        return xr.Dataset(variables, coords=coords, attrs={"description": self.doc})

    def _grid_dataset(self):
        """The long table as a Dataset over its grid's dimensions (ValueError when its rows are not the grid)."""
        import xarray as xr

        def attrs(c: Column) -> dict:
            return {"units": c.unit, "long_name": c.doc or c.name}

        by_name = {c.name: (i, c) for i, c in enumerate(self.columns)}
        keys = np.column_stack([self.data[:, by_name[col][0]] for col in self.grid.values()])
        axes = [k[np.sort(np.unique(k, return_index=True)[1])] for k in keys.T]  # in order of appearance
        shape = tuple(a.size for a in axes)
        full = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(axes))
        if keys.shape != full.shape or not np.array_equal(keys, full):
            raise ValueError(f"table rows are not the grid {dict(zip(self.grid, shape))} over "
                             f"{', '.join(self.grid.values())} in row-major order")
        dims = tuple(self.grid)
        coords = {dim: (dim, axis, attrs(by_name[col][1])) for (dim, col), axis in zip(self.grid.items(), axes)}
        coords |= {name: (dims, np.asarray(values, dtype=str).reshape(shape)) for name, values in self.text.items()}
        variables = {c.name: (dims, self.data[:, i].reshape(shape), attrs(c)) for i, c in enumerate(self.columns)
                     if c.name not in self.grid.values()}
        return xr.Dataset(variables, coords=coords, attrs={"description": self.doc})


def readable(text: str) -> str:
    """A sentence with the raw ids of the elastic trolley's modes and mode groups made readable
    (``beam0_plane1_mode1`` → ``beam 0, plane 1, mode 1``; ``beam0_plane1`` → ``beam 0, plane 1``)."""
    text = re.sub(r"\bbeam([0-9]+)_plane([0-9]+)_mode([0-9]+)\b", r"beam \1, plane \2, mode \3", text)
    return re.sub(r"\bbeam([0-9]+)_plane([0-9]+)\b", r"beam \1, plane \2", text)


@dataclass(frozen=True)
class Headline:
    """One answer of a run, as a person asks for it: name, value in SI ``unit`` ("1" if
    dimensionless), its one-line meaning and where or when it happens (e.g. "t = 2.8 s"); an answer
    with a limit carries its admissible ``envelope`` (lo, hi) in ``unit`` and gets the verdict a
    :func:`within` check of it would (a value beyond the envelope fails)."""

    name: str
    value: float
    unit: str
    meaning: str
    at: str = ""
    envelope: tuple[float, float] | None = None

    def verdict(self) -> str | None:
        """"pass" or "fail" against the envelope; None without one."""
        if self.envelope is None:
            return None
        return within(self.name, self.value, self.value, self.envelope, self.unit).verdict

    def text(self) -> str:
        """``"name: 0.235 mm (at t = 2.8 s)"`` in the readable unit."""
        return f"{self.name}: {units.format(self.value, self.unit)}" + (f" (at {self.at})" if self.at else "")

    def to_json(self) -> dict:
        out = {"name": self.name, "value": float(self.value), "unit": self.unit, "meaning": self.meaning,
               "at": self.at}
        if self.envelope is not None:
            out |= {"limit": [float(v) for v in self.envelope], "verdict": self.verdict()}
        return out


@dataclass(frozen=True)
class Check:
    """A verdict on the run: ``what`` is checked, the measured ``value`` (a number, or the
    (min, max) a quantity reached) in SI ``unit``, the ``threshold`` it must meet (text, e.g.
    "<= 1e-06"), and the ``verdict``: "pass", "warn" or "fail". Build it with :func:`at_most`
    or :func:`within`, which decide the verdict."""

    what: str
    value: float | tuple[float, float]
    unit: str
    threshold: str
    verdict: str

    def __post_init__(self):
        if self.verdict not in VERDICTS:
            raise ValueError(f"check verdict {self.verdict!r} is not one of {', '.join(VERDICTS)}")

    def measured(self) -> str:
        """The value in its readable unit; a range as ``"lo … hi"``."""
        if isinstance(self.value, tuple):
            return " … ".join(units.format(v, self.unit) for v in self.value)
        return units.format(self.value, self.unit)

    def text(self) -> str:
        return f"{VERDICTS[self.verdict]} {self.what}: {self.measured()} ({self.threshold})"

    def to_json(self) -> dict:
        value = [float(v) for v in self.value] if isinstance(self.value, tuple) else float(self.value)
        return {"what": self.what, "value": value, "unit": self.unit, "threshold": self.threshold,
                "verdict": self.verdict}


def at_most(what: str, value: float, limit: float, unit: str = "1", otherwise: str = "fail") -> Check:
    """Passes when ``value <= limit``; else the verdict ``otherwise`` ("fail" or "warn")."""
    return Check(what, float(value), unit, f"<= {units.format(limit, unit)}",
                 "pass" if value <= limit else otherwise)


def within(what: str, low: float, high: float, envelope: tuple[float, float], unit: str,
           otherwise: str = "fail") -> Check:
    """Passes when the range [low, high] a quantity reached lies inside ``envelope``."""
    lo, hi = envelope
    return Check(what, (float(low), float(high)), unit,
                 f"within [{units.format(lo, unit)}, {units.format(hi, unit)}]",
                 "pass" if lo <= low and high <= hi else otherwise)


@dataclass
class Result:
    """The outcome of one run.

    kind      the scene kind
    summary   JSON-able dict of scalars, lists and dicts (finite numbers only)
    headline  the answers a person reads first (:class:`Headline`), in order
    checks    verdicts on the run (:class:`Check`): balances, admissibility, envelopes
    tables    name -> Table, written as ``name.csv``
    files     name -> text or bytes written verbatim (e.g. ``matrices.json``)
    plots     callable(folder) -> list of written paths, called by the pipeline
              unless plots are off; draws only what the scene asks for
    warnings  one line each, echoed on stderr and stored in the summary
    events    name of the table that is the run's event log (one row per event,
              e.g. impacts), or "" when the kind has none
    """

    kind: str
    summary: dict
    tables: dict[str, Table] = field(default_factory=dict)
    files: dict[str, str | bytes] = field(default_factory=dict)
    plots: Callable[[Path], list[Path]] | None = None
    warnings: list[str] = field(default_factory=list)
    events: str = ""
    headline: list[Headline] = field(default_factory=list)
    checks: list[Check] = field(default_factory=list)

    def brief(self) -> str:
        """The headline and the checks that did not pass, one line each (``symmech run`` prints it)."""
        lines = [f"  {h.text()}" for h in self.headline]
        counts = {v: sum(c.verdict == v for c in self.checks) for v in VERDICTS}
        lines += [f"checks: {counts['pass']} pass, {counts['warn']} warn, {counts['fail']} fail"] if self.checks else []
        lines += [f"  {c.text()}" for c in self.checks if c.verdict != "pass"]
        return "\n".join([f"{self.kind}:", *lines]) if lines else ""

    def to_xarray(self, table: str | None = None):
        """Table ``table`` (default: the first that is not the event log) as an ``xarray.Dataset``
        with its first column as the coordinate; the kind, the summary (as JSON) and the
        warnings are in the Dataset's attrs."""
        import json

        names = [n for n in self.tables if n != self.events] or list(self.tables)
        name = table if table is not None else (names[0] if names else None)
        if name not in self.tables:
            raise KeyError(f"no table {name!r}; tables: {', '.join(self.tables) or 'none'}")
        ds = self.tables[name].to_xarray(index=True)
        ds.attrs.update({"kind": self.kind, "table": name, "warnings": "\n".join(self.warnings),
                         "summary": json.dumps(self.summary, default=_json_scalar)})
        return ds

    def event_log(self):
        """The event log as an ``xarray.Dataset`` over dimension ``row`` (None without one)."""
        return self.tables[self.events].to_xarray(index=False) if self.events else None

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
        _check_json_finite([h.to_json() for h in self.headline], "headline")
        _check_json_finite([c.to_json() for c in self.checks], "checks")


def _json_scalar(value):
    return value.item() if isinstance(value, np.generic) else value.tolist() if isinstance(value, np.ndarray) \
        else str(value)


def _check_json_finite(value, path: str) -> None:
    if isinstance(value, dict):
        for k, v in value.items():
            _check_json_finite(v, f"{path}.{k}")
    elif isinstance(value, (list, tuple)):
        for i, v in enumerate(value):
            _check_json_finite(v, f"{path}[{i}]")
    elif isinstance(value, (float, np.floating)) and not math.isfinite(value):
        raise SymmechError(f"non-finite result: {path} = {value}")
