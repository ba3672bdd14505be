"""Energies, resultants and track power of the elastic trolley against sums over an explicit point cloud.

The body (a trolley on rollers with products of inertia, a cantilever with a tip mass) is written out as
weighted points: the rigid trolley's six-point cloud (its mass, centre and inertia: tests/test_elastic_invariants.py)
and the beam's Gauss points and tip. Each point moves to r̃ = r + φᵀ q + ½ qᵀ H q with φ, H from their
definitions (small rotations e_a × r, bending N_k(ξ) b, shortening -1/L ∫0^ξ N_k' N_l' dξ e); its
velocity and acceleration in the fixed frame are v0 + ω × r̃ + u̇ and a0 + ω̇ × r̃ + ω × (ω × r̃) + 2 ω × u̇ + ü.
The references are then the sums ½ Σ m |v|², Σ m (a - g), Σ m r̃ × (a - g), in the frame's components."""
import numpy as np
import pytest

from symmech.generated import trolley_elastic as gen
from symmech.trolley.elastic import system as el, body as el_body, frame as el_frame

pytestmark = pytest.mark.xdist_group("test_elastic_energies")

G0 = 9.81
L_AXLE, HALF_GAUGE = 2.0, 1.0
K_ROLL = np.array([1e6, 2e6, 1.5e6, 3e6, 2.5e6])
BEAM = el_body.Beam((0.5, 0.3, 0.2), (0.0, 1.0, 0.0), (1.0, 0.0, 0.0), 1.3, 4.0, (2e3, 5e3), "cantilever", 3,
               tip_mass=0.4)
E_AXIS, PLANES = np.array([0.0, 1.0, 0.0]), (np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, -1.0]))
RNG = np.random.default_rng(23)


def model(rollers=True, damping=(0.0,) * 5, beams=(BEAM,)):
    return el_body.ElasticModel(80.0, (0.4, 0.2, -0.1), (10.0, 20.0, 15.0, 1.0, -2.0, 0.5), L_AXLE, HALF_GAUGE, G0,
                           el_body.Rollers(tuple(K_ROLL), damping) if rollers else None, beams,
                           el_body.Effects(rollers=rollers, damping=any(damping)))


@pytest.fixture(scope="module")
def system():
    return el.System(model())


def cloud(mdl):
    """Points (P, 3), masses (P,), φ (P, N, 3) and H (P, N, N, 3) of the body (rollers first, then the beam)."""
    pts, w = el_body.rigid_cloud(mdl.mass, mdl.com, mdl.inertia)
    x, wx = np.polynomial.legendre.leggauss(30)
    xi = np.r_[(x + 1) / 2, 1.0]
    n = BEAM.modes
    pts = np.vstack([pts, np.asarray(BEAM.root) + np.outer(xi * BEAM.length, E_AXIS)])
    w = np.r_[w, BEAM.rho_a * BEAM.length * wx / 2, BEAM.tip_mass]
    nr = 5 if mdl.rollers is not None else 0
    N = nr + 2 * n
    phi, H = np.zeros((len(pts), N, 3)), np.zeros((len(pts), N, N, 3))
    if nr:
        rigid = np.moveaxis(gen.rigid_fields(*pts.T), -1, 1)  # (P, 11, 3)
        phi[:, :5] = rigid[:, :5]
        for col, (i, j) in enumerate(el_body.ROTATION_PAIRS):
            H[:, i, j] = H[:, j, i] = rigid[:, 5 + col]
    on_beam = np.arange(len(pts)) >= 6
    basis = gen.cantilever_basis(xi)[:, :, :n]
    for plane, b in enumerate(PLANES):
        c = nr + plane * n
        phi[on_beam, c:c + n] = basis[:, 0, :, None] * b
        for p, s in enumerate(xi):  # shortening: -1/L ∫0^s N_k' N_l' dξ along the axis
            y, wy = np.polynomial.legendre.leggauss(20)
            y, wy = s * (y + 1) / 2, wy * s / 2
            d1 = gen.cantilever_basis(y)[:, 1, :n]
            H[6 + p, c:c + n, c:c + n] = -np.einsum("p,pk,pl->kl", wy, d1, d1)[..., None] / BEAM.length * E_AXIS
    if nr:
        for a in range(3):  # a small rotation carries the beam's deflection: e_a × φ
            for c in range(nr, N):
                H[:, 2 + a, c] = H[:, c, 2 + a] = np.cross(np.eye(3)[a], phi[:, c])
    return pts, w, phi, H


