"""The first rhs and jac calls of a generated numba twin with a mass matrix, in a fresh process on an empty numba
cache: what a user's first `kernels.load(name).rhs(t, y, p)` costs before anything is cached.

    python benchmarks/bench_twin_compile.py                          # this tree, 5 rounds
    python benchmarks/bench_twin_compile.py --baseline DIR --repeats 5   # side by side with the tree at DIR

Each run: a process with its own empty NUMBA_CACHE_DIR, `kernels.load(name)`, one `rhs` and one `jac` call at a
seeded point (the C path's cfuncs compile at the first call; see symmech.numerics.fastcall). CPU = user + system of
the process (getrusage), rounds interleaved between the trees. The values of rhs and jac of both trees are
compared: the largest difference relative to each array's largest magnitude.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

from timing import interleaved_cpu, machine, ratio, tree_env

NAMES = ["smm_rotor_boom", "smm_spatial_boom"]


def child(name: str) -> None:
    """One cold first call of ``name``'s rhs and jac; prints their values as JSON."""
    with tempfile.TemporaryDirectory() as cache:
        os.environ["NUMBA_CACHE_DIR"] = cache
        import numpy as np

        from symmech.numerics import kernels

        twin = kernels.load(name)
        rng = np.random.default_rng(1)
        y, p = rng.uniform(0.5, 1.5, len(twin.STATE)), rng.uniform(0.5, 1.5, len(twin.PARAMS))
        print(json.dumps({"rhs": twin.rhs(0.1, y, p).tolist(), "jac": twin.jac(0.1, y, p).tolist()}))


def command(tree: Path, name: str) -> list[str]:
    return ["env", f"PYTHONPATH={tree_env(tree)['PYTHONPATH']}", sys.executable, __file__, "--child", name]


def values(tree: Path, name: str) -> dict:
    import numpy as np

    out = subprocess.run(command(tree, name), check=True, capture_output=True, text=True).stdout
    return {key: np.array(v) for key, v in json.loads(out).items()}


def deviation(a: dict, b: dict) -> float:
    import numpy as np

    return max(float(np.abs(a[k] - b[k]).max() / np.abs(a[k]).max()) for k in a)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--child", help=argparse.SUPPRESS)
    parser.add_argument("--baseline", type=Path, help="a source tree (its symmech/ and generated/) to time beside")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    if args.child:
        return child(args.child)
    here = Path(__file__).resolve().parents[1]
    trees = {"this tree": here} | ({"baseline": args.baseline.resolve()} if args.baseline else {})
    print(machine())
    for name in NAMES:
        stats = interleaved_cpu({label: command(tree, name) for label, tree in trees.items()}, args.repeats, 1)
        for label, s in stats.items():
            print(f"{name:18s} {label:10s} CPU {s.text()}")
        if args.baseline:
            print(f"{name:18s} baseline / this tree {ratio(stats['baseline'], stats['this tree'])}; rhs and jac "
                  f"differ by {deviation(values(here, name), values(args.baseline, name)):.2g} of their largest")


if __name__ == "__main__":
    main()
