"""The compiled loop's bookkeeping in numba: trajectory rows and warning rows appended to arrays that double
when full, their counts in the carry (layout :data:`layouts.CARRY`)."""
from __future__ import annotations

import numpy as np

from symmech.numerics.jit import jit
from symmech.grain.motion_engine.kinematics import rotation
from symmech.grain.motion_engine.layouts import C_AT, T_AT, TRAJECTORY_WIDTH, WARNING_WIDTH, WR_AT, X_AT


@jit
def record(rows, carry, y, regime):
    """Append the trajectory row (layout ``TRAJECTORY_ROW``) of state y (STATE.size,) in regime ``regime``."""
    n = int(carry[C_AT.rows])
    if n == rows.shape[0]:
        grown = np.empty((2 * n, TRAJECTORY_WIDTH))
        grown[:n] = rows
        rows = grown
    rows[n, T_AT.t:T_AT.q + 4] = y[X_AT.t:X_AT.q + 4]  # t, r, v, q: both in the state's order
    w = y[X_AT.w:X_AT.w + 3]
    if w[0] == 0.0 and w[1] == 0.0 and w[2] == 0.0:  # no spin (rotation off): no rotation matrix to build
        rows[n, T_AT.w:T_AT.w + 3] = 0.0
    else:
        rows[n, T_AT.w:T_AT.w + 3] = rotation(y[X_AT.q:X_AT.q + 4]) @ w
    rows[n, T_AT.regime] = regime
    carry[C_AT.rows] = n + 1
    return rows


@jit
def warn(warns, carry, code, a, b):
    """Append the warning row (code, a, b) (layout ``WARNING_ROW``)."""
    n = int(carry[C_AT.nwarn])
    if n == warns.shape[0]:
        grown = np.empty((2 * n, WARNING_WIDTH))
        grown[:n] = warns
        warns = grown
    warns[n, WR_AT.code], warns[n, WR_AT.a], warns[n, WR_AT.b] = code, a, b
    carry[C_AT.nwarn] = n + 1
    return warns

