"""Overhead of the validate-first pipeline and the atomic write on a scene (the main job by default).

Per repeat, interleaved: (a) the strongest baseline: ``kind.run(setup, ctx)`` on an
already prepared scene, its tables, files and plots written straight into an
existing folder with a plain JSON summary — no reading, validation, finite checks,
lock, temporary folder or rename; (b) the whole of ``symmech run``:
``pipeline.run_to`` (read TOML, validate, prepare, estimate, run, finite checks,
write into a temporary folder, rename) in the same process. Prints medians of
``--repeats`` (>= 5) with their spread, the ratio b / a, and the stages of (b) as
its summary records them. Then, on one result and without plots (identical in both),
20 interleaved repeats of the writing alone: plain writes vs ``pipeline.write``
(lock, temporary folder, module hashes, strict JSON, rename, old folder removed).

    python benchmarks/bench_pipeline.py                          # scenes/grain_default.toml
    python benchmarks/bench_pipeline.py scenes/smm_excavator.toml --repeats 7
"""
from __future__ import annotations

import argparse
import json
import statistics
import tempfile
import time
from pathlib import Path

from symmech.core import pipeline
from symmech.core.context import Context


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scene", nargs="?", default=str(Path(__file__).parents[1] / "scenes" / "grain_default.toml"))
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--plots", action="store_true", help="include plots in (b) (the default run draws them)")
    a = p.parse_args()
    scene = pipeline.load(a.scene)
    bare, whole, stages = [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        pipeline.run_to(a.scene, Path(tmp) / "out", Context(quiet=True), plots=a.plots)  # warm imports
        plain = Path(tmp) / "plain"
        plain.mkdir()
        for _ in range(max(5, a.repeats)):
            start = time.perf_counter()
            result = scene.kind.run(scene.setup, Context(quiet=True))
            pipeline.write_files(plain, result, a.plots)
            (plain / "summary.json").write_text(json.dumps(result.summary, default=str))
            bare.append(time.perf_counter() - start)
            start = time.perf_counter()
            pipeline.run_to(a.scene, Path(tmp) / "out", Context(quiet=True), plots=a.plots)
            whole.append(time.perf_counter() - start)
            stages.append(json.loads((Path(tmp) / "out" / "summary.json").read_text())["timing_s"])

    def show(name, xs):
        print(f"{name:<44} median {statistics.median(xs):9.4f} s  (min {min(xs):.4f}, max {max(xs):.4f})")

    print(f"scene {a.scene}, {len(bare)} interleaved repeats, plots {'on' if a.plots else 'off'}")
    show("(a) kind.run + plain writes", bare)
    show("(b) symmech run path (pipeline.run_to)", whole)
    for stage in stages[0]:
        show(f"    stage {stage}", [s[stage] for s in stages])
    ratio = [w / b for w, b in zip(whole, bare)]
    print(f"ratio (b)/(a): median {statistics.median(ratio):.4f} (min {min(ratio):.4f}, max {max(ratio):.4f})")
    plain_writes, atomic_writes = [], []
    with tempfile.TemporaryDirectory() as tmp:
        plain = Path(tmp) / "plain"
        plain.mkdir()
        result = scene.run(Context(quiet=True))
        for _ in range(20):
            start = time.perf_counter()
            pipeline.write_files(plain, result, False)
            (plain / "summary.json").write_text(json.dumps(result.summary, default=str))
            plain_writes.append(time.perf_counter() - start)
            start = time.perf_counter()
            pipeline.write(result, Path(tmp) / "out", scene, plots=False)
            atomic_writes.append(time.perf_counter() - start)
    show("(c) plain writes, no plots", plain_writes)
    show("(d) pipeline.write, no plots", atomic_writes)
    extra = statistics.median(atomic_writes) - statistics.median(plain_writes)
    print(f"atomic-write overhead (d)-(c): {extra * 1e3:.1f} ms = {extra / statistics.median(bare):.2e} of (a); "
          f"validation {statistics.median(s['validate'] for s in stages) * 1e3:.2f} ms")


if __name__ == "__main__":
    main()
