"""The inertia invariants (9) of the elastic trolley against integrals written out independently.

The body: a trolley with products of inertia on elastic rollers, a cantilever with a tip mass whose axis
is given unnormalised and whose bending direction leans along it, and a pinned beam with held ends on a
slanted axis. References: the rigid trolley's mass, centre and inertia; the rod integrals ∫ r dm,
∫ r rᵀ dm in closed form; the mass matrix ∫ φ_a·φ_b dm and the bending stiffness EI/L³ ∫ N_k'' N_l'' dξ
by a Gauss rule of another order; the second-order fields from their definitions (shortening
-1/L ∫0^ξ N_k' N_l' dξ e, held ends: the stretch spread evenly, the small rotations e_a × φ)."""
import numpy as np
import pytest

from symmech.core.scene import SymmechError
from symmech.generated import trolley_elastic as gen
from symmech.trolley.elastic import system as el, body as el_body

pytestmark = pytest.mark.xdist_group("test_elastic_invariants")

MASS, COM, INERTIA = 80.0, (0.4, 0.2, -0.1), (10.0, 20.0, 15.0, 1.0, -2.0, 0.5)
# the cantilever's axis 2 x2 (unnormalised) and its first bending direction leaning along it: b1 = x1
CANTILEVER = el_body.Beam((0.5, 0.3, 0.2), (0.0, 2.0, 0.0), (1.0, 0.7, 0.0), 1.3, 4.0, (2e3, 5e3), "cantilever", 3,
                     tip_mass=0.4)
PINNED = el_body.Beam((0.0, 0.1, 0.5), (1.0, 1.0, 0.0), (0.0, 0.0, 3.0), 2.0, 1.5, (4e3, 3e3), "pinned", 2,
                 axial="held", ea=1e6)
# (beam, ξ) report points and (None, point) on the trolley, mixed
PROBES = ((0, 1.0), (None, (-0.3, 0.4, 0.1)), (0, 0.35), (1, 0.5), (None, (0.2, -0.1, 0.3)))
# unit axis e and bending directions b1, b2 = e × b1 of each beam, worked out by hand
FRAMES = ((np.array([0.0, 1.0, 0.0]), np.array([1.0, 0.0, 0.0]), np.array([0.0, 0.0, -1.0])),
          (np.array([1.0, 1.0, 0.0]) / np.sqrt(2), np.array([0.0, 0.0, 1.0]), np.array([1.0, -1.0, 0.0]) / np.sqrt(2)))


def model(**effects):
    return el_body.ElasticModel(MASS, COM, INERTIA, 2.0, 1.0, 9.81,
                           el_body.Rollers((1e6,) * 5, (0.0,) * 5), (CANTILEVER, PINNED), el_body.Effects(**effects))


@pytest.fixture(scope="module")
def system():
    return el.System(model(), PROBES)


def basis(beam, xi):
    """[N, N', N''] (P, 3, modes) of the beam's Ritz functions at ξ (P,)."""
    raw = gen.cantilever_basis(xi) if beam.support == "cantilever" else gen.pinned_basis(xi)
    return raw[..., :beam.modes]


def gauss(a, b, n=40):
    x, w = np.polynomial.legendre.leggauss(n)
    return a + (b - a) * (x + 1) / 2, w * (b - a) / 2


def slope_integral(beam, xi):
    """∫0^ξ N_k' N_l' dξ (modes, modes)."""
    x, w = gauss(0.0, xi)
    d1 = basis(beam, x)[:, 1]
    return np.einsum("p,pk,pl->kl", w, d1, d1)


def inertia_tensor(points, weights, centre):
    d = points - centre
    return np.einsum("p,pk,pk->", weights, d, d) * np.eye(3) - np.einsum("p,pi,pj->ij", weights, d, d)


def test_rigid_cloud_has_the_mass_centre_and_inertia():
    pts, w = el_body.rigid_cloud(MASS, COM, INERTIA)
    assert w.sum() == pytest.approx(MASS, rel=1e-15)
    assert np.allclose(w @ pts / MASS, COM, rtol=0, atol=1e-15)
    i11, i22, i33, i12, i23, i13 = INERTIA
    expected = np.array([[i11, i12, i13], [i12, i22, i23], [i13, i23, i33]])
    assert np.abs(inertia_tensor(pts, w, np.array(COM)) - expected).max() < 1e-13 * i22


