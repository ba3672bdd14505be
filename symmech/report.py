"""``symmech report OUT``: one self-contained HTML page about a finished run.

Reads ``OUT/summary.json`` and the plots in ``OUT`` and writes ``OUT/report.html``,
answers first: the run's headline (its answers in readable units), the checks that
did not pass beside the warnings, every check as a verdict, the plots (inline SVG,
else PNG, as data URIs), what accuracy costs (a ``symmech bench precision`` study in
``OUT`` itself or in ``OUT/precision``), the derivations the run used as MathML
(browsers render it natively), the errata of the scene's paper, the provenance
(version, generated-module hashes, wall time), and the raw resolved scene and
summary, collapsed. Nothing is fetched to view it.

Which derivations and errata belong to a kind is found, not listed: the kind's
runtime module lives in a paper package ``symmech.<paper>``; its generated
modules are named ``<paper>_*`` and its errata are ``symmech.<paper>.errata*``.
"""
from __future__ import annotations

import base64
import csv
import datetime
import importlib
import importlib.resources
import importlib.util
import json
import math
import platform
import re
from dataclasses import dataclass
from pathlib import Path

from symmech import __version__
from symmech.core import integrity, units
from symmech.core.results import VERDICTS, Check, readable
from symmech.core.scene import SceneError, SymmechError

TEMPLATE = "report.html.j2"
PRECISION_FOLDER = "precision"  # a study beside the run: `symmech bench precision SCENE --out OUT/precision`


# Terms a run's answers use, explained once under them
GLOSSARY = {
    "case 1": "case 1: the body frame is the moving frame of the track at the reference point O of the trolley",
    "case 2": "case 2: the body frame turned onto the chord from O to the front axle A (effects.local_curvature)",
}
PAPER_BANNER = ("This run uses the paper's conventions (conventions = \"paper\"): they reproduce its printed "
                "Tables 1 and 2, but two of them are physically inconsistent (an angular velocity per metre used as "
                "per second; a Λ* that is not a rotation), so its reactions and overloads are not the trolley's: "
                "at t = 10 s P3 is 571.8 N here against 4263.5 N physically. Run with conventions = \"physics\" "
                "(the default) for design numbers.")


def glossary(texts: list[str]) -> list[str]:
    """The explanations of the :data:`GLOSSARY` terms that ``texts`` use."""
    joined = " ".join(texts)
    return [meaning for term, meaning in GLOSSARY.items() if re.search(rf"\b{term}\b", joined)]


@dataclass(frozen=True)
class Derivation:
    module: str
    name: str
    meaning: str
    unit: str
    equations: str
    mathml: str | None  # None when too long to typeset (symmech.core.typeset.MATHML_LIMIT)


def _paper_package(kind: str) -> str | None:
    """``grain`` for a kind run by ``symmech.grain.*``, and for its sweep (``grain_sweep``); None for a kind
    nobody registered."""
    from symmech.core import registry

    try:
        module = registry.get(kind.removesuffix("_sweep")).run.__module__  # imports only the kind's own modules
    except SceneError:
        return None
    match = re.fullmatch(r"symmech\.(\w+)\..*", module)
    return match.group(1) if match else None


def _used_modules(summary: dict) -> list[str] | None:
    """The generated modules the run imported, and the one it wrote for its scene (mechanisms)."""
    used = list(summary["generated_modules"]) if isinstance(summary.get("generated_modules"), dict) else []
    if summary.get("generated_module"):
        used.append(Path(summary["generated_module"]).stem)
    return used or None


def _generated(package: str, used: list[str] | None) -> list[str]:
    """Generated modules of the paper package: those named in ``used`` (derived or printed), else every derived one;
    each derivation module's (by name) in the order it declares them (the generated index's order)."""
    from symmech.core import discovery
    from symmech.generated import MODULES

    if used:
        return [name for name, producer in MODULES.items() if name in used and producer.startswith(f"symmech.{package}.")]
    derived = {m for m in discovery.modules("derivation") if m.startswith(f"symmech.{package}.")}
    return [name for name, producer in MODULES.items() if producer in derived]


def _typeset_twin(module: Path) -> dict | None:
    """{function: (meaning, unit, equations, MathML or None)} from the MathML twin a run wrote beside its module
    ``module`` (``<name>_mathml.py``); None unless the twin is intact (integrity header, this release) and was made
    for the module text there (its source key is that text's sha256). Parsed as a literal, not executed."""
    read = integrity.literals(module.with_name(f"{module.stem}_mathml.py")) if module.is_file() else None
    if read is None or read[0].key != integrity.sha256(module.read_text(encoding="utf-8")):
        return None
    return read[1].get("FUNCTIONS")


