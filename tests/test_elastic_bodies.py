"""The elastic trolley's bodies against closed forms: the rigid model's body (mass, centre and central inertia
of trolley, beams and tip masses: thin rods and point masses, Steiner's theorem) and a beam's own mode
(Euler-Bernoulli: the cantilever's, with and without a tip mass, and the pinned beam's sin(jπξ)).

No integration: both are the pieces `simulate` reaches through `outputs` and a scene's initial mode."""
import numpy as np
import pytest
from scipy.optimize import brentq

from symmech.core import kinematics as kin
from symmech.trolley.elastic import system as el, body as el_body

pytestmark = pytest.mark.xdist_group("test_elastic_bodies")

TROLLEY = dict(mass=120.0, com=(0.9, 0.4, -0.1), inertia=(12.0, 25.0, 18.0, 1.5, -0.8, 0.6))
# root [m], axis, plane, length [m], ρA [kg/m], tip mass [kg]: skew axes, so every inertia entry is reached
RODS = (((0.2, 0.3, 0.1), (0.0, 1.0, 0.2), (1.0, 0.0, 0.0), 1.4, 3.0, 2.5),
        ((1.5, -0.2, 0.4), (0.3, -0.2, 1.0), (0.0, 1.0, 0.0), 0.8, 5.0, 0.0))


def rod_model(rods=RODS, body=True):
    beams = tuple(el_body.Beam(root, axis, plane, length, rho_a, (4e3, 6e3), "cantilever", 3, tip)
                  for root, axis, plane, length, rho_a, tip in rods)
    return el_body.ElasticModel(TROLLEY["mass"], TROLLEY["com"], TROLLEY["inertia"], 2.1, 0.7, 9.81, None, beams,
                           el_body.Effects(rollers=False, body=body))


def point_inertia(m, r):
    """Inertia tensor [kg m²] of a point mass m at r about the origin."""
    r = np.asarray(r, float)
    return m * (r @ r * np.eye(3) - np.outer(r, r))


def closed_form_body(rods=RODS):
    """Mass [kg], centre [m] and central inertia tensor [kg m²] of the trolley, thin uniform rods and tip masses."""
    mass, moment, inertia = TROLLEY["mass"], TROLLEY["mass"] * np.array(TROLLEY["com"]), np.zeros((3, 3))
    inertia += kin.inertia_matrix(TROLLEY["inertia"]) + point_inertia(TROLLEY["mass"], TROLLEY["com"])
    for root, axis, _, length, rho_a, tip in rods:
        e = np.asarray(axis, float) / np.linalg.norm(axis)
        centre, m = np.asarray(root) + 0.5 * length * e, rho_a * length
        # a thin rod about its centre: m L²/12 about every axis ⟂ e, nothing about e
        inertia += m * length ** 2 / 12 * (np.eye(3) - np.outer(e, e)) + point_inertia(m, centre)
        end = np.asarray(root) + length * e
        inertia += point_inertia(tip, end)
        mass += m + tip
        moment += m * centre + tip * end
    com = moment / mass
    return mass, com, inertia - point_inertia(mass, com)


@pytest.mark.parametrize("body", [True, False])
def test_rigid_body_is_the_trolley_with_its_rods_and_tip_masses(body):
    """Mass, centre and all six central inertia entries (in Body's order I11, I22, I33, I12, I23, I13) to 1e-12,
    and the track data l, a, g0 passed on; the beams count as mass whether elastic or rigid."""
    got = el_body.rigid_body(rod_model(body=body))
    mass, com, inertia = closed_form_body()
    assert got.m == pytest.approx(mass, rel=1e-13)
    np.testing.assert_allclose(got.r, com, rtol=0, atol=1e-13)
    expected = [inertia[0, 0], inertia[1, 1], inertia[2, 2], inertia[0, 1], inertia[1, 2], inertia[0, 2]]
    np.testing.assert_allclose(got.inertia, expected, rtol=0, atol=1e-11 * np.abs(inertia).max())
    assert (got.l, got.ah, got.g0) == (2.1, 0.7, 9.81)


def test_rigid_body_of_a_bare_trolley_is_the_trolley():
    got = el_body.rigid_body(rod_model(rods=()))
    assert got.m == TROLLEY["mass"]
    np.testing.assert_allclose(got.r, TROLLEY["com"], rtol=0, atol=1e-15)
    np.testing.assert_allclose(got.inertia, TROLLEY["inertia"], rtol=0, atol=1e-13)


# ---------------------------------------------------------------- a beam's own modes