def test_rigid_cloud_refuses_a_body_beyond_the_triangle_inequality_only():
    """Refused when I33 exceeds I11 + I22 by more than 1e-12 of the largest second moment (J = diag(2, 1, 0) for
    the plate (1, 2, 3) kg m²): a light body (second moments ~1e-3 kg m²) too."""
    for six in ((1.0, 1.0, 2.01, 0, 0, 0), (1e-3, 2e-3, 3e-3 + 2e-13, 0, 0, 0)):
        message = rf"trolley inertia \[{six[0]}, .*\] kg m\^2 violates the triangle inequality \(I11 \+ I22 >= I33 " \
                  r"and permutations\)$"
        with pytest.raises(SymmechError, match=message):
            el_body.rigid_cloud(1.0, (0, 0, 0), six)
    # a flat plate (I33 = I11 + I22), also 1.5e-12 kg m² beyond (rounding): all its mass in its plane
    for i33 in (3.0, 3.0 + 3e-12):
        pts, w = el_body.rigid_cloud(2.0, (0, 0, 0), (1.0, 2.0, i33, 0, 0, 0))
        assert np.abs(pts[:, 2]).max() < 1e-5
        assert inertia_tensor(pts, w, np.zeros(3))[2, 2] == pytest.approx(3.0, rel=1e-11)


def rod_moments(beam, e):
    """Mass, ∫ r dm and ∫ r rᵀ dm of a uniform rod r = root + x e, x in [0, L], and its tip mass."""
    r0, L, rho = np.asarray(beam.root, float), beam.length, beam.rho_a
    tip = r0 + L * e
    m = rho * L + beam.tip_mass
    first = rho * (L * r0 + L ** 2 / 2 * e) + beam.tip_mass * tip
    second = rho * (L * np.outer(r0, r0) + L ** 2 / 2 * (np.outer(r0, e) + np.outer(e, r0))
                    + L ** 3 / 3 * np.outer(e, e))
    return m, first, second + beam.tip_mass * np.outer(tip, tip)


def test_mass_centre_and_second_moment_of_the_whole_body(system):
    inv = system.inv
    c = np.array(COM)
    i11, i22, i33, i12, i23, i13 = INERTIA
    I = np.array([[i11, i12, i13], [i12, i22, i23], [i13, i23, i33]])
    m, first, second = MASS, MASS * c, MASS * np.outer(c, c) + np.trace(I) / 2 * np.eye(3) - I
    for beam, (e, _, _) in zip((CANTILEVER, PINNED), FRAMES):
        mb, fb, sb = rod_moments(beam, e)
        m, first, second = m + mb, first + fb, second + sb
    assert inv.mass == pytest.approx(m, rel=1e-14)  # the report points carry no mass
    assert np.allclose(inv.S1[0], first, rtol=0, atol=1e-13 * m)
    assert np.abs(inv.G[0, 0] - second).max() < 1e-13 * np.abs(second).max()


def mode_fields(beam, frame, xi):
    """φ (2 modes_count, P, 3) of the beam's coordinates, plane 1 then plane 2, at ξ (P,)."""
    n = basis(beam, xi)[:, 0]
    return np.array([np.outer(n[:, k], b) for b in frame[1:] for k in range(beam.modes)])


def test_mass_matrix_is_the_integral_of_the_field_products(system):
    """M(0)_ab = ∫ φ_a·φ_b dm: the trolley's rigid-body block about O, the beams' Ritz blocks and their coupling."""
    c = np.array(COM)
    i11, i22, i33, i12, i23, i13 = INERTIA
    I_O = np.array([[i11, i12, i13], [i12, i22, i23], [i13, i23, i33]]) + MASS * (c @ c * np.eye(3) - np.outer(c, c))
    M = np.zeros((system.N, system.N))
    # the trolley: u2, u3 along x2, x3, θ about x1…x3 (φ = e_a × r)
    cx = np.array([[0, -c[2], c[1]], [c[2], 0, -c[0]], [-c[1], c[0], 0]])  # c×
    M[:2, :2] = MASS * np.eye(2)
    M[:2, 2:5] = -MASS * cx[1:]  # ∫ e_i·(e_a × r) dm = e_i·(e_a × m c) = -m (c×)_ia
    M[2:5, :2] = M[:2, 2:5].T
    M[2:5, 2:5] = I_O
    start = 5
    for beam, frame in zip((CANTILEVER, PINNED), FRAMES):
        x, w = gauss(0.0, 1.0)
        x, w = np.r_[x, 1.0], np.r_[beam.rho_a * beam.length * w, beam.tip_mass]  # the tip mass at ξ = 1
        r = np.asarray(beam.root, float) + np.outer(x * beam.length, frame[0])
        rigid = np.array([np.broadcast_to([0, 1.0, 0], r.shape), np.broadcast_to([0, 0, 1.0], r.shape),
                          *(np.cross(a, r) for a in np.eye(3))])
        phi = mode_fields(beam, frame, x)
        idx = slice(start, start + len(phi))
        M[idx, idx] = np.einsum("p,kpi,lpi->kl", w, phi, phi)
        M[:5, idx] = np.einsum("p,kpi,lpi->kl", w, rigid, phi)
        M[idx, :5] = M[:5, idx].T
        M[:5, :5] += np.einsum("p,kpi,lpi->kl", w, rigid, rigid)
        start += len(phi)
    got = system.mass(np.zeros(system.N))
    assert np.abs(got - M).max() < 1e-12 * np.abs(M).max()


