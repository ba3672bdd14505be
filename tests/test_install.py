"""A plain (non-editable) install runs every command from a folder outside the checkout
(`errata`, `latex smm:...` and `codegen --check` read the repository's
scenes/ through ``Path(__file__).parents`` and failed after ``pip install .``).

Slow: builds a wheel, installs it into a fresh venv (system site-packages give numpy,
scipy and sympy without downloads) and runs every bundled scene. `.ci/run` runs it.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
from outcontract import assert_valid_output

ROOT = Path(__file__).resolve().parents[1]
SCENES = sorted((ROOT / "scenes").glob("*.toml"))
NOT_SOURCE = shutil.ignore_patterns(".git", "build", "dist", "*.egg-info", "__pycache__", ".*cache",
                                    ".hypothesis", "out", "out-*")

# one worker builds the wheel once; its tests share one numba cache (cold: the bundled grain and elastic scenes
# run on their Python engines, as first runs do) and no run starts a background builder
pytestmark = [pytest.mark.slow, pytest.mark.xdist_group("test_install")]


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """(bin folder of a venv holding the wheel, a working folder outside the checkout)."""
    base = tmp_path_factory.mktemp("install")
    source = base / "source"  # a copy: building in place would leave build/ in the checkout
    shutil.copytree(ROOT, source, ignore=NOT_SOURCE)
    subprocess.run([sys.executable, "-m", "pip", "wheel", str(source), "--no-deps", "-q", "-w",
                    str(base / "wheels")], check=True, timeout=600)
    wheel, = (base / "wheels").glob("symmech-*.whl")
    venv = base / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)], check=True)
    subprocess.run([venv / "bin" / "python", "-m", "pip", "install", "-q", "--no-deps", str(wheel)],
                   check=True, timeout=600)
    work = base / "work"
    work.mkdir()
    return venv / "bin", work


def run_env(installed, **more) -> dict:
    """The environment of the installed commands: the module's numba cache, no background builder."""
    bin_, _ = installed
    return {**os.environ, "NUMBA_CACHE_DIR": str(bin_.parents[1] / "nb"), "SYMMECH_BACKGROUND_BUILD": "0", **more}


def symmech(installed, *args, timeout=900) -> subprocess.CompletedProcess:
    bin_, work = installed
    return subprocess.run([bin_ / "symmech", *map(str, args)], cwd=work, capture_output=True, text=True,
                          timeout=timeout, env=run_env(installed))


def test_main_job_and_a_compile_run_without_a_c_compiler(installed, tmp_path):
    """A machine without a C compiler runs everything. With only the venv's bin on PATH (no cc, gcc or
    clang reachable, CC pointing nowhere) and an empty numba cache, the README's main job answers at once (its
    first run: the Python engine, no builder in tests), and a compiled kernel of the installed package compiles
    and is cached (numba emits machine code through LLVM, no C toolchain; the grain engine's compile is the same
    and runs in tests/test_grain_coldstart.py; its build ahead of time is skipped without a compiler,
    tests/test_aot.py)."""
    bin_, work = installed
    assert not any(shutil.which(cc, path=str(bin_)) for cc in ("cc", "gcc", "clang"))
    env = run_env(installed, PATH=str(bin_), CC=str(tmp_path / "no-cc"))
    cache = Path(env["NUMBA_CACHE_DIR"])
    assert not cache.exists()  # the first test of the module to use it
    scene = next((bin_.parent / "lib").glob("python*/site-packages/symmech/scenes/grain_default.toml"))
    proc = subprocess.run([bin_ / "symmech", "run", scene, "--out", "no_cc", "--quiet"], cwd=work, env=env,
                          capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr
    summary = assert_valid_output(work / "no_cc")
    assert summary["kind"] == "grain" and summary["engine"] == "python" and summary["bounces"] > 100
    code = ("from symmech.numerics import kernels; k = kernels.load('grain_impact'); "
            "print(k.__name__, k.contact_height_scalar(2e-3, 1.5e-3, 1e-3, 0.3, 0.7, 1.1))")
    proc = subprocess.run([bin_ / "python", "-c", code], cwd=work, env=env, capture_output=True, text=True,
                          timeout=900)
    assert proc.returncode == 0 and proc.stdout.split()[0] == "symmech.generated.grain_impact_nb", proc.stderr
    assert any(cache.rglob("grain_impact_nb.contact_height_scalar*.nbi"))  # compiled here, cached there


def test_the_package_imported_is_the_installed_one(installed):
    bin_, work = installed
    code = ("import symmech, symmech.core.scene as s; print(symmech.__file__); print(s.scenes_folder()); "
            "from symmech.core import registry; print(json.dumps(sorted(registry.kinds())))")
    proc = subprocess.run([bin_ / "python", "-c", "import json; " + code], cwd=work, capture_output=True,
                          text=True, check=True)
    package, scenes, kinds = proc.stdout.splitlines()
    assert json.loads(kinds) == ["grain", "impact", "mechanism", "trolley"]
    site = bin_.parent / "lib"
    assert Path(package).is_relative_to(site) and Path(scenes).is_relative_to(site)
    assert sorted(p.name for p in Path(scenes).glob("*.toml")) == [p.name for p in SCENES]


@pytest.mark.parametrize("args, first_words", [
    (["errata"], ""),
    (["latex", "--list"], "grain_impact."),
    (["latex", "smm:rotor_boom.c"], "% smm:rotor_boom.c"),
    (["latex", "grain_impact.H"], "% grain_impact.H"),
])
def test_commands_run_outside_the_checkout(installed, args, first_words):
    proc = symmech(installed, *args)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == "" and proc.stdout.startswith(first_words) and len(proc.stdout) > 100


def test_codegen_in_a_plain_install(installed):
    proc = symmech(installed, "codegen", "--check")
    assert proc.returncode == 0, proc.stderr
    assert "up to date" in proc.stdout
    proc = symmech(installed, "codegen")  # would write into site-packages: refused in one line
    assert proc.returncode == 2 and len(proc.stderr.splitlines()) == 1
    assert "is an installed package" in proc.stderr and "--dir" in proc.stderr


def test_export_from_the_installed_package(installed):
    """The C glue and the generated C modules are package data: an FMU and a C folder from a plain install."""
    bin_, work = installed
    scene = next((bin_.parent / "lib").glob("python*/site-packages/symmech/scenes/smm_rotor_boom.toml"))
    for what, out in (("fmu", "rotor_boom.fmu"), ("c", "rotor_boom_c")):
        proc = symmech(installed, "export", what, scene, "--out", out)
        assert proc.returncode == 0, proc.stderr
    assert (work / "rotor_boom.fmu").is_file() and (work / "rotor_boom_c" / "example").is_file()


@pytest.mark.parametrize("scene", SCENES, ids=[p.stem for p in SCENES])
def test_every_bundled_scene_runs_from_the_installed_package(installed, scene):
    bin_, work = installed
    installed_scene = next((bin_.parent / "lib").glob(f"python*/site-packages/symmech/scenes/{scene.name}"))
    proc = symmech(installed, "run", installed_scene, "--out", scene.stem, "--quiet", "--max-time", "600")
    assert proc.returncode == 0, proc.stderr
    assert assert_valid_output(work / scene.stem)["kind"] == tomllib.loads(scene.read_text())["kind"]
