"""The right-hand sides of the compiled loop's integrations and :mod:`symmech.numerics.ode`'s steppers compiled for
them (closures: see that module's docstring): the torque-free rotation of a flight (``ROT``) and the sliding
contact (``SLIP``, ``STICK``), with the slip's Jacobian for Radau IIA. Radau holds its step after a Newton failure
(RADAU5's rule, :func:`symmech.numerics.radau.steppers`): near zero slip speed scipy's rule grows the step ten-fold
into the next failure (benchmarks/README.md, "The stiff slips' Radau holds its step after a Newton failure")."""
from __future__ import annotations

from symmech.numerics import dop853_tableau as tableau, ode
from symmech.numerics.jit import jit
from symmech.grain.motion_engine.kinematics import gm
from symmech.grain.motion_engine.layouts import INT, RO_AT
from symmech.grain.motion_engine.slip import slide_rhs, slip_jac

ROT, SLIP, STICK = INT(0), INT(1), INT(2)  # right-hand sides of the Dormand-Prince stepper
DOP_STAGES, DOP_EXTENDED, DOP_POWER, DOP_EXPONENT = tableau.STAGES, tableau.EXTENDED, tableau.POWER, tableau.EXPONENT


@jit
def rhs(t, y, args, out):
    """Right-hand side of the toolkit's steppers, args = (kind, data): ``ROT`` torque-free rotation y (layout
    ``ROTATION``), data = the principal inertia (3,); ``SLIP``/``STICK`` sliding, y the sliding vector (layout
    ``SLIDE_STATE``), data the sliding parameters (``SLIDE``)."""
    kind, data = args
    if kind == ROT:
        q, w = RO_AT.q, RO_AT.w
        qd = gm.quaternion_rate_scalar(y[q], y[q + 1], y[q + 2], y[q + 3], y[w], y[w + 1], y[w + 2])
        wd = gm.euler_equations_scalar(data[0], data[1], data[2], y[w], y[w + 1], y[w + 2])
        out[q:q + 4] = qd
        out[w:w + 3] = wd
    else:
        slide_rhs(t, y, data, kind == STICK, out)


@jit
def jac(t, y, args, J):
    """Jacobian d rhs / d y (N_SLIDING, N_SLIDING) into J of the slip (analytic), args = (kind, sp): the only stiff one."""
    slip_jac(t, y, args[1], J)


# The generic DOP853 and Radau IIA code of numerics.ode, compiled for these right-hand sides (Radau: RADAU5's hold).
_steps = ode.steppers(rhs, jac, hold_after_newton_failure=True)
first_step, dop_advance, dop_dense = _steps.first_step, _steps.dop_advance, _steps.dop_dense
radau_start, radau_step = _steps.radau_start, _steps.radau_step

