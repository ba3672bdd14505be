"""The Python grain loop (``motion.simulate``) against closed forms of a sphere: the free flight (a parabola and a
steady spin about a fixed axis), the contact time sqrt(2h/g) of a drop from height h and the bounce times after it,
restitution along the normal, the sticking impulse of a spinning sphere, the landing, rolling at 5/7 of the
speed, the work of a vibrating plate through the impulses, the energy budget entry by entry and the summary.

Every expected value is written here from those formulas; none comes from the code under test.
"""
import math

import numpy as np
import pytest

from symmech.grain import flight, motion
from symmech.grain.coulomb_law import ImpactLaw

G = 9.81
A = 1e-3  # sphere radius [m]
M = 2e-6  # mass [kg]
I = 0.4 * M * A**2  # solid sphere [kg m^2]
H = 0.01  # drop height of the lowest point [m]
T_C = math.sqrt(2 * H / G)  # first contact of a drop from rest [s]
EZ = np.array([0.0, 0.0, 1.0])


def sphere(law, mu=0.5, amplitude=0.0, freq=20.0, phase=0.0, rotation=True):
    vib = flight.Vibration(amplitude, 2 * math.pi * freq, phase, (0.0, 0.0, 1.0))
    return motion.Model((A,) * 3, M, (0.0, 0.0, -G), vib, law, mu, motion.Effects(rotation=rotation))


def numerics(**kw):
    return motion.Numerics(tolerance=1e-11, scan_step=1e-3, sample_interval=1e-3, **kw)


def state(z=A + H, v=(0.0, 0.0, 0.0), w=(0.0, 0.0, 0.0), q=(1.0, 0.0, 0.0, 0.0)):
    return motion.State(0.0, np.array([0.0, 0.0, z]), np.array(v, float), np.array(q, float), np.array(w, float))


def frictionless(e):
    return ImpactLaw("coulomb", e_n=e, e_t=0.0, mu=0.0, check_printed=False)


def quaternion_matrix(q):
    """Body axes as columns in KXYZ of Hamilton quaternions q (..., 4), scalar first."""
    w, x, y, z = np.moveaxis(np.asarray(q) / np.linalg.norm(q, axis=-1, keepdims=True), -1, 0)
    return np.stack([np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
                     np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
                     np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1)], -2)


def rodrigues(w, t):
    """exp(t [w]x) (3, 3): the rotation by |w| t about w."""
    angle, axis = np.linalg.norm(w) * t, np.asarray(w) / np.linalg.norm(w)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def energy(z, v, w_world):
    """Absolute energy [J] on a still plate: kinetic plus the potential of gravity (zero at z = 0)."""
    return 0.5 * M * float(np.dot(v, v)) + 0.5 * I * float(np.dot(w_world, w_world)) + M * G * z


def test_free_flight_is_a_parabola_with_a_steady_spin():
    q0 = np.array([0.9, 0.2, -0.3, 0.25]) / np.linalg.norm([0.9, 0.2, -0.3, 0.25])
    Q0, w_b = quaternion_matrix(q0), np.array([30.0, -20.0, 50.0])
    r0, v0 = np.array([0.001, 0.002, A + H]), np.array([0.05, -0.02, 0.1])
    t_end = 0.02  # the lowest point is still 2 mm up
    st = motion.State(0.0, r0.copy(), v0.copy(), q0 * 2.0, w_b.copy())  # q is normalised by the loop
    res = motion.simulate(sphere(frictionless(0.5)), numerics(), st, t_end)
    rows = res.trajectory
    t = rows[:, 0]
    np.testing.assert_allclose(t, np.arange(21) * 1e-3, rtol=0, atol=1e-15)
    assert np.all(rows[:, 14] == 0)
    g = np.array([0.0, 0.0, -G])
    np.testing.assert_allclose(rows[:, 1:4], r0 + np.outer(t, v0) + 0.5 * np.outer(t**2, g), rtol=0, atol=1e-13)
    np.testing.assert_allclose(rows[:, 4:7], v0 + np.outer(t, g), rtol=0, atol=1e-13)
    # a sphere spins about a fixed axis at a steady rate: Q(t) = Q0 exp(t [w_b]x), world spin Q0 w_b
    Qt = np.array([Q0 @ rodrigues(w_b, s) for s in t])
    np.testing.assert_allclose(quaternion_matrix(rows[:, 7:11]), Qt, rtol=0, atol=1e-8)
    np.testing.assert_allclose(rows[:, 11:14], np.broadcast_to(Q0 @ w_b, (21, 3)), rtol=0, atol=1e-7)
    assert res.final.t == t_end
    np.testing.assert_allclose(res.final.r, rows[-1, 1:4], rtol=0, atol=0)
    np.testing.assert_allclose(res.final.w, w_b, rtol=0, atol=1e-7)
    assert res.time_in == {"flight": pytest.approx(t_end, abs=1e-15), "sliding": 0.0}
    b = res.extra["energy_budget"]
    start = energy(r0[2], v0, Q0 @ w_b)
    assert b["start_J"] == pytest.approx(start, rel=1e-13)
    assert b["end_J"] == pytest.approx(start, rel=1e-10)
    assert b["input_by_surface_J"] == b["lost_in_impacts_J"] == b["lost_at_landings_J"] == 0.0
    assert b["lost_in_sliding_J"] == 0.0 and b["relative_residual"] < 1e-10
    s = res.summary()
    assert s["duration_s"] == t_end and s["bounces"] == 0
    np.testing.assert_allclose(s["mean_transport_velocity_m_s"], v0[:2], rtol=1e-12)
    assert s["time_fraction"] == {"flight": pytest.approx(1.0, rel=1e-14), "sliding": 0.0}


