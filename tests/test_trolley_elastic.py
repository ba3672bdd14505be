"""Elastic trolley (seed 002): derivation, rollers, beams, rigid limit, stiffening, energy."""
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg
from scipy.optimize import brentq

from symmech.core.errata import evaluate
from symmech.generated import trolley_elastic as gen
from symmech.generated import trolley_frame as frm
from symmech.trolley.elastic import system as el, body as el_body, frame as el_frame, simulate as el_sim
from symmech.trolley.elastic import scene as elastic_scene, errata as errata_elastic

sys.path.insert(0, str(Path(__file__).parent))
from trolley_util import prepared, setup as scene_dict  # noqa: E402

RNG = np.random.default_rng(7)
G0 = 9.81
# roots βL of 1 + cos βL cosh βL = 0 (clamped-free beam)
CANTILEVER_BETA = (1.8751040687119611, 4.6940911329741745, 7.8547574382376126)


def drive_for(data, case=1):
    """The elastic model's drive of a trolley scene dict (prepared like `symmech run`)."""
    return elastic_scene.drive_of(prepared(data), case)


def straight(speed=0.0):
    return drive_for(scene_dict(motion={"speed": f"{speed!r}"}))


def circle(radius, speed):
    """Horizontal circle at constant speed: x2 toward the centre, x3 up (Frenet)."""
    r = f"{radius!r}"
    return drive_for(scene_dict(frame="frenet", track={"type": "expression", "x": f"{r}*sin(s/{r})", "y": "0",
                                                       "z": f"{r}*cos(s/{r})"},
                                motion={"speed": f"{speed!r}"}, time={"t_end": 1.0, "steps": 10}))


def modes_at(system, drive, q=None):
    fs = el_sim._state_at(drive, 0.0, 0.0)
    return system.linear_modes(fs, np.zeros(system.N) if q is None else q)


# ---------------------------------------------------------------- derivation and errata

def test_rigid_fields_are_the_derivatives_of_the_exact_turn():
    """φ0, ψ0 against central differences of Λ(θ)ᵀ r (the rigid model's generated Λ)."""
    r = RNG.normal(size=3)
    fields = gen.rigid_fields(*r)
    h = 1e-4

    def disp(q):
        u2, u3, t1, t2, t3 = q
        return frm.Lambda(t1, t2, t3).T @ r - r + np.array([0, u2, u3])

    eye = np.eye(5)
    for a in range(5):
        d1 = (disp(h * eye[a]) - disp(-h * eye[a])) / (2 * h)
        assert np.abs(d1 - fields[:, a]).max() < 1e-8
    for col, (i, j) in enumerate(((2, 2), (2, 3), (2, 4), (3, 3), (3, 4), (4, 4))):
        ei, ej = h * eye[i], h * eye[j]
        d2 = (disp(ei + ej) - disp(ei - ej) - disp(-ei + ej) + disp(-ei - ej)) / (4 * h * h)
        assert np.abs(d2 - fields[:, 5 + col]).max() < 1e-6


def test_errata_find_the_misprinted_psi44_only():
    records = {r["description"].split()[1]: r for r in map(evaluate, errata_elastic.checks())}
    assert records.pop("ψ0_44")["status"] == "differs"
    assert all(r["status"] == "agrees" and r["max_rel_diff"] == 0 for r in records.values())
    assert len(records) == 10


def test_roller_matrix_maps_coordinates_to_contact_deflections():
    C = gen.roller_matrix(2.0, 0.75)
    q = np.array([1e-3, -2e-3, 1e-4, 2e-4, -3e-4])
    fields = gen.rigid_fields(*np.array([(0, 0, -0.75), (0, 0, 0.75), (2, 0, 0), (0, 0, 0), (2, 0, 0)]).T)
    along = [1, 1, 1, 2, 2]
    linear = [fields[p, along[p], :5] @ q for p in range(5)]
    assert np.allclose(C @ q, linear, rtol=1e-15)


