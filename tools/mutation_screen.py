"""Screens: every mutant of a shard run against a frozen copy of its tests, each in a fork of one process that
imported pytest and the mutated module once (mutmut's trampolines choose the mutant at each call), with its
outcome judged from the tests' own reports (mutation_record.py lists the outcomes).

The unmutated copy runs 3 times first and must pass each time; a mutant's limit is 10 times the median of
the three (the first may build numba's cache), at least 60 s. A screen stops a mutant's run at the first test failing on an assertion, as `-x` would;
past a test that fails on another exception or a fixture error it runs on, so that a mutant is recorded "raised"
(killed by a raise: docs/mutation.md) or "error" (not a kill) only when no test of the selection fails on an
assertion.
"""
from __future__ import annotations

import contextlib
import importlib
import io
import json
import os
import random
import shutil
import signal
import statistics
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import mutation_record as rec

ROOT = rec.ROOT
# mutmut 3's own first step of `run` (mutmut/__main__.py): copy the sources and write every mutant beside them
GENERATE = ("from pathlib import Path\nimport mutmut.__main__ as m\nm.set_mutant_under_test('mutant_generation')\n"
            "Path('mutants').mkdir(exist_ok=True)\nm.copy_src_dir(); m.copy_also_copy_files(); m.setup_source_paths()\n"
            "m.store_lines_covered_by_tests(); m.create_mutants(1)\n")
BASELINE_RUNS = 3
AGAIN = "its unkilled mutants again"  # a screen's note for --rest and --survived
TIMEOUT_FACTOR, TIMEOUT_FLOOR = 10.0, 60.0  # a mutant's limit: the median unmutated run times 10, at least 60 s


class Verdict:
    """A pytest plugin that notes the first test failing on an assertion (and stops there), else the first failing
    on another exception or the first fixture error (and runs on: a later test may still fail on an assertion),
    and collection errors. `told(test)` is called at the first raise: a kill already, whatever a later test does
    (hang, kill the process)."""

    def __init__(self, told=None):
        self.session = None
        self.told = told
        self.killed = self.raised = self.error = self.collection = ""

    def pytest_sessionstart(self, session):
        self.session = session

    def pytest_collectreport(self, report):
        if report.failed and not self.collection:
            self.collection = report.nodeid or "(collection)"

    def pytest_exception_interact(self, node, call, report):
        """Called for every failed phase (and collection error) with the exception: classify it."""
        import pytest

        if not hasattr(node, "nodeid") or report.when is None:
            return
        if report.when != "call":  # a fixture: the tests that do not use it may still assert
            self.error = self.error or f"{node.nodeid} ({report.when}: {call.excinfo.typename})"
        elif call.excinfo.errisinstance((AssertionError, pytest.fail.Exception)):
            self.killed = node.nodeid
            self.session.shouldstop = "a test failed on an assertion"
        elif not self.raised:
            self.raised = f"{node.nodeid} ({call.excinfo.typename})"
            if self.told:
                self.told(self.raised)


class Collected:
    """A pytest plugin that keeps the node ids of the tests a collection selected (after `-m` and `-k`)."""

    def __init__(self):
        self.nodes: set[str] = set()

    def pytest_collection_finish(self, session):
        self.nodes = {item.nodeid for item in session.items}


def freeze_tests(folder: Path) -> Path:
    """A copy of tests/ made now, in <folder>/frozen/ beside links to the rest of the repository: the tests a
    screen runs, unchanged by edits to the repository while it runs."""
    frozen = folder / "frozen"
    shutil.rmtree(frozen, ignore_errors=True)
    frozen.mkdir(parents=True)
    shutil.copytree(ROOT / "tests", frozen / "tests", ignore=shutil.ignore_patterns("__pycache__"))
    for entry in ROOT.iterdir():
        if entry.name not in ("tests", ".git", ".venv", "mutants"):
            (frozen / entry.name).symlink_to(entry, target_is_directory=entry.is_dir())
    return frozen / "tests"


def generate(folder: Path, fresh: bool) -> None:
    """Write the mutated copy of the shard's module into <folder>/mutants (again from the current tree if fresh)."""
    if fresh:
        shutil.rmtree(folder / "mutants", ignore_errors=True)
    if not (folder / "mutants").exists():
        subprocess.run([sys.executable, "-c", GENERATE], cwd=folder, check=True, stdout=subprocess.DEVNULL)


