"""The generalized force of a preloaded torsion spring through the term lists (forms.assemble, spatial):
dPi/dq = M0 d(twist)/dq = M0 n . e_q for a body turned about x then z, with an unpreloaded torsion
spring listed first (its stiffness row kept, no force)."""
import numpy as np

from symmech.smm import numeric

from smm_helpers import mech

K0, K, M0 = 7.0, 20.0, 3.0       # [N m/rad], [N m/rad], [N m]
N = [0.0, 0.6, 0.8]


def _gimbal():
    return mech({
        "coordinates": [{"name": "a", "type": "angle", "axis": [1, 0, 0]},
                        {"name": "b", "type": "angle", "axis": [0, 0, 1]}],
        "points": [{"name": "O", "at": [0, 0, 0]},
                   {"name": "C", "from": "O", "vector": [0.1, 0.2, -0.5], "turns": ["a", "b"]}],
        "bodies": [{"name": "B", "mass": 1.0, "inertia": [0.1, 0.2, 0.3], "com": "C", "turns": ["a", "b"]}],
        "torsion_springs": [{"name": "free", "bodies": ["ground", "B"], "stiffness": K0, "axis": [1, 0, 0]},
                            {"name": "t", "bodies": ["ground", "B"], "stiffness": K, "preload": M0, "axis": N}]})


def test_preloaded_torsion_spring_force_and_rows():
    """Rows dtwist/dq: (1, 0) for the x spring, (n . e_x, n . e_z) = (0, 0.8) for n; force M0 (0, 0.8)."""
    n = numeric.assemble(_gimbal())
    np.testing.assert_allclose(n.residual, [0.0, M0 * 0.8], rtol=0, atol=1e-15)
    np.testing.assert_allclose(n.L_c.toarray(), [[1.0, 0.0], [0.0, 0.8]], rtol=0, atol=1e-15)
