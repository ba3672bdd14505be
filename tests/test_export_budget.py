"""`symmech export` runs the scene natively (its main table, the FMU's default experiment): that run is estimated
before any work and held to `--max-time` as `symmech run`'s is, so an export never runs unbounded."""
from __future__ import annotations

import shutil

import pytest

from symmech.cli import main
from symmech.core import pipeline
from symmech.core.context import Context
from symmech.core.scene import SymmechError, scenes_folder
from symmech.export import command
from symmech.grain import motion_scene

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="needs a C compiler")


def _long_grain(tmp_path, duration: float, engine: str = "auto"):
    """The bundled grain scene over ``duration`` [s] of physical time, on ``engine``."""
    text = (scenes_folder() / "grain_default.toml").read_text()
    text = text.replace("duration = 2.0", f"duration = {duration!r}")
    text = text.replace('mode = "accurate"', f'mode = "accurate"\nengine = "{engine}"')
    path = tmp_path / "long.toml"
    path.write_text(text)
    return path


@pytest.mark.parametrize("what, out", [("fmu", "x.fmu"), ("c", "x_c")])
def test_an_export_estimated_over_its_budget_is_refused_before_the_native_run(tmp_path, capsys, monkeypatch, what,
                                                                              out):
    """2000 s of the grain (~1e5 impacts: minutes on either engine) against --max-time 5: one line naming the
    estimate and the budget, exit 2, no native run started, nothing written."""
    def native_run(*args, **kwargs):
        raise AssertionError("the native run started")

    monkeypatch.setattr(motion_scene, "simulate", native_run)
    scene = _long_grain(tmp_path, 2000.0)
    assert main(["export", what, str(scene), "--out", str(tmp_path / out), "--max-time", "5"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "estimated run time" in err and "exceeds --max-time 5 s" in err
    assert not (tmp_path / out).exists()


def test_an_export_whose_native_run_overruns_its_budget_stops_there(tmp_path, monkeypatch):
    """With no estimate to refuse it (a kind without one), the native run itself is stopped at the budget: the
    run's own message, well before the 2000 s of physical time (the Python engine: ~40 min), nothing written."""
    monkeypatch.setattr(pipeline.Scene, "estimate", lambda self, *args, **kwargs: None)
    scene = _long_grain(tmp_path, 2000.0, engine="python")
    ctx = Context(quiet=True, max_time=1.0)
    with pytest.raises(SymmechError, match=r"over the time budget --max-time 1 s \(grain"):
        command.export("c", scene, tmp_path / "x_c", ctx=ctx)
    assert ctx.elapsed() < 30.0  # stopped at the budget, not run to the end
    assert not (tmp_path / "x_c").exists()
