"""`[elastic.initial]`, the state of the elastic coordinates at t = 0.

Free vibrations of a trolley at rest on a straight level track (no gravity, rigid rollers
unless said): a beam started in one of its own modes vibrates in that mode alone, so the
frequency of its report point is the `modes` table's, its decay the damping ratio given;
roller offsets deflect the rollers as the small-rotation kinematics of the contact points
(B at x3 = -a, C at +a, A at x1 = l along x2; O and A along x3) says.
"""
import copy

import numpy as np
import pytest
from scipy.interpolate import CubicSpline
from scipy.special import ellipk

from symmech.core import pipeline
from symmech.core.context import Context
from symmech.core.scene import SceneError
from trolley_util import setup

MAST = {"root": [0.5, 0.5, 0.0], "axis": [0, 1, 0], "plane": [1, 0, 0], "length": 1.5, "mass_per_length": 4.0,
        "ei": [2e4, 3e4], "tip_mass": 2.0}


def scene(beams=(MAST,), initial=None, t_end=0.5, steps=200, effects=None, **numerics):
    data = setup(trolley={"mass": 100.0, "com": [0.0, 0.0, 0.0], "inertia": [10.0, 20.0, 15.0, 0, 0, 0],
                          "axle_distance": 2.0, "half_gauge": 0.7},
                 motion={"speed": "0"}, time={"t_end": t_end, "steps": steps}, effects={"gravity": False})
    data["elastic"] = {"effects": effects or {"rollers": False}, "beams": [dict(b) for b in beams],
                       "points": [{"name": "tip", "beam": 0, "xi": 1.0}] if beams else [],
                       "initial": initial or {}, "numerics": {"modal_samples": 2, "rtol": 1e-9, **numerics}}
    return data


def run(data):
    return pipeline.load(copy.deepcopy(data)).run(Context(quiet=True))


def crossings(t, x):
    """Upward zero crossings [s] of the sampled signal x(t): roots of its cubic spline (error ~h⁴)."""
    spline = CubicSpline(t, x)
    roots = spline.roots(extrapolate=False)
    return roots[spline(roots, 1) > 0]


def peaks(t, x):
    """Maxima (times [s], values) of the sampled signal x(t) from its cubic spline, away from
    its ends (where the spline's end conditions, not the data, fix the slope)."""
    spline = CubicSpline(t, x)
    at = spline.derivative().roots(extrapolate=False)
    at = at[(spline(at, 2) < 0) & (at > t[5]) & (at < t[-6])]
    return at, spline(at)


def test_a_beam_started_in_its_first_mode_vibrates_at_the_modes_table_frequency():
    """Mast with a tip mass, first mode of plane 1 (x1) at 0.1 mm: the tip starts at exactly
    that deflection (the first mode is largest at the tip), plane 2 stays at rest, and the
    frequency from the zero crossings equals the `modes` table's f1 to 1e-7 (measured 9e-9:
    the amplitude dependence of the shortening, ~(a/L)², is ~1e-9 at this amplitude)."""
    res = run(scene(initial={"beams": [{"beam": 0, "plane": 1, "amplitude": 1e-4}]}))
    tip = res.tables["points"]
    t, e1 = tip.column("t"), tip.column("tip_e1")
    assert e1[0] == pytest.approx(1e-4, rel=1e-12)
    assert np.abs(tip.column("tip_e3")).max() < 1e-15
    up = crossings(t, e1)
    assert len(up) >= 5
    modes = res.tables["modes"]
    f1 = modes.column("f")[modes.column("mode_id") == 1]
    assert f1[0] == f1[1]
    assert (len(up) - 1) / (up[-1] - up[0]) == pytest.approx(f1[0], rel=1e-7)


def test_a_damped_beam_mode_decays_at_the_damping_ratio():
    """ζ = 0.05 on the mast (stiffness-proportional, exact for the first mode): the `modes`
    table gives ζ1 = 0.05, and the free vibration started in that mode has the logarithmic
    decrement 2πζ/√(1 - ζ²) between successive peaks and the damped frequency f1 √(1 - ζ²)
    (to 2e-5 and 1e-7; measured 1e-6, 7e-10), from the peaks and the zero crossings."""
    zeta = 0.05
    res = run(scene(beams=({**MAST, "damping_ratio": zeta},),
                    initial={"beams": [{"beam": 0, "plane": 1, "amplitude": 1e-4}]}))
    modes = res.tables["modes"]
    first = modes.column("mode_id") == 1
    assert modes.column("zeta")[first][0] == pytest.approx(zeta, rel=1e-9)
    tip = res.tables["points"]
    at, value = peaks(tip.column("t"), tip.column("tip_e1"))
    assert len(at) >= 4
    decrement = np.log(value[:-1] / value[1:])
    np.testing.assert_allclose(decrement, 2 * np.pi * zeta / np.sqrt(1 - zeta**2), rtol=2e-5)
    up = crossings(tip.column("t"), tip.column("tip_e1"))  # as periodic as the peaks, and sharper
    f_damped = (len(up) - 1) / (up[-1] - up[0])
    assert f_damped == pytest.approx(modes.column("f")[first][0] * np.sqrt(1 - zeta**2), rel=1e-7)


