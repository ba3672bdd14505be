"""Helpers for the named bad-input corpus: bundled scenes as dicts, mutations, and the rejection check.

A case is ``(id, scene dict, expected field)``: ``assert_rejected`` validates the
dict through the same path as ``symmech run`` (``pipeline.load``) and asserts a
one-line SceneError naming exactly that dotted field. ``cli_rejects`` runs the real
command line in a subprocess for the few cases that must prove exit 2 and no traceback.
"""
from __future__ import annotations

import copy
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from symmech.core import pipeline
from symmech.core.scene import SceneError, SymmechError

SCENES = Path(__file__).resolve().parents[1] / "scenes"
DELETE = object()


def bundled(name: str) -> dict:
    """A bundled scene (``scenes/NAME.toml``) as a fresh dict."""
    with open(SCENES / f"{name}.toml", "rb") as fh:
        return tomllib.load(fh)


def changed(base: dict, path: str, value) -> dict:
    """A deep copy of ``base`` with the dotted ``path`` (``a.b[2].c``) set to ``value`` (or DELETE)."""
    data = copy.deepcopy(base)
    keys = []
    for part in path.split("."):
        name, *indices = part.replace("]", "").split("[")
        keys.append(name)
        keys += [int(i) for i in indices]
    node = data
    for key in keys[:-1]:
        if isinstance(key, str) and key not in node:
            node[key] = {}
        node = node[key]
    if value is DELETE:
        del node[keys[-1]]
    else:
        node[keys[-1]] = value
    return data


def edited(base: dict, *pairs) -> dict:
    """``base`` with every ``(dotted path, value)`` of ``pairs`` applied in turn by :func:`changed`."""
    for path, value in pairs:
        base = changed(base, path, value)
    return base


def assert_rejected(data: dict, field: str) -> SceneError:
    """``data`` fails validation with a one-line SceneError naming ``field``."""
    with pytest.raises(SymmechError) as info:
        pipeline.load(data)
    err = info.value
    assert "\n" not in str(err), str(err)
    assert isinstance(err, SceneError), f"not a field error: {err}"
    assert err.field == field, f"named {err.field!r}, expected {field!r}: {err}"
    return err


def cli_rejects(tmp_path: Path, toml_text: str, words: str) -> str:
    """``symmech run`` on ``toml_text`` exits 2 with one stderr line containing ``words``."""
    scene = tmp_path / "bad.toml"
    scene.write_text(toml_text)
    proc = subprocess.run([sys.executable, "-m", "symmech", "run", str(scene), "--out", str(tmp_path / "out")],
                          capture_output=True, text=True, timeout=120)
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2, proc.stderr
    assert len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert words in lines[0], lines[0]
    return lines[0]
