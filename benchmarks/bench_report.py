"""What a report's derivations section costs: a bundled scene's run with ``--report``, and ``report.derivations``.

Two source trees side by side (``--base``: a checkout whose report derives every module again in sympy; the tree of
this file: the report reads the MathML codegen typeset into ``generated/``), each child process run with its own
tree's ``generated/``, ``templates/`` and ``scenes/`` (:func:`timing.tree_env`), rounds interleaved. The runs are
timed by the children's CPU time (getrusage); ``report.derivations`` by ``time.process_time`` around the call alone
in a fresh interpreter (symmech.report imported before), on the summaries of grain_default (its modules), a summary
naming no module for the trolley (every derived module of the paper) and smm_rotor_boom (its mechanism's module).
The numba cache (``NUMBA_CACHE_DIR``) should be fresh and is warmed by one untimed round.

Run: python benchmarks/bench_report.py --base BASE_TREE [--repeats 5]
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

from timing import child_cpu, print_base_this, tree_env

HERE = Path(__file__).resolve().parents[1]
RUNS = ("grain_default", "trolley_helix")
DERIVE = """\
import json, time
from symmech import report
summary = json.loads({summary!r})
start = time.process_time()
report.derivations(summary, {package!r})
print(time.process_time() - start)
"""


def run_report_seconds(tree: Path, scene: Path, out: Path) -> float:
    """CPU seconds of ``symmech run SCENE --report`` with ``tree`` (a fresh process, the children's getrusage)."""
    command = [sys.executable, "-m", "symmech", "run", str(scene), "--out", str(out), "--report", "--quiet"]
    return child_cpu(command, cwd=tree, env=tree_env(tree), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)[0]


def _derive_seconds(tree: Path, summary: dict, package: str) -> float:
    """CPU seconds of ``report.derivations(summary, package)`` alone with ``tree``."""
    code = DERIVE.format(summary=json.dumps(summary), package=package)
    return float(subprocess.run([sys.executable, "-c", code], check=True, cwd=tree, env=tree_env(tree),
                                capture_output=True, text=True).stdout)


def _summaries(tree: Path, out: Path) -> dict[str, tuple[dict, str]]:
    """{case: (summary, paper package)} for the ``report.derivations`` measures, from runs made by ``tree``."""
    def summary(scene):
        return json.loads((out / scene / "summary.json").read_text())

    subprocess.run([sys.executable, "-m", "symmech", "run", str(tree / "scenes" / "smm_rotor_boom.toml"), "--out",
                    str(out / "smm_rotor_boom"), "--quiet"], check=True, cwd=tree, env=tree_env(tree))
    return {"grain_default": (summary("grain_default"), "grain"), "trolley (every module)": ({}, "trolley"),
            "smm_rotor_boom": (summary("smm_rotor_boom"), "smm")}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--base", type=Path, required=True)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    trees = {"base": args.base.resolve(), "this": HERE}
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        for name, tree in trees.items():  # warms the numba cache; the summaries for report.derivations
            for scene in RUNS:
                run_report_seconds(tree, tree / "scenes" / f"{scene}.toml", out / name / scene)
        cases = _summaries(HERE, out / "this")
        samples: dict[tuple[str, str], list[float]] = {}
        for _ in range(args.repeats):
            for name, tree in trees.items():
                for scene in RUNS:
                    samples.setdefault((f"run {scene} --report", name), []).append(
                        run_report_seconds(tree, tree / "scenes" / f"{scene}.toml", out / name / scene))
                for case, (summary, package) in cases.items():
                    samples.setdefault((f"report.derivations {case}", name), []).append(
                        _derive_seconds(tree, summary, package))
    print_base_this(samples, args.repeats)


if __name__ == "__main__":
    main()
