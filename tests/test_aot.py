"""The grain engine built ahead of time (symmech.numerics.aot): used only while current, never required.

The fast tests check the build's folder and a failed build without building (the record's rules:
tests/test_artifact_records.py); the slow ones build the loop with pycc (after numba's
cache, whose compiled functions the build reuses) and run it against numba's loop and the README's main job."""
import json
import subprocess
import sys
import threading
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from symmech.numerics import aot, artifacts
from symmech.grain.motion_engine import driver as compiled

ROOT = Path(__file__).resolve().parents[1]


def test_folder_follows_numba_cache_dir(monkeypatch, tmp_path):
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    own = aot.folder(compiled.__file__)  # a folder of this checkout's own in the shared cache
    assert own.parent == tmp_path and own.name.startswith("symmech-aot-")
    monkeypatch.delenv("NUMBA_CACHE_DIR")
    (tmp_path / "pkg").mkdir()
    assert aot.folder(str(tmp_path / "pkg" / "m.py")) == tmp_path / "pkg" / "__pycache__"


def test_sources_reach_the_loop_its_kernels_the_exact_flight_and_the_generated_twins():
    from symmech.grain.motion_engine import loop as compiled_loop

    files = {Path(f).name for f in artifacts.sources(compiled_loop)}
    assert {"loop.py", "ode.py", "sliding.py", "grain_motion_nb.py", "grain_impact_nb.py", "free_flight_nb.py",
            "free_flight.py", "brent.py"} <= files  # the exact flight's kernels and records' layouts
    assert all(Path(f).is_file() for f in artifacts.sources(compiled_loop))


@pytest.mark.parametrize("missing", ["C compiler", "numba.pycc"])
def test_no_build_without_a_c_compiler_or_pycc(monkeypatch, tmp_path, capfd, missing):
    """pycc fails without a compiler (or cannot be imported: it needs setuptools on Python >= 3.12): build()
    says so and writes nothing; nothing is printed."""
    monkeypatch.setenv("NUMBA_CACHE_DIR", str(tmp_path))
    if missing == "C compiler":
        monkeypatch.setenv("CC", str(tmp_path / "no-such-compiler"))
    else:
        monkeypatch.setitem(sys.modules, "numba.pycc", None)  # its import raises ImportError
    from symmech.grain.motion_engine import kinematics

    cross = (kinematics.cross, "f8[::1](f8[::1], f8[::1])")
    build = aot.Build("nocc", [compiled.__file__], lambda: {"f": cross})
    so, manifest = build.paths()
    assert build.build({}) is False  # no digest is read before the compile
    assert build.load() is None and not so.exists() and not manifest.exists()
    assert capfd.readouterr() == ("", "")


def test_the_python_side_imports_no_numba():
    code = ("import sys; from symmech.grain import motion_scene; from symmech.grain.motion_engine import driver as compiled; "
            "assert 'numba' not in sys.modules, 'numba imported'; print('ok')")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0 and done.stdout.strip() == "ok", done.stderr


# --------------------------------------------------------------------------- real builds (slow)


@pytest.fixture(scope="module")
def built():
    """The grain engine built ahead of time in the suite's cache (numba's cache first, by the session's builder)."""
    assert compiled.ENGINE.wait_warm(1200.0)
    compiled.ENGINE.warm(ahead=True)  # waits for a builder that is at it, else builds
    module = compiled.ENGINE.ahead_of_time()
    assert module is not None, "no C compiler? the slow tier needs one"
    return module


def _on_a_thread(*args):
    box = []
    worker = threading.Thread(target=lambda: box.append(compiled.simulate(*args)))
    worker.start()
    worker.join()
    return box[0]


@pytest.mark.slow
@pytest.mark.compiled_engine
@pytest.mark.parametrize("case", ["default scene, 2 s", "default scene, exact flight, 2 s", "crop grain, stiff slip"])
def test_the_built_loop_equals_numbas(built, case, tmp_path, monkeypatch):
    """The built loop (main thread) and numba's (a thread) on the default scene (flight, 493 impacts, sliding),
    with the DOP853 or the exact flight, and on a slip from rest that turns stiff (Radau): the same impacts and
    Radau steps, impact times within
    1e-12 s, final states within 1e-10 relative (one source, two compilations: they differ by round-off at
    most; the documented engine agreement with the Python loop is 1e-11 s and 1e-7)."""
    from test_grain_hard_cases import CROP, sweep_grain
    from test_grain_regimes import default_scene

    monkeypatch.chdir(ROOT)
    sc, t_end = (default_scene(tmp_path, 2.0), 2.0) if case.startswith("default") else (
        sweep_grain(CROP, 0.6e-3, 18.0, 0.12), 0.12)
    if "exact" in case:
        sc = replace(sc, numerics=replace(sc.numerics, flight="exact"))
    assert compiled.entry() is built.run
    ahead = compiled.simulate(sc.model, sc.numerics, sc.start, t_end)
    jit = _on_a_thread(sc.model, sc.numerics, sc.start, t_end)
    assert len(ahead.impacts) == len(jit.impacts) >= (400 if case.startswith("default") else 0)
    for a, b in zip(ahead.impacts, jit.impacts):
        assert abs(a["t"] - b["t"]) <= 1e-12
    for x, y in ((ahead.final.r, jit.final.r), (ahead.final.v, jit.final.v), (ahead.final.q, jit.final.q),
                 (ahead.final.w, jit.final.w)):
        np.testing.assert_allclose(x, y, rtol=1e-10, atol=1e-15)
    assert ahead.extra["implicit_slip_steps"] == jit.extra["implicit_slip_steps"]
    assert ahead.extra["implicit_slip_steps"] > 0  # both hand stiff slips to Radau


@pytest.mark.slow
@pytest.mark.compiled_engine
def test_the_main_job_runs_on_the_build_without_numba(built, tmp_path):
    code = ("import sys; "
            "from symmech.cli import main; code = main(['run', *sys.argv[1:], '--quiet']); "
            "print('numba' in sys.modules, 'scipy.linalg' in sys.modules, code)")
    done = subprocess.run([sys.executable, "-c", code, str(ROOT / "scenes" / "grain_default.toml"), "--out",
                           str(tmp_path / "out")], capture_output=True, text=True)
    # neither numba nor the scipy.linalg package (the build's BLAS and LAPACK modules are loaded alone)
    assert done.returncode == 0 and done.stdout.splitlines()[-1].split() == ["False", "False", "0"], done.stderr
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["engine_reason"].endswith("built (ahead of time)")
    assert {"grain_motion_nb", "grain_impact_nb"} <= set(summary["generated_modules"])  # compiled into it
    files = {Path(f).name for f in json.loads(compiled.ENGINE.ahead.paths()[1].read_text())["sources"]}
    assert {"driver.py", "layouts.py", "loop.py", "grain_motion_nb.py"} <= files


def test_a_builds_generated_modules_are_verified_and_listed_as_used(monkeypatch):
    from symmech.core import integrity

    monkeypatch.setattr(integrity, "_built_from", {})
    twin = Path(integrity.__file__).parents[2] / "generated" / "grain_motion_nb.py"
    integrity.verify_built_from([str(twin), str(ROOT / "symmech" / "grain" / "sliding.py")])
    header, _ = integrity.split(twin.read_text(encoding="utf-8"))
    assert integrity.used_modules()["grain_motion_nb"] == header.body
    assert integrity._built_from == {"grain_motion_nb": header.body}
