"""What the report of a mechanism scene of the user's own costs (its module rendered by the run, not in generated/).

Each bundled scene named is copied into a temporary folder with its mechanism renamed (``my_<name>``), so that no
generated module matches it. Per round and per tree (``--base`` and the tree of this file, interleaved), in fresh
processes with the tree's own ``generated/``, ``templates/`` and ``scenes/`` (:func:`timing.tree_env`): the CPU of
``symmech run COPY --report --quiet`` (the children's getrusage), and the CPU (``time.process_time``) of
``report.write`` alone after ``symmech run COPY --quiet`` in the same process, as ``run --report`` calls it; and the
CPU of a plain ``symmech run COPY --quiet`` and of ``symmech report OUT`` on its folder in a later process.
The numba cache (``NUMBA_CACHE_DIR``) is warmed by one untimed run of each tree.

Run: python benchmarks/bench_report_own.py --base BASE_TREE [--repeats 5] [SCENE ...]
"""
from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
from pathlib import Path

from bench_report import run_report_seconds
from timing import child_cpu, print_base_this, tree_env

HERE = Path(__file__).resolve().parents[1]
WRITE = """\
import time
from pathlib import Path
from symmech import report
from symmech.cli import main
main(["run", {scene!r}, "--out", {out!r}, "--quiet"])
start = time.process_time()
report.write(Path({out!r}))
print(time.process_time() - start)
"""


def _own_copy(name: str, folder: Path) -> Path:
    """The bundled scene ``name`` with its mechanism renamed ``my_<name>``, written into ``folder``."""
    text = (HERE / "scenes" / f"{name}.toml").read_text()
    path = folder / f"my_{name}.toml"
    path.write_text(re.sub(r'(?m)^name = "(\w+)"', r'name = "my_\1"', text, count=1))
    return path


def _write_seconds(tree: Path, scene: Path, out: Path) -> float:
    """CPU seconds of ``report.write`` after the run of ``scene`` in the same process, with ``tree``."""
    code = WRITE.format(scene=str(scene), out=str(out))
    return float(subprocess.run([sys.executable, "-c", code], check=True, cwd=tree, env=tree_env(tree),
                                capture_output=True, text=True).stdout.split()[-1])


def _run_then_report_seconds(tree: Path, scene: Path, out: Path) -> tuple[float, float]:
    """CPU seconds of a plain ``symmech run SCENE`` and of ``symmech report OUT`` after it, in two fresh processes."""
    def cpu(*command):
        return child_cpu([sys.executable, "-m", "symmech", *command], cwd=tree, env=tree_env(tree),
                         stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)[0]

    return cpu("run", str(scene), "--out", str(out), "--quiet"), cpu("report", str(out), "--quiet")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    parser.add_argument("--base", type=Path, required=True)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("scenes", nargs="*", default=["smm_rotor_boom", "smm_spatial_boom"])
    args = parser.parse_args()
    trees = {"base": args.base.resolve(), "this": HERE}
    samples: dict[tuple[str, str], list[float]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        scenes = [_own_copy(name, out) for name in args.scenes]
        for name, tree in trees.items():  # warms the numba cache
            run_report_seconds(tree, scenes[0], out / name)
        for _ in range(args.repeats):
            for name, tree in trees.items():
                for scene in scenes:
                    samples.setdefault((f"run {scene.name} --report", name), []).append(
                        run_report_seconds(tree, scene, out / name / scene.stem))
                    samples.setdefault((f"report.write after the run, {scene.stem}", name), []).append(
                        _write_seconds(tree, scene, out / name / f"{scene.stem}_write"))
                    run, later = _run_then_report_seconds(tree, scene, out / name / f"{scene.stem}_later")
                    samples.setdefault((f"run {scene.name} (no --report)", name), []).append(run)
                    samples.setdefault((f"report OUT of {scene.stem}, a later process", name), []).append(later)
    print_base_this(samples, args.repeats)


if __name__ == "__main__":
    main()
