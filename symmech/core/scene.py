"""Scene files (TOML) and their validation.

A scene is read into nested :class:`Section` objects; every read states the
field's type, range and unit, so a bad value is reported as one line naming the
dotted field path, the value and the admissible range. Fields a scene sets but
nobody reads are reported too (:meth:`Section.finish`), which catches typos.
"""
from __future__ import annotations

import importlib.resources
import math
import sys
from pathlib import Path

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib


class SymmechError(Exception):
    """An error a user can fix; the CLI prints it as one line, no traceback."""


class SceneError(SymmechError):
    """A scene field is missing, mistyped or out of range."""

    def __init__(self, field: str, problem: str):
        super().__init__(f"scene field '{field}': {problem}")
        self.field = field


_MISSING = object()


class Section:
    """One table of a scene, with typed, range-checked accessors."""

    def __init__(self, data: dict, path: str = ""):
        if not isinstance(data, dict):
            raise SceneError(path or "<root>", f"expected a table, got {data!r}")
        self._data = data
        self._path = path
        self._read: set[str] = set()

    def _field(self, key: str) -> str:
        return f"{self._path}.{key}" if self._path else key

    def has(self, key: str) -> bool:
        return key in self._data

    def name(self, key: str) -> str:
        """Dotted path of field ``key``, for error messages."""
        return self._field(key)

    def keys(self) -> list[str]:
        """The fields this table sets, in file order."""
        return list(self._data)

    def _get(self, key, default):
        self._read.add(key)
        if key in self._data:
            return self._data[key]
        if default is _MISSING:
            raise SceneError(self._field(key), "missing (required)")
        return default

    def section(self, key: str, default=_MISSING) -> "Section":
        value = self._get(key, default)
        return value if isinstance(value, Section) else Section(value, self._field(key))

    def float(self, key: str, *, unit: str, default=_MISSING, lo=None, hi=None,
              lo_open=False, hi_open=False) -> float:
        """A real number in [lo, hi] (open ends when ``lo_open``/``hi_open``)."""
        value = self._get(key, default)
        return _check_real(self._field(key), value, unit, lo, hi, lo_open, hi_open)

    def vector(self, key: str, n: int, *, unit: str, default=_MISSING, lo=None, hi=None,
               lo_open=False, hi_open=False) -> list[float]:
        value = self._get(key, default)
        field = self._field(key)
        if not isinstance(value, (list, tuple)) or len(value) != n:
            raise SceneError(field, f"expected a list of {n} numbers [{unit}], got {value!r}")
        return [_check_real(f"{field}[{i}]", v, unit, lo, hi, lo_open, hi_open)
                for i, v in enumerate(value)]

    def rows(self, key: str, n: int, *, unit: str, min_rows: int = 1, default=_MISSING) -> list[list[float]]:
        """A list of at least ``min_rows`` rows of ``n`` finite numbers (a table of points)."""
        value = self._get(key, default)
        field = self._field(key)
        if not isinstance(value, (list, tuple)) or len(value) < min_rows:
            raise SceneError(field, f"expected a list of at least {min_rows} rows of {n} numbers [{unit}]")
        rows = []
        for i, row in enumerate(value):
            if not isinstance(row, (list, tuple)) or len(row) != n:
                raise SceneError(f"{field}[{i}]", f"expected {n} numbers [{unit}], got {row!r}")
            rows.append([_check_real(f"{field}[{i}][{j}]", v, unit, None, None, False, False)
                         for j, v in enumerate(row)])
        return rows

    def int(self, key: str, *, default=_MISSING, lo=None, hi=None) -> int:
        value = self._get(key, default)
        field = self._field(key)
        if isinstance(value, bool) or not isinstance(value, int):
            raise SceneError(field, f"expected an integer, got {value!r}")
        if (lo is not None and value < lo) or (hi is not None and value > hi):
            raise SceneError(field, f"{value} is outside [{lo}, {hi}]")
        return value

    def bool(self, key: str, *, default=_MISSING) -> bool:
        value = self._get(key, default)
        if not isinstance(value, bool):
            raise SceneError(self._field(key), f"expected true or false, got {value!r}")
        return value

    def str(self, key: str, *, default=_MISSING) -> str:
        value = self._get(key, default)
        if not isinstance(value, str):
            raise SceneError(self._field(key), f"expected a string, got {value!r}")
        return value

    def choice(self, key: str, choices, *, default=_MISSING) -> str:
        value = self.str(key, default=default)
        if value not in choices:
            raise SceneError(self._field(key), f"unknown value {value!r}; choose one of {', '.join(choices)}")
        return value

    def raw(self, key: str, *, default=_MISSING):
        """The field's TOML value unchecked, for fields whose type the caller validates
        itself (e.g. a number or an expression string); marks it read."""
        return self._get(key, default)

    def finish(self) -> None:
        """Reject fields that were set but never read (typos, unknown effects)."""
        unknown = sorted(set(self._data) - self._read)
        if unknown:
            raise SceneError(self._field(unknown[0]), "unknown field")


