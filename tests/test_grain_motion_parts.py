"""Derivations, impact laws, effects switches, hard cases and scene errors of the grain motion."""
import math
from dataclasses import replace
from fractions import Fraction

import numpy as np
import pytest
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from symmech.cli import main
from symmech.generated import grain_motion as gm
from symmech.grain import contact, flight, motion, paper_mode
from symmech.grain.body import Ellipsoid, rotation
from symmech.grain.coulomb_law import ImpactLaw, inverse_effective_mass, principal_inertia
from symmech.grain.impact import reduction_tensor, solve_impact

G = 9.81


# --------------------------------------------------------------------------- derivations

def test_gravity_keeps_its_magnitude_and_matches_the_axis_slopes():
    rng = np.random.default_rng(1)
    alpha, beta = rng.uniform(-0.6, 0.6, (2, 50))
    g_k = gm.gravity(G, alpha, beta)
    np.testing.assert_allclose(np.linalg.norm(g_k, axis=1), G, rtol=1e-13)
    # A rotation of the horizontal frame: pitch the X axis up by alpha, then roll until Y rises by beta.
    for a, b, gk in zip(alpha[:5], beta[:5], g_k[:5]):
        roll = math.asin(math.sin(b) / math.cos(a))
        up = Rotation.from_euler("YX", [-a, roll]).inv().apply([0, 0, 1.0])  # vertical in KXYZ
        np.testing.assert_allclose(gk, -G * up, atol=1e-12)


def test_flight_translation_solves_the_relative_equation():
    vib = flight.Vibration(1e-3, 150.0, 0.4, (0.6, 0.0, 0.8))
    g_k = gm.gravity(G, 0.1, -0.05)
    r0, v0 = np.array([0.0, 0.0, 2e-3]), np.array([0.1, -0.02, 0.3])
    t, h = 0.37, 2e-5
    r = [flight.translate(r0, v0, g_k, vib, 0.2, s)[0] for s in (t - h, t, t + h)]
    acc = (r[0] - 2 * r[1] + r[2]) / h**2
    np.testing.assert_allclose(acc, g_k - vib.kinematics(t)[2], rtol=1e-5)
    start = flight.translate(r0, v0, g_k, vib, 0.2, 0.2)
    np.testing.assert_allclose(np.concatenate(start), np.concatenate([r0, v0]), atol=1e-15)


@pytest.mark.parametrize("axes", [(3e-3, 1e-3, 0.8e-3), (5e-3, 5e-3, 0.05e-3), (1e-2, 0.2e-3, 0.2e-3)],
                         ids=["seed", "very-flat", "very-long"])
def test_support_distance_is_the_lowest_point(axes):
    """Closed form against brute force over a fine surface mesh; R lies on the ellipsoid. The mesh is the golden
    (Fibonacci) lattice: scaled back to the unit sphere, 1000 nodes are spread evenly, each node's nearest one at
    least 3 / sqrt(1000) away (the lattice's packing distance 3.09 / sqrt(N)), their second moment I / 3."""
    unit = contact.ellipsoid_nodes(axes, 1000) / np.asarray(axes)
    np.testing.assert_allclose(np.linalg.norm(unit, axis=1), 1.0, rtol=1e-14)
    assert cKDTree(unit).query(unit, k=2)[0][:, 1].min() > 3 / math.sqrt(1000)
    np.testing.assert_allclose(unit.T @ unit / 1000, np.eye(3) / 3, atol=1e-4)
    Q = Rotation.random(20, random_state=3).as_matrix()
    nodes = contact.ellipsoid_nodes(axes, 200000)
    brute = -np.min(np.einsum("nij,kj->nki", Q, nodes)[..., 2], axis=1)
    h = contact.support_distance(axes, Q)
    assert np.all(h >= brute - 1e-15)
    np.testing.assert_allclose(h, brute, rtol=2e-3)
    R = contact.contact_offset(axes, Q)
    np.testing.assert_allclose(R[:, 2], -h, rtol=1e-12)
    body = np.einsum("nji,nj->ni", Q, R) / np.asarray(axes)
    np.testing.assert_allclose(np.sum(body**2, axis=1), 1.0, rtol=1e-12)
    # a quarter of a 3-4-5 turn about x, exact in rationals: the plane's normal in body axes is n = (0, 4/5, 3/5),
    # the lowest point -D^2 n / |D n| with D = diag(a, b, c), at depth |D n|; a float offset from an exact rotation
    a, b, c = axes
    exact = [[1, 0, 0], [0, Fraction(3, 5), Fraction(-4, 5)], [0, Fraction(4, 5), Fraction(3, 5)]]
    depth = math.hypot(4 * b, 3 * c) / 5
    lowest = np.array([0.0, -4 / 5 * b * b, -3 / 5 * c * c]) / depth
    R = contact.contact_offset(axes, exact)
    assert R.dtype == np.float64
    np.testing.assert_allclose(R, np.array(exact, dtype=float) @ lowest, rtol=1e-14, atol=1e-14 * max(axes))
    assert R[2] == pytest.approx(-depth, rel=1e-14)
    assert contact.support_distance(axes, exact) == pytest.approx(depth, rel=1e-14)


