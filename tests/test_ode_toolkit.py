"""The compiled ODE toolkit (symmech.numerics.ode): scipy's DOP853, Radau IIA and Brent ported to numba, on their
own: tableaux bit-equal to scipy's, empirical orders of convergence, scipy's step counts on stiff and non-stiff
problems, and a generated dynamics module integrated end to end (``ode.integrate``) against ``solve_ivp`` and
the exact free response of the mechanism run.

The stiff test problem is Prothero-Robinson: y' = -lam (y - cos t) - sin t, y(0) = 1, solution cos t for
every lam."""
import functools
import math
import os
import subprocess
import sys
import tomllib
from fractions import Fraction

import numba
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, minimize_scalar

import symmech
from symmech.numerics import brent, linalg, newton, ode, radau
from symmech.core.scene import SymmechError, scenes_folder
from symmech.generated import smm_rotor_boom


@numba.njit
def probe(t, y, args, out):
    out[0] = -args[0] * (y[0] - math.cos(t)) - math.sin(t)


@numba.njit
def probe_jac(t, y, args, J):
    J[0, 0] = -args[0]


@numba.njit
def oscillator(t, y, args, out):
    """y'' = -y as y = (x, x')."""
    out[0], out[1] = y[1], -y[0]


@numba.njit
def no_jac(t, y, args, J):
    J[:] = 0.0


@functools.cache  # made on first use, not at import: a mutation screen's child process (forked after the
def stepper_set(rhs, jac):  # import) then builds them from the mutated factories
    """``ode.steppers(rhs, jac)``, once per process."""
    return ode.steppers(rhs, jac)


def adaptive(lam, t_end, rtol, atol):
    """Accepted steps and the largest error |y - cos t| at their ends of an adaptive Radau solve."""
    args, y, t, f = np.array([lam]), np.array([1.0]), 0.0, np.empty(1)
    probe(t, y, args, f)
    J, LUr, pr, LUc, pc, Q = radau.radau_buffers(1)
    st = stepper_set(probe, probe_jac).radau_start(t, y, f, t_end, args, rtol, np.array([atol]), J)
    steps, err = 0, 0.0
    while t < t_end:
        t, y, f, ok = stepper_set(probe, probe_jac).radau_step(t, y, f, t_end, args, rtol, np.array([atol]), st, J, LUr, pr, LUc, pc, Q)
        assert ok
        steps += 1
        err = max(err, abs(y[0] - math.cos(t)))
    return steps, err


def fixed_radau(lam, n, t_end=1.0):
    """|y(t_end) - cos t_end| after n equal Radau steps (one collocation solve each, exact Jacobian)."""
    args, y, f, h = np.array([lam]), np.array([1.0]), np.empty(1), t_end / n
    J, LUr, pr, LUc, pc, Q = radau.radau_buffers(1)
    J[0, 0] = -lam
    st = np.zeros(radau.N_RADAU)  # no previous step: the Newton solve starts from zero increments
    st[radau.ST_AT.jac_current] = 1.0
    for k in range(n):
        probe(k * h, y, args, f)
        ok, _, _, Z = stepper_set(probe, probe_jac).radau_try(k * h, y, f, h, args, 1e-12, np.array([1e-12]), st, J, LUr, pr, LUc, pc, Q)
        assert ok
        y = y + Z[2]
    return abs(y[0] - math.cos(t_end))


def fixed_dop853(n, t_end=4.0):
    """|y(t_end) - (cos, -sin)(t_end)| of the oscillator from (1, 0) after n equal DOP853 steps (an atol of
    1e30 accepts every step at the length asked for)."""
    y, f, h, t = np.array([1.0, 0.0]), np.empty(2), t_end / n, 0.0
    K, atol = np.empty((ode.DOP_EXTENDED, 2)), np.full(2, 1e30)
    oscillator(t, y, None, f)
    for _ in range(n):
        t_new, y, _, ok = stepper_set(oscillator, no_jac).dop_advance(t, y, f, h, t_end, None, 1e-3, atol, K)
        assert ok and t_new == pytest.approx(t + h, rel=1e-14)
        t, f = t_new, K[ode.DOP_STAGES].copy()
    return np.abs(y - (math.cos(t_end), -math.sin(t_end))).max()


def test_radau_tableau_is_scipys_bit_for_bit():
    """The Radau IIA constants written out in numerics.radau (no scipy import at run time) are those of scipy's
    ``_ivp/radau.py``, to the last bit."""
    from scipy.integrate._ivp import radau as scipy_radau

    for ours, theirs in ((radau.RADAU_C, scipy_radau.C), (radau.RADAU_E[0], scipy_radau.E),
                         (radau.RADAU_T, scipy_radau.T),
                         (radau.RADAU_TI, scipy_radau.TI), (radau.RADAU_PT, scipy_radau.P.T)):
        assert ours.shape == theirs.shape and np.array_equal(ours, theirs)
    assert radau.MU_REAL == scipy_radau.MU_REAL and radau.MU_COMPLEX == scipy_radau.MU_COMPLEX


