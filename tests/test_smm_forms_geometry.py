"""The vector-chain form's geometry (smm/forms.py) on mechanisms written out here: a bad vector expression is refused
naming its point, and a coordinate that both turns and lengthens a chain vector (a screw through the API) has
dr/dq = e x v + e, the two parts summed."""
import pytest

from symmech.core.scene import SymmechError
from symmech.smm import forms, model


def arm(vector, turns=(), slides=()):
    """A point P at `vector` from the ground point O, moved by the one coordinate q about / along z."""
    return model.Mechanism(
        name="arm", parameters={"m": model.Parameter("m", 1.0, "kg", "mass")},
        coordinates=[model.Coordinate("q", "angle", ("0", "0", "1"))],
        points={"O": model.Point("O", None, ("0", "0", "0")),
                "P": model.Point("P", "O", vector, turns=turns, slides=slides)},
        bodies=[model.Body("bob", "m", ("0", "0", "0"), "P", turns)])


def test_a_bad_vector_expression_is_refused_naming_its_point():
    m = arm(("1/0", "0", "0"))
    with pytest.raises(SymmechError) as refused:
        forms.Geometry(m, model.numeric(m))
    assert str(refused.value).startswith("point 'P': expression '1/0' cannot be evaluated")


def test_a_coordinate_that_turns_and_slides_a_vector_moves_it_by_both():
    """v = (2, 0, 0) turned about z and lengthened along z by q: D[q] = e_z x v + e_z = (0, 2, 1)."""
    m = arm(("2", "0", "0"), turns=("q",), slides=("q",))
    g = forms.Geometry(m, model.numeric(m))
    kin = forms.chain_kinematics(g, "P", False)
    assert kin.r == (2.0, 0.0, 0.0)
    assert kin.D == {"q": (0.0, 2.0, 1.0)}
