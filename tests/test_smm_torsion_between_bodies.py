"""A preloaded torsion spring between two moving bodies (forms._twist_hessian with turns on both sides): body A turned
by a about x, body B by b about z, so R_A^T R_B = Rx(-a) Rz(b); its second-order twist against a finite-difference
Hessian of n . rotvec(Rx(-a) Rz(b)) from scipy's Rotation, and c = k (dtwist)(dtwist)^T + M0 d2twist."""
import numpy as np
from scipy.spatial.transform import Rotation

from symmech.smm import numeric

from smm_helpers import fd_hessian, mech

K, M0 = 20.0, 3.0  # [N m/rad], [N m]
N = np.array([0.0, 0.6, 0.8])


def twist(q):
    return N @ (Rotation.from_rotvec([-q[0], 0, 0]) * Rotation.from_rotvec([0, 0, q[1]])).as_rotvec()


def test_the_twist_between_two_turning_bodies_has_their_cross_term():
    m = mech({
        "coordinates": [{"name": "a", "type": "angle", "axis": [1, 0, 0]},
                        {"name": "b", "type": "angle", "axis": [0, 0, 1]}],
        "points": [{"name": "O", "at": [0, 0, 0]},
                   {"name": "CA", "from": "O", "vector": [0.1, 0.2, -0.5], "turns": ["a"]},
                   {"name": "CB", "from": "O", "vector": [0.3, -0.1, 0.2], "turns": ["b"]},
                   {"name": "W", "at": [1.1, 0.2, -0.5]}],
        "bodies": [{"name": "A", "mass": 1.0, "inertia": [0.1, 0.2, 0.3], "com": "CA", "turns": ["a"]},
                   {"name": "B", "mass": 2.0, "inertia": [0.2, 0.1, 0.3], "com": "CB", "turns": ["b"]}],
        "torsion_springs": [{"name": "t", "bodies": ["A", "B"], "stiffness": K, "preload": M0, "axis": N.tolist()}],
        "springs": [{"name": "s", "ends": ["CA", "W"], "stiffness": 0.0}]})
    H = fd_hessian(twist, 2)
    assert abs(H[0, 1] - N[1] / 2) < 1e-6  # -n . (e_x x e_z) / 2 = n_y / 2: the pair of a turn of each body
    d = np.array([-N[0], N[2]])
    np.testing.assert_allclose(numeric.assemble(m).c.toarray(), K * np.outer(d, d) + M0 * H, rtol=0, atol=1e-6)
