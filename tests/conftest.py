"""Session hooks: the compiled grain engine is built once, in the background, while the other tests run.

Tests marked ``compiled_engine`` run last and first wait for that build
(:func:`symmech.grain.compiled.wait_warm`), so no test pays numba's compilation on its own; under
pytest-xdist every worker asks for the build and the build lock lets one process per machine compile.
"""
import pytest

BUILD_TIMEOUT = 1200.0  # s: the cold compile takes ~80 s on an idle 2-core machine, minutes on a busy one


def pytest_configure(config):
    config.addinivalue_line("markers", "compiled_engine: uses the compiled grain engine; ordered last, waits for "
                                       "the background build started at collection")


@pytest.hookimpl(trylast=True)  # after `-m` deselection: no build when no selected test needs it
def pytest_collection_modifyitems(session, config, items):
    marked = [item for item in items if item.get_closest_marker("compiled_engine")]
    if marked:
        from symmech.grain import compiled

        compiled.warm_in_background()
        items[:] = [item for item in items if not item.get_closest_marker("compiled_engine")] + marked


@pytest.fixture(autouse=True)
def _compiled_engine_built(request):
    if request.node.get_closest_marker("compiled_engine"):
        from symmech.grain import compiled

        if not compiled.wait_warm(BUILD_TIMEOUT):
            pytest.fail(f"the compiled grain engine was not built within {BUILD_TIMEOUT:g} s (cache: "
                        f"{compiled.cache_dir()}; `symmech warm` builds it in the foreground)")
