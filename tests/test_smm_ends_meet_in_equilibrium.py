"""A damper or spring whose ends meet only in the equilibrium that `equilibrium.solve` finds (spatial, so
through forms.assemble): the redrawn model is made without the scene's end checks, so the assembly itself
must refuse the element, not give it a direction from round-off (the ends end up ~1e-15 m apart)."""
import pytest

from symmech.core.scene import SymmechError
from symmech.smm import numeric

from smm_helpers import mech


def _bob_pulled_to_origin(element: dict):
    """A bob P on slides x, y, z, drawn at (0.3, 0.2, 0.1), held by two equal springs from (-1, 0, 0) and
    (1, 0, 0) (free length 0.5 m), so in equilibrium at the origin O, where ``element`` joins O and P; a
    pendulum turned about x then y makes the mechanism spatial."""
    return mech({
        "coordinates": [{"name": "a", "type": "angle", "axis": [1, 0, 0]},
                        {"name": "b", "type": "angle", "axis": [0, 1, 0]},
                        {"name": "x", "type": "slide", "axis": [1, 0, 0]},
                        {"name": "y", "type": "slide", "axis": [0, 1, 0]},
                        {"name": "z", "type": "slide", "axis": [0, 0, 1]}],
        "points": [{"name": "O", "at": [0, 0, 0]}, {"name": "B1", "at": [-1, 0, 0]}, {"name": "B2", "at": [1, 0, 0]},
                   {"name": "P", "from": "O", "vector": [0.3, 0.2, 0.1], "slides": ["x", "y", "z"]},
                   {"name": "Q", "from": "O", "vector": [0, 0, -0.5], "turns": ["a", "b"]}],
        "bodies": [{"name": "bob", "mass": 1.0, "com": "P"},
                   {"name": "pendulum", "mass": 1.0, "inertia": [0.1, 0.1, 0.1], "com": "Q"}],
        "springs": [{"name": "s1", "ends": ["B1", "P"], "stiffness": 100.0, "free_length": 0.5},
                    {"name": "s2", "ends": ["B2", "P"], "stiffness": 100.0, "free_length": 0.5}]
        + ([element] if "stiffness" in element else []),
        "dampers": [element] if "viscosity" in element else []})


@pytest.mark.parametrize("element, message", [
    ({"name": "d", "ends": ["O", "P"], "viscosity": 1.0},
     "damper 'd': its ends 'O' and 'P' coincide (zero length)"),
    ({"name": "s0", "ends": ["O", "P"], "stiffness": 10.0, "free_length": 0.0},
     "spring 's0': its ends 'O' and 'P' coincide (zero length); a spring needs a direction")])
def test_element_whose_ends_meet_in_equilibrium_is_refused(element, message):
    with pytest.raises(SymmechError) as err:
        numeric.solve_equilibrium(_bob_pulled_to_origin(element))
    assert str(err.value) == message
