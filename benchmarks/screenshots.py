"""Every bundled scene's and sweep's report, run as bundled and photographed in Chromium, for review.

    nice -n 10 python benchmarks/screenshots.py --shots /work/shots/s14            # everything
    python benchmarks/screenshots.py --shots DIR trolley_helix grain_separation   # only the names given
    python benchmarks/screenshots.py --shots DIR --reuse                          # photograph existing runs again
    python benchmarks/screenshots.py --shots DIR --rereport                       # their reports written again first

Each scene of scenes/ runs as a user runs it: a scene with a ``[sweep]`` table by ``symmech sweep`` then
``symmech report``, any other by ``symmech run --report``, unchanged (no shortened ``--max-time``), into
``SHOTS/runs/NAME``. Two more sweeps of our own (:data:`OWN_SWEEPS`: variants of the bundled ones written into
``SHOTS/scenes``) run the same way. Each ``report.html`` is then photographed twice with Chromium (Playwright):
``SHOTS/NAME_fold.png``, the first screen a designer sees (1280 x 900), and ``SHOTS/NAME_full.png``, the whole
page. A run that fails is reported with its stderr's last line and the others go on. Chromium: the system's
``chromium`` (what the CI installs), else Playwright's own.
"""
from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENES = ROOT / "scenes"
FOLD = {"width": 1280, "height": 900}  # the first screen of a laptop
# name: (bundled scene, {dotted field: value}) of sweeps beyond the bundled ones, for the report's other answers
OWN_SWEEPS = {
    # one axis, grain: the transport sweep along amplitude alone (a line chart, not a map)
    "grain_transport_amplitude": ("grain_transport_sweep.toml", {
        "title": "Crop transport along the vibration amplitude at 25 Hz, at most half the grains hopping",
        "sweep.y": None, "sweep.x.num": 7}),
    # the elastic sweep over speed and roller damping, 6 x 4: every limit of the ride on one grid
    "trolley_elastic_damping": ("trolley_elastic_sweep.toml", {
        "title": "Elastic trolley: the fastest ride onto the helix without lift-off, over the roller damping",
        "sweep.x.num": 6, "sweep.y": {"field": "elastic.rollers.damping", "start": 2e3, "stop": 2e4, "num": 4,
                                      "log": True}}),
}


def has_sweep(path: Path) -> bool:
    return "sweep" in tomllib.loads(path.read_text())


def own_scene(name: str, folder: Path) -> Path:
    """The scene file of an own sweep: its bundled scene with the changed fields (None: removed)."""
    file, changes = OWN_SWEEPS[name]
    text = (SCENES / file).read_text()
    raw = tomllib.loads(text)
    for dotted, value in changes.items():
        *parents, last = dotted.split(".")
        table = raw
        for key in parents:
            table = table[key]
        if value is None:
            table.pop(last)
        else:
            table[last] = value
    path = folder / f"{name}.toml"
    path.write_text(toml_text(raw))
    return path


def toml_text(data: dict, prefix: str = "") -> str:
    """TOML of a scene table: plain values first, then sub-tables and arrays of tables (enough for scenes)."""
    lines, tables = [], []
    for key, value in data.items():
        if isinstance(value, dict):
            tables.append((key, value))
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            tables.extend((key, [v]) for v in value)
        else:
            lines.append(f"{quoted(key)} = {toml_value(value)}")
    text = "\n".join(lines) + ("\n" if lines else "")
    for key, value in tables:
        name = f"{prefix}{quoted(key)}"
        if isinstance(value, list):
            text += f"\n[[{name}]]\n" + toml_text(value[0], f"{name}.")
        else:
            text += f"\n[{name}]\n" + toml_text(value, f"{name}.")
    return text


def quoted(key: str) -> str:
    return key if key.replace("_", "").isalnum() else f'"{key}"'


def toml_value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(value, list):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{quoted(k)} = {toml_value(v)}" for k, v in value.items()) + "}"
    return repr(value)


def run_scene(path: Path, out: Path) -> str:
    """Run one scene into ``out`` and write its report; '' or the failure's last line."""
    symmech = [sys.executable, "-m", "symmech"]
    steps = ([[*symmech, "sweep", str(path), "--out", str(out)], [*symmech, "report", str(out)]] if has_sweep(path)
             else [[*symmech, "run", str(path), "--out", str(out), "--report"]])
    for step in steps:
        done = subprocess.run(step, capture_output=True, text=True)
        if done.returncode != 0:
            return (done.stderr.strip().splitlines() or [f"exit {done.returncode}"])[-1]
    return ""


def chromium(playwright):
    """The system's Chromium when there is one (what the CI installs; root: without the sandbox), else
    Playwright's own (``python -m playwright install chromium``)."""
    system = next((p for p in map(shutil.which, ("chromium", "chromium-browser")) if p), None)
    if system is not None:
        return playwright.chromium.launch(executable_path=system, args=["--no-sandbox"])
    return playwright.chromium.launch()


def photograph(reports: dict[str, Path], shots: Path) -> None:
    from playwright.sync_api import sync_playwright

    with sync_playwright() as p:
        browser = chromium(p)
        for name, html in reports.items():
            page = browser.new_page(viewport=FOLD)
            page.goto(html.as_uri(), wait_until="load")
            page.screenshot(path=str(shots / f"{name}_fold.png"))
            page.screenshot(path=str(shots / f"{name}_full.png"), full_page=True)
            page.close()
            print(f"{name}: {shots / (name + '_fold.png')}, {shots / (name + '_full.png')}", flush=True)
        browser.close()


def main(argv: list[str]) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n", 1)[0])
    parser.add_argument("names", nargs="*", help="scene names (file stems) or own sweeps; default: all")
    parser.add_argument("--shots", type=Path, required=True, help="folder of the screenshots, runs and scenes")
    parser.add_argument("--reuse", action="store_true", help="photograph the reports already in SHOTS/runs")
    parser.add_argument("--rereport", action="store_true",
                        help="write the reports of the runs already in SHOTS/runs again (`symmech report`), then "
                             "photograph them: a report's change seen without running the scenes again")
    ns = parser.parse_args(argv)
    scenes = {p.stem: p for p in sorted(SCENES.glob("*.toml"))}
    names = ns.names or [*scenes, *OWN_SWEEPS]
    unknown = [n for n in names if n not in scenes and n not in OWN_SWEEPS]
    if unknown:
        raise SystemExit(f"unknown scene {unknown[0]!r}; choose from {', '.join([*scenes, *OWN_SWEEPS])}")
    (ns.shots / "scenes").mkdir(parents=True, exist_ok=True)
    reports = {}
    for name in names:
        out = ns.shots / "runs" / name
        if ns.rereport:
            subprocess.run([sys.executable, "-m", "symmech", "report", str(out)], capture_output=True, check=True)
        elif not ns.reuse:
            path = scenes[name] if name in scenes else own_scene(name, ns.shots / "scenes")
            started = time.perf_counter()
            failure = run_scene(path, out)
            print(f"{name}: {'failed: ' + failure if failure else 'ran'} in {time.perf_counter() - started:.0f} s",
                  flush=True)
        if (out / "report.html").is_file():
            reports[name] = out / "report.html"
    photograph(reports, ns.shots)


if __name__ == "__main__":
    main(sys.argv[1:])
