"""The mechanism's lookups (smm/model.py), by hand on a small mechanism written out here: a point's chain from its
root, the refusals that name the missing point and where the chain broke, the characteristic points in first-use
order, a coordinate by name, and the numeric arithmetic over the parameters' values."""
import pytest

from symmech.core.scene import SymmechError
from symmech.smm import model


def mechanism(points):
    """A slider of mass m on a spring from the ground point O to its centre C (points: name -> parent)."""
    return model.Mechanism(
        name="lookup",
        parameters={"m": model.Parameter("m", 2.5, "kg", "mass"), "k": model.Parameter("k", 400.0, "N/m", "stiffness")},
        coordinates=[model.Coordinate("x", "slide", ("1", "0", "0"))],
        points={name: model.Point(name, parent, ("0.1", "0", "0"), slides=("x",) if parent else ())
                for name, parent in points.items()},
        bodies=[model.Body("slider", "m", ("0", "0", "0"), "C", ())],
        springs=[model.Link("s", "O", "C", "k", preload="0"), model.Link("t", "C", "B", "k", preload="0")])


def test_a_chain_runs_from_the_root_to_the_point():
    m = mechanism({"O": None, "B": "O", "C": "B"})
    assert [p.name for p in m.chain("C")] == ["O", "B", "C"]


def test_an_undefined_point_is_named():
    m = mechanism({"O": None, "B": "O", "C": "B"})
    with pytest.raises(SymmechError) as refused:
        m.chain("D")
    assert str(refused.value) == "point 'D' is not defined"


def test_a_broken_chain_names_the_missing_parent_and_whose_parent_it_is():
    """C's parent B is defined, B's parent G is not: the break is G, as the parent of B."""
    m = mechanism({"O": None, "B": "G", "C": "B"})
    with pytest.raises(SymmechError) as refused:
        m.chain("C")
    assert str(refused.value) == ("point 'C' is not reachable from a fixed root: parent point 'G' of 'B' is not "
                                  "defined")


def test_characteristic_points_in_first_use_order_once_each():
    """The body's centre C, then the springs' ends O, C, C, B: C, O, B."""
    assert mechanism({"O": None, "B": "O", "C": "B"}).characteristic_points() == ["C", "O", "B"]


def test_a_coordinate_is_found_by_name_and_an_unknown_one_is_named():
    m = mechanism({"O": None, "B": "O", "C": "B"})
    assert m.coordinate("x").kind == "slide"
    with pytest.raises(KeyError) as refused:
        m.coordinate("y")
    assert refused.value.args == ("y",)


def test_numeric_arithmetic_reads_the_parameters_values():
    arith = model.numeric(mechanism({"O": None, "B": "O", "C": "B"}))
    assert arith("k / m") == 160.0
    assert arith("3*m") == 7.5
