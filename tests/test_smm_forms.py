"""SMM vector-chain form = graph form (11) = Lagrange's equations, symbolically and numerically."""
import math

import numpy as np
import pytest
import sympy
from hypothesis import HealthCheck, assume, given, settings, strategies as st

from symmech.smm import lagrange, numeric
from symmech.smm.derive import bundled_scenes, load_mechanism, matrices
from symmech.smm.model import Effects

from smm_helpers import bar_on_springs, hanging_mass, mech, param

SCENES = bundled_scenes()


def _zero(expr) -> bool:
    return expr == 0 or sympy.simplify(expr) == 0


# the spatial boom's symbolic comparison (~8 s of simplify) in the slow tier: random spatial chains stay here
@pytest.mark.parametrize("path", [p if p.stem != "smm_spatial_boom" else pytest.param(p, marks=pytest.mark.slow)
                                  for p in SCENES], ids=[p.stem for p in SCENES])
def test_bundled_chain_equals_graph_equals_lagrange(path):
    m = load_mechanism(path)
    chain, graph, lag = matrices(m, "chain"), matrices(m, "graph"), lagrange.matrices(m)
    for key in ("a", "b", "c", "residual"):
        for x, y, z in zip(chain[key], graph[key], lag[key]):
            assert _zero(sympy.expand(x - y)), (key, x, y)
            assert _zero(x - z), (key, x, z)


@pytest.mark.parametrize("build", [hanging_mass, bar_on_springs])
@pytest.mark.parametrize("effects", [None, Effects(True, False, True), Effects(False, True, False)])
def test_small_systems_all_forms_agree(build, effects):
    m = build()
    chain, graph, lag = matrices(m, "chain", effects), matrices(m, "graph", effects), lagrange.matrices(m, effects)
    for key in ("a", "b", "c"):
        assert all(_zero(x - y) for x, y in zip(chain[key], graph[key]))
        assert all(_zero(x - z) for x, z in zip(chain[key], lag[key]))
    # dPi/dq keeps the springs' equilibrium forces whatever the effects (preload off drops their stiffness only)
    assert all(_zero(x - z) for x, z in zip(chain["residual"], lag["residual"]))


@st.composite
def planar_chains(draw):
    """Random planar trees of points with relative/absolute angles, slides, bodies, preloaded springs."""
    n_pts = draw(st.integers(2, 4))
    n_ang = draw(st.integers(1, 3))
    n_sl = draw(st.integers(0, 1))
    num = st.floats(-1.5, 1.5, allow_nan=False).map(lambda x: round(x, 3))
    coords = [{"name": f"a{i}", "type": "angle"} for i in range(n_ang)]
    for i in range(n_sl):
        t = draw(st.floats(0, 2 * math.pi))
        coords.append({"name": f"s{i}", "type": "slide", "axis": [math.cos(t), math.sin(t)]})
    points = [{"name": "O", "at": [0, 0]}]
    used = set()
    for i in range(1, n_pts + 1):
        parent = draw(st.sampled_from([p["name"] for p in points]))
        turns = sorted(draw(st.sets(st.sampled_from([c["name"] for c in coords[:n_ang]]), max_size=n_ang)))
        slides = sorted(draw(st.sets(st.sampled_from([c["name"] for c in coords[n_ang:]]), max_size=1))) \
            if n_sl else []
        used |= set(turns) | set(slides)
        points.append({"name": f"P{i}", "from": parent, "vector": [draw(num) + 0.1 * i, draw(num) - 0.2],
                       "turns": turns, "slides": slides})
    missing = [c["name"] for c in coords if c["name"] not in used]
    last = points[-1]
    for name in missing:
        (last["turns"] if name.startswith("a") else last["slides"]).append(name)
    last["turns"].sort()
    names = [p["name"] for p in points[1:]]
    bodies = [{"name": f"B{i}", "mass": draw(st.floats(0.5, 3.0)),
               "inertia": draw(st.one_of(st.just(0.0), st.floats(1e-3, 1.0))), "com": p} for i, p in enumerate(names)]
    springs = []
    for j in range(draw(st.integers(1, 3))):
        b = draw(st.sampled_from(names))
        a = draw(st.sampled_from([x for x in ["O"] + names if x != b]))
        springs.append({"name": f"k{j}", "ends": [a, b], "stiffness": draw(st.floats(10, 1000)),
                        "preload": draw(st.floats(-50, 50))})
    dampers = [{"name": "d0", "ends": ["O", names[-1]], "viscosity": draw(st.floats(0.1, 5))}]
    def body(other):
        return st.sampled_from(["ground"] + [b["name"] for b in bodies if b["name"] != other])
    return {"parameters": {"g": param(9.81, "m/s^2")}, "coordinates": coords, "points": points,
            "bodies": bodies, "springs": springs, "dampers": dampers, "gravity": {"g": "g"},
            "torsion_springs": [{"name": "t0", "bodies": [draw(body(bodies[-1]["name"])), bodies[-1]["name"]],
                                 "stiffness": draw(st.floats(1, 100))}],
            "torsion_dampers": [{"name": "t1", "bodies": [draw(body(bodies[0]["name"])), bodies[0]["name"]],
                                 "viscosity": draw(st.floats(0.1, 5))}]}


def _spread(d):
    """Skip drawings where a spring's ends coincide (that is an input error, tested elsewhere)."""
    from symmech.smm import forms
    from symmech.smm.model import NumericArith

    m = mech(d)
    g = forms.Geometry(m, NumericArith(m.values()))
    for s in m.springs + m.dampers:
        ra = np.array(forms.chain_kinematics(g, s.a, False).r)
        rb = np.array(forms.chain_kinematics(g, s.b, False).r)
        if np.linalg.norm(ra - rb) < 0.05:
            return None
    return m


