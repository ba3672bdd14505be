"""What the import-time integrity check costs.

Each sample is a fresh interpreter importing a set of generated modules, timed inside
the process from ``import symmech.generated`` on (numpy and numba imported before); the baseline imports the same
modules with the body hashing switched off (``integrity.verify_file`` replaced by a
no-op), so the difference is the check alone. Sets: the four modules a trolley run
imports, and every module of the package (numpy and numba twins, 1.2 MB of text).

Run: python benchmarks/bench_integrity.py [--quick]
"""
from __future__ import annotations

import subprocess
import sys

from timing import Stats, machine

TROLLEY = ["trolley_dynamics", "trolley_elastic", "trolley_frame", "trolley_printed"]
PROBE = """\
import importlib, time
import numpy, numba  # not part of the measure
from symmech.core import integrity
if {off}:
    integrity.verify_file = lambda name, path: None
start = time.perf_counter()
import symmech.generated as g
names = {names!r} or [n + s for n in g.MODULES for s in ("", "_nb")]
for name in names:
    importlib.import_module("symmech.generated." + name)
print(time.perf_counter() - start)
"""


def _sample(names: list[str], off: bool) -> float:
    code = PROBE.format(off=off, names=names)
    return float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout)


def main() -> None:
    repeats = 5 if "--quick" in sys.argv else 9
    print(f"import-time integrity check, {machine()}; median of {repeats} interleaved fresh processes")
    for label, names in (("trolley run's 4 modules", TROLLEY), ("all 33 files", [])):
        samples = {True: [], False: []}
        for _ in range(repeats):
            for off in (True, False):
                samples[off].append(_sample(names, off))
        unchecked, checked = (Stats.of(s) for s in samples.values())
        print(f"{label}: checked {checked.text('ms', 1e3)}, unchecked {unchecked.text('ms', 1e3)}, "
              f"check costs {1e3 * (checked.median - unchecked.median):+.1f} ms")


if __name__ == "__main__":
    main()
