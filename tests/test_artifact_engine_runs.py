"""`symmech run` and `symmech warm` on the real grain engine with damaged, foreign and unwritable artifacts.

Each case copies the suite's built engine (numba's cache files of the loop and their record, the ahead-of-time
build and its record) into its own ``NUMBA_CACHE_DIR`` and damages the copy, so the suite's cache is never
touched. Before: SIGBUS (exit 135) on a truncated ahead-of-time module, exit 3 (UnpicklingError) on a truncated
cache file, another checkout's build run silently. After: exit 0, one warning line naming the file, the answer
from the engine that is intact."""
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from symmech.numerics import artifacts
from symmech.grain.motion_engine import driver as compiled

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "grain_default.toml"
pytestmark = [pytest.mark.slow, pytest.mark.compiled_engine]


@pytest.fixture
def cache(tmp_path, monkeypatch):
    """A NUMBA_CACHE_DIR holding a copy of the built grain engine: (numba's folder of the loop, the
    ahead-of-time folder)."""
    from numba.core.caching import UserProvidedCacheLocator  # numba's layout under NUMBA_CACHE_DIR

    from symmech.grain.motion_engine import loop as compiled_loop

    assert compiled.ENGINE.wait_warm(1200.0)
    compiled.ENGINE.warm(ahead=True)
    assert compiled.ENGINE.ahead_of_time() is not None, "no C compiler? the slow tier needs one"
    built_so, built_record = compiled.ENGINE.ahead.paths()
    root = tmp_path / "numba-cache"
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(root))
    numba_folder = root / UserProvidedCacheLocator.get_suitable_cache_subpath(compiled_loop.__file__)
    shutil.copytree(compiled.ENGINE.cache_dir(), numba_folder,
                    ignore=shutil.ignore_patterns("*.pyc", "*.lock", "grain_aot*", "tmp*", "symmech-aot-*"))
    so, record = compiled.ENGINE.ahead.paths()  # under NUMBA_CACHE_DIR now
    so.parent.mkdir(parents=True)
    shutil.copy2(built_so, so)
    shutil.copy2(built_record, record)
    return numba_folder, so, record


def _run(tmp_path, **env):
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, "-m", "symmech", "run", str(SCENE), "--out", str(out), "--quiet"],
                          capture_output=True, text=True, timeout=900,
                          env={**os.environ, "SYMMECH_BACKGROUND_BUILD": "0", **env})
    summary = json.loads((out / "summary.json").read_text()) if done.returncode == 0 else None
    return done, summary


def _warnings(done) -> list[str]:
    return [line for line in done.stderr.splitlines() if line.startswith("symmech: warning: ")]


def test_the_copied_engine_runs_ahead_of_time_without_warnings(cache, tmp_path):
    done, summary = _run(tmp_path)
    assert done.returncode == 0 and _warnings(done) == [], done.stderr
    assert summary["engine_reason"].endswith("built (ahead of time)")
    assert {"grain_motion_nb", "grain_impact_nb"} <= set(summary["generated_modules"])


@pytest.mark.parametrize("damage", ["truncated", "random bytes", "another checkout"])
def test_a_refused_ahead_of_time_build_leaves_numbas_cache(cache, tmp_path, damage):
    numba_folder, so, record = cache
    if damage == "truncated":  # loaded as it was: SIGBUS
        so.write_bytes(so.read_bytes()[:100_000])
    elif damage == "random bytes":
        so.write_bytes(os.urandom(so.stat().st_size))
    else:
        record.write_text(record.read_text().replace(json.dumps(artifacts.CHECKOUT), '"/other/checkout/symmech"'))
    done, summary = _run(tmp_path)
    assert done.returncode == 0, done.stderr
    (warning,) = _warnings(done)
    assert str(record if damage == "another checkout" else so) in warning and "not loaded" in warning
    assert summary["engine_reason"] == "auto: the compiled engine is built (numba's cache)"
    assert {"grain_motion_nb", "grain_impact_nb"} <= set(summary["generated_modules"])  # numba's path ran them
    assert summary["headline"] and not so.exists()  # dropped: the next run does not warn again


@pytest.mark.parametrize("damage", ["index truncated", "data truncated", "data random bytes"])
def test_a_damaged_numba_cache_answers_on_the_python_engine(cache, tmp_path, damage):
    numba_folder, _, _ = cache
    kind = "nbi" if damage.startswith("index") else "1.nbc"
    (target,) = numba_folder.glob(f"loop.run-*.py*.{kind}")
    target.write_bytes(target.read_bytes()[:100] if "truncated" in damage else os.urandom(target.stat().st_size))
    done, summary = _run(tmp_path, SYMMECH_AHEAD_OF_TIME="0")
    assert done.returncode == 0, done.stderr
    (warning,) = _warnings(done)
    assert str(target) in warning and "cache of the grain engine is not used" in warning
    assert summary["engine"] == "python" and summary["headline"]
    assert not [m for m in summary["generated_modules"] if m.endswith("_nb")]  # the compiled loop never loaded


def test_warm_with_an_unwritable_cache_dir_is_one_warning(tmp_path):
    """NUMBA_CACHE_DIR under a regular file (unwritable for root too): numba keeps its cache beside the package,
    the build ahead of time is skipped with one warning naming the folder, exit 0."""
    assert compiled.ENGINE.wait_warm(1200.0)
    (tmp_path / "file").write_text("")
    done = subprocess.run([sys.executable, "-m", "symmech", "warm", "--engine", "grain"], capture_output=True,
                          text=True, timeout=900, env={**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "file" / "c")})
    assert done.returncode == 0 and "compiled grain engine ready" in done.stdout, done.stderr
    (warning,) = _warnings(done)
    assert str(tmp_path / "file" / "c") in warning and "cannot be written" in warning
