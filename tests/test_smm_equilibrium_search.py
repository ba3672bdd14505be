"""The equilibrium search (eq. (6), numeric.solve_equilibrium) against equilibria solved by hand:
preloaded springs keep their free length l0 = l - T0/k, the tangent holds every effect whatever
the scene drops, stiff mechanisms converge to a tolerance relative to their stiffness, damped
modes with rigid, overdamped and repeated modes get their own ratios."""
import math

import numpy as np
import pytest
import scipy.optimize

from symmech.core.scene import SymmechError
from symmech.smm import numeric

from smm_helpers import mech, param


def hanging(k, mass, l, preload, effects=None, free_length=None, g=9.81):
    """Bob on a vertical spring O -> P drawn at length l, slides x and y."""
    spring = {"name": "s", "ends": ["O", "P"], "stiffness": "k"}
    if preload is not None:
        spring["preload"] = preload
    if free_length is not None:
        spring["free_length"] = free_length
    d = {"parameters": {"m": param(mass, "kg"), "k": param(k, "N/m"), "g": param(g, "m/s^2")},
         "coordinates": [{"name": "x", "type": "slide", "axis": [1, 0]}, {"name": "y", "type": "slide", "axis": [0, 1]}],
         "points": [{"name": "O", "at": [0, 0]}, {"name": "P", "from": "O", "vector": [0, -l], "slides": ["x", "y"]}],
         "bodies": [{"name": "bob", "mass": "m", "com": "P"}],
         "springs": [spring], "gravity": {"g": "g"}}
    if effects:
        d["effects"] = effects
    return mech(d)


@pytest.mark.parametrize("k, effects", [(1.0, None), (2.5, {"preload": False, "gravity": False})])
def test_preloaded_spring_keeps_its_free_length(k, effects):
    """T0 = 0.05 N on k [N/m], m g = 0.0981 N: l0 = l - T0/k, l* = l0 + m g/k, q_y = (T0 - m g)/k;
    sideways omega^2 = g/l*, vertical k/m (dropping effects from the scene does not change the search)."""
    mass, l, T0, g = 0.01, 0.4, 0.05, 9.81
    found, report = numeric.solve_equilibrium(hanging(k, mass, l, T0, effects))
    assert found.springs[0].preload is None
    assert float(found.springs[0].free_length) == pytest.approx(l - T0 / k, rel=1e-15)
    assert set(report) == {"iterations", "residual", "q"}
    np.testing.assert_allclose(report["q"], [0.0, (T0 - mass * g) / k], rtol=0, atol=1e-12)
    assert report["residual"] <= 1e-10 and 1 <= report["iterations"] <= 3
    num = numeric.assemble(found)
    ls = l - T0 / k + mass * g / k
    assert num.tensions["s"] == pytest.approx(mass * g, rel=1e-10)
    w2 = np.linalg.eigvalsh(np.linalg.solve(num.a.toarray(), num.c.toarray()))
    expected = sorted([k / mass, g / ls] if effects is None else [k / mass, 0.0])
    np.testing.assert_allclose(np.sort(w2), expected, rtol=1e-9, atol=1e-12)


def test_stiff_spring_converges_relative_to_its_stiffness():
    """k = 1e7 N/m, m = 100 kg: the residual of rounding (~1e-13 N) is far below 1e-10 of the
    stiffness scale; l* = l0 + m g/k."""
    k, mass, l, l0, g = 1e7, 100.0, 0.5, 0.45, 9.81
    found, report = numeric.solve_equilibrium(hanging(k, mass, l, None, free_length=l0))
    assert report["q"][1] == pytest.approx(l - (l0 + mass * g / k), rel=1e-9)


def test_search_with_a_singular_tangent():
    """A free slide (no stiffness, no load) beside the spring: the tangent diag(0, k) is singular;
    least squares steps only along y."""
    k, mass, l, l0, g = 50.0, 2.0, 0.5, 0.3, 9.81
    d = {"parameters": {"g": param(g, "m/s^2")},
         "coordinates": [{"name": "z", "type": "slide", "axis": [0, 0, 1]}, {"name": "y", "type": "slide", "axis": [0, 1, 0]}],
         "points": [{"name": "O", "at": [0, 0, 0]}, {"name": "Z", "from": "O", "vector": [1, 0, 0], "slides": ["z"]},
                    {"name": "P", "from": "O", "vector": [0, -l, 0], "slides": ["y"]}],
         "bodies": [{"name": "puck", "mass": 1.0, "com": "Z"}, {"name": "bob", "mass": mass, "com": "P"}],
         "springs": [{"name": "s", "ends": ["O", "P"], "stiffness": k, "free_length": l0}], "gravity": {"g": "g"}}
    found, report = numeric.solve_equilibrium(mech(d))
    np.testing.assert_allclose(report["q"], [0.0, l - (l0 + mass * g / k)], rtol=0, atol=1e-12)


