"""A trolley sweep answers like a designer's tool: a point with a lift-off warning is never admissible and says
so in its table row and chart cell; the best admissible point for the stated objective is the one starred on
every chart; a design number too flat to chart is stated as a number."""
import dataclasses
import time

import numpy as np
import pytest

from badinput import edited
from symmech.core import pipeline
from symmech.core import plotting
from symmech.core import sweep as core_sweep
from symmech.trolley import sweep
from test_trolley_sweep import RIGID, TINY, outcomes, swept

pytestmark = pytest.mark.xdist_group("test_trolley_sweep")

# TINY sampled finely enough for its modes and with a comfort envelope no point leaves: only lift-off limits it
WIDE = edited(TINY, ("time.steps", 40), ("comfort", {"x1": [-40.0, 40.0], "x2": [-40.0, 40.0], "x3": [-40.0, 40.0]}))


@pytest.fixture
def figures(monkeypatch):
    """The figures the sweep's charts would save, by file stem."""
    saved = {}
    monkeypatch.setattr(plotting, "save", lambda fig, folder, stem: saved.setdefault(stem, fig) and [stem])
    return saved


def test_a_lift_off_point_is_drawn_inadmissible_with_its_reason(figures):
    """The speed's slope a = 300 m/s² reaches ~36 m/s within 0.12 s: a direct run's roller reaction changes sign
    (max > 0 > min), so that point is not admissible, whatever its numbers, and its row and cell say lift-off."""
    direct = pipeline.load(edited(WIDE, ("motion.constants.a", 300.0))).run().tables["elastic_reactions"]
    assert any(direct.column(f"P{i}").max() > 0 > direct.column(f"P{i}").min() for i in range(1, 6))
    p, out = outcomes(swept(WIDE, {"field": "motion.constants.a", "values": [3.0, 300.0]}))
    res = sweep.result(p, out)
    table = res.tables["sweep"]
    assert list(table.column("admissible")) == [1.0, 0.0] and table.column("comfort_margin").min() > 0
    assert table.text["verdict"][0] == "admissible" and "would lift off" in table.text["verdict"][1]
    assert res.summary["best_point"]["x"] == 3.0
    assert [c["points"] for c in res.summary["decision"]["limited_by"] if c["reason"] == "lift-off"] == [1]
    assert any("limited by lift-off" in w for w in res.warnings)
    res.plots(None)
    for stem, fig in figures.items():
        (label,) = [t.get_text() for t in fig.axes[0].texts]
        assert "lift-off" in label.split(", "), stem


def test_the_best_point_is_the_same_on_every_chart(figures):
    """Objective: the largest speed scale with P3 ≤ 250 N and comfort kept. The best point is the largest x among
    the rows that keep both (read from the table), and every chart stars it there."""
    raw = swept(RIGID, {"field": "motion.speed_scale", "values": [0.5, 1.0, 1.5]},
                {"field": "trolley.mass", "values": [50.0, 100.0]}, limits={"P3": 250.0},
                objective={"quantity": "x", "goal": "max"})
    p, out = outcomes(raw)
    res = sweep.result(p, out)
    t = res.tables["sweep"]
    keep = (t.column("comfort_margin") >= 0) & (t.column("peak_P3") <= 250.0)
    assert 0 < keep.sum() < len(keep)  # the limit bites: the best is not simply the largest x swept
    k = int(np.flatnonzero(keep)[np.argmax(t.column("x")[keep])])
    best = (t.column("x")[k], t.column("y")[k])
    assert (res.summary["best_point"]["x"], res.summary["best_point"]["y"]) == best
    # a best value several admissible points reach is said to be shared, by how many
    tied = int(np.count_nonzero(keep & (t.column("x") == best[0])))
    meaning = res.headline[0].meaning
    assert (f"; {tied} admissible points share this value" in meaning) if tied > 1 else "share" not in meaning
    res.plots(None)
    assert len(figures) == 2
    for stem, fig in figures.items():
        stars = [line for line in fig.axes[0].lines if line.get_label() == "best admissible point"]
        assert len(stars) == 1 and (stars[0].get_xdata()[0], stars[0].get_ydata()[0]) == best, stem
        x0, x1 = fig.axes[0].get_xlim()
        assert (x0, x1) == (0.5, 1.5), stem  # the cells end at the swept range
    # the chart the estimate times is one of these charts' size (stopped at its figure: only its size is read)
    sizes = {tuple(fig.get_size_inches()) for fig in figures.values()}

    def measured(**size):
        raise LookupError(size)

    with pytest.MonkeyPatch.context() as m:
        m.setattr(plotting, "figure", measured)
        with pytest.raises(LookupError) as drawn:
            core_sweep.chart_seconds((3, 2))
    assert sizes == {(drawn.value.args[0]["width"], drawn.value.args[0]["height"])}


