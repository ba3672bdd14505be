"""The output transaction of symmech.core.pipeline in-process: the --out checks, the lock, the
rename into place and the clean-up of leftovers (these kill mutants that the
child-process tests of test_outputs.py cannot see). Expected messages are written out by hand."""
from __future__ import annotations

import json
import os
import signal
import socket
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

import pytest
from probe_kind import install

from symmech.core import pipeline
from symmech.core.context import Context
from symmech.core.scene import SymmechError


@pytest.fixture(autouse=True)
def probe(monkeypatch):
    install(monkeypatch)


def _scene(tmp_path: Path, **fields) -> str:
    path = tmp_path / "scene.toml"
    path.write_text("\n".join(['kind = "probe"'] + [f"{k} = {json.dumps(v)}" for k, v in fields.items()]) + "\n")
    return str(path)


def _refusal(out) -> str:
    with pytest.raises(SymmechError) as exc:
        pipeline.check_out(out)
    return str(exc.value)


def test_check_out_accepts_new_empty_and_earlier_result_folders_and_makes_the_parent(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert pipeline.check_out("a/b/out") == tmp_path / "a" / "b" / "out"
    assert (tmp_path / "a" / "b").is_dir() and not (tmp_path / "a" / "b" / "out").exists()
    (tmp_path / "empty").mkdir()
    assert pipeline.check_out("empty") == tmp_path / "empty"
    (tmp_path / "done").mkdir()
    (tmp_path / "done" / "summary.json").write_text("{}")
    (tmp_path / "done" / "series.csv").write_text("")
    assert pipeline.check_out(tmp_path / "done") == tmp_path / "done"


def test_check_out_names_each_refusal(tmp_path, monkeypatch):
    (tmp_path / "file").write_text("x")
    assert _refusal(tmp_path / "file") == f"--out {tmp_path / 'file'} is a file, not a folder; choose a folder"
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "summary.json").mkdir()  # a folder named summary.json is no earlier result
    assert _refusal(tmp_path / "other") == (f"--out {tmp_path / 'other'} is a folder of other files (no summary.json"
                                            " of an earlier run); choose a new or empty folder")
    assert _refusal(tmp_path / "file" / "out") == (f"--out {tmp_path / 'file' / 'out'}: cannot create its parent "
                                                   "folder (File exists)")
    (tmp_path / "run" / "deep").mkdir(parents=True)
    monkeypatch.chdir(tmp_path / "run" / "deep")
    for out in (tmp_path / "run", "."):
        assert _refusal(out) == f"--out {out} contains the current folder; choose a folder of its own"


def test_lock_names_its_holder_is_reentrant_and_is_removed(tmp_path):
    out = tmp_path / "out"
    lock = tmp_path / ".out.lock"
    errors = []

    def second_run():
        try:
            with pipeline.locked(out):
                pass
        except SymmechError as exc:
            errors.append(str(exc))

    with pipeline.locked(out):
        assert lock.read_text() == f"{os.getpid()} {socket.gethostname()}\n"
        with pipeline.locked(out):  # the same thread re-enters
            pass
        assert lock.exists()
        thread = threading.Thread(target=second_run)
        thread.start()
        thread.join()
    assert errors == [f"--out {out} is being written by another symmech run (pid {os.getpid()} on "
                      f"{socket.gethostname()}); wait for it or choose another --out"]
    assert not lock.exists() and pipeline._HELD == {}
    with pipeline.locked(out):  # free again
        assert lock.exists()


def _held_refusal(out: Path, content: bytes) -> str:
    """The refusal of locked(out) while another open file holds the lock file, which says ``content``."""
    import fcntl

    fd = os.open(out.parent / f".{out.name}.lock", os.O_CREAT | os.O_RDWR)
    os.write(fd, content)
    fcntl.flock(fd, fcntl.LOCK_EX)
    try:
        with pytest.raises(SymmechError) as exc:
            with pipeline.locked(out):
                pass
    finally:
        os.close(fd)
    return str(exc.value)


