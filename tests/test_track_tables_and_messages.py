"""Track tables and parametrised tracks at their edges, by hand: the turn limit is inclusive (docs/scenes-trolley.md:
max_turn_deg in (0, 90]), collinear points whose unit directions dot to 1 + 2^-52 are no turn, a kink is named with
its angle and point, a table without interior samples reports no curvature, and each refusal names its field, the
value and the rule in one line.

Expected values are written out: the angle between (1, 1, 1) and (0, 0, 2) is acos(1/sqrt 3) = 54.7356 deg, a
straight table of n unit segments is n m long.
"""
import math
import re

import numpy as np
import pytest

from symmech.core import expressions
from symmech.core.scene import SceneError
from symmech.trolley import track


def test_a_turn_of_exactly_max_turn_deg_is_allowed():
    """A right-angle corner (segments along x, then y: cos = 0 exactly, 90.0 deg) under max_turn_deg = 90."""
    points = [(0, 0, 0), (1, 0, 0), (2, 0, 0), (3, 0, 0), (3, 1, 0), (3, 2, 0), (3, 3, 0)]
    table = track.TableTrack(points, "track.points", 90.0)
    assert 6.0 * 0.95 < table.length < 6.0 * 1.05  # about the polyline's 6 m


def test_a_kink_after_collinear_points_is_refused_with_its_angle_and_point():
    """Points along (1, 1, 1), whose unit directions dot to 1 + 2^-52 (no turn, not NaN), then a turn to +z at
    point 3 by acos(1/sqrt 3) = 54.7 deg, above max_turn_deg = 20."""
    diagonal = np.array([(0, 0, 0), (1, 1, 1), (2, 2, 2)], float)
    d = np.diff(diagonal, axis=0) / np.linalg.norm(np.diff(diagonal, axis=0), axis=1)[:, None]
    assert d[0] @ d[1] > 1.0  # the rounding this test is about
    points = [(0, 0, 0), (1, 1, 1), (2, 2, 2), (3, 3, 3), (3, 3, 5), (3, 3, 7), (3, 3, 9)]
    angle = math.degrees(math.acos(1 / math.sqrt(3)))
    assert f"{angle:.1f}" == "54.7"
    expected = ("scene field 'track.points': track is not smooth: it turns by 54.7 deg at point 3 "
                "(max_turn_deg = 20); add points or smooth the table")
    with pytest.raises(SceneError) as refused:
        track.TableTrack(points, "track.points", 20.0)
    assert str(refused.value) == expected


def test_leaving_a_table_is_refused_with_the_range_and_the_length():
    """A straight table of five unit segments is 5 m long; s from -1 to 5 m leaves it, s from 0 to its very end
    (its length) does not."""
    table = track.TableTrack([(k, 0, 0) for k in range(6)], "track.points", 20.0)
    assert table.length == pytest.approx(5.0, rel=1e-12)
    table.check_domain("track", 0.0, table.length)
    with pytest.raises(SceneError) as refused:
        table.check_domain("track", -1.0, 5.0)
    assert str(refused.value) == ("scene field 'motion.speed': the motion leaves the track table: s from -1 to 5 m "
                                  "(with the front axle in case 2), track length 5 m")


def test_a_table_without_interior_samples_reports_no_curvature():
    """Six collinear points with points 2 and 3 1 mm apart: the 120 samples of the fit (4/119 m apart) put none
    strictly between them, the interior where the curvature is judged, so its error and maximum read 0.

    Then a bent table whose sample 80 lies exactly on point 2: chords 5, 5 (along (3, 4) and (4, 3)), 1/8, 3/4
    and 4 m, exact in binary, 119/8 m in all, so its 120 samples are 1/8 m apart, sample 80 is at u = 10 m = point
    2 and sample 81 at point 3. The interior's edge is not inside it: the bent fit's curvature at point 2 (not 0)
    is not judged, and the table still reports no curvature."""
    points = [(0, 0, 0), (1, 0, 0), (2, 0, 0), (2.001, 0, 0), (3, 0, 0), (4, 0, 0)]
    fine = np.linspace(0.0, 4.0, 120)
    assert not np.any((fine > 2.0) & (fine < 2.001))
    noise = track.TableTrack(points, "track.points", 20.0).noise
    assert noise["curvature_error_per_m"] == 0.0 and noise["curvature_max_per_m"] == 0.0
    assert noise["curvature_overshoot"] == 0.0
    bent = [(0, 0, 0), (3, 4, 0), (7, 7, 0), (7.125, 7, 0), (7.875, 7, 0), (11.875, 7, 0)]
    fine = np.linspace(0.0, 14.875, 120)
    assert fine[80] == 10.0 and fine[81] == 10.125
    noise = track.TableTrack(bent, "track.points", 90.0).noise
    assert noise["curvature_error_per_m"] == 0.0 and noise["curvature_max_per_m"] == 0.0
    assert noise["curvature_overshoot"] == 0.0