def test_rotation_off_flies_without_spin():
    res = motion.simulate(sphere(frictionless(0.5), rotation=False), numerics(), state(w=(3.0, 4.0, 5.0)), 0.01)
    assert np.all(res.trajectory[:, 11:14] == 0.0) and np.all(res.final.w == 0.0)
    assert res.extra["energy_budget"]["start_J"] == pytest.approx(M * G * (A + H), rel=1e-13)


def test_dropped_sphere_bounces_at_the_closed_form_times_with_restitution_along_the_normal():
    """Contact at t_c = sqrt(2h/g), rebound at e g t_c, next contacts t_c (1 + 2e) and t_c (1 + 2e + 2e^2)."""
    e, v_t, w_b = 0.6, np.array([0.03, 0.01]), np.array([0.0, 0.0, 40.0])
    t2 = T_C * (1 + 2 * e)
    t_end = T_C * (1 + 2 * e + e * e)  # between the second and the third contact
    res = motion.simulate(sphere(frictionless(e)), numerics(), state(v=(*v_t, 0.0), w=w_b), t_end)
    assert [i["t"] for i in res.impacts] == [pytest.approx(T_C, abs=1e-12), pytest.approx(t2, abs=1e-11)]
    for k, imp in enumerate(res.impacts):
        u = G * T_C * e**k  # approach speed of impact k
        np.testing.assert_allclose(imp["v_before"], [*v_t, -u], rtol=0, atol=1e-10)
        np.testing.assert_allclose(imp["v_after"], [*v_t, e * u], rtol=0, atol=1e-10)
        np.testing.assert_allclose(imp["u_after"], [*v_t, e * u], rtol=0, atol=1e-10)
        np.testing.assert_allclose(imp["impulse"], [0.0, 0.0, M * (1 + e) * u], rtol=1e-9, atol=1e-20)
        np.testing.assert_allclose([imp["w_before"], imp["w_after"]], [w_b, w_b], rtol=0, atol=1e-9)
        spin = 0.5 * I * w_b @ w_b
        assert imp["ke_before"] == pytest.approx(0.5 * M * (v_t @ v_t + u * u) + spin, rel=1e-9)
        assert imp["ke_after"] == pytest.approx(0.5 * M * (v_t @ v_t + e * e * u * u) + spin, rel=1e-9)
        assert imp["r"][2] == pytest.approx(A, abs=1e-13) and imp["admissible"] and imp["converged"]
    impact_rows = res.trajectory[res.trajectory[:, 14] == 1]
    np.testing.assert_allclose(impact_rows[:, 0], [T_C, T_C, t2, t2], rtol=0, atol=1e-11)
    np.testing.assert_allclose(impact_rows[:, 6], G * T_C * np.array([-1, e, -e, e * e]), rtol=1e-9)
    # between the bounces: z = a + e g t_c (t - t_c) - g (t - t_c)^2 / 2
    between = res.trajectory[(res.trajectory[:, 0] > T_C + 1e-9) & (res.trajectory[:, 0] < t2 - 1e-9)]
    tau = between[:, 0] - T_C
    assert len(between) > 50 and np.all(between[:, 14] == 0)
    np.testing.assert_allclose(between[:, 3], A + e * G * T_C * tau - 0.5 * G * tau**2, rtol=0, atol=1e-12)
    tau = t_end - t2
    z_end = A + e * e * G * T_C * tau - 0.5 * G * tau**2
    assert res.final.r[2] == pytest.approx(z_end, abs=1e-12)
    lost = 0.5 * M * (G * T_C) ** 2 * (1 - e * e) * (1 + e * e)
    b = res.extra["energy_budget"]
    assert b["lost_in_impacts_J"] == pytest.approx(lost, rel=1e-9)
    assert b["start_J"] == pytest.approx(energy(A + H, [*v_t, 0.0], w_b), rel=1e-13)
    assert b["end_J"] == pytest.approx(energy(z_end, [*v_t, e * e * G * T_C - G * tau], w_b), rel=1e-10)
    assert b["input_by_surface_J"] == 0.0 and b["lost_at_landings_J"] == 0.0 and b["relative_residual"] < 1e-9
    s = res.summary()
    assert s["bounces"] == 2 and s["energy_dissipated_by_impacts_J"] == pytest.approx(lost, rel=1e-9)
    assert s["impacts_creating_energy"] == 0 and res.extra["landings"] == 0
    np.testing.assert_allclose(s["mean_transport_velocity_m_s"], v_t, rtol=1e-12)


