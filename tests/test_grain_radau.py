"""The Radau IIA stepper of the compiled grain (symmech.grain.compiled, scipy's radau.py ported to numba) on
the Prothero-Robinson equation y' = -lam (y - cos t) - sin t, y(0) = 1, whose solution is cos t for every lam,
and the analytic Jacobian of the slip it integrates stiff slips with."""
import math

import numpy as np
import pytest

from test_grain_hard_cases import CROP, sweep_grain
from symmech.grain import compiled, flight

pytestmark = pytest.mark.compiled_engine  # ordered last, after the session's background build (conftest.py)


def _buffers(n):
    """Jacobian, LU factors (real, complex), pivots and interpolant of an n-dimensional solve."""
    return (np.empty((n, n)), np.empty((n, n)), np.empty(n, dtype=np.int64), np.empty((n, n), dtype=np.complex128),
            np.empty(n, dtype=np.int64), np.empty((1, 4 * n)))


def adaptive(lam, t_end, rtol, atol):
    """Accepted steps and the largest error |y - cos t| at their ends of an adaptive solve."""
    sp, y, t, f = np.array([lam]), np.array([1.0]), 0.0, np.empty(1)
    compiled._rhs(compiled.PROBE, t, y, sp, f)
    J, LUr, pr, LUc, pc, Q = _buffers(1)
    st = compiled._radau_start(compiled.PROBE, t, y, f, t_end, sp, rtol, np.array([atol]), J)
    steps, err = 0, 0.0
    while t < t_end:
        t, y, f, ok = compiled._radau_step(compiled.PROBE, t, y, f, t_end, sp, rtol, np.array([atol]), st, J,
                                           LUr, pr, LUc, pc, Q)
        assert ok
        steps += 1
        err = max(err, abs(y[0] - math.cos(t)))
    return steps, err


def fixed(lam, n, t_end=1.0):
    """|y(t_end) - cos t_end| after n equal steps (one collocation solve each, exact Jacobian)."""
    sp, y, f, h = np.array([lam]), np.array([1.0]), np.empty(1), t_end / n
    J, LUr, pr, LUc, pc, Q = _buffers(1)
    J[0, 0] = -lam
    st = np.zeros(compiled.N_RADAU)  # no previous step: the Newton solve starts from zero increments
    st[compiled.R_JAC_CURRENT] = 1.0
    for k in range(n):
        compiled._rhs(compiled.PROBE, k * h, y, sp, f)
        ok, _, _, Z = compiled._radau_try(compiled.PROBE, k * h, y, f, h, sp, 1e-12, np.array([1e-12]), st, J,
                                          LUr, pr, LUc, pc, Q)
        assert ok
        y = y + Z[2]
    return abs(y[0] - math.cos(t_end))


@pytest.mark.parametrize("rtol", [1e-4, 1e-6, 1e-8])
def test_stiff_prothero_robinson_within_the_tolerance(rtol):
    """lam = 1e6 over 10 s (stiffness ratio 1e7 per unit time): the error stays below 2 rtol at every step
    end (the equation contracts at rate lam, so the global error is about the last local error; measured
    0.6 rtol at rtol 1e-6), in fewer than 100 steps (an explicit method would need ~1e7)."""
    steps, err = adaptive(1e6, 10.0, rtol, 1e-3 * rtol)
    assert err <= 2 * rtol
    assert steps < 100


def test_the_port_takes_scipys_steps():
    """Same algorithm as scipy's Radau with the same (exact) Jacobian: the same number of accepted steps and
    the same largest error to 1e-6 relative (round-off through the step-size control)."""
    from scipy.integrate import solve_ivp
    steps, err = adaptive(1e6, 10.0, 1e-6, 1e-9)
    ref = solve_ivp(lambda t, y: -1e6 * (y - np.cos(t)) - np.sin(t), (0.0, 10.0), [1.0], method="Radau",
                    rtol=1e-6, atol=1e-9, jac=lambda t, y: np.array([[-1e6]]))
    assert steps == len(ref.t) - 1
    assert err == pytest.approx(np.max(np.abs(ref.y[0] - np.cos(ref.t))), rel=1e-6)


@pytest.mark.parametrize("lam, order", [(1.0, 5.0), (1e6, 3.0)])
def test_empirical_order_with_fixed_steps(lam, order):
    """Fixed steps h = 1/4 ... 1/64 over [0, 1], the slope of log error against log h: order 5 (2s - 1,
    Radau IIA with s = 3) on the non-stiff equation; on the stiff one (h lam >= 1.6e4) the order drops to the
    stage order 3 (Prothero-Robinson order reduction, Hairer & Wanner II, IV.15). Measured 4.99 and 3.05."""
    hs = [2.0**-k for k in range(2, 7)]
    errors = [fixed(lam, 2**k) for k in range(2, 7)]
    assert np.polyfit(np.log(hs), np.log(errors), 1)[0] == pytest.approx(order, abs=0.15)


def test_slip_jacobian_equals_central_differences():
    """The analytic Jacobian of the slip (13 x 13) on the crop grain slipping at 1 cm/s while turning at
    3 rad/s: every row within 1e-7 of its largest entry of central differences (step 1e-6 of the state,
    truncation ~1e-12, measured 5e-9: round-off of the differences). The orientation columns of the slip
    rows (the contact point turning with q) are mu n |w x dR/dq| / |s| (1.9 m/s^2 here) and grow as 1 / |s|
    like the stiff rate itself: a Jacobian without them would not do near v_stop."""
    sc = sweep_grain(CROP, 0.6e-3, 18.0, 0.12)
    Q0 = flight.rotation_matrix(sc.start.q)
    p = compiled.pack(sc.model, sc.numerics)
    sp = compiled._slide_params(p, Q0, compiled._offset(p, Q0), sc.model.mu)
    z = np.zeros(13)
    z[2:4], z[4:7], z[7:11] = (0.01, 0.004), (0.0, 0.0, 3.0), sc.start.q
    t = 0.013
    J = np.empty((13, 13))
    compiled._slip_jac(t, z, sp, J)
    fd, up, down = np.empty((13, 13)), np.empty(13), np.empty(13)
    for j in range(13):
        d = 1e-6 * max(abs(z[j]), 1e-2)
        zp, zm = z.copy(), z.copy()
        zp[j] += d
        zm[j] -= d
        compiled._slide_rhs(t, zp, sp, False, up)
        compiled._slide_rhs(t, zm, sp, False, down)
        fd[:, j] = (up - down) / (2 * d)
    assert sp[compiled.S_ANISO] == 1.0 and np.abs(J[2:4, 7:11]).max() > 1.0
    assert np.all(np.abs(J - fd).max(axis=1) <= 1e-7 * np.abs(fd).max(axis=1))


def test_tableau_is_scipys_bit_for_bit():
    """The Radau IIA constants written out in compiled.py (no scipy import at run time) are those of
    scipy's ``_ivp/radau.py``, to the last bit (an independent transcription of Hairer & Wanner's tableau)."""
    from scipy.integrate._ivp import radau

    for ours, theirs in ((compiled.RADAU_C, radau.C), (compiled.RADAU_E[0], radau.E), (compiled.RADAU_T, radau.T),
                         (compiled.RADAU_TI, radau.TI), (compiled.RADAU_PT, radau.P.T)):
        assert ours.shape == theirs.shape and np.array_equal(ours, theirs)
    assert compiled.MU_REAL == radau.MU_REAL and compiled.MU_COMPLEX == radau.MU_COMPLEX