# ---------------------------------------------------------------- rollers

def roller_model(g0, k, c=(0.0,) * 5, com=(0.8, 0.5, 0.0), inertia=(20.0, 30.0, 25.0, 0, 0, 0), law="linear",
                 preload=(0.0,) * 5):
    return el_body.ElasticModel(100.0, com, inertia, 2.0, 1.0, g0, el_body.Rollers(k, c, law, preload),
                           effects=el_body.Effects(damping=any(c)))


def closed_form_roller_frequencies(m, com, inertia, k, l, a, g0):
    """Bounce/pitch (u2, θ3) and lateral/roll/yaw (u3, θ1, θ2) eigenproblems, textbook form."""
    c = np.asarray(com)
    I_O = np.diag(inertia[:3]) + m * (c @ c * np.eye(3) - np.outer(c, c))
    Mv = np.array([[m, m * c[0]], [m * c[0], I_O[2, 2]]])
    Kv = np.array([[k[0] + k[1] + k[2], k[2] * l], [k[2] * l, k[2] * l * l - m * g0 * c[1]]])
    Ml = np.array([[m, m * c[1], -m * c[0]], [m * c[1], I_O[0, 0], I_O[0, 1]], [-m * c[0], I_O[0, 1], I_O[1, 1]]])
    Kl = np.array([[k[3] + k[4], 0, -k[4] * l], [0, a * a * (k[0] + k[1]) - m * g0 * c[1], 0],
                   [-k[4] * l, 0, k[4] * l * l]])
    return np.sqrt(scipy.linalg.eigh(Kv, Mv)[0]), np.sqrt(scipy.linalg.eigh(Kl, Ml)[0])


@pytest.mark.parametrize("g0", [0.0, G0])
def test_roller_frequencies_on_a_straight_level_track(g0):
    k = (1e6, 1e6, 2e6, 1.5e6, 1e6)
    system = el.System(roller_model(g0, k))
    omega, zeta = modes_at(system, straight(10.0))
    vertical, lateral = closed_form_roller_frequencies(100.0, (0.8, 0.5, 0.0), (20, 30, 25), k, 2.0, 1.0, g0)
    assert np.allclose(omega, np.sort(np.r_[vertical, lateral]), rtol=1e-12)
    assert np.abs(zeta).max() < 1e-12
    # gravity lowers the pitch and roll frequencies through the height of the centre of mass
    if g0:
        assert omega.min() < closed_form_roller_frequencies(100.0, (0.8, 0.5, 0.0), (20, 30, 25), k, 2.0, 1.0,
                                                            0.0)[0].min() - 0.01


def test_quasi_static_state_carries_the_weight():
    k = (1e10, 1e10, 2e10, 1.5e10, 1e10)  # deflections ~1e-7 m: the load moves by that much
    system = el.System(roller_model(G0, k))
    fs = el_sim._state_at(straight(), 0.0, 0.0)
    q = system.quasi_static(fs)
    P = system.reactions(fs, q, 0 * q, 0 * q)
    # statics of three supports: B, C share the moment about the front axle
    total = 100.0 * G0
    front = total * 0.8 / 2.0
    assert np.allclose(P, [0, (total - front) / 2, (total - front) / 2, front, 0, 0], rtol=1e-6, atol=1e-9)


def test_clamped_pair_law():
    rollers = el_body.Rollers((2e6,) * 5, (0.0,) * 5, "clamped_pair", (1e-4, 1e-4, 1e-4, -1e-4, 1e-4))
    d = np.array([5e-5, -3e-4, 2e-4, 5e-5, 0.0])
    force, kt = el_body.roller_forces(rollers, d, np.zeros(5), False)
    # inside the preload both rollers push: 2k; beyond it only one: k; inside the gap none
    assert np.allclose(force, [-2e6 * 5e-5 * 2, 2e6 * (4e-4), -2e6 * 3e-4, 0.0, 0.0])
    assert np.allclose(kt, [-4e6, -2e6, -2e6, 0.0, -4e6])
    h = 1e-9
    for i in range(5):
        e = np.eye(5)[i] * h
        fd = -(el_body.roller_energy(rollers, d + e) - el_body.roller_energy(rollers, d - e)) / (2 * h)
        assert fd == pytest.approx(force[i], rel=1e-6, abs=1e-6)


