"""Declarative scene schemas: one declaration per kind drives validation, defaults and docs.

A kind declares its scene as a :class:`Table` of fields. :func:`validate` checks a
whole TOML document against it *before any work*: types, ranges, units, unknown
fields (with a "did you mean"), nested tables and lists of tables, and the
cross-field admissibility ``checks`` of every table. It returns the *resolved*
scene — a plain dict with every default filled in — or raises
:class:`~symmech.core.scene.SceneError` naming the dotted field path, the value and
the admissible range. :func:`markdown` renders the same declaration as the docs table.

Example::

    BODY = Table("the grain", {
        "mass": Float("mass", unit="kg", lo=1e-12, hi=1e3),
        "semi_axes": Vector("semi-axes a, b, c", n=3, unit="m", lo=0.0, lo_open=True),
    })
    resolved = validate(Table("scene", {"body": BODY}), {"body": {...}})

A field with ``default=REQUIRED`` must be given; ``default=None`` makes it optional
(absent → ``None``); any other default is filled in when absent.
"""
from __future__ import annotations

import difflib
import math
import re
from dataclasses import dataclass, field
from typing import Any
from collections.abc import Callable

from symmech.core.scene import SceneError


class _Required:
    def __repr__(self):
        return "REQUIRED"


REQUIRED = _Required()
# Scenes are small documents: these bounds keep a hostile file from costing time.
MAX_ITEMS = 100_000
MAX_STRING = 10_000


def _join(path: str, key) -> str:
    if isinstance(key, int):
        return f"{path}[{key}]"
    return f"{path}.{key}" if path else key


def _range_text(lo, hi, lo_open, hi_open, unit) -> str:
    left = "(" if lo_open or lo is None else "["
    right = ")" if hi_open or hi is None else "]"
    lo_text = "-inf" if lo is None else f"{lo:g}"
    hi_text = "inf" if hi is None else f"{hi:g}"
    return f"{left}{lo_text}, {hi_text}{right}" + (f" {unit}" if unit else "")


@dataclass(frozen=True)
class Field:
    """Base of every field: a one-line ``doc`` and a ``default`` (REQUIRED, None or a value)."""

    doc: str
    default: Any = field(default=REQUIRED, kw_only=True)

    def check(self, path: str, value):  # pragma: no cover - overridden
        raise NotImplementedError

    def type_text(self) -> str:  # pragma: no cover - overridden
        raise NotImplementedError

    def resolve(self, path: str, present: bool, value):
        if not present:
            if self.default is REQUIRED:
                raise SceneError(path, f"missing (required: {self.type_text()})")
            return self.default
        return self.check(path, value)


@dataclass(frozen=True)
class _Ranged(Field):
    """A field of numbers in SI ``unit`` within [lo, hi] (open ends with ``lo_open``/``hi_open``)."""

    unit: str = ""
    lo: float | None = None
    hi: float | None = None
    lo_open: bool = False
    hi_open: bool = False


@dataclass(frozen=True)
class Float(_Ranged):
    """A finite real number in a range, in SI ``unit``; integers are accepted."""

    def check(self, path, value):
        return check_real(path, value, self.unit, self.lo, self.hi, self.lo_open, self.hi_open)

    def type_text(self):
        return f"number in {_range_text(self.lo, self.hi, self.lo_open, self.hi_open, self.unit)}"


@dataclass(frozen=True)
class Int(Field):
    lo: int | None = None
    hi: int | None = None

    def check(self, path, value):
        if isinstance(value, bool) or not isinstance(value, int):
            raise SceneError(path, f"expected an integer in {_range_text(self.lo, self.hi, False, False, '')}, "
                                   f"got {show(value)}")
        if (self.lo is not None and value < self.lo) or (self.hi is not None and value > self.hi):
            raise SceneError(path, f"{value} is outside {_range_text(self.lo, self.hi, False, False, '')}")
        return value

    def type_text(self):
        return f"integer in {_range_text(self.lo, self.hi, False, False, '')}"


@dataclass(frozen=True)
class Bool(Field):
    def check(self, path, value):
        if not isinstance(value, bool):
            raise SceneError(path, f"expected true or false, got {show(value)}")
        return value

    def type_text(self):
        return "true or false"


@dataclass(frozen=True)
class Str(Field):
    """Free text (titles, descriptions); ``pattern`` (a regex) restricts it, e.g. to identifiers."""

    pattern: str | None = None

    def check(self, path, value):
        if not isinstance(value, str):
            raise SceneError(path, f"expected a string, got {show(value)}")
        if len(value) > MAX_STRING:
            raise SceneError(path, f"string of {len(value)} characters; at most {MAX_STRING}")
        if self.pattern and not re.fullmatch(self.pattern, value):
            raise SceneError(path, f"{value!r} does not match {self.pattern}")
        return value

    def type_text(self):
        return "string" + (f" matching {self.pattern}" if self.pattern else "")