def torsion_pendulum(mass, l, g, k, th0, **preload):
    """Bob m on a massless rod l drawn at th0 from the downward vertical, torsion spring k to ground."""
    return mech({"parameters": {"g": param(g, "m/s^2")},
                 "coordinates": [{"name": "phi", "type": "angle"}],
                 "points": [{"name": "O", "at": [0, 0]},
                            {"name": "B", "from": "O", "vector": [l * math.sin(th0), -l * math.cos(th0)], "turns": ["phi"]}],
                 "bodies": [{"name": "bob", "mass": mass, "com": "B"}],
                 "torsion_springs": [{"name": "t", "bodies": ["ground", "bob"], "stiffness": k, **preload}],
                 "gravity": {"g": "g"}})


def test_unpreloaded_torsion_spring_keeps_its_free_angle():
    """Pendulum (bob m, rod l) drawn at th0, torsion spring k free in the drawn position:
    m g l sin(th0 + phi) + k phi = 0."""
    mass, l, g, k, th0 = 1.5, 0.8, 9.81, 12.0, 0.6
    found, report = numeric.solve_equilibrium(torsion_pendulum(mass, l, g, k, th0))
    phi = scipy.optimize.brentq(lambda p: mass * g * l * math.sin(th0 + p) + k * p, -1.5, 0.0, xtol=1e-15)
    assert report["q"][0] == pytest.approx(phi, abs=1e-9)
    assert float(found.torsion_springs[0].preload) == pytest.approx(k * phi, rel=1e-8)


def test_equilibrium_preloads_and_zero_stiffness_are_refused_by_name():
    with pytest.raises(SymmechError) as err:
        numeric.solve_equilibrium(hanging(1.0, 0.01, 0.4, "equilibrium"))
    assert str(err.value) == ("spring 's': equilibrium.solve needs a preload value or a free length, "
                              "not preload = \"equilibrium\"")
    with pytest.raises(SymmechError) as err:
        numeric.solve_equilibrium(hanging(0.0, 0.01, 0.4, 0.05))
    assert str(err.value) == "spring 's': a preloaded spring of zero stiffness has no free length"
    with pytest.raises(SymmechError) as err:
        numeric.solve_equilibrium(torsion_pendulum(1.5, 0.8, 9.81, 12.0, 0.6, preload="equilibrium"))
    assert str(err.value) == "torsion spring 't': equilibrium.solve needs a preload value, not preload = \"equilibrium\""


def damped_pair(k=(400.0, 400.0), c=(4.0, 16.0), masses=(1.0, 1.0), coupled=False):
    """Two masses on x and y slides, each on its own spring and damper to ground (uncoupled), or
    (``coupled``) a free pair joined by spring k[0] and damper c[0] along x."""
    pts = [{"name": "O", "at": [0, 0]}, {"name": "A", "from": "O", "vector": [1, 0], "slides": ["u"]}]
    if coupled:
        pts.append({"name": "B", "from": "O", "vector": [2, 0], "slides": ["v"]})
        springs = [{"name": "k", "ends": ["A", "B"], "stiffness": k[0]}]
        dampers = [{"name": "c", "ends": ["A", "B"], "viscosity": c[0]}]
        axis_v = [1, 0]
    else:
        pts += [{"name": "B", "from": "O", "vector": [0, 1], "slides": ["v"]}]
        springs = [{"name": "ka", "ends": ["O", "A"], "stiffness": k[0]}, {"name": "kb", "ends": ["O", "B"], "stiffness": k[1]}]
        dampers = [{"name": "ca", "ends": ["O", "A"], "viscosity": c[0]}, {"name": "cb", "ends": ["O", "B"], "viscosity": c[1]}]
        axis_v = [0, 1]
    num = numeric.assemble(mech({
        "coordinates": [{"name": "u", "type": "slide", "axis": [1, 0]}, {"name": "v", "type": "slide", "axis": axis_v}],
        "points": pts, "bodies": [{"name": "a", "mass": masses[0], "com": "A"}, {"name": "b", "mass": masses[1], "com": "B"}],
        "springs": springs, "dampers": dampers}))
    return numeric.modes(num.a.toarray(), num.b.toarray(), num.c.toarray())