def test_preloaded_pair_doubles_the_linear_frequencies():
    k = (1e6, 1e6, 2e6, 1.5e6, 1e6)
    pair = el.System(roller_model(0.0, k, law="clamped_pair", preload=(1e-3,) * 5))
    linear = el.System(roller_model(0.0, tuple(2 * x for x in k)))
    assert np.allclose(modes_at(pair, straight())[0], modes_at(linear, straight())[0], rtol=1e-12)


# ---------------------------------------------------------------- beams

def beam_on_rigid_rollers(beam, g0=0.0, stiffening=True, probes=()):
    mdl = el_body.ElasticModel(100.0, (0, 0, 0), (1, 1, 1, 0, 0, 0), 2.0, 1.0, g0, None, (beam,),
                          el_body.Effects(rollers=False, stiffening=stiffening))
    return el.System(mdl, probes)


def test_cantilever_frequencies_converge_from_above():
    """Two bending planes (EI ratio 4: frequencies x2); Ritz errors fall with the number of modes."""
    L, rho_a, ei = 1.3, 2.0, (3.0, 12.0)
    unit = np.sqrt(ei[0] / (rho_a * L ** 4))
    exact = np.array(CANTILEVER_BETA) ** 2 * unit
    errors = []
    for modes in range(3, 9):
        beam = el_body.Beam((0.2, 0, 0), (1, 0, 0), (0, 1, 0), L, rho_a, ei, "cantilever", modes)
        omega = np.sort(modes_at(beam_on_rigid_rollers(beam), straight())[0])
        plane1 = omega[[0, 2, 4]]  # β1², 2β1², β2², 2β2², β3², …
        assert omega[1] == pytest.approx(2 * omega[0], rel=1e-10)
        assert np.all(plane1 >= exact * (1 - 1e-10))
        errors.append(plane1 / exact - 1)
    errors = np.array(errors)
    floor = 1e-9  # rounding of the state-space eigenvalues
    assert np.all(np.diff(np.maximum(errors, floor), axis=0) <= 0)
    assert np.all(errors[-1] < [floor, 1e-7, 2e-6])
    assert errors[0, 1] > 1e-3  # three functions are far from the second mode


def test_pinned_beam_frequencies():
    L, rho_a, ei = 2.0, 1.5, (4.0, 4.0)
    system = beam_on_rigid_rollers(el_body.Beam((0, 0, 0), (0, 0, 1), (1, 0, 0), L, rho_a, ei, "pinned", 8))
    omega = np.sort(modes_at(system, straight())[0])
    unit = np.sqrt(ei[0] / (rho_a * L ** 4))
    assert np.allclose(omega[[0, 1]], np.pi ** 2 * unit, rtol=1e-10)
    assert np.allclose(omega[[2, 3]], 4 * np.pi ** 2 * unit, rtol=1e-7)


def test_cantilever_with_tip_mass():
    L, rho_a, ei, tip = 1.0, 1.0, (1.0, 1.0), 0.7
    system = beam_on_rigid_rollers(el_body.Beam((0, 0, 0), (1, 0, 0), (0, 1, 0), L, rho_a, ei, "cantilever", 8, tip))
    omega = np.sort(modes_at(system, straight())[0])[0]
    ratio = tip / (rho_a * L)
    f = lambda b: 1 + np.cos(b) * np.cosh(b) + ratio * b * (np.cos(b) * np.sinh(b) - np.sin(b) * np.cosh(b))  # noqa
    beta = brentq(f, 0.5, 1.875)
    assert omega == pytest.approx(beta ** 2 * np.sqrt(ei[0] / (rho_a * L ** 4)), rel=1e-9)


