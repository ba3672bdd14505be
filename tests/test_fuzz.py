"""Scene fuzzer over every registered kind, driven by the kinds' schemas.

Every generated scene — valid ones (fields drawn inside their declared ranges,
durations cut short) and broken ones (wrong types, out-of-range and non-finite
numbers, unknown keys, deleted fields, random expressions, random TOML structure,
mangled text) — must end in exit 0 with finite outputs and a schema-valid summary,
or exit 2 with one line on stderr naming the field (the exact field when the case
is certainly wrong there) — never a traceback or an internal error, never past the
time budget. In-process through ``symmech.cli.main`` for speed; a few cases per kind
through the real command in a subprocess. The quick profile is in the default suite,
the long one is marked slow (``.ci/run`` runs it). Cases are derandomized so a run is
reproducible; ``SYMMECH_FUZZ_RANDOM=1`` explores new ones.
"""
from __future__ import annotations

import faulthandler
import io
import os
import re
import subprocess
import sys
import tempfile
import time
from contextlib import redirect_stderr, redirect_stdout
from dataclasses import dataclass
from pathlib import Path

import pytest
from fuzzscenes import (NAMES, UNKNOWN_KEY, base_scenes, broken_value, put, shorten, sites, tables, toml_data,
                        toml_text, valid_value)
from hypothesis import HealthCheck, find, given, settings
from hypothesis import strategies as st
from outcontract import assert_valid_output
from probe_kind import PROBE, install

from symmech.cli import main
from symmech.core import registry
from symmech.core import schema as s

MAX_TIME = 3.0  # s, --max-time of every case
SLACK = 15.0  # s past --max-time allowed for validation, writing and the budget check's granularity
HANG = 120  # s after which a case counts as a hang
FIELD = re.compile(r"scene field '([^']*)'")
NO_FIELD_OK = ("exceeds --max-time", "over the time budget --max-time", "is not valid TOML",
               "is nested too deeply", "holds an unreadable value", "non-finite result: ")


@dataclass(frozen=True)
class Profile:
    broken: int
    valid: int


QUICK, LONG = Profile(broken=30, valid=3), Profile(broken=200, valid=15)
PROFILES = [pytest.param(QUICK, id="quick"), pytest.param(LONG, id="long", marks=pytest.mark.slow)]
KINDS = sorted(registry.kinds())


def kind_of(name: str) -> registry.Kind:
    return registry.kinds()[name]


def outcome(text: str, folder: Path) -> tuple[int, str, float, Path]:
    """(exit status, stderr, wall time [s], output folder) of ``symmech run`` on ``text``, written with its
    output into ``folder``.

    A case still running after HANG seconds dumps every thread's stack and ends the
    test process (faulthandler's watchdog thread: it does not touch SIGALRM, which
    the kinds' own time-budget watchdog uses).
    """
    (folder / "scene.toml").write_text(text)
    err = io.StringIO()
    faulthandler.dump_traceback_later(HANG, exit=True, file=sys.__stderr__)
    start = time.perf_counter()
    try:
        with redirect_stderr(err), redirect_stdout(io.StringIO()):
            code = main(["run", str(folder / "scene.toml"), "--out", str(folder / "out"), "--quiet",
                         "--no-plots", "--max-time", str(MAX_TIME)])
    finally:
        faulthandler.cancel_dump_traceback_later()
    return code, err.getvalue(), time.perf_counter() - start, folder / "out"


def check(text: str, expected: str | None) -> None:
    with tempfile.TemporaryDirectory(prefix="symmech-fuzz-") as folder:
        code, err, seconds, out = outcome(text, Path(folder))
        assert seconds < MAX_TIME + SLACK, f"{seconds:.1f} s past the budget:\n{text[:2000]}"
        assert code in (0, 2), f"exit {code}: {err}\n{text[:2000]}"
        if code == 0:
            assert_valid_output(out)
            return
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("symmech: error: "), f"{err}\n{text[:2000]}"
        named = FIELD.search(lines[0])
        if expected is not None:
            assert named and (named[1] == expected or named[1].startswith(expected + "[")), \
                f"expected field {expected!r}: {lines[0]}"
        else:
            assert named or any(words in lines[0] for words in NO_FIELD_OK), lines[0]


def _leaf_sites(kind, data):
    return [x for x in sites(kind.schema, data) if x.keys != ("kind",) and
            not isinstance(x.field, (s.Table, s.TableList, s.Mapping))]


@st.composite
def valid_cases(draw, kind):
    data = draw(st.sampled_from(base_scenes(kind)))
    for _ in range(draw(st.integers(0, 3))):
        site = draw(st.sampled_from(_leaf_sites(kind, data)))
        data = put(data, site.keys, draw(valid_value(site.field)))
    return toml_text(shorten(kind.schema, data)), None


