"""The frequency shift by the deflection under the frame's angular acceleration.

A radial cantilever (the beam of tests/test_trolley_elastic_modal.py: L = 1 m, ρA = 2 kg/m,
EI = 0.5 / 1 N m² flapwise / in plane) rooted on the rotation axis, the frame at rest and
accelerating at α about the vertical (the start of a speed ramp on a level circle). The Euler
force -ρA α × r̃ bends it in the plane of rotation, tip deflection δ ≈ 11 ρA α L⁵/(120 EI)
((δ/L)² = 2.1e-3 at α = 0.25 rad/s²), and the modal analysis linearises about that state.

Consistent second order: the frequency shift is O((δ/L)²), and at that order the bending energy
of an inextensible beam is ½ EI ∫ κ² with κ² = w''²/(1 - w'²) = w''² + w'² w''² + …: the
model keeps the quadratic axial field (the exact shortening to that order) but its bending
energy is ½ EI ∫ w''² only. Reference: the exact planar elastica, the rotation θ(x) of the
section as coordinates (θ = Σ a_k (x/L)^k, exact curvature θ', positions by quadrature of
(cos θ, sin θ)), its static state under the (circulatory) Euler force by Newton and the
frequencies of its tangent M⁻¹ K_t. It confirms the issue's model shift (-0.22 % for the first
in-plane mode) and says the consistent one is +0.03 %: the model's shift is beyond its
consistent order, and the left-out curvature term (:func:`symmech.trolley.elastic.modal.curvature_shift`)
accounts for the difference.
"""
import numpy as np
import pytest
import scipy.integrate

from symmech.core import pipeline
from symmech.core.context import Context
from symmech.trolley.elastic import system as el, body as el_body, frame as el_frame, modal
from test_trolley_elastic_modal import CIRCLE, EI, L, R, RHO_A
from trolley_util import setup

ALPHA = 0.25  # rad/s²


def elastica(alpha, n=12, gauss=40):
    """In-plane natural frequencies [rad/s] (ascending) of the exact inextensible elastica under
    the Euler force of an angular acceleration ``alpha`` [rad/s²] about its root (frame at rest),
    linearised about its static state, and the static tip deflection across the axis [m]."""
    x, w = np.polynomial.legendre.leggauss(gauss)
    t, wt = (x + 1) / 2, w / 2
    X, WX = L * t, L * wt
    S, WS = X[:, None] * t, X[:, None] * wt  # inner quadrature of ∫0^x ds
    legendre = [np.polynomial.Legendre.basis(j, domain=[0, 1]) for j in range(n)]
    P = np.stack([S / L * f(S / L) for f in legendre], -1)  # θ basis ξ P_j(2ξ - 1) at the inner points (g, g, n)
    dphi = np.stack([(f(X / L) + X / L * f.deriv()(X / L)) / L for f in legendre], -1)
    K = EI[1] * np.einsum("p,pk,pl->kl", WX, dphi, dphi)
    J = np.array([[0.0, 1.0], [-1.0, 0.0]])  # -α e_z × (r1, r2) = α (r2, -r1)

    def parts(a):
        th = P @ a
        c, s = np.cos(th), np.sin(th)
        r = np.stack([(WS * c).sum(1), (WS * s).sum(1)], -1)
        dr = np.stack([-np.einsum("pq,pq,pqk->pk", WS, s, P), np.einsum("pq,pq,pqk->pk", WS, c, P)], -1)
        d2r = -np.stack([np.einsum("pq,pq,pqk,pql->pkl", WS, c, P, P), np.einsum("pq,pq,pqk,pql->pkl", WS, s, P, P)],
                        -1)
        force = RHO_A * alpha * r @ J.T
        Q = np.einsum("p,pi,pki->k", WX, force, dr)
        dQ = RHO_A * alpha * np.einsum("p,pli,ji,pkj->kl", WX, dr, J, dr) + np.einsum("p,pi,pkli->kl", WX, force, d2r)
        return Q, dQ, RHO_A * np.einsum("p,pki,pli->kl", WX, dr, dr), r

    a = np.zeros(n)
    for _ in range(30):
        Q, dQ, _, _ = parts(a)
        step = np.linalg.solve(K - dQ, Q - K @ a)
        a += step
        if np.abs(step).max() < 1e-15:
            break
    _, dQ, M, r = parts(a)
    lam = np.linalg.eigvals(np.linalg.solve(M, K - dQ))
    theta = np.stack([X / L * f(X / L) for f in legendre], -1) @ a
    return np.sort(np.sqrt(lam.real))[:3], float(WX @ np.sin(theta))


