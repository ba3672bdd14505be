"""Hard cases: stiff loop-closing springs, massless links, rigid-body modes, repeated and
nearly singular cases."""
import math

import numpy as np
import pytest

from symmech.core.scene import SymmechError
from symmech.smm import numeric

from smm_helpers import chain, mech, omega2, param, run_model, run_scene, spring_chain


def test_stiff_closing_spring_converges_and_warns():
    """A wall spring K -> infinity clamps the last of three masses: the two lowest frequencies
    converge to those of a two-mass fixed-fixed chain, and at K/k = 1e13 the tool warns."""
    k, n = 100.0, 3
    clamped = [2 * k * (1 - math.cos(j * math.pi / n)) for j in (1, 2)]
    errors = []
    for K in (1e3, 1e5, 1e7, 1e9):
        w2 = omega2(spring_chain([1.0] * n, [k] * n, end_stiffness=K))
        errors.append(max(abs(w2[:2] - clamped) / clamped))
    assert all(e2 < e1 / 50 for e1, e2 in zip(errors, errors[1:])), errors
    assert errors[-1] < 1e-6
    assert not run_model(spring_chain([1.0] * n, [k] * n, end_stiffness=1e5))["warnings"]
    stiff = run_model(spring_chain([1.0] * n, [k] * n, end_stiffness=1e15))
    assert any("stiffness spread" in x for x in stiff["warnings"]), stiff["warnings"]


def test_massless_link_between_masses():
    """A massless rigid link (no body) carries a mass at its end: two-link pendulum, masses at the
    ends of link 2 and at the joint, link 1 massless except at the joint."""
    l1, l2, m1, m2, g = 0.6, 0.9, 1.0, 2.0, 9.81
    m = mech({
        "parameters": {"g": param(g, "m/s^2")},
        "coordinates": [{"name": "p1", "type": "angle"}, {"name": "p2", "type": "angle"}],
        "points": [{"name": "O", "at": [0, 0]},
                   {"name": "A", "from": "O", "vector": [0, -l1], "turns": ["p1"]},
                   {"name": "B", "from": "A", "vector": [0, -l2], "turns": ["p2"]}],
        "bodies": [{"name": "joint", "mass": m1, "com": "A"}, {"name": "tip", "mass": m2, "com": "B"}],
        "gravity": {"g": "g"},
    })
    # absolute angles: a = [[(m1+m2) l1^2, m2 l1 l2], [., m2 l2^2]], c = g diag((m1+m2) l1, m2 l2)
    a = np.array([[(m1 + m2) * l1**2, m2 * l1 * l2], [m2 * l1 * l2, m2 * l2**2]])
    c = np.diag([(m1 + m2) * g * l1, m2 * g * l2])
    expected = np.sort(np.linalg.eigvals(np.linalg.solve(a, c)).real)
    np.testing.assert_allclose(omega2(m), expected, rtol=1e-10)


def test_free_free_rigid_body_mode():
    scene = {"kind": "mechanism", "chain": {"n": 3, "mass": 2.0, "stiffness": 50.0, "spacing": 1.0,
                                            "ends": "free-free"}, "output": {"plots": []}}
    s = run_scene(scene)
    assert s["rigid_body_modes"] == 1
    assert s["frequencies_rad_s"][0] == 0.0
    np.testing.assert_allclose(s["frequencies_rad_s"][1:], [5.0, math.sqrt(75.0)], rtol=1e-10)


def test_repeated_frequencies_have_orthonormal_modes():
    """A mass between four equal springs (x and y): a double frequency sqrt(2k/m)."""
    k, mass = 300.0, 1.5
    m = mech({
        "coordinates": [{"name": "x", "type": "slide", "axis": [1, 0]},
                        {"name": "y", "type": "slide", "axis": [0, 1]}],
        "points": [{"name": "O", "at": [0, 0]}, {"name": "P", "from": "O", "vector": [0, 0], "slides": ["x", "y"]},
                   {"name": "E", "at": [1, 0]}, {"name": "W", "at": [-1, 0]},
                   {"name": "N", "at": [0, 1]}, {"name": "S", "at": [0, -1]}],
        "bodies": [{"name": "m", "mass": mass, "com": "P"}],
        "springs": [{"name": n, "ends": ["P", n], "stiffness": k} for n in "EWNS"],
    })
    num = numeric.assemble(m)
    md = numeric.modes(num.a.toarray(), num.b.toarray(), num.c.toarray())
    np.testing.assert_allclose(md.omega2, [2 * k / mass] * 2, rtol=1e-12)
    np.testing.assert_allclose(md.shapes.T @ num.a.toarray() @ md.shapes, np.eye(2), atol=1e-12)