@st.composite
def broken_cases(draw, kind):
    data = shorten(kind.schema, draw(st.sampled_from(base_scenes(kind))))
    how = draw(st.sampled_from(["value", "value", "value", "unknown", "delete", "toml", "text"]))
    if how == "value":
        site = draw(st.sampled_from([x for x in sites(kind.schema, data) if x.keys != ("kind",)]))
        if isinstance(site.field, s.Mapping) and draw(st.booleans()):  # names like internal symbols
            value, certain = {draw(st.sampled_from(NAMES)): draw(valid_value(site.field.value))}, False
        elif isinstance(site.field, (s.Table, s.TableList, s.Mapping)):
            value, certain = draw(st.sampled_from(["text", 1.5, True, [1]])), True
        else:
            value, certain = draw(broken_value(site.field))
        return toml_text(put(data, site.keys, value)), site.name if certain else None
    if how == "unknown":
        where = draw(st.sampled_from(tables(kind.schema, data)))
        name = f"{where.name}.{UNKNOWN_KEY}" if where.name else UNKNOWN_KEY
        return toml_text(put(data, where.keys + (UNKNOWN_KEY,), 1.0)), name
    if how == "delete":
        present = [x for x in sites(kind.schema, data) if len(x.keys) == 1 and x.keys[0] in data]
        site = draw(st.sampled_from(present))
        rest = {k: v for k, v in data.items() if k != site.keys[0]}
        return toml_text(rest), site.name if site.field.default is s.REQUIRED else None
    if how == "toml":
        doc = draw(toml_data())
        if draw(st.booleans()):
            doc["kind"] = kind.name
        return toml_text(doc), None
    text = toml_text(data)
    at = draw(st.integers(0, len(text)))
    cut = draw(st.integers(0, 5))
    return text[:at] + draw(st.text(max_size=4)) + text[at + cut:], None


def _settings(examples: int):
    return settings(max_examples=examples, deadline=None, derandomize=not os.environ.get("SYMMECH_FUZZ_RANDOM"),
                    database=None, suppress_health_check=list(HealthCheck))


@pytest.mark.parametrize("profile", PROFILES)
@pytest.mark.parametrize("cases", ["broken", "valid"])
@pytest.mark.parametrize("name", KINDS)
def test_fuzzed_scenes(name, cases, profile):
    kind = kind_of(name)
    strategy, examples = (broken_cases, profile.broken) if cases == "broken" else (valid_cases, profile.valid)

    @_settings(examples)
    @given(case=strategy(kind))
    def fuzz(case):
        check(*case)

    fuzz()


@pytest.mark.parametrize("name", KINDS)
def test_through_the_real_command(tmp_path, name):
    """A NaN, an unknown key and junk TOML per kind: exit 2, one line, no traceback, in a subprocess."""
    kind = kind_of(name)
    data = shorten(kind.schema, base_scenes(kind)[0])
    numbers = [x for x in _leaf_sites(kind, data) if isinstance(x.field, s.Float)]
    cases = [(toml_text(put(data, (UNKNOWN_KEY,), 1)), f"scene field '{UNKNOWN_KEY}': unknown field"),
             (toml_text(data) + "[[[", "is not valid TOML")]
    if numbers:
        cases.append((toml_text(put(data, numbers[0].keys, float("nan"))), f"scene field '{numbers[0].name}'"))
    for i, (text, words) in enumerate(cases):
        scene = tmp_path / f"case{i}.toml"
        scene.write_text(text)
        proc = subprocess.run([sys.executable, "-m", "symmech", "run", str(scene), "--out", str(tmp_path / "out")],
                              capture_output=True, text=True, timeout=HANG)
        assert proc.returncode == 2 and "Traceback" not in proc.stderr, proc.stderr
        assert len(proc.stderr.splitlines()) == 1 and words in proc.stderr, proc.stderr


def exit_status(text: str) -> int:
    with tempfile.TemporaryDirectory(prefix="symmech-fuzz-") as folder:
        return outcome(text, Path(folder))[0]


def test_the_fuzzer_finds_a_planted_bug(monkeypatch):
    """The generators reach a kind's internal error (the probe's ``fail = "bug"``) and
    ``check`` reports it: the fuzzer can fail."""
    install(monkeypatch)
    case = find(valid_cases(PROBE), lambda case: exit_status(case[0]) == 3,
                settings=settings(max_examples=500, deadline=None, database=None, derandomize=True))
    assert 'fail = "bug"' in case[0]
    with pytest.raises(AssertionError, match="exit 3: symmech: internal error: ZeroDivisionError"):
        check(*case)
