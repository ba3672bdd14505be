"""The membrane energy's force and stiffness sum over held beams whatever coordinates they share: two blocks on
the same coordinates (an input `membrane.force` and `stiffness` accept) against Π_m = Σ c (xᵀHx)², its gradient
Σ 4 c (xᵀHx) H x and Hessian Σ 4 c [(xᵀHx) H + 2 (Hx)(Hx)ᵀ], written here with H from the generated slope Gram."""
import numpy as np

from symmech.generated import trolley_elastic as gen
from symmech.trolley.elastic import membrane


def test_blocks_on_shared_coordinates_add_their_forces_and_stiffnesses():
    modes = 2
    h = gen.pinned_slope_gram()[:modes, :modes]
    H = np.zeros((4, 4))
    H[:2, :2] = H[2:, 2:] = h
    blocks = [membrane.block(1, modes, 2e6, 1.5), membrane.block(1, modes, 5e5, 0.8)]  # both on q[1:5]
    c = [2e6 / (8 * 1.5**3), 5e5 / (8 * 0.8**3)]
    q = np.array([0.3, 0.02, -0.01, 0.015, 0.03, -0.2])
    x = q[1:5]
    s, hx = x @ H @ x, H @ x
    force = np.zeros(6)
    force[1:5] = sum(4 * ci * s * hx for ci in c)
    stiffness = np.zeros((6, 6))
    stiffness[1:5, 1:5] = sum(4 * ci * (s * H + 2 * np.outer(hx, hx)) for ci in c)
    np.testing.assert_allclose(membrane.energy(blocks, q), sum(ci * s**2 for ci in c), rtol=1e-14)
    np.testing.assert_allclose(membrane.force(blocks, q), force, rtol=1e-13, atol=0)
    np.testing.assert_allclose(membrane.stiffness(blocks, q), stiffness, rtol=1e-13, atol=0)
