"""Spatial mechanisms, so through the term lists of forms.py: the second-order twist of a preloaded
torsion spring on compound rotations (forms._twist_hessian) against a finite-difference Hessian of
n . rotvec(Rx(qa) Rz(qb)) from scipy's Rotation; the result's coordinates, spring lengths and L_c rows
by hand; a torsion moment from the equilibrium conditions (5)."""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from symmech.smm import numeric
from symmech.smm.model import Effects

from smm_helpers import fd_hessian, mech

K, M0 = 20.0, 3.0          # [N m/rad], [N m]
N = np.array([0.0, 0.6, 0.8])


def twist(q):
    R = Rotation.from_rotvec([q[0], 0, 0]) * Rotation.from_rotvec([0, 0, q[1]])
    return N @ R.as_rotvec()


def _gimbal():
    return mech({
        "coordinates": [{"name": "a", "type": "angle", "axis": [1, 0, 0]},
                        {"name": "b", "type": "angle", "axis": [0, 0, 1]}],
        "points": [{"name": "O", "at": [0, 0, 0]}, {"name": "C", "from": "O", "vector": [0.1, 0.2, -0.5], "turns": ["a", "b"]},
                   {"name": "W", "at": [1.1, 0.2, -0.5]}],
        "bodies": [{"name": "B", "mass": 1.0, "inertia": [0.1, 0.2, 0.3], "com": "C", "turns": ["a", "b"]}],
        "torsion_springs": [{"name": "t", "bodies": ["ground", "B"], "stiffness": K, "preload": M0,
                             "axis": N.tolist()}],
        "springs": [{"name": "s", "ends": ["C", "W"], "stiffness": 0.0}]})


def test_twist_hessian_of_x_then_z_turns():
    """c = k (dtwist)(dtwist)^T + M0 d2twist (no gravity, a slack spring); dtwist = (n.e_x, n.e_z);
    without preload effects c = k (dtwist)(dtwist)^T alone."""
    m = _gimbal()
    H = fd_hessian(twist, 2)
    d = np.array([N[0], N[2]])
    c = numeric.assemble(m).c.toarray()
    np.testing.assert_allclose(c, K * np.outer(d, d) + M0 * H, rtol=0, atol=1e-6)
    assert np.abs(numeric.assemble(m, Effects(preload=False)).c.toarray() - K * np.outer(d, d)).max() < 1e-12
    assert abs(H[0, 1] + N[1] / 2) < 1e-6  # the compound-rotation term is really there: n . (e_x x e_z) / 2


def test_spatial_result_carries_coordinates_lengths_and_stiffness_rows():
    """A (slack) spring C -> W on the gimbal: length |W - C| = 1 m, its L_c row -e . (e_x x C, e_z x C)
    with e = (W - C)/|W - C| = e_x, then the torsion spring's row (n . e_x, n . e_z)."""
    num = numeric.assemble(_gimbal())
    C, e = np.array([0.1, 0.2, -0.5]), np.array([1.0, 0, 0])
    assert num.coords == ["a", "b"]
    assert num.lengths == {"s": 1.0}
    np.testing.assert_allclose(num.L_c.toarray(), [[-e @ np.cross([1, 0, 0], C), -e @ np.cross([0, 0, 1], C)],
                                                   [N[0], N[2]]], rtol=0, atol=1e-15)


def test_spatial_torsion_moment_from_equilibrium():
    """Bob m at C = (0, 0, -0.5) turned about x then z, gravity along -y, torsion spring about x with
    preload "equilibrium": eq. (5) gives M0 = -m g 0.5 and the term lists balance (dPi/dq = 0)."""
    mass, g = 2.0, 9.81
    m = mech({
        "parameters": {"g": {"value": g, "unit": "m/s^2"}},
        "coordinates": [{"name": "a", "type": "angle", "axis": [1, 0, 0]},
                        {"name": "b", "type": "angle", "axis": [0, 0, 1]}],
        "points": [{"name": "O", "at": [0, 0, 0]}, {"name": "C", "from": "O", "vector": [0, 0, -0.5], "turns": ["a", "b"]}],
        "bodies": [{"name": "B", "mass": mass, "inertia": [0.1, 0.2, 0.3], "com": "C", "turns": ["a", "b"]}],
        "torsion_springs": [{"name": "t", "bodies": ["ground", "B"], "stiffness": K, "preload": "equilibrium",
                             "axis": [1, 0, 0]}],
        "gravity": {"g": "g", "direction": [0, -1, 0]}})
    num = numeric.assemble(m)
    np.testing.assert_allclose(num.residual, [0.0, 0.0], rtol=0, atol=1e-14)
    assert numeric.equilibrium_tensions(m)[0] == {"t": pytest.approx(-0.5 * mass * g, rel=1e-14)}
