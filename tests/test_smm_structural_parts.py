"""The graph form of symmech.smm.structural on one-coordinate mechanisms whose a, c and dΠ/dq are written by hand:
a torsion spring's preload moment, a mechanism without bodies; the fields its messages name when a caller's
parameter values make an expression fail (through the API: the scene's validation evaluates them first with the
scene's own values); its values are floats whatever the parameters' type."""
import numpy as np
import pytest

from symmech.core.scene import SymmechError
from symmech.smm import structural
from symmech.smm.model import Effects, NumericArith

from smm_helpers import mech, param

ALL = Effects(True, True, True)


def arm(**extra) -> dict:
    """A bob m at the end of a horizontal arm l on the hinge q at O, under gravity g along -y."""
    return {"parameters": {"m": param(2.0, "kg"), "l": param(0.3, "m"), "g": param(9.81, "m/s^2"),
                           **extra.pop("parameters", {})},
            "coordinates": [{"name": "q", "type": "angle"}],
            "points": [{"name": "O", "at": [0, 0]}, {"name": "P", "from": "O", "vector": ["l", 0], "turns": ["q"]}],
            "bodies": [{"name": "b", "mass": "m", "com": "P"}],
            "gravity": {"g": "g"}, **extra}


def test_a_preloaded_torsion_spring_adds_its_moment_to_the_residual():
    """Π = m g l sin q + M0 q + ½ k q² (the spring's moment M0 at q = 0): dΠ/dq = m g l + M0, d²Π/dq² = k and
    a = m l² at q = 0; the model is valid, so a refusal is a wrong answer too."""
    m = mech(arm(parameters={"k": param(40.0, "N m/rad"), "M0": param(1.25, "N m")},
                 torsion_springs=[{"name": "t", "bodies": ["ground", "b"], "stiffness": "k", "preload": "M0"}]))
    try:
        a, _, c, *_ = out = structural.assemble(m, NumericArith(m.values()), ALL, {})
    except SymmechError as exc:
        pytest.fail(f"a valid mechanism refused: {exc}")
    np.testing.assert_allclose(out[5], [2.0 * 9.81 * 0.3 + 1.25], rtol=1e-14)
    np.testing.assert_allclose(a.toarray(), [[2.0 * 0.3**2]], rtol=1e-14)
    np.testing.assert_allclose(c.toarray(), [[40.0]], rtol=1e-14)


def test_a_mechanism_without_bodies_has_no_inertia_and_its_springs_stiffness():
    """A massless slider x on a spring k along it: a = 0, c = k, dΠ/dq = 0 (no preload, no weight)."""
    m = mech({"parameters": {"k": param(40.0, "N/m"), "l": param(0.3, "m")},
              "coordinates": [{"name": "x", "type": "slide", "axis": [1, 0]}],
              "points": [{"name": "O", "at": [0, 0]},
                         {"name": "P", "from": "O", "vector": ["l", 0], "slides": ["x"]}],
              "springs": [{"name": "s", "ends": ["O", "P"], "stiffness": "k"}]})
    a, _, c, *_ = out = structural.assemble(m, NumericArith(m.values()), ALL, {})
    np.testing.assert_array_equal(a.toarray(), [[0.0]])
    np.testing.assert_allclose(c.toarray(), [[40.0]], rtol=1e-14)
    np.testing.assert_array_equal(out[5], [0.0])


def message(m, values: dict) -> str:
    """The one-line refusal of assembling ``m`` with the parameters ``values``."""
    with pytest.raises(SymmechError) as info:
        structural.assemble(m, NumericArith({**m.values(), **values}), ALL, {})
    return str(info.value)


def test_a_root_point_or_gravity_direction_that_cannot_be_evaluated_is_named():
    """1/z at z = 0 in the root point's position, then in the gravity direction: the message names the field."""
    d = arm(parameters={"z": param(1.0), "w": param(1.0)}, gravity={"g": "g", "direction": [0, "-1/w"]})
    d["points"][0]["at"] = ["1/z - 1", 0]
    m = mech(d)
    assert message(m, {"z": 0.0}).startswith("point 'O': expression '1/z - 1' cannot be evaluated")
    assert message(m, {"w": 0.0}).startswith("gravity.direction: expression '-1/w' cannot be evaluated")


def test_values_are_floats_for_integer_parameters():
    """A caller's integer parameter: n*a (the parser's shortcut for multiples) is an int, the values still floats."""
    values = structural.values(NumericArith({"a": 2}), ["3*a", "4*a", "3*a"], "masses")
    assert values.dtype == np.float64
    assert values.tolist() == [6.0, 8.0, 6.0]
