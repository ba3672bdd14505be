"""The elastic trolley's compiled engine, registered (:mod:`symmech.core.engines`): the elastic body's
assembly in numba, integrated by Radau IIA (:mod:`symmech.trolley.elastic.compiled`)."""
from symmech.core import engines

ROLE = "engine"  # found by symmech.core.discovery

engines.register(engines.Engine(
    "elastic", "the elastic trolley's assembly and Radau IIA solve (numba)", "symmech.trolley.elastic.compiled"))
