"""The factors L_a, m_a, L_c, c_d that `symmech codegen` exports (derive.matrices, through forms.assemble)
hold one column per moving mass or inertia component and per spring, written out by hand: no column for
a component that no coordinate moves (an empty column of L_a with its mass would change the exported
factor, though not a = L_a m_a L_a^T)."""
import numpy as np
import pytest

from symmech.smm.derive import matrices

from smm_helpers import mech

M, J = 40.0, 6.0                   # [kg], [kg m^2]
K1, K2, L1, L2, H = 2000.0, 3000.0, 0.5, 0.7, 1.0   # [N/m], [N/m], [m], [m], [m]


def _f(mat):
    return np.array(mat, dtype=float)


def test_planar_bar_on_two_springs_factors():
    """A bar (centre C slid by y, ends L, R turned by theta) on vertical springs from GL, GR:
    L_a columns bar.y = (1, 0) (dC/dy = e_y) and bar.Jz = (0, 1), m_a = diag(m, J); L_c columns
    e_y . dL/dq = (1, -l1) (e_z x (-l1, 0) = (0, -l1)) and e_y . dR/dq = (1, l2), c_d = diag(k1, k2)."""
    m = mech({
        "coordinates": [{"name": "y", "type": "slide", "axis": [0, 1]}, {"name": "theta", "type": "angle"}],
        "points": [{"name": "O", "at": [0, 0]},
                   {"name": "C", "from": "O", "vector": [0, H], "slides": ["y"]},
                   {"name": "L", "from": "C", "vector": [-L1, 0], "turns": ["theta"]},
                   {"name": "R", "from": "C", "vector": [L2, 0], "turns": ["theta"]},
                   {"name": "GL", "at": [-L1, 0]}, {"name": "GR", "at": [L2, 0]}],
        "bodies": [{"name": "bar", "mass": M, "inertia": J, "com": "C", "turns": ["theta"]}],
        "springs": [{"name": "left", "ends": ["GL", "L"], "stiffness": K1},
                    {"name": "right", "ends": ["GR", "R"], "stiffness": K2}]})
    out = matrices(m)
    np.testing.assert_allclose(_f(out["L_a"]), [[1.0, 0.0], [0.0, 1.0]], rtol=0, atol=1e-15)
    np.testing.assert_allclose(_f(out["m_a"]), np.diag([M, J]), rtol=0, atol=1e-12)
    np.testing.assert_allclose(_f(out["L_c"]), [[1.0, 1.0], [-L1, L2]], rtol=0, atol=1e-15)
    np.testing.assert_allclose(_f(out["c_d"]), np.diag([K1, K2]), rtol=0, atol=1e-12)


@pytest.mark.parametrize("j, la, ma", [((0.3, 0.2, 0.25), [[0.8, 1.0]], [M, 0.3]),
                                       ((0.0, 0.2, 0.2), [[0.8]], [M])])
def test_spatial_pendulum_about_x_factors(j, la, ma):
    """A bob at (0, 0, -l), l = 0.8 m, turned about x, principal moments (J1, J2, J3) along x, y, z:
    dr/dq = e_x x r = (0, l, 0), so L_a = [bob.y: l, bob.Jx: 1], m_a = diag(m, J1); J2, J3 are moved by
    no coordinate, and a zero J1 (a rod along x) leaves [bob.y: l], diag(m)."""
    m = mech({
        "coordinates": [{"name": "a", "type": "angle", "axis": [1, 0, 0]}],
        "points": [{"name": "O", "at": [0, 0, 0]}, {"name": "P", "from": "O", "vector": [0, 0, -0.8], "turns": ["a"]}],
        "bodies": [{"name": "bob", "mass": M, "inertia": list(j), "com": "P"}]})
    out = matrices(m)
    np.testing.assert_allclose(_f(out["L_a"]), la, rtol=0, atol=1e-15)
    np.testing.assert_allclose(_f(out["m_a"]), np.diag(ma), rtol=0, atol=1e-12)


def test_link_with_inertia_only_has_no_mass_columns():
    """A massless link (moment J about z) turned by theta, its centre off the pivot: dr/dtheta != 0, yet
    with m = 0 no translational column; L_a = [link.Jz: 1], m_a = diag(J)."""
    m = mech({
        "coordinates": [{"name": "theta", "type": "angle"}],
        "points": [{"name": "O", "at": [0, 0]}, {"name": "C", "from": "O", "vector": [L1, 0], "turns": ["theta"]}],
        "bodies": [{"name": "link", "mass": 0.0, "inertia": J, "com": "C"}]})
    out = matrices(m)
    np.testing.assert_allclose(_f(out["L_a"]), [[1.0]], rtol=0, atol=1e-15)
    np.testing.assert_allclose(_f(out["m_a"]), [[J]], rtol=0, atol=1e-12)


def test_torsion_dampers_between_links_and_from_the_ground_factors():
    """Two links of a planar double pendulum (link1 turned by th1, link2 by th1 and th2): a torsion damper
    between them sees the relative rotation th2 (axis . (e_b - e_a): th1 cancels), one from the ground to
    link1 sees th1: L_b = [[0, 1], [1, 0]] (rows th1, th2; columns in the dampers' order), b_d = diag(c1, c2),
    so b = diag(c2, c1)."""
    c1, c2 = 2.5, 4.0  # [N m s]
    m = mech({
        "coordinates": [{"name": "th1", "type": "angle"}, {"name": "th2", "type": "angle"}],
        "points": [{"name": "O", "at": [0, 0]},
                   {"name": "P1", "from": "O", "vector": [L1, 0], "turns": ["th1"]},
                   {"name": "P2", "from": "P1", "vector": [L2, 0], "turns": ["th1", "th2"]}],
        "bodies": [{"name": "link1", "mass": M, "inertia": J, "com": "P1", "turns": ["th1"]},
                   {"name": "link2", "mass": M, "inertia": J, "com": "P2", "turns": ["th1", "th2"]}],
        "torsion_dampers": [{"name": "relative", "bodies": ["link1", "link2"], "viscosity": c1},
                            {"name": "absolute", "bodies": ["ground", "link1"], "viscosity": c2}]})
    out = matrices(m)
    np.testing.assert_allclose(_f(out["L_b"]), [[0.0, 1.0], [1.0, 0.0]], rtol=0, atol=1e-15)
    np.testing.assert_allclose(_f(out["b_d"]), np.diag([c1, c2]), rtol=0, atol=1e-12)
    np.testing.assert_allclose(_f(out["b"]), np.diag([c2, c1]), rtol=0, atol=1e-12)
