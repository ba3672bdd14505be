"""The compiled grain engine on an impact that gains energy: the needle of test_grain_motion_closed_forms.py (5:1:1,
tumbling onto a still plate under the printed law with e = lam = 0.9, which gains 5 % kinetic energy there) gets
both warnings of the law, the second with the energies before and after written by hand from the impact log."""
import numpy as np
import pytest

from symmech.grain import compiled, flight, motion
from symmech.grain.coulomb_law import ImpactLaw
from test_grain_motion_closed_forms import EZ, G, numerics, quaternion_matrix

pytestmark = [pytest.mark.slow, pytest.mark.compiled_engine]  # the engine's build: slow tier (conftest.py)


def test_the_printed_laws_energy_gain_is_warned_with_its_energies():
    axes, m = np.array([5e-3, 1e-3, 1e-3]), 1e-6
    q0 = np.array([-0.529, 0.693, -0.481, 0.091]) / np.linalg.norm([-0.529, 0.693, -0.481, 0.091])
    Q = quaternion_matrix(q0)
    n = Q.T @ EZ
    model = motion.Model(tuple(axes), m, (0.0, 0.0, -G), flight.Vibration(0.0, 1.0, 0.0, (0.0, 0.0, 1.0)),
                         ImpactLaw("printed", e=0.9, lam=0.9), 0.3, motion.Effects())
    st = motion.State(0.0, np.array([0.0, 0.0, np.linalg.norm(axes * n) + 1e-9]), np.array([0.01, 0.084, -0.3]),
                      q0, Q.T @ np.array([43.5, 3.4, -2.4]))
    res = compiled.simulate(model, numerics(), st, 1e-5)
    imp = res.impacts[0]
    inertia = m / 5 * (np.sum(axes**2) - axes**2)  # solid ellipsoid, body axes
    ke0, ke1 = (0.5 * m * np.dot(imp[v], imp[v]) + 0.5 * np.dot(inertia, np.square(imp[w]))
                for v, w in (("v_before", "w_before"), ("v_after", "w_after")))
    assert ke1 > 1.04 * ke0 and imp["printed_creates_energy"] is True
    assert res.warnings[:2] == ["printed impact law: no admissible root; the one used creates kinetic energy",
                                f"impact law 'printed' created energy: {ke0:.6g} J -> {ke1:.6g} J"]
