"""`symmech report`: a self-contained HTML page per run, checked as text and in headless Chromium."""
import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from symmech.cli import main

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "scenes"
# kind -> (bundled scene, replacements that keep the run short, seed of its paper)
RUNS = {
    "impact": ("impact_default.toml", {r"\Z": '\n[output]\nformats = ["png", "svg"]\n'}, "000"),
    "grain": ("grain_default.toml", {r"(?m)^duration = .*$": "duration = 0.2"}, "000"),
    "trolley": ("trolley_helix.toml", {r"steps = 5000": "steps = 500", r"paper_tables = true": "paper_tables = false"},
                "002"),
    "mechanism": ("smm_rotor_boom.toml", {}, "003"),
}


# its module fixtures run scenes: built once per xdist worker, so one worker runs the module
pytestmark = pytest.mark.xdist_group("test_report")


@pytest.fixture(scope="module")
def reports(tmp_path_factory):
    """kind -> output folder of a bundled scene run with ``--report``, each in its own process as
    from the command line (``generated_modules`` lists the modules loaded in the run's process)."""
    base = tmp_path_factory.mktemp("reports")
    folders = {}
    for kind, (scene, edits, _) in RUNS.items():
        text = (SCENES / scene).read_text()
        for pattern, repl in edits.items():
            text = re.sub(pattern, repl, text)
        path = base / scene
        path.write_text(text)
        folders[kind] = base / kind
        proc = subprocess.run([sys.executable, "-m", "symmech", "run", str(path), "--out", str(folders[kind]),
                               "--report", "--quiet"], capture_output=True, text=True, timeout=600)
        assert proc.returncode == 0, proc.stderr
    return folders


def html(folder: Path) -> str:
    return (folder / "report.html").read_text(encoding="utf-8")


@pytest.mark.parametrize("kind", RUNS)
def test_report_is_self_contained(reports, kind):
    page = html(reports[kind])
    # every src/href is inline data: nothing to fetch when the file is opened offline
    links = re.findall(r'(?:src|href)="([^"]*)"', page)
    assert links and all(link.startswith("data:") for link in links)
    assert "<script" not in page
    pngs = sorted(p.stem for p in reports[kind].glob("*.png"))
    svgs = sorted(p.stem for p in reports[kind].glob("*.svg"))
    assert page.count("<img ") == len(pngs) >= 1
    # a plot's SVG when the scene asked for it ([output] formats), its PNG otherwise
    assert len(svgs) == (len(pngs) if kind == "impact" else 0)
    assert page.count('src="data:image/svg+xml;base64,') == len(svgs)
    assert page.count('src="data:image/png;base64,') == len(pngs) - len(svgs)


@pytest.mark.parametrize("kind", RUNS)
def test_errata_of_the_scene_paper_only(reports, kind):
    """The errata are the scene's paper's only: its seed stated once above the table, not on every row."""
    page = html(reports[kind])
    assert re.findall(r"Every check is of paper \d \(seed (\d{3})\): \w[^<]*\.</p>", page) == [RUNS[kind][2]]
    assert not re.findall(r"\d{3}_[0-9a-f]{16}", page)  # the seed file's stem: a raw id, nowhere on the page


def test_impact_report_shows_its_checks_and_derivations(reports):
    page = html(reports["impact"])
    summary = json.loads((reports["impact"] / "summary.json").read_text())
    residual = summary["solver"]["residual_19"]
    # the check as a verdict row: what, measured value, threshold, verdict
    assert re.search(r'<tr class="pass"><td>impact equations \(19\) solved \(relative residual\)</td>'
                     r'<td class="num measured">' + re.escape(f"{residual:.3g}") +
                     r'</td><td class="num">&lt;= 1e-08</td>'
                     r'<td class="verdict">✓ pass</td>', page)
    assert "<code>grain_impact.H</code>" in page and "symmech latex grain_impact.H --tex H.tex" in page
    assert page.count('<math display="block">') >= 10


