"""The state the Python grain loop starts from: its own float arrays, whatever the caller passed (lists of
integers here), with the orientation normalised — seen in a run that ends where it starts, where the loop never
replaces that state (otherwise every phase builds new arrays)."""
import numpy as np
import pytest

from symmech.grain import motion
from test_grain_motion_closed_forms import G, I, M, frictionless, numerics, sphere


def test_a_run_of_no_duration_ends_in_its_start_as_float_arrays():
    r, v, q, w = [0, 0, 1], [1, 0, -2], [0, 0, 0, 3], [0, 4, 0]  # 1 m up, q = 3 (0, 0, 0, 1): half a turn about z
    start = motion.State(0.0, r, v, q, w)
    res = motion.simulate(sphere(frictionless(0.5)), numerics(), start, 0.0)
    final = res.final
    for got, want in ((final.r, r), (final.v, v), (final.q, [0, 0, 0, 1]), (final.w, w)):
        assert isinstance(got, np.ndarray) and got.dtype == np.float64
        np.testing.assert_array_equal(got, want)
    assert final.t == 0.0 and res.impacts == [] and res.time_in == {"flight": 0.0, "sliding": 0.0}
    # the start and the end row: t, r, v, q, the world spin (half a turn about z: (0, -4, 0)), flight
    np.testing.assert_array_equal(res.trajectory, [[0, 0, 0, 1, 1, 0, -2, 0, 0, 0, 1, 0, -4, 0, 0]] * 2)
    energy = 0.5 * M * 5.0 + 0.5 * I * 16.0 + M * G * 1.0
    budget = res.extra["energy_budget"]
    assert budget["start_J"] == pytest.approx(energy, rel=1e-15) and budget["end_J"] == budget["start_J"]
    assert budget["residual_J"] == 0.0
