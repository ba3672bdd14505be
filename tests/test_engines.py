"""Compiled engines register themselves (symmech.core.engines): discovery, the protocol every engine
provides, and a stand-in engine that appears in ``symmech warm`` without any edit of the CLI."""
import dataclasses
import sys

import pytest

from symmech import cli
from symmech.core import engines, sample
from symmech.numerics import build
from symmech.core.layout import Bundle, Layout

STANDIN_DECLARATION = '''
from symmech.core import engines

engines.register(engines.Engine("standin", "a stand-in engine of the tests", "standin_implementation"))
'''
STANDIN_IMPLEMENTATION = '''
from dataclasses import dataclass

from symmech.core.layout import Field, Layout

CALLS = []
LAYOUTS = (Layout("StandinParams", (Field("k", "N/m", "a stiffness"), Field("x", "m", "a position", (2,)))),)


class Builder:
    seconds = 12.0

    def warm(self, wait=True, say=None, ahead=False):
        CALLS.append(("warm", wait, ahead))
        return True

    def ahead_of_time(self):
        return None

    def needs_compile(self):
        return True

    def entries(self):
        return {"entry": ()}

    def cache_dir(self):
        return "/nowhere"


ENGINE = Builder()


@dataclass(frozen=True)
class Run:
    x: float


@dataclass(frozen=True)
class Population:
    xs: list


class Runner:
    def simulate(self, inputs):
        return 2 * inputs.x

    def simulate_many(self, inputs):
        return [3 * x for x in inputs.xs]


RUNNER = Runner()
'''


@pytest.fixture
def standin(tmp_path, monkeypatch):
    """A stand-in engine: a declaring module that registers itself when imported, and its implementation."""
    (tmp_path / "standin_engine.py").write_text(STANDIN_DECLARATION)
    (tmp_path / "standin_implementation.py").write_text(STANDIN_IMPLEMENTATION)
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(engines, "_ENGINES", dict(engines.engines()))  # the real ones, and it only here
    for name in ("standin_engine", "standin_implementation"):
        monkeypatch.delitem(sys.modules, name, raising=False)
    __import__("standin_engine")
    return engines.get("standin").module()


def test_the_engines_of_the_papers_are_discovered_and_provide_the_protocol():
    found = engines.engines()
    assert set(found) == {"grain", "elastic"}
    for name, engine in found.items():
        module = engine.module()
        assert isinstance(module.ENGINE, build.Engine) and module.ENGINE.name == name
        assert engine.builder() is module.ENGINE and engine.runner() is module.RUNNER
        assert dataclasses.is_dataclass(module.Run) and module.Run.__dataclass_params__.frozen
        assert module.LAYOUTS and all(isinstance(x, (Layout, Bundle)) for x in module.LAYOUTS)


def test_describe_lists_every_declared_field_with_its_offset_and_unit():
    text = engines.get("grain").describe()
    assert text.startswith("grain: ")
    assert "\n       3 mass [kg] mass\n" in text and "\n      30 period [s] " in text
    text = engines.get("elastic").describe()
    assert "    int64(N+1) ptr [] " in text and "       0 load [m/s^2] " in text


def test_an_engine_unknown_to_the_registry_is_a_key_error_naming_the_known_ones():
    with pytest.raises(KeyError, match="no compiled engine 'steam'; registered: elastic, grain"):
        engines.get("steam")


def test_a_registered_stand_in_engine_appears_in_symmech_warm_without_editing_the_cli(standin, capsys):
    with pytest.raises(SystemExit) as done:
        cli.main(["warm", "--help"])
    assert done.value.code == 0
    help_text = " ".join(capsys.readouterr().out.split())
    assert "--engine NAME which compiled engine to build: all, elastic, grain, standin" in help_text

    assert cli.main(["warm", "--engine", "standin"]) == 0
    assert standin.CALLS == [("warm", True, True)]  # the ahead-of-time build asked for, as for every engine
    assert capsys.readouterr().out.startswith("compiled standin engine ready in ")

    with pytest.raises(SystemExit) as done:
        cli.main(["warm", "--engine", "steam"])
    assert done.value.code == 2
    assert "invalid choice: 'steam' (choose from 'all', 'elastic', 'grain', 'standin')" in capsys.readouterr().err


def test_the_protocol_of_a_stand_in_engine(standin, monkeypatch):
    engine = engines.get("standin")
    assert engine.run(standin.Run(21)) == 42
    with pytest.raises(TypeError, match="engine 'standin' runs standin_implementation.Run, not builtins.int"):
        engine.run(21)  # the inputs name their engine
    assert engine.run_many(standin.Population([1, 2])) == [3, 6]
    with pytest.raises(TypeError, match="runs standin_implementation.Population, not standin_implementation.Run"):
        engine.run_many(standin.Run(21))  # a population's inputs are its own type
    assert engine.load() == {"entry": ()}  # no ahead-of-time build: numba's entries
    monkeypatch.setattr(sample, "slowdown", lambda: 3.0)  # a third of a core now: the 12 s compile takes 36 s
    assert engine.compile_seconds() == 36.0
    standin.ENGINE.needs_compile = lambda: False
    assert engine.compile_seconds() == 0.0
    assert "standin: a stand-in engine of the tests\n  StandinParams\n       0 k [N/m] a stiffness\n       1 x [m] " \
        in engine.describe()


def test_registering_another_engine_under_a_taken_name_is_refused(standin):
    with pytest.raises(ValueError, match="'standin' registered twice"):
        engines.register(engines.Engine("standin", "another", "elsewhere"))


def test_the_cli_names_no_engine():
    """The CLI reads the registry: no engine module or name in cli.py."""
    text = cli.__loader__.get_source(cli.__name__)
    for name in ("compiled", "elastic", "grain"):
        assert f"import {name}" not in text and f'"{name}"' not in text
