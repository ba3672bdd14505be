"""The compiled ODE toolkit: scipy's DOP853 and Radau IIA (order 5, dense output) and Brent's root finder and
bounded minimiser, ported to numba, for any right-hand side.

The ports take scipy's steps: the same step-size control, error norms, Newton iteration and interpolants,
with the tableaux of :mod:`symmech.numerics.dop853` and the Radau constants below (both bit-equal to scipy's,
``tests/test_ode_toolkit.py``, ``tests/test_dop853.py``), so a compiled solve and ``solve_ivp`` on the same
right-hand side agree to round-off.

A right-hand side is a jitted ``rhs(t, y, args, out)`` writing y' (n,) into out (n,) (the form of the
generated ``rhs_into`` kernels); a Jacobian ``jac(t, y, args, J)`` writes dy'/dy (n, n) into J; event
functions ``events(t, y, args, g)`` write g (k,), whose zeros a whole solve locates as ``solve_ivp`` does;
``args`` is anything numba types (an array, a tuple). A root finder's function is ``f(x, args) -> float``.

**How the right-hand side reaches the compiled code** (measured with numba 0.68 in fresh processes on an
empty ``NUMBA_CACHE_DIR``, run twice, ``dispatcher.stats.cache_hits / cache_misses``): a jitted function that
takes a jitted function as an *argument* is never served from the cache (its signature holds the
dispatcher's type, which differs between processes: a miss every run), and a cached function that passes
one (``integrate(my_rhs, ...)``) cannot be cached at all ("uses dynamic globals"): the grain engine would
compile on every start. A function that calls a jitted function held in a *closure variable* is typed with
it as a constant, and a cached caller of such a closure is served from the cache in the next process
(the closure is compiled into the caller). So :func:`make` and :func:`roots` compile the generic code per
right-hand side as closures; the grain engine calls them from its cached entry (cached whole, cold compile
unchanged: benchmarks/README.md). The closures themselves are not cached (``cache=False``): their cache key
would hold the pickled closure variables, a dispatcher with a per-process id, a new entry every process.
So :func:`system` (a generated dynamics module end to end) compiles in each process that uses it.
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from types import SimpleNamespace

import numba
import numpy as np

from symmech.numerics import dop853 as dop
from symmech.numerics import kernels
from symmech.core.scene import SymmechError

jit = numba.njit(cache=True, error_model="numpy", nogil=True)
closure = numba.njit(cache=False, error_model="numpy", nogil=True)  # see the module docstring

EPS = float(np.finfo(float).eps)
INT = np.int64

# DOP853 (numerics.dop853: the coefficients of scipy's solve_ivp, bit for bit).
DOP_A, DOP_B, DOP_C = dop.A, dop.B, dop.C
DOP_E3, DOP_E5, DOP_D = dop.E3, dop.E5, dop.D
DOP_STAGES, DOP_EXTENDED, DOP_POWER = INT(dop.N_STAGES), INT(dop.N_STAGES_EXTENDED), INT(dop.INTERPOLATOR_POWER)
DOP_EXPONENT = -1.0 / 8.0  # error estimator of order 7

# Radau IIA of order 5 (scipy's ``_ivp/radau.py``): nodes, error estimator, the eigen-decomposition of the
# tableau A = T diag(MU_REAL, MU_COMPLEX, conj) TI, the dense-output matrix (written out: no scipy import).
S6 = 6.0 ** 0.5
RADAU_C = np.array([(4.0 - S6) / 10.0, (4.0 + S6) / 10.0, 1.0])
RADAU_E = np.array([[-13.0 - 7.0 * S6, -13.0 + 7.0 * S6, -1.0]]) / 3.0  # (1, 3)
MU_REAL = 3.0 + 3.0 ** (2.0 / 3.0) - 3.0 ** (1.0 / 3.0)
MU_COMPLEX = complex(3.0 + 0.5 * (3.0 ** (1.0 / 3.0) - 3.0 ** (2.0 / 3.0)),
                     -0.5 * (3.0 ** (5.0 / 6.0) + 3.0 ** (7.0 / 6.0)))
RADAU_T = np.array([[0.09443876248897524, -0.14125529502095421, 0.03002919410514742],
                    [0.25021312296533332, 0.20412935229379994, -0.38294211275726192], [1.0, 1.0, 0.0]])
RADAU_TI = np.array([[4.17871859155190428, 0.32768282076106237, 0.52337644549944951],
                     [-4.17871859155190428, -0.32768282076106237, 0.47662355450055044],
                     [0.50287263494578682, -2.57192694985560522, 0.59603920482822492]])
RADAU_PT = np.array([[13.0 / 3.0 + 7.0 * S6 / 3.0, -23.0 / 3.0 - 22.0 * S6 / 3.0, 10.0 / 3.0 + 5.0 * S6],
                    [13.0 / 3.0 - 7.0 * S6 / 3.0, -23.0 / 3.0 + 22.0 * S6 / 3.0, 10.0 / 3.0 - 5.0 * S6],
                    [1.0 / 3.0, -8.0 / 3.0, 10.0 / 3.0]]).T.copy()  # transposed: Q = P^T Z
NEWTON_MAXITER, RADAU_MIN_FACTOR, RADAU_MAX_FACTOR = 6, 0.2, 10.0
RADAU_POWER = 1.0 / 4.0  # initial step of the order-3 error estimator
# Solver state between the steps of one solve (``Radau`` attributes): step, previous step and error norm
# (-1: none), Jacobian current, LU factors valid, start and length of the last step (its interpolant).
R_H, R_H_OLD, R_ERR_OLD, R_JAC_CURRENT, R_LU_VALID, R_T_OLD, R_H_LAST = 0, 1, 2, 3, 4, 5, 6
N_RADAU = 7

BOUNDED_MAXFUN = 500  # function evaluations of the bounded minimiser at most (scipy's default)
BRENT_RTOL, BRENT_ITER = 4 * EPS, 100
DOP853, RADAU = INT(0), INT(1)  # methods of a whole solve
SUCCESS, STEP_TOO_SMALL, TOO_MANY_STEPS, TERMINATED = INT(0), INT(1), INT(2), INT(3)  # status of a whole solve


# --------------------------------------------------------------------------- generic pieces (no rhs)


@jit
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
        for r in range(DOP_POWER):
            acc += F[(DOP_POWER - 1 - r) * n + i]
            acc *= x if r % 2 == 0 else 1 - x
        y[i] = acc + y_old[i]
    return y


@jit
def lu(A, piv):
    """LU factorisation with partial pivoting of A (n, n), real or complex, in place; row swaps into piv."""
    n = A.shape[0]
    for k in range(n):
        m = k
        for i in range(k + 1, n):
            if abs(A[i, k]) > abs(A[m, k]):
                m = i
        piv[k] = m
        for j in range(n):
            A[k, j], A[m, j] = A[m, j], A[k, j]
        for i in range(k + 1, n):
            A[i, k] /= A[k, k]
            for j in range(k + 1, n):
                A[i, j] -= A[i, k] * A[k, j]


@jit
def lu_solve(LU, piv, b):
    """x with A x = b from the factors of :func:`lu`."""
    n = b.size
    x = b.copy()
    for k in range(n):
        x[k], x[piv[k]] = x[piv[k]], x[k]
    for i in range(n):
        for j in range(i):
            x[i] -= LU[i, j] * x[j]
    for i in range(n - 1, -1, -1):
        for j in range(i + 1, n):
            x[i] -= LU[i, j] * x[j]
        x[i] /= LU[i, i]
    return x


@jit
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
    out = np.zeros((A.shape[0], Z.shape[1]))
    for r in range(A.shape[0]):
        for j in range(3):
            for i in range(Z.shape[1]):
                out[r, i] += A[r, j] * Z[j, i]
    return out


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


# --------------------------------------------------------------------------- steppers of one rhs


@closure
def _no_events(t, y, args, out):
    """The event functions of a system without events (k = 0)."""


def make(rhs, jac, events=_no_events) -> SimpleNamespace:
    """:func:`steppers` of ``rhs``, ``jac`` and the whole solves of :func:`_make_solve` (steppers of their own,
    counting the evaluations of rhs; ``solve_events`` locating the zeros of the jitted
    ``events(t, y, args, g)``, which writes the k event functions into g (k,)), each compiled on first call."""
    steps = steppers(rhs, jac)
    steps.solve, steps.solve_events = _make_solve(rhs, jac, events)
    return steps


def steppers(rhs, jac) -> SimpleNamespace:
    """The steppers of the right-hand side ``rhs(t, y, args, out)`` with Jacobian ``jac(t, y, args, J)``
    (jitted; see the module docstring), compiled on first call:

    - ``first_step(t, y, f, t_bound, args, rtol, atol, power)``: scipy's ``select_initial_step``;
    - ``dop_advance(t, y, f, h_abs, t_bound, args, rtol, atol, K)``: one accepted DOP853 step,
      (t_new, y_new, next h_abs, ok); K (16, n) the stages, K[12] f at the new point;
    - ``dop_dense(t_old, h, y_old, y_new, args, K)``: the step's interpolant F (7, n) for :func:`dop_dense_at`;
    - ``radau_start(t, y, f, t_bound, args, rtol, atol, J)``: the state st (N_RADAU,) of a fresh Radau solve;
    - ``radau_step(t, y, f, t_bound, args, rtol, atol, st, J, LUr, pr, LUc, pc, Q)``: one accepted Radau step,
      (t_new, y_new, f_new, ok), its interpolant into Q (1, 4 n) for :func:`radau_dense_at`;
    - ``radau_try(t, y, f, h, args, rtol, atol, st, J, LUr, pr, LUc, pc, Q)``: one collocation solve of length h.

    rtol is a float, atol an array (n,) [units of y]."""

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
            for s in range(1, DOP_STAGES):
                combine(yi, y, K, DOP_A[s], s, h)
                rhs(t + DOP_C[s] * h, yi, args, K[s])
            combine(y_new, y, K, DOP_B, DOP_STAGES, h)
            rhs(t + h, y_new, args, K[DOP_STAGES])
            n5 = n3 = 0.0
            for i in range(n):
                e5 = e3 = 0.0
                for j in range(DOP_STAGES + 1):
                    e5 += DOP_E5[j] * K[j, i]
                    e3 += DOP_E3[j] * K[j, i]
                scale = atol[i] + max(abs(y[i]), abs(y_new[i])) * rtol
                n5 += (e5 / scale) ** 2
                n3 += (e3 / scale) ** 2
            err = 0.0 if n5 == 0 and n3 == 0 else abs(h) * n5 / math.sqrt((n5 + 0.01 * n3) * n)
            if err < 1:
                factor = 10.0 if err == 0 else min(10.0, 0.9 * err ** DOP_EXPONENT)
                if rejected:
                    factor = min(1.0, factor)
                return t_new, y_new, h_abs * factor, True
            h_abs *= max(0.2, 0.9 * err ** DOP_EXPONENT)
            rejected = True

    @closure
    def dop_dense(t_old, h, y_old, y_new, args, K):
        """Interpolant coefficients F (7, n) of the last step (scipy's ``DOP853._dense_output_impl``)."""
        n = y_old.size
        yi = np.empty(n)
        for s in range(DOP_STAGES + 1, DOP_EXTENDED):
            combine(yi, y_old, K, DOP_A[s], s, h)
            rhs(t_old + DOP_C[s] * h, yi, args, K[s])
        F = np.empty((DOP_POWER, n))
        zero = np.zeros(n)
        for i in range(n):
            dy = y_new[i] - y_old[i]
            F[0, i] = dy
            F[1, i] = h * K[0, i] - dy
            F[2, i] = 2 * dy - h * (K[DOP_STAGES, i] + K[0, i])
        for r in range(DOP_POWER - 3):
            combine(F[3 + r], zero, K, DOP_D[r], DOP_EXTENDED, h)
        return F

    @closure
    def newton(t, y, h, Z0, scale, tol, args, LUr, pr, LUc, pc):
        """The collocation system by simplified Newton on the real / complex split (scipy's
        ``solve_collocation_system``): (converged, iterations, Z (3, n) the stage increments, rate; -1: none)."""
        n = y.size
        W = mix(RADAU_TI, Z0)
        Z = Z0.copy()
        F = np.empty((3, n))
        dW = np.empty((3, n))
        Wc = np.empty(n, dtype=np.complex128)
        norm_old, rate, converged, k = -1.0, -1.0, False, 0
        for k in range(NEWTON_MAXITER):
            for i in range(3):
                rhs(t + RADAU_C[i] * h, y + Z[i], args, F[i])
            if not np.all(np.isfinite(F)):
                break
            TF = mix(RADAU_TI, F)  # rows: the real and the complex part's real and imaginary projections
            for i in range(n):
                Wc[i] = complex(TF[1, i], TF[2, i]) - MU_COMPLEX / h * complex(W[1, i], W[2, i])
            dW[0] = lu_solve(LUr, pr, TF[0] - MU_REAL / h * W[0])
            dWc = lu_solve(LUc, pc, Wc)
            dW[1], dW[2] = dWc.real, dWc.imag
            dW_norm = rms(dW, scale)
            if norm_old >= 0.0:
                rate = dW_norm / norm_old
            if rate >= 0.0 and (rate >= 1.0 or rate ** (NEWTON_MAXITER - k) / (1.0 - rate) * dW_norm > tol):
                break
            W += dW
            Z = mix(RADAU_T, W)
            if dW_norm == 0.0 or (rate >= 0.0 and rate / (1.0 - rate) * dW_norm < tol):
                converged = True
                break
            norm_old = dW_norm
        return converged, k + 1, Z, rate

    @closure
    def radau_try(t, y, f, h, args, rtol, atol, st, J, LUr, pr, LUc, pc, Q):
        """One attempt at a step of length h from (t, y), f = rhs there: the Newton solve from the last step's
        interpolant (zero without one), with fresh factors and, if that fails, a fresh Jacobian (scipy's
        ``_step_impl``). Returns (converged, iterations, rate, Z (3, n))."""
        if st[R_H_LAST] != 0.0:
            Z0 = np.empty((3, y.size))
            for i in range(3):
                Z0[i] = radau_dense_at(t + h * RADAU_C[i], st[R_T_OLD], st[R_H_LAST], Q[0]) - y
        else:
            Z0 = np.zeros((3, y.size))
        scale = atol + np.abs(y) * rtol
        newton_tol = max(10.0 * EPS / rtol, min(0.03, rtol ** 0.5))
        while True:
            if st[R_LU_VALID] == 0.0:
                factor(h, J, LUr, pr, LUc, pc)
                st[R_LU_VALID] = 1.0
            converged, n_iter, Z, rate = newton(t, y, h, Z0, scale, newton_tol, args, LUr, pr, LUc, pc)
            if converged or st[R_JAC_CURRENT] != 0.0:
                return converged, n_iter, rate, Z
            jac(t, y, args, J)
            st[R_JAC_CURRENT], st[R_LU_VALID] = 1.0, 0.0

    @closure
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
        h_abs, h_old, err_old = st[R_H], st[R_H_OLD], st[R_ERR_OLD]
        if h_abs < min_step:
            h_abs, h_old, err_old = min_step, -1.0, -1.0
        rejected = False
        while True:
            if h_abs < min_step:
                return t, y, f, False
            t_new = min(t + h_abs, t_bound)
            h = t_new - t
            h_abs = abs(h)
            converged, n_iter, rate, Z = radau_try(t, y, f, h, args, rtol, atol, st, J, LUr, pr, LUc, pc, Q)
            if not converged:
                h_abs *= 0.5
                st[R_LU_VALID] = 0.0
                continue
            y_new = y + Z[2]
            err = radau_error(t, y, y_new, f, h, Z, args, rtol, atol, LUr, pr, rejected)
            safety = 0.9 * (2 * NEWTON_MAXITER + 1) / (2 * NEWTON_MAXITER + n_iter)
            if err <= 1.0:
                break
            h_abs *= max(RADAU_MIN_FACTOR, safety * predict_factor(h_abs, h_old, err, err_old))
            st[R_LU_VALID] = 0.0
            rejected = True
        recompute_jac = n_iter > 2 and rate > 1e-3
        factor_ = min(RADAU_MAX_FACTOR, safety * predict_factor(h_abs, h_old, err, err_old))
        if not recompute_jac and factor_ < 1.2:
            factor_ = 1.0
        else:
            st[R_LU_VALID] = 0.0
        f_new = np.empty(y.size)
        rhs(t_new, y_new, args, f_new)
        if recompute_jac:
            jac(t_new, y_new, args, J)
        st[R_JAC_CURRENT] = 1.0 if recompute_jac else 0.0
        st[R_H_OLD], st[R_ERR_OLD], st[R_H] = st[R_H], err, h_abs * factor_
        st[R_T_OLD], st[R_H_LAST] = t, h
        n = y.size
        Q[0, :3 * n] = mix(RADAU_PT, Z).reshape(3 * n)
        Q[0, 3 * n:] = y
        return t_new, y_new, f_new, True

    @closure
    def radau_start(t, y, f, t_bound, args, rtol, atol, J):
        """Solver state (N_RADAU,) of a fresh solve (scipy's ``Radau.__init__``): first step, Jacobian at (t, y)."""
        st = np.zeros(N_RADAU)
        st[R_H] = first_step(t, y, f, t_bound, args, rtol, atol, RADAU_POWER)
        st[R_H_OLD] = st[R_ERR_OLD] = -1.0
        jac(t, y, args, J)
        st[R_JAC_CURRENT] = 1.0
        return st

    return SimpleNamespace(first_step=first_step, dop_advance=dop_advance, dop_dense=dop_dense, newton=newton,
                           radau_try=radau_try, radau_error=radau_error, radau_step=radau_step,
                           radau_start=radau_start)


def _make_solve(rhs, jac, events):
    """The whole solves of :func:`make`, from t0 to t_eval[-1] (t_eval increasing, >= t0) by DOP853 or RADAU:

    - ``solve(method, t0, y0, t_eval, args, rtol, atol, max_steps)`` -> (Y (k, n) the dense output at t_eval,
      accepted steps, right-hand side evaluations, status SUCCESS / STEP_TOO_SMALL / TOO_MANY_STEPS);
    - ``solve_events(..., max_steps, direction, terminal)`` also locates the zeros of the event functions as
      ``solve_ivp`` does: after each step, event i is active where g_i changed sign (direction[i] +1: rising
      only, -1: falling only, 0: both), its time found on the step's dense output by Brent's method (xtol and
      rtol 4 eps); at the earliest active event with terminal[i] the solve stops (status TERMINATED) and later
      rows of Y stay NaN. Returns (Y, steps, evaluations, status, rows of Y filled, event times (e,), which
      event (e,), the states there (e, n)) in time order."""

    @closure
    def counted(t, y, args, out):
        """rhs, counting its evaluations in args[1][0]."""
        args[1][0] += 1.0
        rhs(t, y, args[0], out)

    @closure
    def jac_of(t, y, args, J):
        jac(t, y, args[0], J)

    steps = steppers(counted, jac_of)
    first_step, dop_advance, dop_dense = steps.first_step, steps.dop_advance, steps.dop_dense
    radau_start, radau_step = steps.radau_start, steps.radau_step

    @closure
    def dense_at(x, method, t_old, h, y_old, F):
        """The last step's interpolant (n,) at x; F its coefficients (DOP853: 7 n, Radau: 4 n)."""
        return radau_dense_at(x, t_old, h, F) if method == RADAU else dop_dense_at(x, t_old, h, y_old, F)

    @closure
    def event_on_step(x, a):
        """Event function a[6] at time x on the step's interpolant: a = (method, t_old, h, y_old, F, args, i, g)."""
        y = dense_at(x, a[0], a[1], a[2], a[3], a[4])
        events(x, y, a[5], a[7])
        return a[7][a[6]]

    brentq = roots(event_on_step).brentq

    @closure
    def solve_events(method, t0, y0, t_eval, args, rtol, atol, max_steps, direction, terminal):
        n, t_end, n_ev = y0.size, t_eval[-1], direction.size
        Y = np.full((t_eval.size, n), np.nan)
        calls = np.zeros(1)
        cargs = (args, calls)
        t, y, f = t0, y0.copy(), np.empty(n)
        counted(t, y, cargs, f)
        g_old, g_new, g_work, at = np.empty(n_ev), np.empty(n_ev), np.empty(n_ev), np.empty(n_ev)
        events(t, y, args, g_old)
        ev_t, ev_i, ev_y, m = np.empty(4), np.empty(4, dtype=INT), np.empty((4, n)), 0
        k = 0
        while k < t_eval.size and t_eval[k] <= t:
            Y[k] = y
            k += 1
        K = np.empty((DOP_EXTENDED, n))
        J, LUr, pr, LUc, pc, Q = radau_buffers(n)
        if method == RADAU:
            st = radau_start(t, y, f, t_end, cargs, rtol, atol, J)
            h_abs = 0.0
        else:
            st = np.zeros(N_RADAU)
            h_abs = first_step(t, y, f, t_end, cargs, rtol, atol, -DOP_EXPONENT)
        for step in range(max_steps):
            if not t < t_end:
                return Y, step, int(calls[0]), SUCCESS, k, ev_t[:m], ev_i[:m], ev_y[:m]
            if method == RADAU:
                t_new, y_new, f_new, ok = radau_step(t, y, f, t_end, cargs, rtol, atol, st, J, LUr, pr, LUc, pc, Q)
            else:
                t_new, y_new, h_abs, ok = dop_advance(t, y, f, h_abs, t_end, cargs, rtol, atol, K)
                f_new = K[DOP_STAGES].copy()
            if not ok:
                return Y, step, int(calls[0]), STEP_TOO_SMALL, k, ev_t[:m], ev_i[:m], ev_y[:m]
            h = t_new - t
            events(t_new, y_new, args, g_new)
            n_active = 0
            for i in range(n_ev):  # active: a sign change in the event's direction; at[i] its time, found below
                up, down = g_old[i] <= 0.0 <= g_new[i], g_old[i] >= 0.0 >= g_new[i]
                at[i] = np.inf
                if (up and direction[i] >= 0) or (down and direction[i] <= 0):
                    at[i] = t
                    n_active += 1
            t_stop, stopped = t_new, False
            if n_active > 0 or (k < t_eval.size and t_eval[k] <= t_new):
                F = dop_dense(t, h, y, y_new, cargs, K).reshape(-1) if method == DOP853 else Q[0]
                for i in range(n_ev):
                    if at[i] == t:
                        at[i] = brentq(t, t_new, 4 * EPS, (method, t, h, y, F, args, i, g_work))
                for i in np.argsort(at)[:n_active]:  # in time order, up to the first terminal one
                    if m == ev_t.size:
                        ev_t, ev_i, ev_y = (np.concatenate((ev_t, ev_t)), np.concatenate((ev_i, ev_i)),
                                            np.concatenate((ev_y, ev_y)))
                    ev_t[m], ev_i[m], ev_y[m] = at[i], i, dense_at(at[i], method, t, h, y, F)
                    m += 1
                    if terminal[i]:
                        t_stop, stopped = at[i], True
                        break
                while k < t_eval.size and t_eval[k] <= t_stop:
                    Y[k] = dense_at(t_eval[k], method, t, h, y, F)
                    k += 1
                if stopped:
                    return Y, step + 1, int(calls[0]), TERMINATED, k, ev_t[:m], ev_i[:m], ev_y[:m]
            t, y, f = t_new, y_new, f_new
            g_old, g_new = g_new, g_old
        status = SUCCESS if not t < t_end else TOO_MANY_STEPS
        return Y, max_steps, int(calls[0]), status, k, ev_t[:m], ev_i[:m], ev_y[:m]

    @closure
    def solve(method, t0, y0, t_eval, args, rtol, atol, max_steps):
        out = solve_events(method, t0, y0, t_eval, args, rtol, atol, max_steps, np.zeros(0), np.zeros(0, np.bool_))
        return out[0], out[1], out[2], out[3]

    return solve, solve_events


# --------------------------------------------------------------------------- root finding of one function


def roots(f) -> SimpleNamespace:
    """Brent's root finder and bounded minimiser of the jitted ``f(x, args) -> float``, compiled on first call:

    - ``brentq(a, b, xtol, args)``: the root in [a, b] (a sign change) to xtol + 4 eps |x| (scipy's ``brentq``);
    - ``bounded_min(a, b, xatol, args)``: (x, f(x)) minimising f over [a, b] (scipy's
      ``minimize_scalar(method="bounded")``, at most BOUNDED_MAXFUN evaluations)."""

    @closure
    def brentq(a, b, xtol, args):
        xpre, xcur = a, b
        fpre, fcur = f(xpre, args), f(xcur, args)
        xblk = fblk = spre = scur = 0.0
        if fpre == 0.0:
            return xpre
        if fcur == 0.0:
            return xcur
        for _ in range(BRENT_ITER):
            if fpre != 0.0 and fcur != 0.0 and (fpre < 0.0) != (fcur < 0.0):
                xblk, fblk = xpre, fpre
                spre = scur = xcur - xpre
            if abs(fblk) < abs(fcur):
                xpre, xcur, xblk = xcur, xblk, xcur
                fpre, fcur, fblk = fcur, fblk, fcur
            delta = (xtol + BRENT_RTOL * abs(xcur)) / 2
            sbis = (xblk - xcur) / 2
            if fcur == 0.0 or abs(sbis) < delta:
                return xcur
            if abs(spre) > delta and abs(fcur) < abs(fpre):
                if xpre == xblk:
                    stry = -fcur * (xcur - xpre) / (fcur - fpre)
                else:
                    dpre = (fpre - fcur) / (xpre - xcur)
                    dblk = (fblk - fcur) / (xblk - xcur)
                    stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
                if 2 * abs(stry) < min(abs(spre), 3 * abs(sbis) - delta):
                    spre, scur = scur, stry
                else:
                    spre = scur = sbis
            else:
                spre = scur = sbis
            xpre, fpre = xcur, fcur
            xcur += scur if abs(scur) > delta else (delta if sbis > 0 else -delta)
            fcur = f(xcur, args)
        return xcur

    @closure
    def bounded_min(a, b, xatol, args):
        sqrt_eps = math.sqrt(2.2e-16)
        golden_mean = 0.5 * (3.0 - math.sqrt(5.0))
        fulc = a + golden_mean * (b - a)
        nfc, xf = fulc, fulc
        rat = e = 0.0
        fx = f(xf, args)
        num = 1
        ffulc = fnfc = fx
        xm = 0.5 * (a + b)
        tol1 = sqrt_eps * abs(xf) + xatol / 3.0
        tol2 = 2.0 * tol1
        while abs(xf - xm) > (tol2 - 0.5 * (b - a)):
            golden = True
            if abs(e) > tol1:  # parabolic fit
                golden = False
                r = (xf - nfc) * (fx - ffulc)
                q = (xf - fulc) * (fx - fnfc)
                pp = (xf - fulc) * q - (xf - nfc) * r
                q = 2.0 * (q - r)
                if q > 0.0:
                    pp = -pp
                q = abs(q)
                r = e
                e = rat
                if abs(pp) < abs(0.5 * q * r) and pp > q * (a - xf) and pp < q * (b - xf):
                    rat = pp / q
                    x = xf + rat
                    if (x - a) < tol2 or (b - x) < tol2:
                        rat = tol1 * (1.0 if xm - xf >= 0 else -1.0)
                else:
                    golden = True
            if golden:
                e = a - xf if xf >= xm else b - xf
                rat = golden_mean * e
            si = 1.0 if rat >= 0 else -1.0
            x = xf + si * max(abs(rat), tol1)
            fu = f(x, args)
            num += 1
            if fu <= fx:
                if x >= xf:
                    a = xf
                else:
                    b = xf
                fulc, ffulc = nfc, fnfc
                nfc, fnfc = xf, fx
                xf, fx = x, fu
            else:
                if x < xf:
                    a = x
                else:
                    b = x
                if fu <= fnfc or nfc == xf:
                    fulc, ffulc = nfc, fnfc
                    nfc, fnfc = x, fu
                elif fu <= ffulc or fulc == xf or fulc == nfc:
                    fulc, ffulc = x, fu
            xm = 0.5 * (a + b)
            tol1 = sqrt_eps * abs(xf) + xatol / 3.0
            tol2 = 2.0 * tol1
            if num >= BOUNDED_MAXFUN:
                break
        return xf, fx

    return SimpleNamespace(brentq=brentq, bounded_min=bounded_min)


# --------------------------------------------------------------------------- a generated dynamics module


def _adapter(module):
    """``rhs(t, y, p, out)``, ``jac(t, y, p, J)`` and ``events(t, y, p, g)`` of the toolkit from a generated ``_nb``
    dynamics module's allocation-free kernels ``rhs_into``, ``jac_into`` and (if it declares events)
    ``events_into``, each of which writes row 0 of its (1, ...) output."""
    rhs_kernel, jac_kernel = module.rhs_into, module.jac_into
    n_events = len(getattr(module, "EVENTS", ()))
    events_kernel = getattr(module, "events_into", None)

    @closure
    def rhs(t, y, p, out):
        rhs_kernel(t, y, p, out.reshape((1, out.size)))

    @closure
    def jac(t, y, p, J):
        jac_kernel(t, y, p, J.reshape((1, J.shape[0], J.shape[1])))

    @closure
    def events(t, y, p, g):
        events_kernel(t, y, p, g.reshape((1, n_events)))

    return rhs, jac, (events if n_events else _no_events)


@functools.cache
def system(name: str) -> SimpleNamespace:
    """The steppers of :func:`make` for the generated dynamics module ``name`` (e.g. ``"smm_rotor_boom"``: its
    numba kernels through :func:`_adapter`) and its events (``names``, ``direction``, ``terminal``: the
    module's ``EVENTS``), built once per process."""
    module = kernels.load(name)
    steps = make(*_adapter(module))
    declared = getattr(module, "EVENTS", ())
    steps.names = tuple(e[0] for e in declared)
    steps.direction = np.array([e[1] for e in declared], dtype=float)
    steps.terminal = np.array([e[2] for e in declared], dtype=np.bool_)
    return steps


@dataclass(frozen=True)
class Solution:
    """A compiled solve: t (k,) [s] the requested times reached, y (n, k) the state there (``solve_ivp``'s
    layout), accepted steps and right-hand side evaluations; per event the module declares (its name) the
    times t_events[name] (e,) [s] and states y_events[name] (e, n) where it occurred (``solve_ivp``'s
    layout), and the name of the terminal event that ended the solve (``terminated_by``; "" when it reached
    t_eval[-1])."""
    t: np.ndarray
    y: np.ndarray
    steps: int
    nfev: int
    t_events: dict = field(default_factory=dict)
    y_events: dict = field(default_factory=dict)
    terminated_by: str = ""


METHODS = {"DOP853": DOP853, "Radau": RADAU}


def integrate(name: str, p, y0, t_eval, t0: float = 0.0, method: str = "DOP853", rtol: float = 1e-8,
              atol=1e-10, max_steps: int = 1_000_000) -> Solution:
    """Integrate the generated dynamics module ``name`` (y' = rhs(t, y, p)) from state y0 (n,) at t0 [s] to
    t_eval[-1] in compiled code, by ``method`` "DOP853" or "Radau" (with the module's symbolic ``jac``), to
    ``rtol`` and ``atol`` (float or (n,), units of y) per step; the state at the times t_eval (k,) [s]
    (increasing, >= t0) from the dense output. The events the module declares (``EVENTS``: name, direction,
    terminal) are located on the dense output by Brent's method as ``solve_ivp`` locates them; a terminal
    one ends the solve there (the times of t_eval after it are left out). SymmechError when the step size
    underflows or ``max_steps`` steps do not reach the end."""
    t_eval = np.asarray(t_eval, float)
    y0 = np.ascontiguousarray(y0, float)
    if method not in METHODS:
        raise SymmechError(f"ode: method '{method}' is not one of {sorted(METHODS)}")
    if t_eval.ndim != 1 or t_eval.size == 0 or t_eval[0] < t0 or np.any(np.diff(t_eval) < 0):
        raise SymmechError(f"ode: t_eval must be a non-empty increasing 1-D array of times >= t0 = {t0:g} s")
    atol = np.broadcast_to(np.asarray(atol, float), y0.shape).copy()
    compiled = system(name)
    Y, steps, nfev, status, filled, ev_t, ev_i, ev_y = compiled.solve_events(
        METHODS[method], float(t0), y0, t_eval, np.ascontiguousarray(p, float), float(rtol), atol, int(max_steps),
        compiled.direction, compiled.terminal)
    if status == STEP_TOO_SMALL:
        raise SymmechError(f"ode: {method} on {name}: required step size is less than spacing between numbers")
    if status == TOO_MANY_STEPS:
        raise SymmechError(f"ode: {method} on {name}: {max_steps} steps did not reach t = {t_eval[-1]:g} s")
    return Solution(t_eval[:filled], Y[:filled].T.copy(), steps, nfev,
                    {e: ev_t[ev_i == i] for i, e in enumerate(compiled.names)},
                    {e: ev_y[ev_i == i] for i, e in enumerate(compiled.names)},
                    compiled.names[ev_i[-1]] if status == TERMINATED else "")