# a few chains in the default tier, more in the slow tier (each chain: a symbolic Lagrange derivation)
@settings(max_examples=4, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(planar_chains())
def test_random_planar_chains_numeric_agreement(d):
    m = _spread(d)
    assume(m is not None)
    num = numeric.assemble(m)
    graph = matrices(m, "graph")
    lag = lagrange.matrices(m)
    values = {sympy.Symbol(k, real=True): v for k, v in m.values().items()}
    for key, ref in (("a", num.a.toarray()), ("b", num.b.toarray()), ("c", num.c.toarray())):
        scale = max(1.0, np.abs(ref).max())
        g_ = np.array(graph[key].subs(values).evalf(), dtype=float)
        l_ = np.array(lag[key].subs(values).evalf(), dtype=float)
        np.testing.assert_allclose(g_, ref, atol=1e-10 * scale, rtol=0)
        np.testing.assert_allclose(l_, ref, atol=1e-10 * scale, rtol=0)
    np.testing.assert_allclose(np.array(lag["residual"].subs(values).evalf(), dtype=float).ravel(), num.residual,
                               atol=1e-10 * max(1.0, np.abs(num.residual).max()))


@st.composite
def spatial_chains(draw):
    """Random spatial trees: angles about random unit axes (Table 2 conjugates e x p), ordered
    rotations, slides, principal moments, preloaded springs, gravity, torsion springs."""
    unit = st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1)).filter(
        lambda v: 0.3 < math.sqrt(sum(x * x for x in v)))
    n_ang = draw(st.integers(1, 2))
    coords = []
    for i in range(n_ang):
        v = draw(unit)
        norm = math.sqrt(sum(x * x for x in v))
        coords.append({"name": f"a{i}", "type": "angle", "axis": [x / norm for x in v]})
    v = draw(unit)
    norm = math.sqrt(sum(x * x for x in v))
    coords.append({"name": "s0", "type": "slide", "axis": [x / norm for x in v]})
    num = st.floats(-1.2, 1.2).map(lambda x: round(x, 3))
    points = [{"name": "O", "at": [0, 0, 0]}]
    for i in range(1, 3):
        parent = draw(st.sampled_from([p["name"] for p in points]))
        turns = sorted(draw(st.sets(st.sampled_from([c["name"] for c in coords[:n_ang]]), max_size=n_ang)))
        points.append({"name": f"P{i}", "from": parent, "turns": turns,
                       "vector": [draw(num) + 0.2 * i, draw(num), draw(num) - 0.1 * i],
                       "slides": ["s0"] if draw(st.booleans()) else []})
    points[-1]["turns"] = sorted(set(points[-1]["turns"]) | {c["name"] for c in coords[:n_ang]})
    points[-1]["slides"] = ["s0"]
    names = [p["name"] for p in points[1:]]
    # principal moments satisfying the triangle inequalities: J3 between |J1 - J2| and J1 + J2
    moments = st.tuples(st.floats(0.1, 1.0), st.floats(0.1, 1.0), st.floats(0.0, 1.0)).map(
        lambda j: [j[0], j[1], abs(j[0] - j[1]) + j[2] * (j[0] + j[1] - abs(j[0] - j[1]))])
    bodies = [{"name": f"B{i}", "mass": draw(st.floats(0.5, 3.0)),
               "inertia": draw(moments), "com": p}
              for i, p in enumerate(names)]
    ends = [draw(st.sampled_from([("O", "P1"), ("O", "P2"), ("P1", "P2")])) for _ in range(2)]
    springs = [{"name": f"k{j}", "ends": list(ends[j]),
                "stiffness": draw(st.floats(10, 1000)), "preload": draw(st.floats(-50, 50))} for j in range(2)]
    v = draw(unit)
    norm = math.sqrt(sum(x * x for x in v))
    return {"parameters": {"g": param(9.81, "m/s^2")}, "coordinates": coords, "points": points,
            "bodies": bodies, "springs": springs,
            "torsion_springs": [{"name": "t0", "bodies": ["ground", "B1"], "stiffness": 30.0,
                                 "axis": [x / norm for x in v]}],
            "torsion_dampers": [{"name": "t1", "bodies": ["B0", "B1"], "viscosity": 2.0}],
            "gravity": {"g": "g", "direction": [0, 0, -1]}}


@settings(max_examples=2, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(spatial_chains())
def test_random_spatial_chains_numeric_agreement(d):
    test_random_planar_chains_numeric_agreement.hypothesis.inner_test(d)


@pytest.mark.slow
@settings(max_examples=16, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(planar_chains())
def test_many_random_planar_chains_numeric_agreement(d):
    test_random_planar_chains_numeric_agreement.hypothesis.inner_test(d)


@pytest.mark.slow
@settings(max_examples=8, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(spatial_chains())
def test_many_random_spatial_chains_numeric_agreement(d):
    test_random_planar_chains_numeric_agreement.hypothesis.inner_test(d)


def test_generated_matrices_hold_only_the_effects_asked_for():
    """Preload and gravity terms are absent from the symbolic c when the scene drops them."""
    g = sympy.Symbol("g", real=True)
    with_all = matrices(hanging_mass())["c"]
    without = matrices(hanging_mass(effects={"preload": False}))["c"]
    assert g in with_all.free_symbols
    assert g not in without.free_symbols
    assert matrices(hanging_mass(effects={"damping": False}))["b"] == sympy.zeros(2, 2)
