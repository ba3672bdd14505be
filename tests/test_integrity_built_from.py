"""A C twin's header, and an ahead-of-time build's sources (integrity.verify_built_from): the generated modules
among them, and only those, are verified and counted as used with the body hash their header records; a source
outside the package or the package's __init__.py is not a generated module. The package's folder is found from the
package itself (a test that found it beside integrity.py would miss it in a copy of the code)."""
from pathlib import Path

import symmech.generated
from symmech.core import integrity

FOLDER = Path(symmech.generated.__file__).parent


def test_a_builds_generated_modules_only_are_verified_and_counted(monkeypatch):
    monkeypatch.setattr(integrity, "_built_from", {})
    twin = FOLDER / "grain_motion_nb.py"
    recorded = twin.read_text(encoding="utf-8").splitlines()[2]  # "# body sha256 <64 hex digits>"
    assert recorded.startswith("# body sha256 ")
    integrity.verify_built_from([str(twin), str(Path(integrity.__file__)), str(FOLDER / "__init__.py")])
    assert integrity._built_from == {"grain_motion_nb": recorded.split()[-1]}
    assert integrity.used_modules()["grain_motion_nb"] == recorded.split()[-1]


def test_a_c_module_gets_its_header_in_c_comments():
    """The three header lines of a C twin start with //, and record the body's sha256 (hashlib, here)."""
    import hashlib

    body = "double f(double x) { return 2.0 * x; }\n"
    text = integrity.with_header(body, "1" * 64, "2" * 64, "//")
    lines = text.splitlines()
    assert [line[:10] for line in lines[:3]] == ["// symmech", "// source ", "// body sh"]
    assert lines[2] == "// body sha256 " + hashlib.sha256(body.encode()).hexdigest()
    assert text.endswith("\n" + body)
