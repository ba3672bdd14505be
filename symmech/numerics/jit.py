"""The numba settings every compiled module of symmech uses, defined once.

``error_model="numpy"``: a float division by zero gives inf or nan as numpy does (no check and no exception
per division); ``nogil``: the engines run on threads (Dask's local scheduler). ``jit`` is kept in numba's
cache (keyed on the defining file); ``closure`` is not: a closure's cache key would hold a dispatcher with a
per-process id (:mod:`symmech.numerics.ode`, "How the right-hand side reaches the compiled code"). The
generated ``_nb`` twins spell their own decorator: they import numpy, numba and math only.

``inline`` and ``inline_closure`` type a function into its caller (numba IR inlining) instead of compiling it on its
own. Besides saving a call in a hot loop, that is what a function with one caller wants: numba links each compiled
callee's whole module, its own callees included, into its caller's and optimises and generates machine code for all of
it again, so every level of a call tree pays for the levels under it (benchmarks/README.md, "Where the compile
goes"). The results stay bit for bit those of the call (the default scene's, compared).
"""
import numba
import numpy as np

SETTINGS = {"error_model": "numpy", "nogil": True}

jit = numba.njit(cache=True, **SETTINGS)
closure = numba.njit(cache=False, **SETTINGS)
inline = numba.njit(cache=True, inline="always", **SETTINGS)  # typed into its caller (see above)
inline_closure = numba.njit(cache=False, inline="always", **SETTINGS)
with_gil = numba.njit(cache=True, error_model=SETTINGS["error_model"])  # calls back into Python (numba.objmode)

INT = np.int64  # the integer type of the compiled counters, indices and status codes
EPS = float(np.finfo(float).eps)
