"""Second derivatives of a point reached through chain vectors turned in different orders (spatial, so
through forms.chain_kinematics): v1 turned about x then y, v2 about y then x. Both orders land on the
same entry (a, b) of d2r/dq2, which must hold the sum e_x x (e_y x v1) + e_y x (e_x x v2); checked
through the gravity part of c against a finite-difference Hessian of the potential -m g d . r(q), with
r(q) = Rx(qa) Ry(qb) v1 + Ry(qb) Rx(qa) v2 from scipy's Rotation."""
import numpy as np
from scipy.spatial.transform import Rotation

from symmech.smm import numeric

from smm_helpers import mech

MASS, G = 2.0, 9.81                          # [kg], [m/s^2]
DOWN = np.array([-0.48, -0.64, -0.6])        # direction of gravity (unit)
V1 = np.array([0.5, 0.1, -0.5])              # [m]
V2 = np.array([0.2, -0.4, -0.3])             # [m]


def _rot(axis, q):
    return Rotation.from_rotvec(q * np.asarray(axis, dtype=float))


def potential(q):
    """-m g d . r [J] of the bob at r(q)."""
    rx, ry = _rot([1, 0, 0], q[0]), _rot([0, 1, 0], q[1])
    r = (rx * ry).apply(V1) + (ry * rx).apply(V2)
    return -MASS * G * DOWN @ r


def _two_orders():
    return mech({
        "coordinates": [{"name": "a", "type": "angle", "axis": [1, 0, 0]},
                        {"name": "b", "type": "angle", "axis": [0, 1, 0]}],
        "points": [{"name": "O", "at": [0, 0, 0]},
                   {"name": "P1", "from": "O", "vector": V1.tolist(), "turns": ["a", "b"]},
                   {"name": "P2", "from": "P1", "vector": V2.tolist(), "turns": ["b", "a"]}],
        "bodies": [{"name": "bob", "mass": MASS, "inertia": [0.1, 0.1, 0.1], "com": "P2"}],
        "gravity": {"g": G, "direction": DOWN.tolist()}})


def test_gravity_stiffness_sums_both_turn_orders():
    """c = d2(-m g d . r)/dq2 (no springs) against finite differences (h = 1e-4, error ~1e-7 J) to 1e-6.
    By hand, the mixed entry: e_x x (e_y x v1) = (0, v1_x, 0), e_y x (e_x x v2) = (v2_y, 0, 0), so
    c_ab = m g (0.48 v2_y + 0.64 v1_x) = 2.51136 N m (v1's order alone: 6.278; both reversed: 3.453)."""
    h = 1e-4
    H = np.empty((2, 2))
    for i in range(2):
        for j in range(2):
            ei, ej = np.eye(2)[i] * h, np.eye(2)[j] * h
            H[i, j] = (potential(ei + ej) - potential(ei - ej) - potential(-ei + ej)
                       + potential(-ei - ej)) / (4 * h * h)
    assert abs(H[0, 1] - MASS * G * 0.128) < 1e-6
    n = numeric.assemble(_two_orders())
    np.testing.assert_allclose(n.c.toarray(), H, rtol=0, atol=1e-6)
    np.testing.assert_allclose(n.c_gravity.toarray(), H, rtol=0, atol=1e-6)
