"""Elastic trolley: held-end membrane stretching (Duffing backbone) and the clamped roller pair."""
import copy
import sys
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg
from numpy.polynomial import Legendre
from scipy.integrate import solve_ivp
from scipy.special import ellipk

from symmech.core.scene import SceneError
from symmech.generated import trolley_elastic as gen
from symmech.trolley.elastic import system as el, body as el_body, frame as el_frame, simulate as el_sim
from symmech.trolley.elastic import scene as elastic_scene, membrane

sys.path.insert(0, str(Path(__file__).parent))
from trolley_util import prepared, setup as scene_dict  # noqa: E402

RNG = np.random.default_rng(23)
AT_REST = el_frame.FrameState(np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3), np.array([0.0, 1.0, 0.0]))
# steel strip 20 mm x 10 mm, 2 m between immovable pins: r = sqrt(I/A) = h/sqrt(12)
L, RHO, E, WIDTH, HEIGHT = 2.0, 7800.0, 2.1e11, 0.02, 0.01
AREA, INERTIA = WIDTH * HEIGHT, WIDTH * HEIGHT ** 3 / 12
GYRATION = np.sqrt(INERTIA / AREA)


def pinned_slopes(modes):
    """N_k'(ξ) of ξ(1 - ξ) P_(k-1)(2ξ - 1), built with numpy's Legendre series on [0, 1] (not the generated
    basis; kept in the Legendre basis, which is well conditioned: ξ(1 - ξ) = (P_0 - P_2)(2ξ - 1) / 6)."""
    bubble = Legendre([1 / 6, 0.0, -1 / 6], domain=[0, 1])
    return [(bubble * Legendre.basis(k, domain=[0, 1])).deriv() for k in range(modes)]


def gauss(a, b, n=24):
    x, w = np.polynomial.legendre.leggauss(n)
    return a + (b - a) * (x + 1) / 2, w * (b - a) / 2


def held_beam(modes=5, axial="held", stiffening=True, mem=True, ei=(E * INERTIA, E * INERTIA)):
    beam = el_body.Beam((0, 0, 0), (0, 0, 1), (1, 0, 0), L, RHO * AREA, ei, "pinned", modes, axial=axial, ea=E * AREA)
    mdl = el_body.ElasticModel(100.0, (0, 0, 0), (1, 1, 1, 0, 0, 0), 2.0, 1.0, 0.0, None, (beam,),
                          el_body.Effects(rollers=False, stiffening=stiffening, membrane=mem))
    return el.System(mdl, [(0, 0.5)])


# ---------------------------------------------------------------- generated fields and the quartic energy

def test_generated_slope_gram_and_held_field_vs_quadrature():
    """At random ξ and next to the pins (ξ = 1e-9, 1 - 1e-9, 0.999, 0, 1), to 1e-12 absolute (entries up to
    0.11; measured 4e-13 at ξ = 0.999, where the reference is exact to 3e-16): the Ritz polynomials are
    emitted in u = 2ξ - 1; expanded in ξ they lost 1.2e-7 there."""
    slopes = pinned_slopes(8)
    x, w = gauss(0.0, 1.0)
    d = np.array([s(x) for s in slopes])
    H = np.einsum("p,kp,lp->kl", w, d, d)
    assert np.abs(gen.pinned_slope_gram() - H).max() < 1e-12
    for xi in [*RNG.uniform(0, 1, 5), 1e-9, 1 - 1e-9, 0.999, 0.0, 1.0]:
        x, w = gauss(0.0, xi)
        d = np.array([s(x) for s in slopes])
        held = xi * H - np.einsum("p,kp,lp->kl", w, d, d)
        assert np.abs(gen.pinned_held_axial(xi) - held).max() < 1e-12
        assert np.abs(gen.pinned_shortening(xi) - (xi * H - held)).max() < 1e-12
    # the held field vanishes at both pins: the supports do not move
    assert np.abs(gen.pinned_held_axial(np.array([0.0, 1.0]))).max() < 1e-12


