"""Every bundled scene's outputs follow the contract of docs/outputs.md (JSON Schema
``symmech/core/output_schema.json``, strict JSON, finite numbers, CSV headers with units,
exactly the listed files), for ``symmech run`` and ``symmech bench precision``.

Runs of a few seconds are in the default suite; the other scenes' runs are checked
against the same contract by the wheel test (tests/test_install.py), their precision
studies here as slow tests (``.ci/run`` runs both). Kinds not yet on the registry are
left to their legacy tests.
"""
from __future__ import annotations

import tomllib

import pytest
from outcontract import assert_valid_output

from symmech.cli import main
from symmech.core import registry
from symmech.core.scene import scenes_folder

QUICK = {"impact_default", "smm_double_pendulum", "smm_excavator", "smm_rotor_boom", "smm_spatial_boom",
         "trolley_helix", "trolley_elastic_helix"}
QUICK_PRECISION = {"impact_default", "smm_double_pendulum"}
# run shortened in the default suite (the contract does not depend on the length of the run; the full
# scene runs in tests/test_trolley_elastic_kind.py and, written out, in the wheel test)
SHORTENED = {"trolley_elastic_helix": ("steps = 1000 ", "steps = 100 ")}
# precision studies of elastic scenes on the compiled elastic engine, as a warm install runs them (the slow
# tier builds it once; on the Python reference engine each study took ~95 s)
COMPILED_PRECISION = {"trolley_elastic_helix", "trolley_elastic_sweep"}
# their study over a tenth of the ride (its reference is the Python engine's Radau at rtol 1e-11: ~80 s of the
# whole 3 s ride); the contract does not depend on the length of the ride
SHORTENED_PRECISION = {"trolley_elastic_helix": (("t_end = 3.0", "t_end = 0.3"), ("steps = 1000 ", "steps = 100 ")),
                       "trolley_elastic_sweep": (("t_end = 2.0", "t_end = 0.2"), ("steps = 667 ", "steps = 67 "))}
# bundled scenes a precision study refuses, and the one line it gives (the rigid trolley's study varies the
# local-curvature integration, which the steady-speed sweep leaves off)
REFUSED_PRECISION = {"trolley_speed_sweep": "bench precision needs effects.local_curvature = true"}


def bundled(having=lambda kind: True, quick=QUICK, compiled=frozenset()):
    params = []
    for path in sorted(scenes_folder().glob("*.toml")):
        kind = registry.kinds().get(tomllib.loads(path.read_text())["kind"])
        if kind is not None and having(kind):
            marks = () if path.stem in quick else (pytest.mark.slow,)
            marks += (pytest.mark.compiled_elastic,) if path.stem in compiled else ()
            params.append(pytest.param(path, id=path.stem, marks=marks))
    return params


@pytest.mark.parametrize("scene", [p for p in bundled() if not p.marks])
def test_run_output_contract(scene, tmp_path, capsys):
    if scene.stem in SHORTENED:
        text = scene.read_text()
        assert SHORTENED[scene.stem][0] in text
        scene = tmp_path / scene.name
        scene.write_text(text.replace(*SHORTENED[scene.stem]))
    assert main(["run", str(scene), "--out", str(tmp_path / "out"), "--quiet"]) == 0, capsys.readouterr().err
    summary = assert_valid_output(tmp_path / "out")
    assert summary["scene_file"] == str(scene)
    assert summary["scene"]["kind"] == tomllib.loads(scene.read_text())["kind"]


@pytest.mark.parametrize("scene", bundled(lambda kind: kind.precision is not None, QUICK_PRECISION,
                                          COMPILED_PRECISION))
def test_bench_precision_works_on_every_bundled_scene(scene, tmp_path, capsys):
    if scene.stem in SHORTENED_PRECISION:
        text = scene.read_text()
        for old, new in SHORTENED_PRECISION[scene.stem]:
            assert old in text
            text = text.replace(old, new)
        scene = tmp_path / scene.name
        scene.write_text(text)
    code = main(["bench", "precision", str(scene), "--out", str(tmp_path / "p"), "--quiet"])
    if scene.stem in REFUSED_PRECISION:
        err = capsys.readouterr().err
        assert code == 2 and err.count("\n") == 1 and REFUSED_PRECISION[scene.stem] in err, err
        return
    assert code == 0, capsys.readouterr().err
    summary = assert_valid_output(tmp_path / "p")
    assert "precision" in summary["timing_s"] and "run" not in summary["timing_s"]