def test_euler_rates_invert_body_rates_and_match_the_planned_convention():
    rng = np.random.default_rng(4)
    ang = rng.uniform(0.2, 2.8, (30, 3))
    rates = rng.normal(size=(30, 3))
    p = gm.body_rates(*ang.T, *rates.T)
    psi, th, ph = ang.T
    expected_p = rates[:, 0] * np.sin(th) * np.sin(ph) + rates[:, 1] * np.cos(ph)
    np.testing.assert_allclose(p[:, 0], expected_p, rtol=1e-12)
    np.testing.assert_allclose(gm.euler_rates(*ang.T, *p.T), rates, rtol=1e-10, atol=1e-12)
    # Body rates are Q^T Q' of the issue-2 rotation matrix (finite difference in time).
    h = 1e-6
    Q0, Q1 = rotation(ang - rates * h), rotation(ang + rates * h)
    W = np.einsum("nji,njk->nik", rotation(ang), (Q1 - Q0) / (2 * h))
    np.testing.assert_allclose(np.stack([W[:, 2, 1], W[:, 0, 2], W[:, 1, 0]], 1), p, rtol=1e-6, atol=1e-8)


# --------------------------------------------------------------------------- impact laws

def random_contacts(n, seed):
    rng = np.random.default_rng(seed)
    axes = rng.uniform(0.2e-3, 4e-3, (n, 3))
    mass = rng.uniform(1e-6, 1e-4, n)
    Q = Rotation.random(n, random_state=seed).as_matrix()
    v = rng.normal(size=(n, 3))
    w = rng.normal(size=(n, 3)) * 100
    return axes, mass, Q, v, w