def _own_mechanism(summary: dict, folder: Path | None) -> list[Derivation]:
    """The matrices of a mechanism scene of the user's own, whose module the run rendered (not in generated/): read
    from the MathML twin the run wrote beside the module in ``folder`` (:func:`_typeset_twin`), else (a twin missing,
    edited, stale or not the module's) derived again from the resolved scene the run recorded (sympy, seconds)."""
    module = Path(summary["generated_module"])
    shown = _typeset_twin(folder / module) if folder else None
    if shown is not None:
        return [Derivation(module.stem, name, *row) for name, row in shown.items()]
    from symmech.core import typeset
    from symmech.smm import build, derive

    spec = derive.module_spec(build.model(summary["scene"]))
    return [Derivation(spec.name, f.name, f.meaning, f.unit, f.equations, typeset.block(f)) for f in spec.functions]


def derivations(summary: dict, package: str | None, folder: Path | None = None) -> list[Derivation]:
    """The derived matrices behind the run (its output folder ``folder``): the modules it names, else its paper's
    derived modules (for a mechanism, whose modules are per scene, only the one the run used). A module of
    ``symmech.generated`` is read from its MathML twin (``<name>_mathml.py``, typeset by codegen: no sympy)."""
    from symmech.generated import MODULES

    used = _used_modules(summary)
    if package is None or (package == "smm" and not used):
        return []
    out = [Derivation(name, function, *shown) for name in _generated(package, used)
           for function, shown in importlib.import_module(f"symmech.generated.{name}_mathml").FUNCTIONS.items()]
    own = summary.get("generated_module")
    if package == "smm" and own and Path(own).stem not in MODULES:
        out += _own_mechanism(summary, folder)
    return out


def errata_records(package: str | None) -> list[dict]:
    """Evaluated errata checks of the paper package (printed formula vs derivation), each with its paper
    named for reading (``seed 002``) rather than by the seed file's stem."""
    from symmech.core import errata

    if package is None:
        return []
    return [{**record, "paper": f"seed {record['seed'].split('_', 1)[0]}"}
            for record in (errata.evaluate(c) for m in errata.modules(package) for c in m.checks())]


def paper_title(package: str | None) -> str:
    """The paper of a paper package in words, from its docstring ("Paper 2 (seed 002): a two-axle trolley
    ..."); empty for none."""
    if package is None:
        return ""
    doc = importlib.import_module(f"symmech.{package}").__doc__ or ""
    return doc.strip().split("\n", 1)[0].rstrip(".")


def scene_title(scene: dict) -> str:
    """The report's title: the scene's ``title``, else its ``description`` (mechanisms), else nothing; the
    backticks of Markdown code dropped (a title is plain text)."""
    return str(scene.get("title") or scene.get("description") or "").replace("`", "")


def _text(value) -> str:
    return f"{value:.6g}" if isinstance(value, float) else "null" if value is None else str(value)


def _headline(summary: dict) -> list[dict]:
    """Rows (name, value in its readable unit, at, meaning, limit, verdict, mark) of the summary's headline;
    an answer with a limit has it as text and is coloured by its verdict as the checks are."""
    rows = []
    for h in summary.get("headline", []):
        limit, verdict = h.get("limit"), h.get("verdict")
        rows.append({"name": readable(h["name"]), "value": units.format(h["value"], h["unit"], 4),
                     "at": readable(h["at"]), "meaning": readable(h["meaning"]),
                     "limit": (f"within [{units.format(limit[0], h['unit'])}, {units.format(limit[1], h['unit'])}]"
                               if limit else ""),
                     "verdict": verdict or "", "mark": VERDICTS[verdict] if verdict else ""})
    return rows


def _checks(summary: dict) -> list[dict]:
    """Rows (what, measured, threshold, verdict, mark) of the summary's checks, failures first."""
    order = {"fail": 0, "warn": 1, "pass": 2}
    rows = []
    for c in summary.get("checks", []):
        value = tuple(c["value"]) if isinstance(c["value"], list) else c["value"]
        check = Check(c["what"], value, c["unit"], c["threshold"], c["verdict"])
        rows.append({"what": readable(check.what), "measured": check.measured(), "threshold": check.threshold,
                     "verdict": check.verdict, "mark": VERDICTS[check.verdict]})
    return sorted(rows, key=lambda r: order[r["verdict"]])


