"""The Radau IIA tableau of order 5 and scipy's step-control constants (``scipy.integrate._ivp.radau``), without
numba: the compiled toolkit (:mod:`symmech.numerics.radau`) steps with them, and ``symmech export`` writes them into
the exported C (``radau_tableau.h``), so both integrators take scipy's steps.

``C`` (3,) the nodes; ``E`` (1, 3) the embedded error estimator; the tableau A = T diag(MU_REAL, MU_COMPLEX,
conj) TI with ``T``, ``TI`` (3, 3); ``PT`` (3, 3) the dense-output matrix transposed (Q = PT Z).
"""
from __future__ import annotations

import numpy as np

S6 = 6.0 ** 0.5
C = np.array([(4.0 - S6) / 10.0, (4.0 + S6) / 10.0, 1.0])
E = np.array([[-13.0 - 7.0 * S6, -13.0 + 7.0 * S6, -1.0]]) / 3.0
MU_REAL = 3.0 + 3.0 ** (2.0 / 3.0) - 3.0 ** (1.0 / 3.0)
MU_COMPLEX = complex(3.0 + 0.5 * (3.0 ** (1.0 / 3.0) - 3.0 ** (2.0 / 3.0)),
                     -0.5 * (3.0 ** (5.0 / 6.0) + 3.0 ** (7.0 / 6.0)))
T = np.array([[0.09443876248897524, -0.14125529502095421, 0.03002919410514742],
              [0.25021312296533332, 0.20412935229379994, -0.38294211275726192], [1.0, 1.0, 0.0]])
TI = np.array([[4.17871859155190428, 0.32768282076106237, 0.52337644549944951],
               [-4.17871859155190428, -0.32768282076106237, 0.47662355450055044],
               [0.50287263494578682, -2.57192694985560522, 0.59603920482822492]])
PT = np.array([[13.0 / 3.0 + 7.0 * S6 / 3.0, -23.0 / 3.0 - 22.0 * S6 / 3.0, 10.0 / 3.0 + 5.0 * S6],
               [13.0 / 3.0 - 7.0 * S6 / 3.0, -23.0 / 3.0 + 22.0 * S6 / 3.0, 10.0 / 3.0 - 5.0 * S6],
               [1.0 / 3.0, -8.0 / 3.0, 10.0 / 3.0]]).T.copy()
NEWTON_MAXITER, MIN_FACTOR, MAX_FACTOR = 6, 0.2, 10.0
POWER = 1.0 / 4.0  # initial step of the order-3 error estimator
