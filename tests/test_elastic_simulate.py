"""`elastic.simulate` against closed forms: a beam of one Ritz function per plane on a trolley at rest is a
damped oscillator of its own, so its coordinates, rates, energy, dissipated energy and the (zero) work of the
track follow from the start offsets alone; on a trolley at a prescribed ramp of acceleration, or pulled by a
ramp of traction, it starts quasi-static and swings about the ramp in closed form. Also the Jacobian simulate
hands implicit solvers (the derivative of its rates), its evaluation counts and its failure message.

The cantilever's one Ritz function is N1 = ξ² (derive_elastic.beam_functions): modal mass m = ρA L/5 + M_tip
(N1(1) = 1), stiffness k = EI ∫ N1''² dξ / L³ = 4 EI/L³; the stiffness-proportional damping of the plane
(2ζ/ω1) K gives that one mode the ratio ζ."""
import dataclasses
import sys
from pathlib import Path

import numpy as np
import pytest

from symmech.core.scene import SymmechError
from symmech.trolley.elastic import system as el, body as el_body, simulate as el_sim

sys.path.insert(0, str(Path(__file__).parent))
from test_trolley_elastic import circle, straight  # noqa: E402
from trolley_util import prepared, setup as scene_dict  # noqa: E402
from symmech.trolley.elastic import scene as elastic_scene  # noqa: E402

pytestmark = pytest.mark.xdist_group("test_elastic_simulate")

L, RHO_A, EI, TIP = 1.2, 4.0, (3e3, 5e3), 1.0
MASS = RHO_A * L / 5 + TIP  # kg, the one mode's
OMEGA = np.sqrt(4 * np.array(EI) / L ** 3 / MASS)  # rad/s, per plane
K1, ELL = 4 * EI[0] / L ** 3, RHO_A * L / 3 + TIP  # N/m of plane 1; ℓ = ∫ N1 dm [kg], its load per x1 acceleration


TROLLEY_MASS = 80.0


def mast(zeta):
    """A cantilever along x2 (plane 1 along x1) on a trolley on rigid rollers, no gravity: N = 2."""
    beam = el_body.Beam((0.5, 0.3, 0.0), (0, 1, 0), (1, 0, 0), L, RHO_A, EI, "cantilever", 1, TIP, zeta)
    return el.System(el_body.ElasticModel(TROLLEY_MASS, (0.8, 0.4, 0.1), (10.0, 20.0, 15.0, 0, 0, 0), 2.0, 1.0, 0.0,
                                     None, (beam,), el_body.Effects(rollers=False)))


def ramp_response(a, b, omega, t):
    """(q, q̇, q̈) of q̈ + ω² q = -ω² (a + b t) from the quasi-static q = -a, q̇ = 0 at t = 0."""
    return (-(a + b * t) + b * np.sin(omega * t) / omega, -b + b * np.cos(omega * t),
            -b * omega * np.sin(omega * t))


def oscillator(q0, v0, omega, zeta, t):
    """Free damped oscillator from q0 [m], v0 [m/s]: (q, q̇) at t."""
    wd = omega * np.sqrt(1 - zeta ** 2)
    decay = np.exp(-zeta * omega * t)
    c, s = np.cos(wd * t), np.sin(wd * t)
    b = (v0 + zeta * omega * q0) / wd
    q = decay * (q0 * c + b * s)
    qd = decay * ((b * wd - zeta * omega * q0) * c - (q0 * wd + zeta * omega * b) * s)
    return q, qd