def test_inverse_effective_mass_is_the_reduction_tensor_over_mass():
    axes, mass, Q, _, _ = random_contacts(5, 1)
    K = inverse_effective_mass(mass, principal_inertia(axes, mass), Q, contact.contact_offset(axes, Q))
    for i in range(5):
        H = reduction_tensor(Ellipsoid(*axes[i], mass[i]), Q[i])
        np.testing.assert_allclose(mass[i] * K[i], H, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("e_n, e_t, mu", [(0.5, -0.5, np.inf), (1.0, 1.0, np.inf), (0.3, 0.8, 0.2),
                                          (0.0, -1.0, 0.5), (0.7, 0.0, 0.0)])
def test_coulomb_law_never_creates_energy(e_n, e_t, mu):
    axes, mass, Q, v, w = random_contacts(4000, 7)
    law = ImpactLaw("coulomb", e_n=e_n, e_t=e_t, mu=mu, check_printed=False)
    out = law.apply(axes, mass, Q, v, w, rotation=True)
    hit = out["u_before"][:, 2] < 0
    assert hit.sum() > 1000
    assert np.all(out["ke_after"][hit] <= out["ke_before"][hit] * (1 + 1e-12))
    # Normal restitution holds exactly inside the cone; on its boundary the contact still separates.
    if mu == np.inf:
        np.testing.assert_allclose(out["u_after"][hit, 2], -e_n * out["u_before"][hit, 2], rtol=1e-9, atol=1e-12)
    assert np.all(out["u_after"][hit, 2] >= -1e-12)


def test_coulomb_law_is_the_printed_law_for_a_sphere():
    """Sphere: e_n = e, e_t = lambda - 1, mu = inf reproduces the printed law solved by the robust solver."""
    rng = np.random.default_rng(2)
    e, lam = 0.6, 0.3
    body = Ellipsoid(2e-3, 2e-3, 2e-3, 3e-5)
    law = ImpactLaw("coulomb", e_n=e, e_t=lam - 1, mu=np.inf, check_printed=False)
    for _ in range(5):
        Q = Rotation.random(random_state=rng.integers(1000)).as_matrix()
        v = rng.normal(size=3) - [0, 0, 2]
        w = rng.normal(size=3) * 50
        ref = solve_impact(body, Q, v, w, e, lam)
        out = law.apply(np.array([[2e-3] * 3]), np.array([3e-5]), Q[None], v[None], w[None], True)
        np.testing.assert_allclose(out["v"][0], ref.v_c_after, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(out["w"][0], ref.omega_after, rtol=1e-9, atol=1e-9)


def test_printed_law_energy_creation_is_reported():
    """Elongated grains at random: the printed law creates energy in some impacts, and says so."""
    axes, mass, Q, v, w = random_contacts(400, 11)
    axes[:, 0] *= 5
    law = ImpactLaw("printed", e=0.9, lam=0.9)
    out = law.apply(axes, mass, Q, v, w, rotation=True)
    bad = ~out["admissible"]
    assert bad.any()
    assert sum("created energy" in x for x in out["warnings"]) == bad.sum()
    assert np.all(out["ke_after"][bad] > out["ke_before"][bad])


# --------------------------------------------------------------------------- effects switches

def grain_model(**kw):
    vib = flight.Vibration(1.2e-3, 2 * math.pi * 25, 0.0, (math.cos(0.5), 0.0, math.sin(0.5)))
    law = ImpactLaw("coulomb", e_n=0.4, e_t=-0.3, mu=0.5, check_printed=False)
    base = dict(axes=(1.5e-3, 1.5e-3, 1.5e-3), mass=2e-5, g_k=tuple(gm.gravity(G, 0.05, 0.0)), vibration=vib,
                law=law, mu=0.4, effects=motion.Effects())
    base.update(kw)
    return motion.Model(**base)


def run(model, t_end=0.2, mode="accurate", w=(0.0, 0.0, 0.0), z=3e-3):
    st = motion.State(0.0, np.array([0.0, 0.0, z]), np.zeros(3), np.array([1.0, 0, 0, 0]), np.array(w, float))
    T = 2 * math.pi / model.vibration.omega  # the surface's period even when its vibration is off
    num = motion.Numerics(mode=mode, tolerance=1e-10, scan_step=T / 40, dt=T / 1000, nodes=100,
                          sample_interval=T / 5)
    sim = paper_mode.simulate if mode == "paper" else motion.simulate
    return sim(model, num, st, t_end)


def test_effects_off_equal_full_model_with_parameters_zeroed():
    full = grain_model()
    # vibration off == amplitude zero
    a = run(replace(full, effects=motion.Effects(vibration=False)))
    b = run(replace(full, vibration=replace(full.vibration, amplitude=0.0)))
    np.testing.assert_allclose(a.final.r, b.final.r, atol=1e-12)
    # inclination off == horizontal surface
    a = run(replace(full, g_k=(0.0, 0.0, -G), effects=motion.Effects(inclination=False)))
    b = run(replace(full, g_k=tuple(gm.gravity(G, 0.0, 0.0))))
    np.testing.assert_allclose(a.final.r, b.final.r, atol=1e-12)
    # friction off == friction coefficient zero
    a = run(replace(full, effects=motion.Effects(friction=False)))
    b = run(replace(full, mu=0.0))
    np.testing.assert_allclose(a.final.r, b.final.r, atol=1e-9)
    # rotation off == a sphere without spin, tangential impulse or sliding friction (nothing to turn it)
    smooth = replace(full, law=ImpactLaw("coulomb", e_n=0.4, e_t=0.0, mu=0.0, check_printed=False), mu=0.0)
    a = run(replace(smooth, effects=motion.Effects(rotation=False)))
    b = run(smooth)
    np.testing.assert_allclose(a.final.r, b.final.r, atol=1e-10)
    assert len(a.impacts) == len(b.impacts) > 3


# --------------------------------------------------------------------------- hard cases

def test_chattering_on_a_still_plate_ends_in_sliding():
    model = grain_model(effects=motion.Effects(vibration=False, inclination=False))
    res = run(model, t_end=1.0)
    assert res.time_in["sliding"] > 0.5
    assert 5 < len(res.impacts) < 200
    assert res.trajectory[-1, -1] == motion.REGIMES.index("sliding")
    # Bounce heights fall geometrically by e_n^2 until the rest velocity is reached.
    up = np.array([i["v_after"][2] for i in res.impacts])
    np.testing.assert_allclose(up[1:4] / up[:3], 0.4, rtol=1e-6)


def test_paper_mode_chattering_ends_in_sliding():
    """Without rotation (a rolling body's discrete nodes make a bumpy wheel that keeps it bouncing)."""
    model = grain_model(effects=motion.Effects(vibration=False, inclination=False, rotation=False))
    res = run(model, t_end=0.5, mode="paper")
    assert res.trajectory[-1, -1] == motion.REGIMES.index("sliding")
    assert len(res.impacts) < 100


def test_grazing_contact_between_scan_points_is_found():
    """h(t) = (t - 0.5)^2 - 1e-8 dips below zero between scan points 0.4 and 0.6."""
    def h(t):
        return (np.asarray(t) - 0.5) ** 2 - 1e-8
    root = contact.first_root(h, 0.0, 1.0, 0.2, 1e-12)
    assert root == pytest.approx(0.5 - 1e-4, abs=1e-10)
    assert contact.first_root(lambda t: (np.asarray(t) - 0.5) ** 2 + 1e-8, 0.0, 1.0, 0.2, 1e-12) is None


def test_grazing_contact_midway_between_two_equal_scan_values_is_found():
    """h(t) = (t - 0.375)^2 - 1e-8 scanned at 0.25 from 0: h(0.25) = h(0.5) = 1/64 exactly, neither sample below
    both neighbours; the dip between them is still found, its first root at 0.375 - 1e-4."""
    root = contact.first_root(lambda t: (np.asarray(t) - 0.375) ** 2 - 1e-8, 0.0, 1.0, 0.25, 1e-12)
    assert root == pytest.approx(0.375 - 1e-4, abs=1e-10)


@pytest.mark.parametrize("axes", [(4e-3, 4e-3, 0.2e-3), (6e-3, 0.4e-3, 0.4e-3)], ids=["very-flat", "very-long"])
def test_flat_and_long_grains_run_and_never_create_energy(axes):
    model = grain_model(axes=axes, mass=1e-5)
    res = run(model, t_end=0.3, w=(5.0, 30.0, -10.0), z=8e-3)
    assert len(res.impacts) > 3
    assert all(i["admissible"] for i in res.impacts)
    assert np.all(np.isfinite(res.trajectory))
    # Never below the plane by more than the root tolerance.
    Q = flight.rotation_matrix(res.trajectory[:, 7:11])
    gap = res.trajectory[:, 3] - contact.support_distance(axes, Q)
    assert gap.min() > -1e-9


def test_high_frequency_low_amplitude_surface():
    """Gamma = 3 at 400 Hz (A ~ 4.7 um): the sphere bounces and drifts by the throw direction."""
    w = 2 * math.pi * 400
    vib = flight.Vibration(3 * G / w**2, w, 0.0, (math.cos(0.5), 0.0, math.sin(0.5)))
    model = grain_model(vibration=vib, effects=motion.Effects(rotation=False, inclination=False))
    res = run(model, t_end=0.05, z=1.5e-3)
    assert len(res.impacts) > 5
    assert res.final.r[0] > 0


def test_scene_errors_are_one_line_naming_the_field(tmp_path, capsys):
    base = (tmp_path / "s.toml")
    cases = {
        'semi_axes = [1e-3, -1e-3, 1e-3]': "body.semi_axes[1]",
        'semi_axes = [1e-3, 1e-3, 1e-3]\nmass = 1e-5\ndensity = 1000.0': "body.mass",
        'semi_axes = [1e-3, 1e-3, 1e-3]\nmass = 1e-5\n[surface]\nalpha_deg = 60.0\nbeta_deg = 60.0': "surface.beta_deg",
        'semi_axes = [1e-3, 1e-3, 1e-3]\nmass = 1e-5\n[initial]\nposition = [0.0, 0.0, 1e-4]': "initial.position",
        'semi_axes = [1e-3, 1e-3, 1e-3]\nmass = 1e-5\n[effects]\nvibrations = false': "effects.vibrations",
        'semi_axes = [1e-3, 1e-3, 1e-3]\nmass = 1e-5\n[vibration]\nfrequency = 0.0': "vibration.frequency",
        'semi_axes = [1e-3, 1e-3, 1e-3]\nmass = 1e-5\n[numerics]\nmode = "fast"': "numerics.mode",
        'semi_axes = [1e-3, 1e-3, 1e-3]\nmass = 1e-5': "impact.mu",
    }
    for body, field in cases.items():
        law = "mu = -0.5\n" if field == "impact.mu" else ""
        base.write_text('kind = "grain"\nduration = 0.01\n[impact]\ne_n = 0.5\ne_t = 0.0\n' + law + "[body]\n"
                        + body + "\n")
        assert main(["run", str(base), "--out", str(tmp_path / "o")]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and field in err and "Traceback" not in err, err


def test_paper_mode_as_printed_runs_and_differs_from_corrected():
    model = grain_model(g_k=tuple(gm.gravity(G, 0.2, 0.1)))
    st = motion.State(0.0, np.array([0.0, 0.0, 3e-3]), np.zeros(3), np.array([1.0, 0, 0, 0]), np.zeros(3))
    T = model.period
    num = motion.Numerics(mode="paper", dt=T / 500, nodes=100, sample_interval=T)
    corrected = paper_mode.simulate(model, num, st, 2 * T, (0.2, 0.1))
    printed = paper_mode.simulate(model, replace(num, as_printed=True), st, 2 * T, (0.2, 0.1))
    assert np.linalg.norm(printed.final.r - corrected.final.r) > 1e-4


def test_constant_euler_rates_of_62_break_angular_momentum_for_an_asymmetric_grain():
    """(62) keeps the Euler-angle rates of the impact: for an asymmetric grain L drifts by O(1)."""
    inertia = principal_inertia(np.array([3e-3, 1.5e-3, 1e-3]), 1e-5)
    ang0 = np.array([0.3, 1.0, 0.5])
    rates = gm.euler_rates(*ang0, 30.0, -10.0, 50.0)
    L = []
    for t in (0.0, 0.02, 0.04):
        ang = ang0 + rates * t
        L.append(rotation(ang) @ (inertia * gm.body_rates(*ang, *rates)))
    drift = max(np.linalg.norm(x - L[0]) for x in L) / np.linalg.norm(L[0])
    assert drift > 0.1


def test_paper_mode_rotates_a_grain_started_at_gimbal_lock():
    """theta = 0 (body axis 3 along the normal), where the Euler rates of (62) are singular. Before, paper mode
    froze the rotation; now a spin about the normal turns the grain exactly (regular precession, for which (62) is
    exact): Q(t) = Rz(30 t) Q0, and a tumbling start turns by about |w| t without NaN."""
    model = grain_model(axes=(2e-3, 1.5e-3, 1e-3), mass=1e-5)
    st = motion.State(0.0, np.array([0.0, 0.0, 8e-3]), np.zeros(3), np.array([1.0, 0, 0, 0]),
                      np.array([0.0, 0.0, 30.0]))
    T = model.period
    num = motion.Numerics(mode="paper", dt=T / 500, nodes=100, sample_interval=T / 5)
    res = paper_mode.simulate(model, num, st, T)
    assert len(res.impacts) == 0 and not res.warnings
    c, s = math.cos(30 * T), math.sin(30 * T)
    np.testing.assert_allclose(flight.rotation_matrix(res.final.q), [[c, -s, 0], [s, c, 0], [0, 0, 1]], atol=1e-12)
    tumble = paper_mode.simulate(model, num, replace(st, w=np.array([5.0, -3.0, 30.0])), T)
    assert np.all(np.isfinite(tumble.trajectory))
    turned = 2 * math.acos(min(1.0, abs(tumble.final.q[0])))
    assert turned == pytest.approx(math.sqrt(5**2 + 3**2 + 30**2) * T, rel=0.2)
    # Accurate mode (quaternions) has no such singularity either.
    acc = run(model, t_end=2 * T, w=(0.0, 0.0, 30.0))
    assert np.all(np.isfinite(acc.trajectory))

def test_paper_mode_landing_drops_spin_and_says_so():
    """A sphere spinning at 30 rad/s lands plastically and without friction on a still plate (the impulse passes
    through the centre: the spin is kept through the impact). Paper-mode sliding is a point mass's: the spin is
    dropped, and its kinetic energy I w^2 / 2 (I = 2/5 m a^2) is reported with a warning; accurate mode keeps it
    (a point contact below the centre exerts no couple about the normal)."""
    law = ImpactLaw("coulomb", e_n=0.0, e_t=0.0, mu=0.0, check_printed=False)
    model = grain_model(law=law, g_k=(0.0, 0.0, -G), effects=motion.Effects(vibration=False, inclination=False))
    paper = run(model, t_end=0.1, mode="paper", w=(0.0, 0.0, 30.0))
    assert paper.trajectory[-1, -1] == motion.REGIMES.index("sliding")
    np.testing.assert_array_equal(paper.final.w, 0.0)
    spin_energy = 0.5 * 0.4 * 2e-5 * 1.5e-3**2 * 30.0**2
    assert paper.summary()["spin_energy_dropped_J"] == pytest.approx(spin_energy, rel=1e-12)
    assert any("lost spin at landings" in w for w in paper.warnings)
    accurate = run(model, t_end=0.1, w=(0.0, 0.0, 30.0))
    np.testing.assert_allclose(flight.rotation_matrix(accurate.final.q) @ accurate.final.w, [0, 0, 30.0],
                               atol=1e-9)
    assert "spin_energy_dropped_J" not in accurate.summary()


def test_progress_reports_at_most_every_interval_and_always_when_final(monkeypatch):
    """``motion.Progress``: no report before ``PROGRESS_INTERVAL`` of wall time has passed since the last one
    (the clock is the test's), one after it, and one whenever ``final`` is set."""
    clock = [100.0]
    monkeypatch.setattr(motion.time, "monotonic", lambda: clock[0])
    seen = []
    progress = motion.Progress(seen.append)
    progress(0.1)
    clock[0] += 0.5 * motion.PROGRESS_INTERVAL
    progress(0.2)
    assert seen == []
    clock[0] += 0.6 * motion.PROGRESS_INTERVAL
    progress(0.3)
    progress(0.4)
    assert seen == [0.3]
    progress(0.5, final=True)
    assert seen == [0.3, 0.5]
    motion.Progress(None)(0.6, final=True)  # no callback: nothing to call