def cantilever_shape(lam, xi):
    """Euler-Bernoulli cantilever mode of eigenvalue λ = βL at ξ, moment-free tip (with or without a point mass)."""
    sigma = (np.cosh(lam) + np.cos(lam)) / (np.sinh(lam) + np.sin(lam))
    return np.cosh(lam * xi) - np.cos(lam * xi) - sigma * (np.sinh(lam * xi) - np.sin(lam * xi))


def tip_mass_roots(ratio, count):
    """The first ``count`` λ = βL of a cantilever carrying a tip mass ``ratio`` ρA L."""
    f = lambda b: 1 + np.cos(b) * np.cosh(b) + ratio * b * (np.cos(b) * np.sinh(b) - np.sin(b) * np.cosh(b))  # noqa
    grid = np.linspace(0.1, 12.0, 2000)
    signs = np.sign(f(grid))
    starts = np.nonzero(signs[:-1] != signs[1:])[0][:count]
    return [brentq(f, grid[k], grid[k + 1], xtol=1e-15) for k in starts]


XI = np.linspace(0.0, 1.0, 401)
# (support, length [m], ρA [kg/m], (EI1, EI2) [N m²], tip mass [kg])
MODE_BEAMS = (("cantilever", 1.3, 2.0, (300.0, 1200.0), 0.0),
              ("cantilever", 0.9, 3.0, (500.0, 200.0), 1.8),
              ("pinned", 1.6, 4.0, (800.0, 2000.0), 0.0))


def mode_system():
    """The three beams of MODE_BEAMS, 8 Ritz functions per plane, on a trolley on rigid rollers (no rollers)."""
    beams = tuple(el_body.Beam((0.4 * i, 0.1, 0.0), (0, 1, 0), (1, 0, 0), length, rho_a, ei, support, 8, tip)
                  for i, (support, length, rho_a, ei, tip) in enumerate(MODE_BEAMS))
    return el.System(el_body.ElasticModel(90.0, (0.5, 0.2, 0.0), (10.0, 20.0, 15.0, 0, 0, 0), 2.0, 1.0, 9.81, None,
                                      beams, el_body.Effects(rollers=False)))


def exact_mode(beam, mode):
    """The closed form's shape at XI scaled to a largest deflection of +1 and its λ = βL (ω² = λ⁴ EI/(ρA L⁴))."""
    support, _, rho_a, _, tip = MODE_BEAMS[beam]
    if support == "pinned":
        lam = mode * np.pi
        shape = np.sin(lam * XI)
    else:
        lam = tip_mass_roots(tip / (rho_a * MODE_BEAMS[beam][1]), mode)[mode - 1]
        shape = cantilever_shape(lam, XI)
    return shape / shape[np.argmax(np.abs(shape))], lam


@pytest.fixture(scope="module")
def system():
    return mode_system()


@pytest.mark.parametrize("beam, plane, mode, tol", [(0, 1, 1, 1e-7), (0, 2, 1, 1e-7), (0, 1, 2, 1e-5),
                                                    (1, 2, 1, 1e-7), (1, 1, 2, 1e-5), (2, 1, 1, 1e-6),
                                                    (2, 2, 2, 5e-5)])
def test_beam_mode_is_the_euler_bernoulli_mode_of_that_beam_and_plane(system, beam, plane, mode, tol):
    """Only the coordinates of that beam's plane are set; their deflection along the beam is the closed-form
    mode with its largest deflection +1 m (a pinned beam's higher modes up to their sign; to ``tol``, the Ritz
    error of 8 polynomials), and its Rayleigh quotient on the Ritz K, M is the closed-form ω² = λ⁴ EI/(ρA L⁴)
    (to 10 tol: the mode's, not another's)."""
    support, length, rho_a, ei, _ = MODE_BEAMS[beam]
    q = el.beam_mode(system, beam, plane, mode)
    names = system.inv.names
    idx = [names.index(f"beam{beam}_p{plane}_m{k}") for k in range(1, 9)]
    others = np.setdiff1d(np.arange(system.N), idx)
    assert np.all(q[others] == 0.0)
    shape, lam = exact_mode(beam, mode)
    deflection = el_body.beam_basis(support, XI)[0][:, 0, :] @ q[idx]
    assert deflection.max() == pytest.approx(1.0, abs=tol)
    if support == "pinned" and mode > 1:  # sin(jπξ): peaks of both signs, as large (round-off picks one)
        shape *= np.sign(deflection @ shape)
    np.testing.assert_allclose(deflection, shape, rtol=0, atol=tol)
    block = np.ix_(idx, idx)
    rayleigh = (q[idx] @ system.inv.K[block] @ q[idx]) / (q[idx] @ system.mass(np.zeros(system.N))[block] @ q[idx])
    assert rayleigh == pytest.approx(lam ** 4 * ei[plane - 1] / (rho_a * length ** 4), rel=10 * tol)

