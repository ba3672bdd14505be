"""numeric.equilibrium_tensions (eq. (5)) against statics by hand: a bob hung from three springs in space
(force balance solved from the springs' unit vectors), a pendulum held by a torsion spring (moment
balance about the pivot), the pivot order of partial pivoting written out, and the refusals of
indeterminate and unbalanced springs by exact field and message."""
import math

import numpy as np
import pytest

from symmech.core.scene import SceneError
from symmech.smm import numeric

from smm_helpers import mech, param

MASS, G = 2.0, 9.81
# P - A for the three anchors A of the spatial hang: spring 1 mostly along y, 2 along z, 3 along x
LEGS = np.array([[0.2, 1.0, 0.3], [0.5, 0.1, 0.9], [0.8, 0.2, 0.3]])


def _spatial_hang():
    anchors = [{"name": f"A{j}", "at": (-leg).tolist()} for j, leg in enumerate(LEGS)]
    return mech({
        "parameters": {"g": param(G, "m/s^2")},
        "coordinates": [{"name": n, "type": "slide", "axis": ax}
                        for n, ax in (("x", [1, 0, 0]), ("y", [0, 1, 0]), ("z", [0, 0, 1]))],
        "points": [{"name": "P", "at": [0, 0, 0]}, {"name": "B", "from": "P", "vector": [0, 0, 0],
                                                    "slides": ["x", "y", "z"]}, *anchors],
        "bodies": [{"name": "bob", "mass": MASS, "com": "B"}],
        "springs": [{"name": f"s{j}", "ends": [f"A{j}", "B"], "stiffness": 100.0, "preload": "equilibrium"}
                    for j in range(3)],
        "gravity": {"g": "g", "direction": [0, 0, -1]}})


def _pivot_order(a):
    """Rows of ``a`` in the order Gaussian elimination with partial pivoting takes them."""
    a, order = a.astype(float).copy(), list(range(len(a)))
    for j in range(len(a)):
        p = j + int(np.argmax(np.abs(a[j:, j])))
        a[[j, p]], order[j], order[p] = a[[p, j]], order[p], order[j]
        a[j + 1:] -= np.outer(a[j + 1:, j] / a[j, j], a[j])
    return order


def test_spatial_hang_tensions_balance_the_weight_in_pivot_order():
    """sum_j T_j u_j = m g e_z, u_j = (A_j - P)/|A_j - P| the pull of spring j on the bob."""
    tensions, rows = numeric.equilibrium_tensions(_spatial_hang())
    pulls = -LEGS / np.linalg.norm(LEGS, axis=1)[:, None]
    expected = np.linalg.solve(pulls.T, [0.0, 0.0, MASS * G])
    np.testing.assert_allclose([tensions[f"s{j}"] for j in range(3)], expected, rtol=1e-12)
    # G's rows are dl_j/dq = -u_j: y leads spring 1, then z, then x (a 3-cycle, not its inverse)
    assert _pivot_order(-pulls.T) == [1, 2, 0]
    assert rows == [1, 2, 0]


def _torsion_pendulum(th0, springs):
    """Bob on a massless rod l = 0.8 m drawn th0 from the downward vertical, torsion springs to ground
    (no spring: no lengths to scale the rank tolerance)."""
    l = 0.8
    return mech({"parameters": {"g": param(G, "m/s^2")},
                 "coordinates": [{"name": "phi", "type": "angle"}],
                 "points": [{"name": "O", "at": [0, 0]},
                            {"name": "B", "from": "O", "vector": [l * math.sin(th0), -l * math.cos(th0)],
                             "turns": ["phi"]}],
                 "bodies": [{"name": "bob", "mass": MASS, "com": "B"}],
                 "torsion_springs": [{"name": n, "bodies": ["ground", "bob"], "stiffness": 3.0,
                                      "preload": "equilibrium"} for n in springs],
                 "gravity": {"g": "g"}})


def test_torsion_moment_holds_the_pendulum():
    """Moment balance about O: M + m g l sin(th0) = 0."""
    th0 = 0.7
    tensions, rows = numeric.equilibrium_tensions(_torsion_pendulum(th0, ["t"]))
    assert tensions == {"t": pytest.approx(-MASS * G * 0.8 * math.sin(th0), rel=1e-12)}
    assert rows == [0]


