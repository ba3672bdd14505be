"""Headline and checks of every kind (docs/outputs.md): each headline value is recomputed here from
the CSV tables the run wrote (or, for an impact, from momentum and the restitution law), each check's
verdict from its measured value and threshold; `symmech run` prints them and the report shows a
failing check as failed, at the top."""
import csv
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

from symmech.cli import main

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "scenes"
# kind -> (bundled scene, edits that keep the run short)
RUNS = {
    "grain": ("grain_default.toml", {r"(?m)^duration = .*$": "duration = 0.5",
                                     r"(?m)^\[numerics\]$": '[numerics]\nengine = "python"'}),
    "impact": ("impact_default.toml", {}),
    "trolley": ("trolley_helix.toml", {r"steps = 5000": "steps = 500", r"paper_tables = true": "paper_tables = false"}),
    # 100 steps over 3 s: too coarse for the 78 Hz roller mode, so the sampling check warns
    # the reference engine, named: a module fixture runs before conftest's per-test engine choice
    "elastic": ("trolley_elastic_helix.toml", {r"(?m)^steps = .*$": "steps = 100",
                                               r"(?m)^\[elastic.numerics\]$": '[elastic.numerics]\nengine = "python"'}),
    "mechanism": ("smm_rotor_boom.toml", {}),
}


# its module fixtures run scenes (built once per xdist worker, so one worker runs the module), and the
# report derives the trolley paper: in the worker that already has every derivation (codegen.derive caches)
pytestmark = pytest.mark.xdist_group("derive")


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """kind -> (output folder, stdout of `symmech run`)."""
    base = tmp_path_factory.mktemp("headline")
    out = {}
    for kind, (scene, edits) in RUNS.items():
        text = (SCENES / scene).read_text()
        for pattern, repl in edits.items():
            text, n = re.subn(pattern, repl, text, count=1)
            assert n == 1, (scene, pattern)
        (base / scene).write_text(text)
        out[kind] = base / kind
        assert main(["run", str(base / scene), "--out", str(out[kind]), "--no-plots"]) == 0
    return out


@pytest.fixture(scope="module")
def summaries(runs):
    return {kind: json.loads((folder / "summary.json").read_text()) for kind, folder in runs.items()}


