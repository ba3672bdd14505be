"""Damping ratios, free and forced response, neglected-effect reports, generated-module batches."""
import math

import numpy as np

from symmech.smm import numeric

from smm_helpers import mech, param, run_scene


def two_mass_damped(c1=3.0):
    """Wall -k1- m1 -k2- m2, damper c1 between the wall and m1 only (non-proportional)."""
    return mech({
        "parameters": {"k1": param(200.0, "N/m"), "k2": param(120.0, "N/m"), "c1": param(c1, "N s/m")},
        "coordinates": [{"name": "x1", "type": "slide", "axis": [1, 0]},
                        {"name": "x2", "type": "slide", "axis": [1, 0]}],
        "points": [{"name": "O", "at": [0, 0]},
                   {"name": "P1", "from": "O", "vector": [1, 0], "slides": ["x1"]},
                   {"name": "P2", "from": "O", "vector": [2, 0], "slides": ["x2"]}],
        "bodies": [{"name": "m1", "mass": 1.5, "com": "P1"}, {"name": "m2", "mass": 0.8, "com": "P2"}],
        "springs": [{"name": "s1", "ends": ["O", "P1"], "stiffness": "k1"},
                    {"name": "s2", "ends": ["P1", "P2"], "stiffness": "k2"}],
        "dampers": [{"name": "d1", "ends": ["O", "P1"], "viscosity": "c1"}],
    })


def test_non_proportional_damping_ratios_match_characteristic_polynomial():
    m1, m2, k1, k2, c1 = 1.5, 0.8, 200.0, 120.0, 3.0
    # det(lambda^2 a + lambda b + c) for a = diag(m1, m2), b = diag(c1, 0), c = [[k1+k2, -k2], [-k2, k2]]
    poly = np.polymul([m1, c1, k1 + k2], [m2, 0, k2])
    poly = np.polysub(poly, [k2 * k2])
    roots = np.roots(poly)
    roots = roots[roots.imag > 0]
    assert len(roots) == 2  # both modes underdamped
    num = numeric.assemble(two_mass_damped(c1))
    md = numeric.modes(num.a.toarray(), num.b.toarray(), num.c.toarray())
    order = np.argsort([abs(r) for r in roots])
    np.testing.assert_allclose(md.zeta, [(-roots[i].real / abs(roots[i])) for i in order], rtol=1e-9)


def test_single_dof_free_and_forced_response():
    m, k, c = 2.0, 800.0, 4.0
    a, b, cc = np.array([[m]]), np.array([[c]]), np.array([[k]])
    w0 = math.sqrt(k / m)
    z = c / (2 * math.sqrt(k * m))
    wd = w0 * math.sqrt(1 - z * z)
    t = np.linspace(0, 1.0, 501)
    q = numeric.free_response(a, b, cc, np.array([0.01]), np.array([0.0]), t)[:, 0]
    exact = 0.01 * np.exp(-z * w0 * t) * (np.cos(wd * t) + z * w0 / wd * np.sin(wd * t))
    np.testing.assert_allclose(q, exact, atol=1e-12)
    w = np.linspace(0.0, 40.0, 81)
    H = numeric.frequency_response(a, b, cc, np.array([1.0]), w)[:, 0]
    np.testing.assert_allclose(np.abs(H), 1 / np.sqrt((k - m * w**2) ** 2 + (c * w) ** 2), rtol=1e-12)


def test_dropped_gravity_in_pendulum_is_reported():
    """A pendulum's stiffness is all gravity: dropping it warns and reports the change."""
    scene = {"kind": "mechanism", "parameters": {"g": param(9.81, "m/s^2")},
             "coordinates": [{"name": "p", "type": "angle"}, {"name": "x", "type": "slide", "axis": [1, 0]}],
             "points": [{"name": "O", "at": [0, 0]},
                        {"name": "C", "from": "O", "vector": [0, 0], "slides": ["x"]},
                        {"name": "A", "from": "C", "vector": [0, -1.0], "turns": ["p"]},
                        {"name": "W", "at": [1, 0]}],
             "bodies": [{"name": "cart", "mass": 2.0, "com": "C"}, {"name": "bob", "mass": 1.0, "com": "A"}],
             "springs": [{"name": "k", "ends": ["C", "W"], "stiffness": 300.0}],
             "gravity": {"g": "g"}, "effects": {"gravity": False}, "output": {"plots": []}}
    s = run_scene(scene)
    rep = s["neglected_effects"]
    assert rep["dropped"] == ["gravity"]
    assert any("removes" in w and "gravity" in w for w in s["warnings"])
    assert s["rigid_body_modes"] == 1
    # all effects: the lower omega^2 of the cart-pendulum is positive (gravity restores it)
    assert rep["omega2_with_all_effects"][0] > 1.0


def test_generated_module_batches():
    from symmech.generated import smm_double_pendulum as mod

    m1 = np.linspace(0.5, 2.0, 7)
    a = mod.a(m1, 1.0, 1.0, 1.0, 9.81)
    assert a.shape == (7, 2, 2)
    np.testing.assert_allclose(a[:, 0, 0], m1 + 4.0, rtol=1e-15)
    c = mod.c(m1[:, None], 1.0, np.array([0.5, 1.0]), 1.0, 9.81)
    assert c.shape == (7, 2, 2, 2)
    np.testing.assert_allclose(c[3, 1, 0, 0], 9.81 * (m1[3] * 1.0 + 1.0 * 2.0), rtol=1e-15)


def test_overdamped_mode_has_no_ratio_and_warns():
    """zeta = c/(2 sqrt(k m)) = 2.5 > 1: real eigenvalues, no ratio, a warning."""
    scene = {"kind": "mechanism",
             "coordinates": [{"name": "x", "type": "slide", "axis": [1, 0]}],
             "points": [{"name": "O", "at": [0, 0]}, {"name": "P", "from": "O", "vector": [1, 0], "slides": ["x"]}],
             "bodies": [{"name": "m", "mass": 1.0, "com": "P"}],
             "springs": [{"name": "k", "ends": ["O", "P"], "stiffness": 100.0}],
             "dampers": [{"name": "c", "ends": ["O", "P"], "viscosity": 50.0}],
             "output": {"plots": []}}
    s = run_scene(scene)
    assert s["damping_ratios"] == [None]
    assert s["frequencies_rad_s"] == [10.0]
    assert any("overdamped" in w for w in s["warnings"])