def changes(folder: Path, module: str, names: list[str]) -> dict[str, tuple[str, str]]:
    """(hash, summary) of each mutant's change, read from the mutated copy in <folder>."""
    from mutmut.mutation.diff_apply import get_diff_for_mutant

    with contextlib.chdir(folder):
        return {name: rec.change_of(get_diff_for_mutant(name, path=module)) for name in names}


def mutant_names(folder: Path, module: str) -> list[str]:
    """Every mutant mutmut wrote for `module` in <folder>."""
    meta = json.loads((folder / "mutants" / (module + ".meta")).read_text("utf-8"))
    return list(meta["exit_code_by_key"])


def run_one(key: str, args: list[str], timeout: float) -> tuple[str, str, float]:
    """pytest `args` on mutant `key` ("" for none) in a forked child: (outcome, deciding test, seconds)."""
    import pytest

    read, write = os.pipe()
    start = time.monotonic()
    pid = os.fork()
    if pid == 0:
        os.close(read)
        os.environ["MUTANT_UNDER_TEST"] = key  # mutmut's trampolines read it at every call
        verdict = Verdict(told=lambda test: os.write(write, json.dumps({"raised": test}).encode() + b"\n"))
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            code = int(pytest.main(args, plugins=[verdict]))
        found = {"code": code, "killed": verdict.killed, "raised": verdict.raised, "error": verdict.error,
                 "collection": verdict.collection}
        os.write(write, json.dumps(found).encode()[:60000] + b"\n")
        os._exit(0)
    os.close(write)
    timed_out = False
    while not os.waitpid(pid, os.WNOHANG)[0]:
        if time.monotonic() - start > timeout:
            os.kill(pid, signal.SIGKILL)
            os.waitpid(pid, 0)
            timed_out = True
            break
        time.sleep(0.05)
    seconds = time.monotonic() - start
    with os.fdopen(read, "rb") as pipe:
        told = [json.loads(line) for line in pipe.read().splitlines() if line.endswith(b"}")]
    found = told[-1] if told and "code" in told[-1] else None
    if found is None:  # stopped at the limit or died; a test that failed on a raise before that killed it
        raised = next((t["raised"] for t in told if "raised" in t), "")
        return ("raised", raised, seconds) if raised else ("timeout" if timed_out else "crash", "", seconds)
    for outcome in ("collection", "killed", "raised", "error"):
        if found[outcome]:
            return outcome, found[outcome], seconds
    outcome = {0: "survived", 5: "no-tests"}.get(found["code"], "crash")
    return outcome, "" if outcome != "crash" else f"pytest exit {found['code']}", seconds


def load(folder: Path, module: str, tests: list[str], fresh: bool) -> tuple[list[str], set[str]]:
    """Generate the mutants, freeze the tests, import pytest and the mutated module in this process and collect the
    tests once: (the selection's pytest args, the node ids of the tests it selects)."""
    generate(folder, fresh)
    frozen = freeze_tests(folder)
    args = [str(frozen / a.removeprefix("tests/")) if a.startswith("tests/") else a for a in tests]
    args += ["-q", "-n", "0", "-p", "no:cacheprovider", "--tb=no"]  # the plugin reads the exceptions; no tracebacks
    os.chdir(folder / "mutants")
    sys.path[:0] = [str(folder / "mutants"), str(frozen)]
    import pytest

    importlib.import_module(module.removesuffix(".py").replace("/", "."))
    # collect once here, as mutmut's own clean run does: the forks find the test modules and what they import
    # already loaded (a value a test module computes at import comes from the unmutated code, in mutmut too)
    os.environ["MUTANT_UNDER_TEST"] = ""
    collected = Collected()
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        pytest.main([*args, "--collect-only"], plugins=[collected])
    return args, collected.nodes


def baseline(args: list[str], runs: int = BASELINE_RUNS) -> tuple[float, list[float]]:
    """Time the unmutated run of the pytest `args` `runs` times, each of which must pass: (a mutant's time limit,
    the times)."""
    times = []
    for _ in range(runs):
        outcome, test, seconds = run_one("", args, 3600.0)
        if outcome != "survived":
            raise SystemExit(f"the unmutated code does not pass its tests ({outcome} {test}): no screen")
        times.append(seconds)
    return time_limit(times), times


