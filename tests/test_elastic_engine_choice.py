"""The elastic model's ``auto`` engine: the compiled engine when numba's cache holds it, else the
Python engine (the reference) while the compiled one is built in the background for the next run, and a
first compile in the foreground only when the Python engine's estimate exceeds it. No numba compile here:
the cache state is stubbed."""
import copy
import tomllib

import pytest

from symmech.core import pipeline, sample, scene
from symmech.trolley.elastic import compiled as ec
from symmech.trolley.elastic import scene as elastic_scene
from symmech.trolley.elastic.scene import engine as choose  # the real choice (tests/conftest.py patches the module's)

BUNDLED = tomllib.loads((scene.scenes_folder() / "trolley_elastic_helix.toml").read_text(encoding="utf-8"))


def loaded(engine="auto", method="Radau", t_end=3.0, steps=1000):
    doc = copy.deepcopy(BUNDLED)
    doc["time"] = {"t_end": t_end, "steps": steps}
    doc["elastic"]["numerics"].update(engine=engine, method=method)
    return pipeline.load(doc)


@pytest.fixture
def cold(monkeypatch):
    """numba's cache without the compiled engine; the background builders started (none really)."""
    started = []
    monkeypatch.delenv("SYMMECH_BACKGROUND_BUILD", raising=False)  # tests/conftest.py's
    monkeypatch.setattr(ec.ENGINE, "cold", lambda: True)
    monkeypatch.setattr(ec.ENGINE, "warm_in_background", lambda: started.append("builder") or True)
    monkeypatch.setattr(ec.ENGINE, "warm", lambda wait=True, say=None: pytest.fail("no foreground compile here"))
    return started


def test_auto_takes_the_built_engine(monkeypatch):
    monkeypatch.setattr(ec.ENGINE, "cold", lambda: False)
    assert choose(loaded().setup.elastic) == ("compiled", "auto: the compiled engine is built (numba's cache)")


def test_auto_on_a_cold_cache_answers_with_the_python_engine_unless_compiling_pays(cold):
    setup = loaded().setup.elastic  # 1000 steps: ~100 s on the Python engine against a ~130 s compile
    name, why = choose(setup)
    assert name == "python" and why.startswith("auto: the compiled engine is not built yet; building it")
    assert (elastic_scene.SECONDS_PER_STEP["python"] * 1000 < ec.COLD_COMPILE_SECONDS
            < elastic_scene.SECONDS_PER_STEP["python"] * 1000 * 2)
    assert choose(setup, runs=2)[0] == "compiled"  # a sweep of two such points: compiling first pays
    assert choose(loaded(steps=20000).setup.elastic) == (
        "compiled", "auto: the Python engine would take ~2e+03 s, longer than compiling first")
    assert choose(loaded("compiled").setup.elastic) == ("compiled", 'numerics.engine = "compiled"')
    assert choose(loaded("python").setup.elastic) == ("python", 'numerics.engine = "python"')
    assert choose(loaded(method="BDF").setup.elastic)[0] == "python"
    assert cold == []  # choosing starts nothing


def test_the_cold_reason_says_when_no_builder_will_run(cold, monkeypatch):
    monkeypatch.setenv("SYMMECH_BACKGROUND_BUILD", "0")  # the real warm_in_background would start none
    assert choose(loaded().setup.elastic) == ("python", "auto: the compiled engine is not built yet; no background "
                                              "build (SYMMECH_BACKGROUND_BUILD=0) (`symmech warm --engine elastic` "
                                              "builds it now)")


def test_a_cold_auto_run_runs_the_python_engine_and_starts_the_builder(cold, monkeypatch):
    monkeypatch.setattr(elastic_scene, "engine", choose)
    out = elastic_scene.simulate(loaded(t_end=0.03, steps=10).setup.elastic)
    assert out["engine"] == "python" and out["engine_reason"].startswith("auto: the compiled engine is not built")
    assert cold == ["builder"]
    cold.clear()
    elastic_scene.simulate(loaded("python", t_end=0.03, steps=10).setup.elastic)
    assert cold == []  # an explicit engine starts no builder
    monkeypatch.setattr(elastic_scene, "engine", lambda setup, runs=1: ("python", "another reason"))
    elastic_scene.simulate(loaded(t_end=0.03, steps=10).setup.elastic)
    assert cold == []  # nor does `auto` when the Python engine runs for another reason (tests/conftest.py's)


def test_the_estimate_names_the_engine_and_what_a_first_run_costs(cold, monkeypatch):
    monkeypatch.setattr(elastic_scene, "engine", choose)
    monkeypatch.setattr(sample, "slowdown", lambda: 1.0)  # the compile as on an idle core
    auto, compiled = loaded().estimate(), loaded("compiled").estimate()
    assert "the elastic model (python engine; auto: the compiled engine is not built yet" in auto.what
    assert "compiling the elastic engine once" in compiled.what and "symmech warm" in compiled.what
    steps = 1000 * (elastic_scene.SECONDS_PER_STEP["compiled"] - elastic_scene.SECONDS_PER_STEP["python"])
    assert compiled.seconds - auto.seconds == pytest.approx(ec.COLD_COMPILE_SECONDS + steps)
