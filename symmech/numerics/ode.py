"""The compiled ODE toolkit's driver: whole solves with dense output and events by scipy's DOP853 or Radau IIA
(order 5), ported to numba, for any right-hand side; one method per module beside it (:mod:`.dop853`,
:mod:`.radau`, :mod:`.first_step`, Brent's root finder and bounded minimiser in :mod:`.brent`, the LU of
:mod:`.linalg`), the numba settings in :mod:`.jit`.

The ports take scipy's steps: the same step-size control, error norms, Newton iteration and interpolants,
with the DOP853 tableau and the Radau constants written out in their modules (both bit-equal to scipy's,
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
from dataclasses import dataclass, field
from types import SimpleNamespace

import numpy as np

from symmech.core.scene import SymmechError
from symmech.numerics import dop853, kernels, radau
from symmech.numerics import first_step as initial
from symmech.numerics.brent import roots
from symmech.numerics.dop853_tableau import EXPONENT as DOP_EXPONENT, EXTENDED as DOP_EXTENDED, STAGES as DOP_STAGES
from symmech.numerics.dop853 import dop_dense_at
from symmech.numerics.jit import EPS, INT, closure
from symmech.numerics.radau import N_RADAU, radau_buffers, radau_dense_at

DOP853, RADAU = INT(0), INT(1)  # methods of a whole solve
SUCCESS, STEP_TOO_SMALL, TOO_MANY_STEPS, TERMINATED = INT(0), INT(1), INT(2), INT(3)  # status of a whole solve
STEP_TOO_SMALL_TEXT = "required step size is less than spacing between numbers"  # scipy's words, every engine's


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


def steppers(rhs, jac, hold_after_newton_failure=False) -> SimpleNamespace:
    """The steppers of the right-hand side ``rhs(t, y, args, out)`` with Jacobian ``jac(t, y, args, J)``
    (jitted; see the module docstring), compiled on first call:

    - ``first_step(t, y, f, t_bound, args, rtol, atol, power)``: scipy's ``select_initial_step``
      (:mod:`symmech.numerics.first_step`);
    - ``dop_advance``, ``dop_dense``: one accepted DOP853 step and its interpolant (:mod:`symmech.numerics.dop853`);
    - ``radau_start``, ``radau_step``, ``radau_try``, ``radau_error``, ``newton``: Radau IIA
      (:mod:`symmech.numerics.radau`; ``hold_after_newton_failure``: no step growth right after a step the
      Newton iteration shortened, RADAU5's rule, else scipy's steps).

    rtol is a float, atol an array (n,) [units of y]."""
    dop_advance, dop_dense = dop853.steppers(rhs)
    radau_start, radau_step, radau_try, radau_error, newton = radau.steppers(rhs, jac, hold_after_newton_failure)
    return SimpleNamespace(first_step=initial.make(rhs), dop_advance=dop_advance, dop_dense=dop_dense,
                           newton=newton, radau_try=radau_try, radau_error=radau_error, radau_step=radau_step,
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
        raise SymmechError(f"ode: {method} on {name}: {STEP_TOO_SMALL_TEXT}")
    if status == TOO_MANY_STEPS:
        raise SymmechError(f"ode: {method} on {name}: {max_steps} steps did not reach t = {t_eval[-1]:g} s")
    return Solution(t_eval[:filled], Y[:filled].T.copy(), steps, nfev,
                    {e: ev_t[ev_i == i] for i, e in enumerate(compiled.names)},
                    {e: ev_y[ev_i == i] for i, e in enumerate(compiled.names)},
                    compiled.names[ev_i[-1]] if status == TERMINATED else "")
