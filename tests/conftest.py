"""Session hooks: the compiled engines are built once, in the background, while the other tests run.

Tests marked ``compiled_engine`` (the grain engine) or ``compiled_elastic`` (the elastic trolley engine) are
in the slow tier (each build is 1-2 CPU-minutes, the default suite's budget is 3 minutes); they run last and
first wait for that engine's build (``ENGINE.wait_warm`` of :mod:`symmech.grain.motion_engine.driver`,
:mod:`symmech.trolley.elastic.compiled`), so no test pays numba's compilation on its own; under pytest-xdist
every worker asks for the build and the build lock lets one process per machine compile. Runs inside the
tests start no builder (``SYMMECH_BACKGROUND_BUILD=0``): a grain or elastic scene on ``auto`` with a cold
cache answers on the Python engine, as a first run does.

The elastic trolley's default engine (``auto``) is the compiled one once built; tests not marked ``compiled_elastic`` run it on
the Python engine (its reference, which they test; ``engine_reason`` says so), so that no unmarked test
compiles it in each xdist worker. tests/test_elastic_compiled.py proves the compiled engine against it.

Under mutmut (tools/mutate.py, ``MUTANT_UNDER_TEST`` set) no builder process is started: mutmut reaps every child
of its main process as one of its workers (a builder's exit stops the run with a KeyError), and a builder would
compile the unmutated package. A marked test compiles the mutated copy in the foreground (once, in mutmut's main
process, whose forks inherit it); an unmarked grain scene on ``engine = "auto"`` runs the Python loop there, even
once a marked test has built the mutated copy's compiled engine (the motion shard mutates the Python loop).
"""
import importlib
import os

import pytest

BUILD_TIMEOUT = 1200.0  # s: a cold compile takes ~1-2 min on an idle 2-core machine, minutes on a busy one
ENGINES = {"compiled_engine": "symmech.grain.motion_engine.driver", "compiled_elastic": "symmech.trolley.elastic.compiled"}


def pytest_configure(config):
    config.addinivalue_line("markers", "compiled_engine: uses the compiled grain engine; ordered last, waits for "
                                       "the background build started at collection")
    config.addinivalue_line("markers", "compiled_elastic: uses the compiled elastic trolley engine; ordered last, "
                                       "waits for the background build started at collection")


def _marked(item) -> list:
    return [marker for marker in ENGINES if item.get_closest_marker(marker)]


@pytest.hookimpl(trylast=True)  # after `-m` deselection: no build when no selected test needs it
def pytest_collection_modifyitems(session, config, items):
    needed = {marker for item in items for marker in _marked(item)}
    for marker in sorted(needed):
        if not (_under_mutmut() or config.option.collectonly):
            importlib.import_module(ENGINES[marker]).ENGINE.warm_in_background()
    # no test run starts a builder of its own (the default tier builds no compiled engine at all); the tests
    # of the builder itself take this out of their environment
    os.environ["SYMMECH_BACKGROUND_BUILD"] = "0"
    if needed:
        items[:] = [item for item in items if not _marked(item)] + [item for item in items if _marked(item)]
    if getattr(config.option, "loadgroup", False):
        _keep_xdist_groups(items)


def _keep_xdist_groups(items) -> None:
    """Give each ``xdist_group`` test the ``@group`` suffix ``--dist loadgroup`` schedules by, where xdist left none.

    pytest 9.2 holds a node's id in ``_id``; pytest-xdist 3.8 still writes the suffix into ``_nodeid``, which
    nothing reads any more, so every group was spread over the workers and each worker derived, compiled and
    ran the groups' module fixtures again (an open xdist bug: loadgroup with pytest's structured node ids).
    The suffix is xdist's own: the group names, sorted, joined by ``_``."""
    for item in items:
        names = sorted({str(mark.args[0] if mark.args else mark.kwargs.get("name", "default"))
                        for mark in item.iter_markers("xdist_group")})
        if names and "@" not in item.nodeid.rpartition("]")[2] and hasattr(item, "_id"):
            item._id = type(item._id).parse(f"{item.nodeid}@{'_'.join(names)}")


@pytest.fixture(autouse=True)
def _elastic_reference_engine(request, monkeypatch):
    if not request.node.get_closest_marker("compiled_elastic"):
        from symmech.trolley.elastic import scene as elastic_scene

        monkeypatch.setattr(elastic_scene, "engine", lambda setup, runs=1: ("python", "tests: the reference engine "
                                                                                      "(tests/conftest.py)"))


def _under_mutmut() -> bool:
    return "MUTANT_UNDER_TEST" in os.environ


@pytest.fixture(autouse=True)
def _python_loop_under_mutmut(request, monkeypatch):
    if _under_mutmut() and not _marked(request.node):  # (no builder starts: SYMMECH_BACKGROUND_BUILD=0)
        from symmech.grain import motion_scene

        choose = motion_scene.choose_engine
        monkeypatch.setattr(motion_scene, "choose_engine", lambda sc, num=None, duration=None: (
            ("python", "tests under mutmut (tests/conftest.py)") if (num or sc.numerics).engine == "auto"
            else choose(sc, num, duration)))


@pytest.fixture(autouse=True)
def _compiled_engine_built(request):
    for marker in _marked(request.node):
        engine = importlib.import_module(ENGINES[marker]).ENGINE
        if _under_mutmut():
            engine.warm()
        elif not engine.wait_warm(BUILD_TIMEOUT):
            pytest.fail(f"the {ENGINES[marker]} engine was not built within {BUILD_TIMEOUT:g} s (cache: "
                        f"{engine.cache_dir()}; `symmech warm` builds it in the foreground)")
