"""The numba settings every compiled module of symmech uses, defined once.

``error_model="numpy"``: a float division by zero gives inf or nan as numpy does (no check and no exception
per division); ``nogil``: the engines run on threads (Dask's local scheduler). ``jit`` is kept in numba's
cache (keyed on the defining file); ``closure`` is not: a closure's cache key would hold a dispatcher with a
per-process id (:mod:`symmech.numerics.ode`, "How the right-hand side reaches the compiled code"). The
generated ``_nb`` twins spell their own decorator: they import numpy, numba and math only.
"""
import numba
import numpy as np

SETTINGS = {"error_model": "numpy", "nogil": True}

jit = numba.njit(cache=True, **SETTINGS)
closure = numba.njit(cache=False, **SETTINGS)
inline = numba.njit(cache=True, inline="always", **SETTINGS)  # typed into its caller: no call in a hot loop
with_gil = numba.njit(cache=True, error_model=SETTINGS["error_model"])  # calls back into Python (numba.objmode)

INT = np.int64  # the integer type of the compiled counters, indices and status codes
EPS = float(np.finfo(float).eps)
