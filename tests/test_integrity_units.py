"""symmech.core.integrity in-process: the header, the body hash, the per-process cache, the import
hook's finder and loader, and the atomic write (these kill mutants that the
fresh-interpreter tests of test_integrity.py cannot see). References are hand-written header lines
and hashlib, never the module's own functions."""
from __future__ import annotations

import codecs
import hashlib
import importlib.util
import locale
import os
import sys
import types

import pytest

from symmech import __version__
from symmech.core import integrity
from symmech.core.scene import SymmechError

INPUTS, KEY = "a" * 64, "b" * 64
BODY = "x = 1\n"


def _module_text(body: str = BODY, version: str = __version__) -> str:
    """A generated module as codegen writes it, the header spelled out by hand."""
    digest = hashlib.sha256(body.encode("utf-8")).hexdigest()
    return (f"# symmech {version} generated module; inputs sha256 {INPUTS}\n"
            f"# source key {KEY}\n# body sha256 {digest}\n{body}")


def test_with_header_writes_the_three_header_lines_then_the_body():
    assert integrity.with_header(BODY, INPUTS, KEY) == _module_text()
    assert integrity.sha256("é") == hashlib.sha256("é".encode()).hexdigest()


def test_split_reads_a_header_only_at_the_start_and_only_with_full_hashes():
    header, body = integrity.split(_module_text("y = 2\n"))
    assert header == integrity.Header(__version__, INPUTS, KEY, hashlib.sha256(b"y = 2\n").hexdigest())
    assert body == "y = 2\n"
    assert header.text() + body == _module_text("y = 2\n")
    for text in (" " + _module_text(), _module_text().replace(KEY, KEY[:-1], 1), BODY):
        assert integrity.split(text) == (None, text)


@pytest.mark.parametrize("content, why", [
    (None, "missing"),
    (b"\xff\xfe not utf-8", "unreadable (UnicodeDecodeError)"),
    (BODY.encode(), "edited (no symmech header)"),
    ((_module_text() + "# appended\n").encode(), "edited or truncated (body sha256 differs from its header)"),
    (_module_text(version="0.0.1").encode(), f"stale (written by symmech 0.0.1, this is {__version__})"),
    (_module_text().encode(), None),
])
def test_problem_names_why_a_module_cannot_be_used(tmp_path, content, why):
    path = tmp_path / "m.py"
    if content is not None:
        path.write_bytes(content)
    assert integrity.problem(path) == why
    if why is None:
        assert integrity.verify_file("m", path) == hashlib.sha256(BODY.encode()).hexdigest()
    else:
        with pytest.raises(SymmechError) as exc:
            integrity.verify_file("m", path)
        assert str(exc.value) == f"generated module m is {why}: regenerate with `symmech codegen`"


def test_a_file_is_hashed_once_until_its_mtime_or_size_changes(tmp_path):
    path = tmp_path / "m.py"
    path.write_text(_module_text())
    digest = hashlib.sha256(BODY.encode()).hexdigest()
    assert integrity.verify_file("m", path) == digest
    stamp = os.stat(path).st_mtime_ns
    path.write_text(_module_text().replace("x = 1", "x = 2"))  # same size: an edit the cache hides
    os.utime(path, ns=(stamp, stamp))
    assert integrity.verify_file("m", path) == digest
    os.utime(path, ns=(stamp + 10**9, stamp + 10**9))
    with pytest.raises(SymmechError, match="m is edited or truncated"):
        integrity.verify_file("m", path)


def test_the_finder_loads_intact_modules_of_the_package_only(tmp_path):
    (tmp_path / "good.py").write_text(_module_text())
    (tmp_path / "bad.py").write_text(_module_text() + "x = 3\n")
    finder = integrity._GeneratedFinder()
    assert finder.find_spec("json", None) is None
    assert finder.find_spec("symmech.generated_like.good", [str(tmp_path)]) is None
    assert finder.find_spec("symmech.generated.absent", [str(tmp_path)]) is None
    good = finder.find_spec("symmech.generated.good", [str(tmp_path)])
    assert isinstance(good.loader, integrity._VerifyingLoader)
    assert (good.loader.name, good.loader.path) == ("symmech.generated.good", str(tmp_path / "good.py"))
    module = importlib.util.module_from_spec(good)
    good.loader.exec_module(module)
    assert module.x == 1
    bad = finder.find_spec("symmech.generated.bad", [str(tmp_path)])
    with pytest.raises(SymmechError, match=r"^generated module bad is edited or truncated"):
        bad.loader.exec_module(importlib.util.module_from_spec(bad))


def test_guard_checks_the_index_and_puts_one_finder_first(tmp_path, monkeypatch):
    monkeypatch.setattr(sys, "meta_path", [f for f in sys.meta_path if not isinstance(f, integrity._GeneratedFinder)])
    index = tmp_path / "__init__.py"
    index.write_text(BODY)
    with pytest.raises(SymmechError, match=r"^generated module __init__ is edited \(no symmech header\)"):
        integrity.guard(str(index))
    index.write_text(_module_text())
    integrity.guard(str(index))
    integrity.guard(str(index))
    assert isinstance(sys.meta_path[0], integrity._GeneratedFinder)
    assert sum(isinstance(f, integrity._GeneratedFinder) for f in sys.meta_path) == 1


