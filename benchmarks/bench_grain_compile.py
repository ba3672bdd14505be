"""Cold start of the compiled grain engine: import + numba compile + first call in a fresh process.

Each round runs, in fresh processes with an empty ``NUMBA_CACHE_DIR`` (everything compiles: the generated
kernels and the loop), this tree and optionally another source tree (``--before DIR``, e.g. a ``git archive``
of an earlier commit), interleaved; then the cached start (cache beside the module, warmed first).
``--functions`` instead compiles once, cold, and prints where the time goes per compiled function (numba's
``numba:compile`` and ``numba:llvm_lock`` events: a function's own time excludes the callees it compiled).
``--cpu TREE...`` measures the CPU of one cold compile per tree and round (the variants of a compile-time study:
each a source tree), interleaved: an empty ``NUMBA_CACHE_DIR``, a fresh process at ``nice -n 10``, CPU by
``getrusage`` around the first call, the compile events counted; then a second process on the same cache (it must
compile nothing) and the whole default scene, whose impact rows, trajectory and final state are compared bit for
bit with the first tree's. ``--first-run`` times the README's main job (``symmech run scenes/grain_default.toml``, default engine
``auto``) in a fresh process on an empty cache beside the baseline ``python -c "import numpy, scipy,
matplotlib"``, interleaved; each round's background builder is then killed (SIGKILL, by its process id: the
lock must not outlive it). Then one build (``symmech warm``) and a run on the built engine, whose impacts
and final position are compared with the first run's. ``--during-build`` times, in interleaved rounds, the
first run on an empty cache against a second run started right after a first one while that run's builder
compiles (the builder killed after each), and prints each run's engine.

    python benchmarks/bench_grain_compile.py --before /tmp/before --repeats 5
    python benchmarks/bench_grain_compile.py --functions
    python benchmarks/bench_grain_compile.py --first-run --repeats 5
    python benchmarks/bench_grain_compile.py --during-build --repeats 5
    python benchmarks/bench_grain_compile.py --cpu /tmp/before . --repeats 1
"""
from __future__ import annotations

import argparse
import json
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from timing import interleaved, machine, ratio, tree_env

HERE = Path(__file__).resolve().parents[1]
CODE = ("from symmech.core import pipeline; from symmech.grain.motion_engine import driver as compiled; "
        "sc = pipeline.load('scenes/grain_default.toml').setup; "
        "compiled.simulate(sc.model, sc.numerics, sc.start, 0.01)")
# In the fresh process: every compile and LLVM section, as (kind, start?, function, time) in order.
RECORD = """
import json, sys
from numba.core import event
with event.install_recorder("numba:compile") as compiles, event.install_recorder("numba:llvm_lock") as llvm:
    exec(sys.argv[1])
rows = [(ts, ev.kind, ev.is_start, ev.data["dispatcher"].py_func.__qualname__ if ev.kind == "numba:compile" else "",
         ev.data["dispatcher"].py_func.__module__ if ev.kind == "numba:compile" else "")
        for ts, ev in compiles.buffer + llvm.buffer]
print(json.dumps(sorted(rows, key=lambda r: r[0])))
"""


def fresh(tree: Path, cold: bool, record: bool = False) -> str:
    """One fresh process on ``tree``; with ``cold`` an empty numba cache; returns its stdout (with ``record``
    the compile events)."""
    env = tree_env(tree)
    with tempfile.TemporaryDirectory() as cache:
        if cold:
            env["NUMBA_CACHE_DIR"] = cache
        args = [sys.executable, "-c", RECORD, CODE] if record else [sys.executable, "-c", CODE]
        return subprocess.run(args, cwd=tree, env=env, check=True, capture_output=True, text=True).stdout


# In the fresh process: CPU seconds of the first call, its compile events; then the whole scene's results saved.
MEASURED = """
import json, resource, sys
import numpy as np
from numba.core import event

def cpu():
    r = resource.getrusage(resource.RUSAGE_SELF)
    return r.ru_utime + r.ru_stime

from symmech.core import pipeline
from symmech.grain.motion_engine import driver as compiled
sc = pipeline.load('scenes/grain_default.toml').setup
with event.install_recorder("numba:compile") as compiles, event.install_recorder("numba:llvm_lock") as llvm:
    c0 = cpu()
    compiled.simulate(sc.model, sc.numerics, sc.start, 0.01)
    c1 = cpu()
rows = [(ts, ev.kind, ev.is_start, ev.data["dispatcher"].py_func.__qualname__ if ev.kind == "numba:compile" else "",
         ev.data["dispatcher"].py_func.__module__ if ev.kind == "numba:compile" else "")
        for ts, ev in compiles.buffer + llvm.buffer]
r = compiled.simulate(sc.model, sc.numerics, sc.start, sc.start.t + sc.duration)
f = r.final
np.savez(sys.argv[1], trajectory=r.trajectory, impacts=np.asarray(r.impact_log.rows),
         final=np.array([f.t, *f.r, *f.v, *f.q, *f.w]))
print(json.dumps({"cpu": c1 - c0, "events": sorted(rows, key=lambda r: r[0])}))
"""


