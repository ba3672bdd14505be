"""`elastic.simulate` against closed forms: a beam of one Ritz function per plane on a trolley at rest is a
damped oscillator of its own, so its coordinates, rates, energy, dissipated energy and the (zero) work of the
track follow from the start offsets alone.

The cantilever's one Ritz function is N1 = ξ² (derive_elastic.beam_functions): modal mass m = ρA L/5 + M_tip
(N1(1) = 1), stiffness k = EI ∫ N1''² dξ / L³ = 4 EI/L³; the stiffness-proportional damping of the plane
(2ζ/ω1) K gives that one mode the ratio ζ."""
import sys
from pathlib import Path

import numpy as np
import pytest

from symmech.trolley import elastic as el

sys.path.insert(0, str(Path(__file__).parent))
from test_trolley_elastic import straight  # noqa: E402

pytestmark = pytest.mark.xdist_group("test_elastic_simulate")

L, RHO_A, EI, TIP = 1.2, 4.0, (3e3, 5e3), 1.0
MASS = RHO_A * L / 5 + TIP  # kg, the one mode's
OMEGA = np.sqrt(4 * np.array(EI) / L ** 3 / MASS)  # rad/s, per plane


def mast(zeta):
    """A cantilever along x2 (plane 1 along x1) on a trolley on rigid rollers, no gravity: N = 2."""
    beam = el.Beam((0.5, 0.3, 0.0), (0, 1, 0), (1, 0, 0), L, RHO_A, EI, "cantilever", 1, TIP, zeta)
    return el.System(el.ElasticModel(80.0, (0.8, 0.4, 0.1), (10.0, 20.0, 15.0, 0, 0, 0), 2.0, 1.0, 0.0, None,
                                     (beam,), el.Effects(rollers=False)))


def oscillator(q0, v0, omega, zeta, t):
    """Free damped oscillator from q0 [m], v0 [m/s]: (q, q̇) at t."""
    wd = omega * np.sqrt(1 - zeta ** 2)
    decay = np.exp(-zeta * omega * t)
    c, s = np.cos(wd * t), np.sin(wd * t)
    b = (v0 + zeta * omega * q0) / wd
    q = decay * (q0 * c + b * s)
    qd = decay * ((b * wd - zeta * omega * q0) * c - (q0 * wd + zeta * omega * b) * s)
    return q, qd


@pytest.mark.parametrize("method, zeta", [("Radau", 0.03), ("DOP853", 0.0)])
def test_a_kicked_mast_on_a_trolley_at_rest_is_two_free_oscillators(method, zeta):
    """Plane 1 offset by 0.1 mm (dq0), plane 2 started at 5 mm/s (dqd0), both at once in plane 2 as a check that
    the offsets add: q, q̇ of each plane to 2e-7 of the amplitude (measured 2e-8: the shortening's
    (a/L)²); E(t) = ½ m (q̇² + ω² q²) summed (the trolley at rest, no gravity) to 2e-7 of E(0), the dissipated
    energy E(0) - E(t) (1e-7), the work of the track 0."""
    system = mast(zeta)
    t = np.linspace(0.0, 0.12, 25)  # a period of plane 1 (0.106 s), 0.8 of plane 2
    dq0, dqd0 = np.array([1e-4, -2e-5]), np.array([0.0, 5e-3])
    r = el.simulate(system, straight(), t, method, rtol=1e-10, dq0=dq0, dqd0=dqd0)
    assert r["names"] == ["beam0_p1_m1", "beam0_p2_m1"]
    energy = 0.0
    for plane in range(2):
        q, qd = oscillator(dq0[plane], dqd0[plane], OMEGA[plane], zeta, t)
        scale = max(abs(dq0[plane]), abs(dqd0[plane]) / OMEGA[plane])
        np.testing.assert_allclose(r["q"][:, plane], q, rtol=0, atol=2e-7 * scale)
        np.testing.assert_allclose(r["qd"][:, plane], qd, rtol=0, atol=2e-7 * scale * OMEGA[plane])
        energy = energy + 0.5 * MASS * (qd ** 2 + OMEGA[plane] ** 2 * q ** 2)
    np.testing.assert_allclose(r["E"], energy, rtol=0, atol=2e-7 * energy[0])
    np.testing.assert_allclose(r["dissipated"], energy[0] - energy, rtol=0, atol=1e-7 * energy[0])
    if zeta > 0:
        assert r["dissipated"][-1] > 0.1 * energy[0]
    np.testing.assert_allclose(r["work"], 0.0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(r["t"], t, rtol=0, atol=0)
