"""The paper's helix example: Tables 1 and 2 in paper conventions, default physics beside them."""
import json
from pathlib import Path

import numpy as np
import pytest

from symmech.cli import main
from symmech.core import errata
from symmech.trolley import errata as trolley_errata
from symmech.trolley import tables
from trolley_util import prepared

SCENES = Path(__file__).resolve().parents[1] / "scenes"


# its module fixture is built once per xdist worker: one worker runs the module
pytestmark = pytest.mark.xdist_group("test_trolley_paper")


@pytest.fixture(scope="module")
def paper_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("paper")
    assert main(["run", str(SCENES / "trolley_helix_paper.toml"), "--out", str(out)]) == 0
    return out, json.loads((out / "summary.json").read_text())


def test_tables_reproduced_to_printed_digits_except_one(paper_run):
    _, summary = paper_run
    rows = summary["paper_tables"]["rows"]
    assert len(rows) == 72
    misses = [r for r in rows if abs(r["paper_conventions"] - r["printed"]) > 0.5 * 10.0 ** -_decimals(r) + 1e-12]
    # The one exception: Table 2, P0, case 2 at t = 5 s is printed equal to case 1.
    assert [(r["quantity"], r["case"], r["t"]) for r in misses] == [("P0", 2, 5.0)]
    assert misses[0]["printed"] == -826.967
    assert misses[0]["paper_conventions"] == pytest.approx(-823.275, abs=5e-4)
    assert summary["paper_tables"]["reproduced"] == 71


def _decimals(row):
    for _table, q, case, t, _value, decimals in tables.entries():
        if (q, case, t) == (row["quantity"], row["case"], row["t"]):
            return decimals
    raise KeyError(row)


def test_paper_csv_columns_and_a_printed_row(paper_run):
    out, _ = paper_run
    header = (out / "case1.csv").read_text().splitlines()[0]
    assert header == ("t [s],V1 [m/s],V2 [m/s],V3 [m/s],a1 [m/s^2],a2 [m/s^2],a3 [m/s^2],"
                      "P0 [N],P1 [N],P2 [N],P3 [N],P4 [N],P5 [N]")
    data = np.loadtxt(out / "case2.csv", delimiter=",", skiprows=1)
    assert data.shape == (5001, 13)
    row = data[2500]  # t = 10 s; Table 1 and 2, case 2
    assert row[0] == pytest.approx(10.0)
    np.testing.assert_allclose(row[1:4], [22.985, -0.321, 0.044], atol=5e-4)
    np.testing.assert_allclose(row[4:7], [3.998, 3.131, -0.112], atol=5e-4)
    np.testing.assert_allclose(row[7:], [-310.563, 221.546, 186.080, 562.907, 35.466, 35.466], atol=5e-4)
    for name in ("track.png", "reactions.png", "overloads.png", "case1_overload.csv"):
        assert (out / name).stat().st_size > 0


def test_default_physics_scene_lists_both_conventions(tmp_path):
    assert main(["run", str(SCENES / "trolley_helix.toml"), "--out", str(tmp_path)]) == 0
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["conventions"] == "physics"
    row = next(r for r in summary["paper_tables"]["rows"] if (r["quantity"], r["case"], r["t"]) == ("a2", 1, 10.0))
    # Physics: normal acceleration κ V0² (κ = 0.14103 1/m, V0(10) = 23.2873 m/s) minus (κ² + ϰ²)/2 r-terms.
    v0 = 30 + 7 * np.sin(5.0)
    kappa, tau = 7 / (49 + (5 / (2 * np.pi)) ** 2), (5 / (2 * np.pi)) / (49 + (5 / (2 * np.pi)) ** 2)
    dv0 = 3 + 3.5 * np.cos(5.0)
    expected = kappa * v0**2 + kappa * dv0 * 1.0 - 0.5 * (kappa**2 + tau**2) * v0**2
    assert row["default_physics"] == pytest.approx(expected, rel=1e-9)
    # the case's acceleration extremes hold that value of a2 at t = 10 s, in m/s²
    a2 = summary["cases"]["case1"]["acceleration"]["a2"]
    assert a2["min"] <= expected <= a2["max"] and a2["unit"] == "m/s^2"
    assert row["printed"] == 3.274
    assert row["paper_conventions"] == pytest.approx(3.274, abs=5e-4)
    # the comfort checks state each case's overload range (its extremes) in g against the envelope
    extremes = summary["cases"]["case1"]["overload"]
    checks = {c["what"]: c for c in summary["checks"]}
    for k, (lo, hi) in enumerate(((-2, 2), (-1.5, 6), (-2, 2)), start=1):
        check = checks[f"case 1: overload n{k} in the comfort envelope"]
        assert check["value"] == [extremes[f"n{k}"]["min"], extremes[f"n{k}"]["max"]]
        assert (check["unit"], check["threshold"]) == ("g", f"within [{lo:g} g, {hi:g} g]")
    # the headline's critical n1 is the extreme with the smaller margin to [-2, 2] g: the minimum (-7.6 g
    # near the end of the ride, where the centre of mass ahead of O feels -κ² x1 V0²), not the +1.6 g at t = 0
    n1 = extremes["n1"]
    assert n1["min"] < -7 and 0 < 2 - n1["max"] < 0.5 and n1["t_min"] > 17
    head = next(h for h in summary["headline"] if h["name"] == "case 1: critical overload n1")
    assert (head["value"], head["unit"], head["verdict"]) == (n1["min"], "g", "fail")
    assert head["at"].startswith(f"t = {n1['t_min']:.4g} s")


