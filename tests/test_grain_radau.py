"""The analytic Jacobian of the slip the compiled grain integrates stiff slips with (by numerics.ode's Radau IIA,
tested on its own in test_ode_toolkit.py)."""
import itertools

import numpy as np
import pytest

from test_grain_hard_cases import CROP, sweep_grain
from test_ode_toolkit import against_scipys_rule
from symmech.grain import flight
from symmech.numerics import ode, radau
from symmech.grain.motion_engine import driver as compiled, kinematics, slip, steppers
from symmech.grain.motion_engine.layouts import S_AT

pytestmark = [pytest.mark.slow, pytest.mark.compiled_engine]  # the engine's build: slow tier (conftest.py)


def test_slip_jacobian_equals_central_differences():
    """The analytic Jacobian of the slip (13 x 13) on the crop grain slipping at 1 cm/s while turning at
    3 rad/s: every row within 1e-7 of its largest entry of central differences (step 1e-6 of the state,
    truncation ~1e-12, measured 5e-9: round-off of the differences). The orientation columns of the slip
    rows (the contact point turning with q) are mu n |w x dR/dq| / |s| (1.9 m/s^2 here) and grow as 1 / |s|
    like the stiff rate itself: a Jacobian without them would not do near v_stop."""
    sc = sweep_grain(CROP, 0.6e-3, 18.0, 0.12)
    Q0 = flight.rotation_matrix(sc.start.q)
    p = compiled.pack(sc.model, sc.numerics)
    sp = slip.slide_params(p, Q0, kinematics.contact_offset(p, Q0), sc.model.mu)
    z = np.zeros(13)
    z[2:4], z[4:7], z[7:11] = (0.01, 0.004), (0.0, 0.0, 3.0), sc.start.q
    t = 0.013
    J = np.empty((13, 13))
    slip.slip_jac(t, z, sp, J)
    fd, up, down = np.empty((13, 13)), np.empty(13), np.empty(13)
    for j in range(13):
        d = 1e-6 * max(abs(z[j]), 1e-2)
        zp, zm = z.copy(), z.copy()
        zp[j] += d
        zm[j] -= d
        slip.slide_rhs(t, zp, sp, False, up)
        slip.slide_rhs(t, zm, sp, False, down)
        fd[:, j] = (up - down) / (2 * d)
    assert sp[S_AT.aniso] == 1.0 and np.abs(J[2:4, 7:11]).max() > 1.0
    assert np.all(np.abs(J - fd).max(axis=1) <= 1e-7 * np.abs(fd).max(axis=1))


def test_the_slips_radau_holds_the_step_after_a_newton_failure():
    """The grain's stiff slips take Hairer and Wanner's RADAU5 rule (``steppers``: ``hold_after_newton_failure``;
    the rule itself: test_ode_toolkit.py): the crop grain slipping at 1e-10 m/s without spin, 60 Radau steps at
    rtol 1e-9, each also taken from the same state by the toolkit's steppers of the same slip under scipy's rule
    (test_ode_toolkit.py's ``against_scipys_rule``): the cap acts after at least three of them."""
    sc = sweep_grain(CROP, 0.6e-3, 18.0, 0.12)
    Q0 = flight.rotation_matrix(sc.start.q)
    p = compiled.pack(sc.model, sc.numerics)
    sp = slip.slide_params(p, Q0, kinematics.contact_offset(p, Q0), sc.model.mu)
    z = np.zeros(13)
    z[2:4], z[7:11] = (1e-10, 0.0), sc.start.q
    t, rtol, atol, args = 0.013, 1e-9, np.full(13, 1e-12), (steppers.SLIP, sp)
    f = np.empty(13)
    steppers.rhs(t, z, args, f)
    J, LUr, pr, LUc, pc, Q = radau.radau_buffers(13)
    st = steppers.radau_start(t, z, f, 1.0, args, rtol, atol, J)
    steps = against_scipys_rule(steppers, ode.steppers(steppers.rhs, steppers.jac), t, z, f, 1.0, args, rtol, atol,
                                st, (J, LUr, pr, LUc, pc, Q))
    assert sum(capped for _, _, capped, _ in itertools.islice(steps, 60)) >= 3
