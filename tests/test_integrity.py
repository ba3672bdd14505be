"""Every import of a generated module checks its body hash, by any path.

Each case copies ``generated/`` to a temporary folder, appends one harmless line to one
module, and in a fresh interpreter makes that copy the ``symmech.generated`` package
(its own ``__init__`` runs, as an installed one does) before importing.
"""
from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from symmech.generated import MODULES

ROOT = Path(__file__).resolve().parents[1]
GENERATED = ROOT / "generated"
SCENES = ROOT / "scenes"
EDIT = "# one harmless appended line\n"
REFUSAL = "generated module {name} is edited or truncated (body sha256 differs from its header): " \
          "regenerate with `symmech codegen`"
# Makes the folder PACKAGE the package symmech.generated of a fresh interpreter.
BOOT = """\
import importlib.util, sys
spec = importlib.util.spec_from_file_location("symmech.generated", {init!r}, submodule_search_locations=[{folder!r}])
package = importlib.util.module_from_spec(spec)
sys.modules["symmech.generated"] = package
spec.loader.exec_module(package)
"""
# Imports NAME by every style; prints {style: the refusal, or "imported"}.
STYLES = """\
import importlib, json
from symmech.core.scene import SymmechError
def attempt(style):
    try:
        style()
    except SymmechError as exc:
        return str(exc)
    return "imported"
def load():
    if not {name!r}.endswith("_nb"):
        sys.modules["numba"] = None  # kernels.load uses the numpy module only when numba is absent
    from symmech.numerics import kernels
    kernels.load({name!r}.removesuffix("_nb"))
answers = {{
    "import": attempt(lambda: exec("import symmech.generated.{name}")),
    "from": attempt(lambda: exec("from symmech.generated import {name}")),
    "import_module": attempt(lambda: importlib.import_module("symmech.generated.{name}")),
    "kernels.load": attempt(load),
    "control": attempt(lambda: importlib.import_module("symmech.generated.{control}")),
}}
print(json.dumps(answers))
"""


def _edited_copy(tmp_path: Path, *names: str) -> Path:
    folder = tmp_path / "generated"
    shutil.copytree(GENERATED, folder, ignore=shutil.ignore_patterns("__pycache__"))
    for name in names:
        with open(folder / f"{name}.py", "a", encoding="utf-8") as f:
            f.write(EDIT)
    return folder


def _python(folder: Path, code: str, cwd: Path) -> subprocess.CompletedProcess:
    boot = BOOT.format(init=str(folder / "__init__.py"), folder=str(folder))
    return subprocess.run([sys.executable, "-c", boot + code], cwd=cwd, capture_output=True, text=True, timeout=300)


# one numpy and one numba module of each paper in the default tier (a fresh interpreter each, ~0.4 s of CPU);
# every other module in the slow tier: the import hook that refuses them is the same for all
SAMPLE = {"grain_impact", "grain_motion_nb", "smm_rotor_boom", "smm_formulas_nb", "trolley_frame",
          "trolley_elastic_lagrange_nb", "trolley_printed", "grain_impact_printed_nb"}


@pytest.mark.parametrize("name", [pytest.param(n, marks=() if n in SAMPLE else pytest.mark.slow)
                                  for n in sorted(MODULES) + sorted(f"{n}_nb" for n in MODULES)])
def test_every_import_style_refuses_an_edited_module(tmp_path, name):
    control = "trolley_printed" if name != "trolley_printed" else "grain_impact_printed"
    proc = _python(_edited_copy(tmp_path, name), STYLES.format(name=name, control=control), tmp_path)
    assert proc.returncode == 0, proc.stderr
    answers = json.loads(proc.stdout.splitlines()[-1])
    refusal = REFUSAL.format(name=name)
    assert answers == {"import": refusal, "from": refusal, "import_module": refusal, "kernels.load": refusal,
                       "control": "imported"}


def test_an_intact_copy_imports_every_module_and_an_edited_index_is_refused(tmp_path):
    names = sorted(MODULES) + sorted(f"{n}_nb" for n in MODULES)
    code = f"import importlib\nfor n in {names!r}: importlib.import_module('symmech.generated.' + n)\nprint('ok')"
    proc = _python(_edited_copy(tmp_path), code, tmp_path)
    assert (proc.returncode, proc.stdout) == (0, "ok\n"), proc.stderr
    proc = _python(_edited_copy(tmp_path / "index", "__init__"), "print('imported')", tmp_path)
    assert proc.returncode == 1 and "imported" not in proc.stdout
    assert proc.stderr.splitlines()[-1] == "symmech.core.scene.SymmechError: " + REFUSAL.format(name="__init__")


