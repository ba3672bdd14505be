"""Two held beams on one trolley: the membrane energy, force and tangent stiffness are the sums of each
beam's own, and each beam's are those of its length and axial stiffness (independent quadrature route)."""
import numpy as np
import pytest
from numpy.polynomial import Legendre

from symmech.trolley.elastic import system as el, body as el_body
from symmech.trolley.elastic import membrane

RNG = np.random.default_rng(2)
# steel strips: (length [m], EA [N], modes); different lengths and sections, so no beam mirrors the other
BEAMS = ((2.0, 2.1e11 * 2e-4, 4), (1.3, 2.1e11 * 5e-5, 3))


def slopes(modes):
    """N_k'(ξ) (modes, P) of ξ(1 - ξ) P_(k-1)(2ξ - 1) at the 24 Gauss points of [0, 1], and the weights."""
    x, w = np.polynomial.legendre.leggauss(24)
    x, w = (x + 1) / 2, w / 2
    bubble = Legendre([1 / 6, 0.0, -1 / 6], domain=[0, 1])
    return np.array([(bubble * Legendre.basis(k, domain=[0, 1])).deriv()(x) for k in range(modes)]), w


def beam_membrane(q, length, ea, modes):
    """Π [J], ∂Π/∂q (2n,) and ∂²Π/∂q² (2n, 2n) of one held beam, q = [plane 1, plane 2] (2n,):
    Π = ½ EA L ε̄², mean strain ε̄ = 1/(2L) ∫0^L (w1'² + w2'²) dx = 1/(2L²) ∫0^1 ((q1·N')² + (q2·N')²) dξ."""
    d, w = slopes(modes)
    gram = np.einsum("p,kp,lp->kl", w, d, d) / length ** 2  # ∂²ε̄/∂q² per plane
    hess = np.kron(np.eye(2), gram)
    strain = 0.5 * q @ hess @ q
    grad = hess @ q
    return (0.5 * ea * length * strain ** 2, ea * length * strain * grad,
            ea * length * (np.outer(grad, grad) + strain * hess))


def two_held_beams():
    beams = tuple(el_body.Beam((0.1 * i, 0, 0), (0, 0, 1), (1, 0, 0), length, 7800 * ea / 2.1e11, (1e4, 2e4), "pinned",
                          modes, axial="held", ea=ea) for i, (length, ea, modes) in enumerate(BEAMS))
    mdl = el_body.ElasticModel(100.0, (0, 0, 0), (1, 1, 1, 0, 0, 0), 2.0, 1.0, 0.0, None, beams,
                          el_body.Effects(rollers=False, stiffening=True, membrane=True))
    return el.System(mdl)


def test_each_beam_owns_its_block():
    system = two_held_beams()
    blocks = system.inv.membrane
    assert len(blocks) == 2
    for i, (b, (length, ea, modes)) in enumerate(zip(blocks, BEAMS)):
        assert [system.inv.names[j] for j in b.index] == [f"beam{i}_p{p}_m{k}" for p in (1, 2)
                                                           for k in range(1, modes + 1)]
        assert b.c == pytest.approx(ea / (8 * length ** 3), rel=1e-15)
    # disjoint coordinates: the sums over beams add blocks that never overlap
    assert not set(blocks[0].index) & set(blocks[1].index)


def test_energy_force_and_stiffness_are_the_sums_over_both_beams():
    system = two_held_beams()
    blocks = system.inv.membrane
    for _ in range(3):
        q = RNG.normal(size=system.N) * 0.01
        shares, force, stiffness = [], np.zeros(system.N), np.zeros((system.N, system.N))
        for b, (length, ea, modes) in zip(blocks, BEAMS):
            e, f, k = beam_membrane(q[b.index], length, ea, modes)
            shares.append(e)
            force[b.index] += f
            stiffness[np.ix_(b.index, b.index)] += k
        energy = sum(shares)
        assert min(shares) > 0.01 * energy  # both beams carry a share
        assert membrane.energy(blocks, q) == pytest.approx(energy, rel=1e-12)
        assert np.abs(membrane.force(blocks, q) - force).max() < 1e-12 * np.abs(force).max()
        assert np.abs(membrane.stiffness(blocks, q) - stiffness).max() < 1e-12 * np.abs(stiffness).max()
        # the potential of the system: bending plus both beams' stretching
        assert system.potential(q) == pytest.approx(0.5 * q @ system.inv.K @ q + energy, rel=1e-12)
