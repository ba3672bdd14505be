"""The compiled grain engine's vectors and codes, shared by its loop (:mod:`symmech.grain.compiled_loop`)
and its Python side (:mod:`symmech.grain.compiled`): the parameter vector's layout, the carry vector's, the
regime, status and warning codes, and the limits both sides apply. No numba here."""
from __future__ import annotations

import numpy as np

from symmech.grain import motion, sliding

# Parameter vector layout.
P_AXES, P_MASS, P_INERTIA, P_G = 0, 3, 4, 7  # (3), (1), (3), (3)
P_AMP, P_OMEGA, P_PHASE, P_DIR = 10, 11, 12, 13  # surface vibration; direction (3)
P_LAW, P_EN, P_ET, P_MU_IMPACT, P_E, P_LAM, P_CHECK = 16, 17, 18, 19, 20, 21, 22
P_MU, P_ROTATION, P_TOL, P_SCAN, P_REST, P_MAX_IMPACTS, P_SAMPLE, P_PERIOD = 23, 24, 25, 26, 27, 28, 29, 30
N_PARAMS = 31
LAW_COULOMB, LAW_PRINTED = 0.0, 1.0

# Integer codes are numpy scalars, not Python ints: numba types a Python int constant passed to a jitted
# function as a literal and compiles that function once more for every such value (83 instead of 61 overloads).
INT = np.int64
FLIGHT, IMPACT, SLIDING = INT(0), INT(1), INT(2)  # regime codes, as motion.REGIMES
# Carry vector: the loop's own state between two calls.
C_REGIME, C_ON_PLANE, C_LANDINGS, C_IDLE, C_T_FLIGHT, C_T_SLIDING = 0, 1, 2, 3, 4, 5
C_WORK, C_IMPACTS, C_LAND_LOSS, C_SLIDE_LOSS, C_ROWS, C_NIMP, C_NWARN = 6, 7, 8, 9, 10, 11, 12
# Rocking contacts; accepted Radau steps of stiff slips; absolute energy at the start and at the end.
C_ROCKING, C_IMPLICIT, C_E_START, C_E_END = 13, 14, 15, 16
N_CARRY = 17
# Status of a call.
DONE, MORE, STALLED, SLIDE_STALLED, SLIDE_RHS, SLIDE_FAIL, ROT_FAIL = (INT(k) for k in range(7))
# Warning codes (rows: code, value, value).
W_MAX_IMPACTS, W_CHATTER, W_PRINTED_ENERGY, W_PRINTED_PULLS, W_PRINTED_RESIDUAL, W_ENERGY = (
    INT(k) for k in range(1, 7))
IMPACT_WIDTH = 31  # t, r, v before/after, w before/after, impulse, u before/after, ke, flags (4)

PHASES_PER_CALL = 2000
COLD_COMPILE_SECONDS = 80.0  # wall time of the first compile, idle machine: 78 s (benchmarks/bench_grain_compile.py)
ZENO_IMPACTS, ZENO_INTERVAL, MAX_IDLE_STEPS = motion.ZENO_IMPACTS, motion.ZENO_INTERVAL, motion.MAX_IDLE_STEPS
MAX_STALLED_EVENTS = sliding.MAX_STALLED_EVENTS