def test_nearly_singular_mass_matrix():
    """A tiny mass gives a high but correct frequency; a vanishing one is refused by name."""
    k, M, eps = 100.0, 1.0, 1e-6
    m = spring_chain([M, eps], [k, k])
    # two masses, springs wall-M and M-eps: exact roots of the characteristic polynomial
    a = np.diag([M, eps])
    c = np.array([[2 * k, -k], [-k, k]])
    expected = np.sort(np.linalg.eigvals(np.linalg.solve(a, c)).real)
    np.testing.assert_allclose(omega2(m), expected, rtol=1e-8)
    # within the admissible mass range, but 1e-13 of the other mass: numerically singular
    bad = spring_chain([1e3, 1e-10], [k, k])
    with pytest.raises(SymmechError, match="coordinate 's2'"):
        numeric.check_mass(bad, numeric.assemble(bad).a.toarray())


def test_unstable_equilibrium_is_reported():
    """An inverted pendulum: negative omega^2, reported as unstable, no NaN frequency."""
    m = mech({
        "parameters": {"g": param(9.81, "m/s^2")},
        "coordinates": [{"name": "p", "type": "angle"}],
        "points": [{"name": "O", "at": [0, 0]}, {"name": "A", "from": "O", "vector": [0, 1.0], "turns": ["p"]}],
        "bodies": [{"name": "b", "mass": 1.0, "com": "A"}],
        "gravity": {"g": "g"},
    })
    s = run_model(m)
    assert s["frequencies_rad_s"] == [None]
    assert any("unstable" in w for w in s["warnings"])


def test_large_chain_sparse_assembly():
    """10,000 DOF assemble sparsely; the lowest mode matches the closed form."""
    import scipy.sparse.linalg

    n, k, mass = 10000, 1e4, 0.1
    m = chain(n=n, mass=mass, stiffness=k, spacing=0.01)
    num = numeric.assemble(m)
    assert num.c.nnz == 3 * n - 2
    w = np.sort(scipy.sparse.linalg.eigsh(num.c.tocsc(), k=3, M=num.a.tocsc(), sigma=0.0,
                                          return_eigenvectors=False))
    expected = [2 * k / mass * (1 - math.cos(j * math.pi / (n + 1))) for j in (1, 2, 3)]
    np.testing.assert_allclose(w, expected, rtol=1e-6)


@pytest.mark.parametrize("K", [1e16, 1e18])
def test_stiff_loop_spring_keeps_real_modes_elastic(K):
    """With a loop-closing spring K >= 1e16 the clamped-chain modes (omega^2 = 100, 300)
    were reported as rigid-body modes (threshold 100 eps max omega^2 >= 222). Rigid modes are now the
    nullity of the Jacobi-scaled stiffness: none here; the spread is reported and warned about."""
    s = run_model(spring_chain([1.0] * 3, [100.0] * 3, end_stiffness=K))
    assert s["rigid_body_modes"] == 0
    np.testing.assert_allclose(s["omega2_1_per_s2"][:2], [100.0, 300.0], rtol=1e-10)
    assert s["frequencies_rad_s"][0] == pytest.approx(10.0, rel=1e-10)
    assert s["conditioning"]["stiffness_spread"] == pytest.approx(K / 100.0, rel=1e-6)
    assert s["conditioning"]["scaled_stiffness_condition"] < 10.0
    assert any("stiffness spread" in w for w in s["warnings"])


def test_stiff_spring_beside_a_true_rigid_mode():
    """Free-free three masses (no wall springs) with a 1e16 spring between masses 2 and 3: exactly one
    rigid-body mode; the soft mode is omega^2 = k (1/m1 + 1/(m2 + m3)) in the rigid-pair limit."""
    k, K = 100.0, 1e16
    m = mech({
        "coordinates": [{"name": f"s{i}", "type": "slide", "axis": [1, 0]} for i in (1, 2, 3)],
        "points": [{"name": "O", "at": [0, 0]}] + [{"name": f"P{i}", "from": "O", "vector": [float(i), 0],
                                                     "slides": [f"s{i}"]} for i in (1, 2, 3)],
        "bodies": [{"name": f"b{i}", "mass": 1.0, "com": f"P{i}"} for i in (1, 2, 3)],
        "springs": [{"name": "k", "ends": ["P1", "P2"], "stiffness": k},
                    {"name": "K", "ends": ["P2", "P3"], "stiffness": K}],
    })
    s = run_model(m)
    assert s["rigid_body_modes"] == 1 and s["frequencies_rad_s"][0] == 0.0
    np.testing.assert_allclose(s["omega2_1_per_s2"][1], k * (1 + 1 / 2), rtol=1e-9)
