"""A mechanism of the user's own: the MathML twin its run writes beside its module, which a later `symmech report`
reads instead of deriving the scene again, and trusts only intact and made for that module."""
import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from symmech.cli import main
from symmech.core import integrity
from symmech.generated import smm_double_pendulum_mathml

SCENES = Path(__file__).resolve().parents[1] / "scenes"
MODULE = "smm_my_pendulum"  # not in generated/: the run renders it


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory) -> Path:
    """Output folder of a plain `symmech run` (no report) of the double pendulum renamed."""
    folder = tmp_path_factory.mktemp("twin")
    scene = folder / "my_pendulum.toml"
    scene.write_text((SCENES / "smm_double_pendulum.toml").read_text()
                     .replace('name = "double_pendulum"', 'name = "my_pendulum"', 1))
    assert main(["run", str(scene), "--out", str(folder / "out"), "--no-plots", "--quiet"]) == 0
    return folder / "out"


@pytest.fixture
def counted(monkeypatch) -> list[str]:
    """Names of the mechanisms derived (``derive.module_spec``) from here on."""
    from symmech.smm import derive

    derived = []
    monkeypatch.setattr(derive, "module_spec", lambda m, spec=derive.module_spec: derived.append(m.name) or spec(m))
    return derived


def _summary(folder: Path) -> dict:
    return json.loads((folder / "summary.json").read_text())


def test_the_run_lists_its_module_and_the_twin_made_for_it(run_folder):
    summary = _summary(run_folder)
    assert summary["generated_module"] == f"{MODULE}.py"
    assert {f"{MODULE}.py", f"{MODULE}_mathml.py"} <= set(summary["files"])
    header, _ = integrity.split((run_folder / f"{MODULE}_mathml.py").read_text())
    assert header.key == integrity.sha256((run_folder / f"{MODULE}.py").read_text())


def test_a_later_report_reads_the_twin_as_the_derivation_would_typeset_it(run_folder, counted):
    """The derivations read from the folder equal, text for text, those derived again from the recorded scene."""
    from symmech import report

    summary = _summary(run_folder)
    read = report.derivations(summary, "smm", run_folder)
    assert counted == []
    derived = report.derivations(summary, "smm")
    assert counted == ["my_pendulum"]
    assert read == derived
    # the same matrices as the bundled pendulum's, which codegen typeset into generated/
    own = [(d.name, d.mathml) for d in read if d.module == MODULE]
    assert own == [(name, row[3]) for name, row in smm_double_pendulum_mathml.FUNCTIONS.items()]
    assert sum(mathml is not None for _, mathml in own) >= 3


def test_a_later_report_in_a_fresh_process_imports_no_sympy(run_folder, tmp_path):
    code = ("import json, sys; from pathlib import Path; from symmech import report; "
            f"out = Path({str(run_folder)!r}); "
            "shown = report.derivations(json.loads((out / 'summary.json').read_text()), 'smm', out); "
            f"print(sum(d.module == {MODULE!r} and d.mathml is not None for d in shown), 'sympy' in sys.modules)")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path, check=True)
    typeset = sum(row[3] is not None for row in smm_double_pendulum_mathml.FUNCTIONS.values())
    assert proc.stdout.split() == [str(typeset), "False"], proc.stderr


def _edit_body(twin: Path, module: Path) -> None:
    """A typeset matrix changed, the header left as written."""
    text = twin.read_text()
    assert text.count("<mo>=</mo>") >= 3
    twin.write_text(text.replace("<mo>=</mo>", "<mo>&#8800;</mo>", 1))


def _other_module(twin: Path, module: Path) -> None:
    """The module beside the twin replaced by another intact one (a comment more), the twin left intact."""
    header, body = integrity.split(module.read_text())
    module.write_text(integrity.with_header(body + "# edited\n", header.inputs, header.key))


def _stale(twin: Path, module: Path) -> None:
    header, body = integrity.split(twin.read_text())
    twin.write_text(header.text().replace(f"symmech {header.version} ", "symmech 0.0.0 ", 1) + body)


def _missing(twin: Path, module: Path) -> None:
    twin.unlink()


@pytest.mark.parametrize("damage", [_edit_body, _other_module, _stale, _missing], ids=lambda f: f.__name__[1:])
def test_a_twin_not_intact_or_not_the_modules_is_not_trusted(run_folder, tmp_path, counted, damage):
    """The report derives the scene again, and shows what that derivation typesets, not the twin."""
    from symmech import report

    folder = tmp_path / "out"
    shutil.copytree(run_folder, folder)
    twin, module = folder / f"{MODULE}_mathml.py", folder / f"{MODULE}.py"
    damage(twin, module)
    summary = _summary(folder)
    shown = report.derivations(summary, "smm", folder)
    assert counted == ["my_pendulum"]
    assert shown == report.derivations(_summary(run_folder), "smm", run_folder)
    assert main(["report", str(folder)]) == 0
    page = (folder / "report.html").read_text()
    assert "&#8800;" not in page and all(d.mathml in page for d in shown if d.module == MODULE)
