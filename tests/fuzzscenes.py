"""Scene generation for the fuzzer, driven by each kind's declarative schema.

A case is ``(toml_text, expected_field)``: the field the one-line error must name
when the case is certainly invalid at that field (a NaN, a wrong type, an unknown
key), or None when either outcome is admissible (exit 0, or exit 2 naming some field).
"""
from __future__ import annotations

import copy
import functools
import json
import math
import re
import tomllib
from dataclasses import dataclass

from hypothesis import strategies as st

from symmech.core import schema as s
from symmech.core.scene import scenes_folder

# Durations of generated valid scenes are cut to this [s] so a case stays short.
SHORT_RUN = 0.05
DURATION_NAMES = re.compile(r"(duration|t_end|t_max|time_span|end_time)")
UNKNOWN_KEY = "zz_not_a_field"


# ---- the base scene of a kind ---------------------------------------------------------

@functools.cache  # every case draws its base scene: parsing every bundled file each time was seconds per suite
def _bundled() -> tuple[dict, ...]:
    """Every bundled scene (as TOML data), in file-name order, parsed once per process."""
    return tuple(tomllib.loads(path.read_text()) for path in sorted(scenes_folder().glob("*.toml")))


def base_scenes(kind) -> list[dict]:
    """Every bundled scene of ``kind`` (as TOML data, a fresh copy), or one built from its defaults."""
    found = [copy.deepcopy(data) for data in _bundled() if data.get("kind") == kind.name]
    return found or [{"kind": kind.name}]


# ---- walking a scene along its schema -------------------------------------------------

@dataclass(frozen=True)
class Site:
    """A place in a scene: key path (str keys and int indices), dotted name, declared field."""

    keys: tuple
    name: str
    field: s.Field


def sites(table: s.Table, data: dict, keys=(), name="") -> list[Site]:
    """Every field the scene ``data`` could set, present or not (tables recurse where present)."""
    out = []
    for key, f in table.all_fields(data).items():
        here = Site(keys + (key,), f"{name}.{key}" if name else key, f)
        out.append(here)
        value = data.get(key) if isinstance(data, dict) else None
        if isinstance(f, s.Table) and isinstance(value, dict):
            out += sites(f, value, here.keys, here.name)
        elif isinstance(f, s.TableList) and isinstance(value, list):
            for i, item in enumerate(value):
                if isinstance(item, dict):
                    out += sites(f.item, item, here.keys + (i,), f"{here.name}[{i}]")
    return out


def tables(table: s.Table, data: dict) -> list[Site]:
    """The tables present in ``data`` (the root included), where an unknown key can go."""
    root = Site((), "", table)
    return [root] + [x for x in sites(table, data) if isinstance(x.field, s.Table) and
                     isinstance(get(data, x.keys), dict)] + \
        [Site(x.keys + (i,), f"{x.name}[{i}]", x.field.item) for x in sites(table, data)
         if isinstance(x.field, s.TableList) and isinstance(get(data, x.keys), list)
         for i in range(len(get(data, x.keys))) if isinstance(get(data, x.keys)[i], dict)]


def get(data, keys):
    for key in keys:
        try:
            data = data[key]
        except (KeyError, IndexError, TypeError):
            return None
    return data


def put(data: dict, keys: tuple, value) -> dict:
    data = copy.deepcopy(data)
    node = data
    for key in keys[:-1]:
        if isinstance(key, str) and not isinstance(node.get(key), (dict, list)):
            node[key] = {}
        node = node[key]
    node[keys[-1]] = value
    return data


def shorten(table: s.Table, data: dict) -> dict:
    """``data`` with every duration-like Float cut to SHORT_RUN (within its range)."""
    for site in sites(table, data):
        f = site.field
        if isinstance(f, s.Float) and DURATION_NAMES.search(site.keys[-1] if isinstance(site.keys[-1], str) else ""):
            value = SHORT_RUN
            if f.lo is not None:
                value = max(value, f.lo * 1.01 if f.lo > 0 else f.lo + 1e-3)
            if f.hi is not None:
                value = min(value, f.hi)
            data = put(data, site.keys, value)
    return data


# ---- values ---------------------------------------------------------------------------

def _float_in(lo, hi, lo_open, hi_open):
    low = -1e6 if lo is None else lo
    high = (max(1e6, abs(low) * 10) if hi is None else hi)
    return st.floats(min_value=low, max_value=high, exclude_min=lo_open and lo is not None,
                     exclude_max=hi_open and hi is not None, allow_nan=False, allow_infinity=False)


NAMES = ["t", "s", "x", "y", "q", "x0", "pi", "e", "numpy", "np", "math", "__import__", "exec", "self", "kind"]
FUNCS = ["sin", "cos", "tan", "exp", "log", "sqrt", "abs", "atan2", "asin", "cosh", "eval", "open"]
NASTY = ["1/0", "log(0)*t", "(-1)**0.5", "sin(1,2)", "9**9**9", "10**400", "exp(1000)", "__import__('os')",
         "().__class__", "lambda: 1", "[1, 2]", "t if t else 1", "x" * 20000, "", " ", "1e999", "sqrt(-1)",
         "0**-1", "s/0", "tan(pi/2)", "acos(2)", "t**t**t**t", "((((((((((((((((((((t))))))))))))))))))))" * 50]