@pytest.mark.parametrize("modes, err", [(1, 1 / 3), (3, 0.0)])
def test_static_sag_under_gravity(modes, err):
    """Horizontal cantilever: tip sag ρAgL⁴/(8EI); Ritz with ξ² alone gives 2/3 of it, the
    quartic deflection is exact from three functions."""
    L, rho_a, ei = 1.5, 3.0, (50.0, 50.0)
    system = beam_on_rigid_rollers(el_body.Beam((0, 0, 0), (1, 0, 0), (0, 1, 0), L, rho_a, ei, "cantilever", modes),
                                   g0=G0, probes=[(0, 1.0)])
    fs = el_sim._state_at(straight(), 0.0, 0.0)
    q = system.quasi_static(fs)
    rr, _ = system.coefficients(q)
    tip = np.einsum("k,kpi->pi", rr, system.inv.probe_fields)[0] - system.inv.probe_points[0]
    sag = rho_a * G0 * L ** 4 / (8 * ei[0])
    assert -tip[1] / sag == pytest.approx(1 - err, rel=1e-10)


# ---------------------------------------------------------------- geometric stiffening

def southwell(hub_ratio):
    """K1 + hub K2 = ∫ T φ'² / (Ω² ∫ m φ²) with the exact first cantilever mode (Rayleigh)."""
    b = CANTILEVER_BETA[0]
    s = (np.cosh(b) + np.cos(b)) / (np.sinh(b) + np.sin(b))
    x, w = np.polynomial.legendre.leggauss(60)
    x, w = (x + 1) / 2, w / 2
    phi = np.cosh(b * x) - np.cos(b * x) - s * (np.sinh(b * x) - np.sin(b * x))
    dphi = b * (np.sinh(b * x) + np.sin(b * x) - s * (np.cosh(b * x) - np.cos(b * x)))
    tension = (1 - x * x) / 2 + hub_ratio * (1 - x)
    return (w * tension * dphi ** 2).sum() / (w * phi ** 2).sum()


@pytest.mark.parametrize("hub", [0.0, 0.5])
def test_rotating_cantilever_follows_southwell(hub):
    """Beam radial on a horizontal circle, root at distance hub·L from the centre."""
    R, L, rho_a, ei = 10.0, 1.0, 1.0, (1.0, 1.0)
    omega0 = CANTILEVER_BETA[0] ** 2
    beam = el_body.Beam((0, R - hub * L, 0), (0, -1, 0), (0, 0, 1), L, rho_a, ei, "cantilever", 8)
    out = {}
    for stiffening in (True, False):
        system = beam_on_rigid_rollers(beam, stiffening=stiffening)
        rates = []
        for spin in (0.05 * omega0, 0.1 * omega0):
            w = np.sort(modes_at(system, circle(R, spin * R))[0])
            chord, flap = w[0], w[1]  # chordwise lies below flapwise once spinning
            rates.append(((flap ** 2 - omega0 ** 2) / spin ** 2, (chord ** 2 - omega0 ** 2) / spin ** 2))
        out[stiffening] = np.array(rates)
    K = southwell(hub)
    # Richardson: the coefficient at Ω -> 0 from two small speeds (error O(Ω²))
    limit = (4 * out[True][0] - out[True][1]) / 3
    if hub == 0:
        assert K == pytest.approx(1.1933, abs=1e-4)
    assert limit[0] == pytest.approx(K, rel=1e-4)        # flapwise
    assert limit[1] == pytest.approx(K - 1, rel=1e-3)    # chordwise
    # without the ψ fields: no stiffening out of plane, the spurious softening -Ω² in plane
    assert np.allclose(out[False][:, 0], 0.0, atol=1e-6)
    assert np.allclose(out[False][:, 1], -1.0, atol=1e-6)


