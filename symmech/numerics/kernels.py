"""Compiled kernels of a generated module, or the numpy reference when numba is absent.

``load("grain_impact")`` returns ``symmech.generated.grain_impact_nb`` (numba)
when numba imports, else a stand-in with the same names built on the numpy
module: ``f`` is the numpy function and ``f_scalar`` calls it and returns a
float (scalar quantities) or a float64 array of the element shape (``rhs_scalar``
and ``jac_scalar`` of a dynamics module: its ``rhs`` and ``jac``); ``f_into(...,
out)`` writes it into ``out[0]``. The twin's ``rhs``/``jac`` are the C path of
:mod:`symmech.numerics.fastcall` (nothing compiled here). Runtime
code written against ``load`` runs everywhere; only its speed differs. The
import verifies the module, as every import of ``symmech.generated`` does
(:mod:`symmech.core.integrity`).
"""
from __future__ import annotations

import functools
import importlib
from types import SimpleNamespace

from symmech.core.integrity import PACKAGE


def _scalar_twin(function):
    def twin(*args):
        value = function(*args)
        return float(value) if value.ndim == 0 else value

    twin.__name__ = f"{function.__name__}_scalar"
    twin.__doc__ = f"{function.__name__} on floats (numpy fallback: numba is not installed)."
    return twin


def _into_twin(function):
    def twin(*args):
        *inputs, out = args
        out[0] = function(*inputs)

    twin.__name__ = f"{function.__name__}_into"
    twin.__doc__ = f"{function.__name__} on floats into out[0] (numpy fallback: numba is not installed)."
    return twin


@functools.cache
def load(name: str):
    """The numba module ``<name>_nb``, or the numpy stand-in described above; SymmechError
    when the module is edited, truncated or stale. numba's cache files of its kernels are loaded under
    :func:`symmech.numerics.artifacts.guard_numba_cache`."""
    try:
        import numba  # noqa: F401  (the twin needs it; without it the numpy module stands in)
    except ImportError:
        pass
    else:
        from symmech.numerics import artifacts, fastcall

        artifacts.guard_numba_cache()  # a damaged cache file of the twin's kernels: recompiled, not an error
        twin = importlib.import_module(f"{PACKAGE}.{name}_nb")
        fastcall.install(twin)
        return twin
    reference = importlib.import_module(f"{PACKAGE}.{name}")
    # the layout of a dynamics module's rhs(t, y, p)
    names = {k: getattr(reference, k) for k in ("STATE", "PARAMS") if hasattr(reference, k)}
    for f in reference.__all__:
        names[f] = getattr(reference, f)
        names[f"{f}_scalar"] = _scalar_twin(names[f])
        names[f"{f}_into"] = _into_twin(names[f])
    return SimpleNamespace(__name__=reference.__name__, __all__=sorted(names), **names)