def expressions():
    atoms = st.sampled_from(NAMES) | st.floats(allow_nan=False, allow_infinity=False, width=32).map(repr) | \
        st.integers(-5, 400).map(str)
    return st.sampled_from(NASTY) | st.recursive(atoms, lambda inner: st.one_of(
        st.tuples(inner, st.sampled_from(["+", "-", "*", "/", "**", "%", "//", "<", "and"]), inner)
        .map(lambda t: f"({t[0]} {t[1]} {t[2]})"),
        st.tuples(st.sampled_from(FUNCS), st.lists(inner, max_size=3)).map(lambda t: f"{t[0]}({', '.join(t[1])})"),
        inner.map(lambda a: f"-{a}")), max_leaves=10)


def valid_value(f: s.Field):
    """Values the field's declaration admits (physical admissibility may still refuse them)."""
    if isinstance(f, s.Float):
        return _float_in(f.lo, f.hi, f.lo_open, f.hi_open)
    if isinstance(f, s.Int):
        lo = -1000 if f.lo is None else f.lo
        return st.integers(lo, max(lo, min(f.hi if f.hi is not None else lo + 1000, lo + 1000)))
    if isinstance(f, s.Bool):
        return st.booleans()
    if isinstance(f, s.Choice):
        return st.sampled_from(f.choices)
    if isinstance(f, s.Choices):
        return st.lists(st.sampled_from(f.choices), min_size=f.min_items, max_size=len(f.choices), unique=True)
    if isinstance(f, s.Str):
        return st.from_regex(f.pattern, fullmatch=True) if f.pattern else st.text(max_size=20)
    if isinstance(f, s.Vector):
        return st.lists(_float_in(f.lo, f.hi, f.lo_open, f.hi_open), min_size=f.n, max_size=f.n)
    if isinstance(f, s.Rows):
        row = st.lists(_float_in(None, None, False, False), min_size=f.n, max_size=f.n)
        return st.lists(row, min_size=f.min_rows, max_size=min(f.max_rows, f.min_rows + 5))
    if isinstance(f, s.Custom):
        return expressions() | _float_in(None, None, False, False)
    return st.nothing()


NON_FINITE = [math.nan, math.inf, -math.inf]
EXTREME = [1e308, -1e308, 1e-308, 5e-324, -1e-308, 0.0, -0.0, 10**30, -(10**30), 2**63, 1e16]
WRONG_TYPES = ["text", True, [], {"a": 1}, [[1, 2], [3]], "1.0"]


def broken_value(f: s.Field):
    """(value, certainly_wrong): values a user might mistype into the field."""
    numeric = isinstance(f, (s.Float, s.Int))
    pair = [] if isinstance(f, s.Vector) and f.n == 2 else [[1, 2]]  # a 2-vector takes [1, 2]
    wrong = ["text", {"a": 1}] + pair + ([] if isinstance(f, s.Bool) else [True])
    if isinstance(f, s.Float):
        wrong += NON_FINITE
    if isinstance(f, s.Int):
        wrong += [1.5, math.nan]
    if isinstance(f, s.Vector):
        wrong += [[math.nan] * f.n, [1.0] * (f.n + 1), ["1"] * f.n]
    certain = st.sampled_from(wrong).map(lambda v: (v, True)) if (numeric or isinstance(f, (s.Vector, s.Bool, s.Choices))) \
        else st.nothing()
    edges = []
    if isinstance(f, (s.Float, s.Vector, s.Int)):
        for bound, step in ((f.lo, -1), (f.hi, 1)):
            if bound is not None:
                edges += [bound, bound + step * (abs(bound) * 1e-9 + 1e-300), bound + step * (abs(bound) + 1)]
    maybe = st.sampled_from(EXTREME + WRONG_TYPES + NON_FINITE + edges) | expressions() | valid_value(f)
    if isinstance(f, s.Vector):
        maybe = maybe | st.lists(st.sampled_from(EXTREME + edges + [1.0]), min_size=f.n, max_size=f.n)
    return certain | maybe.map(lambda v: (v, False))


# ---- TOML text --------------------------------------------------------------------------

def toml_text(data: dict) -> str:
    """``data`` as a TOML document: one ``key = value`` line per top-level key, inline tables inside."""
    return "".join(f"{_key(k)} = {_value(v)}\n" for k, v in data.items())


def _key(key) -> str:
    return key if re.fullmatch(r"[A-Za-z0-9_-]+", key) else json.dumps(key)


def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return "nan" if math.isnan(v) else ("inf" if v == math.inf else "-inf" if v == -math.inf else repr(v))
    if isinstance(v, int):
        return str(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(type(v))


def toml_data():
    """Random TOML documents (any structure), sometimes with a real ``kind``."""
    text = st.text(st.characters(exclude_categories=("Cs",)), max_size=12)
    leaves = st.booleans() | st.integers(-(2**63), 2**63 - 1) | st.floats() | text
    values = st.recursive(leaves, lambda inner: st.lists(inner, max_size=4) |
                          st.dictionaries(text, inner, max_size=4), max_leaves=12)
    return st.dictionaries(text, values, max_size=5)
