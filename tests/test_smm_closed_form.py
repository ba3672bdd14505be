"""Closed-form frequencies of small mechanisms vs the SMM matrices."""
import math

import numpy as np
import pytest

from symmech.smm import numeric
from symmech.smm.model import Effects

from smm_helpers import bar_on_springs, hanging_mass, mech, omega2, param, run_scene, spring_chain
from smm_helpers import chain as chain_of

RTOL = 1e-10


def chain(n, ends, motion="axial", tension=0.0, k=150.0, m=0.7, L=0.4):
    return chain_of(n=n, mass=m, stiffness=k, spacing=L, ends=ends, motion=motion, tension=tension)


@pytest.mark.parametrize("n", [1, 3, 7])
def test_chain_fixed_fixed(n):
    k, m = 150.0, 0.7
    expected = [2 * k / m * (1 - math.cos(j * math.pi / (n + 1))) for j in range(1, n + 1)]
    np.testing.assert_allclose(omega2(chain(n, "fixed-fixed")), expected, rtol=RTOL)


@pytest.mark.parametrize("n", [1, 4, 6])
def test_chain_fixed_free(n):
    k, m = 150.0, 0.7
    expected = [2 * k / m * (1 - math.cos((2 * j - 1) * math.pi / (2 * n + 1))) for j in range(1, n + 1)]
    np.testing.assert_allclose(omega2(chain(n, "fixed-free")), expected, rtol=RTOL)


@pytest.mark.parametrize("n", [2, 5])
def test_chain_free_free(n):
    k, m = 150.0, 0.7
    expected = [2 * k / m * (1 - math.cos(j * math.pi / n)) for j in range(n)]
    w2 = omega2(chain(n, "free-free"))
    assert abs(w2[0]) < 1e-10 * w2[-1]
    np.testing.assert_allclose(w2[1:], expected[1:], rtol=RTOL)


def test_double_pendulum_equal_links():
    g, l = 9.81, 0.9
    m = mech({
        "parameters": {"m": param(1.3, "kg"), "l": param(l, "m"), "g": param(g, "m/s^2")},
        "coordinates": [{"name": "p1", "type": "angle"}, {"name": "p2", "type": "angle"}],
        "points": [{"name": "O", "at": [0, 0]},
                   {"name": "A", "from": "O", "vector": [0, "-l"], "turns": ["p1"]},
                   {"name": "B", "from": "A", "vector": [0, "-l"], "turns": ["p1", "p2"]}],
        "bodies": [{"name": "b1", "mass": "m", "com": "A"}, {"name": "b2", "mass": "m", "com": "B"}],
        "gravity": {"g": "g"},
    })
    np.testing.assert_allclose(omega2(m), [g / l * (2 - math.sqrt(2)), g / l * (2 + math.sqrt(2))], rtol=RTOL)


def test_bar_on_two_springs_bounce_and_pitch():
    m, J, k, l = 40.0, 6.0, 2000.0, 0.5
    w2 = omega2(bar_on_springs(m, J, k, k, l, l))
    np.testing.assert_allclose(w2, sorted([2 * k / m, 2 * k * l * l / J]), rtol=RTOL)


def test_bar_on_two_unequal_springs_coupled():
    m, J, k1, k2, l1, l2 = 40.0, 6.0, 1500.0, 2600.0, 0.4, 0.7
    # det(c - w2 a) = 0 for c = [[k1+k2, k2 l2 - k1 l1], [., k1 l1^2 + k2 l2^2]], a = diag(m, J)
    c11, c12, c22 = k1 + k2, k2 * l2 - k1 * l1, k1 * l1**2 + k2 * l2**2
    p = c11 / m + c22 / J
    q = (c11 * c22 - c12**2) / (m * J)
    expected = [(p - math.sqrt(p * p - 4 * q)) / 2, (p + math.sqrt(p * p - 4 * q)) / 2]
    np.testing.assert_allclose(omega2(bar_on_springs(m, J, k1, k2, l1, l2)), expected, rtol=RTOL)


