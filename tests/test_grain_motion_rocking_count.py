"""The Python grain loop counts every rocking contact and warns once with the count: the crop grain of
test_grain_hard_cases.py at 1 mm, 32 Hz over 0.2 s ends four geometric series of bounces (flights shrinking by
e_n = 0.4). Where the series accumulates, the surface's normal force, written here from the vibration
(n = -A w^2 sin(w t + phase) d_z - g_z), decides: negative, a rocking contact (the tilting spin dropped, it flies
on); positive, a landing. Two of each."""
import math

import numpy as np

from symmech.grain import motion
from test_grain_hard_cases import CROP, sweep_grain


def normal_force(model, t: float) -> float:
    """Normal force per unit mass [m/s^2] the surface must exert to hold a grain at time t [s]."""
    vib = model.vibration
    return -vib.amplitude * vib.omega**2 * math.sin(vib.omega * t + vib.phase) * vib.direction[2] - model.g_k[2]


def test_two_rocking_contacts_are_counted_and_warned_with_their_number():
    sc = sweep_grain(CROP, 1.0e-3, 32.0, 0.2)
    res = motion.simulate(sc.model, sc.numerics, sc.start, sc.duration)
    ts = np.array([i["t"] for i in res.impacts])
    flights = np.diff(ts)
    # a series ends at an impact after a flight below 10 us followed by one over 1 ms (or by none)
    after = np.append(flights, np.inf)
    ends = [k for k in range(1, len(ts)) if flights[k - 1] < 1e-5 and after[k] > 1e-3]
    assert len(ends) == 4
    for k in ends:
        np.testing.assert_allclose(flights[k - 6:k - 1] / flights[k - 7:k - 2], 0.4, rtol=2e-2)
    pulls_away = [normal_force(sc.model, ts[k]) < 0 for k in ends]
    assert pulls_away == [True, False, False, True]
    assert res.extra["rocking_contacts"] == 2 and res.extra["landings"] == 2
    rocking = [w for w in res.warnings if "rocking contact" in w]
    assert len(rocking) == 1 and rocking[0].startswith("2 rocking contact(s): ")
    budget = res.extra["energy_budget"]
    assert budget["lost_at_landings_J"] > 0 and budget["relative_residual"] < 1e-9