def test_radau_collocation_conditions():
    """The Radau IIA tableau A = T diag(MU_REAL, MU_COMPLEX, conj)^-1 TI (the eigen-decomposition of A^-1)
    satisfies the simplifying conditions C(3): sum_j a_ij c_j^(k-1) = c_i^k / k, k = 1..3, to 1e-14."""
    lam = np.diag([radau.MU_REAL, radau.MU_COMPLEX.real, radau.MU_COMPLEX.real]).astype(complex)
    lam[1, 2], lam[2, 1] = -radau.MU_COMPLEX.imag, radau.MU_COMPLEX.imag  # the real form of the complex pair
    A = np.linalg.inv(radau.RADAU_T @ lam.real @ radau.RADAU_TI)
    c = radau.RADAU_C
    for k in range(1, 4):
        np.testing.assert_allclose(A @ c ** (k - 1), c ** k / k, rtol=0, atol=1e-14)


@pytest.mark.slow  # compiles its own adaptive Radau closures (~10 s of CPU; not cacheable across processes)
@pytest.mark.parametrize("rtol", [1e-4, 1e-6, 1e-8])
def test_radau_stiff_prothero_robinson_within_the_tolerance(rtol):
    """lam = 1e6 over 10 s: the error stays below 2 rtol at every step end (the equation contracts at rate
    lam, so the global error is about the last local error; measured 0.6 rtol at rtol 1e-6), in fewer than
    100 steps (an explicit method would need ~1e7)."""
    steps, err = adaptive(1e6, 10.0, rtol, 1e-3 * rtol)
    assert err <= 2 * rtol
    assert steps < 100


@pytest.mark.slow  # compiles its own solver closures (not cacheable across processes, numerics/ode.py)
def test_radau_takes_scipys_steps():
    """Same algorithm as scipy's Radau with the same (exact) Jacobian: the same number of accepted steps and
    the same largest error to 1e-6 relative (round-off through the step-size control)."""
    steps, err = adaptive(1e6, 10.0, 1e-6, 1e-9)
    ref = solve_ivp(lambda t, y: -1e6 * (y - np.cos(t)) - np.sin(t), (0.0, 10.0), [1.0], method="Radau",
                    rtol=1e-6, atol=1e-9, jac=lambda t, y: np.array([[-1e6]]))
    assert steps == len(ref.t) - 1
    assert err == pytest.approx(np.max(np.abs(ref.y[0] - np.cos(ref.t))), rel=1e-6)


@numba.njit
def cubic_probe(t, y, args, out):
    """y' = -lam (y^3 - cos^3 t) - sin t: solution cos t for every lam; stiff and nonlinear, so that a long step
    from the Jacobian at its start fails the simplified Newton iteration."""
    out[0] = -args[0] * (y[0] ** 3 - math.cos(t) ** 3) - math.sin(t)


@numba.njit
def cubic_probe_jac(t, y, args, J):
    J[0, 0] = -3.0 * args[0] * y[0] ** 2


def against_scipys_rule(held, scipys, t, y, f, t_end, args, rtol, atol, st, buffers):
    """Radau steps of ``held`` (steppers with ``hold_after_newton_failure``) from (t, y), each also taken from the same
    state by ``scipys`` (scipy's rule): the same step bit for bit, and the next step asked scipy's or capped at the
    step taken, scipy's where the step was taken as asked (to the round-off of t + h - t: nothing shortened it).
    Yields (t, y, capped, taken as asked) after each step, until t_end."""
    while t < t_end:
        other, asked = [a.copy() for a in (y, f, st, *buffers)], st[radau.ST_AT.h]
        t_s, y_s, _, ok_s = scipys.radau_step(t, other[0], other[1], t_end, args, rtol, atol, *other[2:])
        t, y, f, ok = held.radau_step(t, y, f, t_end, args, rtol, atol, st, *buffers)
        assert ok and ok_s and t == t_s and np.array_equal(y, y_s)
        h_last, proposed = st[radau.ST_AT.h_last], other[2][radau.ST_AT.h]
        assert st[radau.ST_AT.h] in (proposed, min(proposed, h_last))
        as_asked = h_last >= asked * (1 - 1e-12)
        assert st[radau.ST_AT.h] == proposed or not as_asked
        yield t, y, st[radau.ST_AT.h] < proposed, as_asked