def test_hanging_mass_sideways_frequency_from_preload_alone():
    k, mass, l, g = 500.0, 2.0, 0.8, 9.81
    w2 = omega2(hanging_mass(k, mass, l, g))
    np.testing.assert_allclose(w2, sorted([g / l, k / mass]), rtol=RTOL)
    no_preload = omega2(hanging_mass(k, mass, l, g, effects={"preload": False}))
    np.testing.assert_allclose(no_preload, [0.0, k / mass], atol=1e-9 * k / mass)


def test_pretensioned_string_transverse_stiffness_is_all_preload():
    n, T, m, L = 5, 80.0, 0.3, 0.25
    string = chain(n, "fixed-fixed", "transverse", tension=T, k=1e4, m=m, L=L)
    expected = [2 * T / (m * L) * (1 - math.cos(j * math.pi / (n + 1))) for j in range(1, n + 1)]
    np.testing.assert_allclose(omega2(string), expected, rtol=RTOL)
    num = numeric.assemble(string, Effects(True, False, True))
    assert np.abs(num.c.toarray()).max() == 0.0


def test_stiffness_times_influence_coefficients_is_identity():
    """The paper's check (c)(alpha) = E; alpha by unit loads on a chain of springs in series."""
    ks = [300.0, 120.0, 450.0, 80.0]
    m = spring_chain([1.0, 2.0, 3.0, 4.0], ks)
    c = numeric.assemble(m).c.toarray()
    n = len(ks)
    # unit load at mass j stretches springs 0..j-1: displacement of mass i = sum_{s <= min(i, j)} 1/k_s
    alpha = np.array([[sum(1 / ks[s] for s in range(min(i, j) + 1)) for j in range(n)] for i in range(n)])
    np.testing.assert_allclose(c @ alpha, np.eye(n), atol=1e-12)


def test_equilibrium_found_first():
    """A mass on a spring of free length l0 drawn at the wrong height: eq. (6) finds
    l = l0 + m g / k, then the sideways frequency is g / l (preload term) and the vertical k / m."""
    k, mass, l0, g = 400.0, 2.0, 0.5, 9.81
    d = {"kind": "mechanism",
         "parameters": {"m": param(mass, "kg"), "k": param(k, "N/m"), "g": param(g, "m/s^2")},
         "coordinates": [{"name": "x", "type": "slide", "axis": [1, 0]},
                         {"name": "y", "type": "slide", "axis": [0, 1]}],
         "points": [{"name": "O", "at": [0, 0]},
                    {"name": "P", "from": "O", "vector": [0.02, -0.3], "slides": ["x", "y"]}],
         "bodies": [{"name": "bob", "mass": "m", "com": "P"}],
         "springs": [{"name": "s", "ends": ["O", "P"], "stiffness": "k", "free_length": l0}],
         "gravity": {"g": "g"}, "equilibrium": {"solve": True}, "output": {"plots": []}}
    s = run_scene(d)
    length = l0 + mass * g / k
    np.testing.assert_allclose(s["omega2_1_per_s2"], sorted([g / length, k / mass]), rtol=1e-9)
    np.testing.assert_allclose(s["equilibrium"]["q"], [-0.02, 0.3 - length], atol=1e-10)
    assert s["warnings"] == []


def test_preload_from_equilibrium_conditions():
    """preload = "equilibrium": eq. (5) gives the hanger tension m g, hence omega^2 = g / l sideways."""
    from symmech.smm.derive import matrices
    import sympy

    k, mass, l, g = 500.0, 2.0, 0.8, 9.81
    m = hanging_mass(k, mass, l, g)
    m.springs[0] = m.springs[0].__class__("hanger", "O", "P", "k", "equilibrium")
    assert numeric.equilibrium_tensions(m)[0] == {"hanger": pytest.approx(mass * g, rel=1e-14)}
    np.testing.assert_allclose(omega2(m), sorted([g / l, k / mass]), rtol=RTOL)
    c = matrices(m)["c"]
    gs, ls = sympy.Symbol("g", real=True), sympy.Symbol("l", real=True)
    assert sympy.simplify(c[0, 0] - sympy.Symbol("m", real=True) * gs * ls / sympy.Abs(ls) ** 2) == 0


