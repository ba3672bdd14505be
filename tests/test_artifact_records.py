"""Records of built artifacts (symmech.numerics.artifacts) and the ahead-of-time loader on real damaged files.

Every refusal names the file; a refused ahead-of-time build is dropped after one warning and never loaded (a
file that is not an extension module would raise ImportError if it were: the refusal must not try)."""
import json
import os
import subprocess
import sys

import pytest

from symmech.numerics import aot, artifacts
from symmech.grain.motion_engine import driver as compiled


@pytest.fixture
def built(tmp_path):
    """A built file and a source, recorded as this checkout records them."""
    so, source, record = tmp_path / "thing.so", tmp_path / "thing.c", tmp_path / "thing.json"
    so.write_bytes(os.urandom(4096))
    source.write_text("int x;\n")
    artifacts.write_record(record, [so], artifacts.digests([str(source)]))
    return so, source, record


def test_a_current_record_is_accepted(built):
    so, source, record = built
    data, why = artifacts.check(record, [so])
    assert why is None
    assert data["built"] == {"thing.so": artifacts.digest(so)} and data["checkout"] == artifacts.CHECKOUT
    assert data["sources"] == {str(source): artifacts.digest(source)}


@pytest.mark.parametrize("damage, words", [
    (lambda so: so.write_bytes(so.read_bytes()[:1000]), "is damaged or replaced"),  # truncated
    (lambda so: so.write_bytes(os.urandom(4096)), "is damaged or replaced"),  # random bytes, same size
    (lambda so: so.write_bytes(b""), "is damaged or replaced"),  # zero bytes
    (lambda so: so.unlink(), "is missing or unreadable"),
])
def test_a_damaged_built_file_is_refused_by_name(built, damage, words):
    so, _, record = built
    damage(so)
    data, why = artifacts.check(record, [so])
    assert data is None and why == f"{so} {words}" + (f" (its SHA-256 differs from {record.name})"
                                                    if "damaged" in words else "")


def test_an_edited_source_makes_the_artifact_stale(built):
    so, source, record = built
    source.write_text("int y;\n")
    assert artifacts.check(record, [so]) == (None, f"{record} is stale (built from another version of {source})")


def test_another_checkout_is_refused(built):
    so, _, record = built
    data = json.loads(record.read_text())
    data["checkout"] = "/elsewhere/symmech"
    record.write_text(json.dumps(data))
    assert artifacts.check(record, [so]) == (None, f"{record} was built by another checkout (/elsewhere/symmech)")


@pytest.mark.parametrize("field, value", [("numpy", "1.0.0"), ("abi", ".cpython-399-x.so"), ("python", "3.0")])
def test_another_platform_is_refused(built, field, value):
    """An extension of another numpy, Python ABI or Python: refused before loading."""
    so, _, record = built
    data = json.loads(record.read_text())
    data["platform"][field] = value
    record.write_text(json.dumps(data))
    assert artifacts.check(record, [so]) == (None, f"{record} was built for another Python or numpy")


@pytest.mark.parametrize("text", ["", "{", "[]", '{"built": {}}', b"\xff\xfe".decode("latin-1")])
def test_an_unreadable_record_is_refused(built, text):
    so, _, record = built
    record.write_text(text, encoding="latin-1")
    data, why = artifacts.check(record, [so])
    assert data is None and why.startswith(f"{record} is unreadable (")


def test_an_unrecorded_file_and_a_missing_one(built, tmp_path):
    so, _, record = built
    record.unlink()
    assert artifacts.check(record, [so]) == (None, f"{so} is not recorded (no thing.json)")
    assert artifacts.check(tmp_path / "none.json", [tmp_path / "none.so"]) == (None, "missing")
    (tmp_path / "file").write_text("")  # a cache folder that cannot exist: nothing built, nothing to refuse
    assert artifacts.check(tmp_path / "file" / "x.json", [tmp_path / "file" / "x.so"]) == (None, "missing")


def test_a_record_that_lists_a_missing_file(built, tmp_path):
    """A record pointing at a file that is not there (one of several built files deleted)."""
    so, source, record = built
    other = tmp_path / "other.nbc"
    other.write_bytes(b"data")
    artifacts.write_record(record, [so, other], artifacts.digests([str(source)]))
    other.unlink()
    assert artifacts.check(record, [so]) == (None, f"{other} is missing or unreadable")