def kinematics(body, q, qd, qdd):
    """r̃, u̇, ü (P, 3) of the cloud at the state."""
    pts, _, phi, H = body
    tangent = phi + np.einsum("pabi,b->pai", H, q)
    r = pts + np.einsum("pai,a->pi", phi, q) + 0.5 * np.einsum("pabi,a,b->pi", H, q, q)
    return r, np.einsum("pai,a->pi", tangent, qd), np.einsum("pai,a->pi", tangent, qdd) + \
        np.einsum("pabi,a,b->pi", H, qd, qd)


def random_state(N, scale=1.0):
    q = RNG.normal(size=N) * np.r_[1e-2, 1e-2, 0.05, 0.05, 0.05, np.full(N - 5, 0.1)] * scale
    qd, qdd = RNG.normal(size=(2, N))
    nu = RNG.normal(size=3)
    fs = el_frame.FrameState(RNG.normal(size=3) * 10, RNG.normal(size=3) * 5, RNG.normal(size=3), RNG.normal(size=3),
                       nu / np.linalg.norm(nu))
    return fs, q, qd, qdd


def bending_energy(q):
    x, w = np.polynomial.legendre.leggauss(30)
    d2 = gen.cantilever_basis((x + 1) / 2)[:, 2, :BEAM.modes]
    k = np.einsum("p,pk,pl->kl", w / 2, d2, d2) / BEAM.length ** 3
    n = BEAM.modes
    planes = [q[5 + i * n:5 + (i + 1) * n] for i in range(2)]
    return sum(0.5 * ei * x @ k @ x for x, ei in zip(planes, BEAM.ei))


def test_potential_is_the_bending_and_the_roller_springs(system):
    fs, q, _, _ = random_state(system.N)
    d = gen.roller_matrix(L_AXLE, HALF_GAUGE) @ q[:5]
    expected = bending_energy(q) + 0.5 * K_ROLL @ (d * d)
    assert system.potential(q) == pytest.approx(expected, rel=1e-12)
    batch = np.array([q, 2 * q])  # quadratic: four times the energy at twice the coordinates
    assert np.allclose(system.potential(batch), [expected, 4 * expected], rtol=1e-12)


def test_clamped_pair_energy_in_closed_form():
    """½ k [(δ - d)₊² + (δ + d)₊² - 2 δ₊²]: inside the preload 2k springs (k d²); beyond it one roller; a gap δ < 0
    stores nothing until it closes."""
    k = 2e6
    pair = el_body.Rollers((k,) * 5, (0.0,) * 5, "clamped_pair", (1e-3, 1e-3, 1e-3, -1e-3, -1e-3))
    d = np.array([5e-4, -3e-3, 0.0, 5e-4, 3e-3])
    parts = [k * 5e-4 ** 2, 0.5 * k * ((1e-3 + 3e-3) ** 2 - 2e-6), 0.0, 0.0, 0.5 * k * (3e-3 - 1e-3) ** 2]
    assert el_body.roller_energy(pair, d) == pytest.approx(sum(parts), rel=1e-12)
    assert el_body.roller_energy(pair, np.zeros((2, 5))) == pytest.approx([0.0, 0.0], abs=1e-18)
    linear = el_body.Rollers((k,) * 5, (0.0,) * 5, "linear", (1e-3,) * 5)  # the linear law ignores a preload
    assert el_body.roller_energy(linear, d) == pytest.approx(0.5 * k * d @ d, rel=1e-12)


