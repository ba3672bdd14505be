"""The fused reactions ``trolley_dynamics.reactions_along_track`` (one generated function from
θ, dθ/ds, d²θ/ds², V0, V̇0) against the chain of five generated functions glued with numpy that
``trolley.model`` runs, at seeded random points, in both targets."""
import numpy as np
import pytest

from symmech.generated import trolley_dynamics as dyn
from symmech.generated import trolley_dynamics_nb as dyn_nb
from symmech.generated import trolley_frame as frm

N = 500
BODY = (120.0, 0.9, 0.6, -0.15, 11.0, 23.0, 31.0, 1.5, -2.0, 0.7)  # m, r1..r3, I11 I22 I33 I12 I23 I13
G0, L, AH = 9.81, 2.2, 0.8


def _points(seed):
    rng = np.random.default_rng(seed)
    th = rng.uniform(-1.4, 1.4, (3, N))
    dth = rng.normal(0.0, 0.3, (3, N))
    ddth = rng.normal(0.0, 0.1, (3, N))
    return th, dth, ddth, rng.uniform(-30.0, 30.0, N), rng.normal(0.0, 3.0, N)


def _chain(th, dth, ddth, v0, dv0):
    """Ω, Ω' -> α, β (e = x1, e' = 0) -> a, ω, ω̇, ν = Λ e2 -> reactions (11): the runtime's route."""
    lam = frm.Lambda(*th)
    W, dW = frm.omega_per_length(*th, *dth), frm.omega_per_length_rate(*th, *dth, *ddth)
    one, zero = np.ones_like(v0), np.zeros_like(v0)
    c = dyn.point_coefficients(one, zero, zero, zero, zero, zero, *W.T, *dW.T, *BODY[1:4])
    acc = dv0[:, None] * c[:, :3] + (v0**2)[:, None] * c[:, 3:]
    w, dw = v0[:, None] * W, dv0[:, None] * W + (v0**2)[:, None] * dW
    return dyn.reactions(*BODY, *acc.T, *w.T, *dw.T, *lam[:, :, 1].T, G0, L, AH)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_fused_reactions_equal_the_chain(seed):
    th, dth, ddth, v0, dv0 = _points(seed)
    expected = _chain(th, dth, ddth, v0, dv0)
    scale = np.abs(expected).max()
    assert scale > 1e3  # the points load the rails: a test of something
    for module in (dyn, dyn_nb):
        got = module.reactions_along_track(*th, *dth, *ddth, v0, dv0, *BODY, G0, L, AH)
        assert got.shape == (N, 6)
        assert np.abs(got - expected).max() <= 1e-12 * scale


def test_fused_reactions_at_rest_on_a_level_straight_track():
    """Closed form: a level, straight track at rest carries only the weight. In the sign of (11)
    (ΣP = m a + m g0 ν, x2 up): P1 + P2 + P3 = m g0, and the moments about O of P1 at (0, 0, −ah),
    P2 at (0, 0, ah), P3 at (l, 0, 0), all along x2, equal r × m g0 e2: P3 l = m g0 r1,
    (P2 − P1) ah = m g0 r3."""
    zero = np.zeros(1)
    P = dyn.reactions_along_track(*[zero] * 9, zero, zero, *BODY, G0, L, AH)[0]
    m, r1, r3 = BODY[0], BODY[1], BODY[3]
    assert P[[0, 4, 5]] == pytest.approx([0.0, 0.0, 0.0], abs=1e-12)
    assert P[1] + P[2] + P[3] == pytest.approx(m * G0, rel=1e-14)
    assert P[3] * L == pytest.approx(m * G0 * r1, rel=1e-14)
    assert (P[2] - P[1]) * AH == pytest.approx(m * G0 * r3, rel=1e-13)