def test_a_tables_noise_estimates_do_not_depend_on_the_direction_it_is_listed_in():
    """Ten unit chords turning by -5 deg after the first and by -5 deg twice at the end, listed forwards and
    backwards: the same curve, so the same curvature overshoot, at the same place (chord length u from one end,
    10 m - u from the other), to round-off.
    The overshoot is judged against the three-point curvature of the two points either side of each sample, a
    neighbourhood symmetric under the reversal."""
    heading = np.radians(np.cumsum([0, -5, 0, 0, 0, 0, 0, 0, -5, -5]))
    chords = np.stack([np.cos(heading), np.sin(heading), np.zeros(10)], axis=-1)
    points = np.concatenate([np.zeros((1, 3)), np.cumsum(chords, axis=0)])
    ahead = track.TableTrack(points, "track.points", 20.0).noise
    back = track.TableTrack(points[::-1], "track.points", 20.0).noise
    assert ahead["curvature_overshoot"] > 0.05
    assert back["curvature_overshoot"] == pytest.approx(ahead["curvature_overshoot"], rel=1e-9)
    assert back["curvature_max_per_m"] == pytest.approx(ahead["curvature_max_per_m"], rel=1e-9)
    assert back["overshoot_near_m"] == pytest.approx(10.0 - ahead["overshoot_near_m"], abs=1e-9)


def test_a_parameter_whose_speed_vanishes_is_refused_where_it_does():
    """X0(u) = (u^3, 0, 0) on [-1, 1]: |dX0/du| = 3 u^2 is zero at u = 0, a node of the arc length's grid."""
    with pytest.raises(SceneError) as refused:
        track.ArcLength(lambda u: 3.0 * np.square(u), -1.0, 1.0, "track.u_range")
    assert str(refused.value) == ("scene field 'track.u_range': dX0/du vanishes at u = 0: the parametrization is "
                                  "singular there")


def test_arc_length_inverse_of_a_track_whose_speed_grows():
    """|dX0/du| = 2 u on [1, 2] (X0 = (u², 0, 0)): s(u) = u² - 1, u(s) = √(s + 1), to round-off after the Newton
    steps from the table's linear interpolation (h = 1/4000: an error of ~1e-8 before them)."""
    arc = track.ArcLength(lambda u: 2 * np.asarray(u, float), 1.0, 2.0, "track")
    s = np.array([0.0, 0.1234, 1.5, 2.9, 3.0])
    assert arc.length == pytest.approx(3.0, rel=1e-14)
    np.testing.assert_allclose(arc.parameter(s), np.sqrt(s + 1), rtol=0, atol=1e-13)


def test_a_table_that_loops_back_onto_itself_is_refused_where_it_does():
    """30 samples of a vertical circle of radius 1 m over 2 pi + 0.6 rad: the track passes its start again one turn,
    2 pi m of arc, later (far more than 4 of its 300 dense samples' spacing, far less than 4 / spacing), and the
    refusal names the two arc lengths where it does."""
    points = [(math.cos(a), 0.0, math.sin(a)) for a in np.linspace(0.0, 2 * math.pi + 0.6, 30)]
    with pytest.raises(SceneError, match=r"^scene field 'track.points': track intersects itself near s = ") as err:
        track.TableTrack(points, "track.points", 30.0)
    first, second = (float(x) for x in re.findall(r"s = ([0-9.e+-]+) m", str(err.value)))
    assert abs(second - first - 2 * math.pi) < 0.05