def test_spinning_turned_sphere_sticks_with_the_closed_form_impulse():
    """Sphere, K = diag(7/(2m), 7/(2m), 1/m) at R = (0, 0, -a): P_t = -(1 + e_t) 2m/7 u_t, P_n = -(1 + e_n) m u_n;
    v+ = v + P/m, w+ = w + R x P / I, so u_t+ = -e_t u_t and u_n+ = -e_n u_n."""
    e_n, e_t = 0.5, 0.3
    q0 = np.array([0.3, -0.5, 0.7, 0.4]) / np.linalg.norm([0.3, -0.5, 0.7, 0.4])
    Q0, w_b, v_t = quaternion_matrix(q0), np.array([12.0, -8.0, 6.0]), np.array([0.04, -0.03])
    law = ImpactLaw("coulomb", e_n=e_n, e_t=e_t, mu=math.inf, check_printed=False)
    res = motion.simulate(sphere(law), numerics(), state(v=(*v_t, 0.0), w=w_b, q=q0), T_C + 1e-3)
    imp = res.impacts[0]
    assert imp["t"] == pytest.approx(T_C, abs=1e-12)
    R = np.array([0.0, 0.0, -A])
    w = Q0 @ w_b  # a sphere's spin stays put in flight
    v = np.array([*v_t, -G * T_C])
    u = v + np.cross(w, R)
    P = np.array([*(-(1 + e_t) * 2 * M / 7 * u[:2]), -(1 + e_n) * M * u[2]])
    v1, w1 = v + P / M, w + np.cross(R, P) / I
    np.testing.assert_allclose(imp["u_before"], u, rtol=1e-9)
    np.testing.assert_allclose(imp["impulse"], P, rtol=1e-9)
    np.testing.assert_allclose(imp["v_after"], v1, rtol=1e-9)
    np.testing.assert_allclose(imp["w_before"], w_b, rtol=1e-9)
    Q = Q0 @ rodrigues(w_b, T_C)  # the sphere has turned about its spin axis
    np.testing.assert_allclose(imp["w_after"], Q.T @ w1, rtol=1e-8)  # body axes
    np.testing.assert_allclose(imp["u_after"], [*(-e_t * u[:2]), -e_n * u[2]], rtol=1e-9)
    after = res.trajectory[res.trajectory[:, 14] == 1][1]
    np.testing.assert_allclose(after[11:14], w1, rtol=1e-9)  # world axes in the trajectory
    assert imp["ke_after"] == pytest.approx(0.5 * M * v1 @ v1 + 0.5 * I * w1 @ w1, rel=1e-9)
    assert res.extra["energy_budget"]["lost_in_impacts_J"] == pytest.approx(
        0.5 * M * v @ v + 0.5 * I * w @ w - imp["ke_after"], rel=1e-9)


