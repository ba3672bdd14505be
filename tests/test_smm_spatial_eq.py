"""Spatial equilibrium search (eq. (6)), principal axes and torsion-spring preloads.

References are independent of the SMM: the potential and the kinetic energy of the test
mechanisms are written here directly from rotation matrices (sympy, exact derivatives),
minimised with scipy, and compared with the model that ``numeric.solve_equilibrium`` redraws."""
import functools
import math
from dataclasses import replace

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize
import sympy
from hypothesis import HealthCheck, given, settings, strategies as st

from symmech.core.scene import SymmechError
from symmech.smm import lagrange, numeric
from symmech.smm.derive import matrices

from smm_helpers import mech, param
from test_smm_forms import spatial_chains, test_random_planar_chains_numeric_agreement as _numeric_agreement

# a body on a spherical-like joint (angles about x, y, z, in this order) with a pendulum-like
# arm, three springs given by free lengths to ground anchors, skew gravity, a tilted principal
# frame; a light link turned by the first angle only carries a preloaded torsion spring.
V_C = (0.1, 0.2, -0.8)                     # O -> centre of mass [m]
ATTACH = [(0.3, 0.0, 0.1), (-0.2, 0.25, 0.0), (0.0, -0.3, -0.2)]  # C -> spring ends [m]
ANCHOR = [(0.9, 0.3, -0.5), (-0.7, 0.8, -0.9), (0.2, -0.9, -1.2)]  # ground anchors [m]
K = [300.0, 200.0, 250.0]                  # [N/m]
L0 = [0.35, 0.4, 0.3]                      # free lengths [m]
MASS, G, GDIR = 6.0, 9.81, (2 / 7, -3 / 7, -6 / 7)
J = (0.4, 0.3, 0.2)                        # principal central moments [kg m^2]
P_AXES = ((0, 0.6, 0.8), (1, 0, 0), (0, 0.8, -0.6))
KT, MT, JL = 15.0, 2.0, 0.05               # torsion stiffness [N m/rad], preload [N m], link inertia


def _scene(order=("a", "b", "c")):
    points = [{"name": "O", "at": [0, 0, 0]},
              {"name": "C", "from": "O", "vector": list(V_C), "turns": list(order)},
              {"name": "H", "from": "O", "vector": [0.2, 0, 0], "turns": ["a"]}]
    points += [{"name": f"S{i}", "from": "C", "vector": list(v), "turns": ["a", "b", "c"]}
               for i, v in enumerate(ATTACH)]
    points += [{"name": f"G{i}", "at": list(v)} for i, v in enumerate(ANCHOR)]
    return {
        "parameters": {"g": param(G, "m/s^2")},
        "coordinates": [{"name": "a", "type": "angle", "axis": [1, 0, 0]},
                        {"name": "b", "type": "angle", "axis": [0, 1, 0]},
                        {"name": "c", "type": "angle", "axis": [0, 0, 1]}],
        "points": points,
        "bodies": [{"name": "body", "mass": MASS, "inertia": list(J), "com": "C",
                    "principal_axes": [list(p) for p in P_AXES]},
                   {"name": "link", "mass": 0.0, "inertia": [JL, 0, 0], "com": "H"}],
        "springs": [{"name": f"k{i}", "ends": [f"S{i}", f"G{i}"], "stiffness": K[i], "free_length": L0[i]}
                    for i in range(3)],
        "torsion_springs": [{"name": "t", "bodies": ["ground", "link"], "stiffness": KT, "preload": MT,
                             "axis": [1, 0, 0]}],
        "gravity": {"g": "g", "direction": list(GDIR)},
    }


