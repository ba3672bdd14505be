"""Scene files (TOML), read within bounds, and the errors a user can fix.

Validation of the fields is declared per kind in :mod:`symmech.core.schema`; this
module reads the document (size, nesting and encoding bounded, every problem one
line naming the file) and defines :class:`SymmechError` / :class:`SceneError`.
"""
from __future__ import annotations

import importlib.resources
import re
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


# A scene is a small document: these bounds keep a hostile or mistaken file
# (a log, a binary, a generated monster) from costing time or crashing the parser.
MAX_SCENE_BYTES = 16 * 2**20
MAX_DEPTH = 32

# tomllib's time grows as the square of a dotted key's parts (a 20,000-part key: 6.5 s, the file bound allows
# millions). A key of more than MAX_DEPTH parts is too deep whatever its table, so it is refused before parsing.
# The chain must start a line, a table header or an inline table's entry, so a value or comment holding one is
# left to the parser; only a multi-line string whose line starts with 33 dotted words would be refused unread.
_KEY_PART = r"""(?:[A-Za-z0-9_-]+|"(?:[^"\\\n]|\\.)*"|'[^'\n]*')"""
_LONG_DOTTED_KEY = re.compile(
    rf"(?:^|[{{,\[])[ \t]*((?:{_KEY_PART}[ \t]*\.[ \t]*){{{MAX_DEPTH}}}{_KEY_PART})", re.MULTILINE)


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
    refuse_long_dotted_key(text)
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


def refuse_long_dotted_key(text: str) -> None:
    """SceneError naming the first dotted key of more than MAX_DEPTH parts, found without parsing ``text``."""
    found = _LONG_DOTTED_KEY.search(text)
    if found:
        parts = re.findall(_KEY_PART, found.group(1))
        field = ".".join(part.strip("\"'") for part in parts)
        raise SceneError(field, f"nested deeper than {MAX_DEPTH} tables or arrays")


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
    return Path(str(importlib.resources.files("symmech.scenes")))
