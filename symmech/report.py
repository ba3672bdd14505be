"""``symmech report OUT``: one self-contained HTML page about a finished run.

Reads ``OUT/summary.json`` and the plots in ``OUT`` and writes ``OUT/report.html``
with: the resolved scene, the derivations the run used as MathML (browsers render
it natively), the checks and results with their numbers, the errata of the
scene's paper, the plots (inline SVG, else PNG, as data URIs) and the provenance
(version, generated-module hashes, wall time). Nothing is fetched to view it.

Which derivations and errata belong to a kind is found, not listed: the kind's
runtime module lives in a paper package ``symmech.<paper>``; its generated
modules are named ``<paper>_*`` and its errata are ``symmech.<paper>.errata*``.
"""
from __future__ import annotations

import base64
import datetime
import functools
import importlib
import importlib.resources
import importlib.util
import json
import platform
import re
from dataclasses import dataclass
from pathlib import Path

from symmech import __version__
from symmech.core.scene import SymmechError

TEMPLATE = "report.html.j2"
# Derivations whose sympy text is longer than this are listed, not typeset (H alone
# is 19,000 characters: MathML of it would be megabytes nobody reads).
MATHML_LIMIT = 2500
# Summary keys about where and how the run happened, shown as provenance.
PROVENANCE = ("symmech_version", "status", "wall_time_s", "elapsed_s", "timing_s", "generated_modules",
              "generated_module", "scene_file")
SKIPPED = ("kind", "scene", "files", "warnings", *PROVENANCE)
# Summary keys whose name says they hold a check (a residual, a verdict, a count of violations).
CHECK_WORDS = ("residual", "converged", "admissible", "creating_energy", "creates_energy", "comfort", "defect",
               "error", "check", "unstable", "rigid_body")


@dataclass(frozen=True)
class Derivation:
    module: str
    name: str
    meaning: str
    unit: str
    equations: str
    mathml: str | None  # None when too long to typeset


def _paper_package(kind: str) -> str | None:
    """``grain`` for a kind run by ``symmech.grain.*`` (None for a kind nobody registered)."""
    from symmech.core import registry

    try:
        module = registry.kinds()[kind].run.__module__
    except KeyError:
        return None
    match = re.fullmatch(r"symmech\.(\w+)\..*", module)
    return match.group(1) if match else None


def _name_mathml(name: str) -> str:
    import sympy
    from sympy.printing.mathml import mathml

    head = name.split("_", 1)[0]
    if len(head) == 1 or head.lower() in ("lambda", "omega", "theta", "phi", "psi"):
        return mathml(sympy.Symbol(name), printer="presentation")
    return f"<mtext>{name}</mtext>"


def _used_modules(summary: dict) -> list[str] | None:
    """The generated modules the run imported, and the one it wrote for its scene (mechanisms)."""
    used = list(summary["generated_modules"]) if isinstance(summary.get("generated_modules"), dict) else []
    if summary.get("generated_module"):
        used.append(Path(summary["generated_module"]).stem)
    return used or None


@functools.cache
def _module_specs(module: str) -> tuple:
    """The specs a derivation module declares, derived once per process."""
    return tuple(importlib.import_module(module).module_specs())


def _specs(package: str | None, used: list[str] | None) -> list:
    """ModuleSpecs of the paper package: those named in ``used`` (derived or printed), else
    every derived one. Only this package's derivations run, and no more than needed."""
    from symmech.core import codegen

    if package is None:
        return []
    specs = []
    for module in codegen.paper_modules(("derive", "printed") if used else ("derive",)):
        if module.__name__.startswith(f"symmech.{package}."):
            specs += [s for s in _module_specs(module.__name__) if not used or s.name in used]
            if used and set(used) <= {s.name for s in specs}:
                break
    return specs


def derivations(summary: dict, package: str | None) -> list[Derivation]:
    """The derived matrices behind the run: the modules it names, else its paper's derived modules
    (for a mechanism, whose modules are per scene, only the one the run used)."""
    from sympy.printing.mathml import mathml

    used = _used_modules(summary)
    specs = [] if package == "smm" and not used else _specs(package, used)
    out = []
    for spec in specs:
        for f in spec.functions:
            expr = f.matrix if f.shape else f.matrix[0, 0]
            typeset = None
            if len(str(expr)) <= MATHML_LIMIT:
                rhs = mathml(expr, printer="presentation")
                typeset = (f'<math display="block"><mrow>{_name_mathml(f.name)}<mo>=</mo>{rhs}</mrow></math>')
            out.append(Derivation(spec.name, f.name, f.meaning, f.unit, f.equations, typeset))
    return out