@functools.lru_cache(maxsize=1)
def _reference():
    """q*, omega^2 from Pi and T written directly: R = Rx(a) Ry(b) Rz(c)."""
    a, b, c = q = sympy.symbols("a b c", real=True)
    Rx = sympy.Matrix([[1, 0, 0], [0, sympy.cos(a), -sympy.sin(a)], [0, sympy.sin(a), sympy.cos(a)]])
    Ry = sympy.Matrix([[sympy.cos(b), 0, sympy.sin(b)], [0, 1, 0], [-sympy.sin(b), 0, sympy.cos(b)]])
    Rz = sympy.Matrix([[sympy.cos(c), -sympy.sin(c), 0], [sympy.sin(c), sympy.cos(c), 0], [0, 0, 1]])
    R = Rx * Ry * Rz
    rc = R * sympy.Matrix(V_C)
    pi = -MASS * G * sympy.Matrix(GDIR).dot(rc) + KT * a**2 / 2 + MT * a
    for v, w, k, l0 in zip(ATTACH, ANCHOR, K, L0):
        d = rc + R * sympy.Matrix(v) - sympy.Matrix(w)
        pi += k * (sympy.sqrt(d.dot(d)) - l0) ** 2 / 2
    grad = sympy.lambdify([q], [pi.diff(s) for s in q], cse=True)
    hess = sympy.lambdify([q], sympy.hessian(pi, q), cse=True)
    f = sympy.lambdify([q], pi, cse=True)
    res = scipy.optimize.minimize(f, np.zeros(3), jac=lambda x: np.array(grad(x), float),
                                  hess=lambda x: np.array(hess(x), float), method="trust-exact",
                                  options={"gtol": 1e-13})
    qs = res.x
    for _ in range(3):  # polish the minimiser's answer with exact Newton steps
        qs = qs - np.linalg.solve(np.array(hess(qs), float), np.array(grad(qs), float))
    Jc = sympy.lambdify([q], rc.jacobian(q))(qs)
    W = np.zeros((3, 3))
    for i, s in enumerate(q):
        Om = np.array(sympy.lambdify([q], R.diff(s) * R.T)(qs), float)
        W[:, i] = [Om[2, 1], Om[0, 2], Om[1, 0]]
    RP = np.array(sympy.lambdify([q], R)(qs), float) @ np.array(P_AXES, float).T
    M = MASS * Jc.T @ Jc + W.T @ RP @ np.diag(J) @ RP.T @ W
    M[0, 0] += JL
    return qs, scipy.linalg.eigh(np.array(hess(qs), float), M, eigvals_only=True), np.array(grad(qs), float)


def test_spatial_equilibrium_matches_direct_minimisation():
    q_ref, w2_ref, g_ref = _reference()
    assert np.abs(g_ref).max() < 1e-9 and np.abs(q_ref).min() > 0.05  # a genuinely turned equilibrium
    m = mech(_scene())
    found, report = numeric.solve_equilibrium(m)
    np.testing.assert_allclose(report["q"], q_ref, atol=1e-9, rtol=0)
    num = numeric.assemble(found)
    assert np.abs(num.residual).max() < 1e-9
    w2 = scipy.linalg.eigh(num.c.toarray(), num.a.toarray(), eigvals_only=True)
    np.testing.assert_allclose(w2, w2_ref, rtol=1e-8)
    # the redrawn model (conjugated axes, turned principal axes, torsion moment, gravity) by
    # Lagrange's route; its springs are left out to keep sympy fast (checked against q*, omega^2)
    bare = replace(found, springs=[])
    lag = lagrange.matrices(bare)
    num = numeric.assemble(bare)
    values = {sympy.Symbol(k, real=True): v for k, v in found.values().items()}
    for key, ref in (("a", num.a.toarray()), ("c", num.c.toarray())):
        np.testing.assert_allclose(np.array(lag[key].subs(values).evalf(), float), ref,
                                   atol=1e-10 * np.abs(ref).max(), rtol=0)


def test_inconsistent_turn_order_is_refused():
    m = mech(_scene(order=("a", "c", "b")))  # C turned by a, c, b but the springs' ends by a, b, c
    with pytest.raises(SymmechError, match="coordinate '[bc]' is preceded by the turns"):
        numeric.solve_equilibrium(m)