def test_a_lock_being_taken_says_starting_now_and_a_garbled_holder_is_still_named(tmp_path):
    out = tmp_path / "out"
    tail = "; wait for it or choose another --out"
    assert _held_refusal(out, b"") == f"--out {out} is being written by another symmech run (starting now)" + tail
    assert _held_refusal(out, b"12 h\xffst\n") == (f"--out {out} is being written by another symmech run "
                                                   "(pid 12 on h\ufffdst)" + tail)
    assert _held_refusal(out, b"12 host extra") == (f"--out {out} is being written by another symmech run "
                                                    "(starting now)" + tail)


def test_the_lock_file_is_readable_by_all_and_a_missing_folder_is_named(tmp_path):
    mask = os.umask(0)
    try:
        with pipeline.locked(tmp_path / "out"):
            assert os.stat(tmp_path / ".out.lock").st_mode & 0o777 == 0o644
    finally:
        os.umask(mask)
    gone = tmp_path / "gone" / "out"
    with pytest.raises(SymmechError) as exc:
        with pipeline.locked(gone):
            pass
    assert str(exc.value) == (f"--out {gone}: cannot create the lock file {gone.parent / '.out.lock'} "
                              "(No such file or directory)")


def test_replace_holds_back_interrupts_between_the_renames_and_removes_the_old_folder(tmp_path, monkeypatch):
    out, new = tmp_path / "out", tmp_path / "new"
    out.mkdir()
    (out / "old.txt").write_text("old")
    new.mkdir()
    (new / "new.txt").write_text("new")
    masks, renames = [], []
    rename = os.rename

    def watched(a, b):
        masks.append(signal.pthread_sigmask(signal.SIG_BLOCK, []))
        renames.append((Path(a), Path(b)))
        rename(a, b)

    monkeypatch.setattr(os, "rename", watched)
    pipeline._replace_dir(new, out)
    assert len(masks) == 2 and all({signal.SIGINT, signal.SIGTERM} <= m for m in masks)
    (first, aside), second = renames
    assert first == out and aside.name == "previous" and aside.parent.parent == tmp_path
    assert aside.parent.name.startswith(".out.old-") and second == (new, out)
    assert signal.SIGINT not in signal.pthread_sigmask(signal.SIG_BLOCK, [])
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]
    assert [p.name for p in out.iterdir()] == ["new.txt"]


def test_leftovers_of_this_out_only_are_removed(tmp_path):
    out = tmp_path / "o[1]"
    names = [".o[1].partial-a", ".o[1].old-b", ".o[1].other-c", ".o1.partial-d", ".o[1]x.partial-e", ".p.partial-f"]
    for name in names:
        (tmp_path / name).mkdir()
        (tmp_path / name / "f").write_text("x")
    pipeline._remove_leftovers(out)
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(names[2:])


