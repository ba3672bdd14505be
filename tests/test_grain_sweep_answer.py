"""A grain sweep's decision on hand-built statistics: the constraints, a failed or warned grain each exclude a
point with its reason; the best point is the least overlap among the eligible points only."""
import numpy as np
import pytest

from symmech.grain import sweep, sweep_report

# a 2 x 2 plane, x-major: points 0 (0, 0), 1 (0, 1), 2 (1, 0), 3 (1, 1)
CROP = {"mean_vx": np.array([[0.005, 0.03], [0.04, 0.05]]), "hop_fraction": np.array([[0.0, 0.2], [0.95, 0.5]])}
WEED = {"mean_vx": np.array([[0.0, 0.0], [0.0, 0.0]]), "hop_fraction": np.array([[1.0, 1.0], [1.0, 1.0]])}
CONSTRAINTS = {"population": "crop", "min_mean_vx": 0.02, "hop_fraction_min": None, "hop_fraction_max": 0.9}


def test_constraints_and_warned_grains_exclude_points_with_their_reason():
    warned = [("weed", 1, 1, 4, ["2 rocking contact(s): ..."])]
    why = sweep_report.reasons(["crop", "weed"], [CROP, WEED], CONSTRAINTS, [], warned, (2, 2))
    # point 0: 5 mm/s < 20 mm/s; point 2: hop fraction 0.95 > 0.9; point 3: a warned weed grain; the weed's own
    # hop fraction of 1 is not constrained (the constraints name the crop)
    assert [[label for label, _ in w] for w in why] == [["too slow"], [], ["hops"], ["warned grain"]]
    assert why[0][0][1] == "crop moves at 5 mm/s < 20 mm/s" and why[3][0][1].startswith("weed grain 4: 2 rocking")


def test_the_best_point_is_the_least_overlap_among_the_eligible_points():
    """Overlaps 0.1, 0.4, 0.05, 0.2: the least (point 2) is not eligible, so the best is point 0 (0.1)."""
    sep = {"overlap": np.array([[0.1, 0.4], [0.05, 0.2]]), "delta_vx": np.zeros((2, 2)),
           "overlap_lo": np.array([[0.05, 0.3], [0.01, 0.15]]), "overlap_hi": np.array([[0.15, 0.5], [0.1, 0.3]])}
    ok = np.array([True, True, False, True])
    best, similar = sweep.best_point(sep, ok)
    # not significantly worse: an eligible point whose interval's lower end is at most the best's upper end 0.15
    assert best == 0 and similar.tolist() == [[True, False], [False, True]]
    assert sweep.best_point(sep, np.zeros(4, bool)) == (None, None)
    # one population: the fastest eligible transport
    assert sweep_report.best(np.array([True, True, False, False]), ["crop"], [CROP], None) == 1


def test_one_population_needs_grains_for_its_mean_not_for_a_difference():
    """With one population there is no Δv_x: the grains needed are for its mean X velocity at the best point."""
    why = [[], [], [("hops", "crop's hop fraction 0.95 outside [0, 0.9]")], []]
    stats = [{**CROP, "mean_vx_lo": CROP["mean_vx"] - 0.001, "mean_vx_hi": CROP["mean_vx"] + 0.001}]
    axes = [("vibration amplitude", "m", False), ("vibration frequency", "Hz", False)]
    values = [np.array([1e-3, 2e-3]), np.array([20.0, 30.0])]
    precision = {"delta_vx_at_best": {"spread_m_s": 0.01, "grains_needed": 385}}
    headline, *_ = sweep_report.answer(axes, values, why, 3, ["crop"], stats, None, precision, 1e-3)
    needed = next(h for h in headline if h.name == "grains per population needed")
    assert needed.value == 385 and needed.meaning == "for crop's mean X velocity at the best point to ± 1 mm/s (95 %)"
    assert not any("Δv_x" in h.name or "Δv_x" in h.meaning for h in headline)


def test_a_sweep_along_one_axis_draws_lines_with_the_same_best_point(monkeypatch, tmp_path):
    """One swept field: a line chart per quantity (before: none), each starring the best point at its own value,
    shading the eligible points' cells, labelling the others, and staying within the swept range."""
    from symmech.core import plotting

    drawn = {}
    monkeypatch.setattr(plotting, "save", lambda fig, folder, stem, formats=("png",): drawn.setdefault(stem, fig)
                        and [tmp_path / f"{stem}.png"])
    xs = np.array([1e-3, 2e-3, 3e-3])
    speed, hops = np.array([[0.01], [0.03], [0.05]]), np.array([[0.0], [0.2], [0.9]])
    why = [[("too slow", "crop moves at 10 mm/s < 20 mm/s")], [], [("hops", "crop's hop fraction 0.90 ...")]]
    charts = [("crop_mean_vx", speed, "crop: mean transport velocity", "m/s", False),
              ("crop_hop_fraction", hops, "crop: fraction of grains hopping", "1", False)]
    files = sweep_report.plots([("vibration amplitude", "m", False)], [xs], None, charts, why, 1, tmp_path)
    assert [f.name for f in files] == ["crop_mean_vx.png", "crop_hop_fraction.png"]
    for stem, z, *_ in charts:
        ax = drawn[stem].axes[0]
        curve, star = ax.get_lines()
        np.testing.assert_array_equal(curve.get_ydata(), z.ravel())
        assert (star.get_xdata()[0], star.get_ydata()[0]) == (2e-3, z[1, 0])  # the same point on every chart
        shaded = [p.get_x() for p in ax.patches]  # the eligible cell: halfway to the neighbouring values
        assert shaded == pytest.approx([1.5e-3])
        assert [t.get_text() for t in ax.texts] == ["too slow", "hops"]
        assert ax.get_xlim() == pytest.approx((1e-3, 3e-3))  # the end cells end at the swept values