@pytest.mark.slow  # compiles two sets of Radau closures of its own (~20 s of CPU; not cacheable across processes)
def test_radau_holds_the_step_after_a_newton_failure_when_asked():
    """``hold_after_newton_failure`` (Hairer and Wanner's RADAU5 rule), step by step against scipy's rule
    (:func:`against_scipys_rule`): on the cubic probe (lam = 1e5, rtol 1e-6, over 4 s; scipy's Radau fails the
    iteration 94 times in its 78 steps there) the cap acts on at least one step, at least ten steps are taken as
    asked, and the held solve stays within 2 rtol of cos t at every step end."""
    lam, rtol, atol, t_end = 1e5, 1e-6, np.array([1e-9]), 4.0
    args, y0, f = np.array([lam]), np.array([1.0]), np.empty(1)
    held, scipys = ode.steppers(cubic_probe, cubic_probe_jac, True), stepper_set(cubic_probe, cubic_probe_jac)
    cubic_probe(0.0, y0, args, f)
    J, LUr, pr, LUc, pc, Q = radau.radau_buffers(1)
    st = held.radau_start(0.0, y0, f, t_end, args, rtol, atol, J)
    capped = as_asked = 0
    for t, y, cap, asked in against_scipys_rule(held, scipys, 0.0, y0, f, t_end, args, rtol, atol, st,
                                                 (J, LUr, pr, LUc, pc, Q)):
        assert abs(y[0] - math.cos(t)) <= 2 * rtol
        capped, as_asked = capped + cap, as_asked + asked
    assert capped >= 1 and as_asked >= 10


def textbook_lu(A):
    """Doolittle elimination with partial pivoting in numpy, every row updated (the zero multipliers too)."""
    A = A.copy()
    piv = np.empty(len(A), dtype=np.int64)
    for k in range(len(A)):
        m = k + int(np.argmax(np.abs(A[k:, k])))  # the first largest
        piv[k] = m
        A[[k, m]] = A[[m, k]]
        for i in range(k + 1, len(A)):
            A[i, k] /= A[k, k]
            A[i, k + 1:] -= A[i, k] * A[k, k + 1:]
    return A, piv


@pytest.mark.slow  # compiles the LU and its solve for real and complex matrices (~3 s of CPU)
def test_lu_of_the_slip_iteration_matrix_skips_zero_rows_bit_for_bit():
    """The Radau iteration matrix mu/h - J of a stiff slip (the grain's 13 sliding states: r, v, w, q, work, loss;
    J zero in the columns of r, work, loss and in the rows of w_x, w_y) factored by ``linalg.lu``,
    which leaves a row alone when its multiplier is zero, equals the textbook elimination that updates every row,
    entry by entry (real: the same operations on every row it changes), and its solve A x = b equals numpy's to 1e-13 (real and complex)."""
    rng = np.random.default_rng(3)
    pattern = np.zeros((13, 13), dtype=bool)
    pattern[0, 2] = pattern[1, 3] = True  # r' = v
    pattern[np.ix_([2, 3, 6, 11, 12], range(2, 11))] = True  # v, w_z, work, loss: of v, w, q
    pattern[np.ix_(range(7, 11), range(4, 11))] = True  # q' of w, q
    J = np.where(pattern, rng.normal(size=(13, 13)) * 1e4, 0.0)
    for A in (3e4 * np.eye(13) - J, (2e4 + 1e4j) * np.eye(13) - J):
        LU, piv = A.copy(), np.empty(13, dtype=np.int64)
        linalg.lu(LU, piv)
        b = rng.normal(size=13).astype(A.dtype)
        x = b.copy()
        linalg.solve_in_place(LU, piv, x)
        np.testing.assert_allclose(x, np.linalg.solve(A, b), rtol=1e-13, atol=1e-13 * np.abs(x).max())
        if A.dtype == float:
            ref, ref_piv = textbook_lu(A)
            assert np.array_equal(piv, ref_piv) and np.array_equal(LU, ref)


@pytest.mark.xdist_group("radau_probe")  # one worker compiles the probe's Radau closures (~6 s of CPU) for both
@pytest.mark.parametrize("lam, order", [(1.0, 5.0), (1e6, 3.0)])
def test_radau_empirical_order_with_fixed_steps(lam, order):
    """Fixed steps h = 1/4 ... 1/64 over [0, 1], the slope of log error against log h: order 5 (2s - 1,
    Radau IIA with s = 3) on the non-stiff equation; on the stiff one (h lam >= 1.6e4) the order drops to the
    stage order 3 (Prothero-Robinson order reduction, Hairer & Wanner II, IV.15). Measured 4.99 and 3.05."""
    hs = [2.0**-k for k in range(2, 7)]
    errors = [fixed_radau(lam, 2**k) for k in range(2, 7)]
    assert np.polyfit(np.log(hs), np.log(errors), 1)[0] == pytest.approx(order, abs=0.15)


def test_dop853_empirical_order_with_fixed_steps():
    """The oscillator over [0, 4] in 4 ... 16 equal steps: the global error falls as h^8 (slope of log error
    against log h within 0.3 of 8; the errors stay above round-off: measured 7.9e-10 at 8 steps, 2.8e-12 at
    16, 1.1e-14 at 32, where round-off starts)."""
    ns = [4, 8, 16]
    errors = [fixed_dop853(n) for n in ns]
    assert min(errors) > 1e-12
    assert np.polyfit(np.log(4.0 / np.array(ns)), np.log(errors), 1)[0] == pytest.approx(8.0, abs=0.3)