def test_errata_records_for_the_trolley():
    records = {(c.equation, c.description): errata.evaluate(c) for c in trolley_errata.checks()}
    agree = [k for k, r in records.items() if r["status"] == "agrees"]
    assert ("(13)", "∂Λ/∂θ2") in agree and ("(14)", "coefficients l_ij of the system for Δθ") in agree
    omega = next(r for k, r in records.items() if k[0] == "ω (helix)")
    assert omega["status"] == "differs"
    tab = next(r for k, r in records.items() if k[1].startswith("printed entries vs paper conventions"))
    assert tab["status"] == "differs"
    assert tab["max_rel_diff"] == pytest.approx((826.967 - 823.275) / 826.967, rel=1e-3)


def test_exact_lstar_derivative_agrees_with_fine_differences():

    from symmech.trolley import model, scene

    st = prepared(tables.PAPER_EXAMPLE)
    s = np.linspace(3.0, 400.0, 40)
    sa = model.chord_point(st.track, s, st.body.l)
    exact = scene.exact_paper_lstar_derivative(st)(s, sa)
    fd = model._stencil(lambda x: model.paper_lstar(st.track, x, st.body.l, "frenet")[0], s, 1e-3, 4)[0]
    np.testing.assert_allclose(fd, exact, atol=1e-9)
    assert np.abs(exact).max() > 1e-4  # the paper's Λ* does vary along the helix (~3e-4 1/m)


@pytest.mark.slow
def test_precision_bench_shows_orders_one_two_four(tmp_path):
    from symmech.core import pipeline
    from symmech.core.context import Context
    from symmech.trolley import scene

    result = scene.precision(pipeline.load(SCENES / "trolley_helix_paper.toml").setup, Context(quiet=True))
    table = result.tables["precision"]
    err = {(m, n): e for family, m, n, e in zip(table.text["family"], table.text["method"], table.column("steps"),
                                                 table.column("max_abs_error")) if family == "paper"}
    for method, order in (("backward", 1), ("central2", 2), ("central4", 4)):
        ratio = err[(method, 1000)] / err[(method, 2000)]
        assert ratio == pytest.approx(2.0**order, rel=0.15)
    assert result.plots(tmp_path)[0].stat().st_size > 0


def test_tables_need_the_papers_backward_difference():
    """With a central difference for dΛ*/ds the case 2 binormal entries no longer reproduce."""
    import copy

    from symmech.trolley import scene

    data = copy.deepcopy(tables.PAPER_EXAMPLE)
    data["numerics"] = {"lstar_derivative": "central4"}
    st = prepared(data)
    res = scene.compute(st)
    a3 = res[2]["a"][3750, 2]  # t = 15 s, printed -0.693
    assert abs(a3 - (-0.693)) > 5e-3
    assert abs(res[2]["P"][3750, 4] - (-60.946)) > 0.1


def test_exact_case2_derivatives_match_differences_on_a_catenary():
    """X0(s) = (asinh s, sqrt(1 + s²), 0) has unit speed and curvature 1/(1 + s²), so Λ* varies."""
    import copy

    from symmech.trolley import model, scene

    data = copy.deepcopy(tables.PAPER_EXAMPLE)
    data.update(conventions="physics", track={"type": "expression", "x": "asinh(s)", "y": "sqrt(1 + s**2)",
                                                "z": "0"})
    data["trolley"]["axle_distance"] = 0.5
    st = prepared(data)
    s = np.linspace(-2.0, 2.0, 21)
    d1, d2 = scene.exact_lstar_derivatives(st)(s, model.chord_point(st.track, s, 0.5))
    fun = lambda x: model.chord_rotation(st.track, x, 0.5, "frenet")[0]  # noqa: E731
    f1, f2 = model._stencil(fun, s, 0.01, 4)
    assert np.abs(d1).max() > 0.05 and np.abs(d2).max() > 0.05
    np.testing.assert_allclose(f1, d1, atol=1e-7)
    np.testing.assert_allclose(f2, d2, atol=1e-6)
