"""Every damping path of the elastic trolley against the damping ratio it was given and the energy it dissipates.

Beams: stiffness-proportional damping D = (2ζ/ω1) K per bending plane, so the plane's modes decay with
ζ_j = ζ ω_j/ω1 (ζ at the first); rollers: dampers c_i beside the springs k_i, with c = β k the modes
decay with ζ_j = β ω_j / 2. The references are the textbook frequencies (closed forms, or the
eigenproblem of the Ritz K, M), the free decay of a damped oscillator and the energy balance
E(0) - E(t) = ∫ q̇ᵀ D q̇ dt (+ Σ c ḋ²)."""
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg
from scipy.integrate import solve_ivp

from symmech.trolley.elastic import system as el, body as el_body, frame as el_frame, simulate as el_sim

sys.path.insert(0, str(Path(__file__).parent))
from test_trolley_elastic import CANTILEVER_BETA, closed_form_roller_frequencies  # noqa: E402

AT_REST = el_frame.FrameState(np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3), np.array([0.0, 1.0, 0.0]))
# (support, length [m], ρA [kg/m], (EI1, EI2) [N m²], modes, ζ): an undamped beam first (the damping
# loop skips it and goes on), a soft whip (ω1 < 1 rad/s) and a pinned beam
BEAMS = (("cantilever", 1.0, 3.0, (5e3, 9e3), 4, 0.0),
         ("cantilever", 2.0, 0.5, (0.2, 0.35), 4, 0.01),
         ("pinned", 1.5, 4.0, (2e3, 3e3), 3, 0.04))
FIRST_ROOT = {"cantilever": CANTILEVER_BETA[0] ** 2, "pinned": np.pi ** 2}  # ω1 √(ρA L⁴/EI)


def beams_on_rigid_rollers(beams):
    """A trolley on rigid rollers carrying ``beams`` (rows of BEAMS), linear (no stiffening), no gravity."""
    parts = tuple(el_body.Beam((0.3 * i, 0, 0), (0, 0, 1), (1, 0, 0), length, rho_a, ei, support, modes,
                          damping_ratio=zeta) for i, (support, length, rho_a, ei, modes, zeta) in enumerate(beams))
    mdl = el_body.ElasticModel(100.0, (0, 0, 0), (1, 1, 1, 0, 0, 0), 2.0, 1.0, 0.0, None, parts,
                          el_body.Effects(rollers=False, stiffening=False))
    return el.System(mdl)


def plane_blocks(system, beams):
    """(indices, ζ, EI) of every beam plane."""
    names = system.inv.names
    return [([names.index(f"beam{i}_p{p}_m{k}") for k in range(1, beam[4] + 1)], beam[5], beam[3][p - 1])
            for i, beam in enumerate(beams) for p in (1, 2)]


def test_beam_damping_gives_each_plane_its_ratio_at_its_first_mode():
    system = beams_on_rigid_rollers(BEAMS)
    M, K, D = system.mass(np.zeros(system.N)), system.inv.K, system.inv.D
    expected = []
    outside = D.copy()
    for (idx, zeta, ei), beam in zip(plane_blocks(system, BEAMS), [b for b in BEAMS for _ in (1, 2)]):
        block = np.ix_(idx, idx)
        w2, phi = scipy.linalg.eigh(K[block], M[block])  # mass-normalised modes of the plane
        omega = np.sqrt(w2)
        support, length, rho_a = beam[:3]
        # Ritz frequencies bound the exact ones from above (3e-4 high with three pinned functions)
        assert 0 <= omega[0] / (FIRST_ROOT[support] * np.sqrt(ei / (rho_a * length ** 4))) - 1 < 1e-3
        modal = phi.T @ D[block] @ phi  # diag(2 ζ_j ω_j): D ∝ K is classical damping
        ratios = zeta * omega / omega[0]
        assert np.abs(modal - np.diag(2 * ratios * omega)).max() <= 1e-10 * max(2 * ratios.max() * omega.max(), 1)
        expected += list(zip(omega, ratios))
        outside[block] = 0.0
    assert not outside.any()  # no damping couples two planes or two beams
    # the state-space eigenvalues of the whole model: |λ| = ω_j, -Re λ/|λ| = ζ_j
    omega, zeta = system.linear_modes(AT_REST, np.zeros(system.N))
    ref = np.array(sorted(expected))
    assert np.allclose(omega, ref[:, 0], rtol=1e-9)
    assert np.allclose(zeta, ref[:, 1], rtol=1e-7, atol=1e-12)