def _check_real(field, value, unit, lo, hi, lo_open, hi_open) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SceneError(field, f"expected a number [{unit}], got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise SceneError(field, f"{value} is not finite")
    low_bad = lo is not None and (value <= lo if lo_open else value < lo)
    high_bad = hi is not None and (value >= hi if hi_open else value > hi)
    if low_bad or high_bad:
        left = "(" if lo_open else "["
        right = ")" if hi_open else "]"
        lo_text = "-inf" if lo is None else f"{lo:g}"
        hi_text = "inf" if hi is None else f"{hi:g}"
        unit_text = f" {unit}" if unit else ""
        raise SceneError(field, f"{value:g}{unit_text} is outside {left}{lo_text}, {hi_text}{right}")
    return value


# A scene is a small document: these bounds keep a hostile or mistaken file
# (a log, a binary, a generated monster) from costing time or crashing the parser.
MAX_SCENE_BYTES = 16 * 2**20
MAX_DEPTH = 32


def read_toml(path) -> dict:
    """The TOML document at ``path``; every problem is one SymmechError naming the file."""
    path = Path(path)
    if path.is_dir():
        raise SymmechError(f"scene {path} is a folder; give a TOML file")
    try:
        size = path.stat().st_size
        if size > MAX_SCENE_BYTES:
            raise SymmechError(f"scene file {path} has {size} bytes; at most {MAX_SCENE_BYTES} are read")
        raw = path.read_bytes()
    except FileNotFoundError:
        raise SymmechError(f"scene file not found: {path}") from None
    except OSError as exc:
        raise SymmechError(f"cannot read scene file {path}: {exc.strerror or exc}") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = raw[:exc.start].count(b"\n") + 1
        raise SymmechError(f"scene file {path} is not UTF-8 text (byte 0x{raw[exc.start]:02x} "
                           f"on line {line})") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SymmechError(f"scene file {path} is not valid TOML: {exc}") from None
    except RecursionError:
        raise SymmechError(f"scene file {path} is nested too deeply (at most {MAX_DEPTH} levels)") from None
    except ValueError as exc:  # e.g. an integer of more than 4300 digits
        raise SymmechError(f"scene file {path} holds an unreadable value: {exc}") from None
    check_depth(data)
    return data


def check_depth(data) -> None:
    """SceneError naming the first field nested deeper than MAX_DEPTH tables/arrays."""
    stack = [(data, "", 0)]
    while stack:
        node, where, depth = stack.pop()
        if depth > MAX_DEPTH:
            raise SceneError(where, f"nested deeper than {MAX_DEPTH} tables or arrays")
        if isinstance(node, dict):
            stack += [(v, f"{where}.{k}" if where else str(k), depth + 1) for k, v in node.items()]
        elif isinstance(node, list):
            stack += [(v, f"{where}[{i}]", depth + 1) for i, v in enumerate(node)]


def scenes_folder() -> Path:
    """The folder of the bundled example scenes (package data ``symmech.scenes``)."""
    try:
        return Path(str(importlib.resources.files("symmech.scenes")))
    except ModuleNotFoundError:
        # An editable install made before scenes/ became a package maps no
        # symmech.scenes; its checkout still has the folder. Reinstall to drop this.
        checkout = Path(__file__).resolve().parents[2] / "scenes"
        if checkout.is_dir():
            return checkout
        raise


def load(path) -> Section:
    """Read a scene file into a :class:`Section`."""
    return Section(read_toml(path))