def cold_cpu(tree: Path, out: str) -> dict:
    """One cold compile on ``tree`` (empty cache, fresh process, nice 10): CPU [s], overloads, compile-event and
    LLVM seconds, the load before it; then the second process's compiles on that cache (0 when the cache works)."""
    env = tree_env(tree)
    with tempfile.TemporaryDirectory() as cache:
        env["NUMBA_CACHE_DIR"] = cache
        load = os.getloadavg()[0]
        runs = [json.loads(subprocess.run(["nice", "-n", "10", sys.executable, "-c", MEASURED, f"{out}{k}.npz"],
                                          cwd=tree, env=env, check=True, capture_output=True, text=True).stdout)
                for k in range(2)]
    table = own_times(runs[0]["events"])
    return {"cpu": runs[0]["cpu"], "overloads": sum(r[0] for r in table.values()), "load": load,
            "events": sum(r[1] for r in table.values()), "llvm": sum(r[2] for r in table.values()),
            "second": sum(1 for e in runs[1]["events"] if e[1] == "numba:compile" and e[2])}


def same_results(a: str, b: str) -> bool:
    """Whether two runs' trajectory, impact rows and final state are equal bit for bit (as int64)."""
    x, y = np.load(a), np.load(b)
    return all(x[k].shape == y[k].shape and np.array_equal(x[k].view(np.int64), y[k].view(np.int64))
               for k in ("trajectory", "impacts", "final"))


def cpu_study(trees: list[Path], repeats: int) -> None:
    """Interleaved cold compiles of each tree (see the module docstring), CPU medians and results compared."""
    print(f"machine: {machine()}; {time.strftime('%Y-%m-%d %H:%M UTC', time.gmtime())}")
    rows = {str(t): [] for t in trees}
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(repeats):
            for i, tree in enumerate(trees):
                row = cold_cpu(tree.resolve(), f"{tmp}/{i}_{k}_")
                row["equal"] = same_results(f"{tmp}/0_{k}_0.npz", f"{tmp}/{i}_{k}_0.npz")
                rows[str(tree)].append(row)
                print(f"  round {k}: {tree}: {json.dumps(row)}", flush=True)
    for tree, rs in rows.items():
        cpu = sorted(r["cpu"] for r in rs)
        print(f"  {tree}: cold compile {cpu[len(cpu) // 2]:.1f} s CPU (min {cpu[0]:.1f}, max {cpu[-1]:.1f}, n={len(cpu)}), "
              f"{rs[0]['overloads']} overloads, second process compiled {max(r['second'] for r in rs)}, "
              f"results bit for bit as the first tree's: {all(r['equal'] for r in rs)}")


def own_times(events: list) -> dict:
    """Per function (module.name): [overloads compiled, own seconds, own LLVM seconds]; "own" leaves out the
    nested compiles of callees (each charged to the callee), LLVM sections go to the innermost compile."""
    table, stack, llvm_start = {}, [], None
    for ts, kind, start, name, module in events:
        if kind == "numba:llvm_lock":
            if start:
                llvm_start = ts
            elif stack:
                stack[-1][2] += ts - llvm_start
            continue
        if start:
            stack.append([f"{module.rsplit('.', 1)[-1]}.{name}", ts, 0.0, 0.0])  # name, start, llvm, nested
            continue
        key, begun, llvm, nested = stack.pop()
        row = table.setdefault(key, [0, 0.0, 0.0])
        row[0] += 1
        row[1] += ts - begun - nested
        row[2] += llvm
        if stack:
            stack[-1][3] += ts - begun
    return table


def functions(top: int) -> None:
    """Compile once, cold, and print the functions that took the most time of their own."""
    table = own_times(json.loads(fresh(HERE, True, record=True)))
    total = sum(r[1] for r in table.values())
    print(f"machine: {machine()}; cold compile, {len(table)} functions, {sum(r[0] for r in table.values())} "
          f"overloads, {total:.1f} s in numba's compile events")
    print(f"  {'function':<44} {'overloads':>9} {'own s':>8} {'LLVM s':>8} {'share':>6}")
    for key, (n, own, llvm) in sorted(table.items(), key=lambda kv: -kv[1][1])[:top]:
        print(f"  {key:<44} {n:>9} {own:>8.2f} {llvm:>8.2f} {own / total:>6.1%}")