def free_decay(system, q0, t_end, fs=AT_REST):
    """Integrate M q̈ + R = 0 from rest at q0 with E_d' = the damping power: dense solution of [q, q̇, E_d]."""
    n = system.N

    def rhs(t, y):
        q, qd = y[:n], y[n:2 * n]
        return np.r_[qd, system.accelerations(fs, q, qd), el_sim._dissipation(system, qd)]
    sol = solve_ivp(rhs, (0.0, t_end), np.r_[q0, np.zeros(n), 0.0], method="DOP853", rtol=1e-11,
                    atol=1e-14 * np.abs(q0).max(), dense_output=True)
    assert sol.status == 0
    return sol.sol


def mechanical_energy(system, y):
    n = system.N
    q, qd = y[:n], y[n:2 * n]
    return 0.5 * qd @ system.mass(q) @ qd + system.potential(q)


def test_beam_free_decay_follows_the_damped_oscillator_and_dissipates_its_energy():
    """Released from rest in its first mode, the pinned beam's modal coordinate is
    a e^(-ζωt) (cos ω_d t + ζ/√(1-ζ²) sin ω_d t); the energy lost is the integral of q̇ᵀ D q̇."""
    beam = BEAMS[2]
    system = beams_on_rigid_rollers((beam,))
    M, K = system.mass(np.zeros(system.N)), system.inv.K
    w2, phi = scipy.linalg.eigh(K, M)
    omega, mode = np.sqrt(w2[0]), phi[:, 0]
    zeta = beam[5]
    amplitude = 1e-3
    t = np.linspace(0.0, 5 * 2 * np.pi / omega, 201)
    y = free_decay(system, amplitude * mode, t[-1])(t)
    eta = mode @ M @ y[:system.N]  # the modal coordinate (mass-normalised mode)
    wd = omega * np.sqrt(1 - zeta ** 2)
    decay = amplitude * np.exp(-zeta * omega * t)
    exact = decay * (np.cos(wd * t) + zeta / np.sqrt(1 - zeta ** 2) * np.sin(wd * t))
    assert np.abs(eta - exact).max() < 1e-7 * amplitude
    energy = np.array([mechanical_energy(system, yi) for yi in y.T])
    # E(t) = ½ (η̇² + ω² η²) of the mode, η̇ = -a ω/√(1-ζ²) e^(-ζωt) sin ω_d t
    rate = -decay * omega / np.sqrt(1 - zeta ** 2) * np.sin(wd * t)
    assert np.allclose(energy, 0.5 * (rate ** 2 + omega ** 2 * exact ** 2), rtol=1e-6, atol=1e-8 * energy[0])
    assert np.abs(energy[0] - energy - y[-1]).max() < 1e-8 * energy[0]
    assert y[-1, -1] > 0.9 * energy[0]  # five periods at ζ = 0.04 take 92 % of it


# ---------------------------------------------------------------- rollers

K_ROLL = (1e6, 1e6, 2e6, 1.5e6, 1e6)
BETA = 2e-4  # c = β k [s]
BODY = dict(mass=100.0, com=(0.8, 0.5, 0.0), inertia=(20.0, 30.0, 25.0, 0, 0, 0))


def roller_system(law="linear", preload=(0.0,) * 5, damping=True):
    rollers = el_body.Rollers(K_ROLL, tuple(BETA * k for k in K_ROLL), law, preload)
    return el.System(el_body.ElasticModel(BODY["mass"], BODY["com"], BODY["inertia"], 2.0, 1.0, 0.0, rollers,
                                      effects=el_body.Effects(damping=damping)))


def test_roller_dampers_give_the_modes_their_ratios():
    vertical, lateral = closed_form_roller_frequencies(BODY["mass"], BODY["com"], BODY["inertia"][:3], K_ROLL,
                                                       2.0, 1.0, 0.0)
    omega_ref = np.sort(np.r_[vertical, lateral])
    omega, zeta = roller_system().linear_modes(AT_REST, np.zeros(5))
    assert np.allclose(omega, omega_ref, rtol=1e-10)
    assert np.allclose(zeta, BETA * omega_ref / 2, rtol=1e-8)
    assert 0.01 < zeta.min() and zeta.max() < 0.1
    # a preloaded clamped pair: both rollers push, twice the springs and twice the dampers
    pair = roller_system("clamped_pair", (1e-3,) * 5)
    omega2, zeta2 = pair.linear_modes(AT_REST, np.zeros(5))
    assert np.allclose(omega2, np.sqrt(2) * omega_ref, rtol=1e-10)
    assert np.allclose(zeta2, BETA * omega2 / 2 / 2, rtol=1e-8)  # the damper acts once: c/(2k) per spring pair
    # damping off: the same frequencies, no decay
    omega0, zeta0 = roller_system(damping=False).linear_modes(AT_REST, np.zeros(5))
    assert np.allclose(omega0, omega_ref, rtol=1e-10) and np.abs(zeta0).max() < 1e-12