def test_edit_after_a_verified_import_is_refused_in_the_same_process(tmp_path):
    """Each file is hashed once per process, unless it changes (the cache is keyed by mtime and size)."""
    code = ("import importlib\nfrom symmech.core import integrity\n"
            "first = importlib.import_module('symmech.generated.trolley_printed')\n"
            f"open({str(tmp_path / 'generated' / 'trolley_printed.py')!r}, 'a').write({EDIT!r})\n"
            "del sys.modules['symmech.generated.trolley_printed']\n"
            "try:\n    importlib.import_module('symmech.generated.trolley_printed')\n"
            "except integrity.SymmechError as exc:\n    print(exc)\n")
    proc = _python(_edited_copy(tmp_path), code, tmp_path)
    assert proc.stdout == REFUSAL.format(name="trolley_printed") + "\n", proc.stderr


# A small bundled scene of each kind and a generated module its run imports (the mechanism kind imports
# none: below)
RUNS = [("grain_default", "grain_motion"), ("impact_default", "grain_impact"), ("trolley_helix", "trolley_frame"),
        ("trolley_elastic_helix", "trolley_elastic")]


@pytest.mark.parametrize("scene, name", RUNS)
def test_run_on_an_edited_module_is_one_line_exit_2(tmp_path, scene, name):
    args = ["run", str(SCENES / f"{scene}.toml"), "--out", "o", "--max-time", "60", "--quiet"]
    code = f"from symmech.cli import main\nsys.exit(main({args!r}))"
    proc = _python(_edited_copy(tmp_path, name), code, tmp_path)
    assert (proc.returncode, proc.stdout) == (2, ""), proc.stderr
    assert proc.stderr == f"symmech: error: {REFUSAL.format(name=name)}\n"
    assert not (tmp_path / "o").exists()


def test_a_mechanism_run_imports_no_generated_module(tmp_path):
    """The mechanism kind renders its scene's module in the run and imports it from a temporary file: with
    every module of the generated package edited, its run still succeeds and loads none of them."""
    args = ["run", str(SCENES / "smm_double_pendulum.toml"), "--out", "o", "--quiet", "--no-plots"]
    code = (f"from symmech.cli import main\nassert main({args!r}) == 0\n"
            "print(sorted(m for m in sys.modules if m.startswith('symmech.generated.')))")
    proc = _python(_edited_copy(tmp_path, *sorted(MODULES)), code, tmp_path)
    assert (proc.returncode, proc.stdout.splitlines()[-1]) == (0, "[]"), proc.stderr


def test_codegen_regenerates_an_edited_module(tmp_path):
    """codegen reads the files it checks without importing them: it names and rewrites an edited module."""
    folder = _edited_copy(tmp_path, "trolley_printed")
    check, write = ["codegen", "--check", "--dir", str(folder)], ["codegen", "--dir", str(folder)]
    code = f"from symmech.cli import main\nprint(main({check!r}), main({write!r}))"
    proc = _python(folder, code, tmp_path)
    assert proc.stdout.splitlines()[-1] == "1 0", proc.stderr
    assert f"  {folder / 'trolley_printed.py'}" in proc.stderr.splitlines()
    assert (folder / "trolley_printed.py").read_bytes() == (GENERATED / "trolley_printed.py").read_bytes()


def test_the_report_refuses_an_edited_mathml_twin(tmp_path):
    """What the report typesets is a generated module like the others: an edited one is refused, not shown."""
    code = ("from symmech.core.scene import SymmechError\nfrom symmech import report\n"
            "try:\n    report.derivations({'generated_modules': {'trolley_frame': ''}}, 'trolley')\n"
            "except SymmechError as exc:\n    print(exc)\n")
    proc = _python(_edited_copy(tmp_path, "trolley_frame_mathml"), code, tmp_path)
    assert proc.stdout == REFUSAL.format(name="trolley_frame_mathml") + "\n", proc.stderr