def independent_membrane_energy(q, modes):
    """½ EA L ε̄², ε̄ = (1/2L) ∫ (w1'² + w2'²) dx by quadrature in x [m]."""
    x, w = gauss(0.0, 1.0)
    d = np.array([s(x) for s in pinned_slopes(modes)]) / L  # dN/dx
    slope2 = (q[:modes] @ d) ** 2 + (q[modes:] @ d) ** 2
    strain = (w * slope2).sum() * L / (2 * L)
    return 0.5 * E * AREA * L * strain ** 2


def test_membrane_energy_force_and_stiffness_vs_quadrature():
    modes = 5
    system = held_beam(modes)
    blocks = system.inv.membrane
    assert len(blocks) == 1 and np.array_equal(blocks[0].index, np.arange(2 * modes))
    assert system.inv.names[modes - 1:modes + 1] == [f"beam0_p1_m{modes}", "beam0_p2_m1"]  # one beam, two planes
    zero = np.zeros(system.N)
    h = 1e-7
    for _ in range(4):
        q = RNG.normal(size=2 * modes) * 0.01
        U = independent_membrane_energy(q, modes)
        assert membrane.energy(blocks, q) == pytest.approx(U, rel=1e-12)
        eye = np.eye(2 * modes) * h
        grad = np.array([(independent_membrane_energy(q + e, modes) - independent_membrane_energy(q - e, modes))
                         / (2 * h) for e in eye])
        scale = np.abs(grad).max()
        assert np.abs(membrane.force(blocks, q) - grad).max() < 1e-6 * scale
        # the residual at rest: bending K q plus the membrane force; its Jacobian: K plus the tangent
        R, _, Rq, _ = system.evaluate(AT_REST, q, zero, zero, jacobian=True)
        assert np.abs(R - system.inv.K @ q - grad).max() < 1e-6 * np.abs(R).max()
        fd = np.array([(system.evaluate(AT_REST, q + e, zero, zero) - system.evaluate(AT_REST, q - e, zero, zero))
                       / (2 * h) for e in eye]).T
        assert np.abs(Rq - fd).max() < 1e-6 * np.abs(Rq).max()
    # membrane off or free ends: no quartic term
    assert held_beam(modes, mem=False).inv.membrane == ()
    assert held_beam(modes, axial="free").inv.membrane == ()


# ---------------------------------------------------------------- backbone curve

def free_vibration_frequency(system, amplitude, periods=1.5):
    """ω [rad/s] of the undamped free vibration started at rest in the first linear mode with
    mid-span deflection ``amplitude`` [m]: the time between down-crossings of the modal
    coordinate (dense output, DOP853); also ω0 [rad/s] of the linear mode."""
    n = system.N
    zero = np.zeros(n)
    _, M, K, _ = system.evaluate(AT_REST, zero, zero, zero, jacobian=True)
    w2, V = scipy.linalg.eigh(K, M)
    mode = V[:, 0] / (V[:, 0] @ system.inv.probe_fields[1:1 + n, 0, 0])  # unit mid-span deflection
    omega0 = np.sqrt(w2[0])

    def crossing(t, y):
        return mode @ M @ y[:n]
    crossing.direction = -1
    sol = solve_ivp(lambda t, y: np.r_[y[n:], system.accelerations(AT_REST, y[:n], y[n:])],
                    (0, periods * 2 * np.pi / omega0), np.r_[amplitude * mode, zero], method="DOP853",
                    rtol=1e-10, atol=1e-14 * amplitude, events=crossing)
    down = sol.t_events[0]
    assert len(down) == 2
    return 2 * np.pi / (down[1] - down[0]), omega0


def duffing_exact(eps):
    """ω/ω0 of ẍ + ω0² x (1 + ε (x/a)²) = 0 from rest at x = a: π √(1+ε) / (2 K(m)), m = ε / (2(1+ε))."""
    return np.pi * np.sqrt(1 + eps) / (2 * ellipk(eps / (2 * (1 + eps))))