def test_repeated_frequency_with_two_damping_ratios():
    """Equal omega = 20 rad/s, zeta = c/(2 sqrt(k m)) = 0.1 and 0.4: each root is matched once."""
    md = damped_pair()
    assert sorted(md.zeta) == pytest.approx([0.1, 0.4], rel=1e-9)


def test_overdamped_mode_below_an_underdamped_one():
    """omega_a = 10 rad/s with zeta 2.5 (real roots), omega_b = 20 rad/s with zeta 0.1."""
    md = damped_pair(k=(100.0, 400.0), c=(50.0, 4.0))
    assert md.zeta[0] is None and md.zeta[1] == pytest.approx(0.1, rel=1e-9)


def test_free_pair_damping_ratio_beside_the_rigid_mode():
    """A free pair: rigid drift, then omega^2 = k/mu, zeta = c/(2 sqrt(k mu)), mu = m1 m2/(m1 + m2)."""
    k, c, m1, m2 = 300.0, 6.0, 1.0, 2.0
    md = damped_pair(k=(k, 0.0), c=(c, 0.0), masses=(m1, m2), coupled=True)
    mu = m1 * m2 / (m1 + m2)
    assert md.kinds == ["rigid", "elastic"]
    assert md.zeta[0] is None and md.zeta[1] == pytest.approx(c / (2 * math.sqrt(k * mu)), rel=1e-9)


def test_search_tangent_keeps_gravity_the_scene_drops():
    """A pendulum drawn at th0 whose scene drops gravity from the matrices: its only stiffness is
    gravity's, and the search still hangs it straight down (phi = -th0), step for step as the same
    pendulum whose scene keeps gravity (the first tangent too)."""
    th0, l = 0.5, 0.8

    def pendulum(gravity):
        return mech({"parameters": {"g": param(9.81, "m/s^2")},
                     "coordinates": [{"name": "phi", "type": "angle"}],
                     "points": [{"name": "O", "at": [0, 0]},
                                {"name": "B", "from": "O", "vector": [l * math.sin(th0), -l * math.cos(th0)],
                                 "turns": ["phi"]}],
                     "bodies": [{"name": "bob", "mass": 1.0, "com": "B"}],
                     "gravity": {"g": "g"}, "effects": {"gravity": gravity}})
    _, report = numeric.solve_equilibrium(pendulum(False))
    assert report["q"][0] == pytest.approx(-th0, abs=1e-10)
    assert report == numeric.solve_equilibrium(pendulum(True))[1]


def test_search_out_of_steps_is_refused_with_the_residual():
    """No Newton step allowed: the refusal names the count and the residual |T0 - m g| = 0.0481 N."""
    with pytest.raises(SymmechError) as err:
        numeric.solve_equilibrium(hanging(1.0, 0.01, 0.4, 0.05), max_iter=0)
    assert str(err.value) == ("equilibrium search did not converge in 0 Newton steps (residual 0.0481); "
                              "give the equilibrium configuration in the scene")


def test_line_search_refuses_a_step_that_only_matches_the_residual():
    """Rod l = 1 m drawn horizontal, m g l = pi/2 N m, torsion spring k = 1 N m/rad free hanging down
    (preload k pi/2): with th = pi/2 + phi, k th + m g l sin(th) = 0 has the one root th = 0, phi = -pi/2. The first
    Newton step -(k pi/2 + m g l)/k = -pi lands on the mirror image, whose residual -pi equals the start's
    bit for bit (cos(pi) = -1 exactly): a step that does not lower the residual is halved, and the half step
    lands on the equilibrium (torsion moment 0, lever arm cos(pi/2) ~ 6e-17 m) in one iteration."""
    m = mech({"parameters": {"g": param(math.pi / 2, "m/s^2")},
              "coordinates": [{"name": "phi", "type": "angle"}],
              "points": [{"name": "O", "at": [0, 0]}, {"name": "B", "from": "O", "vector": [1, 0], "turns": ["phi"]}],
              "bodies": [{"name": "bob", "mass": 1.0, "com": "B"}],
              "torsion_springs": [{"name": "t", "bodies": ["ground", "bob"], "stiffness": 1.0, "preload": math.pi / 2}],
              "gravity": {"g": "g"}})
    _, report = numeric.solve_equilibrium(m)
    assert report["iterations"] == 1 and report["residual"] <= 1e-15
    assert report["q"][0] == pytest.approx(-math.pi / 2, abs=1e-15)
