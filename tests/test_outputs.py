"""Transactional, self-describing outputs through the probe kind.

Each test names the defect it guards: before, a failed run left the previous
summary beside new partial files, an interrupted run a truncated CSV, a full disk
a 0-byte summary, two runs interleaved, files of an earlier scene survived.
"""
from __future__ import annotations

import errno
import hashlib
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import pytest
from outcontract import assert_valid_output
from probe_kind import install

from symmech import __version__
from symmech.cli import main
from symmech.core import pipeline

PROBE_CLI = [sys.executable, str(Path(__file__).with_name("probe_kind.py"))]


@pytest.fixture(autouse=True)
def probe(monkeypatch):
    install(monkeypatch)


def scene(tmp_path: Path, name="scene", **fields) -> str:
    lines = ['kind = "probe"'] + [f"{k} = {json.dumps(v)}" for k, v in fields.items()]
    path = tmp_path / f"{name}.toml"
    path.write_text("\n".join(lines) + "\n")
    return str(path)


def run(capsys, *args) -> tuple[int, str]:
    code = main(["run", *map(str, args)])
    err = capsys.readouterr().err
    return code, err


def snapshot(folder: Path) -> dict:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


def leftovers(out: Path) -> list[str]:
    """Temporary folders or lock files beside ``out``."""
    return sorted(p.name for p in out.parent.iterdir() if p.name.startswith(f".{out.name}."))


def one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


def test_summary_records_version_resolved_scene_module_hashes_and_time(tmp_path, capsys):
    out = tmp_path / "out"
    assert run(capsys, scene(tmp_path, rows=4), "--out", out) == (0, "")
    s = assert_valid_output(out)
    assert s["symmech_version"] == __version__ and s["kind"] == "probe" and s["status"] == "ok"
    assert s["scene"] == {"kind": "probe", "rows": 4, "fail": "never", "hold": "none", "ready": "",
                          "release": "", "file": "extra.txt", "estimate": 0.0}
    from symmech.generated import smm_double_pendulum

    text = Path(smm_double_pendulum.__file__).read_text()
    body = text.split("\n", 3)[3]  # after the three header lines, which record this hash
    assert s["generated_modules"]["smm_double_pendulum"] == hashlib.sha256(body.encode()).hexdigest()
    assert f"# body sha256 {s['generated_modules']['smm_double_pendulum']}\n" in text
    timing = s["timing_s"]
    assert set(timing) == {"validate", "estimate", "run", "write", "total"}
    assert timing["total"] == pytest.approx(timing["validate"] + timing["estimate"] + timing["run"] + timing["write"],
                                            rel=1e-12)
    assert s["files"] == ["a.png", "extra.txt", "series.csv"]
    assert s["tables"] == {"series": {"rows": 4, "doc": "", "text_columns": [], "columns": [
        {"name": "t", "unit": "s", "doc": "time"}, {"name": "y", "unit": "m", "doc": "height"}]}}
    assert (out / "series.csv").read_text().splitlines()[0] == "t [s],y [m]"
    assert leftovers(out) == []


def test_warnings_set_the_status(tmp_path, capsys):
    code, err = run(capsys, scene(tmp_path, fail="warn"), "--out", tmp_path / "out")
    assert code == 0 and one_line(err) == "symmech: warning: the probe warns as asked"
    s = assert_valid_output(tmp_path / "out")
    assert s["status"] == "warnings" and s["warnings"] == ["the probe warns as asked"]


@pytest.mark.parametrize("fail, words", [
    ("run", "scene field 'fail': the probe failed as asked"),
    ("plots", "the probe failed while plotting"),  # after files were written into the temporary folder
    ("nan", "non-finite result: series.y = nan at t = 2 s (row 2)"),
])
def test_failed_run_leaves_previous_results_untouched(tmp_path, capsys, fail, words):
    out = tmp_path / "out"
    assert run(capsys, scene(tmp_path), "--out", out)[0] == 0
    before = snapshot(out)
    code, err = run(capsys, scene(tmp_path, "bad", fail=fail, rows=3, file="other.txt"), "--out", out)
    assert code == 2 and words in one_line(err)
    assert snapshot(out) == before and leftovers(out) == []


def test_files_of_an_earlier_scene_do_not_survive(tmp_path, capsys):
    out = tmp_path / "out"
    assert run(capsys, scene(tmp_path, file="first.txt"), "--out", out)[0] == 0
    assert run(capsys, scene(tmp_path, file="second.txt"), "--out", out, "--no-plots")[0] == 0
    s = assert_valid_output(out)
    assert s["files"] == ["second.txt", "series.csv"] and not (out / "first.txt").exists()