@pytest.mark.slow  # a long free vibration per amplitude
def test_held_pinned_beam_follows_the_duffing_backbone():
    """w = a(t) sin(πx/L) is exact for held ends (the axial force is uniform): with
    Π = EI π⁴ a²/(4L³) + EA π⁴ a⁴/(32L³) and T = ρAL ȧ²/4, ä + ω0² a (1 + ε (a/â)²) = 0 with
    ε = (â/r)²/4 at the amplitude â; first-order harmonic balance: ω/ω0 = sqrt(1 + (3/16)(â/r)²)."""
    omega_ref = np.pi ** 2 * np.sqrt(E * INERTIA / (RHO * AREA * L ** 4))
    held = held_beam(5)
    for ratio in (0.5, 1.0, 2.0):
        omega, omega0 = free_vibration_frequency(held, ratio * GYRATION)
        assert omega0 == pytest.approx(omega_ref, rel=1e-6)
        # exact period of the single-mode Duffing oscillator; residue: 5 Ritz functions vs sin (1e-5 at â = 2r)
        assert omega / omega0 == pytest.approx(duffing_exact(ratio ** 2 / 4), rel=3e-5)
        # first-order harmonic balance overestimates by 4e-5, 5e-4, 3.9e-3 at â/r = 0.5, 1, 2
        assert omega / omega0 == pytest.approx(np.sqrt(1 + 3 / 16 * ratio ** 2), rel=5e-3)
    assert omega / omega0 > 1.3
    # free far end: no stretching, the frequency hardly depends on the amplitude. What is left is the
    # axial inertia of the shortening u1 = -(π²â²/2L)(ξ/2 + sin 2πξ/4π) cos²: T gains γ a² ȧ², harmonic
    # balance gives ω²/ω0² = 1/(1 + π⁴ J (â/L)²), J = ∫ (ξ/2 + sin 2πξ/4π)² dξ = 1/12 - 3/(32π²)
    # (-3.0e-5 here)
    amplitude = 2 * GYRATION
    omega_free, omega0_free = free_vibration_frequency(held_beam(5, axial="free"), amplitude)
    assert omega0_free == pytest.approx(omega0, rel=1e-12)
    J = 1 / 12 - 3 / (32 * np.pi ** 2)
    assert omega_free / omega0_free == pytest.approx(1 / np.sqrt(1 + np.pi ** 4 * J * (amplitude / L) ** 2), rel=1e-6)
    assert omega_free / omega0_free == pytest.approx(1.0, abs=1e-4)


def test_membrane_energy_is_conserved_along_the_track():
    """Held beam on elastic rollers, uniform horizontal circle, no damping: the Jacobi energy
    h = T2 - T0 + Π + V_g (Π with the quartic membrane term) is constant."""
    data = scene_dict(frame="frenet", track={"type": "expression", "x": "15*sin(s/15)", "y": "0", "z": "15*cos(s/15)"},
                      motion={"speed": "12.0"}, time={"t_end": 1.0, "steps": 10})
    drive = elastic_scene.drive_of(prepared(data), 1)
    beam = el_body.Beam((0.5, 0.3, 0), (0, 0, 1), (1, 0, 0), 1.2, 4.0, (3e3, 5e3), "pinned", 3, axial="held", ea=2e7)
    mdl = el_body.ElasticModel(80.0, (0.8, 0.4, 0.1), (10.0, 20.0, 15.0, 0, 0, 0), 2.0, 1.0, 9.81,
                          el_body.Rollers((2e5, 2e5, 3e5, 2e5, 2e5), (0.0,) * 5), beams=(beam,))
    system = el.System(mdl)
    kick = np.zeros(system.N)
    kick[[0, 2, 5, 8]] = [1e-3, 2e-3, 0.2, -0.1]  # 5 cm at mid-span: Π_m > Π_bending
    # explicit: Radau's Newton iterations cost ~15x more on this strongly nonlinear, non-stiff case
    r = el_sim.simulate(system, drive, np.linspace(0.0, 0.05, 6), method="DOP853", rtol=1e-10, dq0=kick)
    q = r["q"][0]
    Pi_m = membrane.energy(system.inv.membrane, q)
    assert Pi_m > 2 * 0.5 * q @ system.inv.K @ q
    assert np.abs(r["h"] - r["h"][0]).max() < 1e-8 * Pi_m