def test_a_flat_quantity_is_stated_not_colour_mapped():
    """A spread of 2e-4 on 1.0001 (below 1e-3 of it) is stated as one number; a spread of 1 % is charted."""
    flat = core_sweep.flat_statement(np.array([1.00005, 1.00025, 1.0001]), "largest dynamic amplification", "1",
                                     1e-3)
    assert flat["value"] == pytest.approx(1.00013333, rel=1e-8) and flat["spread"] == pytest.approx(2e-4, rel=1e-9)
    assert flat["text"] == ("largest dynamic amplification: 1.0001 everywhere, within the tolerance (its spread over "
                            "the sweep, 0.0002, is below 0.001 of its size); not charted")
    assert core_sweep.flat_statement(np.array([1.0, 1.01]), "amplification", "1", 1e-3) is None
    assert core_sweep.flat_statement(np.array([np.nan, 2.0]), "amplification", "1", 1e-3) is None  # one finite


def test_a_best_value_shared_by_several_points_says_so():
    """Objective: the largest speed scale. Two admissible points (masses 50 and 100 kg) reach the largest, 1.0:
    the answer says 2 share it and which is starred; a single best point says nothing of sharing."""
    from symmech.core.results import Column, Table

    raw = swept(RIGID, {"field": "motion.speed_scale", "values": [0.5, 1.0]},
                {"field": "trolley.mass", "values": [50.0, 100.0]}, objective={"quantity": "x", "goal": "max"})
    p = sweep.plan(raw, pipeline.load(raw).resolved)
    for admissible, shared in (([1.0, 1.0, 1.0, 1.0], "; 2 admissible points share this value"), ([1, 1, 1, 0], "")):
        table = Table([Column("x", "1"), Column("y", "kg"), Column("admissible", "1")],
                      np.column_stack([[0.5, 0.5, 1.0, 1.0], [50.0, 100.0, 50.0, 100.0], admissible]))
        ok = table.column("admissible") == 1
        decision = sweep.decide(p, table, ok, [[] if k else [("lift-off", "...")] for k in ok])
        best = sweep.answer(p, table, decision, {})[0][0]
        assert best.value == 1.0 and best.at.startswith("speed scale 1, ")
        assert best.meaning.endswith("neighbouring values" + (shared and shared + ", the first in sweep order is "
                                                                           "starred"))
    # the smallest speed scale, over four hand-made points (x-major): (0.5, 50 kg) leaves the comfort envelope by
    # 0.25 g, (1, 100 kg) failed, the other two admissible; the largest roller reaction is 1 kN at every point
    cols = [Column(f"peak_P{i}", "N") for i in range(6)] + [Column("peak_reaction_max", "N"),
                                                          Column("comfort_margin", "g")]
    points = [("ok", cols, [1.0, 2.0, 3.0, 4.0, 5.0, 1e3, 1e3, margin], {}, []) for margin in (-0.25, 0.5, 0.75)]
    res = sweep.result(dataclasses.replace(p, objective=("x", "min")), points + [("failed", "stopped here")])
    best = res.summary["best_point"]
    assert (best["index"], best["x"], best["y"]) == ([0, 1], 0.5, 100.0) and res.summary["decision"]["best"] == best
    assert [(h.name, h.value, h.meaning, h.at) for h in res.headline] == [
        ("best point: smallest speed scale", 0.5, "the smallest speed scale of the 2 admissible points (no warning, no "
         "failed check, comfort and the stated limits kept); its cell reaches halfway to the neighbouring values",
         "speed scale 0.5, body mass 100 kg"),
        ("admissible points", 2.0, "of 4: speed scale 0.5 … 1, body mass 50 kg … 100 kg", ""),
        ("largest roller reaction |P1…P5|", 1e3, "1 kN everywhere, within the tolerance (its spread over the sweep, "
                                                 "0 N, is below 0.001 of its size); not charted", "every point")]
    assert res.warnings == [
        "1 of 4 point(s) limited by comfort at speed scale 0.5, body mass 50 kg; first: leaves the comfort envelope "
        "by 0.25 g",
        "1 of 4 point(s) limited by failed at speed scale 1, body mass 100 kg; first: the run stopped: stopped here"]
    # a point the scene refuses is a failed task, with the scene's message
    refused = sweep.evaluate(dataclasses.replace(p, y={**p.y, "values": [50.0, -1.0]}), 0, 1, time.time() + 60.0)
    assert refused == ("failed", "scene field 'trolley.mass': -1 kg is outside [0.001, 1e+07] kg")
