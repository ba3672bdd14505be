"""The residual R(q, q̇, q̈) of the elastic trolley and its Jacobians, by independent routes.

R against the virtual work of the d'Alembert forces of an explicit point cloud (tests/test_elastic_energies.py):
R_a = Σ m ∂r̃/∂q_a · (a - g) + ∂Π/∂q_a + damping, with Π the bending and spring energy written out; the
accelerations make that virtual work vanish; M, ∂R/∂q, ∂R/∂q̇ against differences of R (R is affine in q̈, so M
is exact), on a body with every term: stiffening, a held beam, beam and roller damping."""
import sys
from pathlib import Path

import numpy as np
import pytest

from symmech.core.scene import SymmechError
from symmech.generated import trolley_elastic as gen
from symmech.trolley.elastic import system as el, body as el_body, frame as el_frame

sys.path.insert(0, str(Path(__file__).parent))
from test_elastic_energies import (BEAM, G0, HALF_GAUGE, K_ROLL, L_AXLE, bending_energy, cloud,  # noqa: E402
                                   kinematics, model, random_state)

pytestmark = pytest.mark.xdist_group("test_elastic_residual")

C_ROLL = (300.0, 500.0, 200.0, 400.0, 600.0)
C = gen.roller_matrix(L_AXLE, HALF_GAUGE)


def virtual_work(body, fs, q, qd, qdd):
    """Σ m ∂r̃/∂q_a · (a - g) (N,) of the cloud."""
    pts, w, phi, H = body
    r, ud, udd = kinematics(body, q, qd, qdd)
    a = fs.a0 + np.cross(fs.dw, r) + np.cross(fs.w, np.cross(fs.w, r)) + 2 * np.cross(fs.w, ud) + udd
    tangent = phi + np.einsum("pabi,b->pai", H, q)
    return np.einsum("p,pai,pi->a", w, tangent, a + G0 * fs.nu)


def elastic_forces(q, qd):
    """∂Π/∂q + the dampers' force (N,): bending (central differences of the quadratic energy, exact but for
    rounding) and the rollers' springs and dampers -Cᵀ (-k d - c ḋ)."""
    h = 1e-3
    grad = np.array([(bending_energy(q + h * e) - bending_energy(q - h * e)) / (2 * h) for e in np.eye(len(q))])
    grad[:5] += C.T @ (K_ROLL * (C @ q[:5]) + np.asarray(C_ROLL) * (C @ qd[:5]))
    return grad


@pytest.fixture(scope="module")
def system():
    return el.System(model(damping=C_ROLL))


def test_residual_is_the_virtual_work_of_the_point_cloud(system):
    body = cloud(system.mdl)
    for _ in range(3):
        fs, q, qd, qdd = random_state(system.N)
        expected = virtual_work(body, fs, q, qd, qdd) + elastic_forces(q, qd)
        got = system.evaluate(fs, q, qd, qdd)
        assert np.abs(got - expected).max() < 1e-11 * np.abs(expected).max()
        # the accelerations are where the virtual work of the d'Alembert forces balances the elastic forces
        acc = system.accelerations(fs, q, qd)
        balance = virtual_work(body, fs, q, qd, acc) + elastic_forces(q, qd)
        assert np.abs(balance).max() < 1e-10 * np.abs(expected).max()


HELD = el_body.Beam((0.0, 0.1, 0.5), (1.0, 1.0, 0.0), (0.0, 0.0, 1.0), 2.0, 1.5, (4e3, 3e3), "pinned", 2,
               damping_ratio=0.03, axial="held", ea=1e6)


def test_jacobians_are_the_derivatives_of_the_residual():
    damped = el_body.Beam(*[getattr(BEAM, f) for f in ("root", "axis", "plane", "length", "rho_a", "ei", "support",
                                                   "modes", "tip_mass")], damping_ratio=0.02)
    system = el.System(model(damping=C_ROLL, beams=(damped, HELD)))
    assert np.abs(system.inv.D).max() > 0 and system.inv.membrane
    fs, q, qd, qdd = random_state(system.N)
    R, M, Rq, Rqd = system.evaluate(fs, q, qd, qdd, jacobian=True)
    assert np.array_equal(R, system.evaluate(fs, q, qd, qdd))
    assert np.abs(system.mass(q) - M).max() == 0.0
    eye = np.eye(system.N)
    # R is affine in q̈: unit differences are exact but for rounding
    fd_M = np.array([system.evaluate(fs, q, qd, qdd + e) - R for e in eye]).T
    assert np.abs(fd_M - M).max() < 1e-9 * np.abs(M).max()
    h = 1e-6
    for arg, J in ((0, Rq), (1, Rqd)):
        def at(x):
            state = [q, qd]
            state[arg] = x
            return system.evaluate(fs, *state, qdd)
        base = (q, qd)[arg]
        fd = np.array([(at(base + h * e) - at(base - h * e)) / (2 * h) for e in eye]).T
        assert np.abs(fd - J).max() < 1e-6 * np.abs(J).max()


def test_a_body_without_rotary_inertia_is_refused_in_one_sentence():
    mdl = el_body.ElasticModel(50.0, (0, 0, 0), (0, 0, 0, 0, 0, 0), 2.0, 1.0, G0, el_body.Rollers((1e6,) * 5, (0.0,) * 5))
    system = el.System(mdl)
    fs = el_frame.FrameState(np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3), np.array([0, 1.0, 0]))
    with pytest.raises(SymmechError, match=r"^the mass matrix of the elastic model is singular: give the trolley a "
                                           r"positive inertia about every axis \(trolley.inertia\)$"):
        system.accelerations(fs, np.zeros(5), np.zeros(5))