def test_the_impact_limit_stops_at_the_contact_after_the_last_impact():
    e = 0.6
    t3 = T_C * (1 + 2 * e + 2 * e * e)
    res = motion.simulate(sphere(frictionless(e)), numerics(max_impacts=2), state(), 1.0)
    assert len(res.impacts) == 2
    assert res.final.t == pytest.approx(t3, abs=1e-11) and res.time_in["flight"] == pytest.approx(t3, abs=1e-11)
    assert res.warnings == [f"stopped at t = {res.final.t:.6g} s after numerics.max_impacts = 2 impacts"]
    assert f"{res.final.t:.6g}" == f"{t3:.6g}"


def test_a_plastic_drop_lands_and_rolls_at_five_sevenths():
    """e = 0: the drop stops at t_c and lands (one landing, no landing loss: the impact left no normal velocity);
    sliding with mu, the sphere rolls at 5/7 of v0 and sliding loses m v0^2 / 7."""
    v0, mu = 0.05, 0.4
    t_roll = 2 * v0 / (7 * mu * G)  # slip stops: v = v0 - mu g t = 5/7 v0
    t_end = T_C + 2 * t_roll
    res = motion.simulate(sphere(frictionless(0.0), mu=mu), numerics(), state(v=(v0, 0.0, 0.0)), t_end)
    assert len(res.impacts) == 1 and res.extra["landings"] == 1
    assert res.time_in["flight"] == pytest.approx(T_C, abs=1e-12)
    assert res.time_in["sliding"] == pytest.approx(2 * t_roll, abs=1e-12)
    np.testing.assert_allclose(res.final.v, [5 / 7 * v0, 0.0, 0.0], rtol=0, atol=1e-9)
    assert res.final.r[2] == A
    # distance: v0 t - mu g t^2 / 2 while slipping, then 5/7 v0
    x = v0 * T_C + v0 * t_roll - 0.5 * mu * G * t_roll**2 + 5 / 7 * v0 * t_roll
    assert res.final.r[0] == pytest.approx(x, rel=1e-8)
    np.testing.assert_allclose(res.trajectory[-1, 11:14], [0.0, 5 / 7 * v0 / A, 0.0], rtol=0, atol=1e-6)
    b = res.extra["energy_budget"]
    assert b["lost_in_impacts_J"] == pytest.approx(0.5 * M * (G * T_C) ** 2, rel=1e-9)
    assert b["lost_at_landings_J"] == pytest.approx(0.0, abs=1e-12 * M * v0**2)
    assert b["lost_in_sliding_J"] == pytest.approx(M * v0**2 / 7, rel=1e-7)
    assert b["relative_residual"] < 1e-9
    sliding_rows = res.trajectory[res.trajectory[:, 14] == 2]
    assert np.all(sliding_rows[:, 3] == A) and np.all(sliding_rows[:, 6] == 0.0)
    s = res.summary()
    assert s["time_fraction"]["flight"] == pytest.approx(T_C / t_end, rel=1e-10)
    assert s["time_fraction"]["sliding"] == pytest.approx(2 * t_roll / t_end, rel=1e-10)


@pytest.mark.parametrize("rotation", [True, False])
def test_released_on_the_plane_moving_down_lands_with_the_plastic_loss(rotation):
    """On the plane with normal velocity -u and spin about the normal: the landing impulse m u through the centre
    loses m u^2 / 2 and keeps the spin; it is not counted as a landing of the loop."""
    u, v_t = 0.02, (0.0, 0.0)
    w_b = (0.0, 0.0, 30.0) if rotation else (0.0, 0.0, 0.0)
    res = motion.simulate(sphere(frictionless(0.5), rotation=rotation), numerics(),
                          state(z=A, v=(*v_t, -u), w=w_b), 0.002)
    assert res.impacts == [] and res.extra["landings"] == 0
    b = res.extra["energy_budget"]
    assert b["lost_at_landings_J"] == pytest.approx(0.5 * M * u * u, rel=1e-12)
    np.testing.assert_allclose(res.trajectory[0, 4:7], [*v_t, -u], rtol=0, atol=0)
    assert res.trajectory[0, 14] == 0 and np.all(res.trajectory[1:, 14] == 2)
    assert np.all(res.trajectory[1:, 6] == 0.0)
    np.testing.assert_allclose(res.final.w, w_b, rtol=0, atol=1e-9)
    assert res.time_in == {"flight": 0.0, "sliding": pytest.approx(0.002, abs=1e-15)}


