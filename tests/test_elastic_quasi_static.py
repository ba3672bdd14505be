"""The quasi-static state of the elastic trolley (Newton on R(q, 0, 0) = 0) against closed forms.

A pinned beam with held ends, horizontal, one Ritz function per plane, sagging under gravity: bending
K q, stretching 4 c H² q³ (Π_m = c (H q²)², c = EA/(8 L³)) and the weight f = g ρA L ∫ N dξ balance on the
real root of K q + 4 c H² q³ + f = 0 (numpy's roots), far from the linear sag -f/K: Newton needs several
steps. A body whose rollers all have free play carries no load: refused in one sentence."""
import numpy as np
import pytest

from symmech.core.scene import SymmechError
from symmech.generated import trolley_elastic as gen
from symmech.trolley.elastic import system as el, body as el_body, frame as el_frame

pytestmark = pytest.mark.xdist_group("test_elastic_quasi_static")

L, RHO_A, EI, EA, G0 = 2.0, 1.5, 10.0, 1e7, 9.81
AT_REST = el_frame.FrameState(np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3), np.array([0.0, 1.0, 0.0]))


@pytest.fixture(scope="module")
def sagging():
    """The system (beam along x1 bending along x2, up), the closed-form sag q1 [m] of its first plane, the bending
    stiffness EI/L³ ∫ N''² dξ [N/m] and the slope integral ∫ N'² dξ [1] of its one function."""
    beam = el_body.Beam((0, 0, 0), (1, 0, 0), (0, 1, 0), L, RHO_A, (EI, EI), "pinned", 1, axial="held", ea=EA)
    mdl = el_body.ElasticModel(100.0, (0, 0, 0), (1, 1, 1, 0, 0, 0), 2.0, 1.0, G0, None, (beam,), el_body.Effects(rollers=False))
    x, w = np.polynomial.legendre.leggauss(30)
    x, w = (x + 1) / 2, w / 2
    n, d1, d2 = np.moveaxis(gen.pinned_basis(x)[:, :, 0], 1, 0)
    k, h, load = EI / L ** 3 * w @ d2 ** 2, w @ d1 ** 2, G0 * RHO_A * L * (w @ n)
    roots = np.roots([4 * EA / (8 * L ** 3) * h * h, 0.0, k, load])
    (sag,) = roots[np.abs(roots.imag) < 1e-9].real
    assert abs(sag) < 0.1 * load / k  # the stretching carries the load, not the bending
    return el.System(mdl), sag, k, h


def test_held_beam_sags_to_the_root_of_the_cubic(sagging):
    system, sag, _, _ = sagging
    q = system.quasi_static(AT_REST)
    assert q == pytest.approx([sag, 0.0], rel=1e-12, abs=1e-15)


def test_potential_is_bending_plus_stretching(sagging):
    """Π = ½ k (q1² + q2²) + c (h (q1² + q2²))²: the planes bend apart and stretch the one beam together."""
    system, _, k, h = sagging
    q = np.array([0.03, -0.02])
    square = q @ q
    assert system.potential(q) == pytest.approx(0.5 * k * square + EA / (8 * L ** 3) * (h * square) ** 2, rel=1e-12)


def test_newton_starts_from_the_given_state_and_counts_its_steps(sagging):
    system, sag, _, _ = sagging
    start = np.array([sag * (1 + 1e-9), 0.0])
    assert system.quasi_static(AT_REST, start, max_iter=2) == pytest.approx([sag, 0.0], rel=1e-12, abs=1e-15)
    with pytest.raises(SymmechError, match=r"^no quasi-static state of the elastic model \(Newton did not converge "
                                           r"in 2 steps; residual [0-9.e+-]+\)$"):
        system.quasi_static(AT_REST, max_iter=2)


def test_free_play_of_every_roller_is_refused():
    rollers = el_body.Rollers((1e6,) * 5, (0.0,) * 5, "clamped_pair", (-1e-3,) * 5)
    system = el.System(el_body.ElasticModel(100.0, (0.5, 0.3, 0), (10, 20, 15, 0, 0, 0), 2.0, 1.0, G0, rollers))
    with pytest.raises(SymmechError, match=r"^no quasi-static state of the elastic model: its stiffness is singular "
                                           r"\(a free play of the rollers, elastic.rollers.preload < 0, carries no "
                                           r"load\)$"):
        system.quasi_static(AT_REST)


def test_preloaded_pair_beyond_its_preload_carries_the_weight():
    """Stiff clamped pairs preloaded by 10 nm, deflected ~0.1 µm: Newton's first step (both rollers pushing, 2k) is
    half the answer, and the steps must shrink relative to the small q, not to 1 m. The reactions are the
    statics of three supports (B, C share what the front axle A does not carry)."""
    k = (2e9, 2e9, 4e9, 3e9, 2e9)
    rollers = el_body.Rollers(k, (0.0,) * 5, "clamped_pair", (1e-8,) * 5)
    system = el.System(el_body.ElasticModel(100.0, (0.8, 0.5, 0.0), (20.0, 30.0, 25.0, 0, 0, 0), 2.0, 1.0, G0, rollers))
    q = system.quasi_static(AT_REST)
    assert np.abs(q).max() < 1e-6
    total = 100.0 * G0
    front = total * 0.8 / 2.0
    P = system.reactions(AT_REST, q, 0 * q, 0 * q)
    assert np.allclose(P, [0, (total - front) / 2, (total - front) / 2, front, 0, 0], rtol=1e-6, atol=1e-6)
