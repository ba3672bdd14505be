"""Radau IIA of order 5 with its dense output (scipy's ``solve_ivp(method="Radau")``), in numba: the constants
(scipy's ``_ivp/radau.py``, written out: no scipy import), the simplified Newton iteration on the real and
complex split of the tableau, the step-size control and :func:`steppers` of a right-hand side with its
Jacobian, the interpolant :func:`radau_dense_at` and the solver state between steps (layout ``RADAU_STATE`` of ``st``)."""
import math

import numpy as np

from symmech.core.layout import Field, Layout
from symmech.numerics import first_step as initial
from symmech.numerics import radau_tableau as tab
from symmech.numerics.jit import EPS, closure, inline, inline_closure, jit
from symmech.numerics.linalg import lu, lu_solve, solve_in_place

# Radau IIA of order 5 (scipy's ``_ivp/radau.py``, :mod:`symmech.numerics.radau_tableau`, which the C export reads too)
RADAU_C, RADAU_E, RADAU_T, RADAU_TI, RADAU_PT = tab.C, tab.E, tab.T, tab.TI, tab.PT
MU_REAL, MU_COMPLEX = tab.MU_REAL, tab.MU_COMPLEX
NEWTON_MAXITER, RADAU_MIN_FACTOR, RADAU_MAX_FACTOR = tab.NEWTON_MAXITER, tab.MIN_FACTOR, tab.MAX_FACTOR
RADAU_POWER = tab.POWER
# Solver state between the steps of one solve (scipy's ``Radau`` attributes), read as ``st[ST_AT.h]``.
RADAU_STATE = Layout("RadauState", (
    Field("h", "s", "length of the next step"),
    Field("h_old", "s", "length of the previous step (-1: none)"),
    Field("err_old", "1", "error norm of the previous step (-1: none)"),
    Field("jac_current", "1", "1: the Jacobian is current"),
    Field("lu_valid", "1", "1: the LU factors are valid"),
    Field("t_old", "s", "start of the last step (its interpolant)"),
    Field("h_last", "s", "length of the last step (0: none yet)"),
))
ST_AT, N_RADAU = RADAU_STATE.slots, RADAU_STATE.size


@inline
def rms(x, scale):
    """scipy's ``norm(x / scale)``: root mean square of x (..., n) scaled by scale (n,)."""
    acc = 0.0
    flat = x.reshape(-1)
    n = scale.size
    for i in range(flat.size):
        acc += (flat[i] / scale[i % n]) ** 2
    return math.sqrt(acc / flat.size)


@jit
def mix(A, Z):
    """A @ Z for a small A (k, 3) and Z (3, n), by loops (no BLAS call for 3 x 13)."""
    out = np.empty((A.shape[0], Z.shape[1]))
    mix_into(A, Z, out)
    return out


@inline
def mix_into(A, Z, out):
    """:func:`mix` into out (k, n): the Newton iteration's products without an array made per iteration."""
    out[:] = 0.0
    for r in range(A.shape[0]):
        for j in range(3):
            for i in range(Z.shape[1]):
                out[r, i] += A[r, j] * Z[j, i]


@jit
def factor(h, J, LUr, pr, LUc, pc):
    """LU factors of MU_REAL / h - J and MU_COMPLEX / h - J into LUr, pr, LUc, pc."""
    n = J.shape[0]
    for i in range(n):
        for j in range(n):
            LUr[i, j] = (MU_REAL / h if i == j else 0.0) - J[i, j]
            LUc[i, j] = (MU_COMPLEX / h if i == j else 0.0) - J[i, j]
    lu(LUr, pr)
    lu(LUc, pc)


@inline
def _finite(F):
    """Whether every entry of F (3, n) is finite (np.all(np.isfinite(F)) without its array)."""
    for i in range(F.shape[0]):
        for j in range(F.shape[1]):
            if not math.isfinite(F[i, j]):
                return False
    return True


@jit
def predict_factor(h_abs, h_abs_old, err, err_old):
    """Step factor from the error norms (scipy's ``predict_factor``, Hairer & Wanner IV.8; -1: none)."""
    multiplier = 1.0
    if err_old >= 0.0 and h_abs_old >= 0.0 and err != 0.0:
        multiplier = h_abs / h_abs_old * (err_old / err) ** 0.25
    return np.inf if err == 0.0 else min(1.0, multiplier) * err ** -0.25


@jit
def radau_dense_at(t, t_old, h, Q):
    """The Radau interpolant (n,) at t (``RadauDenseOutput``) from Q (4 n,): the coefficients of x, x^2, x^3
    (x = (t - t_old) / h) row by row, then y_old."""
    n = Q.size // 4
    x = (t - t_old) / h
    y = np.empty(n)
    for i in range(n):
        y[i] = Q[3 * n + i] + x * (Q[i] + x * (Q[n + i] + x * Q[2 * n + i]))
    return y