def test_work_of_a_vibrating_plate_is_the_sum_of_its_impulses_times_its_velocity():
    """Plate s = A0 sin(w t + phi) e_z at Gamma = 2 (7 impacts in 6 periods, no landing): input = sum of P_z A0 w cos(w t_i + phi) over the impacts, and
    the relative normal velocity reverses with e at each."""
    e, freq, phase = 0.5, 25.0, 0.4
    om = 2 * math.pi * freq
    amp = 2.0 * G / om**2
    model = sphere(frictionless(e), amplitude=amp, freq=freq, phase=phase, rotation=False)
    num = motion.Numerics(tolerance=1e-11, scan_step=1 / freq / 40, sample_interval=1e-3)
    res = motion.simulate(model, num, state(z=A + 1e-4), 6 / freq)
    assert len(res.impacts) == 7 and res.extra["landings"] == 0
    t = np.array([i["t"] for i in res.impacts])
    P = np.array([i["impulse"] for i in res.impacts])
    u0, u1 = np.array([i["u_before"] for i in res.impacts]), np.array([i["u_after"] for i in res.impacts])
    np.testing.assert_allclose(u1[:, 2], -e * u0[:, 2], rtol=1e-9)
    np.testing.assert_allclose(P[:, 2], -M * (1 + e) * u0[:, 2], rtol=1e-9)
    b = res.extra["energy_budget"]
    assert b["input_by_surface_J"] == pytest.approx(np.sum(P[:, 2] * amp * om * np.cos(om * t + phase)), rel=1e-12)
    # absolute energy at the start: the plate moves at amp om cos(phase) and sits at amp sin(phase)
    s0, ds0 = amp * math.sin(phase), amp * om * math.cos(phase)
    assert b["start_J"] == pytest.approx(0.5 * M * ds0**2 + M * G * (A + 1e-4 + s0), rel=1e-12)
    assert b["relative_residual"] < 1e-9


def test_tilted_ellipsoid_landing_keeps_the_momentum_about_the_contact_and_drops_the_tilting_spin():
    """An ellipsoid resting tilted on the plane with normal velocity -u: the plastic impulse P = u / K_nn e_z at
    the lowest point R (K = 1/m - [R]x I^-1 [R]x, by hand) turns it by I^-1 (R x P); the landing keeps the spin
    about the normal and drops the tilt, so it loses m u^2 / 2 - I_zz w_z^2 / 2."""
    axes, m, u = np.array([3e-3, 2e-3, 1e-3]), 4e-6, 0.02
    q0 = np.array([0.8, 0.3, -0.4, 0.2]) / np.linalg.norm([0.8, 0.3, -0.4, 0.2])
    Q = quaternion_matrix(q0)
    n = Q.T @ EZ  # the plane's normal in body axes
    R = -Q @ (axes**2 * n) / np.linalg.norm(axes * n)  # lowest point, from the centre
    I_w = Q @ np.diag(m / 5 * (np.sum(axes**2) - axes**2)) @ Q.T

    def skew(x):
        return np.array([[0, -x[2], x[1]], [x[2], 0, -x[0]], [-x[1], x[0], 0]])

    K = np.eye(3) / m - skew(R) @ np.linalg.inv(I_w) @ skew(R)
    P = np.array([0.0, 0.0, u / K[2, 2]])
    w_z = (np.linalg.inv(I_w) @ np.cross(R, P))[2]
    assert abs(w_z) > 0.1  # the landing spins it about the normal
    model = motion.Model(tuple(axes), m, (0.0, 0.0, -G), flight.Vibration(0.0, 1.0, 0.0, (0.0, 0.0, 1.0)),
                         frictionless(0.5), 0.3, motion.Effects())
    st = motion.State(0.0, np.array([0.0, 0.0, np.linalg.norm(axes * n)]), np.array([0.0, 0.0, -u]), q0,
                      np.zeros(3))
    res = motion.simulate(model, numerics(), st, 1e-6)
    landed = res.trajectory[1]
    assert landed[0] == 0.0 and landed[14] == 2
    np.testing.assert_allclose(landed[4:7], 0.0, rtol=0, atol=1e-15)
    np.testing.assert_allclose(landed[11:14], [0.0, 0.0, w_z], rtol=1e-9, atol=1e-12 * abs(w_z))
    lost = 0.5 * m * u * u - 0.5 * I_w[2, 2] * w_z**2
    assert res.extra["energy_budget"]["lost_at_landings_J"] == pytest.approx(lost, rel=1e-9)