def test_bending_stiffness_of_every_plane(system):
    K = np.zeros((system.N, system.N))
    start = 5
    for beam in (CANTILEVER, PINNED):
        x, w = gauss(0.0, 1.0)
        d2 = basis(beam, x)[:, 2]
        k = np.einsum("p,pk,pl->kl", w, d2, d2) / beam.length ** 3
        for ei in beam.ei:
            K[start:start + beam.modes, start:start + beam.modes] = ei * k
            start += beam.modes
    assert np.abs(system.inv.K - K).max() < 1e-11 * np.abs(K).max()
    (held,) = system.inv.membrane  # the pinned beam's stretching: its four coordinates, EA/(8 L³)
    assert list(held.index) == list(range(11, 15))
    assert held.c == pytest.approx(1e6 / (8 * 2.0 ** 3), rel=1e-15)


def expected_probe_fields(system):
    """Every field (F, probes, 3) at the report points, from the definitions."""
    names, pairs, N = system.inv.names, system.inv.pairs, system.N
    out = np.zeros((system.F, len(PROBES), 3))
    for p, (b, where) in enumerate(PROBES):
        phi = np.zeros((N, 3))
        psi = {}
        if b is None:
            r = np.asarray(where, float)
            rigid = gen.rigid_fields(*r)
            phi[:5] = rigid[:, :5].T
            psi.update({pair: rigid[:, 5 + col] for col, pair in enumerate(el_body.ROTATION_PAIRS)})
        else:
            beam, frame = (CANTILEVER, PINNED)[b], FRAMES[b]
            r = np.asarray(beam.root, float) + where * beam.length * frame[0]
            rigid = gen.rigid_fields(*r)
            phi[:5] = rigid[:, :5].T
            psi.update({pair: rigid[:, 5 + col] for col, pair in enumerate(el_body.ROTATION_PAIRS)})
            first = names.index(f"beam{b}_p1_m1")
            n = beam.modes
            phi[first:first + 2 * n] = mode_fields(beam, frame, np.array([where]))[:, 0]
            stretch = slope_integral(beam, where)
            if beam.axial == "held":  # the far end stays: the shortening spreads evenly along the beam
                stretch = stretch - where * slope_integral(beam, 1.0)
            for plane in range(2):
                base = first + plane * n
                for k in range(n):
                    for m in range(k, n):
                        psi[(base + k, base + m)] = -stretch[k, m] / beam.length * frame[0]
            for a in range(3):
                for c in range(first, first + 2 * n):
                    psi[(2 + a, c)] = np.cross(np.eye(3)[a], phi[c])
        out[0, p] = r
        out[1:1 + N, p] = phi
        for idx, pair in enumerate(pairs):
            out[1 + N + idx, p] = psi.get(pair, np.zeros(3))
    return out


def shortening(first):
    """The pairs (k, l) of shortening fields, k <= l in one bending plane, of the beams' coordinates from ``first``."""
    return {(first + b + k, first + b + m) for b, n in ((0, 3), (3, 3), (6, 2), (8, 2))
            for k in range(n) for m in range(k, n)}


def test_fields_at_the_report_points(system):
    inv = system.inv
    assert len(inv.names) == 15 and inv.n_roll == 5
    beam_pairs = {(2 + a, c) for a in range(3) for c in range(5, 15)}
    assert set(inv.pairs) == set(el_body.ROTATION_PAIRS) | beam_pairs | shortening(5)
    expected = expected_probe_fields(system)
    assert np.abs(inv.probe_fields - expected).max() < 1e-13
    assert np.allclose(inv.probe_points, expected[0], rtol=0, atol=1e-15)
    for idx, (a, b) in enumerate(inv.pairs):
        assert inv.dA[a, b] == inv.dA[b, a] == 1 + system.N + idx