@jit
def radau_buffers(n):
    """Jacobian J (n, n), LU factors and pivots (real LUr, pr; complex LUc, pc) and interpolant Q (1, 4 n) of
    an n-dimensional Radau solve, in the order :func:`make`'s ``radau_step`` takes them."""
    return (np.empty((n, n)), np.empty((n, n)), np.empty(n, dtype=np.int64), np.empty((n, n), dtype=np.complex128),
            np.empty(n, dtype=np.int64), np.empty((1, 4 * n)))


@jit
def radau_dense_until(Y, k, t_eval, t_stop, t_old, h, Q):
    """Rows Y[k], Y[k + 1], … at the output times t_eval[k…] <= t_stop from the collocation polynomial Q
    (1, 4 n) of the step (t_old, h); returns the next k."""
    while k < t_eval.size and t_eval[k] <= t_stop:
        Y[k] = radau_dense_at(t_eval[k], t_old, h, Q[0])
        k += 1
    return k


def steppers(rhs, jac, hold_after_newton_failure=False) -> tuple:
    """(radau_start, radau_step, radau_try, radau_error, newton) of the jitted ``rhs(t, y, args, out)`` with
    Jacobian ``jac(t, y, args, J)``, compiled on first call (closures: :mod:`symmech.numerics.ode`):

    - ``radau_start(t, y, f, t_bound, args, rtol, atol, J)``: the state st (N_RADAU,) of a fresh Radau solve;
    - ``radau_step(t, y, f, t_bound, args, rtol, atol, st, J, LUr, pr, LUc, pc, Q)``: one accepted Radau step,
      (t_new, y_new, f_new, ok), its interpolant into Q (1, 4 n) for :func:`radau_dense_at`;
    - ``radau_try(t, y, f, h, args, rtol, atol, st, J, LUr, pr, LUc, pc, Q)``: one collocation solve of length h.

    rtol is a float, atol an array (n,) [units of y]. The step control is scipy's; with
    ``hold_after_newton_failure`` the step after one the Newton iteration shortened is asked no longer than it
    (Hairer and Wanner's RADAU5): where the iteration fails again at once after scipy's growth of up to
    ``RADAU_MAX_FACTOR`` (the grain's slips near zero speed), the next step is not grown into a failure again."""
    first_step = initial.make(rhs)

    @inline_closure
    def newton(t, y, h, Z0, scale, tol, args, LUr, pr, LUc, pc):
        """The collocation system by simplified Newton on the real / complex split (scipy's
        ``solve_collocation_system``): (converged, iterations, Z (3, n) the stage increments, rate; -1: none)."""
        n = y.size
        W = mix(RADAU_TI, Z0)
        Z = Z0.copy()
        F, TF, dW = np.empty((3, n)), np.empty((3, n)), np.empty((3, n))  # work arrays, reused by every iteration
        stage = np.empty(n)
        Wc = np.empty(n, dtype=np.complex128)
        norm_old, rate, converged, k = -1.0, -1.0, False, 0
        for k in range(NEWTON_MAXITER):
            for i in range(3):
                for j in range(n):
                    stage[j] = y[j] + Z[i, j]
                rhs(t + RADAU_C[i] * h, stage, args, F[i])
            if not _finite(F):
                break
            mix_into(RADAU_TI, F, TF)  # rows: the real and the complex part's real and imaginary projections
            for i in range(n):
                Wc[i] = complex(TF[1, i], TF[2, i]) - MU_COMPLEX / h * complex(W[1, i], W[2, i])
                dW[0, i] = TF[0, i] - MU_REAL / h * W[0, i]
            solve_in_place(LUr, pr, dW[0])
            solve_in_place(LUc, pc, Wc)
            for i in range(n):
                dW[1, i], dW[2, i] = Wc[i].real, Wc[i].imag
            dW_norm = rms(dW, scale)
            if norm_old >= 0.0:
                rate = dW_norm / norm_old
            if rate >= 0.0 and (rate >= 1.0 or rate ** (NEWTON_MAXITER - k) / (1.0 - rate) * dW_norm > tol):
                break
            W += dW
            mix_into(RADAU_T, W, Z)
            if dW_norm == 0.0 or (rate >= 0.0 and rate / (1.0 - rate) * dW_norm < tol):
                converged = True
                break
            norm_old = dW_norm
        return converged, k + 1, Z, rate

    @inline_closure
    def radau_try(t, y, f, h, args, rtol, atol, st, J, LUr, pr, LUc, pc, Q):
        """One attempt at a step of length h from (t, y), f = rhs there: the Newton solve from the last step's
        interpolant (zero without one), with fresh factors and, if that fails, a fresh Jacobian (scipy's
        ``_step_impl``). Returns (converged, iterations, rate, Z (3, n))."""
        if st[ST_AT.h_last] != 0.0:
            Z0 = np.empty((3, y.size))
            for i in range(3):
                Z0[i] = radau_dense_at(t + h * RADAU_C[i], st[ST_AT.t_old], st[ST_AT.h_last], Q[0]) - y
        else:
            Z0 = np.zeros((3, y.size))
        scale = atol + np.abs(y) * rtol
        newton_tol = max(10.0 * EPS / rtol, min(0.03, rtol ** 0.5))
        while True:
            if st[ST_AT.lu_valid] == 0.0:
                factor(h, J, LUr, pr, LUc, pc)
                st[ST_AT.lu_valid] = 1.0
            converged, n_iter, Z, rate = newton(t, y, h, Z0, scale, newton_tol, args, LUr, pr, LUc, pc)
            if converged or st[ST_AT.jac_current] != 0.0:
                return converged, n_iter, rate, Z
            jac(t, y, args, J)
            st[ST_AT.jac_current], st[ST_AT.lu_valid] = 1.0, 0.0

    @inline_closure
    def radau_error(t, y, y_new, f, h, Z, args, rtol, atol, LUr, pr, rejected):
        """Norm of the embedded order-3 error estimate, filtered by (MU_REAL / h - J)^-1 (again through f at
        the filtered point after a rejection, as scipy)."""
        ZE = mix(RADAU_E, Z)[0] / h
        error = lu_solve(LUr, pr, f + ZE)
        scale = atol + np.maximum(np.abs(y), np.abs(y_new)) * rtol
        err = rms(error, scale)
        if rejected and err > 1.0:
            fe = np.empty(y.size)
            rhs(t, y + error, args, fe)
            err = rms(lu_solve(LUr, pr, fe + ZE), scale)
        return err

    @closure
    def radau_step(t, y, f, t_bound, args, rtol, atol, st, J, LUr, pr, LUc, pc, Q):
        """One accepted Radau step (scipy's ``Radau._step_impl``)."""
        min_step = 10 * abs(np.nextafter(t, np.inf) - t)
        h_abs, h_old, err_old = st[ST_AT.h], st[ST_AT.h_old], st[ST_AT.err_old]
        if h_abs < min_step:
            h_abs, h_old, err_old = min_step, -1.0, -1.0
        rejected = shortened = False
        while True:
            if h_abs < min_step:
                return t, y, f, False
            t_new = min(t + h_abs, t_bound)
            h = t_new - t
            h_abs = abs(h)
            converged, n_iter, rate, Z = radau_try(t, y, f, h, args, rtol, atol, st, J, LUr, pr, LUc, pc, Q)
            if not converged:
                h_abs *= 0.5
                st[ST_AT.lu_valid] = 0.0
                shortened = True
                continue
            y_new = y + Z[2]
            err = radau_error(t, y, y_new, f, h, Z, args, rtol, atol, LUr, pr, rejected)
            safety = 0.9 * (2 * NEWTON_MAXITER + 1) / (2 * NEWTON_MAXITER + n_iter)
            if err <= 1.0:
                break
            h_abs *= max(RADAU_MIN_FACTOR, safety * predict_factor(h_abs, h_old, err, err_old))
            st[ST_AT.lu_valid] = 0.0
            rejected = True
        recompute_jac = n_iter > 2 and rate > 1e-3
        factor_ = min(RADAU_MAX_FACTOR, safety * predict_factor(h_abs, h_old, err, err_old))
        if hold_after_newton_failure and shortened:  # a Newton failure shortened this step: no growth after it
            factor_ = min(factor_, 1.0)
        if not recompute_jac and factor_ < 1.2:
            factor_ = 1.0
        else:
            st[ST_AT.lu_valid] = 0.0
        f_new = np.empty(y.size)
        rhs(t_new, y_new, args, f_new)
        if recompute_jac:
            jac(t_new, y_new, args, J)
        st[ST_AT.jac_current] = 1.0 if recompute_jac else 0.0
        st[ST_AT.h_old], st[ST_AT.err_old], st[ST_AT.h] = st[ST_AT.h], err, h_abs * factor_
        st[ST_AT.t_old], st[ST_AT.h_last] = t, h
        n = y.size
        Q[0, :3 * n] = mix(RADAU_PT, Z).reshape(3 * n)
        Q[0, 3 * n:] = y
        return t_new, y_new, f_new, True

    @closure
    def radau_start(t, y, f, t_bound, args, rtol, atol, J):
        """Solver state (N_RADAU,) of a fresh solve (scipy's ``Radau.__init__``): first step, Jacobian at (t, y)."""
        st = np.zeros(N_RADAU)
        st[ST_AT.h] = first_step(t, y, f, t_bound, args, rtol, atol, RADAU_POWER)
        st[ST_AT.h_old] = st[ST_AT.err_old] = -1.0
        jac(t, y, args, J)
        st[ST_AT.jac_current] = 1.0
        return st

    return radau_start, radau_step, radau_try, radau_error, newton