def test_summary_counts_and_rates_of_a_given_motion():
    """Motion.summary of a hand-made result starting at t = 0.3 s: rates over the duration 0.5 s, the impact
    counts by verdict (None: not checked), the energy lost in impacts, extra and warnings passed through."""
    def impact(ke0, ke1, admissible, printed, gain):
        return {"ke_before": ke0, "ke_after": ke1, "admissible": admissible, "printed_admissible": printed,
                "printed_creates_energy": gain}

    impacts = [impact(5.0, 2.0, True, False, True), impact(3.0, 4.0, False, None, None),
               impact(1.0, 0.5, True, True, False), impact(2.0, 1.0, True, False, False),
               impact(1.5, 1.0, True, False, False)]
    start = motion.State(0.3, np.array([1.0, 2.0, 0.1]), np.zeros(3), np.array([1.0, 0, 0, 0]), np.zeros(3))
    final = motion.State(0.8, np.array([1.2, 1.9, 0.4]), np.zeros(3), np.array([1.0, 0, 0, 0]), np.zeros(3))
    res = motion.Motion(np.zeros((0, 15)), motion.ImpactLog(impacts), {"flight": 0.4, "sliding": 0.1}, ["w1"], start, final,
                        {"landings": 3})
    assert res.summary() == {
        "duration_s": pytest.approx(0.5, abs=1e-15),
        "mean_transport_velocity_m_s": [pytest.approx(0.4, rel=1e-12), pytest.approx(-0.2, rel=1e-12)],
        "bounces": 5, "time_fraction": {"flight": pytest.approx(0.8, rel=1e-12), "sliding": pytest.approx(0.2, rel=1e-12)},
        "energy_dissipated_by_impacts_J": pytest.approx(3.0 - 1.0 + 0.5 + 1.0 + 0.5, rel=1e-15),
        "impacts_creating_energy": 1, "impacts_where_printed_law_is_inadmissible": 3,
        "impacts_where_printed_law_creates_energy": 1, "landings": 3, "warnings": ["w1"]}


def test_rolling_start_with_spin_about_the_normal_samples_the_closed_form_spin(monkeypatch):
    """Released on the plane at v0 along x with spin s about the normal: friction spins it up about y at
    5 mu g t / (2a) until it rolls at 5/7 v0 (t_roll = 2 v0 / (7 mu g)); the spin about the normal stays. The
    sliding rows sit at the sample times (from 0); progress is reported from inside the phase (at the rolling event)."""
    v0, mu, s = 0.05, 0.4, 30.0
    t_roll = 2 * v0 / (7 * mu * G)
    t_end = 0.0015 + t_roll
    monkeypatch.setattr(motion, "PROGRESS_INTERVAL", 0.0)
    seen = []
    res = motion.simulate(sphere(frictionless(0.0), mu=mu), numerics(), state(z=A, v=(v0, 0.0, 0.0), w=(0, 0, s)),
                          t_end, on_step=seen.append)
    rows = res.trajectory[res.trajectory[:, 14] == 2]
    t = rows[:, 0]
    np.testing.assert_allclose(t[:-2], np.arange(int(t_end / 1e-3) + 1) * 1e-3, rtol=0, atol=1e-15)
    assert t[-2] == t[-1] == t_end  # the phase's end and the run's last row
    w_y = np.minimum(5 * mu * G * t / (2 * A), 5 / 7 * v0 / A)
    np.testing.assert_allclose(rows[:, 11:14], np.column_stack([0 * t, w_y, s + 0 * t]), rtol=0, atol=1e-6 * s)
    np.testing.assert_allclose(rows[:, 4], np.maximum(v0 - mu * G * t, 5 / 7 * v0), rtol=0, atol=1e-9)
    assert any(t_roll - 1e-9 < x < t_roll + 1e-9 for x in seen) and seen[0] == 0.0 and seen[-1] == t_end


def test_bounces_shorter_than_the_scan_step_follow_the_geometric_series_until_the_landing():
    """Drop with e = 0.6: contacts at t_c (1 + 2e (1 - e^k) / (1 - e)), rebounds at e^(k+1) sqrt(2 g h); from the
    tenth on a flight (2 e^k sqrt(2h/g)) is shorter than the 1 ms scan step. The 21st rebound, 9.7e-6 m/s, is
    below rest_velocity = 1e-5 m/s: it lands there."""
    e = 0.6
    k = np.arange(21)
    t_k = T_C * (1 + 2 * e * (1 - e**k) / (1 - e))
    res = motion.simulate(sphere(frictionless(e)), numerics(), state(), t_k[-1] + 0.002)
    np.testing.assert_allclose([i["t"] for i in res.impacts], t_k, rtol=0, atol=1e-11)
    np.testing.assert_allclose([i["v_after"][2] for i in res.impacts], e ** (k + 1) * G * T_C, rtol=1e-6)
    assert res.extra["landings"] == 1 and res.time_in["flight"] == pytest.approx(t_k[-1], abs=1e-11)