def test_a_twist_singular_on_the_ride_is_refused_in_its_own_field_and_metres():
    """θ1(s) = 1 / (s - 2) on a ride over [0, 5] m is infinite at s = 2 m: the refusal names the twist's field and the
    arc length in metres."""
    line = track.Track()  # the base's twist check, without a midline's own
    line.twist_expr = expressions.parse("track.twist", "1/(s - 2)", ("s",), {})
    with pytest.raises(SceneError, match=r"^scene field 'track.twist': '1/\(s - 2\)' is infinite or overflows at "
                                         r"s = 2 m \(domain \[0, 5\]\)$"):
        line.check_domain("track", 0.0, 5.0)


def test_coinciding_points_are_refused_by_their_numbers():
    points = [(0, 0, 0), (1, 0, 0), (2, 0, 0), (2, 0, 0), (3, 0, 0)]
    with pytest.raises(SceneError, match=r"^scene field 'track.points': points 2 and 3 coincide; a track table needs"):
        track.TableTrack(points, "track.points", 20.0)


def test_a_twist_reads_the_scenes_constants():
    """[track] twist = "c*s" with constants c = 0.25 rad/m on a straight table: θ1 = c s, θ1' = c, θ1'' = 0."""
    line = track.build({"type": "table", "points": [(k, 0, 0) for k in range(6)], "max_turn_deg": 20.0,
                        "smoothing": 0.0, "twist": "c*s", "constants": {"c": 0.25}})
    theta, rate, curl = line.twist(np.array([2.0, 4.0]))
    np.testing.assert_allclose(theta, [0.5, 1.0], rtol=1e-15)
    np.testing.assert_allclose(rate, [0.25, 0.25], rtol=1e-15)
    np.testing.assert_array_equal(curl, [0.0, 0.0])


def test_a_smoothed_table_stays_within_its_smoothing_of_its_points():
    """Twelve points 1 m apart along x, zigzagging by ±2 cm, smoothed to 1 cm: the fit is the smoothest within an RMS
    distance of 1 cm of them (splprep's sum of squares n σ²), so the RMS of the points' distances to the track is
    1 cm, to 10 % (its dense samples 3 mm apart); the zigzag itself is 2 cm off the straight line."""
    points = np.array([(float(k), 0.02 * (-1) ** k, 0.0) for k in range(12)])
    table = track.TableTrack(points, "track.points", 20.0, 0.01)
    midline = table.derivatives(np.linspace(0.0, table.length, 4001), 0)[0]
    distance = np.linalg.norm(midline[None, :, :] - points[:, None, :], axis=-1).min(axis=1)
    assert 0.009 < math.sqrt(np.mean(distance ** 2)) < 0.011


def test_a_midline_undefined_on_the_ride_is_refused_in_its_coordinates_field():
    """y(s) = sqrt(5 - s) on a ride over [0, 6] m is undefined past s = 5 m: the refusal names track.y (x and z are
    defined there) in metres."""
    line = track.build({"type": "expression", "x": "s", "y": "sqrt(5 - s)", "z": "0", "parameter": "s", "twist": "0"})
    with pytest.raises(SceneError, match=r"^scene field 'track.y': 'sqrt\(5 - s\)' is undefined or complex at s = 5 m"):
        line.check_domain("track", 0.0, 6.0)


def test_single_precision_stations_are_read_as_doubles():
    """The paper's helix (R = 2 m, λ = 0.5 m) at stations given in float32: X0 and its derivatives are those of the
    stations' exact values, R cos φ, R sin φ, λ φ with φ = s / √(R² + λ²), to round-off (a float32 evaluation
    would be off by ~1e-7)."""
    helix = track.build({"type": "helix", "radius": 2.0, "rise": 0.5, "twist": "0"})
    s = np.array([0.1, 1.3, 7.7], np.float32)
    root = math.sqrt(2.0**2 + 0.5**2)
    phi = s.astype(float) / root
    rise = (0.5 * phi, np.full(3, 0.5 / root), np.zeros(3))  # λ φ and its derivatives in s
    for k, value in enumerate(helix.derivatives(s, 2)):
        turn = phi + k * np.pi / 2  # d/ds of cos φ and sin φ: a quarter turn and a factor 1 / √(R² + λ²)
        exact = np.stack([2.0 * np.cos(turn) / root**k, 2.0 * np.sin(turn) / root**k, rise[k]], axis=-1)
        np.testing.assert_allclose(value, exact, rtol=0, atol=1e-14)