@pytest.mark.slow  # compiles its own whole-solve closures (~14 s of CPU; not cacheable across processes)
@pytest.mark.parametrize("method", ["DOP853", "Radau"])
def test_whole_solve_takes_scipys_steps_with_dense_output(method):
    """The whole compiled solve of the non-stiff oscillator over 20 s (DOP853) and of the stiff probe over
    10 s (Radau): scipy's accepted steps, and the dense output at 57 requested times within 1e-12 (DOP853) and
    1e-9 (Radau: the Newton iteration's round-off through the step control) of solve_ivp's at the same times,
    and near the exact solution cos t."""
    if method == "DOP853":
        t_eval = np.linspace(0.0, 20.0, 57)
        steps, y0, args, ref_kw = ode.make(oscillator, no_jac), np.array([1.0, 0.0]), None, {}
        fun = lambda t, y: [y[1], -y[0]]  # noqa: E731
    else:
        t_eval = np.linspace(0.0, 10.0, 57)
        steps, y0, args = ode.make(probe, probe_jac), np.array([1.0]), np.array([1e6])
        fun = lambda t, y: -1e6 * (y - np.cos(t)) - np.sin(t)  # noqa: E731
        ref_kw = {"jac": lambda t, y: np.array([[-1e6]])}
    atol = np.full(y0.size, 1e-11)
    Y, n_steps, nfev, status = steps.solve(ode.METHODS[method], 0.0, y0, t_eval, args, 1e-8, atol, 100000)
    assert status == ode.SUCCESS
    ref = solve_ivp(fun, (0.0, t_eval[-1]), y0, method=method, rtol=1e-8, atol=1e-11, **ref_kw)
    dense = solve_ivp(fun, (0.0, t_eval[-1]), y0, method=method, rtol=1e-8, atol=1e-11, t_eval=t_eval, **ref_kw)
    assert n_steps == len(ref.t) - 1
    np.testing.assert_allclose(Y.T, dense.y, rtol=0, atol=1e-12 if method == "DOP853" else 1e-9)
    # The exact solution: DOP853's interpolant is of order 7; Radau's is cubic over steps of ~0.5 s of a stiff
    # solve (measured 1.3e-3 between step ends, as scipy's).
    np.testing.assert_allclose(Y[:, 0], np.cos(t_eval), rtol=0, atol=1e-6 if method == "DOP853" else 3e-3)


@numba.njit
def kepler(x, args):
    return x - args[0] * math.sin(x) - args[1]


@numba.njit
def bowl(x, args):
    return (x - args[0]) ** 2 + math.cos(3.0 * x) * 0.01


def test_brentq_and_bounded_min_equal_scipys():
    """Kepler's equation E - e sin E = M (e 0.3, M 1.2) and a bumpy bowl on [0, 5]: the root equals scipy's
    brentq (same xtol, rtol 4 eps) to 1e-15 and has residual below 1e-14, and so does ``bracketed`` given the ends'
    values; the minimiser returns scipy's bounded-Brent minimum to 1e-12 (xatol 1e-12)."""
    args = np.array([0.3, 1.2])
    kepler_roots = ode.roots(kepler)  # in the test: a screen's child builds it from the mutated factory
    root = kepler_roots.brentq(0.0, math.pi, 1e-15, args)
    assert root == pytest.approx(brentq(lambda x: x - 0.3 * math.sin(x) - 1.2, 0.0, math.pi, xtol=1e-15),
                                 abs=1e-15)
    assert abs(kepler(root, args)) < 1e-14
    ends = kepler(0.0, args), kepler(math.pi, args)
    assert kepler_roots.bracketed(0.0, math.pi, *ends, 1e-15, args) == root
    x, fx = ode.roots(bowl).bounded_min(0.0, 5.0, 1e-12, np.array([2.0]))
    ref = minimize_scalar(lambda x: (x - 2.0) ** 2 + math.cos(3.0 * x) * 0.01, bounds=(0.0, 5.0),
                          method="bounded", options={"xatol": 1e-12})
    assert x == pytest.approx(ref.x, abs=1e-12) and fx == pytest.approx(ref.fun, abs=1e-14)


def counted(fdf):
    """fdf with its evaluations counted in ``calls``."""
    calls = []

    def counting(x, args):
        calls.append(x)
        return fdf(x, args)
    return counting, calls


def kepler_and_rate(x, args):
    return x - args[0] * math.sin(x) - args[1], 1.0 - args[0] * math.cos(x)


def arctan_and_rate(x, args):
    """sign atan(x - root) (args: root, sign): Newton from far off overshoots any bracket."""
    return args[1] * math.atan(x - args[0]), args[1] / (1.0 + (x - args[0]) ** 2)


def cube_and_rate(x, args):
    """(x - root)^3 (args: root): a triple root, where Newton only thirds the error each step."""
    return (x - args[0]) ** 3, 3.0 * (x - args[0]) ** 2


def inside_the_brackets(calls, fdf, args, a, b):
    """Whether every evaluation lies strictly inside the bracket the ones before it left (by their signs)."""
    bracket, a_negative = [a, b], fdf(a, args)[0] < 0.0
    for x in calls:
        if not min(bracket) < x < max(bracket):
            return False
        bracket[0 if (fdf(x, args)[0] < 0.0) == a_negative else 1] = x
    return True