def test_energy_budget_of_a_vibrating_conveyor_closes_over_flights_impacts_and_sliding_phases():
    """A point mass thrown off a 30 degree vibrating incline once a period (Gamma_v = 1.3): the surface's work
    equals the change of energy plus the losses, summed over every phase."""
    gam, om = math.radians(30), 2 * math.pi * 25
    amp = 1.3 * G / (om**2 * math.sin(gam))
    vib = flight.Vibration(amp, om, 0.3, (math.cos(gam), 0.0, math.sin(gam)))
    g_k = (G * math.sin(math.radians(3)), 0.0, -G * math.cos(math.radians(3)))
    model = motion.Model((A,) * 3, M, g_k, vib, frictionless(0.0), 0.4, motion.Effects(rotation=False))
    num = motion.Numerics(tolerance=1e-11, scan_step=1 / 25 / 40, sample_interval=1e-3)
    res = motion.simulate(model, num, state(z=A), 3 / 25)
    b = res.extra["energy_budget"]
    assert res.extra["landings"] >= 2 and b["lost_in_sliding_J"] > 0 and b["input_by_surface_J"] > 0
    assert b["end_J"] - b["start_J"] == pytest.approx(
        b["input_by_surface_J"] - b["lost_in_impacts_J"] - b["lost_at_landings_J"] - b["lost_in_sliding_J"],
        abs=1e-9 * b["input_by_surface_J"])


@pytest.mark.slow  # 160 impacts: 2-8 s
def test_a_hundred_bounces_within_the_chattering_window_end_in_sliding():
    """e = 0.95 on a plate of amplitude 1e-15 m (so the contacts are the still plate's, at t_c (1 + 2e (1 - e^n) /
    (1 - e))) whose period puts the window of 1e-4 periods between the spans of the last 99 and 98 gaps closing at
    impact 159: the loop lands at impact 160, the first that closes 100 impacts within the window, although the
    rebounds are still far above rest_velocity."""
    e = 0.95
    t = T_C * (1 + 2 * e * (1 - e ** np.arange(400)) / (1 - e))
    window = t[158] - t[59] - 0.5 * (t[158] - t[157])
    model = sphere(frictionless(e), amplitude=1e-15, freq=1e-4 / window, rotation=False)
    assert model.period * 1e-4 == pytest.approx(window, rel=1e-14)
    n = next(k + 1 for k in range(99, 400) if t[k] - t[k - 99] < window)
    assert n == 160 and e**n * G * T_C > 10 * 1e-5
    res = motion.simulate(model, numerics(), state(), t[n - 1] + 0.01)
    assert len(res.impacts) == n and res.extra["landings"] == 1
    np.testing.assert_allclose(res.impacts[-1]["t"], t[n - 1], rtol=0, atol=1e-10)
    assert res.warnings == ["100 impacts within 0.0001 periods: chattering summed into sliding"]
    assert res.time_in["sliding"] == pytest.approx(0.01, abs=1e-10)


def needle():
    """(model, start) of a needle (5:1:1) tumbling onto a still plate under the printed law (e = lam = 0.9)."""
    axes, m = np.array([5e-3, 1e-3, 1e-3]), 1e-6
    q0 = np.array([-0.529, 0.693, -0.481, 0.091]) / np.linalg.norm([-0.529, 0.693, -0.481, 0.091])
    Q = quaternion_matrix(q0)
    n = Q.T @ EZ
    model = motion.Model(tuple(axes), m, (0.0, 0.0, -G), flight.Vibration(0.0, 1.0, 0.0, (0.0, 0.0, 1.0)),
                         ImpactLaw("printed", e=0.9, lam=0.9), 0.3, motion.Effects())
    st = motion.State(0.0, np.array([0.0, 0.0, np.linalg.norm(axes * n) + 1e-9]), np.array([0.01, 0.084, -0.3]),
                      q0, Q.T @ np.array([43.5, 3.4, -2.4]))
    return model, st