def test_full_disk_is_an_error_not_a_empty_summary(tmp_path, capsys, monkeypatch):
    out = tmp_path / "out"
    assert run(capsys, scene(tmp_path), "--out", out)[0] == 0
    before = snapshot(out)
    real_mkdtemp = tempfile.mkdtemp

    def full_disk_folder(**kwargs):  # summary.json of the new folder lands on /dev/full: ENOSPC
        folder = real_mkdtemp(**kwargs)
        os.symlink("/dev/full", os.path.join(folder, "summary.json"))
        return folder

    monkeypatch.setattr(tempfile, "mkdtemp", full_disk_folder)
    code, err = run(capsys, scene(tmp_path), "--out", out)
    assert code == 2
    assert os.strerror(errno.ENOSPC) in one_line(err) and "previous results left untouched" in err
    assert snapshot(out) == before and leftovers(out) == []


@pytest.mark.parametrize("make, words", [
    (lambda d: (d / "out").write_text("x"), "is a file, not a folder"),
    (lambda d: (d / "out").mkdir() or (d / "out" / "thesis.tex").write_text("x"), "folder of other files"),
])
def test_bad_out_is_refused_before_any_work(tmp_path, capsys, make, words):
    make(tmp_path)
    text = scene(tmp_path, fail="bug")  # would crash if it ran
    before = {p.name for p in tmp_path.rglob("*")}
    code, err = run(capsys, text, "--out", tmp_path / "out")
    assert code == 2 and words in one_line(err)
    assert {p.name for p in tmp_path.rglob("*")} == before


def test_out_below_a_file_or_the_current_folder_is_refused(tmp_path, capsys, monkeypatch):
    (tmp_path / "file").write_text("x")
    code, err = run(capsys, scene(tmp_path), "--out", tmp_path / "file" / "out")
    assert code == 2 and "cannot create its parent folder" in one_line(err)
    monkeypatch.chdir(tmp_path)
    code, err = run(capsys, scene(tmp_path), "--out", ".")
    assert code == 2 and "contains the current folder" in one_line(err)


def test_unwritable_out_is_an_error(tmp_path, capsys):
    code, err = run(capsys, scene(tmp_path), "--out", "/proc/symmech-out")
    assert code == 2 and "--out /proc/symmech-out" in one_line(err)


def test_lock_file_of_a_dead_run_is_taken_over(tmp_path, capsys):
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    import socket

    lock = tmp_path / ".out.lock"
    lock.write_text(f"{dead.pid} {socket.gethostname()}\n")
    (tmp_path / ".out.partial-abc").mkdir()  # a killed run's temporary folder
    assert run(capsys, scene(tmp_path), "--out", tmp_path / "out")[0] == 0
    assert leftovers(tmp_path / "out") == []


def wait_for(path: Path, proc: subprocess.Popen, seconds=60.0) -> None:
    end = time.monotonic() + seconds
    while not path.exists():
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < end, "probe did not start"
        time.sleep(0.02)


