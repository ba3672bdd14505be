"""The first step of a solve (scipy's ``select_initial_step``, Hairer, Norsett & Wanner II.4), in numba."""
import math

import numpy as np

from symmech.numerics.jit import closure


def make(rhs):
    """``first_step(t, y, f, t_bound, args, rtol, atol, power)`` of the jitted ``rhs(t, y, args, out)``: the
    first step [units of t] from (t, y), f = rhs there, to t_bound; power = 1 / (order of the error estimator
    + 1); rtol a float, atol (n,) [units of y]. A closure, compiled on first call (:mod:`symmech.numerics.ode`)."""

    @closure
    def first_step(t, y, f, t_bound, args, rtol, atol, power):
        """scipy's ``select_initial_step``; power = 1 / (order of the error estimator + 1)."""
        span = abs(t_bound - t)
        if span == 0.0:
            return 0.0
        scale = atol + np.abs(y) * rtol
        d0 = math.sqrt(np.mean((y / scale) ** 2))
        d1 = math.sqrt(np.mean((f / scale) ** 2))
        h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
        h0 = min(h0, span)
        f1 = np.empty(y.size)
        rhs(t + h0, y + h0 * f, args, f1)
        d2 = math.sqrt(np.mean(((f1 - f) / scale) ** 2)) / h0
        h1 = max(1e-6, h0 * 1e-3) if d1 <= 1e-15 and d2 <= 1e-15 else (0.01 / max(d1, d2)) ** power
        return min(100 * h0, h1, span)

    return first_step