def test_a_warning_is_one_line_once_per_process(capsys, monkeypatch):
    monkeypatch.setattr(artifacts, "_warned", set())
    for _ in range(3):
        artifacts.warn("/x/y.so is damaged; rebuilt")
    assert capsys.readouterr().err == "symmech: warning: /x/y.so is damaged; rebuilt\n"


# --------------------------------------------------------------------------- the ahead-of-time loader


@pytest.fixture
def build(monkeypatch, tmp_path):
    """A Build in an empty NUMBA_CACHE_DIR holding a 'module' that is no extension module, with a current
    record (were it loaded, ImportError)."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    monkeypatch.setattr(artifacts, "_warned", set())
    source = tmp_path / "loop.py"
    source.write_text("x = 1\n")
    b = aot.Build("probe", [compiled.__file__], dict)
    so, record = b.paths()
    so.parent.mkdir(parents=True)
    so.write_bytes(b"not an extension module" * 100)
    artifacts.write_record(record, [so], artifacts.digests([str(source)]))
    return b, so, record, source


def test_the_folder_is_the_checkouts_own_under_a_shared_cache(build, tmp_path, monkeypatch):
    b, so, _, _ = build
    assert so.parent.parent == tmp_path and so.parent.name.startswith("symmech-aot-")
    monkeypatch.setattr(artifacts, "CHECKOUT", "/another/clone/symmech")  # a second checkout, same NUMBA_CACHE_DIR
    assert b.paths()[0].parent.parent == tmp_path and b.paths()[0].parent != so.parent


def test_a_current_build_is_loaded_and_an_unloadable_one_dropped(build, capsys):
    """Current: the (fake) module is loaded, which fails (ImportError): one warning, dropped, no exception."""
    b, so, record, _ = build
    assert b.load() is None and b.refused and not so.exists() and not record.exists()
    (line,) = capsys.readouterr().err.splitlines()
    assert line.startswith(f"symmech: warning: {so} cannot be loaded (") and "numba's cache serves" in line


@pytest.mark.parametrize("damage", ["truncated", "random bytes", "zero bytes", "another checkout", "stale source",
                                    "record of a missing module"])
def test_a_refused_build_is_dropped_after_one_warning(build, damage, capsys):
    b, so, record, source = build
    if damage == "truncated":
        so.write_bytes(so.read_bytes()[:100])
    elif damage == "random bytes":
        so.write_bytes(os.urandom(2300))
    elif damage == "zero bytes":
        so.write_bytes(b"")
    elif damage == "another checkout":
        record.write_text(record.read_text().replace(json.dumps(artifacts.CHECKOUT), '"/other/checkout/symmech"'))
    elif damage == "stale source":
        source.write_text("x = 2\n")
    else:
        so.unlink()
    assert b.load() is None and b.refused
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("symmech: warning: ") and "; not loaded (numba's cache" in err[0]
    assert (str(so) if damage in ("truncated", "random bytes", "zero bytes", "record of a missing module")
            else str(record)) in err[0]
    assert not so.exists() and not record.exists()  # dropped: the next run neither warns nor loads it


def test_no_build_no_warning(monkeypatch, tmp_path, capsys):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    b = aot.Build("probe", [compiled.__file__], dict)
    assert b.load() is None and not b.refused and capsys.readouterr().err == ""


def test_an_unwritable_folder_is_one_warning_and_no_build(monkeypatch, tmp_path, capsys):
    """NUMBA_CACHE_DIR under a regular file (read-only as root too): build() returns False with one warning
    naming the folder, before any compiler runs."""
    (tmp_path / "file").write_text("")
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "file" / "cache"))
    monkeypatch.setattr(artifacts, "_warned", set())
    b = aot.Build("probe", [compiled.__file__], lambda: {"f": (compiled.pack, None)})
    assert b.build({}) is False  # no digest is read before the folder is written
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and f"{b.paths()[0].parent} cannot be written" in err[0]


def test_a_build_being_replaced_is_left_alone(build, capsys):
    """A builder holds the lock while it replaces the module and its record: a reader neither judges nor drops
    the half-replaced pair (here: a module whose record does not match yet), it goes without the build."""
    from symmech.numerics.build import file_lock

    b, so, record, _ = build
    so.write_bytes(b"the new module, record not written yet")
    with file_lock(b.lock_file(), wait=True):
        code = ("import sys; from symmech.numerics import aot; from symmech.grain.motion_engine import driver as compiled; "
                "b = aot.Build('probe', [compiled.__file__], dict); print(b.load() is None, b.refused)")
        done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and done.stdout.split() == ["True", "False"] and done.stderr == "", done.stderr
    assert so.exists() and record.exists()