def wavy_and_rate(x, args):
    """x - r + c sin(k x) (args: r, c, k): with c k > 1 its slope changes sign, and Newton's step can leave a
    bracket by less than half the step before."""
    r, c, k = args
    return x - r + c * math.sin(k * x), 1.0 + c * k * math.cos(k * x)


def test_newton_finds_the_bracketed_root_in_fewer_evaluations_than_brent():
    """The safeguarded Newton root finder on Kepler's equation E - e sin E = M returns scipy's brentq root to
    1e-15 in at most 5 evaluations of f and f', fewer than brentq's on the same bracket (which starts from the
    ends' values too). From far off (atan, bracket [-10, 30] either way round, where Newton's step from the
    secant point leaves the bracket) it starts at the secant point of the ends, evaluates only strictly inside
    the bracket left by the evaluations before, and reaches the root within the tolerance in fewer than 60
    evaluations; on a triple root (Newton slows to a third per step; from either end, with f(a) below 1 too)
    within 90, and to 1e-16 near 1e-6, where the relative part of the tolerance is 1e-21; where the slope
    changes sign in the bracket (a wavy f) it finds one of the roots there, again only inside the brackets; an end
    where f is zero is the root, with no evaluation."""
    for e, mean, a, b in ((0.3, 1.2, 0.0, math.pi), (0.9, 0.01, 0.0, math.pi), (0.99, 3.0, 0.0, math.pi),
                          (0.3, 1.2, 0.5, 2.5)):
        fdf, calls = counted(kepler_and_rate)
        ends = kepler_and_rate(a, (e, mean))[0], kepler_and_rate(b, (e, mean))[0]
        root = newton.bracketed_root(fdf)(a, b, *ends, 1e-15, (e, mean))
        brent_calls = []
        expected = brentq(lambda x: brent_calls.append(x) or x - e * math.sin(x) - mean, a, b, xtol=1e-15)
        assert root == pytest.approx(expected, abs=1e-15)
        assert len(calls) <= 5 and len(calls) < len(brent_calls) - 2
    for a, b, sign in ((-10.0, 30.0, 1.0), (30.0, -10.0, 1.0), (-10.0, 30.0, -1.0), (-2.0, 30.0, 1.0)):
        fdf, calls = counted(arctan_and_rate)
        fa, fb = sign * math.atan(a - 0.3), sign * math.atan(b - 0.3)
        root = newton.bracketed_root(fdf)(a, b, fa, fb, 1e-13, (0.3, sign))
        assert abs(root - 0.3) < 1e-13 and len(calls) < 60
        assert calls[0] == pytest.approx(a + (b - a) * fa / (fa - fb), rel=1e-15)  # the chord's zero
        assert inside_the_brackets(calls, arctan_and_rate, (0.3, sign), a, b)
    for a, b, root_at, xtol, error in ((-1.0, 2.0, 0.3, 1e-12, 1e-12), (0.9, -1.0, 0.3, 1e-12, 1e-12),
                                       (-1.0, 2.0, 1e-6, 1e-17, 1e-16)):
        fdf, calls = counted(cube_and_rate)
        root = newton.bracketed_root(fdf)(a, b, (a - root_at) ** 3, (b - root_at) ** 3, xtol, (root_at,))
        assert abs(root - root_at) < error and len(calls) <= 90  # bisection alone: 42 halvings to 1e-12
        assert inside_the_brackets(calls, cube_and_rate, (root_at,), a, b)
    for args, a, b in (((-0.34, 0.68, 11.7), -3.0, 1.3), ((-0.63, 0.19, 8.9), -0.8, 2.4)):
        fdf, calls = counted(wavy_and_rate)
        root = newton.bracketed_root(fdf)(a, b, wavy_and_rate(a, args)[0], wavy_and_rate(b, args)[0], 1e-12, args)
        assert min(a, b) < root < max(a, b) and abs(wavy_and_rate(root, args)[0]) < 1e-11
        assert inside_the_brackets(calls, wavy_and_rate, args, a, b)
    fdf, calls = counted(arctan_and_rate)
    assert newton.bracketed_root(fdf)(0.3, 2.0, 0.0, 1.0, 1e-12, (0.3, 1.0)) == 0.3
    assert newton.bracketed_root(fdf)(-1.0, 0.3, -1.0, 0.0, 1e-12, (0.3, 1.0)) == 0.3
    assert calls == []


def test_compiled_newton_is_the_python_one_bit_for_bit():
    """``brent.newton`` compiles the same function: on Kepler's equation, its root equals the Python one's
    exactly, from several brackets and tolerances."""
    compiled = brent.newton(numba.njit(kepler_and_rate))
    python = newton.bracketed_root(kepler_and_rate)
    for e, mean, b, xtol in ((0.3, 1.2, math.pi, 1e-15), (0.9, 0.01, 2.0, 1e-6), (0.99, 3.0, 3.5, 1e-12)):
        ends = kepler_and_rate(0.0, (e, mean))[0], kepler_and_rate(b, (e, mean))[0]
        assert compiled(0.0, b, *ends, xtol, np.array([e, mean])) == python(0.0, b, *ends, xtol, (e, mean))