def time_limit(times: list[float]) -> float:
    """A mutant's time limit [s] from the unmutated runs' times [s]: 10 times their median, at least 60 s. Not the
    slowest: the first run may build numba's cache of the mutated copy (705 s against 18 and 30 s after it), and a
    limit of 7000 s would let a mutant that runs on without end hold the screen for two hours."""
    return max(TIMEOUT_FLOOR, TIMEOUT_FACTOR * statistics.median(times))


def kept(entries: dict[str, rec.Entry], renames: dict[str, str], stale: tuple) -> dict[str, rec.Entry]:
    """The record's lines a screen keeps (all but `stale`), each under its mutant's current name (`renames`:
    recorded -> current): after an edit renumbered a function's mutants, a mutant screened now may carry the name a
    kept line had, and writing it under that name would overwrite the kept line."""
    return {renames.get(n, n): replace(e, mutant=renames.get(n, n)) for n, e in entries.items() if n not in stale}


def screen(shard: str, folder: Path, module: str, tests: list[str], names: list[str], fresh: bool,
           which: str = "", drawn: str = "", renames: dict[str, str] | None = None, stale: tuple = ()) -> int:
    """Screen `names` (mutmut names, of the shard's patterns) and write their outcomes into the module's record;
    `which`: what they are, when not all of the shard's (say "its unkilled mutants again": the shard's note says
    so); `drawn`: how a random sample was drawn (the record's "sample:" note); `renames`: recorded name -> the
    current name of the same change; `stale`: recorded lines to drop (their change is no longer made)."""
    args, _ = load(folder, module, tests, fresh)
    limit, times = baseline(args)
    path = rec.record_path(module)
    entries = kept(rec.read(path), renames or {}, stale)
    found = changes(folder, module, names)
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                            text=True).stdout.strip()
    made = len(mutant_names(folder, module))
    label = f"{shard} ({which})" if which else shard
    notes = [n for n in rec.notes_of(path) if not n.startswith((f"shard {label}:", "made:", "module:"))]
    notes[:0] = [f"made: {made} mutants of {module} by mutmut", f"module: {module}"]
    if drawn:
        notes = [n for n in notes if not n.startswith("sample:")] + [f"sample: {drawn}"]
    notes.append(f"shard {label}: {time.strftime('%Y-%m-%d %H:%M', time.gmtime())} UTC, tree {commit}, tests "
                 f"{' '.join(tests)}; unmutated runs {', '.join(f'{t:.1f}' for t in times)} s, limit {limit:.0f} s")
    print(f"== screen {shard}: {len(names)} mutants, unmutated {times} s, limit {limit:.0f} s", flush=True)
    for i, name in enumerate(names):
        outcome, test, seconds = run_one(name, args, limit)
        digest, summary = found[name]
        entries[name] = rec.Entry(name, shard, digest, outcome, test, seconds, summary)
        print(f"    {name}: {outcome} {test} ({seconds:.1f} s)", flush=True)
        if i % 10 == 9 or i == len(names) - 1:
            rec.write(path, entries, notes)
    if not names:
        rec.write(path, entries, notes)
    counts = rec.tally({n: entries[n] for n in names}, path.stem, rec.equivalents())
    print(f"== screen {shard}: " + ", ".join(f"{n} {k}" for k, n in counts.items() if n), flush=True)
    return 0


def sample(entries: dict[str, rec.Entry], module: str, killed: int, seed: int) -> list[rec.Entry]:
    """`killed` killed entries at random (all when fewer) and every survivor with a written proof."""
    proofs = rec.equivalents()
    kills = sorted(n for n, e in entries.items() if e.outcome in rec.KILLS)
    chosen = random.Random(seed).sample(kills, min(killed, len(kills)))
    proven = [n for n, e in entries.items() if rec.is_proven(e, module, proofs)]
    return [entries[n] for n in sorted(chosen + proven)]