@dataclass(frozen=True)
class Choice(Field):
    choices: tuple[str, ...] = ()

    def check(self, path, value):
        if not isinstance(value, str) or value not in self.choices:
            raise SceneError(path, f"unknown value {show(value)}{did_you_mean(value, self.choices)}; "
                                   f"choose one of {', '.join(self.choices)}")
        return value

    def type_text(self):
        return "one of " + ", ".join(f"`{c}`" for c in self.choices)


@dataclass(frozen=True)
class Choices(Field):
    """A list of distinct values, each one of ``choices`` (at least ``min_items``), kept in the given order."""

    choices: tuple[str, ...] = ()
    min_items: int = 0

    def check(self, path, value):
        if not isinstance(value, (list, tuple)) or len(value) < self.min_items:
            raise SceneError(path, f"expected a list of at least {self.min_items} of {', '.join(self.choices)}, "
                                   f"got {show(value)}")
        for i, item in enumerate(value):
            if not isinstance(item, str) or item not in self.choices:
                raise SceneError(_join(path, i), f"unknown value {show(item)}{did_you_mean(item, self.choices)}; "
                                                 f"choose from {', '.join(self.choices)}")
            if item in value[:i]:
                raise SceneError(_join(path, i), f"{item!r} is listed twice")
        return list(value)

    def type_text(self):
        return f"list of {self.min_items}+ of " + ", ".join(f"`{c}`" for c in self.choices)


@dataclass(frozen=True)
class Vector(_Ranged):
    """A list of exactly ``n`` finite numbers, each in the range."""

    n: int = 3

    def check(self, path, value):
        if not isinstance(value, (list, tuple)) or len(value) != self.n:
            raise SceneError(path, f"expected a list of {self.n} numbers [{self.unit}], got {show(value)}")
        return [check_real(_join(path, i), v, self.unit, self.lo, self.hi, self.lo_open, self.hi_open)
                for i, v in enumerate(value)]

    def type_text(self):
        return f"list of {self.n} numbers in {_range_text(self.lo, self.hi, self.lo_open, self.hi_open, self.unit)}"


@dataclass(frozen=True)
class Rows(Field):
    """A table of points: ``min_rows``..``max_rows`` rows of ``n`` finite numbers."""

    n: int = 2
    unit: str = ""
    min_rows: int = 1
    max_rows: int = MAX_ITEMS

    def check(self, path, value):
        if not isinstance(value, (list, tuple)) or not self.min_rows <= len(value) <= self.max_rows:
            raise SceneError(path, f"expected {self.min_rows} to {self.max_rows} rows of {self.n} numbers "
                                   f"[{self.unit}], got {show(value)}")
        rows = []
        for i, row in enumerate(value):
            where = _join(path, i)
            if not isinstance(row, (list, tuple)) or len(row) != self.n:
                raise SceneError(where, f"expected {self.n} numbers [{self.unit}], got {show(row)}")
            rows.append([check_real(_join(where, j), v, self.unit, None, None, False, False)
                         for j, v in enumerate(row)])
        return rows

    def type_text(self):
        return f"{self.min_rows}+ rows of {self.n} numbers [{self.unit}]"


@dataclass(frozen=True)
class Custom(Field):
    """A field checked by ``parse(path, value) -> resolved`` (expressions, number-or-expression, ...).

    ``parse`` raises SceneError naming ``path``; ``type_doc`` says what is accepted.
    """

    parse: Callable[[str, Any], Any] = None
    type_doc: str = ""

    def check(self, path, value):
        return self.parse(path, value)

    def type_text(self):
        return self.type_doc


Check = Callable[[dict, str], None]


@dataclass(frozen=True)
class Table(Field):
    """A TOML table with declared ``fields``.

    ``variants = (key, {value: {name: Field}})`` adds the fields of the variant that
    the choice field ``key`` selects (e.g. the impact law's own coefficients).
    ``checks`` run on the resolved table (with its dotted path) after its fields:
    cross-field physical admissibility, raising SceneError.
    """

    fields: dict[str, Field] = field(default_factory=dict)
    variants: tuple[str, dict[str, dict[str, Field]]] | None = None
    checks: tuple[Check, ...] = ()

    def all_fields(self, data: dict) -> dict[str, Field]:
        if not self.variants:
            return self.fields
        key, options = self.variants
        chosen = data.get(key, self.fields[key].default) if isinstance(data, dict) else None
        return {**self.fields, **options.get(chosen, {})}

    def check(self, path, value):
        if not isinstance(value, dict):
            raise SceneError(path or "<scene>", f"expected a table, got {show(value)}")
        if self.variants:  # the selector first: an unknown variant is reported, not its fields
            key = self.variants[0]
            self.fields[key].resolve(_join(path, key), key in value, value.get(key))
        fields = self.all_fields(value)
        for key in value:
            if key not in fields:
                raise SceneError(_join(path, key), f"unknown field{did_you_mean(key, fields)}")
        resolved = {}
        for key, f in fields.items():
            resolved[key] = f.resolve(_join(path, key), key in value, value.get(key))
        for check in self.checks:
            check(resolved, path)
        return resolved

    def resolve(self, path, present, value):
        # An optional table given as {} default still gets its own defaults filled in.
        if not present and isinstance(self.default, dict):
            return self.check(path, dict(self.default))
        return super().resolve(path, present, value)

    def type_text(self):
        return "table"