def needle_energies(model, imp) -> tuple[float, float]:
    """Kinetic energy [J] before and after an impact of the log, by hand: m v^2/2 + sum I_i w_i^2/2 (solid
    ellipsoid, body axes)."""
    axes, m = np.array(model.axes), model.mass
    inertia = m / 5 * (np.sum(axes**2) - axes**2)
    return tuple(0.5 * m * np.dot(imp[v], imp[v]) + 0.5 * np.dot(inertia, np.square(imp[w]))
                 for v, w in (("v_before", "w_before"), ("v_after", "w_after")))


def test_the_impact_laws_warnings_reach_the_run():
    """A needle (5:1:1) hitting the plate tumbling, with the printed law (e = lam = 0.9) that gains 5 % kinetic
    energy there: the run reports the law's two warnings, the energy by hand from the log (m v^2/2 + sum I_i w_i^2/2,
    body axes), and counts the impact as creating energy."""
    model, st = needle()
    res = motion.simulate(model, numerics(), st, 1e-5)
    imp = res.impacts[0]
    ke0, ke1 = needle_energies(model, imp)
    assert ke1 > 1.04 * ke0 and not imp["admissible"] and imp["printed_creates_energy"] is True
    assert res.warnings[:2] == ["printed impact law: no admissible root; the one used creates kinetic energy",
                                f"impact law 'printed' created energy: {ke0:.6g} J -> {ke1:.6g} J"]
    s = res.summary()
    assert s["impacts_creating_energy"] == 1 and s["impacts_where_printed_law_creates_energy"] == 1


def test_a_start_given_as_tuples_runs_as_arrays():
    """The start state may be any sequences (a non-unit quaternion too): released on the plane moving down at u, it
    lands with the loss m u^2 / 2 and slides from the height a, turning about the normal."""
    u = 0.02
    st = motion.State(0.0, (0.0, 0.0, A), (0.0, 0.0, -u), (2.0, 0.0, 0.0, 0.0), (0.0, 0.0, 30.0))
    res = motion.simulate(sphere(frictionless(0.5)), numerics(), st, 0.002)
    assert res.extra["energy_budget"]["lost_at_landings_J"] == pytest.approx(0.5 * M * u * u, rel=1e-12)
    t = res.trajectory[:, 0]
    assert np.all(res.trajectory[1:, 3] == A)
    np.testing.assert_allclose(res.trajectory[:, 7:11], np.column_stack([np.cos(15 * t), 0 * t, 0 * t, np.sin(15 * t)]),
                               rtol=0, atol=1e-9)  # spinning about the normal at 30 rad/s


def test_released_at_rest_under_weak_gravity_slides_from_the_start():
    """g = 0.5 m/s^2 still pushes the grain onto the plane: it slides from the start (no landing counted)."""
    model = motion.Model((A,) * 3, M, (0.0, 0.0, -0.5), flight.Vibration(0.0, 1.0, 0.0, (0.0, 0.0, 1.0)),
                         frictionless(0.5), 0.4, motion.Effects())
    res = motion.simulate(model, numerics(), state(z=A), 0.002)
    assert res.extra["landings"] == 0 and res.time_in == {"flight": 0.0, "sliding": pytest.approx(0.002, abs=1e-15)}



@pytest.mark.slow  # two tumbling flights in Python: 0.8 s
def test_exact_flight_of_a_tumbling_needle_meets_the_plate_where_dop853_does():
    """The needle tumbling 5 mm above a still plate, flown in closed form (free_flight's Jacobi functions, contacts
    certified by the gap's curvature bound) and by DOP853 to 1e-11: the same first contact to 1e-9 s, and the same
    state there (the centre, whose height is the support distance of the attitude, to 1e-10 m; the spin to 1e-6
    rad/s)."""
    model, st = needle()
    st = motion.State(0.0, st.r + np.array([0.0, 0.0, 5e-3]), st.v, st.q, st.w)
    exact, ref = (motion.simulate(model, numerics(flight=how, max_impacts=1), st, 0.1).impacts[0]
                  for how in ("exact", "dop853"))
    assert exact["t"] == pytest.approx(ref["t"], abs=1e-9) and 1e-3 < ref["t"] < 3e-2
    np.testing.assert_allclose(exact["r"], ref["r"], rtol=0, atol=1e-10)
    np.testing.assert_allclose(exact["w_before"], ref["w_before"], rtol=0, atol=1e-6)
    np.testing.assert_allclose(exact["v_before"], ref["v_before"], rtol=0, atol=1e-9)
