"""The derived sliding regime (``generated/grain_sliding``, layer 1 ``symmech.grain.derive_sliding``) against the
Python sliding model (``symmech.grain.sliding``, written by hand in KXYZ with the spin in the surface frame) at
random states of an ellipsoid (turning about the normal) and a sphere (rolling): normal force, slip, stick force,
slip direction, the slip's and the stick's rates, the event indicators, the friction impulse and the landing (its
last step ``rest_on_plane``), each to 1e-12 of its magnitude."""
from __future__ import annotations

import math

import numpy as np
import pytest

from symmech.generated import grain_motion as gm, grain_sliding as gs
from symmech.grain import contact, flight, sliding
from symmech.grain.coulomb_law import inverse_effective_mass, principal_inertia

TOLERANCE = 1e-12
ELLIPSOID = (3.5e-3, 1.6e-3, 1.4e-3)  # m, the default scene's grain
SPHERE = (1e-3,) * 3


def _case(rng, axes):
    """A random sliding problem: the Python model, its body and contact, the generated functions' leading
    arguments (t, the 13 flight states, gravity, vibration, inertia, semi-axes, mass, roll) and the native state
    y (r (2), v (2), w_K (3), q (4), W, D)."""
    mass = 1300.0 * 4 / 3 * math.pi * math.prod(axes)
    inertia = tuple(principal_inertia(axes, mass))
    d = rng.normal(size=3)
    vib = flight.Vibration(rng.uniform(1e-4, 2e-3), rng.uniform(50.0, 300.0), rng.uniform(0, 6.3),
                           tuple(d / np.linalg.norm(d)))
    g_k = (rng.uniform(-1, 1), rng.uniform(-1, 1), -9.81)
    model = sliding.Sliding(g_k, vib, rng.uniform(0.1, 0.8))
    body = sliding.Body(axes, mass, inertia, True)
    q = rng.normal(size=4)
    q /= np.linalg.norm(q)
    Q = flight.rotation_matrix(q)
    w_body, v = rng.normal(0.0, 30.0, 3), rng.normal(0.0, 0.05, 2)
    t = rng.uniform(0.0, 1.0)
    args = (t, 0.1, -0.2, 2e-3, *v, 0.0, *q, *w_body, *g_k, vib.amplitude, vib.omega, vib.phase, *vib.direction,
            *inertia, *axes, mass, float(body.sphere))
    y = np.concatenate([[0.1, -0.2], v, Q @ w_body, q, [0.0, 0.0]])
    return model, sliding._Contact(model, body, q), args, y, Q


def _close(derived, python):
    derived, python = np.asarray(derived, float).ravel(), np.asarray(python, float).ravel()
    assert np.abs(derived - python).max() <= TOLERANCE * max(np.abs(python).max(), 1e-300), (derived, python)


@pytest.mark.parametrize("axes", [ELLIPSOID, SPHERE], ids=["ellipsoid", "sphere"])
def test_derived_sliding_is_the_python_sliding_model(axes):
    rng = np.random.default_rng(32)
    for _ in range(20):
        model, ode, args, y, Q = _case(rng, axes)
        t, mu = args[0], model.mu
        _close(gs.normal_force(t, *args[14:23]), model.normal(t))
        _close(gs.slip(*args), ode.geometry(y)[1])
        _close(gs.stick_force(*args), ode.stick_force(t, y)[0])
        _close(gs.slip_direction(*args), ode.slip_direction(t, y))
        for derived, stick in ((gs.slip_rate(*args, mu), False), (gs.stick_rate(*args), True)):
            rate = ode.rhs(t, y, stick)
            # flight states: r' (3), v' (3), q' (4), body rates' (3); z and v_z hold still on the plane
            _close(derived[[0, 1, 3, 4]], rate[:4])
            assert derived[2] == derived[5] == 0.0
            _close(derived[6:10], rate[7:11])
            _close(derived[10:], Q.T @ rate[4:7])
        ref = rng.normal(size=2)
        ref /= np.linalg.norm(ref)
        ref_state = y.copy()
        ref_state[2:4] = ref - (ode.geometry(y)[1] - y[2:4])  # a slip along ref at the phase start
        v_stop = 1e-9
        _close(gs.slip_events(*args, v_stop, *ref)[0], sliding._slip_stops(ode, ref_state, v_stop)(t, y))
        _close(gs.stick_events(*args, mu)[0], sliding._stick_ends(ode, mu)(t, y))
        _close(gs.slip_events(*args, v_stop, *ref)[1], model.normal(t))


def _landed(args, Q):
    """The Python loop's landing (``motion._land``) written out from the Python contact and impact modules: the
    plastic normal impulse -u_z / K_zz at the lowest point, the tilting spin of a non-sphere dropped, v_z = 0, the
    centre at the support height; the 13 flight states."""
    axes, mass, inertia = np.array(args[26:29]), args[29], np.array(args[23:26])
    R = contact.contact_offset(axes, Q)
    v, w = np.array(args[4:7]), Q @ np.array(args[11:14])
    K = inverse_effective_mass(mass, inertia, Q, R)
    P = np.array([0.0, 0.0, -(v + np.cross(w, R))[2] / K[2, 2]])
    v, w = v + P / mass, w + Q @ ((Q.T @ np.cross(R, P)) / inertia)
    if max(axes) != min(axes):
        w[:2] = 0.0
    v[2] = 0.0
    return np.concatenate([args[1:3], [contact.support_distance(axes, Q)], v, args[7:11], Q.T @ w])


@pytest.mark.parametrize("axes", [ELLIPSOID, SPHERE], ids=["ellipsoid", "sphere"])
def test_friction_impulse_is_the_settling_of_the_python_model(axes):
    """Near v_stop the Python model removes the slip by an impulse and sticks, or restarts it at 2 v_stop along
    the slip direction: the derived impulse to the same target gives the same velocity and spin. The landing
    before a sliding phase (the exported grain's: impact_contact, plastic_impulse, impact_state at the plastic
    normal impulse, rest_on_plane) is the Python loop's."""
    rng = np.random.default_rng(33)
    outcomes = set()
    for _ in range(20):
        model, ode, args, y, Q = _case(rng, axes)
        state, inertia, mass = args[1:14], args[23:26], args[29]
        contact_k_u = gm.impact_contact(*state, *inertia, *args[26:29], mass)
        pushed = gm.impact_state(*state, *inertia, *args[26:29], mass, 0.0, 0.0, gm.plastic_impulse(*contact_k_u)[0])
        _close(gs.rest_on_plane(*pushed, *args[26:29], args[30]), _landed(args, Q))
        t, v_stop = args[0], 1e-6
        y[2:4] -= ode.geometry(y)[1] - rng.normal(0.0, 0.3 * v_stop, 2)  # a slip within v_stop
        args = (*args[:4], *y[2:4], *args[6:])
        stick, settled = sliding._settle(ode, t, y, v_stop)
        outcomes.add(stick)
        target = (0.0, 0.0) if stick else 2.0 * v_stop * ode.slip_direction(t, y)
        after = gs.friction_impulse(*args, *target)
        _close(after[3:5], settled[2:4])
        _close(after[10:], Q.T @ settled[4:7])
        np.testing.assert_array_equal(after[[0, 1, 2, 5, 6, 7, 8, 9]], np.asarray(args[1:14])[[0, 1, 2, 5, 6, 7, 8, 9]])
    assert outcomes == {True, False}  # both transitions met