def test_effects_switch_off_their_coordinates_and_fields():
    def of(**effects):
        return el_body.invariants(model(**effects))

    full = of()
    no_rollers, rigid_beams, no_stiffening, no_membrane = (of(rollers=False), of(body=False), of(stiffening=False),
                                                          of(membrane=False))
    assert no_rollers.names == full.names[5:] and no_rollers.n_roll == 0
    assert set(no_rollers.pairs) == shortening(0)
    assert rigid_beams.names == list(el_body.ROLLER_NAMES) and rigid_beams.pairs == list(el_body.ROTATION_PAIRS)
    assert not any(i >= 5 and j >= 5 for i, j in no_stiffening.pairs)
    assert len(no_stiffening.pairs) == len(el_body.ROTATION_PAIRS) + 30
    assert no_membrane.membrane == () and len(full.membrane) == 1
    # the bodies' mass is there whatever the effects
    for inv in (no_rollers, rigid_beams, no_stiffening):
        assert inv.mass == pytest.approx(full.mass, rel=1e-15)
        assert np.allclose(inv.G[0, 0], full.G[0, 0], rtol=1e-15, atol=0)


@pytest.mark.parametrize("support, axial", [("cantilever", "free"), ("pinned", "free"), ("pinned", "held")])
def test_axial_field_is_the_shortening_of_the_slopes(support, axial):
    """-L ψ_kl(ξ) = ∫0^ξ N_k' N_l' dξ, less ξ times its value at the far end when the ends are held."""
    beam = el_body.Beam((0, 0, 0), (1, 0, 0), (0, 1, 0), 1.0, 1.0, (1.0, 1.0), support, 8, axial=axial)
    xi = np.array([0.2, 0.5, 0.9])
    _, axial_field = el_body.beam_basis(support, xi, axial)
    for x, got in zip(xi, axial_field):
        expected = slope_integral(beam, x) - (x * slope_integral(beam, 1.0) if axial == "held" else 0.0)
        assert np.abs(got - expected).max() < 1e-12 * np.abs(expected).max()


def test_clamped_pair_energy_is_zero_at_rest_and_grows_as_its_closed_form():
    """Two rollers clamping the rail, each preloaded by δ: Π = ½ k [(δ - d)₊² + (δ + d)₊² - 2 δ₊²] is k d² while both
    touch (|d| <= δ), ½ k [(|d| + δ)² - 2 δ²] after one lifts, and 0 undeflected; with a gap (δ < 0) ½ k (|d| + δ)²
    once the rail reaches a roller; a batch of deflections (rows) gets one energy a row. The linear law is ½ k d²."""
    k, delta = 2e6, 1e-3
    rollers = el_body.Rollers((k,) * 5, (0.0,) * 5, "clamped_pair", (delta, delta, delta, delta, -delta))
    d = np.array([0.0, 0.5e-3, -2e-3, 0.3e-3, 3e-3])
    expected = [0.0, k * 0.25e-6, 0.5 * k * (9e-6 - 2e-6), k * 0.09e-6, 0.5 * k * 4e-6]
    got = [el_body.roller_energy(rollers, np.where(np.arange(5) == i, d, 0.0)) for i in range(5)]
    assert np.allclose(got, expected, rtol=1e-12, atol=0)
    rows = np.array([np.where(np.arange(5) == i, d, 0.0) for i in (1, 2)])
    assert np.allclose(el_body.roller_energy(rollers, rows), expected[1:3], rtol=1e-12, atol=0)
    linear = el_body.Rollers((k,) * 5, (0.0,) * 5)
    assert np.isclose(el_body.roller_energy(linear, d), 0.5 * k * float(d @ d), rtol=1e-12, atol=0)


def test_roller_laws_take_any_real_numbers_as_floats():
    """Stiffness and preload as Python integers past int64 (an object array unless converted): the forces,
    stiffness and energy are float arrays, equal to those of the same numbers given as floats."""
    big, d = 2 ** 70, np.array([1e-3, -2e-3, 0.0, 5e-4, 3e-3])
    exact = el_body.Rollers((big,) * 5, (0,) * 5, "clamped_pair", (2 ** 64, 0, 0, 0, 0))
    floats = el_body.Rollers((float(big),) * 5, (0.0,) * 5, "clamped_pair", (2.0 ** 64, 0.0, 0.0, 0.0, 0.0))
    for got, ref in ((el_body.roller_forces(exact, d, d, True), el_body.roller_forces(floats, d, d, True)),
                     ((el_body.roller_energy(exact, d),), (el_body.roller_energy(floats, d),))):
        for a, b in zip(got, ref):
            assert np.asarray(a).dtype == np.float64
            np.testing.assert_array_equal(a, b)