def test_roller_offsets_deflect_the_rollers_as_the_contact_points_move():
    """Offsets u2, u3, θ1, θ2, θ3 and no gravity (quasi-static state q = 0): the roller
    deflections at t = 0 are the components of u + θ × r at B (0, 0, -a), C (0, 0, a),
    A (l, 0, 0) along x2 and at O (0, 0, 0), A along x3, l = 2 m, a = 0.7 m (1e-15 m)."""
    u = np.array([0.0, 1e-3, -2e-3])  # u1 is not a coordinate (the motion along x1 is prescribed)
    theta = np.array([3e-3, -4e-3, 5e-3])
    data = scene(beams=(), initial={"rollers": [*u[1:], *theta]}, t_end=0.01, steps=2, modal_samples=0)
    data["elastic"]["effects"] = {"rollers": True}
    data["elastic"]["rollers"] = {"stiffness": [1e6] * 5}
    d = run(data).tables["roller_deflections"].data[0, 1:]
    l, a = 2.0, 0.7
    contacts = [((0, 0, -a), 1), ((0, 0, a), 1), ((l, 0, 0), 1), ((0, 0, 0), 2), ((l, 0, 0), 2)]
    expected = [(u + np.cross(theta, r))[axis] for r, axis in contacts]
    np.testing.assert_allclose(d, expected, rtol=0, atol=1e-15)


@pytest.mark.slow  # ~40 s on a shared core: the stretched strip takes ~15000 evaluations
def test_a_held_beam_started_at_a_large_amplitude_follows_the_duffing_backbone():
    """A steel strip (2 m, 20 x 10 mm) between immovable pins started in its first mode at a
    mid-span deflection of twice its radius of gyration r: membrane stretching stiffens it, and
    the frequency from the scene's report point is the single-mode Duffing oscillator's
    ω/ω0 = π √(1 + ε) / (2 K(ε / (2(1 + ε)))), ε = (â/r)²/4 = 1, over the `modes` table's
    linear f1 (to 1e-4; measured 9.5e-6, the residue of 5 Ritz functions against sin πξ, as in
    tests/test_trolley_membrane.py)."""
    length, rho, young, width, height = 2.0, 7800.0, 2.1e11, 0.02, 0.01
    area, inertia = width * height, width * height**3 / 12
    gyration = np.sqrt(inertia / area)
    strip = {"root": [0.0, 0.0, 0.0], "axis": [0, 0, 1], "plane": [1, 0, 0], "length": length,
             "mass_per_length": rho * area, "ei": [young * inertia] * 2, "support": "pinned", "modes": 5,
             "axial": "held", "ea": young * area}
    data = scene(beams=(strip,), initial={"beams": [{"beam": 0, "plane": 1, "amplitude": 2 * gyration}]},
                 t_end=0.4, steps=160)
    data["elastic"]["points"] = [{"name": "mid", "beam": 0, "xi": 0.5}]
    res = run(data)
    mid = res.tables["points"]
    assert mid.column("mid_e1")[0] == pytest.approx(2 * gyration, rel=1e-12)
    up = crossings(mid.column("t"), mid.column("mid_e1"))
    ratio = (len(up) - 1) / (up[-1] - up[0]) / res.tables["modes"].column("f")[0]
    eps = 1.0
    assert ratio == pytest.approx(np.pi * np.sqrt(1 + eps) / (2 * ellipk(eps / (2 * (1 + eps)))), rel=1e-4)
    assert ratio > 1.3


@pytest.mark.parametrize("effects, initial, field", [
    ({"rollers": False}, {"rollers": [1e-3, 0, 0, 0, 0]}, "elastic.initial.rollers"),
    ({"rollers": False}, {"roller_rates": [0, 0, 0.1, 0, 0]}, "elastic.initial.roller_rates"),
    ({"rollers": False, "body": False}, {"beams": [{"beam": 0, "plane": 1, "amplitude": 1e-3}]},
     "elastic.initial.beams[0]"),
])
def test_initial_state_of_a_rigid_part_is_refused(effects, initial, field):
    with pytest.raises(SceneError) as err:
        pipeline.load(scene(initial=initial, effects=effects))
    assert err.value.field == field


def test_cli_refuses_a_bad_initial_state_in_one_line(tmp_path):
    from badinput import cli_rejects

    text = """kind = "trolley"
[track]
type = "expression"
x = "s"
y = "0"
z = "0"
[trolley]
mass = 100.0
com = [0.0, 0.0, 0.0]
inertia = [10.0, 20.0, 15.0, 0.0, 0.0, 0.0]
axle_distance = 2.0
half_gauge = 1.0
[motion]
speed = "0"
[time]
t_end = 0.1
steps = 2
[elastic.effects]
rollers = false
[[elastic.beams]]
root = [0.0, 0.0, 0.0]
axis = [0, 1, 0]
plane = [1, 0, 0]
length = 1.5
mass_per_length = 4.0
ei = [2e4, 3e4]
[[elastic.initial.beams]]
beam = 0
plane = 1
amplitude = 0.5
"""
    line = cli_rejects(tmp_path, text, "elastic.initial.beams[0].amplitude")
    assert "[-0.15, 0.15] m" in line
