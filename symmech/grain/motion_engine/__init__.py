"""The grain's compiled engine, registered (:mod:`symmech.core.engines`): the accurate-mode event loop in
numba (:mod:`symmech.grain.motion_engine.driver`), built ahead of time where a C compiler is available."""
from symmech.core import engines

ROLE = "engine"  # found by symmech.core.discovery

engines.register(engines.Engine(
    "grain", "the grain's accurate-mode event loop (numba; built ahead of time with a C compiler)",
    "symmech.grain.motion_engine.driver"))