# ---------------------------------------------------------------- along the track

def helix(t_end=10.0):
    return drive_for(scene_dict(frame="frenet", track={"type": "helix", "radius": 7.0, "rise": 5 / (2 * np.pi)},
                                motion={"speed": "3*t + 7*sin(t/2)"}, time={"t_end": t_end, "steps": 10}))


@pytest.mark.slow  # two 10 s rides on stiff rollers on the Python engine (~4.5 s of CPU)
def test_rigid_limit_on_the_paper_helix():
    """P0…P5 converge to the rigid model's reactions with the error falling like 1/k."""
    t = np.linspace(0.0, 10.0, 21)
    late = t >= 5.0  # after the start transient has been damped out
    errors = []
    for k in (1e7, 1e8):
        mdl = el_body.ElasticModel(100.0, (1.0, 0.5, 0.0), (10.0, 20.0, 15.0, 0, 0, 0), 2.0, 1.0, G0,
                              el_body.Rollers((k,) * 5, (2000.0,) * 5))
        r = el_sim.simulate(el.System(mdl), helix(), t)
        scale = np.abs(r["P_rigid"][late]).max()
        errors.append(np.abs(r["P"][late] - r["P_rigid"][late]).max() / scale)
    assert errors[1] < 1e-4
    assert 8 < errors[0] / errors[1] < 12


def test_reactions_equal_the_resultants_at_every_step():
    mdl = el_body.ElasticModel(100.0, (1.0, 0.5, 0.2), (10.0, 20.0, 15.0, 1.0, 0, 0), 2.0, 1.0, G0,
                          el_body.Rollers((1e6, 2e6, 1e6, 1e6, 3e6), (500.0,) * 5),
                          beams=(el_body.Beam((0.5, 0.3, 0), (0, 1, 0), (1, 0, 0), 1.0, 5.0, (2e3, 4e3), modes=3),))
    r = el_sim.simulate(el.System(mdl), helix(), np.linspace(0.0, 2.0, 11))
    P, F = r["P"], r["F"]
    scale = np.abs(P).max()
    # translations: exact (their fields are constant); x1: P0 is defined by it
    assert np.abs(F[:, 1] - P[:, 1:4].sum(1)).max() < 1e-9 * scale
    assert np.abs(F[:, 2] - P[:, 4:6].sum(1)).max() < 1e-9 * scale
    # moments about O of the roller forces at the displaced contacts: exact up to the order of
    # the quadratic approximation of the rotations
    theta = np.abs(r["q"][:, 2:5]).max()
    assert np.abs(r["M"] - r["M_contacts"]).max() < 10 * theta * np.abs(r["M"]).max()
    assert theta < 1e-2


# undamped: ~10 s of DOP853 at tight tolerance (slow tier); damped stays in the default tier
@pytest.mark.parametrize("damped", [pytest.param(False, marks=pytest.mark.slow), True])
def test_jacobi_energy_on_a_uniform_circle(damped):
    """Steady frame (horizontal circle, constant speed): h = T2 - T0 + Π + V_g is constant
    without damping and falls by exactly the dissipated energy with it."""
    c = (300.0,) * 5 if damped else (0.0,) * 5
    beam = el_body.Beam((0.5, 0.3, 0), (0, 0, 1), (1, 0, 0), 1.2, 4.0, (3e3, 5e3), modes=1,
                   damping_ratio=0.05 if damped else 0.0)
    mdl = el_body.ElasticModel(80.0, (0.8, 0.4, 0.1), (10.0, 20.0, 15.0, 0, 0, 0), 2.0, 1.0, G0,
                          el_body.Rollers((2e5, 2e5, 3e5, 2e5, 2e5), c), beams=(beam,),
                          effects=el_body.Effects(damping=damped))
    system = el.System(mdl)
    drive = circle(15.0, 12.0)
    kick = np.zeros(system.N)
    kick[[0, 2, 4, 5]] = [1e-3, 2e-3, -1e-3, 5e-3]
    r = el_sim.simulate(system, drive, np.linspace(0.0, 0.2, 21), rtol=1e-9, dq0=kick)
    fs = el_sim._state_at(drive, 0.0, 0.0)
    at_rest = system.jacobi_energy(fs, system.quasi_static(fs), np.zeros(system.N))
    excess = r["h"][0] - at_rest  # the energy of the kick
    assert excess > 0.1
    balance = r["h"] + r["dissipated"]
    assert np.abs(balance - balance[0]).max() < 1e-7 * excess
    if damped:
        assert r["h"][0] - r["h"][-1] > 0.3 * excess
    else:
        assert r["dissipated"][-1] == 0.0