def test_spatial_torsion_spring_off_its_axis_is_refused():
    d = _scene()
    d["torsion_springs"][0]["bodies"] = ["ground", "body"]
    with pytest.raises(SymmechError, match="torsion spring 't'.*about the spring axis only"):
        numeric.solve_equilibrium(mech(d))


def test_principal_axes_must_be_orthonormal():
    d = _scene()
    d["bodies"][0]["principal_axes"] = [[0, 0.6, 0.8], [1, 0, 0], [0, 0.6, -0.8]]
    with pytest.raises(SymmechError, match=r"bodies\[0\].principal_axes': must be orthonormal; axis 1 . axis 3"):
        mech(d)


# ---------------------------------------------------------------- torsion-spring preload

def _pendulum(preload, effects=None, solve=False, bodies=("ground", "bob")):
    """Bob m on a massless rod l drawn at th0 from the downward vertical; torsion spring k
    (``bodies``: ground -> bob) with moment M0 in the drawn configuration."""
    d = {"parameters": {"m": param(1.5, "kg"), "l": param(0.8, "m"), "g": param(9.81, "m/s^2"),
                        "k": param(12.0, "N m/rad"), "th0": param(0.6, "rad")},
         "coordinates": [{"name": "phi", "type": "angle"}],
         "points": [{"name": "O", "at": [0, 0]},
                    {"name": "B", "from": "O", "vector": ["l*sin(th0)", "-l*cos(th0)"], "turns": ["phi"]}],
         "bodies": [{"name": "bob", "mass": "m", "com": "B"}],
         "torsion_springs": [{"name": "t", "bodies": list(bodies), "stiffness": "k", "preload": preload}],
         "gravity": {"g": "g"}}
    if effects:
        d["effects"] = effects
    return mech(d)


def test_preloaded_torsion_spring_holds_a_pendulum_off_vertical():
    """Pi = -m g l cos(th0 + phi) + k phi^2/2 + M0 phi: dPi/dphi(0) = m g l sin th0 + M0 = 0 for
    M0 = -m g l sin th0, and omega^2 = (k + m g l cos th0) / (m l^2) (planar: no M0 d2twist term)."""
    m = _pendulum("-m*g*l*sin(th0)")
    mass, l, g, k, th0 = 1.5, 0.8, 9.81, 12.0, 0.6
    num = numeric.assemble(m)
    assert abs(num.residual[0]) < 1e-13
    w2 = num.c.toarray()[0, 0] / num.a.toarray()[0, 0]
    assert w2 == pytest.approx((k + mass * g * l * math.cos(th0)) / (mass * l * l), rel=1e-13)
    sym = matrices(m)
    s = {n: sympy.Symbol(n, real=True) for n in ("m", "l", "g", "k", "th0")}
    assert sympy.simplify(sym["residual"][0]) == 0
    assert sympy.simplify(sym["c"][0, 0] - s["k"] - s["m"] * s["g"] * s["l"] * sympy.cos(s["th0"])) == 0
    # an unbalanced moment: dPi/dphi = m g l sin th0 + M0
    assert numeric.assemble(_pendulum(1.0)).residual[0] == pytest.approx(mass * g * l * math.sin(th0) + 1.0,
                                                                         rel=1e-14)


def test_preloaded_torsion_spring_keeps_its_free_angle_in_the_search():
    """With M0 = 1 N m the search finds m g l sin(th0 + phi) + k phi + M0 = 0 and
    omega^2 = (k + m g l cos(th0 + phi)) / (m l^2)."""
    mass, l, g, k, th0 = 1.5, 0.8, 9.81, 12.0, 0.6
    found, report = numeric.solve_equilibrium(_pendulum(1.0))
    phi = scipy.optimize.brentq(lambda p: mass * g * l * math.sin(th0 + p) + k * p + 1.0, -1.5, 0.0, xtol=1e-15)
    assert abs(report["q"][0] - phi) < 1e-9 and abs(phi) > 0.3
    num = numeric.assemble(found)
    assert num.c.toarray()[0, 0] / num.a.toarray()[0, 0] == pytest.approx(
        (k + mass * g * l * math.cos(th0 + phi)) / (mass * l * l), rel=1e-9)