def test_indeterminate_torsion_springs_name_the_first_torsion_field():
    with pytest.raises(SceneError) as err:
        numeric.equilibrium_tensions(_torsion_pendulum(0.7, ["t1", "t2"]))
    assert err.value.field == "torsion_springs[0].preload"
    assert str(err.value) == ("scene field 'torsion_springs[0].preload': springs t1, t2: equilibrium (5) does not "
                              "fix their tensions (statically indeterminate); give preload values")


def _vertical_bob(springs, x=0.0):
    """Bob at (x, -1) on a vertical slide y (and x), springs to O = (0, 0) and U = (0, 1)."""
    return mech({
        "parameters": {"g": param(G, "m/s^2")},
        "coordinates": [{"name": "x", "type": "slide", "axis": [1, 0]},
                        {"name": "y", "type": "slide", "axis": [0, 1]}],
        "points": [{"name": "O", "at": [0, 0]}, {"name": "U", "at": [0, 1]},
                   {"name": "P", "from": "O", "vector": [x, -1], "slides": ["x", "y"]}],
        "bodies": [{"name": "bob", "mass": MASS, "com": "P"}],
        "springs": [{"name": n, "ends": [end, "P"], "stiffness": 10.0, "preload": pre} for n, end, pre in springs],
        "gravity": {"g": "g"}})


def test_indeterminate_springs_name_the_first_equilibrium_spring():
    """A given preload first, then two equilibrium springs along the same line: the field is springs[1]."""
    m = _vertical_bob([("given", "O", 1.0), ("a", "O", "equilibrium"), ("b", "U", "equilibrium")])
    with pytest.raises(SceneError) as err:
        numeric.equilibrium_tensions(m)
    assert err.value.field == "springs[1].preload"
    assert str(err.value) == ("scene field 'springs[1].preload': springs a, b: equilibrium (5) does not fix their "
                              "tensions (statically indeterminate); give preload values")


def test_unbalanced_load_refused_with_the_residual_and_its_coordinate():
    """A bob at (1, -1) on two springs from O along the diagonal, 1 N given and one unknown: row x (no
    weight on it) takes T = -1 N, so the springs pull nothing and the weight m g = 19.6 N stays on y."""
    m = _vertical_bob([("given", "O", 1.0), ("a", "O", "equilibrium")], x=1.0)
    with pytest.raises(SceneError) as err:
        numeric.equilibrium_tensions(m)
    assert str(err.value) == ("scene field 'springs[1].preload': springs a cannot balance the loads: "
                              f"dPi/dq = {MASS * G:.3g} remains on coordinate 'y'")


def test_radial_spring_of_a_long_pendulum_is_indeterminate_despite_round_off():
    """A spring from the pivot to the bob of a pendulum (l = 10 km, drawn 1.1 rad out) has dl/dphi = 0:
    its L_c entry is round-off (~1e-12 m, from l sin, l cos), below 1e-10 of the spring's length, so
    eq. (5) is refused instead of giving the round-off's ~1e17 N."""
    l, th = 1e4, 1.1
    m = mech({"parameters": {"g": param(G, "m/s^2")},
              "coordinates": [{"name": "phi", "type": "angle"}],
              "points": [{"name": "O", "at": [0, 0]},
                         {"name": "B", "from": "O", "vector": [l * math.sin(th), -l * math.cos(th)], "turns": ["phi"]}],
              "bodies": [{"name": "bob", "mass": MASS, "com": "B"}],
              "springs": [{"name": "s", "ends": ["O", "B"], "stiffness": 5.0, "preload": "equilibrium"}],
              "gravity": {"g": "g"}})
    with pytest.raises(SceneError, match=r"springs s: equilibrium \(5\) does not fix their tensions"):
        numeric.equilibrium_tensions(m)


def test_two_springs_that_cannot_hold_a_spatial_bob_are_named_together():
    """Two of the three legs of the spatial hang: their pulls span a plane without the weight's line."""
    m = _spatial_hang()
    m.springs.pop()
    with pytest.raises(SceneError, match=r"^scene field 'springs\[0\].preload': springs s0, s1 cannot balance the "
                                         r"loads: dPi/dq = \S+ remains on coordinate '[xyz]'$"):
        numeric.equilibrium_tensions(m)
