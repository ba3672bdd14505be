"""Mode kinds, damping ratios without damping, the conditioning numbers and the singular-mass
refusal, against matrices and eigenvalues written by hand."""
import math
from fractions import Fraction

import numpy as np
import pytest

from symmech.core.scene import SceneError
from symmech.smm import numeric

from smm_helpers import mech, param, spring_chain


def inverted_pendulum_on_free_cart(M=3.0, m=1.2, l=0.7, g=9.81):
    """A cart (slide x, no spring) carrying a pendulum standing upright (angle p)."""
    return mech({
        "parameters": {"g": param(g, "m/s^2")},
        "coordinates": [{"name": "x", "type": "slide", "axis": [1, 0]}, {"name": "p", "type": "angle"}],
        "points": [{"name": "O", "at": [0, 0]}, {"name": "C", "from": "O", "vector": [0, 0], "slides": ["x"]},
                   {"name": "B", "from": "C", "vector": [0, l], "turns": ["p"]}],
        "bodies": [{"name": "cart", "mass": M, "com": "C"}, {"name": "bob", "mass": m, "com": "B"}],
        "gravity": {"g": "g"},
    })


def test_unstable_mode_below_a_rigid_one():
    """a = [[M+m, -m l], [-m l, m l^2]], c = diag(0, -m g l): omega^2 = -(M+m) g/(M l) (unstable, the
    lowest) and 0 (the cart's drift, rigid), in this order; no damping ratio for either."""
    M, m, l, g = 3.0, 1.2, 0.7, 9.81
    num = numeric.assemble(inverted_pendulum_on_free_cart(M, m, l, g))
    assert num.coords == ["x", "p"]
    np.testing.assert_allclose(num.a.toarray(), [[M + m, -m * l], [-m * l, m * l * l]], rtol=1e-15)
    np.testing.assert_allclose(num.c.toarray(), [[0, 0], [0, -m * g * l]], rtol=1e-15)
    md = numeric.modes(num.a.toarray(), num.b.toarray(), num.c.toarray())
    np.testing.assert_allclose(md.omega2, [-(M + m) * g / (M * l), 0.0], rtol=1e-12, atol=1e-12)
    assert md.kinds == ["unstable", "rigid"]
    assert md.zeta == [None, None]


def test_slow_elastic_mode_and_undamped_ratios():
    """A long pendulum (omega^2 = g/l = 0.25 1/s^2 < 1) is elastic; beside a free slide (rigid) the
    undamped ratios are None (rigid) and 0 (elastic); one elastic mode: spread 1; Jacobi-scaled
    stiffness diag(0 or 1): condition 1."""
    g, l = 9.81, 9.81 / 0.25
    m = mech({
        "parameters": {"g": param(g, "m/s^2")},
        "coordinates": [{"name": "x", "type": "slide", "axis": [0, 0, 1]},
                        {"name": "p", "type": "angle", "axis": [0, 0, 1]}],
        "points": [{"name": "O", "at": [0, 0, 0]}, {"name": "H", "from": "O", "vector": [0, 0, 0], "slides": ["x"]},
                   {"name": "B", "from": "O", "vector": [0, -l, 0], "turns": ["p"]}],
        "bodies": [{"name": "puck", "mass": 2.0, "com": "H"}, {"name": "bob", "mass": 1.0, "com": "B"}],
        "gravity": {"g": "g"},
    })
    num = numeric.assemble(m)
    md = numeric.modes(num.a.toarray(), num.b.toarray(), num.c.toarray())
    np.testing.assert_allclose(md.omega2, [0.0, 0.25], rtol=1e-12, atol=1e-15)
    assert md.kinds == ["rigid", "elastic"]
    assert md.zeta == [None, 0.0]
    assert md.spread == 1.0 and md.condition == 1.0


