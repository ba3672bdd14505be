"""What a user reads or gets back at the edges the mutation triage had called harmless: the elastic trolley's
refusal after Newton's default step budget, the rocking warning's words, a quiet Chatterjee-Ruina law at its
half-space and frictionless limits, and trajectory rows sampled more than 1 s apart (the schema allows it).

Expected values are written here: the default budget (50 steps) from the signature's documentation, the
rocking warning as grain/outcome.py words it for both engines (a literal here: a change of words is a decision),
the sphere's closed-form impulse, the parabola of a free fall.
"""
import math
import warnings

import numpy as np
import pytest

from symmech.core.scene import SymmechError
from symmech.grain import flight, motion, outcome
from symmech.grain.coulomb_law import ImpactLaw, coulomb_impulse
from symmech.trolley.elastic import system as el, body as el_body, frame as el_frame

G = 9.81


def test_newton_refuses_after_fifty_steps_by_default_and_says_so():
    """A held pinned beam sagging under gravity; Newton on K q + 4 c H² q³ + f = 0 from q = 10⁶ m shrinks q by
    about a third a step (the cubic dominates), so it is still far off after 50 steps and converges within 80."""
    beam = el_body.Beam((0, 0, 0), (1, 0, 0), (0, 1, 0), 2.0, 1.5, (10.0, 10.0), "pinned", 1, axial="held", ea=1e7)
    model = el_body.ElasticModel(100.0, (0, 0, 0), (1, 1, 1, 0, 0, 0), 2.0, 1.0, G, None, (beam,),
                            el_body.Effects(rollers=False))
    system = el.System(model)
    at_rest = el_frame.FrameState(np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3), np.array([0.0, 1.0, 0.0]))
    far = np.array([1e6, 0.0])
    with pytest.raises(SymmechError, match=r"^no quasi-static state of the elastic model \(Newton did not converge "
                                           r"in 50 steps; residual [0-9.e+-]+\)$"):
        system.quasi_static(at_rest, far)
    sag = system.quasi_static(at_rest, far, max_iter=80)[0]
    assert -0.05 < sag < -0.03  # the real root of the cubic (tests/test_elastic_quasi_static.py: -0.0408 m)


def test_rocking_warning_reads_as_documented():
    assert outcome.rocking_warning(3) == (
        "3 rocking contact(s): a tumbling ellipsoid held on the plane by its spin while the surface accelerates "
        "away; rocking is not modelled, so its tilting spin was dropped (booked as landing loss) and it flew on")


@pytest.mark.parametrize("mu", [math.inf, 0.0])
def test_coulomb_law_at_its_limits_is_silent_and_exact(mu):
    """A sphere (K = diag(7/2, 7/2, 1)/m): at μ = ∞ the friction-cone branch divides by D_z = 0, at μ = 0 by μ
    (0/0 for a head-on impact); both are masked by `where`, so numpy must not warn. Closed forms: P_n =
    -(1 + e_n) m u_z; P_t = -(1 + e_t) m u_t / 3.5 (sticking, μ = ∞) or 0 (μ = 0)."""
    m, e_n, e_t = 3e-5, 0.5, 0.2
    u = np.array([[0.6, -0.3, -1.0], [0.0, 0.0, -0.7], [0.2, 0.1, -0.3]])
    K = np.broadcast_to(np.diag([3.5, 3.5, 1.0]) / m, (3, 3, 3))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        P = coulomb_impulse(K, u, e_n, e_t, mu)
    sticking = mu == math.inf
    expected = np.column_stack([-(1 + e_t) * m * u[:, :2] / 3.5 * sticking, -(1 + e_n) * m * u[:, 2]])
    np.testing.assert_allclose(P, expected, rtol=1e-13, atol=0)


@pytest.mark.parametrize("interval", [2.0, 0.5])
def test_rows_more_than_a_second_apart_are_all_kept(interval):
    """A ball falling from 400 m from t = 3 s to 11 s (no contact), rows every 2 s or 0.5 s: the start, the
    multiples of the interval between (4, 6, 8, 10 s; 3.5, 4, ..., 10.5 s), the end; positions on the parabola."""
    law = ImpactLaw("coulomb", e_n=0.5, e_t=0.0, mu=0.0, check_printed=False)
    still = flight.Vibration(0.0, 2 * math.pi * 20.0, 0.0, (0.0, 0.0, 1.0))
    model = motion.Model((1e-3,) * 3, 2e-6, (0.0, 0.0, -G), still, law, 0.5, motion.Effects(rotation=True))
    numerics = motion.Numerics(tolerance=1e-11, scan_step=0.05, sample_interval=interval)
    start = motion.State(3.0, np.array([0.0, 0.0, 400.0]), np.array([0.1, 0.0, 0.0]), np.array([1.0, 0, 0, 0]),
                         np.zeros(3))
    rows = motion.simulate(model, numerics, start, 11.0).trajectory
    between = np.arange(math.floor(3.0 / interval) + 1, math.ceil(11.0 / interval)) * interval
    t = np.concatenate([[3.0], between, [11.0]])
    np.testing.assert_allclose(rows[:, 0], t, rtol=0, atol=1e-12)
    np.testing.assert_allclose(rows[:, 1], 0.1 * (t - 3.0), rtol=0, atol=1e-9)
    np.testing.assert_allclose(rows[:, 3], 400.0 - 0.5 * G * (t - 3.0) ** 2, rtol=0, atol=1e-9)