def table(folder: Path, name: str) -> dict:
    """name.csv as {column name (unit stripped): numpy array, or list of text}."""
    with open(folder / f"{name}.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    out = {}
    for j, header in enumerate(rows[0]):
        cells = [r[j] for r in rows[1:]]
        try:
            out[header.split(" [")[0]] = np.array([float(c) for c in cells])
        except ValueError:
            out[header] = cells
    return out


def headline(summary: dict) -> dict:
    return {h["name"]: h for h in summary["headline"]}


def checks(summary: dict) -> dict:
    return {c["what"]: c for c in summary["checks"]}


def test_grain_headline_from_the_tables(runs, summaries):
    h, folder = headline(summaries["grain"]), runs["grain"]
    tr, im = table(folder, "trajectory"), table(folder, "impacts")
    t = tr["t"]
    span = t[-1] - t[0]
    assert h["transport velocity along the slope"]["value"] == pytest.approx((tr["x"][-1] - tr["x"][0]) / span,
                                                                             rel=1e-12)
    assert h["transport velocity across the slope"]["value"] == pytest.approx((tr["y"][-1] - tr["y"][0]) / span,
                                                                              rel=1e-12, abs=1e-15)
    # each interval between rows is in the regime of the row that ends it; an impact row ends a flight
    regime = tr["regime"]
    time_in = {}
    for i in range(len(t) - 1):
        r = regime[i + 1] if regime[i + 1] != "impact" else regime[i]
        r = "flight" if r == "impact" else r
        time_in[r] = time_in.get(r, 0.0) + t[i + 1] - t[i]
    assert h["time in flight"]["value"] == pytest.approx(100 * time_in["flight"] / span, abs=1e-9)
    assert h["time sliding"]["value"] == pytest.approx(100 * time_in.get("sliding", 0.0) / span, abs=1e-9)
    assert h["impacts"]["value"] == len(im["t"]) > 10
    assert h["energy dissipated by impacts"]["value"] == pytest.approx(np.sum(im["ke_before"] - im["ke_after"]),
                                                                       rel=1e-12)
    c = checks(summaries["grain"])
    assert c["impacts creating energy"]["value"] == np.sum(im["energy_change"] > 0) == 0
    assert c["impacts whose solver did not converge"]["value"] == im["converged"].count("False") == 0
    # rows per mean interval between impacts: sample interval T/40 of the 25 Hz vibration
    sampling = c["trajectory rows per mean interval between impacts"]
    assert sampling["value"] == pytest.approx(span / len(im["t"]) / (1 / 25 / 40), rel=1e-12)
    assert sampling["verdict"] == ("pass" if sampling["value"] >= 2 else "warn")
    assert all(c["verdict"] == "pass" for c in summaries["grain"]["checks"])
    # the texts a reader sees: names, units, meanings, the span averaged over, the checks' names and thresholds
    s, over = summaries["grain"], "mean over 0.5 s"  # the fixture's duration
    assert list(s["time_fraction"]) == ["flight", "sliding"]
    assert [(x["name"], x["unit"], x["meaning"], x["at"]) for x in s["headline"]] == [
        ("transport velocity along the slope", "m/s", "net displacement along X / duration", over),
        ("transport velocity across the slope", "m/s", "net displacement along Y / duration", over),
        ("time in flight", "%", "share of the run spent in flight", ""),
        ("time sliding", "%", "share of the run spent sliding", ""),
        ("impacts", "1", "rows of impacts.csv", ""),
        ("energy dissipated by impacts", "J", "sum of ke_before - ke_after over impacts.csv", ""),
        ("energy dissipated in all", "J", "impacts, landings and sliding friction", "")]
    budget = s["energy_budget"]
    assert h["energy dissipated in all"]["value"] == pytest.approx(
        budget["lost_in_impacts_J"] + budget["lost_at_landings_J"] + budget["lost_in_sliding_J"], rel=1e-12)
    assert [(x["what"], x["threshold"]) for x in s["checks"]] == [
        ("energy balance closes (relative residual)", "<= 1e-06"), ("impacts creating energy", "<= 0"),
        ("impacts whose solver did not converge", "<= 0"), ("impacts where the printed law would create energy", "<= 0"),
        ("trajectory rows per mean interval between impacts", ">= 2")]
    assert s["tables"]["impacts"]["doc"] == ("one row per impact; admissible: no energy created by this law; "
                                             "printed_law_*: the printed law's verdict at this impact (empty when "
                                             "not evaluated)")


def test_impact_headline_from_momentum_and_the_law(summaries):
    """Centre velocity after = before + T/m (m = 1e-5 kg); the contact point rebounds at -e u_Kz (e = 0.5)."""
    s = summaries["impact"]
    h = headline(s)
    T = np.array(s["impulse_T"])
    after = np.array([0.3, 0.1, -0.5]) + T / 1.0e-5
    for x, v in zip("xyz", after):
        assert h[f"centre velocity after, {x}"]["value"] == pytest.approx(v, rel=1e-12)
    assert h["normal impulse"]["value"] == T[2] > 0
    assert h["tangential impulse"]["value"] == pytest.approx(math.hypot(T[0], T[1]), rel=1e-15)
    assert h["rebound velocity of the contact point"]["value"] == pytest.approx(
        -0.5 * s["contact_velocity_before"][2], rel=1e-9)
    assert h["kinetic energy lost"]["value"] == pytest.approx(s["kinetic_energy_before"] - s["kinetic_energy_after"],
                                                              rel=1e-12)
    assert h["angular speed after"]["value"] == pytest.approx(np.linalg.norm(s["angular_velocity_after"]), rel=1e-15)
    lost = 100 * (1 - s["kinetic_energy_after"] / s["kinetic_energy_before"])
    centre = [(f"centre velocity after, {x}", "m/s", "velocity of the centre just after the impact") for x in "xyz"]
    assert [(x["name"], x["unit"], x["meaning"]) for x in s["headline"]] == [
        ("normal impulse", "N s", "T_z, along the plane's normal"),
        ("tangential impulse", "N s", "|(T_x, T_y)|, friction"), *centre,
        ("angular speed after", "rad/s", "|ω| after the impact"),
        ("rebound velocity of the contact point", "m/s",
         "its velocity along the normal after the impact (> 0: it leaves the plane)"),
        ("kinetic energy lost", "J", f"{lost:.3g} % of the energy before")]
    assert [(c["what"], c["unit"], c["threshold"], c["verdict"]) for c in s["checks"]] == [
        ("impact equations (19) solved (relative residual)", "1", "<= 1e-08", "pass"),
        ("kinetic energy after / before (no energy created)", "1", "<= 1", "pass"),
        ("an admissible root: no energy created, no pull into the plane", "1", "= 1 (admissible)", "pass")]
    assert s["checks"][1]["value"] == pytest.approx(s["kinetic_energy_after"] / s["kinetic_energy_before"], rel=1e-15)


def _peak(values: np.ndarray) -> tuple[float, int]:
    i = int(np.argmax(np.abs(values)))
    return float(values[i]), i


def test_trolley_headline_and_comfort_verdicts_from_the_tables(runs, summaries):
    s = summaries["trolley"]
    h, c = headline(s), checks(s)
    envelope = s["scene"]["comfort"]
    for case in (1, 2):
        cs, over = table(runs["trolley"], f"case{case}"), table(runs["trolley"], f"case{case}_overload")
        for k in (1, 2, 3):
            n = over[f"n{k}"]
            lo, hi = envelope[f"x{k}"]
            # the extreme with the smaller margin to its side of the envelope (negative: outside)
            i = int(np.argmax(n)) if hi - n.max() <= n.min() - lo else int(np.argmin(n))
            assert h[f"case {case}: critical overload n{k}"]["value"] == n[i]
            assert h[f"case {case}: critical overload n{k}"]["at"].startswith(f"t = {over['t'][i]:.4g} s")
            check = c[f"case {case}: overload n{k} in the comfort envelope"]
            assert check["value"] == [n.min(), n.max()]
            assert check["verdict"] == ("pass" if lo <= n.min() and n.max() <= hi else "fail")
        for j in range(6):
            assert h[f"case {case}: peak reaction P{j}"]["value"] == _peak(cs[f"P{j}"])[0]
    # the helix at 57 m/s is far outside the comfort envelope along x2: a failed check
    assert c["case 1: overload n2 in the comfort envelope"]["verdict"] == "fail"


def test_elastic_headline_from_the_tables(runs, summaries):
    s, folder = summaries["elastic"], runs["elastic"]
    h, c = headline(s), checks(s)
    P = table(folder, "elastic_reactions")
    for i in range(6):
        ratio = np.abs(P[f"P{i}"]).max() / np.abs(P[f"P{i}_rigid"]).max()
        assert h[f"dynamic amplification of P{i}"]["value"] == pytest.approx(ratio, rel=1e-14)
    d = table(folder, "roller_deflections")
    assert h["largest roller deflection"]["value"] == max(np.abs(d[f"d{i}"]).max() for i in range(1, 6))
    pts = table(folder, "points")
    tip = np.sqrt(sum(pts[f"tip_e{k}"] ** 2 for k in (1, 2, 3))).max()
    assert h["largest body deflection at tip"]["value"] == pytest.approx(tip, rel=1e-14) and tip > 1e-3
    assert "largest body deflection at seat" not in h  # the seat is on the rigid trolley
    modes = table(folder, "modes")
    f = modes["f"]  # one row per sample and tracked mode
    assert h["lowest natural frequency"]["value"] == f[f > 0].min()
    # energy balance: max |residual| over the scale of the energy exchanged (energy.csv)
    e = table(folder, "energy")
    scale = max(np.abs(e["work"]).max(), np.abs(e["E"] - e["E"][0]).max(), e["dissipated"][-1])
    balance = c["elastic: energy balance closes (relative residual)"]
    assert balance["value"] == pytest.approx(np.abs(e["residual"]).max() / scale, rel=1e-9)
    assert balance["verdict"] == "pass" and balance["value"] < 1e-6
    for k, axis in enumerate(("x1", "x2", "x3"), 1):
        n = pts[f"seat_n{k}"]
        assert c[f"elastic: overload of seat along {axis} in the comfort envelope"]["value"] == [n.min(), n.max()]
    # 100 steps over 3 s sample at 33.3 Hz: below 4 samples per period of the lightly damped modes
    top = f[modes["zeta"] < 0.1].max()
    sampling = c["elastic: output samples per period of the highest lightly damped mode"]
    assert sampling["value"] == pytest.approx(100 / 3.0 / top, rel=1e-12) and sampling["verdict"] == "warn"
    assert any("set time.steps >= " + str(math.ceil(4 * top * 3.0)) in w for w in s["warnings"])


def test_mechanism_headline_from_the_tables(runs, summaries):
    s, folder = summaries["mechanism"], runs["mechanism"]
    h = headline(s)
    modes = table(folder, "modes")
    elastic = [f for f, kind in zip(modes["f"], modes["class"]) if kind == "elastic"]
    assert [h[f"natural frequency f{i + 1}"]["value"] for i in range(len(elastic))] == elastic
    free = table(folder, "free_response")
    q = {k: v for k, v in free.items() if k != "t"}
    name = max(q, key=lambda k: np.abs(q[k]).max())
    assert h[f"largest free response, {name}"]["value"] == _peak(q[name])[0]
    frf = table(folder, "frequency_response")
    amplitude = {k[4:]: v for k, v in frf.items() if k.startswith("abs_")}
    name = max(amplitude, key=lambda k: amplitude[k].max())
    assert h[f"largest frequency response, {name}"]["value"] == amplitude[name].max()
    assert all(c["verdict"] == "pass" for c in s["checks"])


def test_run_prints_the_headline_unless_quiet(tmp_path, capsys):
    scene = SCENES / "impact_default.toml"
    assert main(["run", str(scene), "--out", str(tmp_path / "a"), "--no-plots"]) == 0
    out = capsys.readouterr().out
    # T_z = 4.768e-6 N s in a readable unit; the three checks pass, so none is listed
    assert "  normal impulse: 4.77 µN s" in out and "checks: 3 pass, 0 warn, 0 fail" in out
    assert main(["run", str(scene), "--out", str(tmp_path / "b"), "--no-plots", "--quiet"]) == 0
    assert "normal impulse" not in capsys.readouterr().out


def test_report_opens_with_the_answers_and_a_failed_check(runs):
    """The trolley helix leaves the comfort envelope: the verdict opens the page, the failed check is a failed
    row, listed under 'Needs attention' before the answers (above the fold however many answers there are), then
    the headline in kN; "case 1" is explained on top."""
    from symmech import report

    page = report.render(runs["trolley"])
    answers, attention, checks_at = (page.index(f'<h2 id="{i}">') for i in ("answers", "attention", "checks"))
    assert page.index('<p class="verdict bad">\n✗ ') < attention < answers < checks_at
    assert "Case 1: the body frame is the moving frame of the track" in page[:attention]  # said on top
    failed = re.findall(r'<tr class="fail"><td>([^<]*)</td>', page)
    assert "case 1: overload n2 in the comfort envelope" in failed
    top = page[attention:checks_at]
    assert "case 1: overload n2 in the comfort envelope" in top and "✗ fail" in top
    assert re.search(r"<td>case 1: peak reaction P3</td><td class=\"value\">23\.\d+ kN</td>", page)
    assert '<details id="summary">' in page and "tables.case1_overload" not in page


def test_grain_sampled_too_coarsely_for_its_impacts_warns():
    """Rows every 20 ms while the grain bounces about every 4 ms: the check warns and the warning
    names numerics.sample_interval and the interval that would show the bounces."""
    import tomllib

    from symmech.core import pipeline

    scene = tomllib.loads((SCENES / "grain_default.toml").read_text())
    scene["duration"] = 0.3
    scene["numerics"].update(engine="python", sample_interval=0.02)
    result = pipeline.load(scene).run()
    bounces = result.summary["bounces"]
    check = next(c for c in result.checks if c.what == "trajectory rows per mean interval between impacts")
    assert check.value == pytest.approx(0.3 / bounces / 0.02, rel=1e-12) and check.verdict == "warn"
    assert any("numerics.sample_interval <= " + f"{0.3 / bounces / 2:.3g} s" in w for w in result.warnings)
