"""The Chatterjee-Ruina law computes in double precision whatever the coefficients' dtype: single-precision e_n,
e_t and μ (an input the API accepts) give the float64 answer of the same numbers (numpy keeps float32 when a float32
array meets a Python float). The reference is the float64 call on those numbers and a sphere's closed form,
K = diag(7/2, 7/2, 1)/m and P_n = -(1 + e_n) m u_z."""
import numpy as np

from symmech.grain.coulomb_law import coulomb_impulse


def test_single_precision_coefficients_give_the_double_precision_impulse():
    m = 3e-5
    K = np.broadcast_to(np.diag([3.5, 3.5, 1.0]) / m, (2, 3, 3))
    u = np.array([[0.3, -0.1, -0.7], [0.0, 0.2, -0.4]])
    e_n, e_t, mu = np.float32([0.3, 0.7]), np.float32([0.1, -0.3]), np.float32([np.inf, 0.1])
    P = coulomb_impulse(K, u, e_n, e_t, mu)
    assert P.dtype == np.float64
    np.testing.assert_allclose(P, coulomb_impulse(K, u, e_n.astype(float), e_t.astype(float), mu.astype(float)),
                               rtol=1e-15, atol=0)
    np.testing.assert_allclose(P[:, 2], -(1 + e_n.astype(float)) * m * u[:, 2], rtol=1e-14)