def test_used_modules_reads_the_recorded_hash_of_package_modules_only(tmp_path, monkeypatch):
    (tmp_path / "with_header.py").write_text(_module_text("z = 0\n"))
    (tmp_path / "plain.py").write_text(BODY)
    for name, file in [("symmech.generated.fake_a", "with_header.py"), ("symmech.generated.fake_b", "plain.py"),
                       ("symmech.generatedfake_c", "plain.py"), ("fake_d", "plain.py")]:
        module = types.ModuleType(name)
        module.__file__ = str(tmp_path / file)
        monkeypatch.setitem(sys.modules, name, module)
    monkeypatch.setitem(sys.modules, "symmech.generated.fake_e", types.ModuleType("symmech.generated.fake_e"))
    used = integrity.used_modules()
    assert used["fake_a"] == hashlib.sha256(b"z = 0\n").hexdigest()
    assert used["fake_b"] == "no header"
    assert not {"fake_e", "generatedfake_c", "fake_d"} & set(used)
    assert not any(name.startswith(("symmech.", ".")) for name in used)


def test_atomic_write_replaces_the_file_readable_by_all_and_leaves_nothing_else(tmp_path):
    path = tmp_path / "m.py"
    path.write_text("old")
    integrity.write_atomic(path, "é\r\nnew\n")
    assert path.read_bytes() == "é\r\nnew\n".encode()
    assert os.stat(path).st_mode & 0o777 == 0o644
    assert [p.name for p in tmp_path.iterdir()] == ["m.py"]


def test_atomic_write_renames_a_hidden_temporary_file_from_beside_the_target(tmp_path, monkeypatch):
    path = tmp_path / "m.py"
    renames = []
    replace = os.replace
    monkeypatch.setattr(os, "replace", lambda src, dst: (renames.append((src, dst)), replace(src, dst)))
    integrity.write_atomic(path, "text")
    [(src, dst)] = renames
    src = os.fspath(src)
    assert (os.path.dirname(src), dst) == (str(tmp_path), path)
    assert os.path.basename(src).startswith(".m.py.") and src.endswith(".tmp")
    assert path.read_text() == "text"


def test_files_are_read_and_written_as_utf8_whatever_the_locale(tmp_path, monkeypatch):
    """Under a C locale (ASCII: LANG=C, say, in a program that has not switched to UTF-8) a module whose body holds
    non-ASCII text is written byte for byte as UTF-8, found intact, and its recorded hash is read."""
    body = "s = 'μ — é'\n"
    text = _module_text(body)
    path = tmp_path / "m.py"
    module = types.ModuleType("symmech.generated.fake_utf8")
    module.__file__ = str(path)
    monkeypatch.setitem(sys.modules, "symmech.generated.fake_utf8", module)
    before = locale.setlocale(locale.LC_CTYPE)
    locale.setlocale(locale.LC_CTYPE, "C")
    try:
        assert codecs.lookup(locale.getencoding()).name == "ascii"
        integrity.write_atomic(path, text)
        assert integrity.problem(path) is None
        assert integrity.used_modules()["fake_utf8"] == hashlib.sha256(body.encode("utf-8")).hexdigest()
    finally:
        locale.setlocale(locale.LC_CTYPE, before)
    assert path.read_bytes() == text.encode("utf-8")


def test_an_interrupt_after_the_rename_surfaces_as_itself(tmp_path, monkeypatch):
    """The temporary file is already renamed when the interrupt comes: its clean-up finds nothing to remove and
    the caller sees the interrupt, not a FileNotFoundError; the file holds the new text."""
    replace = os.replace

    def replace_then_interrupt(src, dst):
        replace(src, dst)
        raise RuntimeError("interrupted after the rename")

    monkeypatch.setattr(os, "replace", replace_then_interrupt)
    path = tmp_path / "m.py"
    with pytest.raises(RuntimeError, match="^interrupted after the rename$"):
        integrity.write_atomic(path, "new")
    assert [p.name for p in tmp_path.iterdir()] == ["m.py"] and path.read_text() == "new"


def test_a_file_whose_stat_fails_is_checked_every_time(tmp_path, monkeypatch):
    """Without a (path, mtime, size) stamp nothing is cached: a damaged module checked after an intact one, both
    unstat-able, is still refused."""
    good, bad = tmp_path / "good.py", tmp_path / "bad.py"
    good.write_text(_module_text())
    bad.write_text(BODY)

    def unavailable(path, *args, **kwargs):
        raise PermissionError(13, "Permission denied", str(path))

    monkeypatch.setattr(os, "stat", unavailable)
    assert integrity.verify_file("good", good) == hashlib.sha256(BODY.encode()).hexdigest()
    with pytest.raises(SymmechError, match=r"^generated module bad is edited \(no symmech header\)"):
        integrity.verify_file("bad", bad)


def test_a_damaged_module_of_a_build_is_named_in_the_refusal(tmp_path, monkeypatch):
    """An ahead-of-time build's source in the package's folder (here a stand-in folder) that is not intact is
    refused by its module name, as its import would be."""
    import symmech.generated

    monkeypatch.setattr(symmech.generated, "__file__", str(tmp_path / "__init__.py"))
    (tmp_path / "twin_nb.py").write_text(BODY)
    with pytest.raises(SymmechError, match=r"^generated module twin_nb is edited \(no symmech header\): regenerate"):
        integrity.verify_built_from([str(tmp_path / "twin_nb.py")])


def test_the_finder_leaves_every_other_module_to_the_usual_loaders():
    """With the finder installed (by the package's import), a module outside the package imported afresh (colorsys
    of the standard library, no symmech header) loads as usual. No fixture: none may import anything first."""
    import symmech.generated  # noqa: F401

    assert any(isinstance(finder, integrity._GeneratedFinder) for finder in sys.meta_path)
    sys.modules.pop("colorsys", None)
    colorsys = importlib.import_module("colorsys")
    assert colorsys.rgb_to_hsv(0.0, 0.0, 1.0) == (2 / 3, 1.0, 1.0)