# --------------------------------------------------------------------------- a generated module end to end


def _rotor_boom():
    """The bundled rotor boom: parameters (13,), initial state (4,), the run's free response (times, q)."""
    scene = symmech.load(tomllib.loads((scenes_folder() / "smm_rotor_boom.toml").read_text()))
    table = scene.run().tables["free_response"]
    m = scene.setup.m
    p = np.array([m.parameters[name].value for name, _, _ in smm_rotor_boom.PARAMS])
    ini = scene.resolved["initial"]
    y0 = np.concatenate([ini["q"], ini["qdot"] or np.zeros(len(ini["q"]))])
    return p, y0, table.data[:, 0], table.data[:, 1:]


@pytest.mark.slow  # compiles the toolkit for the module in each process (~23 s of CPU)
@pytest.mark.parametrize("method, rtol, tol", [("DOP853", 1e-11, 1e-9), ("Radau", 1e-9, 1e-8)])
def test_integrate_generated_module_equals_solve_ivp_and_the_exact_response(method, rtol, tol):
    """The rotor boom's damped free response, compiled end to end (generated rhs, Radau with the generated
    jac), at the run's output times: within tol of the run's exact matrix exponential (as solve_ivp is in
    test_dynamics_rhs); within 1e-10 (DOP853, in scipy's accepted steps) / tol (Radau, within 2 % of scipy's
    steps) of solve_ivp on the numpy rhs at the same times, relative to each state's largest value (measured
    3e-11 and 3e-10: the numba and LAPACK solves of the mass matrix round differently)."""
    p, y0, t, q_run = _rotor_boom()
    atol = rtol * 1e-3 * np.abs(y0).max()
    sol = ode.integrate("smm_rotor_boom", p, y0, t, t0=t[0], method=method, rtol=rtol, atol=atol)
    implicit = {"jac": smm_rotor_boom.jac} if method == "Radau" else {}
    ref = solve_ivp(smm_rotor_boom.rhs, (t[0], t[-1]), y0, method=method, t_eval=t, args=(p,), rtol=rtol,
                    atol=atol, **implicit)
    steps = solve_ivp(smm_rotor_boom.rhs, (t[0], t[-1]), y0, method=method, args=(p,), rtol=rtol, atol=atol,
                      **implicit)
    n = q_run.shape[1]
    assert sol.y.shape == (2 * n, t.size)
    if method == "DOP853":
        assert sol.steps == len(steps.t) - 1
    else:  # the Newton iteration's convergence rate steers the step: round-off moves it (measured 2483 / 2457)
        assert sol.steps == pytest.approx(len(steps.t) - 1, rel=0.02)
    relative = np.abs(sol.y - ref.y).max(axis=1) / np.abs(ref.y).max(axis=1)
    assert np.all(relative < (1e-10 if method == "DOP853" else tol))
    np.testing.assert_array_less(np.abs(sol.y[:n].T - q_run).max(axis=0), tol * np.abs(q_run).max(axis=0))


@pytest.mark.slow  # compiles its own solver closures (not cacheable across processes, numerics/ode.py)
def test_integrate_radau_with_the_generated_jac_on_a_stiff_boom():
    """The rotor boom with the drive suspension's viscosity mu3 raised 1e4 times: a mode decaying at
    3.6e4 1/s beside the 11 rad/s oscillation (eigenvalues of the generated jac). Radau with the generated jac
    needs under a tenth of DOP853's steps (measured 921 against 11399, as scipy's) and agrees with DOP853 at
    21 requested times to 1e-6 of each state's largest value (both at rtol 1e-8; measured 6e-10 in the
    coordinates, 3.5e-7 in the rate of the stiff one), and with scipy's Radau on the numpy rhs and jac to
    1e-6. DOP853 over 400 s is refused at the default step budget (a million steps, ~16 s)."""
    p, y0, _, _ = _rotor_boom()
    p[12] *= 1e4
    assert np.linalg.eigvals(smm_rotor_boom.jac(0.0, y0, p)).real.min() < -3e4
    t = np.linspace(0.0, 2.0, 21)
    stiff = ode.integrate("smm_rotor_boom", p, y0, t, method="Radau", rtol=1e-8, atol=1e-14)
    dop = ode.integrate("smm_rotor_boom", p, y0, t, method="DOP853", rtol=1e-8, atol=1e-14)
    ref = solve_ivp(smm_rotor_boom.rhs, (0.0, 2.0), y0, method="Radau", t_eval=t, args=(p,), rtol=1e-8,
                    atol=1e-14, jac=smm_rotor_boom.jac)
    assert stiff.steps < dop.steps / 10
    scale = np.abs(dop.y).max(axis=1)
    assert np.all(np.abs(stiff.y - dop.y).max(axis=1) < 1e-6 * scale)
    assert np.all(np.abs(stiff.y - ref.y).max(axis=1) < 1e-6 * scale)
    # DOP853's step is held at its stability limit (11399 steps for 2 s): 400 s would take over two million, past
    # the default budget of a million steps, which the refusal names
    with pytest.raises(SymmechError, match="^ode: DOP853 on smm_rotor_boom: 1000000 steps did not reach t = 400 s$"):
        ode.integrate("smm_rotor_boom", p, y0, [400.0], method="DOP853", rtol=1e-8, atol=1e-14)


