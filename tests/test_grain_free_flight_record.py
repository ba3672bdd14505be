"""The exact free rotation's constants as the compiled twin reads them (free_flight.ExactRotation.record): each field
at its offset in the FreeRotation layout, the fields in declaration order, their sizes summed here."""
import math

import numpy as np
import pytest

from symmech.grain import free_flight


def fields_of(vector):
    """{name: value} of a FreeRotation vector, by the layout's fields in order."""
    out, at = {}, 0
    for f in free_flight.ROTATION.fields:
        out[f.name] = vector[at:at + f.size]
        at += f.size
    assert at == len(vector)
    return out


def test_the_record_holds_the_start_and_the_body_at_their_offsets():
    """An asymmetric body (1, 2, 3) kg m^2 from q0 = (1, 1, 0, 0) (normalised: a quarter turn about x) at t0 = 0.25 s."""
    rot = free_flight.ExactRotation((1.0, 2.0, 3.0), (1.0, 1.0, 0.0, 0.0), (0.3, 0.2, 1.0), 0.25)
    got = fields_of(rot.record())
    assert got["t0"].tolist() == [0.25]
    np.testing.assert_allclose(got["q0"], [math.sqrt(0.5), math.sqrt(0.5), 0.0, 0.0], rtol=1e-15)
    assert got["w0"].tolist() == [0.3, 0.2, 1.0] and got["inertia"].tolist() == [1.0, 2.0, 3.0]
    assert got["fixed_axis"].tolist() == [0.0]
    momentum = math.sqrt(0.3**2 + 0.4**2 + 3.0**2)  # |I w|
    assert got["momentum"][0] == pytest.approx(momentum, rel=1e-15)