def errata_records(package: str | None) -> list[dict]:
    """Evaluated errata checks of the paper package (printed formula vs derivation)."""
    from symmech.core import codegen, errata

    if package is None:
        return []
    modules = [m for m in codegen.paper_modules(("errata",)) if m.__name__.startswith(f"symmech.{package}.")]
    return [errata.evaluate(c) for m in modules for c in m.checks()]


def _flatten(value, prefix: str = "") -> list[tuple[str, str]]:
    """(dotted key, text) rows of a JSON value; long lists are summarised, and a measurement
    (a dict of scalars with a ``unit``, e.g. extremes and their times) is one row."""
    if isinstance(value, dict) and "unit" in value and not any(isinstance(v, (dict, list)) for v in value.values()):
        parts = ", ".join(f"{k} = {_text(v)}" for k, v in value.items() if k != "unit")
        return [(prefix, f"{parts} (unit {value['unit']})")]
    if isinstance(value, dict):
        rows = []
        for k, v in value.items():
            rows += _flatten(v, f"{prefix}.{k}" if prefix else str(k))
        return rows
    if isinstance(value, list) and value and all(isinstance(v, dict) for v in value) and len(value) <= 12:
        rows = []
        for i, v in enumerate(value):
            rows += _flatten(v, f"{prefix}[{i}]")
        return rows
    return [(prefix, _text(value))]


def _text(value) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, list):
        if len(value) > 12:
            return f"list of {len(value)} values"
        return "[" + ", ".join(_text(v) for v in value) + "]"
    return "null" if value is None else str(value)


def _split_checks(summary: dict) -> tuple[list, list]:
    """(checks, results): rows of the summary; a row is a check when its key says so."""
    rows = _flatten({k: v for k, v in summary.items() if k not in SKIPPED})
    checks = [r for r in rows if any(w in r[0].lower() for w in CHECK_WORDS)]
    return checks, [r for r in rows if r not in checks]


def _figures(out: Path) -> list[tuple[str, str]]:
    """(title, data URI) of every plot in ``out``: the SVG when there is one, else the PNG."""
    figures = []
    for stem in sorted({p.stem for ext in ("png", "svg") for p in out.glob(f"*.{ext}")}):
        svg = out / f"{stem}.svg"
        path, mime = (svg, "image/svg+xml") if svg.exists() else (out / f"{stem}.png", "image/png")
        data = base64.b64encode(path.read_bytes()).decode("ascii")
        figures.append((stem.replace("_", " "), f"data:{mime};base64,{data}"))
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
        return ", ".join(f"{phase} {_text(seconds)}" for phase, seconds in timing.items())
    return _text(summary.get("wall_time_s", summary.get("elapsed_s", "not recorded")))


def render(out: Path) -> str:
    """The HTML text of the report on the run in folder ``out``."""
    import jinja2

    summary_path = Path(out) / "summary.json"
    try:
        summary = json.loads(summary_path.read_text())
    except FileNotFoundError:
        raise SymmechError(f"{summary_path}: no such file (run `symmech run SCENE --out {out}` first)") from None
    except json.JSONDecodeError as exc:
        raise SymmechError(f"{summary_path}: not valid JSON ({exc.msg} at line {exc.lineno})") from None
    kind = str(summary.get("kind", "unknown"))
    package = _paper_package(kind)
    derived = derivations(summary, package)
    checks, results = _split_checks(summary)
    hashes, hash_source = _module_hashes(summary, sorted({d.module for d in derived}), Path(out))
    provenance = [("symmech version of the run", _text(summary.get("symmech_version", "not recorded"))),
                  ("status", _text(summary.get("status", "not recorded"))),
                  ("wall time [s]", _wall_time(summary)),
                  ("scene file", _text(summary.get("scene_file", "not recorded"))),
                  ("report written by", f"symmech {__version__}, Python {platform.python_version()}"),
                  ("report written at", datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"))]
    env = jinja2.Environment(loader=jinja2.FunctionLoader(
        lambda name: importlib.resources.files("symmech").joinpath(name).read_text(encoding="utf-8")),
        autoescape=True, trim_blocks=True, lstrip_blocks=True)
    return env.get_template(TEMPLATE).render(
        kind=kind, package=package, out=str(out), summary=summary,
        scene=json.dumps(summary["scene"], indent=2) if "scene" in summary else None,
        derivations=derived, checks=checks, results=results, warnings=summary.get("warnings", []),
        errata=errata_records(package), figures=_figures(Path(out)), provenance=provenance,
        hashes=hashes, hash_source=hash_source)


def write(out: Path) -> Path:
    """Write ``out/report.html``; returns its path."""
    path = Path(out) / "report.html"
    path.write_text(render(Path(out)), encoding="utf-8")
    return path