def test_energies_are_the_sums_over_the_points(system):
    """T, T2, T0 of the cloud; h = T2 - T0 + Π + g0 ν·∫ r̃ dm, E = T + Π + g0 (m y_O + ν·∫ r̃ dm)."""
    body = cloud(system.mdl)
    w = body[1]
    for _ in range(3):
        fs, q, qd, _ = random_state(system.N)
        r, ud, _ = kinematics(body, q, qd, 0 * q)
        carried = fs.v0 + np.cross(fs.w, r)
        t2, t0, t = (0.5 * np.einsum("p,pi,pi->", w, x, x) for x in (ud, carried, carried + ud))
        pi = system.potential(q)
        gravity = G0 * fs.nu @ (w @ r)
        assert system.jacobi_energy(fs, q, qd) == pytest.approx(t2 - t0 + pi + gravity, rel=1e-12, abs=1e-12 * t)
        height = 3.7
        total = t + pi + G0 * (w.sum() * height + fs.nu @ (w @ r))
        assert system.total_energy(fs, q, qd, height) == pytest.approx(total, rel=1e-12)


def resultants_of_cloud(body, fs, q, qd, qdd):
    w = body[1]
    r, ud, udd = kinematics(body, q, qd, qdd)
    a = fs.a0 + np.cross(fs.dw, r) + np.cross(fs.w, np.cross(fs.w, r)) + 2 * np.cross(fs.w, ud) + udd
    f = w[:, None] * (a + G0 * fs.nu)  # a - g, g = -g0 ν
    return f.sum(0), np.cross(r, f).sum(0)


@pytest.mark.parametrize("rollers", [True, False])
def test_resultants_reactions_and_track_power(rollers):
    system = el.System(model(rollers=rollers))
    body = cloud(system.mdl)
    for _ in range(3):
        fs, q, qd, qdd = random_state(system.N)
        F, M = resultants_of_cloud(body, fs, q, qd, qdd)
        got_F, got_M = system.resultants(fs, q, qd, qdd)
        assert np.abs(got_F - F).max() < 1e-11 * np.abs(F).max()
        assert np.abs(got_M - M).max() < 1e-11 * np.abs(M).max()
        assert system.track_power(fs, q, qd, qdd) == pytest.approx(F @ fs.v0 + M @ fs.w, rel=1e-11)
        P = system.reactions(fs, q, qd, qdd)
        if rollers:  # P0 closes the x1 balance, P1…P5 the springs -k d
            d = gen.roller_matrix(L_AXLE, HALF_GAUGE) @ q[:5]
            assert np.allclose(P, np.r_[F[0], -K_ROLL * d], rtol=1e-12, atol=1e-9)
        else:  # rigid rollers: P0…P5 at the contacts carry F and M (B, C along x2 at x3 = ∓ah, A at x1 = l)
            contacts = np.array([(0, 0, 0), (0, 0, -HALF_GAUGE), (0, 0, HALF_GAUGE), (L_AXLE, 0, 0), (0, 0, 0),
                                 (L_AXLE, 0, 0)], float)
            dirs = np.eye(3)[[0, 1, 1, 1, 2, 2]]
            forces = P[:, None] * dirs
            assert np.abs(forces.sum(0) - F).max() < 1e-10 * np.abs(F).max()
            assert np.abs(np.cross(contacts, forces).sum(0) - M).max() < 1e-10 * np.abs(M).max()


def test_contact_moment_of_the_roller_forces_at_the_displaced_contacts(system):
    contacts = np.array([(0, 0, -HALF_GAUGE), (0, 0, HALF_GAUGE), (L_AXLE, 0, 0), (0, 0, 0), (L_AXLE, 0, 0)], float)
    dirs = np.eye(3)[[1, 1, 1, 2, 2]]
    rigid = np.moveaxis(gen.rigid_fields(*contacts.T), -1, 1)
    qs = np.array([random_state(system.N)[1] for _ in range(2)])
    forces = RNG.normal(size=(2, 5)) * 1e3
    got = system.contact_moment(qs, forces)
    for q, P, m in zip(qs, forces, got):
        u = np.einsum("pai,a->pi", rigid[:, :5], q[:5])
        for col, (i, j) in enumerate(el_body.ROTATION_PAIRS):
            u += (0.5 if i == j else 1.0) * q[i] * q[j] * rigid[:, 5 + col]
        expected = np.cross(contacts + u, P[:, None] * dirs).sum(0)
        assert np.abs(m - expected).max() < 1e-12 * np.abs(expected).max()