def cantilever(modes=6, length=L, body=True):
    """The system of the radial cantilever of ``length`` [m] (``body``: the beams' effect on)."""
    beam = el_body.Beam((0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0), length, RHO_A, EI, modes=modes)
    return el.System(el_body.ElasticModel(1.0, (0, 0, 0), (1, 1, 1, 0, 0, 0), 2.0, 1.0, 0.0, None, (beam,),
                                          el_body.Effects(rollers=False, body=body)))


def model(alpha, modes=6, length=L):
    """The model's first three in-plane frequencies [rad/s], linearised about the quasi-static
    state under α, their left-out curvature shifts, and the system (a beam of ``length`` [m])."""
    system = cantilever(modes, length)
    fs = el_frame.FrameState(np.zeros(3), np.zeros(3), np.zeros(3), np.array([0.0, alpha, 0.0]), np.array([0.0, 1, 0]))
    q = system.quasi_static(fs)
    omega, _, X = system.linear_modes(fs, q, shapes=True)
    comp = modal.components(system)
    plane = comp.plane[np.argmax(modal.participation(comp, system.mass(q), X), axis=0)]
    inplane = np.flatnonzero(plane == 2)[:3]
    return omega[inplane], modal.curvature_shift(system, q, omega, X)[inplane], system


def test_the_elastica_reference_is_the_cantilever_at_rest_and_linear_beam_theory_under_a_small_load():
    """α = 0: β²√(EI/ρAL⁴) with βL = 1.87510407, 4.69409113, 7.85475744 (1e-7); α = 0.01 rad/s²:
    tip deflection 11 ρA α L⁵ / (120 EI) of the triangular load (1e-5: the nonlinear part is
    O((δ/L)²) = 3e-6)."""
    beta = np.array([1.87510407, 4.69409113, 7.85475744])
    np.testing.assert_allclose(elastica(0.0)[0], beta**2 * np.sqrt(EI[1] / (RHO_A * L**4)), rtol=1e-7)
    alpha = 0.01
    assert abs(elastica(alpha)[1]) == pytest.approx(11 * RHO_A * alpha * L**5 / (120 * EI[1]), rel=1e-5)


def test_the_model_shift_is_beyond_its_order_and_the_left_out_curvature_accounts_for_it():
    """At α = 0.25 rad/s² ((δ/L)² = 2.1e-3): the model's first three in-plane frequencies move by
    -0.220, -0.171, -0.184 % (the issue's -0.1 to -0.2 %), the consistent (exact elastica) ones by
    +0.034, -0.038, -0.059 %; the model's shift plus the left-out curvature term's first-order
    shift is the consistent one to 2e-5 (measured 1.2e-5, 3.9e-6, 1.7e-6: O((δ/L)⁴), 16 times less
    at α/2), and both shifts scale as α² (ratio 4 between α and α/2 to 1 %)."""
    exact0, model0 = elastica(0.0)[0], model(0.0)[0]
    shifts = {}
    for alpha in (ALPHA, ALPHA / 2):
        exact = elastica(alpha)[0]
        omega, correction, _ = model(alpha)
        shifts[alpha] = (exact / exact0 - 1, omega / model0 - 1, correction)
    exact, mine, correction = shifts[ALPHA]
    assert (abs(elastica(ALPHA)[1]) / L) ** 2 == pytest.approx(2.1e-3, rel=0.02)
    np.testing.assert_allclose(mine, [-2.20e-3, -1.71e-3, -1.84e-3], atol=1e-5)
    np.testing.assert_allclose(exact, [3.4e-4, -3.8e-4, -5.9e-4], atol=1e-5)
    np.testing.assert_allclose(mine + correction, exact, atol=2e-5)
    half = shifts[ALPHA / 2]
    np.testing.assert_allclose(mine / half[1], 4.0, rtol=0.01)
    np.testing.assert_allclose(exact / half[0], 4.0, rtol=0.01)
    assert np.abs(half[1] + half[2] - half[0]).max() < np.abs(mine + correction - exact).max() / 8


