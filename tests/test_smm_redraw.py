"""The model redrawn in a configuration q (numeric.moved) against rotation matrices written here
(scipy's Rotation), and the refusal of coordinates turned by different outer angles."""
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from symmech.core.scene import SymmechError
from symmech.smm import numeric

from smm_helpers import mech

QA, QB = 0.7, -0.4  # [rad]
V0 = np.array([0.3, -0.2, -1.0])  # [m]


def vec(text):
    return np.array([float(x) for x in text])


def gimbal(axis_b=(0, 0, 1), **more):
    """Two angles, a about x then b about ``axis_b`` (spatial); a body with distinct principal
    moments and no principal axes given, at the end of V0; ``more`` scene tables beside them."""
    return mech({
        "coordinates": [{"name": "a", "type": "angle", "axis": [1, 0, 0]},
                        {"name": "b", "type": "angle", "axis": list(axis_b)}],
        "points": [{"name": "O", "at": [0, 0, 0]}, {"name": "C", "from": "O", "vector": V0.tolist(), "turns": ["a", "b"]}],
        "bodies": [{"name": "B", "mass": 2.0, "inertia": [0.1, 0.2, 0.3], "com": "C", "turns": ["a", "b"]}],
        **more,  # a table of the same name replaces the gimbal's
    })


def test_two_angle_gimbal_redrawn_exactly():
    """R = Rx(qa) Rz(qb): the point R V0, b's axis Rx(qa) e_z (a's unchanged), the body's principal
    axes the columns of R; the coordinates keep their names."""
    R = (Rotation.from_rotvec([QA, 0, 0]) * Rotation.from_rotvec([0, 0, QB])).as_matrix()
    m = numeric.moved(gimbal(), np.array([QA, QB]))
    np.testing.assert_allclose(vec(m.points["C"].vector), R @ V0, rtol=0, atol=1e-15)
    np.testing.assert_allclose(vec(m.coordinates[0].axis), [1, 0, 0], rtol=0, atol=1e-15)
    np.testing.assert_allclose(vec(m.coordinates[1].axis), Rotation.from_rotvec([QA, 0, 0]).apply([0, 0, 1]),
                               rtol=0, atol=1e-15)
    np.testing.assert_allclose([vec(p) for p in m.bodies[0].axes], R.T, rtol=0, atol=1e-15)
    # principal axes given (the drawn frame's axes in turn: y, z, x): each is turned by R
    given = [[0, 1, 0], [0, 0, 1], [1, 0, 0]]
    body = {"name": "B", "mass": 2.0, "inertia": [0.1, 0.2, 0.3], "com": "C", "turns": ["a", "b"],
            "principal_axes": given}
    m = numeric.moved(gimbal(bodies=[body]), np.array([QA, QB]))
    np.testing.assert_allclose([vec(p) for p in m.bodies[0].axes], (R @ np.array(given).T).T, rtol=0, atol=1e-15)


def test_torsion_spring_turned_off_its_axis_is_refused_in_one_line():
    """A torsion spring about x on the gimbal's body, which b also turns about z: its twist is no sum of
    angles, and the redraw says so, naming the spring and its axis."""
    m = gimbal(torsion_springs=[{"name": "t", "bodies": ["ground", "B"], "stiffness": 2.0, "axis": [1, 0, 0]}])
    with pytest.raises(SymmechError) as err:
        numeric.moved(m, np.array([QA, QB]))
    assert str(err.value) == ("equilibrium.solve: torsion spring 't' turns about axes other than its own axis "
                              "[1.0, 0.0, 0.0]; the equilibrium search handles torsion springs whose bodies turn "
                              "about the spring axis only")


def test_redrawn_axis_is_a_unit_vector():
    """An axis drawn 1e-9 off unit length (admitted) comes back of unit length."""
    m = numeric.moved(gimbal((0, 0, 1 + 9e-10)), np.array([QA, QB]))
    assert np.linalg.norm(vec(m.coordinates[1].axis)) == pytest.approx(1.0, abs=1e-15)


def planar_slider(order2=("p1", "p2")):
    """Planar: a slide s along x carried by two turns p1, p2 on two points (turn orders may differ:
    planar rotations commute)."""
    return mech({
        "coordinates": [{"name": "p1", "type": "angle"}, {"name": "p2", "type": "angle"},
                        {"name": "s", "type": "slide", "axis": [1, 0]}],
        "points": [{"name": "O", "at": [0, 0]},
                   {"name": "P", "from": "O", "vector": [0.5, 0], "turns": ["p1", "p2"], "slides": ["s"]},
                   {"name": "Q", "from": "O", "vector": [0.8, 0.1], "turns": list(order2), "slides": ["s"]}],
        "bodies": [{"name": "m1", "mass": 1.0, "com": "P"}, {"name": "m2", "mass": 1.0, "com": "Q"}],
    })


@pytest.mark.parametrize("order2", [("p1", "p2"), ("p2", "p1")])
def test_planar_slide_turns_with_its_host(order2):
    """The slide's axis turns by p1 + p2 in any order; P = R (v0 + s e_x)."""
    q = np.array([0.3, 0.5, 0.2])
    m = numeric.moved(planar_slider(order2), q)
    c, s = np.cos(0.8), np.sin(0.8)
    np.testing.assert_allclose(vec(m.coordinates[2].axis), [c, s, 0], rtol=0, atol=1e-15)
    np.testing.assert_allclose(vec(m.points["P"].vector), [0.7 * c, 0.7 * s, 0], rtol=0, atol=1e-15)
    assert m.coordinates[0].axis == ("0", "0", "1")
    assert [b.name for b in m.bodies] == ["m1", "m2"]  # unturned bodies are all kept


def _spatial(points, bodies=()):
    return mech({
        "coordinates": [{"name": "a", "type": "angle", "axis": [1, 0, 0]},
                        {"name": "b", "type": "angle", "axis": [0, 1, 0]},
                        {"name": "s", "type": "slide", "axis": [0, 0, 1]}],
        "points": [{"name": "O", "at": [0, 0, 0]}] + points,
        "bodies": [{"name": "M", "mass": 1.0, "com": "P"}] + list(bodies),
    })


@pytest.mark.parametrize("m, message", [
    (lambda: _spatial([{"name": "P", "from": "O", "vector": [0, 0, -1], "turns": ["a", "b"], "slides": ["s"]},
                       {"name": "Q", "from": "O", "vector": [0, 0, 1], "turns": ["b", "a"]}]),
     "coordinate 'b' is preceded by the turns ['a'] in point 'P' but by [] in point 'Q'; the equilibrium "
     "search needs every coordinate turned by the same outer angles wherever it appears"),
    (lambda: _spatial([{"name": "P", "from": "O", "vector": [0, 0, -1], "turns": ["a", "b"], "slides": ["s"]},
                       {"name": "Q", "from": "O", "vector": [0, 0, 1], "turns": ["a"], "slides": ["s"]}]),
     "coordinate 's' is preceded by the turns ['a', 'b'] in point 'P' but by ['a'] in point 'Q'"),
    (lambda: _spatial([{"name": "P", "from": "O", "vector": [0, 0, -1], "turns": ["a", "b"], "slides": ["s"]}],
                      [{"name": "N", "mass": 1.0, "inertia": [1, 1, 1], "com": "P", "turns": ["b", "a"]}]),
     "coordinate 'b' is preceded by the turns ['a'] in point 'P' but by [] in body 'N'"),
])
def test_different_outer_turns_are_refused_by_name(m, message):
    with pytest.raises(SymmechError) as err:
        numeric.solve_equilibrium(m())
    assert message in str(err.value)