def test_stiff_rollers_need_no_tiny_steps():
    """k = 1e8 N/m under a 10 kg body: ω ~ 5000 rad/s, yet the implicit integrator takes few steps."""
    mdl = el_body.ElasticModel(10.0, (1.0, 0.5, 0.0), (1.0, 2.0, 1.5, 0, 0, 0), 2.0, 1.0, G0,
                          el_body.Rollers((1e8,) * 5, (1e3,) * 5))
    system = el.System(mdl)
    r = el_sim.simulate(system, helix(), np.linspace(0.0, 5.0, 11))
    fastest = modes_at(system, helix())[0].max()
    assert fastest > 4000
    assert r["nfev"] < 2000  # an explicit method would need > fastest * 5 s / 3 ≈ 7000 steps


def test_fast_assembly_equals_the_symbolic_lagrange_route():
    """Invariants + d'Alembert (runtime) vs Lagrange's equations of the generated small model."""
    from symmech.generated import trolley_elastic_lagrange as lag

    rng = np.random.default_rng(11)
    m0, com, inertia = 90.0, np.array([0.7, 0.4, -0.2]), np.array([12.0, 18.0, 15.0])
    rho_a, L, tip, b1, b3, ei = 3.0, 1.4, 1.5, 0.6, 0.3, (2e3, 5e3)
    k, c, l, ah = np.array([1e5, 2e5, 1.5e5, 3e5, 2.5e5]), np.array([50.0, 80.0, 60.0, 40.0, 70.0]), 2.0, 0.8
    beam = el_body.Beam((b1, 0, b3), (0, 1, 0), (1, 0, 0), L, rho_a, ei, "cantilever", 1, tip)
    system = el.System(el_body.ElasticModel(m0, tuple(com), (*inertia, 0, 0, 0), l, ah, G0,
                                       el_body.Rollers(tuple(k), tuple(c)), (beam,)))
    flip = np.array([1, 1, 1, 1, 1, 1, -1])  # the runtime's second plane is axis × plane = -x3
    for _ in range(5):
        q = rng.normal(size=7) * np.r_[1e-2, 1e-2, 0.05, 0.05, 0.05, 0.1, 0.1]
        qd, qdd = rng.normal(size=(2, 7))
        nu = rng.normal(size=3)
        fs = el_frame.FrameState(rng.normal(size=3) * 10, rng.normal(size=3) * 5, rng.normal(size=3), rng.normal(size=3),
                           nu / np.linalg.norm(nu))
        fast = system.evaluate(fs, flip * q, flip * qd, flip * qdd) * flip
        dv = fs.a0 - np.cross(fs.w, fs.v0)
        slow = lag.lagrange_residual(*q, *qd, *qdd, *fs.v0, *dv, *fs.w, *fs.dw, *fs.nu, m0, *com, *inertia,
                                     rho_a, L, tip, b1, b3, *ei, *k, *c, G0, l, ah)
        assert np.abs(fast - slow).max() < 1e-10 * np.abs(slow).max()