@dataclass(frozen=True)
class TableList(Field):
    """An array of tables (``[[name]]``), each checked against ``item``."""

    item: Table = None
    min_items: int = 0
    max_items: int = MAX_ITEMS
    checks: tuple[Check, ...] = ()

    def check(self, path, value):
        if not isinstance(value, (list, tuple)) or not self.min_items <= len(value) <= self.max_items:
            raise SceneError(path, f"expected {self.min_items} to {self.max_items} tables, got {show(value)}")
        resolved = [self.item.check(_join(path, i), v) for i, v in enumerate(value)]
        for check in self.checks:
            check(resolved, path)
        return resolved

    def type_text(self):
        return f"array of tables ({self.min_items}..{self.max_items})"


@dataclass(frozen=True)
class Mapping(Field):
    """A table of user-chosen names (identifiers) to values of one ``value`` field."""

    value: Field = None
    key_pattern: str = r"[A-Za-z_][A-Za-z0-9_]*"
    max_items: int = 10_000

    def check(self, path, value):
        if not isinstance(value, dict) or len(value) > self.max_items:
            raise SceneError(path, f"expected a table of at most {self.max_items} names, got {show(value)}")
        out = {}
        for key, v in value.items():
            if not re.fullmatch(self.key_pattern, key):
                raise SceneError(_join(path, key), f"name {key!r} is not an identifier ({self.key_pattern})")
            out[key] = self.value.check(_join(path, key), v)
        return out

    def type_text(self):
        return f"table of names to {self.value.type_text()}"


def plot_output(plots: dict[str, str], default: tuple[str, ...]) -> Table:
    """The ``[output]`` table of a kind with plots: which of ``plots`` (name -> its caption) to
    draw, and in which image formats; every kind declares it through here
    (:func:`symmech.core.plotting.draw` reads it)."""
    from symmech.core.plotting import FORMATS

    return Table("which plots `symmech run` draws (`--no-plots`: none)", {
        "plots": Choices("plots to draw, each `<name>.<format>`: " + " ".join(f"`{k}`: {v}" for k, v in plots.items()),
                         choices=tuple(plots), default=list(default)),
        "formats": Choices("image formats; `symmech report` inlines the SVG when there is one, else the PNG",
                           choices=FORMATS, min_items=1, default=["png"]),
    }, default={})


def validate(schema: Table, data: dict) -> dict:
    """The resolved scene: ``data`` checked against ``schema`` with defaults filled in."""
    return schema.check("", data)


def check_real(path, value, unit, lo, hi, lo_open, hi_open) -> float:
    """``value`` as a float if it is a finite number in the range, else SceneError."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SceneError(path, f"expected a number in {_range_text(lo, hi, lo_open, hi_open, unit)}, "
                               f"got {show(value)}")
    try:
        number = float(value)
    except OverflowError:
        raise SceneError(path, f"{value} overflows a float; admissible {_range_text(lo, hi, lo_open, hi_open, unit)}") from None
    if not math.isfinite(number):
        raise SceneError(path, f"{number} is not finite; admissible {_range_text(lo, hi, lo_open, hi_open, unit)}")
    low_bad = lo is not None and (number <= lo if lo_open else number < lo)
    high_bad = hi is not None and (number >= hi if hi_open else number > hi)
    if low_bad or high_bad:
        unit_text = f" {unit}" if unit else ""
        raise SceneError(path, f"{number:g}{unit_text} is outside {_range_text(lo, hi, lo_open, hi_open, unit)}")
    return number


def show(value) -> str:
    """repr of a user's value for a one-line message, cut to 60 characters."""
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def did_you_mean(word, options) -> str:
    """The message suffix `` (did you mean 'x'?)`` naming the option closest to ``word``, or ""."""
    if not isinstance(word, str):
        return ""
    close = difflib.get_close_matches(word, list(options), n=1)
    return f" (did you mean '{close[0]}'?)" if close else ""


def markdown(schema: Table, path: str = "") -> str:
    """Docs tables for ``schema``: one table per TOML table, fields with type, unit/range, default, meaning."""
    lines = [f"### `[{path}]`" if path else "### top level", "",
             "| field | type and admissible values | default | meaning |", "| --- | --- | --- | --- |"]
    nested = []
    variant_rows = []
    if schema.variants:
        key, options = schema.variants
        for value, fields in options.items():
            variant_rows += [(name, f, f" (when `{key} = \"{value}\"`)") for name, f in fields.items()]
    for name, f, when in [(n, f, "") for n, f in schema.fields.items()] + variant_rows:
        default = "required" if f.default is REQUIRED else ("—" if f.default is None else f"`{_toml(f.default)}`")
        lines.append(f"| `{name}` | {f.type_text()} | {default} | {f.doc}{when} |")
        if isinstance(f, Table):
            nested.append(markdown(f, _join(path, name)))
        elif isinstance(f, TableList):
            nested.append(markdown(f.item, f"[{_join(path, name)}]"))
    return "\n".join(lines + [""] + nested)


def _toml(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, dict):
        return "{}" if not value else "{...}"
    return repr(value)