@pytest.mark.parametrize("method, zeta", [("DOP853", 0.0), ("Radau", 0.03)])
def test_a_kicked_mast_on_a_trolley_at_rest_is_two_free_oscillators(method, zeta):
    """Plane 1 offset by 0.1 mm (dq0), plane 2 started at 5 mm/s (dqd0), both at once in plane 2 as a check that
    the offsets add: q, q̇ of each plane to 2e-7 of the amplitude (measured 2e-8: the shortening's
    (a/L)²); E(t) = ½ m (q̇² + ω² q²) summed (the trolley at rest, no gravity) to 2e-7 of E(0), the dissipated
    energy E(0) - E(t) (1e-7), the work of the track 0."""
    system = mast(zeta)
    t = np.linspace(0.0, 0.12, 25)  # a period of plane 1 (0.106 s), 0.8 of plane 2
    dq0, dqd0 = np.array([1e-4, -2e-5]), np.array([0.0, 5e-3])
    r = el_sim.simulate(system, straight(), t, method, rtol=1e-10, dq0=dq0, dqd0=dqd0)
    assert r["names"] == ["beam0_p1_m1", "beam0_p2_m1"] and r["engine"] == "python"  # the run names its engine
    energy = 0.0
    for plane in range(2):
        q, qd = oscillator(dq0[plane], dqd0[plane], OMEGA[plane], zeta, t)
        scale = max(abs(dq0[plane]), abs(dqd0[plane]) / OMEGA[plane])
        np.testing.assert_allclose(r["q"][:, plane], q, rtol=0, atol=2e-7 * scale)
        np.testing.assert_allclose(r["qd"][:, plane], qd, rtol=0, atol=2e-7 * scale * OMEGA[plane])
        energy = energy + 0.5 * MASS * (qd ** 2 + OMEGA[plane] ** 2 * q ** 2)
    np.testing.assert_allclose(r["E"], energy, rtol=0, atol=2e-7 * energy[0])
    np.testing.assert_allclose(r["dissipated"], energy[0] - energy, rtol=0, atol=1e-7 * energy[0])
    if zeta > 0:
        assert r["dissipated"][-1] > 0.1 * energy[0]
    np.testing.assert_allclose(r["work"], 0.0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(r["t"], t, rtol=0, atol=0)


def test_a_mast_on_a_trolley_at_a_prescribed_growing_acceleration_follows_the_closed_form():
    """V0 = 2 + 0.1 t + 5 t² on a straight level track, no gravity: m q̈ + k q = -ℓ (0.1 + 10 t) from the
    quasi-static state at t = 0 (q = -0.1 ℓ/k, q̇ = 0): q = -(ℓ/k)(0.1 + 10 t) + (10 ℓ/(k ω)) sin ωt; V0, V̇0
    and s = 2 t + 0.05 t² + 5 t³/3 as prescribed."""
    data = scene_dict(effects={"gravity": False, "local_curvature": False},
                      motion={"speed": "2 + 0.1*t + 5*t**2"}, time={"t_end": 0.1, "steps": 4})
    t = np.linspace(0.0, 0.1, 21)
    r = el_sim.simulate(mast(0.0), elastic_scene.drive_of(prepared(data), 1), t, reason="asked")  # default tolerances
    assert (r["engine"], r["engine_reason"]) == ("python", "asked")
    q, qd, _ = ramp_response(0.1 * ELL / K1, 10 * ELL / K1, OMEGA[0], t)
    np.testing.assert_allclose(r["q"][:, 0], q, rtol=0, atol=1e-7 * np.abs(q).max())
    np.testing.assert_allclose(r["qd"][:, 0], qd, rtol=0, atol=3e-7 * np.abs(qd).max())
    np.testing.assert_allclose(r["q"][:, 1], 0.0, rtol=0, atol=1e-15)
    np.testing.assert_allclose(r["V0"], 2 + 0.1 * t + 5 * t ** 2, rtol=1e-14)
    np.testing.assert_allclose(r["dV0"], 0.1 + 10 * t, rtol=1e-14)
    np.testing.assert_allclose(r["s"], 2 * t + 0.05 * t ** 2 + 5 * t ** 3 / 3, rtol=0, atol=1e-14)


def test_a_mast_on_a_trolley_pulled_by_a_ramp_of_traction_follows_the_closed_form():
    """P0 = F0 + F1 t along a straight level track from 2 m/s, no gravity: the trolley and the mast's plane 1
    (along x1) obey m_tot V̇0 + ℓ q̈ = P0 and m q̈ + k q = -ℓ V̇0, ℓ = ∫ N1 dm = ρA L/3 + M_tip. Eliminating V̇0:
    m_e q̈ + k q = -ℓ P0/m_tot, m_e = m - ℓ²/m_tot; from the quasi-static start at t = 0 (q̇ = 0, q = -c F0,
    c = ℓ/(m_tot k)) the ramp gives q = -c (F0 + F1 t) + c F1 sin(Ω t)/Ω, Ω² = k/m_e. Then V̇0 = (P0 - ℓ q̈)/m_tot,
    V0 and s its integrals (ℓ q̇, ℓ q in closed form). Measured: q 7e-9, q̇ 4e-8, V̇0 3e-10, V0 1e-12, s 2e-13."""
    F0, F1, v0 = 30.0, 200.0, 2.0  # q ~ 2e-4 m: the shortening terms, ~(q/L)², stay below 1e-7
    data = scene_dict(effects={"gravity": False, "local_curvature": False, "traction": True},
                      motion={"traction": f"{F0!r} + {F1!r}*t", "initial_speed": v0}, time={"t_end": 0.1, "steps": 4})
    drive = elastic_scene.drive_of(prepared(data), 1)
    t = np.linspace(0.0, 0.1, 21)
    r = el_sim.simulate(mast(0.0), drive, t, rtol=1e-10)
    m_tot = TROLLEY_MASS + RHO_A * L + TIP
    omega = np.sqrt(K1 / (MASS - ELL ** 2 / m_tot))
    c = ELL / (m_tot * K1)
    q, qd, qdd = ramp_response(c * F0, c * F1, omega, t)
    amplitude = c * F1 / omega
    np.testing.assert_allclose(r["q"][:, 0], q, rtol=0, atol=1e-7 * np.abs(q).max())
    np.testing.assert_allclose(r["q"][:, 1], 0.0, rtol=0, atol=1e-15)
    np.testing.assert_allclose(r["qd"][:, 0], qd, rtol=0, atol=3e-7 * np.abs(qd).max())
    assert amplitude > 0.05 * np.abs(q).max()  # the start matters: a wrong start shows in the swing
    P0 = F0 + F1 * t
    np.testing.assert_allclose(r["P"][:, 0], P0, rtol=1e-9)
    np.testing.assert_allclose(r["dV0"], (P0 - ELL * qdd) / m_tot, rtol=1e-8)
    V0 = v0 + (F0 * t + F1 * t ** 2 / 2 - ELL * qd) / m_tot  # q̇(0) = 0
    np.testing.assert_allclose(r["V0"], V0, rtol=1e-9)
    s = v0 * t + (F0 * t ** 2 / 2 + F1 * t ** 3 / 6 - ELL * (q - q[0])) / m_tot
    np.testing.assert_allclose(r["s"], s, rtol=0, atol=1e-9 * s[-1])


@pytest.mark.parametrize("method, handed", [("Radau", True), ("BDF", True), ("LSODA", True), ("DOP853", False)])
def test_implicit_methods_get_the_derivative_of_the_rates_as_their_jacobian(monkeypatch, method, handed):
    """The Jacobian simulate hands the solver: d(q, q̇)'/d(q, q̇) of its own right-hand side by central
    differences (to 1e-6), on a trolley on elastic rollers on a circle (coupled, speed-dependent terms), at
    the start and a kicked state; none to an explicit method (and none when told not to: scipy differences)."""
    import scipy.integrate

    handed_over = {}
    solve_ivp = scipy.integrate.solve_ivp

    def spy(fun, span, y0, **kw):
        handed_over.update(fun=fun, y0=y0, jac=kw.get("jac"))
        return solve_ivp(fun, span, y0, **kw)

    monkeypatch.setattr(scipy.integrate, "solve_ivp", spy)
    beam = el_body.Beam((0.5, 0.3, 0), (0, 0, 1), (1, 0, 0), 1.2, 4.0, (3e3, 5e3), modes=1, damping_ratio=0.05)
    system = el.System(el_body.ElasticModel(80.0, (0.8, 0.4, 0.1), (10.0, 20.0, 15.0, 0, 0, 0), 2.0, 1.0, 9.81,
                                       el_body.Rollers((2e5, 2e5, 3e5, 2e5, 2e5), (300.0,) * 5), beams=(beam,)))
    el_sim.simulate(system, circle(15.0, 12.0), np.linspace(0.0, 0.01, 3), method)
    jac, fun, n = handed_over["jac"], handed_over["fun"], 2 * system.N
    if not handed:
        assert jac is None
        return
    kick = np.r_[np.linspace(1e-3, -2e-3, n), 0.0, 0.0]
    for y in (handed_over["y0"], handed_over["y0"] + kick):
        h = 1e-7 * np.maximum(np.abs(y[:n]), 1e-3)
        diff = np.column_stack([(fun(0.004, y + np.eye(len(y))[j] * h[j]) - fun(0.004, y - np.eye(len(y))[j] * h[j]))
                                [:n] / (2 * h[j]) for j in range(n)])
        analytic = jac(0.004, y)
        assert analytic.shape == (n + 2, n + 2)
        np.testing.assert_allclose(analytic[:n, :n], diff, rtol=0, atol=1e-6 * np.abs(diff).max())


def test_without_the_analytic_jacobian_scipy_differences(monkeypatch):
    import scipy.integrate

    seen = []
    solve_ivp = scipy.integrate.solve_ivp
    monkeypatch.setattr(scipy.integrate, "solve_ivp",
                        lambda *a, **kw: seen.append(kw.get("jac")) or solve_ivp(*a, **kw))
    el_sim.simulate(mast(0.0), straight(), np.linspace(0.0, 0.01, 3), analytic_jacobian=False)
    assert seen == [None]


@pytest.mark.parametrize("method", ["Radau", "DOP853"])
def test_the_evaluation_counts_are_the_calls_the_solver_made(monkeypatch, method):
    """nfev and njev (the scene's function_evaluations) count the right-hand side and Jacobian calls."""
    import scipy.integrate

    calls = {"fun": 0, "jac": 0}
    solve_ivp = scipy.integrate.solve_ivp

    def counting(name, f):
        def wrapped(*args):
            calls[name] += 1
            return f(*args)
        return wrapped

    def spy(fun, span, y0, **kw):
        if kw.get("jac") is not None:
            kw["jac"] = counting("jac", kw["jac"])
        return solve_ivp(counting("fun", fun), span, y0, **kw)

    monkeypatch.setattr(scipy.integrate, "solve_ivp", spy)
    r = el_sim.simulate(mast(0.02), straight(), np.linspace(0.0, 0.02, 5), method, dq0=np.array([1e-4, 0.0]))
    assert (r["nfev"], r["njev"]) == (calls["fun"], calls["jac"])
    assert calls["fun"] > 10 and (calls["jac"] > 0) == (method == "Radau")


def test_a_failed_integration_names_the_last_time_reached():
    """A speed that turns NaN after 0.05 s: the solver gives up past the output at 0.04 s, and says so."""
    drive = straight(2.0)
    broken = dataclasses.replace(drive, speed=lambda t: (np.where(np.asarray(t) < 0.05, 2.0, np.nan), 0.0 * t))
    with pytest.raises(SymmechError, match=r"^elastic trolley: integration failed after t = 0\.04 s \(Required step"):
        el_sim.simulate(mast(0.0), broken, np.linspace(0.0, 0.1, 11))
