"""numba's cache files under symmech's guard and an engine's record of them, on real damaged files.

A tiny ``cache=True`` function in a temporary module stands in for an engine's entry (the same numba cache
files, compiled in a fraction of a second; the module executed anew is a new dispatcher that loads them):
its index (``.nbi``) and data (``.nbc``) files are truncated or overwritten with random bytes; numba alone
raises on them (UnpicklingError, EOFError: exit 3 of a run), under
:func:`symmech.numerics.artifacts.guard_numba_cache` the process warns once naming the file, recompiles and answers.
"""
import hashlib
import importlib.util
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numba
import pytest

from symmech.numerics import artifacts, build

SOURCE = textwrap.dedent("""
    import numba

    @numba.njit(cache=True)
    def cube_plus(x):
        return x * x * x + 1.5
""")


def fresh(folder: Path):
    """The module in ``folder`` executed anew: a new dispatcher, which loads numba's cache at its first call."""
    spec = importlib.util.spec_from_file_location("probe_entry", folder / "probe_entry.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture
def entry(tmp_path, monkeypatch):
    """The folder of the module and its cache folder (in-tree: ``NUMBA_CACHE_DIR`` unset), after a first call
    that compiled it into the cache, under the guard."""
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    monkeypatch.setattr(numba.core.config, "CACHE_DIR", "")  # numba read the variable at its import
    monkeypatch.setattr(artifacts, "_warned", set())
    (tmp_path / "probe_entry.py").write_text(SOURCE)
    artifacts.guard_numba_cache()
    assert fresh(tmp_path).cube_plus(2.0) == 9.5
    return tmp_path, tmp_path / "__pycache__"


def _damage(path: Path, how: str) -> None:
    path.write_bytes(path.read_bytes()[:len(path.read_bytes()) // 2] if how == "truncated" else os.urandom(600))


@pytest.mark.parametrize("how", ["truncated", "random bytes"])
@pytest.mark.parametrize("kind", ["nbi", "nbc"])
def test_a_damaged_cache_file_is_one_warning_and_a_recompile(entry, kind, how, capsys):
    folder, cache = entry
    (damaged,) = cache.glob(f"probe_entry.cube_plus-*.{kind}")
    _damage(damaged, how)
    module = fresh(folder)
    assert module.cube_plus(2.0) == 9.5 and module.cube_plus.stats.cache_misses  # compiled, not loaded
    err = capsys.readouterr().err
    assert err.startswith(f"symmech: warning: numba cache file {damaged} is damaged (")
    assert err.endswith("); dropped and recompiled\n") and err.count("\n") == 1
    again = fresh(folder)  # the recompile was cached whole: loaded, no warning
    assert again.cube_plus(2.0) == 9.5 and not again.cube_plus.stats.cache_misses
    assert capsys.readouterr().err == ""


@pytest.mark.slow
def test_numba_alone_fails_on_a_truncated_index(entry):
    """What the guard is for: the same damage without it (a fresh process) is an exception out of numba."""
    folder, cache = entry
    (index,) = cache.glob("probe_entry.cube_plus-*.nbi")
    _damage(index, "truncated")
    code = f"import sys; sys.path.insert(0, {str(folder)!r}); import probe_entry; probe_entry.cube_plus(2.0)"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 1 and ("UnpicklingError" in done.stderr or "EOFError" in done.stderr)


# --------------------------------------------------------------------------- an engine's record


@pytest.fixture
def engine(entry, monkeypatch):
    """A build.Engine over the tiny entry, warmed (compiled, cache recorded) in this process."""
    folder, cache = entry
    module = fresh(folder)
    sys.modules["probe_entry"] = module  # an entry's sources are found through its module
    eng = build.Engine("probe", "probe_entry", lambda: {module.cube_plus: (numba.float64,)}, 1.0)
    assert eng.warm()
    monkeypatch.setattr(artifacts, "_warned", set())  # the warm's own warning (no record yet) printed
    yield eng, cache
    sys.modules.pop("probe_entry", None)


def test_a_warm_build_records_index_data_and_sources(engine):
    eng, cache = engine
    data, why = artifacts.check(eng.record_file(), [])
    assert why is None and not eng.cold()
    assert {Path(f).suffix for f in data["built"]} == {".nbi", ".nbc"}
    assert [Path(f).name for f in data["sources"]] == ["probe_entry.py"]


@pytest.mark.parametrize("damage", ["data truncated", "index random bytes", "record of another checkout",
                                    "source edited"])
def test_a_refused_cache_is_cold_with_one_warning_then_rebuilt(engine, damage, capsys):
    eng, cache = engine
    capsys.readouterr()
    (index,) = cache.glob("probe_entry.cube_plus-*.nbi")
    (data,) = cache.glob("probe_entry.cube_plus-*.nbc")
    record = eng.record_file()
    if damage == "data truncated":
        _damage(data, "truncated")
    elif damage == "index random bytes":
        _damage(index, "random bytes")
    elif damage == "record of another checkout":
        record.write_text(record.read_text().replace(artifacts.CHECKOUT, "/other/checkout"))
    else:
        source = index.parent.parent / "probe_entry.py"
        source.write_text(source.read_text() + "\n# edited\n")
    assert eng.cold()
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("symmech: warning: ")
    assert "cache of the probe engine is not used" in err[0]
    assert str({"data truncated": data, "index random bytes": index}.get(damage, record)) in err[0]
    assert eng.warm() and not eng.cold()  # dropped and compiled again, recorded
    assert artifacts.check(record, [])[1] is None


def test_a_source_edited_while_the_build_compiles_leaves_a_stale_record(entry, monkeypatch, capsys):
    """The record holds the sources as they were when the build began (its process had imported them): an edit
    during the compile makes the cache stale at the next check (one warning naming the record), not current."""
    folder, cache = entry
    module = fresh(folder)
    monkeypatch.setitem(sys.modules, "probe_entry", module)  # an entry's sources are found through its module
    source = folder / "probe_entry.py"
    compile_as_imported = module.cube_plus.compile

    def compile_while_edited(signature):
        source.write_text(source.read_text().replace("1.5", "2.5"))
        return compile_as_imported(signature)

    monkeypatch.setattr(module.cube_plus, "compile", compile_while_edited)
    eng = build.Engine("probe", "probe_entry", lambda: {module.cube_plus: (numba.float64,)}, 1.0)
    assert eng.warm() and module.cube_plus(2.0) == 9.5  # the code compiled is the one imported
    data = json.loads(eng.record_file().read_text())
    assert data["sources"] == {str(source): hashlib.sha256(SOURCE.encode()).hexdigest()}
    capsys.readouterr()
    assert eng.cold()
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{eng.record_file()} is stale (built from another version of {source})" in err


def test_an_unrecorded_cache_is_cold_without_a_warning(engine, capsys):
    """numba's files without a record (a cache from before records, or the record deleted): nothing is refused
    at load, the engine is cold and the next build replaces them."""
    eng, cache = engine
    capsys.readouterr()
    eng.record_file().unlink()
    assert eng.cold() and capsys.readouterr().err == ""
    assert eng.warm() and not eng.cold()


def test_the_record_lives_in_numbas_folder_of_the_entries_module(engine, monkeypatch, tmp_path):
    eng, cache = engine
    module = sys.modules["probe_entry"]
    assert eng.cache_dir() == build.cache_dir(module.cube_plus) == cache and eng.record_file().parent == cache
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path / "elsewhere"))
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path / "elsewhere"))
    assert build.cache_dir(fresh(cache.parent).cube_plus) == eng.cache_dir() != cache


def test_a_cold_grain_engine_is_told_without_importing_its_loop(tmp_path):
    """No record in an empty NUMBA_CACHE_DIR: cold, and neither the compiled loop nor its generated twins were
    imported (summary.json's generated_modules lists what ran: the Python engine's modules only)."""
    code = ("import sys; from symmech.grain.motion_engine import driver as compiled; print(compiled.ENGINE.cold(), "
            "'symmech.grain.motion_engine.loop' in sys.modules, 'symmech.generated.grain_motion_nb' in sys.modules)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                          env={**os.environ, "NUMBA_CACHE_DIR": str(tmp_path)})
    assert done.returncode == 0 and done.stdout.split() == ["True", "False", "False"], done.stderr
