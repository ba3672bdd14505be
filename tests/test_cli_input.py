"""Whatever the scene file or the command line, symmech answers in one line: exit 2 for a
user error (naming the file, field or option), never a traceback (non-UTF-8 or
deeply nested TOML, a folder as the scene, a missing file crashed with a traceback)."""
from __future__ import annotations

import subprocess
import sys

import pytest
from probe_kind import install

from symmech.cli import main
from symmech.core import scene
from symmech.core.scene import MAX_DEPTH, MAX_SCENE_BYTES


@pytest.fixture(autouse=True)
def probe(monkeypatch):
    install(monkeypatch)


def answer(capsys, argv) -> tuple[int, str]:
    code = main(argv)
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    return code, lines[0]


def write(tmp_path, content: bytes):
    path = tmp_path / "scene.toml"
    path.write_bytes(content)
    return path


@pytest.mark.parametrize("content, words", [
    (b'kind = "grain"\ntitle = "caf\xe9"\n', "is not UTF-8 text (byte 0xe9 on line 2)"),
    (b"\xff\xfe\x00k\x00i\x00n\x00d", "is not UTF-8 text (byte 0xff on line 1)"),
    (b"a = " + b"[" * 5000 + b"]" * 5000, f"is nested too deeply (at most {MAX_DEPTH} levels)"),
    (b"a = " + b"{b = " * 3000 + b"1" + b"}" * 3000, "is nested too deeply"),
    (b"a = " + b"[" * (MAX_DEPTH + 2) + b"]" * (MAX_DEPTH + 2),
     "scene field 'a" + "[0]" * MAX_DEPTH + "': nested deeper than"),
    # refused before parsing: tomllib's time grows as the key's parts squared (6.5 s of CPU for these 20,000)
    (b"a" + b".a" * 20_000 + b" = 1", "scene field 'a" + ".a" * MAX_DEPTH + "': nested deeper than"),
    (b"[t]\n" + b"\"q\" . " * 20_000 + b"k = 1", "scene field 'q" + ".q" * MAX_DEPTH + "': nested deeper than"),
    (b"[" + b"a." * 20_000 + b"a]", "scene field 'a" + ".a" * MAX_DEPTH + "': nested deeper than"),
    (b"x = {" + b"a." * 20_000 + b"a = 1}", "scene field 'a" + ".a" * MAX_DEPTH + "': nested deeper than"),
    # the same chain in a value or a comment is the parser's to read: no false refusal
    (b'title = "' + b"a." * 40 + b'" # ' + b"b." * 40 + b"\n", "scene field 'kind': unknown scene kind None"),
    (b"n = " + b"9" * 5000, "holds an unreadable value: Exceeds the limit (4300 digits)"),
    (b"kind = [grain", "is not valid TOML: "),
    (b"", "scene field 'kind': unknown scene kind None; choose one of "),
    (b'kind = "prbe"', "unknown scene kind 'prbe' (did you mean 'probe'?); choose one of "),
], ids=["latin1", "utf16", "deep-array", "deep-table", "array-past-limit", "long-dotted-key", "long-quoted-key",
        "long-table-header", "long-inline-key", "dotted-value-and-comment", "long-integer",
        "bad-toml", "empty", "misspelt-kind"])
def test_unreadable_scene_files(tmp_path, capsys, content, words):
    path = write(tmp_path, content)
    code, line = answer(capsys, ["run", str(path), "--out", str(tmp_path / "out")])
    assert code == 2 and line.startswith("symmech: error: ") and words in line
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("parts, parsed", [(MAX_DEPTH, True), (MAX_DEPTH + 1, False), (50_000, False)])
def test_a_long_dotted_key_is_refused_before_parsing(tmp_path, monkeypatch, parts, parsed):
    calls = []
    monkeypatch.setattr(scene.tomllib, "loads", lambda text: calls.append(text) or {})
    path = write(tmp_path, b"[t]\n x" + b" . x" * (parts - 1) + b" = 1\n")
    if parsed:
        assert scene.read_toml(path) == {} and len(calls) == 1
    else:
        with pytest.raises(scene.SceneError, match="^scene field 'x" + r"\.x" * MAX_DEPTH + "': nested deeper"):
            scene.read_toml(path)
        assert calls == []


def test_huge_scene_file_is_not_read(tmp_path, capsys):
    path = tmp_path / "huge.toml"
    with open(path, "wb") as fh:  # sparse: costs no disk
        fh.truncate(MAX_SCENE_BYTES + 1)
    code, line = answer(capsys, ["run", str(path)])
    assert code == 2 and f"has {MAX_SCENE_BYTES + 1} bytes; at most {MAX_SCENE_BYTES}" in line


@pytest.mark.parametrize("argv, words", [
    (["run", "{tmp}"], "is a folder; give a TOML file"),
    (["run", "{tmp}/missing.toml"], "scene file not found: "),
    (["run", "/proc/self/mem"], "cannot read scene file /proc/self/mem"),
    (["bench", "precision", "{tmp}"], "is a folder; give a TOML file"),
    (["run", "x.toml", "--max-time", "-1"], "argument --max-time: -1 is outside (0, inf) s"),
    (["run", "x.toml", "--max-time", "soon"], "expected a number of seconds, got 'soon'"),
    (["run"], "the following arguments are required: scene"),
    (["rnu"], "invalid choice: 'rnu'"),
    (["latex", "nowhere:thing"], "unknown matrix namespace 'nowhere:'"),
    (["latex", "no_such.matrix"], "no derived matrix named 'no_such.matrix'"),
])
def test_bad_command_lines(tmp_path, capsys, argv, words):
    argv = [a.replace("{tmp}", str(tmp_path)) for a in argv]
    try:
        code, line = answer(capsys, argv)
    except SystemExit as exit_:  # argparse's own exit, still one line
        code, line = exit_.code, capsys.readouterr().err.strip()
        assert "\n" not in line
    assert code == 2 and words in line, line


@pytest.mark.parametrize("content", [b"\xff\xfe", b"a = " + b"[" * 3000 + b"]" * 3000])
def test_no_traceback_from_the_real_command(tmp_path, content):
    path = write(tmp_path, content)
    proc = subprocess.run([sys.executable, "-m", "symmech", "run", str(path), "--out", str(tmp_path / "o")],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2 and proc.stdout == ""
    assert len(proc.stderr.splitlines()) == 1 and "Traceback" not in proc.stderr
