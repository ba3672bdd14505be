"""The fast-call extension (symmech.numerics.fastcall) on real damaged files: checked against its record before it
is loaded, refused with one warning naming it, rebuilt, and the numba path when it cannot be.

A truncated extension loaded as it was killed the process with SIGBUS (exit 135): that case runs in a
subprocess. The extension's kernels are checked against the generated numpy module by tests/test_fastcall.py."""
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from symmech.numerics import artifacts, fastcall


@pytest.fixture(scope="module")
def pristine(tmp_path_factory):
    """A folder holding the extension built and recorded once (~0.5 s with the system C compiler)."""
    folder = tmp_path_factory.mktemp("fastcall")
    if fastcall.extension.__wrapped__(folder) is None:
        pytest.fail("no C compiler: the fast-call extension cannot be built")
    return folder


@pytest.fixture
def folder(pristine, tmp_path, monkeypatch):
    """A copy of the built folder (same file names: the name is the source's and platform's hash)."""
    monkeypatch.setattr(artifacts, "_warned", set())
    shutil.copytree(pristine, tmp_path / "cache")
    return tmp_path / "cache"


def _paths(folder: Path) -> tuple[Path, Path]:
    so = fastcall.artifact(folder)
    return so, so.with_name(so.name.removesuffix(fastcall.sysconfig.get_config_var("EXT_SUFFIX")) + ".json")


def test_the_extension_is_recorded_with_its_source(folder):
    so, record = _paths(folder)
    data, why = artifacts.check(record, [so])
    assert why is None and data["sources"] == {str(fastcall.SOURCE): artifacts.digest(fastcall.SOURCE)}


def test_a_truncated_extension_is_rebuilt_not_loaded(folder):
    """In a subprocess: loading the truncated file would be SIGBUS. Exit 0, one warning naming the file, the
    extension rebuilt (its record current again) and its Kernel type usable."""
    so, record = _paths(folder)
    so.write_bytes(so.read_bytes()[:4000])
    code = ("import sys; from pathlib import Path; from symmech.numerics import fastcall; "
            "ext = fastcall.extension(Path(sys.argv[1])); print(ext is not None and hasattr(ext, 'Kernel'))")
    done = subprocess.run([sys.executable, "-c", code, str(folder)], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and done.stdout == "True\n", done.stderr
    assert done.stderr == (f"symmech: warning: {so} is damaged or replaced (its SHA-256 differs from {record.name}); "
                           "dropped and built again\n")
    assert artifacts.check(record, [so])[1] is None


@pytest.mark.parametrize("damage", ["random bytes", "zero bytes", "unrecorded", "another checkout",
                                    "another numpy", "record of a missing file"])
def test_a_refused_extension_is_one_warning_and_a_rebuild(folder, damage, capsys):
    so, record = _paths(folder)
    data = json.loads(record.read_text())
    if damage == "random bytes":
        so.write_bytes(os.urandom(so.stat().st_size))
    elif damage == "zero bytes":
        so.write_bytes(b"")
    elif damage == "unrecorded":
        record.unlink()
    elif damage == "another checkout":
        record.write_text(json.dumps({**data, "checkout": "/other/checkout/symmech"}))
    elif damage == "another numpy":  # a stale extension: built against another numpy, copied under this name
        record.write_text(json.dumps({**data, "platform": {**data["platform"], "numpy": "1.19.0"}}))
    else:
        so.unlink()
    ext = fastcall.extension.__wrapped__(folder)
    assert ext is not None and hasattr(ext, "Kernel")
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("symmech: warning: ") and err[0].endswith("; dropped and built again")
    assert str(record if damage in ("another checkout", "another numpy") else so) in err[0]
    assert artifacts.check(record, [so])[1] is None  # rebuilt and recorded by this checkout


def test_a_refused_extension_that_cannot_be_rebuilt_leaves_the_numba_path(folder, monkeypatch, capsys):
    """No compiler now: the damaged file is dropped, nothing is loaded (rhs/jac stay the twin's numba path)."""
    so, record = _paths(folder)
    so.write_bytes(so.read_bytes()[:4000])
    monkeypatch.setenv("CC", str(folder / "no-such-compiler"))
    assert fastcall.extension.__wrapped__(folder) is None
    assert not so.exists() and not record.exists()
    assert capsys.readouterr().err.count("\n") == 1
