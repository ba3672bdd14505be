"""The compiled printed law's roots without LAPACK: ``impact_law.quartic_roots`` (Durand-Kerner in complex scalars)
against numpy's companion-matrix eigenvalues (``np.roots``), and ``impact_law._trig_roots`` against the Python
reference ``impact._trig_roots`` (numpy's ``eigvals``), tangent (double-root) cases included."""
import numpy as np
import pytest

from symmech.grain import impact

pytestmark = pytest.mark.slow  # compiles the engine's printed-law root finder (a few s on a cold numba cache)


def test_quartic_roots_are_numpys_for_simple_and_complex_roots():
    from symmech.grain.motion_engine.impact_law import quartic_roots

    rng = np.random.default_rng(3)
    for _ in range(2000):
        c = rng.normal(size=4) * 10.0 ** rng.uniform(-3, 3, size=4)
        got = np.array(quartic_roots(*c))
        ref = np.roots(np.r_[1.0, c])
        for z in got:  # each root found, to 1e-9 of its size (the eigensolver's own error is ~1e-15 here)
            assert np.min(np.abs(ref - z)) <= 1e-9 * (1.0 + abs(z))
        for z in ref:
            assert np.min(np.abs(got - z)) <= 1e-9 * (1.0 + abs(z))


def test_a_double_real_root_is_found_as_a_nearly_real_pair():
    """(t - 0.5)^2 (t + 1) (t - 2): the pair at 0.5 to ~sqrt(eps), as an eigensolver finds it."""
    from symmech.grain.motion_engine.impact_law import quartic_roots

    c = np.poly([0.5, 0.5, -1.0, 2.0])[1:]
    got = sorted(quartic_roots(*c), key=lambda z: z.real)
    assert abs(got[0] + 1.0) < 1e-14 and abs(got[3] - 2.0) < 1e-14
    for z in got[1:3]:
        assert abs(z - 0.5) < 1e-6


def test_trig_roots_are_the_python_references_tangent_cases_included():
    """20,000 random equations, one in four shifted to touch zero at its maximum or minimum (a double root):
    the same roots found (NaN where none) as the reference with numpy's eigenvalues, to 1e-8 rad (a double root
    is polished to ~sqrt(eps): the reference and the engine before this solver differed by 2e-9 rad too)."""
    from symmech.grain.motion_engine.impact_law import _trig_roots

    rng = np.random.default_rng(2)
    ks = rng.normal(size=(20000, 5))
    mu = np.linspace(-np.pi, np.pi, 20001)
    for i in range(0, len(ks), 4):
        F = ks[i, 1] * np.cos(mu) + ks[i, 2] * np.sin(mu) + ks[i, 3] * np.cos(2 * mu) + ks[i, 4] * np.sin(2 * mu)
        ks[i, 0] = -F.max() if i % 8 == 0 else -F.min()
    ref, _ = impact._trig_roots(ks, 1e-14)
    got = np.array([_trig_roots(k, 1e-14, 12) for k in ks])
    np.testing.assert_array_equal(np.isnan(got), np.isnan(ref))
    assert np.nanmax(np.abs(got - ref)) < 1e-8
    simple = np.arange(len(ks)) % 4 != 0
    assert np.nanmax(np.abs(got[simple] - ref[simple])) < 1e-12