@pytest.mark.parametrize("kind", RUNS)
def test_captions_are_sentences_not_file_names(reports, kind):
    """Every figure of every kind's run has a caption sentence (capital, words, full stop), none a file name."""
    page = html(reports[kind])
    captions = re.findall(r"<figcaption>([^<]*)</figcaption>", page)
    stems = {p.stem for p in reports[kind].glob("*.png")}
    assert len(captions) == len(stems) >= 1
    for caption in captions:
        assert caption[0].isupper() and caption.endswith(".") and len(caption.split()) >= 6, caption
        assert not re.search(r"\.(png|svg)\b", caption), caption
        assert caption.rstrip(".").lower() not in {stem.replace("_", " ") for stem in stems} | stems, caption


def test_overload_beyond_its_limit_is_coloured_with_the_limit(reports):
    """The trolley's critical overload n2 (tens of g on the helix) is beyond the default comfort envelope
    [-1.5, 6] g (docs/scenes-trolley.md): its answer row is coloured as a failed check, with the limit beside it;
    an overload inside its envelope is coloured as passed. Inside or not is read from the overload CSVs."""
    import numpy as np

    page = html(reports["trolley"])
    envelope = {1: (-2.0, 2.0), 2: (-1.5, 6.0), 3: (-2.0, 2.0)}
    verdicts = []
    for case in (1, 2):
        n = np.loadtxt(reports["trolley"] / f"case{case}_overload.csv", delimiter=",", skiprows=1)
        for k, (lo, hi) in envelope.items():
            ok = lo <= n[:, k].min() and n[:, k].max() <= hi
            verdicts.append(ok)
            row = (rf'<tr class="{"pass" if ok else "fail"}"><td>case {case}: critical overload n{k}</td>'
                   rf'<td class="value">-?[0-9.]+ g</td><td class="num verdict">{"✓" if ok else "✗"} '
                   rf'within \[{lo:g} g, {hi:g} g\]</td>')
            assert re.search(row, page), row
    assert not all(verdicts)  # the 44 g of the helix is among them


def test_provenance_hashes(reports):
    """The run's own record of its modules when it made one, else the installed modules' headers."""
    page = html(reports["trolley"])
    recorded = json.loads((reports["trolley"] / "summary.json").read_text()).get("generated_modules")
    if recorded:
        expected = recorded["trolley_frame"]
    else:
        header = (ROOT / "generated" / "trolley_frame.py").read_text().split("\n", 1)[0]
        expected = re.search(r"inputs sha256 ([0-9a-f]{64})", header).group(1)
    assert f"<td>trolley_frame</td><td class=\"num\">{expected}</td>" in page


def test_mechanism_report_typesets_the_scene_matrices(reports):
    page = html(reports["mechanism"])
    assert "<code>smm_rotor_boom.c</code>" in page and "<code>smm_rotor_boom.a</code>" in page
    assert "smm_excavator" not in page  # only the run's own mechanism
    header = (reports["mechanism"] / "smm_rotor_boom.py").read_text().split("\n", 1)[0]
    assert f"<td>smm_rotor_boom</td><td class=\"num\">{header.rsplit(' ', 1)[1]}</td>" in page


PACKAGES = {"impact": "grain", "grain": "grain", "trolley": "trolley", "mechanism": "smm"}


@pytest.mark.parametrize("kind", RUNS)
def test_the_derivations_of_a_bundled_scene_import_no_sympy(reports, kind, tmp_path):
    """They are read from the MathML codegen typeset into generated/, not derived again; the whole report of a
    mechanism imports no sympy either (the trolley's errata build a helix track from its expressions in sympy)."""
    code = ("import json, sys; from pathlib import Path; from symmech import report; "
            f"summary = json.loads(Path({str(reports[kind] / 'summary.json')!r}).read_text()); "
            f"shown = report.derivations(summary, {PACKAGES[kind]!r}); "
            f"page = {kind == 'mechanism'} and report.render(Path({str(reports[kind])!r})); "
            "print(len(shown), sum(d.mathml is not None for d in shown), 'sympy' in sys.modules)")
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    shown, typeset, sympy_imported = proc.stdout.split()
    assert int(shown) >= int(typeset) >= 5 and sympy_imported == "False", proc.stderr