def test_write_failures_name_the_out_folder_and_the_file(tmp_path, monkeypatch):
    scene = pipeline.load(_scene(tmp_path))
    result = scene.run(Context(quiet=True))
    out = tmp_path / "out"

    def no_room(**kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(tempfile, "mkdtemp", no_room)
    with pytest.raises(SymmechError) as exc:
        pipeline.write(result, out, scene)
    assert str(exc.value) == f"--out {out}: cannot write beside it (Permission denied)"
    monkeypatch.undo()
    install(monkeypatch)
    for args, where in [((str(tmp_path / "x" / "series.csv"),), " (series.csv)"), ((), "")]:
        def full(path, table, args=args):
            raise OSError(28, "No space left on device", *args)

        monkeypatch.setattr(pipeline, "_write_csv", full)
        with pytest.raises(SymmechError) as exc:
            pipeline.write(result, out, scene)
        assert str(exc.value) == (f"cannot write the results into {out}: No space left on device{where}; "
                                  "previous results left untouched")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.toml"]


def test_run_to_writes_the_timed_summary_and_prints_each_warning(tmp_path, capsys):
    out = tmp_path / "out"
    start = time.perf_counter()
    scene, result = pipeline.run_to(_scene(tmp_path, fail="warn"), out, Context(quiet=True), plots=False)
    wall = time.perf_counter() - start
    summary = json.loads((out / "summary.json").read_text())
    assert result.warnings == ["the probe warns as asked"] and scene.resolved["fail"] == "warn"
    assert capsys.readouterr().err == "symmech: warning: the probe warns as asked\n"
    timing = summary["timing_s"]
    assert {"validate", "run", "write"} <= set(timing) and 0 < timing["write"] < wall
    assert timing["total"] == pytest.approx(sum(v for k, v in timing.items() if k != "total"), rel=1e-12)
    assert summary["files"] == ["extra.txt", "series.csv"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out", "scene.toml"]


def test_write_fills_a_hidden_folder_beside_out_and_writes_bytes_numpy_values_and_indented_json(tmp_path,
                                                                                                 monkeypatch):
    scene = pipeline.load(_scene(tmp_path))
    result = scene.run(Context(quiet=True))
    result.files["raw.bin"] = b"\x00\xff"
    result.summary.update(count=np.int64(3), values=np.array([0.5, 2.0]), where=Path("a/b"))
    moved = []
    replace = pipeline._replace_dir
    monkeypatch.setattr(pipeline, "_replace_dir", lambda new, out: (moved.append(new), replace(new, out)))
    out = tmp_path / "out"
    pipeline.write(result, out, scene, plots=False)
    [new] = moved
    assert new.parent == tmp_path and new.name.startswith(".out.partial-")
    assert (out / "raw.bin").read_bytes() == b"\x00\xff"
    text = (out / "summary.json").read_text()
    summary = json.loads(text)
    assert (summary["count"], summary["values"], summary["where"]) == (3, [0.5, 2.0], "a/b")
    assert text == json.dumps(summary, indent=2) + "\n"


def test_a_nan_in_the_summary_is_refused_not_written(tmp_path):
    scene = pipeline.load(_scene(tmp_path))
    result = scene.run(Context(quiet=True))
    result.summary["bad"] = float("nan")
    with pytest.raises(ValueError, match="not JSON compliant"):
        pipeline.write(result, tmp_path / "out", scene)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.toml"]


def test_run_to_draws_plots_by_default_and_gives_the_precision_study_the_callers_context(tmp_path):
    pipeline.run_to(_scene(tmp_path), tmp_path / "out", Context(quiet=True))
    assert (tmp_path / "out" / "a.png").is_file()
    ctx = Context(quiet=True)
    pipeline.run_to(_scene(tmp_path, fail="warn"), tmp_path / "study", ctx, study="precision")
    assert ctx.warnings == ["the probe warns as asked"]


def test_a_lock_file_removed_as_it_is_opened_is_opened_again(tmp_path, monkeypatch):
    """The holder of the lock removes its file between our open and our stat: we lock the new file."""
    out, lock = tmp_path / "out", tmp_path / ".out.lock"
    stat, raced = os.stat, []

    def racing_stat(path, *args, **kwargs):
        if Path(path) == lock and not raced:
            raced.append(path)
            os.unlink(lock)
            raise FileNotFoundError(2, "No such file or directory", str(path))
        return stat(path, *args, **kwargs)

    monkeypatch.setattr(os, "stat", racing_stat)
    with pipeline.locked(out):
        monkeypatch.undo()
        assert raced and lock.read_text() == f"{os.getpid()} {socket.gethostname()}\n"


def test_a_leftover_that_cannot_be_removed_does_not_fail_the_run(tmp_path, monkeypatch):
    out = tmp_path / "out"
    out.mkdir()
    (out / "summary.json").write_text("{}")
    (tmp_path / ".out.partial-a").mkdir()
    new = tmp_path / "new"
    new.mkdir()

    def refuse(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(os, "rmdir", refuse)
    pipeline._remove_leftovers(out)
    pipeline._replace_dir(new, out)
    assert not new.exists() and [p.name for p in out.iterdir()] == []