def _spatial_torsion_scene():
    """Two bodies on compound rotations (relative angles), skew torsion axes, preloaded torsion
    springs ground -> B, A -> B and B -> A, tilted principal axes (exact rational numbers)."""
    return mech({
        "parameters": {"M0": param(3.7, "N m"), "k": param(20.0, "N m/rad"), "g": param(9.81, "m/s^2")},
        "coordinates": [{"name": "a", "type": "angle", "axis": [1, 0, 0]},
                        {"name": "b", "type": "angle", "axis": [0, 1, 0]},
                        {"name": "c", "type": "angle", "axis": [0, "3/5", "4/5"]}],
        "points": [{"name": "O", "at": [0, 0, 0]},
                   {"name": "P", "from": "O", "vector": ["3/10", "1/10", -1], "turns": ["a", "b"]},
                   {"name": "Q", "from": "P", "vector": ["1/5", "1/2", "1/10"], "turns": ["a", "b", "c"]}],
        "bodies": [{"name": "A", "mass": 2, "inertia": ["1/10", "1/5", "3/10"], "com": "P"},
                   {"name": "B", "mass": 1, "inertia": ["3/10", "1/5", "1/10"], "com": "Q",
                    "principal_axes": [[0, "3/5", "4/5"], [1, 0, 0], [0, "4/5", "-3/5"]]}],
        "torsion_springs": [{"name": "t0", "bodies": ["ground", "B"], "stiffness": "k", "preload": "M0",
                             "axis": ["12/25", "3/5", "16/25"]},
                            {"name": "t1", "bodies": ["A", "B"], "stiffness": "k", "preload": "-2*M0",
                             "axis": [0, "3/5", "4/5"]},
                            {"name": "t2", "bodies": ["B", "A"], "stiffness": "k", "preload": "M0",
                             "axis": ["4/5", 0, "3/5"]}],
        "gravity": {"g": "g", "direction": ["3/5", 0, "-4/5"]}})


@pytest.mark.parametrize("effects", [None, {"preload": False}])
def test_spatial_torsion_preload_chain_graph_lagrange_symbolic(effects):
    from symmech.smm.model import Effects

    m = _spatial_torsion_scene()
    eff = Effects(preload=False) if effects else None
    ch, gr, lg = matrices(m, "chain", eff), matrices(m, "graph", eff), lagrange.matrices(m, eff)
    for key in ("a", "c", "residual"):
        for x, y, z in zip(ch[key], gr[key], lg[key]):
            assert sympy.simplify(x - y) == 0 and sympy.simplify(x - z) == 0, (key, x, z)
    if eff is None:  # the compound-rotation term M0 d2twist is really there
        drop = matrices(m, "chain", Effects(preload=False))["c"]
        assert sympy.simplify(ch["c"][0, 1] - drop[0, 1]) != 0


@st.composite
def spatial_chains_with_axes(draw):
    """The random spatial chains of test_smm_forms with tilted principal axes on every body and
    preloaded torsion springs on compound rotations; their translational springs are dropped
    (tested there; their square roots are what makes Lagrange's route slow)."""
    d = draw(spatial_chains())
    d["springs"] = []
    angles = [c for c in d["coordinates"] if c["type"] == "angle"]
    if len(angles) == 1:  # the M0 d2twist term needs two non-parallel turns
        d["coordinates"].insert(1, {"name": "a1", "type": "angle", "axis": [0.0, 0.6, -0.8]})
        d["points"][-1]["turns"].append("a1")
    for b in d["bodies"]:
        v = np.array([draw(st.floats(-1, 1)) for _ in range(3)]) + [0.0, 0.0, 1.5]
        e = v / np.linalg.norm(v)
        t = draw(st.floats(0.2, 3.0))
        Kx = np.array([[0, -e[2], e[1]], [e[2], 0, -e[0]], [-e[1], e[0], 0]])
        R = np.eye(3) + math.sin(t) * Kx + (1 - math.cos(t)) * Kx @ Kx
        b["principal_axes"] = R.T.tolist()
    d["torsion_springs"][0]["preload"] = draw(st.floats(-20, 20))
    d["torsion_springs"].append({"name": "t2", "bodies": ["B0", "B1"], "stiffness": 5.0,
                                 "preload": draw(st.floats(-20, 20)), "axis": [0.6, 0, 0.8]})
    return d