@pytest.mark.slow  # compiles its own solver closures (not cacheable across processes, numerics/ode.py)
def test_integrate_refuses_bad_requests():
    """An unknown method, no times or decreasing ones and a step budget too small are errors, not silent results;
    the last names the end it did not reach, for all the times or the last alone, whether the parameters and atol
    are floats or exact rationals (Fractions, an object array to numpy: read as the floats they equal, not handed
    to the compiled solver as objects)."""
    p, y0, t, _ = _rotor_boom()
    with pytest.raises(SymmechError, match="method 'RK45'"):
        ode.integrate("smm_rotor_boom", p, y0, t, method="RK45")
    with pytest.raises(SymmechError, match="increasing"):
        ode.integrate("smm_rotor_boom", p, y0, t[::-1])
    with pytest.raises(SymmechError, match="non-empty"):
        ode.integrate("smm_rotor_boom", p, y0, t[:0])
    end = f"ode: DOP853 on smm_rotor_boom: 3 steps did not reach t = {t[-1]:g} s"
    # a single output time is a request like any other (it reaches the step budget)
    for times, params, atol in [(t, p, 1e-10), (t[-1:], p, 1e-10), (t, [Fraction(x) for x in p], 1e-10),
                                (t, p, Fraction(1, 10**10))]:
        with pytest.raises(SymmechError) as err:
            ode.integrate("smm_rotor_boom", params, y0, times, atol=atol, max_steps=3)
        assert str(err.value) == end


CACHED_CALLER = '''
import numba, numpy as np
from symmech.numerics import ode

@numba.njit(cache=True)
def decay(t, y, args, out):
    out[0] = -args[0] * y[0]

_advance = ode.steppers(decay, decay).dop_advance

@numba.njit(cache=True)
def caller(y):
    K, f = np.empty((ode.DOP_EXTENDED, 1)), -y
    return _advance(0.0, y, f, 0.1, 1.0, np.array([1.0]), 1e-6, np.array([1e-9]), K)[1][0]
'''


@pytest.mark.slow  # compiles its own solver closures (not cacheable across processes, numerics/ode.py)
def test_a_cached_caller_of_the_toolkit_loads_from_the_cache_in_a_fresh_process(tmp_path):
    """The design decision of numerics.ode (its docstring): a cached jitted function calling the toolkit's closures
    is compiled once and served from numba's cache in the next process (no miss, one hit), with the same value,
    e^-0.1 to the step's tolerance."""
    (tmp_path / "cached_caller.py").write_text(CACHED_CALLER)
    code = ("import cached_caller as c, numpy as np; v = c.caller(np.array([1.0])); "
            "print(v, sum(c.caller.stats.cache_hits.values()), sum(c.caller.stats.cache_misses.values()))")
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache"), "PYTHONPATH": str(tmp_path)}
    runs = [subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
            .stdout.split() for _ in range(2)]
    assert runs[0][1:] == ["0", "1"] and runs[1][1:] == ["1", "0"]
    assert float(runs[1][0]) == float(runs[0][0]) == pytest.approx(math.exp(-0.1), abs=1e-6)


# --------------------------------------------------------------------------- events


@numba.njit
def spring(t, y, args, out):
    """x'' = -w^2 x as y = (x, x'), w = args[0]."""
    out[0], out[1] = y[1], -args[0] ** 2 * y[0]


@numba.njit
def spring_events(t, y, args, g):
    """g0 = x (zero crossings), g1 = x' + w / 2 (the velocity passing -w / 2)."""
    g[0], g[1] = y[0], y[1] + args[0] / 2


