"""DOP853 in numba (scipy's ``RungeKutta._step_impl`` and ``DOP853._dense_output_impl``): :func:`steppers` of a
right-hand side and the interpolant :func:`dop_dense_at`, on the tableau of :mod:`symmech.numerics.dop853_tableau`
(Hairer's ``dop853.f``, bit-equal to scipy's)."""
from __future__ import annotations

import math

import numpy as np

from symmech.numerics.dop853_tableau import A, B, C, D, E3, E5, EXPONENT, EXTENDED, POWER, STAGES
from symmech.numerics.jit import closure, inline, jit


@inline
def combine(out, y, K, a, s, h):
    """out = y + h sum_j<s a_j K_j, element by element (no temporaries: this is the hot loop)."""
    for i in range(K.shape[1]):
        acc = 0.0
        for j in range(s):
            acc += a[j] * K[j, i]
        out[i] = y[i] + acc * h


@jit
def dop_dense_at(t, t_old, h, y_old, F):
    """The DOP853 interpolant (n,) at t (``Dop853DenseOutput``); F (7 n,) the coefficients row by row."""
    x = (t - t_old) / h
    n = y_old.size
    y = np.empty(n)
    for i in range(n):
        acc = 0.0
        for r in range(POWER):
            acc += F[(POWER - 1 - r) * n + i]
            acc *= x if r % 2 == 0 else 1 - x
        y[i] = acc + y_old[i]
    return y


def steppers(rhs) -> tuple:
    """(dop_advance, dop_dense) of the jitted ``rhs(t, y, args, out)``, compiled on first call (closures:
    :mod:`symmech.numerics.ode`):

    - ``dop_advance(t, y, f, h_abs, t_bound, args, rtol, atol, K)``: one accepted step, (t_new, y_new, next
      h_abs, ok); K (16, n) the stages, K[12] f at the new point; rtol a float, atol (n,) [units of y];
    - ``dop_dense(t_old, h, y_old, y_new, args, K)``: the step's interpolant F (7, n) for :func:`dop_dense_at`."""

    @closure
    def dop_advance(t, y, f, h_abs, t_bound, args, rtol, atol, K):
        """One accepted DOP853 step (scipy's ``RungeKutta._step_impl``)."""
        n = y.size
        min_step = 10 * abs(np.nextafter(t, np.inf) - t)
        h_abs = max(h_abs, min_step)
        rejected = False
        yi = np.empty(n)
        y_new = np.empty(n)
        while True:
            if h_abs < min_step:
                return t, y, h_abs, False
            t_new = min(t + h_abs, t_bound)
            h = t_new - t
            h_abs = abs(h)
            K[0] = f
            for s in range(1, STAGES):
                combine(yi, y, K, A[s], s, h)
                rhs(t + C[s] * h, yi, args, K[s])
            combine(y_new, y, K, B, STAGES, h)
            rhs(t + h, y_new, args, K[STAGES])
            n5 = n3 = 0.0
            for i in range(n):
                e5 = e3 = 0.0
                for j in range(STAGES + 1):
                    e5 += E5[j] * K[j, i]
                    e3 += E3[j] * K[j, i]
                scale = atol[i] + max(abs(y[i]), abs(y_new[i])) * rtol
                n5 += (e5 / scale) ** 2
                n3 += (e3 / scale) ** 2
            err = 0.0 if n5 == 0 and n3 == 0 else abs(h) * n5 / math.sqrt((n5 + 0.01 * n3) * n)
            if err < 1:
                factor = 10.0 if err == 0 else min(10.0, 0.9 * err ** EXPONENT)
                if rejected:
                    factor = min(1.0, factor)
                return t_new, y_new, h_abs * factor, True
            h_abs *= max(0.2, 0.9 * err ** EXPONENT)
            rejected = True

    @closure
    def dop_dense(t_old, h, y_old, y_new, args, K):
        """Interpolant coefficients F (7, n) of the last step (scipy's ``DOP853._dense_output_impl``)."""
        n = y_old.size
        yi = np.empty(n)
        for s in range(STAGES + 1, EXTENDED):
            combine(yi, y_old, K, A[s], s, h)
            rhs(t_old + C[s] * h, yi, args, K[s])
        F = np.empty((POWER, n))
        zero = np.zeros(n)
        for i in range(n):
            dy = y_new[i] - y_old[i]
            F[0, i] = dy
            F[1, i] = h * K[0, i] - dy
            F[2, i] = 2 * dy - h * (K[STAGES, i] + K[0, i])
        for r in range(POWER - 3):
            combine(F[3 + r], zero, K, D[r], EXTENDED, h)
        return F

    return dop_advance, dop_dense