@pytest.mark.parametrize("length", [L, 1.7])
def test_curvature_hessian_is_that_of_its_energy(length):
    """Both planes bent (seeded q): the Hessian equals central differences of
    Π_c = ½ ∫ (Σ_p √EI_p w_p' w_p'')² dx evaluated on 4001 points (Simpson), to 1e-5, on the beam of
    1 m and on one of 1.7 m (d/dx = d/dξ / L, d²/dx² = d²/dξ² / L², dx = L dξ: at 1 m they cannot be told apart)."""
    system = cantilever(length=length)
    beam = system.mdl.beams[0]
    xi = np.linspace(0.0, 1.0, 4001)
    basis = el_body.beam_basis(beam.support, xi)[0][:, :, :beam.modes]
    d1, d2 = basis[:, 1] / length, basis[:, 2] / length**2

    def energy(q):
        w = q.reshape(2, -1)
        g = sum(np.sqrt(ei) * (d1 @ wp) * (d2 @ wp) for ei, wp in zip(beam.ei, w))
        return 0.5 * length * scipy.integrate.simpson(g**2, x=xi)

    q = np.random.default_rng(22).normal(scale=0.05, size=system.N)
    h = 1e-4
    fd = np.array([[(energy(q + h * (ea + eb)) - energy(q + h * (ea - eb)) - energy(q - h * (ea - eb))
                     + energy(q - h * (ea + eb))) / (4 * h * h) for eb in np.eye(system.N)] for ea in np.eye(system.N)])
    H = modal.curvature_hessian(system, q)
    np.testing.assert_allclose(H, fd, rtol=1e-5, atol=1e-6 * np.abs(fd).max())


def test_beam_slope_is_the_largest_slope_of_both_planes_and_zero_without_beams():
    """Seeded q on a 1.7 m beam: max over x of |(w_1', w_2')|, w_p' = Σ_k q_pk φ_k'(x/L) / L on 4001 points (the
    module samples 2001: the same maximum to 1e-6); with the body effect off the model has no beams' slope, 0."""
    system = cantilever(length=1.7)
    beam = system.mdl.beams[0]
    q = np.random.default_rng(7).normal(scale=0.05, size=system.N)
    d1 = el_body.beam_basis(beam.support, np.linspace(0.0, 1.0, 4001))[0][:, 1, :beam.modes] / 1.7
    w = q.reshape(2, -1)
    assert modal.beam_slope(system, q) == pytest.approx(np.hypot(d1 @ w[0], d1 @ w[1]).max(), rel=1e-6)
    assert modal.beam_slope(cantilever(length=1.7, body=False), q) == 0.0


def _ramp(alpha):
    """A level circle R = 2 m from rest at V̇0 = α R (frame angular acceleration α), no gravity,
    rigid rollers, the beam rooted at the centre of the circle along x1."""
    data = setup(track=CIRCLE, trolley={"mass": 100.0, "com": [0.0, 0.0, 0.0], "inertia": [10.0, 20.0, 15.0, 0, 0, 0]},
                 motion={"speed": f"{alpha * R!r}*t"}, time={"t_end": 0.2, "steps": 4}, effects={"gravity": False})
    data["elastic"] = {"effects": {"rollers": False},
                       "beams": [{"root": [0.0, 0.0, R], "axis": [1.0, 0.0, 0.0], "plane": [0.0, 1.0, 0.0],
                                  "length": L, "mass_per_length": RHO_A, "ei": list(EI), "modes": 6}],
                       "numerics": {"modal_samples": 2}}
    return data


@pytest.mark.parametrize("alpha, warned", [(ALPHA, True), (0.1, False)])
def test_the_shift_beyond_the_consistent_order_is_flagged(tmp_path, alpha, warned):
    """The modes table carries the left-out curvature shift of every mode; above 0.1 % a warning
    names the mode, the model's shift (against the linearisation about the undeformed state)
    and the left-out term, at α = 0.25 rad/s² (+0.256 % on the first in-plane mode, the model's
    shift -0.220 %); at α = 0.1 rad/s² (+0.041 %) none."""
    _, res = pipeline.run_to(_ramp(alpha), tmp_path / "out", Context(quiet=True), plots=False)
    modes = res.tables["modes"]
    at_rest = modes.column("t") == 0.0
    flagged = [w for w in res.warnings if "consistent order" in w]
    assert bool(flagged) == warned
    top = np.abs(modes.column("curvature_shift")[at_rest]).max()
    assert top == pytest.approx(2.556e-3 * (alpha / ALPHA) ** 2, rel=0.01)
    if warned:
        assert "beam0_plane2_mode1" in flagged[0] and "+0.256 %" in flagged[0] and "by -0.22 %" in flagged[0]
