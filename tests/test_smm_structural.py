"""SMM at scale: the vectorised graph form (11) of symmech.smm.structural equals
the term-list assembly of symmech.smm.forms on planar mechanisms (a, b, c, its preload and gravity
parts, dPi/dq, to 1e-13 of each matrix's scale), and large chains match their closed forms."""
import math

import numpy as np
import pytest
import scipy.sparse.linalg

from symmech.smm import numeric, structural
from symmech.smm.derive import bundled_scenes, load_mechanism, parameter_args
from symmech.smm.model import Effects, NumericArith

from smm_helpers import bar_on_springs, chain, hanging_mass, mech, spring_chain
from test_smm_pivot import random_scene, tension_error


def pendulum(n: int, k: float = 50.0) -> dict:
    """n links of length l hanging from O, relative angles, bobs m, torsion springs k, gravity."""
    points = [{"name": "O", "at": [0, 0]}]
    points += [{"name": f"P{i}", "from": "O" if i == 0 else f"P{i - 1}", "vector": [0, "-l"],
                "turns": [f"q{j}" for j in range(i + 1)]} for i in range(n)]
    return {"parameters": {"m": {"value": 1.0, "unit": "kg"}, "l": {"value": 0.1, "unit": "m"},
                           "k": {"value": k, "unit": "N m/rad"}, "g": {"value": 9.81, "unit": "m/s^2"}},
            "coordinates": [{"name": f"q{i}", "type": "angle"} for i in range(n)], "points": points,
            "bodies": [{"name": f"b{i}", "mass": "m", "com": f"P{i}"} for i in range(n)],
            "torsion_springs": [{"name": f"t{i}", "bodies": ["ground" if i == 0 else f"b{i - 1}", f"b{i}"],
                                 "stiffness": "k"} for i in range(n)],
            "gravity": {"g": "g"}}


def planar_models():
    yield from ((p.stem, load_mechanism(p)) for p in bundled_scenes() if p.stem != "smm_spatial_boom")
    yield "hanging_mass", hanging_mass()
    yield "bar_on_springs", bar_on_springs()
    yield "spring_chain", spring_chain([1.0, 2.0, 0.5], [100.0, 50.0, 80.0], end_stiffness=1e6)
    yield "pendulum_12", mech(pendulum(12))
    yield "transverse_chain", chain(n=5, mass=0.3, stiffness=10.0, spacing=0.2, tension=40.0, motion="transverse")
    admissible = [s for s in range(60) if tension_error(s) is not None][:6]
    for seed in [250, 280, 297] + admissible:
        yield f"random_{seed}", mech(random_scene(seed))


MODELS = list(planar_models())


@pytest.mark.parametrize("name, m", MODELS, ids=[n for n, _ in MODELS])
@pytest.mark.parametrize("effects", [Effects(True, True, True), Effects(False, True, False)])
def test_structural_equals_term_lists(name, m, effects):
    ar = NumericArith(m.values())
    assert structural.applies(m, ar)
    tensions = numeric.equilibrium_tensions(m)[0]
    fast = numeric.assemble(m, effects)
    ref = numeric.assemble_terms(m, ar, effects, tensions)
    for key in ("a", "b", "c", "c_preload", "c_gravity"):
        x, y = getattr(fast, key).toarray(), getattr(ref, key).toarray()
        scale = max(np.abs(y).max(), 1.0)
        np.testing.assert_allclose(x, y, rtol=0, atol=1e-13 * scale, err_msg=f"{name}: {key}")
    np.testing.assert_allclose(fast.residual, ref.residual, rtol=0,
                               atol=1e-13 * max(np.abs(ref.residual).max(), 1.0))
    for s in m.springs:
        assert math.isclose(fast.tensions[s.name], ref.tensions[s.name], rel_tol=1e-13, abs_tol=1e-12)


def test_spatial_mechanisms_keep_the_term_lists():
    m = load_mechanism([p for p in bundled_scenes() if p.stem == "smm_spatial_boom"][0])
    assert not structural.applies(m, NumericArith(m.values()))


def test_pendulum_chain_is_dense_and_matches_term_lists_at_40_links():
    """Relative angles make a and c dense: 40 links, every entry equal to the term lists."""
    m = mech(pendulum(40))
    fast = numeric.assemble(m)
    assert fast.a.nnz == 40 * 40 and fast.c.nnz == 40 * 40
    ref = numeric.assemble_terms(m, NumericArith(m.values()), m.effects, {})
    np.testing.assert_allclose(fast.c.toarray(), ref.c.toarray(), rtol=0, atol=1e-13 * np.abs(ref.c).max())


@pytest.mark.parametrize("ends", ["fixed-fixed", "fixed-free", "free-free"])
def test_long_chain_lowest_modes_closed_form(ends):
    """5,000 masses: the lowest 10 omega^2 by shift-invert Lanczos = 2 k/m (1 - cos theta_j)."""
    from symmech.smm.chain import exact_omega2

    spec = dict(n=5000, mass=0.1, stiffness=1e4, spacing=0.01, ends=ends)
    m = chain(**spec)
    num = numeric.assemble(m)
    w = np.sort(scipy.sparse.linalg.eigsh(num.c.tocsc(), k=10, M=num.a.tocsc(), sigma=0.0 if ends != "free-free" else -1e-3,
                                          return_eigenvectors=False))
    exact = np.array(exact_omega2({**spec, "motion": "axial", "tension": 0.0})[:10])
    # kappa ~ (n/pi)^2 ~ 3e6: about 1e-8 of the spectrum's top in absolute terms
    np.testing.assert_allclose(w, exact, rtol=0, atol=1e-8 * 4 * 1e4 / 0.1 + 1e-7 * exact.max())
    # what a user reads: the default name, the springs by name (k0 to the fixed start, kn to the fixed end) at zero
    # tension, the parameters' units and meanings (the generated module's PARAMS)
    assert m.name == f"chain_5000_{ends}_axial"
    first, last = (1 if ends == "free-free" else 0), (5000 if ends == "fixed-fixed" else 4999)
    assert num.tensions == {f"k{i}": 0.0 for i in range(first, last + 1)}
    assert [(a.name, a.unit, a.meaning) for a in parameter_args(m)] == [
        ("m", "kg", "mass of each particle"), ("k", "N/m", "stiffness of each spring"),
        ("L", "m", "spring length in equilibrium"), ("T", "N", "spring tension in equilibrium")]
