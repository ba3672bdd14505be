"""The modal bookkeeping of symmech.trolley.elastic.modal on small inputs written out by hand: the groups of the
components (the roller DOFs together, each beam plane on its own), the start phase (the largest component in the
kinetic norm, not in size, made real and positive) and the curvature shift of a mode without frequency."""
import dataclasses

import numpy as np

from symmech.trolley.elastic import body as el_body, modal, system as el
from test_trolley_elastic import roller_model


def rollers_and_beams(n_beams: int, modes: int = 2) -> el.System:
    """The rollers' trolley of tests/test_trolley_elastic.py carrying ``n_beams`` cantilevers of ``modes`` modes."""
    beams = tuple(el_body.Beam((0.0, 0.1 * b, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), 1.0, 2.0, (0.5, 1.0), modes=modes)
                  for b in range(n_beams))
    return el.System(dataclasses.replace(roller_model(9.81, (1e6,) * 5), beams=beams))


def test_components_group_the_roller_dofs_together_and_each_beam_plane_apart():
    """Two beams of two modes on the rollers (5 + 2 x 2 x 2 = 13 components): group 0 for the five roller DOFs,
    2 b + p for the modes of beam b in plane p, integers; components share a group exactly when they share beam
    and plane (what the scene's group participation sums over); the labels name them in that order."""
    comp = modal.components(rollers_and_beams(2))
    beams = [(b, p, k) for b in range(2) for p in (1, 2) for k in (1, 2)]
    assert comp.labels == ("roller_u2", "roller_u3", "roller_th1", "roller_th2", "roller_th3",
                           *(f"beam{b}_plane{p}_mode{k}" for b, p, k in beams))
    expected = [0] * 5 + [2 * b + p for b, p, _ in beams]
    assert comp.group.dtype.kind == "i"
    np.testing.assert_array_equal(comp.group, expected)
    key = list(zip(comp.beam.tolist(), comp.plane.tolist()))
    same_group = comp.group[:, None] == comp.group[None, :]
    np.testing.assert_array_equal(same_group, [[a == b for b in key] for a in key])


def test_start_phase_turns_the_largest_kinetic_component_real_and_positive():
    """M = diag(1, 100, 4): column 0 = (1, 0.5 e^{0.7i}, 0.1) has kinetic weights |x|² M_ii = (1, 25, 0.04), so its
    second entry (not its first, the largest in size) becomes real positive: the column times e^{-0.7i}. Column 1
    = (2 e^{-i}, 0.1, 0.3i) weighs (4, 1, 0.36): times e^{i}. A column's phase is its own, whatever the other's."""
    M = np.diag([1.0, 100.0, 4.0])
    X = np.array([[1.0, 2 * np.exp(-1j)], [0.5 * np.exp(0.7j), 0.1], [0.1, 0.3j]])
    turned = modal.start_phase(M, X)
    np.testing.assert_allclose(turned[:, 0], X[:, 0] * np.exp(-0.7j), rtol=0, atol=1e-15)
    np.testing.assert_allclose(turned[:, 1], X[:, 1] * np.exp(1j), rtol=0, atol=1e-15)
    np.testing.assert_allclose([turned[1, 0], turned[0, 1]], [0.5, 2.0], rtol=0, atol=1e-15)


def test_curvature_shift_is_rayleighs_quotient_and_zero_without_a_frequency():
    """One beam (no rollers) bent at q: for the unit shapes x = e_j the first-order shift is H_jj / (2 ω² M_jj)
    (the Rayleigh quotient of the docstring, H the curvature Hessian, M the mass at q), in floats; a mode of
    ω = 0 (a rigid motion) has no frequency to shift: 0. Two beams on the rollers: H block-diagonal, a block a
    beam."""
    system = rollers_and_beams(1, modes=3)
    system = el.System(dataclasses.replace(system.mdl, rollers=None, effects=el_body.Effects(rollers=False)))
    q = np.array([0.02, -0.01, 0.005, 0.03, 0.01, -0.02])
    H, M = modal.curvature_hessian(system, q), system.mass(q)
    assert np.abs(np.diag(H)).min() > 0
    columns = [0, 3, 4]
    X = np.eye(system.N)[:, columns]
    omega = np.array([2.0, 3.0, 5.0])
    shift = modal.curvature_shift(system, q, omega, X)
    assert shift.dtype == np.float64
    np.testing.assert_allclose(shift, np.diag(H)[columns] / (2 * omega**2 * np.diag(M)[columns]), rtol=1e-14)
    omega[1] = 0.0
    shift = modal.curvature_shift(system, q, omega, X)
    assert shift[1] == 0.0 and shift.dtype == np.float64
    # two such beams on the rollers (5 + 2 x 6 components): each beam's block is its own at its q, in its own rows
    # and columns, and the rollers' rows and columns are zero (the energy is the beams' bending alone)
    q_rollers = np.array([0.01, -0.02, 0.03, 0.04, -0.05])
    both = modal.curvature_hessian(rollers_and_beams(2, modes=3), np.concatenate([q_rollers, q, q[::-1]]))
    np.testing.assert_array_equal(both[:5], 0.0)
    np.testing.assert_array_equal(both[:, :5], 0.0)
    np.testing.assert_allclose(both[5:11, 5:11], H, rtol=1e-14)
    np.testing.assert_allclose(both[11:, 11:], modal.curvature_hessian(system, q[::-1]), rtol=1e-14)
    np.testing.assert_array_equal(both[5:11, 11:], 0.0)