def test_no_stiffness_all_rigid():
    md = numeric.modes(np.diag([2.0, 3.0]), np.zeros((2, 2)), np.zeros((2, 2)))
    assert md.kinds == ["rigid", "rigid"] and md.zeta == [None, None]
    assert md.spread == 1.0 and md.condition == 1.0


def test_condition_of_the_jacobi_scaled_stiffness():
    """Wall -k1- m1 -k2- m2: D c D = [[1, -r], [-r, 1]], r = sqrt(k2/(k1+k2)): condition (1+r)/(1-r);
    spread = omega2_max/omega2_min of the closed-form two-mass roots."""
    k1, k2, m1, m2 = 300.0, 120.0, 1.0, 2.0
    num = numeric.assemble(spring_chain([m1, m2], [k1, k2]))
    md = numeric.modes(num.a.toarray(), num.b.toarray(), num.c.toarray())
    r = math.sqrt(k2 / (k1 + k2))
    assert md.condition == pytest.approx((1 + r) / (1 - r), rel=1e-12)
    p, q = (k1 + k2) / m1 + k2 / m2, k1 * k2 / (m1 * m2)
    lo, hi = (p - math.sqrt(p * p - 4 * q)) / 2, (p + math.sqrt(p * p - 4 * q)) / 2
    assert md.spread == pytest.approx(hi / lo, rel=1e-12)
    assert md.kinds == ["elastic", "elastic"]
    # Two unit-diagonal pairs coupled by b and e up to 7e76 (D = I): eigenvalues 1 -+ b, 1 -+ e, condition
    # (b + 1)/(e - 1), which must come out correctly rounded: LAPACK's dsyevr rescales a matrix whose largest
    # entry passes ~8.2e76 (by a factor that is not a power of two, costing the last bit), so the scaling must
    # not carry these across
    for b, e in [(4e76, 3e75), (7e76, 3e75), (6e76, 7e75)]:
        c = np.array([[1, b, 0, 0], [b, 1, 0, 0], [0, 0, 1, e], [0, 0, e, 1]])
        md = numeric.modes(np.eye(4), np.zeros((4, 4)), c)
        assert md.condition == float((Fraction(b) + 1) / (Fraction(e) - 1))
        assert md.kinds == ["unstable", "unstable", "elastic", "elastic"]


@pytest.mark.parametrize("gap_in_eps, kinds", [(38, ["rigid", "elastic"]), (42, ["elastic", "elastic"])])
def test_null_eigenvalue_threshold_is_ten_n_eps_of_the_largest(gap_in_eps, kinds):
    """c = [[1, 1 - d], [1 - d, 1]] (D = I): eigenvalues d and 2 - d; a null one is within 10 n eps (2 - d) =
    40 eps of the largest, so d = 38 eps is a rigid mode and d = 42 eps an elastic one (2 eps either side of the
    threshold, the 2 x 2 eigenvalue's round-off about one eps)."""
    eps = np.finfo(float).eps
    d = gap_in_eps * eps
    c = np.array([[1.0, 1.0 - d], [1.0 - d, 1.0]])
    found, condition = numeric.classify(c, np.array([d, 2.0 - d]))
    assert found == kinds
    if kinds[0] == "elastic":
        assert condition == pytest.approx((2.0 - d) / d, rel=0.1)


def test_light_mechanism_is_not_refused_and_the_refusal_names_the_field():
    """The singular-mass test is relative: 1e-9 kg beside 1e-13 kg m^2 is a regular (small) mass
    matrix; an eigenvalue at 1e-12 of the largest is refused, naming the coordinate's field and
    the smallest eigenvalue."""
    m = spring_chain([1.0, 1.0], [10.0, 10.0])
    numeric.check_mass(m, np.diag([1e-9, 1e-13]))
    with pytest.raises(SceneError) as err:
        numeric.check_mass(m, np.diag([1.0, 1e-12]))
    assert err.value.field == "coordinates[1]"
    assert "(smallest eigenvalue 1e-12 of 1): coordinate 's2' moves no mass" in str(err.value)