@pytest.mark.slow  # compiles its own solver closures (not cacheable across processes, numerics/ode.py)
@pytest.mark.parametrize("method", ["DOP853", "Radau"])
def test_events_of_an_oscillator_at_its_zero_crossings_and_as_solve_ivp_finds_them(method):
    """x = cos(w t): zeros at (j + 1/2) pi / w within 1e-9 s (rtol 1e-10; measured 3e-11, the solve's phase
    error); the falling ones only (direction -1) at (2j + 1/2) pi / w; DOP853's equal solve_ivp's to 1e-12 s
    (the same steps and interpolant; measured 2e-15). A terminal x' = -w/2 (first at t = pi / (6 w)) stops the
    solve there: the rows of t_eval after it stay NaN, its state is (cos, -w sin) at pi / (6 w) to 1e-8."""
    w, t_eval = 3.0, np.linspace(0.0, 5.0, 11)
    solve = ode.make(spring, no_jac, spring_events).solve_events
    run = lambda direction, terminal: solve(ode.METHODS[method], 0.0, np.array([1.0, 0.0]), t_eval,  # noqa: E731
                                            np.array([w]), 1e-10, np.full(2, 1e-12), 100000, np.array(direction),
                                            np.array(terminal))
    Y, _, _, status, filled, at, which, states = run([0.0, 1.0], [False, False])
    assert status == ode.SUCCESS and filled == t_eval.size and not np.isnan(Y).any()
    zeros = at[which == 0]
    np.testing.assert_allclose(zeros, (np.arange(5) + 0.5) * np.pi / w, rtol=0, atol=1e-9)
    np.testing.assert_allclose(states[which == 0][:, 0], 0.0, atol=1e-9)
    if method == "DOP853":
        ref = solve_ivp(lambda t, y: [y[1], -w * w * y[0]], (0.0, 5.0), [1.0, 0.0], method="DOP853", rtol=1e-10,
                        atol=1e-12, events=lambda t, y: y[0])
        np.testing.assert_allclose(zeros, ref.t_events[0], rtol=0, atol=1e-12)
    falling = run([-1.0, 1.0], [False, False])
    np.testing.assert_allclose(falling[5][falling[6] == 0], (2 * np.arange(3) + 0.5) * np.pi / w, atol=1e-9)
    Y, _, _, status, filled, at, which, states = run([0.0, 0.0], [False, True])
    t_stop = np.pi / (6 * w)
    assert status == ode.TERMINATED and list(which) == [1] and at[0] == pytest.approx(t_stop, abs=1e-9)
    np.testing.assert_allclose(states[0], [math.cos(w * t_stop), -w * math.sin(w * t_stop)], atol=1e-8)
    assert filled == 1 and not np.isnan(Y[0]).any() and np.isnan(Y[1:]).all()


@pytest.mark.slow  # compiles the toolkit for the grain flight (not cacheable across processes, numerics/ode.py)
def test_integrate_ends_a_grain_flight_at_contact():
    """The grain flight module declares its terminal contact event. Spinning about the plane normal over a
    still plane, the gap is rz - c and the contact time is the free-flight closed form
    (vz + sqrt(vz^2 + 2 g (z0 - c))) / g, within 1e-12 s; tumbling over the vibrating plane, the contact
    and the states at t_eval equal solve_ivp's with the module's events as a terminal falling event to 1e-12
    s and 1e-12 of each state's largest value (the same steps; measured 2e-16 s, 3e-13)."""
    from symmech.generated import grain_motion as gm

    a, b, c, mass = 2e-3, 1.4e-3, 1e-3, 1e-5
    inertia = [mass * (b * b + c * c) / 5, mass * (a * a + c * c) / 5, mass * (a * a + b * b) / 5]
    g, t = 9.81, np.linspace(0.0, 1.0, 101)
    still = np.array([0.0, 0.0, -g, 0.0, 100.0, 0.0, 0.0, 0.0, 1.0, *inertia, a, b, c])
    spin = np.array([0.0, 0.0, 0.05, 0.3, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 200.0])
    sol = ode.integrate("grain_motion", still, spin, t, rtol=1e-10, atol=1e-12)
    t_contact = (1.0 + math.sqrt(1.0 + 2 * g * (0.05 - c))) / g
    assert sol.terminated_by == "contact" and sol.t_events["contact"] == pytest.approx([t_contact], abs=1e-12)
    assert sol.y_events["contact"][0, 2] == pytest.approx(c, abs=1e-12)
    assert np.array_equal(sol.t, t[t <= t_contact]) and sol.y.shape == (13, sol.t.size)
    shaking = np.array([0.0, -1.2, -9.73, 0.5e-3, 2 * np.pi * 25, 0.3, 0.0, 0.6, 0.8, *inertia, a, b, c])
    q = np.array([0.9, 0.1, -0.3, 0.2]) / np.linalg.norm([0.9, 0.1, -0.3, 0.2])
    tumbling = np.concatenate([[0.0, 0.0, 0.05, 0.4, 0.1, 1.0], q, [40.0, -25.0, 60.0]])
    sol = ode.integrate("grain_motion", shaking, tumbling, t, rtol=1e-10, atol=1e-12)

    def contact(t, y, p):
        return gm.events(t, y, p)[0]
    contact.terminal, contact.direction = True, -1
    ref = solve_ivp(gm.rhs, (0.0, 1.0), tumbling, method="DOP853", t_eval=t, args=(shaking,), rtol=1e-10,
                    atol=1e-12, events=contact)
    assert ref.status == 1 and sol.terminated_by == "contact"
    np.testing.assert_allclose(sol.t_events["contact"], ref.t_events[0], rtol=0, atol=1e-12)
    assert np.array_equal(sol.t, ref.t)
    scale = np.abs(ref.y).max(axis=1, keepdims=True)
    assert np.all(np.abs(sol.y - ref.y) <= 1e-12 * scale)
    assert np.all(np.abs(sol.y_events["contact"] - ref.y_events[0]) <= 1e-12 * scale.T)