# ---------------------------------------------------------------- scene fields

HELD = {"root": [0.5, 0.5, 0.0], "axis": [0, 1, 0], "plane": [1, 0, 0], "length": 1.5, "mass_per_length": 4.0,
        "ei": [2e4, 3e4], "support": "pinned", "axial": "held", "ea": 1e7}


def prepare_beam(beam, effects=None):
    st = prepared(scene_dict())
    elastic = {"effects": {"rollers": False, **(effects or {})}, "beams": [beam]}
    resolved = elastic_scene.SCHEMA.check("elastic", copy.deepcopy(elastic))
    return elastic_scene.prepare(resolved, st.body, elastic_scene.drive_of(st, 1), st.t)


def test_held_ends_from_the_scene():
    blocks = prepare_beam(HELD).system.inv.membrane
    assert len(blocks) == 1 and blocks[0].c == pytest.approx(1e7 / (8 * 1.5 ** 3), rel=1e-15)
    assert prepare_beam(HELD, {"membrane": False}).system.inv.membrane == ()


@pytest.mark.parametrize("change, field", [({"support": "cantilever"}, "elastic.beams[0].axial"),
                                           ({"ea": None}, "elastic.beams[0].ea")])
def test_held_ends_need_two_pins_and_ea(change, field):
    beam = {k: v for k, v in {**HELD, **change}.items() if v is not None}
    with pytest.raises(SceneError) as err:
        prepare_beam(beam)
    assert str(err.value).startswith(f"scene field '{field}'")


# ---------------------------------------------------------------- clamped roller pair

@pytest.mark.parametrize("mass", [500.0, 600.0, 1000.0])
def test_clamped_pairs_carry_the_weight_and_open_a_gap(mass):
    """Three vertical clamped pairs (B, C, A) under the weight on a straight level track. The loads
    are statically determinate: P1 = P2 = 0.3 W, P3 = 0.4 W (centre of mass at x1 = 0.8 of l = 2).
    Pair law: P = -2k d inside the preload δ, P = k (δ - d) once the upper roller lifts off
    (W > 2kδ), leaving a gap -d - δ = W/k - 2δ between it and the rail."""
    k, delta, g0 = 1e6, 1e-3, 9.81
    mdl = el_body.ElasticModel(mass, (0.8, 0.0, 0.0), (20.0, 30.0, 25.0, 0, 0, 0), 2.0, 1.0, g0,
                          el_body.Rollers((k,) * 5, (0.0,) * 5, "clamped_pair", (delta,) * 5),
                          effects=el_body.Effects(damping=False))
    system = el.System(mdl)
    fs = el_sim._state_at(elastic_scene.drive_of(prepared(scene_dict(motion={"speed": "0.0"})), 1), 0.0, 0.0)
    q = system.quasi_static(fs)
    d = system.roller_state(q, 0 * q)[0]
    loads = mass * g0 * np.array([0.3, 0.3, 0.4])
    expected = np.where(loads < 2 * k * delta, -loads / (2 * k), delta - loads / k)
    assert np.allclose(d[:3], expected, rtol=1e-6, atol=1e-12)
    assert np.abs(d[3:]).max() < 1e-12
    gap = np.maximum(-d[:3] - delta, 0.0)
    assert np.allclose(gap, np.maximum(loads / k - 2 * delta, 0.0), rtol=1e-6, atol=1e-12)
    assert (gap > 0).sum() == {500.0: 0, 600.0: 1, 1000.0: 3}[mass]


def test_scene_field_docs_match_the_schema():
    from symmech.core.schema import markdown

    docs = (Path(__file__).parent.parent / "docs" / "scenes-trolley-elastic.md").read_text(encoding="utf-8")
    assert markdown(elastic_scene.SCHEMA, "elastic") in docs
