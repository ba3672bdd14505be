"""The usual files: version, licence, citation, changelog."""
import re
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from symmech.cli import main
from symmech.core.scene import tomllib

ROOT = Path(__file__).resolve().parents[1]


def test_version_matches_pyproject(capsys):
    declared = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    try:
        main(["--version"])
    except SystemExit as exc:
        assert exc.code == 0
    assert capsys.readouterr().out.strip() == f"symmech {declared}"


def test_version_from_the_installed_command():
    out = subprocess.run([sys.executable, "-m", "symmech", "--version"], capture_output=True, text=True,
                         check=True).stdout
    assert re.fullmatch(r"symmech \d+\.\d+\.\d+\n", out)


def test_licence_is_mit_and_declared():
    assert (ROOT / "LICENSE").read_text().startswith("MIT License")
    assert tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["license"] in ("MIT", {"text": "MIT"})


def test_citation_names_software_and_three_papers():
    cff = yaml.safe_load((ROOT / "CITATION.cff").read_text())
    declared = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    assert cff["cff-version"] == "1.2.0" and cff["type"] == "software" and cff["version"] == declared
    refs = cff["references"]
    assert len(refs) == 3 and all(r["title"] and r["authors"] for r in refs)
    families = {a["family-names"] for r in refs for a in r["authors"]}
    assert {"Лукьяненко", "Gnezdilov", "Russkikh", "Поминов"} <= families


def test_changelog_covers_every_resolved_issue():
    text = (ROOT / "CHANGELOG.md").read_text()
    for issue in (2, 3, 4, 5, 12):
        assert f"### Issue {issue} " in text


@pytest.mark.xdist_group("project_files")
def test_a_grouped_test_carries_its_group_to_the_scheduler(request):
    """Under ``--dist loadgroup`` (pyproject's addopts) a test's id ends in ``@group``: the scheduler keeps a group
    in one worker by that suffix alone (tests/conftest.py writes it where pytest-xdist could not)."""
    if not getattr(request.config.option, "loadgroup", False):
        pytest.skip("not an xdist worker under --dist loadgroup")
    assert request.node.nodeid.endswith("::test_a_grouped_test_carries_its_group_to_the_scheduler@project_files")