def test_the_grains_errata_import_no_sympy(tmp_path):
    """The gradient of the printed (24) that (25)-(27) are checked against is generated at codegen."""
    code = ("import sys; from symmech import report; "
            "print(len(report.errata_records('grain')), 'sympy' in sys.modules)")
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    records, sympy_imported = proc.stdout.split()
    assert int(records) >= 27 and sympy_imported == "False", proc.stderr


# (derivation module, generated module, function): a few of each paper, typeset by codegen
TYPESET = [("symmech.grain.derive", "grain_impact", "rotation"), ("symmech.grain.derive", "grain_impact", "contact_height"),
           ("symmech.trolley.derive", "trolley_frame", "Lambda"), ("symmech.trolley.derive", "trolley_frame", "A"),
           ("symmech.smm.derive", "smm_rotor_boom", "a"), ("symmech.smm.derive", "smm_rotor_boom", "L_c")]


@pytest.mark.parametrize(("producer", "module", "function"), TYPESET)
def test_the_generated_mathml_is_sympys_of_the_derivation(producer, module, function):
    """The MathML twin holds sympy's presentation MathML of the derived matrix, derived here again, with the
    function's meaning, unit and equations."""
    import importlib

    from sympy.printing.mathml import mathml

    from symmech.core import codegen

    spec = next(s for s in codegen.derive(producer)[0] if s.name == module)
    f = next(f for f in spec.functions if f.name == function)
    meaning, unit, equations, typeset = importlib.import_module(f"symmech.generated.{module}_mathml").FUNCTIONS[function]
    assert (meaning, unit, equations) == (f.meaning, f.unit, f.equations)
    rhs = mathml(f.matrix if f.shape else f.matrix[0, 0], printer="presentation")
    assert typeset.startswith('<math display="block"><mrow>') and typeset.endswith(f"<mo>=</mo>{rhs}</mrow></math>")


def test_a_matrix_over_the_limit_is_listed_not_typeset():
    """H of the grain (19,000 characters of sympy text) is named with its meaning, without MathML."""
    from symmech.core import codegen, typeset
    from symmech.generated import grain_impact_mathml

    spec = next(s for s in codegen.derive("symmech.grain.derive")[0] if s.name == "grain_impact")
    h = next(f for f in spec.functions if f.name == "H")
    assert len(str(h.matrix)) > typeset.MATHML_LIMIT
    assert grain_impact_mathml.FUNCTIONS["H"] == (h.meaning, h.unit, h.equations, None)


def test_a_mechanism_of_the_users_own_is_typeset_by_its_run(tmp_path):
    """A mechanism not in generated/ (its module rendered by the run) is typeset by the run into the MathML twin of
    its module: the rotor boom renamed shows its own module's functions, typeset as codegen typeset the bundled
    one's."""
    from symmech.generated import smm_rotor_boom_mathml

    scene = tmp_path / "my_boom.toml"
    scene.write_text((SCENES / "smm_rotor_boom.toml").read_text().replace('name = "rotor_boom"', 'name = "my_boom"', 1))
    assert main(["run", str(scene), "--out", str(tmp_path / "out"), "--report", "--quiet"]) == 0
    page = html(tmp_path / "out")
    for function, (_, _, _, typeset) in smm_rotor_boom_mathml.FUNCTIONS.items():
        assert f"<code>smm_my_boom.{function}</code>" in page
        assert typeset is None or typeset in page


def test_run_report_of_a_mechanism_of_the_users_own_derives_it_once(tmp_path, monkeypatch):
    """`run --report` reads the twin the run typeset beside its module, not a second derivation; its page shows
    what a report without the run's folder derives again from the recorded scene."""
    from symmech import report
    from symmech.smm import derive

    scene = tmp_path / "my_boom.toml"
    scene.write_text((SCENES / "smm_rotor_boom.toml").read_text().replace('name = "rotor_boom"', 'name = "my_boom"', 1))
    derived = []
    monkeypatch.setattr(derive, "module_spec", lambda m, spec=derive.module_spec: derived.append(m.name) or spec(m))
    assert main(["run", str(scene), "--out", str(tmp_path / "out"), "--report", "--quiet"]) == 0
    assert derived == ["my_boom"]
    again = report.derivations(json.loads((tmp_path / "out" / "summary.json").read_text()), "smm")
    assert derived == ["my_boom", "my_boom"] and sum(d.module == "smm_my_boom" for d in again) >= 5
    page = html(tmp_path / "out")
    for d in again:
        assert f"<code>{d.module}.{d.name}</code>" in page
        assert d.mathml is None or d.mathml in page