def held_run(tmp_path: Path, out: Path, stage: str) -> tuple[subprocess.Popen, Path]:
    ready = tmp_path / f"ready-{stage}"
    text = scene(tmp_path, f"held-{stage}", hold=stage, ready=str(ready), release=str(tmp_path / "go"))
    # SIGINT restored to its default: a shell's background job (`pytest &`) passes it on ignored, and
    # Python then installs no KeyboardInterrupt handler, so the interrupt under test would never arrive
    proc = subprocess.Popen([*PROBE_CLI, "run", text, "--out", str(out), "--quiet"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    wait_for(ready, proc)
    return proc, ready


@pytest.mark.parametrize("stage, sig", [("run", signal.SIGINT), ("plots", signal.SIGINT),
                                        ("plots", signal.SIGTERM)])
def test_interrupted_run_cleans_up_and_keeps_previous_results(tmp_path, capsys, stage, sig):
    out = tmp_path / "out"
    assert run(capsys, scene(tmp_path), "--out", out)[0] == 0
    before = snapshot(out)
    proc, _ = held_run(tmp_path, out, stage)
    try:
        proc.send_signal(sig)
        _, err = proc.communicate(timeout=60)
    finally:  # a run that outlived its signal must not outlive the test
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 130
    assert one_line(err) == f"symmech: interrupted; {out} keeps its previous content"
    assert snapshot(out) == before and leftovers(out) == []


def test_second_run_into_the_same_folder_is_refused(tmp_path, capsys):
    out = tmp_path / "out"
    proc, _ = held_run(tmp_path, out, "run")
    try:
        code, err = run(capsys, scene(tmp_path, file="other.txt"), "--out", out)
        assert code == 2
        assert f"is being written by another symmech run (pid {proc.pid} on " in one_line(err)
    finally:
        (tmp_path / "go").touch()
        proc.communicate(timeout=60)
    assert proc.returncode == 0
    assert assert_valid_output(out)["files"] == ["a.png", "extra.txt", "series.csv"]
    assert leftovers(out) == []


def test_internal_error_is_one_line_with_exit_3(tmp_path, capsys):
    code, err = run(capsys, scene(tmp_path, fail="bug"), "--out", tmp_path / "out")
    assert code == 3
    assert one_line(err).startswith("symmech: internal error: ZeroDivisionError: division by zero (please report")
    assert not (tmp_path / "out").exists()


def test_estimate_refused_past_max_time_and_shown_when_long(tmp_path, capsys):
    code, err = run(capsys, scene(tmp_path, estimate=50.0), "--out", tmp_path / "out", "--max-time", "10")
    assert code == 2
    assert one_line(err) == ("symmech: error: estimated run time 50 s (probe) exceeds --max-time 10 s; "
                             "raise --max-time to run it")
    code, err = run(capsys, scene(tmp_path, estimate=5.0), "--out", tmp_path / "out")
    assert code == 0 and one_line(err) == "symmech: estimated run time 5 s (probe)"
    assert assert_valid_output(tmp_path / "out")["estimate"] == {"seconds": 5.0, "what": "probe"}  # as told
    code, err = run(capsys, scene(tmp_path, estimate=5.0), "--out", tmp_path / "out", "--quiet")
    assert code == 0 and err == ""


def test_max_time_stops_a_running_scene(tmp_path, capsys):
    text = scene(tmp_path, hold="run", ready=str(tmp_path / "ready"), release=str(tmp_path / "never"))
    start = time.perf_counter()
    code, err = run(capsys, text, "--out", tmp_path / "out", "--max-time", "0.5")
    assert code == 2 and "over the time budget --max-time 0.5 s (probe)" in one_line(err)
    assert time.perf_counter() - start < 10


def test_bench_precision_goes_through_the_registry(tmp_path, capsys):
    code = main(["bench", "precision", scene(tmp_path), "--out", str(tmp_path / "p")])
    assert code == 0
    s = assert_valid_output(tmp_path / "p")
    assert set(s["timing_s"]) == {"validate", "precision", "write", "total"} and s["estimate"] is None


def test_python_api_is_the_same_path(tmp_path):
    sc = pipeline.load({"kind": "probe", "rows": 2})
    result = sc.run()
    assert result.tables["series"].column("t").tolist() == [0.0, 1.0]
    assert pipeline.write(result, tmp_path / "api", sc, plots=False) == (tmp_path / "api").resolve()
    assert assert_valid_output(tmp_path / "api")["scene_file"] == "<dict>"


def test_progress_bar_on_a_terminal_only(monkeypatch):
    import io

    from symmech.core.context import Context

    class Terminal(io.StringIO):
        def isatty(self):
            return True

    monkeypatch.setattr(sys, "stderr", Terminal())
    with Context().progress(10, "probe", unit="step") as bar:
        time.sleep(2.1)  # bars appear after 2 s: short runs stay silent
        bar.update(5)
    assert "probe" in sys.stderr.getvalue() and "5/10" in sys.stderr.getvalue()
    with Context(quiet=True).progress(10, "probe") as bar:
        assert bar.disable
    monkeypatch.setattr(sys, "stderr", io.StringIO())  # not a terminal
    with Context().progress(10, "probe") as bar:
        assert bar.disable


def test_precision_study_as_a_result_follows_the_contract(tmp_path):
    from symmech.core import precision

    rows = [{"method": "m1", "knob": "steps", "value": v, "error": 10.0 ** -v, "seconds": 1e-3 * v}
            for v in (1, 2, 3)]
    result = precision.result("probe", rows, "precision_probe", "probe study", "exact")
    sc = pipeline.load({"kind": "probe"})
    pipeline.write(result, tmp_path / "p", sc)
    s = assert_valid_output(tmp_path / "p")
    assert s["files"] == ["precision_probe.csv", "precision_probe.png"]
    assert s["reference"] == "exact"
    lines = (tmp_path / "p" / "precision_probe.csv").read_text().splitlines()
    assert lines[0] == "value [1],error [1],seconds [s],method,knob"
    assert lines[2] == "2.0,0.01,0.002,m1,steps"


def test_racing_runs_never_interleave(tmp_path):
    """Four runs started together into one folder: each writes a whole result or is refused."""
    out = tmp_path / "out"
    procs = [subprocess.Popen([*PROBE_CLI, "run", scene(tmp_path, f"s{i}", rows=i + 1, file=f"f{'abcd'[i]}.txt"),
                               "--out", str(out)], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
             for i in range(4)]
    results = [(p.wait(timeout=120), p.stderr.read()) for p in procs]
    assert {code for code, _ in results} <= {0, 2} and any(code == 0 for code, _ in results), results
    assert all("being written by another symmech run" in err for code, err in results if code == 2)
    s = assert_valid_output(out)
    assert len((out / "series.csv").read_text().splitlines()) == s["rows"] + 1
    assert s["files"] == ["a.png", s["scene"]["file"], "series.csv"] and leftovers(out) == []
