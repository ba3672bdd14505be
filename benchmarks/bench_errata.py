"""What a paper's errata records cost a report, in fresh processes, for checkouts side by side.

Per round and per checkout (``--tree``, interleaved): the CPU seconds of ``report.errata_records(PAPER)``
inside a fresh interpreter (imports included, numpy imported before) and whether sympy was imported by it;
and the CPU (children's getrusage) and wall seconds of ``symmech run SCENE --report --quiet`` and of the same
run without ``--report``. Each checkout runs on its own generated code (``timing.tree_env``).

Run: python benchmarks/bench_errata.py --tree OLD --tree NEW [--paper smm] [--scene scenes/smm_rotor_boom.toml]
     [--repeats 5]
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time

from timing import Stats, child_cpu, machine, tree_env

PROBE = """\
import sys, time
import numpy  # not part of the measure
start = time.process_time()
from symmech import report
records = report.errata_records({paper!r})
print(time.process_time() - start, len(records), "sympy" in sys.modules)
"""


def _records(tree: str, paper: str) -> tuple[float, int, bool]:
    out = subprocess.run([sys.executable, "-c", PROBE.format(paper=paper)], env=tree_env(tree), cwd=tree,
                         capture_output=True, text=True, check=True).stdout.split()
    return float(out[0]), int(out[1]), out[2] == "True"


def _run(tree: str, scene: str, report: bool) -> tuple[float, float]:
    """(CPU, wall) seconds of one ``symmech run`` of ``scene`` in ``tree``."""
    with tempfile.TemporaryDirectory() as out:
        command = [sys.executable, "-m", "symmech", "run", scene, "--out", out, "--quiet"] + ["--report"] * report
        start = time.perf_counter()
        cpu, _ = child_cpu(command, env=tree_env(tree), cwd=tree, stdout=subprocess.DEVNULL)
    return cpu, time.perf_counter() - start


def _line(label: str, values: list[float]) -> str:
    return f"{label:<34} {Stats.of(values).text()}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--tree", action="append", required=True, help="a checkout (repeat to compare)")
    ap.add_argument("--paper", default="smm")
    ap.add_argument("--scene", default="scenes/smm_rotor_boom.toml")
    ap.add_argument("--repeats", type=int, default=5)
    ns = ap.parse_args()
    print(machine())
    samples = {tree: {"records": [], "run": [], "run wall": [], "report": [], "report wall": []} for tree in ns.tree}
    sympy, count = {}, {}
    for _ in range(ns.repeats):
        for tree in ns.tree:
            s = samples[tree]
            cpu, count[tree], sympy[tree] = _records(tree, ns.paper)
            s["records"].append(cpu)
            for key, report in (("run", False), ("report", True)):
                cpu, wall = _run(tree, ns.scene, report)
                s[key].append(cpu)
                s[f"{key} wall"].append(wall)
    for tree in ns.tree:
        print(f"{tree}: {count[tree]} records of {ns.paper}, sympy imported: {sympy[tree]}")
        s = samples[tree]
        print(_line(f"  errata_records({ns.paper!r}) CPU", s["records"]))
        for key, what in (("run", "run"), ("report", "run --report")):
            print(_line(f"  {what} CPU", s[key]))
            print(_line(f"  {what} wall", s[f"{key} wall"]))


if __name__ == "__main__":
    main()