def test_missing_summary_is_a_one_line_error(tmp_path, capsys):
    assert main(["report", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "summary.json: no such file" in err


# --------------------------------------------------------------------------- in a browser


def _chromium() -> str | None:
    return next((p for p in map(shutil.which, ("chromium", "chromium-browser")) if p), None)


@pytest.fixture(scope="module")
def browser():
    sync_api = pytest.importorskip("playwright.sync_api", reason="playwright not installed (.ci/run installs it)")
    executable = _chromium()
    if executable is None:
        pytest.skip("no system Chromium (.ci/run installs Debian's chromium)")
    with sync_api.sync_playwright() as p:
        # root in CI: Chromium's sandbox needs an unprivileged user
        b = p.chromium.launch(executable_path=executable, args=["--no-sandbox"])
        yield b
        b.close()


MEASURE = """() => {
  const box = e => { const r = e.getBoundingClientRect(); return [r.width, r.height]; };
  const maths = [...document.querySelectorAll('math')];
  const imgs = [...document.querySelectorAll('img')];
  const frac = document.querySelector('mfrac'), mi = document.querySelector('mi');
  return {
    maths: maths.map(box), imgs: imgs.map(e => [e.naturalWidth, ...box(e)]),
    frac: frac ? box(frac)[1] : null, mi: mi ? box(mi)[1] : null,
    display: maths.length ? getComputedStyle(maths[0]).display : null,
  };
}"""


@pytest.mark.parametrize("kind", RUNS)
def test_report_in_chromium(reports, browser, kind, tmp_path):
    page = browser.new_page(viewport={"width": 1200, "height": 900})
    problems = []
    page.on("console", lambda m: problems.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: problems.append(str(e)))
    page.goto((reports[kind] / "report.html").as_uri(), wait_until="load")
    found = page.evaluate(MEASURE)
    shot = tmp_path / f"report_{kind}.png"
    page.screenshot(path=str(shot), full_page=True)
    page.close()
    assert problems == []
    assert found["maths"] and all(w > 0 and h > 0 for w, h in found["maths"])
    # laid out as MathML, not as unknown inline tags: a block box, fractions stacked
    assert found["display"] == "block math"
    if found["frac"] is not None:
        assert found["frac"] > 1.5 * found["mi"]
    assert found["imgs"] and all(n > 0 and w > 100 and h > 100 for n, w, h in found["imgs"])
    assert shot.stat().st_size > 10_000


def test_report_reads_the_pipeline_record(tmp_path):
    """Fields the validate-first pipeline writes: resolved scene, status, timing, module hashes."""
    from symmech import report

    digest = "ab" * 32
    summary = {"symmech_version": "0.1.0", "kind": "impact", "status": "ok", "scene_file": "s.toml",
               "timing_s": {"validate": 0.01, "run": 0.5, "write": 0.25, "total": 0.76},
               "generated_modules": {"grain_impact": digest}, "solver": {"residual_19": 2.5e-15},
               "headline": [{"name": "normal impulse", "value": 4.768e-6, "unit": "N s", "meaning": "T_z", "at": ""}],
               "checks": [{"what": "energy kept", "value": 0.5, "unit": "1", "threshold": "<= 1", "verdict": "pass"},
                          {"what": "a made-up bound", "value": [-2.5, 7.0], "unit": "g",
                           "threshold": "within [-1, 6] g", "verdict": "fail"}],
               "scene": {"kind": "impact", "impact": {"e": 0.5, "lambda": 0.25}}, "warnings": ["w1"]}
    (tmp_path / "summary.json").write_text(json.dumps(summary))
    page = report.render(tmp_path)
    assert '&#34;lambda&#34;: 0.25' in page  # the resolved scene, escaped
    assert "<td>validate 10 ms, run 500 ms, write 250 ms, total 760 ms</td>" in page  # readable units
    assert f'<td>grain_impact</td><td class="num">{digest}</td>' in page
    assert '<td>normal impulse</td><td class="value">4.768 µN s</td>' in page
    # the failed check: first in the table, marked failed, and at the top beside the warning
    rows = re.findall(r'<tr class="(\w+)"><td>([^<]*)</td><td class="num measured">([^<]*)</td>', page)
    assert rows == [("fail", "a made-up bound", "-2.5 g … 7 g"), ("pass", "energy kept", "0.5")]
    assert '<td class="verdict">✗ fail</td>' in page
    assert page.index("✗ fail:</strong> a made-up bound") < page.index('<div class="warn">w1</div>') < \
        page.index('<h2 id="checks">')
    assert '<p class="verdict bad">\n✗ 1 check(s) failed (1 passed, 0 warned, 1 failed).' in page
    assert "No plots in this folder." in page
    assert "<code>grain_impact.mu_equation</code>" in page and "grain_motion" not in page


def test_report_shows_the_precision_study_beside_the_run(tmp_path):
    """A `symmech bench precision` study in OUT/precision: its rows in the report, the row at the run's
    own setting (mode accurate, tolerance 1e-9) highlighted, not the paper-mode row of equal value. The section
    reads the scene's settings, not its kind: a kind nobody registered spares the grain paper's derivations and
    their MathML (~50 s of CPU in a worker without them)."""
    from symmech import report

    (tmp_path / "precision").mkdir()
    (tmp_path / "summary.json").write_text(json.dumps({
        "kind": "made_up", "headline": [], "checks": [],
        "scene": {"kind": "grain", "numerics": {"mode": "accurate", "tolerance": 1e-9}}}))
    (tmp_path / "precision" / "summary.json").write_text(json.dumps({
        "kind": "grain", "study": "precision", "reference": "accurate at 1e-12", "tables": {"precision_grain": {}}}))
    (tmp_path / "precision" / "precision_grain.csv").write_text(
        "value [1],error [1],seconds [s],method,knob\n"
        "1e-07,3e-06,0.5,accurate (exact flight),tolerance\n"
        "1e-09,2e-08,0.9,accurate (exact flight),tolerance\n"
        "1e-09,0.1,0.2,paper mode,tolerance\n")
    page = report.render(tmp_path)
    assert "reference: accurate at 1e-12" in page
    assert page.count("<img ") == 1  # the study's diagram, drawn again with the run's setting ringed
    chosen = re.findall(r'<tr class="chosen">((?:<td class="num">[^<]*</td>)+)</tr>', page)
    assert chosen == ['<td class="num">1e-09</td><td class="num">2e-08</td><td class="num">0.9</td>'
                      '<td class="num">accurate (exact flight)</td><td class="num">tolerance</td>']


@pytest.mark.slow  # a whole precision study of the impact scene (~7 s of CPU)
def test_report_runs_a_precision_study_when_asked(tmp_path):
    """`symmech report OUT --precision`: the scene's `bench precision` study into OUT/precision, then
    the report with its diagram and one table row per solver setting of the study's CSV."""
    out = tmp_path / "impact"
    assert main(["run", str(SCENES / "impact_default.toml"), "--out", str(out), "--no-plots", "--quiet"]) == 0
    assert main(["report", str(out), "--precision", "--quiet"]) == 0
    study = json.loads((out / "precision" / "summary.json").read_text())
    assert study["study"] == "precision" and study["scene_file"] == str(SCENES / "impact_default.toml")
    rows = (out / "precision" / "precision_impact.csv").read_text().strip().splitlines()[1:]
    page = html(out)
    section = page[page.index('<h2 id="precision">'):page.index('<h2 id="derivations">')]
    assert section.count("<img ") == 1 and section.count("<tr><td") == len(rows) > 5


def _page(tmp_path, **fields) -> str:
    """The report of a hand-written summary of a kind nobody registered (no derivations, no errata: fast)."""
    from symmech import report

    (tmp_path / "summary.json").write_text(json.dumps({"kind": "made_up", "status": "ok", **fields}))
    return report.render(tmp_path)


PAPER_ROWS = [{"table": "Table 1", "quantity": "V1", "unit": "m/s", "case": 1, "t": 5.0, "printed": 19.119,
               "paper_conventions": 19.1188, "default_physics": 17.8361, "reproduced_to_printed_digits": True}]
PASSED = [{"what": "case 1: overload n1 in the comfort envelope", "value": [0.1, 1.6], "unit": "g",
           "threshold": "within [-2, 2] g", "verdict": "pass"}]


def test_paper_conventions_never_read_as_all_green(tmp_path):
    """Every check passing in the paper's conventions is no design verdict: the first line says so, the banner
    counts the reproduced table entries, and the table is open with each quantity's unit."""
    page = _page(tmp_path, scene={"conventions": "paper"}, checks=PASSED,
                 paper_tables={"entries": 72, "reproduced": 71, "rows": PAPER_ROWS})
    verdict = re.search(r'<p class="verdict (\w+)">\s*(.*?)</p>', page, re.S)
    assert verdict.group(1) == "careful" and "All" not in verdict.group(2) and "✓" not in verdict.group(2)
    assert "Paper conventions: not the trolley's numbers" in verdict.group(2)
    banner = re.search(r'<div class="banner">(.*?)</div>', page, re.S).group(1)
    assert "71 of 72 printed entries reproduced" in banner
    assert re.search(r'<details open><summary>71 of 72 printed entries', page)
    assert "<td>V1 [m/s]</td>" in page


def test_physics_run_folds_the_paper_tables_and_explains_its_cases_on_top(tmp_path):
    """In consistent physics the printed tables are an aside (collapsed); what case 1 and 2 are is said before
    the answers that use them; a headline without places has no empty 'where / when' column."""
    headline = [{"name": "case 1: peak reaction P1", "value": 990.0, "unit": "N", "meaning": "rear roller B",
                 "at": ""}]
    page = _page(tmp_path, scene={"conventions": "physics", "title": "A helix"}, checks=PASSED, headline=headline,
                 paper_tables={"entries": 72, "reproduced": 71, "rows": PAPER_ROWS})
    assert "<p><strong>A helix</strong></p>" in page
    assert '<div class="banner">' not in page and "✓ All 1 checks passed" in page
    assert re.search(r"<details><summary>71 of 72 printed entries[^<]*\(click to show\)", page)
    assert page.index("Case 1: the body frame is the moving frame") < page.index('<h2 id="answers">')
    assert "where / when" not in page


def test_a_mechanism_report_is_titled_by_its_description(tmp_path):
    page = _page(tmp_path, scene={"name": "excavator", "description": "An excavator arm on its hydraulics"})
    assert "<p><strong>An excavator arm on its hydraulics</strong></p>" in page
    page = _page(tmp_path, scene={"name": "chain", "description": "3,000 masses for `symmech bench precision`"})
    assert "<p><strong>3,000 masses for symmech bench precision</strong></p>" in page  # Markdown code, no backticks


def test_a_run_without_generated_modules_says_so_instead_of_an_empty_table(tmp_path):
    page = _page(tmp_path, generated_modules={})
    assert "<th>sha256</th>" not in page and "The run used no generated module." in page


def test_figures_follow_the_order_the_scene_asked_for(tmp_path):
    """Captions are recorded in the scene's [output] order (modes before free_response): the figures follow it,
    not the alphabet; a plot without a caption comes last, by its file name."""
    for stem in ("free_response", "modes", "extra"):
        (tmp_path / f"{stem}.png").write_bytes(b"\x89PNG\r\n\x1a\n")
    page = _page(tmp_path, captions={"modes": "The mode shapes.", "free_response": "The free response."})
    assert re.findall(r"<figcaption>([^<]*)</figcaption>", page) == ["The mode shapes.", "The free response.",
                                                                     "extra"]