@settings(max_examples=1, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(spatial_chains_with_axes())
def test_random_spatial_chains_with_principal_axes_and_torsion_preload(d):
    """Chain form (numeric, sparse) = graph form = Lagrange (a, b, c, residual), abs 1e-10 of scale."""
    _numeric_agreement.hypothesis.inner_test(d)


@pytest.mark.slow
@settings(max_examples=4, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(spatial_chains_with_axes())
def test_more_random_spatial_chains_with_principal_axes_and_torsion_preload(d):
    _numeric_agreement.hypothesis.inner_test(d)


def test_spatial_scene_run_solves_equilibrium():
    from smm_helpers import run_scene

    """`symmech run` path: [equilibrium] solve = true on the spatial scene gives q* and omega."""
    q_ref, w2_ref, _ = _reference()
    s = run_scene({**_scene(), "equilibrium": {"solve": True}, "output": {"plots": []}})
    np.testing.assert_allclose(s["equilibrium"]["q"], q_ref, atol=1e-9, rtol=0)
    np.testing.assert_allclose(s["omega2_1_per_s2"], w2_ref, rtol=1e-8)
    assert not s["warnings"]


def test_torsion_preload_from_equilibrium_conditions():
    """preload = "equilibrium": eq. (5) gives M0 = -m g l sin th0, hence the closed form above;
    symbolic chain = Lagrange; the search refuses it by name."""
    mass, l, g, k, th0 = 1.5, 0.8, 9.81, 12.0, 0.6
    m = _pendulum("equilibrium")
    tensions, _ = numeric.equilibrium_tensions(m)
    assert tensions == {"t": pytest.approx(-mass * g * l * math.sin(th0), rel=1e-14)}
    num = numeric.assemble(m)
    assert abs(num.residual[0]) < 1e-13
    assert num.c.toarray()[0, 0] / num.a.toarray()[0, 0] == pytest.approx(
        (k + mass * g * l * math.cos(th0)) / (mass * l * l), rel=1e-13)
    ch, lg = matrices(m), lagrange.matrices(m)
    for key in ("c", "residual"):
        assert all(sympy.simplify(x - z) == 0 for x, z in zip(ch[key], lg[key]))
    # drawn from the bob to the ground: the twist and M0 change sign, Lagrange's c and equilibrium do not
    lg = lagrange.matrices(_pendulum("equilibrium", bodies=("bob", "ground")))
    s = {n: sympy.Symbol(n, real=True) for n in ("m", "l", "g", "k", "th0")}
    assert sympy.simplify(lg["residual"][0]) == 0
    assert sympy.simplify(lg["c"][0, 0] - s["k"] - s["m"] * s["g"] * s["l"] * sympy.cos(s["th0"])) == 0
    with pytest.raises(SymmechError, match="torsion spring 't': equilibrium.solve needs a preload value"):
        numeric.solve_equilibrium(m)


def test_principal_axes_field_shape_is_checked():
    d = _scene()
    d["bodies"][0]["principal_axes"] = [[0, 0.6, 0.8], [1, 0, 0]]
    with pytest.raises(SymmechError, match=r"bodies\[0\].principal_axes.*three axes of 3 components"):
        mech(d)
