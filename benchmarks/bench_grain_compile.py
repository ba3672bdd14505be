"""Cold start of the compiled grain engine: import + numba compile + first call in a fresh process.

Each round runs, in fresh processes with an empty ``NUMBA_CACHE_DIR`` (everything compiles: the generated
kernels and the loop), this tree and optionally another source tree (``--before DIR``, e.g. a ``git archive``
of an earlier commit), interleaved; then the cached start (cache beside the module, warmed first).

    python benchmarks/bench_grain_compile.py --before /tmp/before --repeats 5
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from timing import interleaved, machine, ratio

HERE = Path(__file__).resolve().parents[1]
CODE = ("from symmech.core import pipeline; from symmech.grain import compiled; "
        "sc = pipeline.load('scenes/grain_default.toml').setup; "
        "compiled.simulate(sc.model, sc.numerics, sc.start, 0.01)")


def fresh(tree: Path, cold: bool) -> None:
    """One fresh process on ``tree``; with ``cold`` an empty numba cache."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    with tempfile.TemporaryDirectory() as cache:
        if cold:
            env["NUMBA_CACHE_DIR"] = cache
        subprocess.run([sys.executable, "-c", CODE], cwd=tree, env=env, check=True, capture_output=True)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--before", type=Path, help="another source tree to compare (cold)")
    p.add_argument("--repeats", type=int, default=5)
    a = p.parse_args()
    print(f"machine: {machine()}")
    trees = {"this tree": HERE, **({"before": a.before.resolve()} if a.before else {})}
    cold = interleaved({f"cold, {k}": (lambda t=t: fresh(t, True)) for k, t in trees.items()}, a.repeats)
    for label, s in cold.items():
        print(f"  {label:<18} {s.text()}")
    if a.before:
        print(f"  before/this: {ratio(cold['cold, before'], cold['cold, this tree'])}")
    fresh(HERE, False)  # warm the cache beside the module
    warm = interleaved({"cached, this tree": lambda: fresh(HERE, False)}, a.repeats)
    print(f"  {'cached, this tree':<18} {warm['cached, this tree'].text()}")


if __name__ == "__main__":
    main()