def test_roller_damping_force():
    d, dd = np.array([1e-4, -2e-4, 3e-4, 0.0, -5e-5]), np.array([0.1, -0.2, 0.05, 0.3, -0.1])
    c = BETA * np.array(K_ROLL)
    for law, preload, spring in (("linear", (0.0,) * 5, -np.array(K_ROLL) * d),
                                 ("clamped_pair", (1e-3,) * 5, -2 * np.array(K_ROLL) * d)):
        rollers = el_body.Rollers(K_ROLL, tuple(c), law, preload)
        force, kt = el_body.roller_forces(rollers, d, dd, True)
        assert np.allclose(force, spring - c * dd, rtol=1e-14, atol=0)
        undamped, kt0 = el_body.roller_forces(rollers, d, dd, False)
        assert np.allclose(undamped, spring, rtol=1e-14, atol=0)
        assert np.array_equal(kt, kt0)


def test_roller_free_decay_dissipates_what_the_dampers_absorb():
    """A kicked body on damped rollers: the mechanical energy falls by the integral of Σ c ḋ²,
    and most of it is gone after 0.3 s (ζ 0.013 to 0.037 at 135 to 372 rad/s)."""
    system = roller_system()
    q0 = np.array([4e-4, -3e-4, 2e-4, 1e-4, -2e-4])
    y = free_decay(system, q0, 0.3)(np.linspace(0.0, 0.3, 61))
    energy = np.array([mechanical_energy(system, yi) for yi in y.T])
    assert np.abs(energy[0] - energy - y[-1]).max() < 1e-8 * energy[0]
    assert y[-1, -1] > 0.9 * energy[0]


def test_free_lateral_slide_has_zero_frequencies_and_real_decay_rates():
    """No lateral springs (k4 = k5 = 0), lateral dampers only, centre of mass on the rail plane, B and C
    alike (roll decoupled): u3 and θ2 keep any offset (λ = 0: ω = 0, ζ = 0) and their rates decay at the
    real rates eig(M⁻¹ D) (ζ = 1, overdamped); the roll I θ1'' + a²(c1 + c2) θ1' + a²(k1 + k2) θ1 = 0 is
    a closed form."""
    k, c = (1e6, 1e6, 2e6, 0.0, 0.0), (200.0, 200.0, 400.0, 300.0, 500.0)  # B, C alike: roll apart from bounce
    m, com, inertia, l, a = 100.0, np.array([0.8, 0.0, 0.0]), (20.0, 30.0, 25.0), 2.0, 1.0
    system = el.System(el_body.ElasticModel(m, tuple(com), (*inertia, 0, 0, 0), l, a, 0.0, el_body.Rollers(k, c)))
    omega, zeta = system.linear_modes(AT_REST, np.zeros(5))
    assert len(omega) == 7  # 2 zeros, 2 real decay rates, roll, bounce and pitch
    assert np.array_equal(omega[:2], [0.0, 0.0]) and np.array_equal(zeta[:2], [0.0, 0.0])
    i_o = np.diag(inertia) + m * (com @ com * np.eye(3) - np.outer(com, com))  # about O
    mass = np.array([[m, -m * com[0]], [-m * com[0], i_o[1, 1]]])  # (u3, θ2)
    damping = np.array([[c[3] + c[4], -c[4] * l], [-c[4] * l, c[4] * l * l]])
    rates = np.sort(np.linalg.eigvals(np.linalg.solve(mass, damping)).real)
    overdamped = np.isclose(zeta, 1.0, rtol=0, atol=1e-12)
    assert np.allclose(omega[overdamped], rates, rtol=1e-9)
    w_roll = np.sqrt(a * a * (k[0] + k[1]) / i_o[0, 0])
    z_roll = a * a * (c[0] + c[1]) / (2 * i_o[0, 0] * w_roll)
    roll = np.flatnonzero(np.isclose(omega, w_roll, rtol=1e-9))
    assert len(roll) == 1 and zeta[roll[0]] == pytest.approx(z_roll, rel=1e-8)