def test_preload_from_equilibrium_refused_when_indeterminate_or_unbalanced():
    from symmech.core.scene import SymmechError

    two = mech({
        "parameters": {"g": param(9.81, "m/s^2")},
        "coordinates": [{"name": "y", "type": "slide", "axis": [0, 1]}],
        "points": [{"name": "O", "at": [0, 0]}, {"name": "P", "from": "O", "vector": [0, -1], "slides": ["y"]},
                   {"name": "U", "at": [0, 1]}],
        "bodies": [{"name": "bob", "mass": 1.0, "com": "P"}],
        "springs": [{"name": "a", "ends": ["O", "P"], "stiffness": 10.0, "preload": "equilibrium"},
                    {"name": "b", "ends": ["U", "P"], "stiffness": 10.0, "preload": "equilibrium"}],
        "gravity": {"g": "g"},
    })
    with pytest.raises(SymmechError, match="statically indeterminate"):
        numeric.equilibrium_tensions(two)
    side = mech({
        "parameters": {"g": param(9.81, "m/s^2")},
        "coordinates": [{"name": "x", "type": "slide", "axis": [1, 0]},
                        {"name": "y", "type": "slide", "axis": [0, 1]}],
        "points": [{"name": "O", "at": [0, 0]},
                   {"name": "P", "from": "O", "vector": [1, 0], "slides": ["x", "y"]}],
        "bodies": [{"name": "bob", "mass": 1.0, "com": "P"}],
        "springs": [{"name": "a", "ends": ["O", "P"], "stiffness": 10.0, "preload": "equilibrium"}],
        "gravity": {"g": "g"},
    })
    with pytest.raises(SymmechError, match="cannot balance the loads.*'y'"):
        numeric.equilibrium_tensions(side)


def test_equilibrium_search_turns_a_pendulum_pulled_by_a_spring():
    """Pendulum (massless rod l, bob m) pulled sideways by a spring of free length l0 to a wall
    point W: the equilibrium angle and frequency found by eq. (6) match a direct minimisation
    of Pi(phi) = -m g l cos(phi) + k/2 (|W - r(phi)| - l0)^2 with Pi'' by finite differences."""
    import scipy.optimize

    mass, l, k, l0, g, d = 1.5, 1.0, 40.0, 0.3, 9.81, 1.2
    W = np.array([d, -l])

    def pi(phi):
        r = np.array([l * math.sin(phi), -l * math.cos(phi)])
        return -mass * g * l * math.cos(phi) + 0.5 * k * (np.linalg.norm(W - r) - l0) ** 2

    phi_star = scipy.optimize.minimize_scalar(pi, bounds=(0.0, 1.2), method="bounded",
                                              options={"xatol": 1e-12}).x
    h = 1e-4
    stiff = (pi(phi_star + h) - 2 * pi(phi_star) + pi(phi_star - h)) / h**2
    d_ = {"kind": "mechanism",
          "parameters": {"g": param(g, "m/s^2")},
          "coordinates": [{"name": "phi", "type": "angle"}],
          "points": [{"name": "O", "at": [0, 0]}, {"name": "B", "from": "O", "vector": [0, -l], "turns": ["phi"]},
                     {"name": "W", "at": W.tolist()}],
          "bodies": [{"name": "bob", "mass": mass, "com": "B"}],
          "springs": [{"name": "s", "ends": ["B", "W"], "stiffness": k, "free_length": l0}],
          "gravity": {"g": "g"}, "equilibrium": {"solve": True}, "output": {"plots": []}}
    s = run_scene(d_)
    assert abs(s["equilibrium"]["q"][0] - phi_star) < 1e-7
    np.testing.assert_allclose(s["omega2_1_per_s2"][0], stiff / (mass * l * l), rtol=1e-6)