def _precision(out: Path, summary: dict) -> dict | None:
    """The work-precision study in ``out`` (a study folder) or ``out/precision``: its figures and rows,
    with the rows whose knob has the run's own setting marked (the chosen method's place)."""
    folder = out if summary.get("study") == "precision" else out / PRECISION_FOLDER
    try:
        study = json.loads((folder / "summary.json").read_text())
    except (FileNotFoundError, json.JSONDecodeError):
        return None
    if study.get("study") != "precision":
        return None
    chosen = _settings(summary.get("scene", {})) if folder != out else {}
    name = next(iter(study.get("tables", {})), None)
    header, records = [], []
    if name is not None:
        with open(folder / f"{name}.csv", newline="") as fh:
            header, *records = list(csv.reader(fh))
    mine = [_is_chosen(dict(zip(header, cells)), chosen) for cells in records]
    figures = _diagram(study, name, header, records, mine) if any(mine) else _figures(folder, {})
    return {"folder": str(folder), "reference": study.get("reference", ""), "figures": figures, "header": header,
            "rows": [{"cells": [_cell(c) for c in cells], "chosen": m} for cells, m in zip(records, mine)],
            "own": folder == out}


def _diagram(study: dict, name: str, header: list[str], records: list[list[str]], mine: list[bool]) -> list:
    """The study's work-precision diagram drawn again with the run's own setting ringed, as a figure."""
    import tempfile

    from symmech.core import precision

    rows = [dict(zip(header, cells)) for cells in records]
    points = [{"method": r["method"], "seconds": float(r["seconds [s]"]), "error": float(r["error [1]"])}
              for r in rows]
    with tempfile.TemporaryDirectory() as tmp:
        precision.diagram(points, Path(tmp), name, study["tables"][name].get("doc", name), study.get("reference", ""),
                          [p for p, m in zip(points, mine) if m])
        return _figures(Path(tmp), {})


def _cell(text: str) -> str:
    """A CSV cell for reading: numbers to 3 digits, text as it is."""
    try:
        return f"{float(text):.3g}"
    except ValueError:
        return text


def _settings(scene: dict) -> dict:
    """{field name: value} of every number and text field of a resolved scene, by its last name."""
    out = {}
    for key, value in scene.items():
        if isinstance(value, dict):
            out.update(_settings(value))
        elif isinstance(value, (int, float, str)) and not isinstance(value, bool):
            out[key] = value
    return out


def _is_chosen(row: dict, chosen: dict) -> bool:
    """Is a study row (method, knob, value) the run's own setting: the scene's field named as the knob
    has the row's value, and the row's method begins with the scene's ``mode``, ``method`` or (solver)
    ``name``, if it has one?"""
    knob, value = row.get("knob"), row.get("value [1]")
    setting = chosen.get(knob)
    if value is None or not isinstance(setting, (int, float)) or not math.isclose(float(value), setting,
                                                                                  rel_tol=1e-9):
        return False
    ways = [str(chosen[k]).lower() for k in ("mode", "method", "name") if isinstance(chosen.get(k), str)]
    return not ways or any(row.get("method", "").lower().startswith(w) for w in ways)


def _figures(out: Path, captions: dict) -> list[tuple[str, str]]:
    """(caption, data URI) of every plot in ``out``: the SVG when there is one, else the PNG; the caption the run
    recorded for it (``captions``: {file stem: sentence}, in the order the scene asked for them), else its file
    name, after the captioned ones."""
    stems = {p.stem for ext in ("png", "svg") for p in out.glob(f"*.{ext}")}
    figures = []
    for stem in [s for s in captions if s in stems] + sorted(stems - set(captions)):
        svg = out / f"{stem}.svg"
        path, mime = (svg, "image/svg+xml") if svg.exists() else (out / f"{stem}.png", "image/png")
        data = base64.b64encode(path.read_bytes()).decode("ascii")
        figures.append((captions.get(stem, stem.replace("_", " ")), f"data:{mime};base64,{data}"))
    return figures


def _module_hashes(summary: dict, names: list[str], out: Path) -> tuple[dict, str]:
    """Generated-module hashes: the run's own record, else the header lines of the modules
    (a module the run wrote into ``out`` first, then the installed ``symmech.generated``)."""
    recorded = summary.get("generated_modules")
    hashes = dict(recorded) if isinstance(recorded, dict) else {}
    for name in (n for n in names if n not in hashes):
        path = out / f"{name}.py"
        if not path.exists():
            spec = importlib.util.find_spec(f"symmech.generated.{name}")
            if spec is None or spec.origin is None:
                continue
            path = Path(spec.origin)
        match = re.search(r"inputs sha256 ([0-9a-f]{64})", path.read_text().split("\n", 1)[0])
        hashes[name] = match.group(1) if match else "unknown"
    if isinstance(recorded, dict):
        return hashes, ("body sha256 of each imported module, recorded by the run; the scene's own module: "
                        "inputs sha256 from its first line")
    return hashes, "inputs sha256 from each module's first line, read at report time (the run recorded none)"