def deciding(entry: rec.Entry, folder: Path, tests: list[str]) -> list[str]:
    """pytest args that run only the test a recorded kill names (in the frozen copy, with the selection's marks and
    its options such as --noconftest); [] for any other outcome, which needs the whole selection (a survivor
    survives all of it)."""
    if entry.outcome not in rec.KILLS or not entry.test:
        return []
    return node_args([deciding_test(entry)], folder, tests)


def deciding_test(entry: rec.Entry) -> str:
    """The node id of the test a recorded kill names ("" for none): the text before its exception's " (Name)", which
    is last; a parametrised id may hold " (" itself."""
    return entry.test.rsplit(" (", 1)[0] if entry.test.endswith(")") else entry.test


def reruns(chosen: list[rec.Entry], collected: set[str], folder: Path, tests: list[str]) -> dict[str, list[str]]:
    """The pytest args each chosen mutant is rerun with: its deciding test's (:func:`deciding`), or [] (the whole
    selection) for a survivor and for a kill whose deciding test the selection no longer holds (renamed, removed,
    or deselected), which the check says: pytest would refuse the node id (exit 4) or run nothing."""
    out = {}
    for e in chosen:
        out[e.mutant] = deciding(e, folder, tests)
        if out[e.mutant] and deciding_test(e) not in collected:
            print(f"    {e.mutant}: its deciding test {deciding_test(e)} is not in the selection any more (renamed "
                  "or removed): rerun against the whole selection", flush=True)
            out[e.mutant] = []
    return out


def node_args(nodes: list[str], folder: Path, tests: list[str]) -> list[str]:
    """pytest args that run only the tests `nodes` (pytest node ids under tests/) in the frozen copy, with the
    selection's marks and options."""
    marks = tests[tests.index("-m"):tests.index("-m") + 2] if "-m" in tests else []
    options = [a for a in tests if a.startswith("--")]
    return [*(str(folder / "frozen" / node) for node in nodes), *marks, *options, "-q", "-n", "0", "-p",
            "no:cacheprovider", "--tb=no"]


def recheck(shard: str, folder: Path, module: str, tests: list[str], chosen: list[rec.Entry]) -> int:
    """Rerun `chosen` on mutants made from the current tree, a recorded kill against the test that made it, any
    other outcome against the whole selection; 1 when an outcome no longer holds or a mutant is gone."""
    # one unmutated run of the tests the check will run (only the deciding tests when every chosen outcome is a
    # kill, else the whole selection): it must pass, and its time only sets the limit, which can turn a recorded
    # outcome into a timeout (a failed check), never a failed check into a passed one
    start = time.monotonic()
    args, collected = load(folder, module, tests, fresh=True)
    rerun = reruns(chosen, collected, folder, tests)
    kills_only = all(rerun.values())
    limit, _ = baseline(node_args(sorted({deciding_test(e) for e in chosen}), folder, tests) if kills_only else args,
                        runs=1)
    # only the chosen mutants' functions: a mutant is found again in its own function (mutation_record.match), and a
    # diff costs a parse of the module (a minute for the 2000 mutants of a large module)
    functions = {rec.function_of(e.mutant) for e in chosen}
    candidates = [n for n in mutant_names(folder, module) if rec.function_of(n) in functions]
    current = {name: (rec.function_of(name), digest)
               for name, (digest, _) in changes(folder, module, candidates).items()}
    found = rec.match(chosen, current)
    failures, ready = 0, time.monotonic()
    for e in chosen:
        name = found.get(e.mutant)
        if name is None:
            print(f"    {e.mutant} ({e.change}): no longer made from the current tree; rescreen the shard")
            failures += 1
            continue
        outcome, test, _ = run_one(name, rerun[e.mutant] or args, limit)
        held = outcome == e.outcome or (e.outcome, outcome) == ("raised", "killed")  # an assertion now: better
        failures += not held
        print(f"    {e.mutant}{'' if name == e.mutant else f' (now {name})'}: recorded {e.outcome}, now {outcome} "
              f"{test} {'ok' if held else 'CHANGED'}", flush=True)
    print(f"== recheck {shard}: {len(chosen) - failures} of {len(chosen)} hold; {ready - start:.0f} s to make the "
          f"mutants and run the unmutated {'deciding tests' if kills_only else 'selection'}, "
          f"{time.monotonic() - ready:.0f} s to rerun", flush=True)
    return 1 if failures else 0