def _builders(cache: str) -> list[int]:
    """Process ids of the background builders working on ``cache`` (its NUMBA_CACHE_DIR)."""
    pids = []
    for proc in Path("/proc").iterdir():
        try:
            cmd = (proc / "cmdline").read_bytes().split(b"\0")
            env = (proc / "environ").read_bytes().split(b"\0")
        except (OSError, ValueError):
            continue
        if b"--background" in cmd and f"NUMBA_CACHE_DIR={cache}".encode() in env:
            pids.append(int(proc.name))
    return pids


def first_run(cache: str, out: Path, kill: bool = True) -> None:
    """The main job in a fresh process on ``cache``; with ``kill`` its background builder killed after."""
    env = {**os.environ, "NUMBA_CACHE_DIR": cache}
    subprocess.run([sys.executable, "-m", "symmech", "run", "scenes/grain_default.toml", "--out", str(out),
                    "--quiet"], cwd=HERE, env=env, check=True, capture_output=True)
    for pid in _builders(cache) if kill else ():
        os.kill(pid, signal.SIGKILL)


def _result(out: Path) -> tuple[str, np.ndarray, np.ndarray]:
    """Engine, impact times [s] and final position [m] of a grain run's folder."""
    def rows(name):
        return [line for line in (out / name).read_text().splitlines() if not line.startswith("#")][1:]

    engine = json.loads((out / "summary.json").read_text())["engine"]
    times = np.array([float(line.split(",")[0]) for line in rows("impacts.csv")])
    return engine, times, np.array([float(x) for x in rows("trajectory.csv")[-1].split(",")[1:4]])


def first_runs(repeats: int) -> None:
    print(f"machine: {machine()}")
    with tempfile.TemporaryDirectory() as tmp:
        caches = iter(range(10**6))

        def cold_run():
            first_run(f"{tmp}/cache{next(caches)}", Path(tmp) / "out")

        times = interleaved({"baseline": lambda: subprocess.run([sys.executable, "-c", "import numpy, scipy, "
                                                                  "matplotlib"], check=True),
                             "first run": cold_run}, repeats)
        for label, st in times.items():
            print(f"  {label:<10} {st.text()}")
        print(f"  first run / baseline: {ratio(times['first run'], times['baseline'])}")
        cache = f"{tmp}/built"
        first_run(cache, Path(tmp) / "first", kill=False)
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "symmech", "warm", "--quiet"], cwd=HERE, check=True,
                       env={**os.environ, "NUMBA_CACHE_DIR": cache}, capture_output=True)
        print(f"  the first run's builder finished {time.perf_counter() - start:.1f} s after the run answered")
        first_run(cache, Path(tmp) / "second")
        (e1, t1, r1), (e2, t2, r2) = _result(Path(tmp) / "first"), _result(Path(tmp) / "second")
        print(f"  engines: first run {e1}, second run {e2}; {len(t1)} vs {len(t2)} impacts, times agree to "
              f"{np.abs(t1 - t2).max() if len(t1) == len(t2) else float('nan'):.2g} s, final position to "
              f"{np.linalg.norm(r1 - r2):.2g} m")


def during_build(repeats: int) -> None:
    """The first run on an empty cache against a second run during the first run's background build."""
    print(f"machine: {machine()}")
    with tempfile.TemporaryDirectory() as tmp:
        caches = iter(range(10**6))
        first, second, engines = [], [], set()
        for _ in range(repeats):
            for times, before in ((first, False), (second, True)):
                cache, out = f"{tmp}/cache{next(caches)}", Path(tmp) / "out"
                if before:
                    first_run(cache, Path(tmp) / "before", kill=False)
                    assert _builders(cache), "the first run started no builder"
                start = time.perf_counter()
                first_run(cache, out, kill=False)
                times.append(time.perf_counter() - start)
                engines.add((before, _result(out)[0], bool(_builders(cache))))
                for pid in _builders(cache):
                    os.kill(pid, signal.SIGKILL)
        for label, t in (("first run", first), ("second run during the build", second)):
            print(f"  {label:<28} {statistics.median(t):.2f} s (min {min(t):.2f}, max {max(t):.2f}; n = {len(t)})")
        print(f"  second / first (medians): {statistics.median(second) / statistics.median(first):.3f}")
        print(f"  (during build, engine, a builder still at work after the run): {sorted(engines)}")


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--before", type=Path, help="another source tree to compare (cold)")
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--functions", action="store_true", help="print the compile time per function instead")
    p.add_argument("--top", type=int, default=25, help="with --functions: rows printed")
    p.add_argument("--first-run", action="store_true", help="time the README main job on an empty cache instead")
    p.add_argument("--cpu", type=Path, nargs="+", help="source trees: the CPU of a cold compile of each instead")
    p.add_argument("--during-build", action="store_true",
                   help="time a second run during the first run's background build against the first run")
    a = p.parse_args()
    if a.during_build:
        return during_build(a.repeats)
    if a.cpu:
        return cpu_study(a.cpu, a.repeats)
    if a.functions:
        return functions(a.top)
    if a.first_run:
        return first_runs(a.repeats)
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