def _wall_time(summary: dict) -> str:
    """The run's wall time: the pipeline's ``timing_s`` phases, else a kind's own figure."""
    timing = summary.get("timing_s")
    if isinstance(timing, dict):
        return ", ".join(f"{phase} {units.format(seconds, 's', 3)}" for phase, seconds in timing.items())
    seconds = summary.get("wall_time_s", summary.get("elapsed_s"))
    return units.format(seconds, "s", 3) if isinstance(seconds, (int, float)) else "not recorded"


def _read_summary(out: Path) -> dict:
    summary_path = out / "summary.json"
    try:
        return json.loads(summary_path.read_text())
    except FileNotFoundError:
        raise SymmechError(f"{summary_path}: no such file (run `symmech run SCENE --out {out}` first)") from None
    except json.JSONDecodeError as exc:
        raise SymmechError(f"{summary_path}: not valid JSON ({exc.msg} at line {exc.lineno})") from None


def run_precision(out: Path, ctx) -> Path:
    """Run the work-precision study of the run's scene (``symmech bench precision``) into
    ``out/precision``, where :func:`render` finds it; the scene file the run names if it is still
    there, else the resolved scene it recorded. Returns the study's folder."""
    from symmech.core import pipeline

    summary = _read_summary(Path(out))
    source = summary.get("scene_file")
    scene = source if source and Path(source).is_file() else summary.get("scene")
    if not isinstance(scene, (str, dict)):
        raise SymmechError(f"{out}/summary.json names no scene to study (run `symmech bench precision SCENE "
                           f"--out {out}/{PRECISION_FOLDER}` instead)")
    target = Path(out) / PRECISION_FOLDER
    pipeline.run_to(scene, target, ctx, study="precision")
    return target


def _scene_file(summary: dict) -> str:
    """Where the scene came from: its path, or that it was given as a table (the Python API)."""
    source = summary.get("scene_file")
    if source is None:
        return "not recorded"
    return "given as a table, not a file (Python API)" if str(source).startswith("<") else str(source)


def render(out: Path) -> str:
    """The HTML text of the report on the run in folder ``out``."""
    import jinja2

    summary = _read_summary(Path(out))
    kind = str(summary.get("kind", "unknown"))
    package = _paper_package(kind)
    derived = derivations(summary, package, Path(out))
    checks = _checks(summary)
    headline = _headline(summary)
    warnings = [readable(w) for w in summary.get("warnings", [])]
    hashes, hash_source = _module_hashes(summary, sorted({d.module for d in derived}), Path(out))
    provenance = [("symmech version of the run", _text(summary.get("symmech_version", "not recorded"))),
                  ("status", _text(summary.get("status", "not recorded"))),
                  ("wall time", _wall_time(summary)),
                  ("scene file", _scene_file(summary)),
                  ("report written by", f"symmech {__version__}, Python {platform.python_version()}"),
                  ("report written at", datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"))]
    env = jinja2.Environment(loader=jinja2.FunctionLoader(
        lambda name: importlib.resources.files("symmech").joinpath(name).read_text(encoding="utf-8")),
        autoescape=True, trim_blocks=True, lstrip_blocks=True)
    return env.get_template(TEMPLATE).render(
        kind=kind, package=package, out=str(out), summary=summary,
        title=scene_title(summary.get("scene", {})),
        scene=json.dumps(summary["scene"], indent=2) if "scene" in summary else None,
        raw=json.dumps({k: v for k, v in summary.items() if k != "scene"}, indent=2),
        headline=headline, checks=checks, attention=[c for c in checks if c["verdict"] != "pass"],
        glossary=glossary([h["name"] for h in headline] + [c["what"] for c in checks]),
        paper=summary.get("scene", {}).get("conventions") == "paper", paper_banner=PAPER_BANNER,
        paper_tables=summary.get("paper_tables"),
        precision=_precision(Path(out), summary), derivations=derived, warnings=warnings,
        errata=errata_records(package), paper_title=paper_title(package), figures=_figures(Path(out), summary.get("captions", {})),
        provenance=provenance,
        hashes=hashes, hash_source=hash_source)


def write(out: Path) -> Path:
    """Write ``out/report.html``; returns its path."""
    path = Path(out) / "report.html"
    path.write_text(render(Path(out)), encoding="utf-8")
    return path
