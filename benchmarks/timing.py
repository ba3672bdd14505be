"""Interleaved repeats for the benchmarks: medians with min/max, never single shots.

Every contender runs once per round, rounds repeat ``repeats`` times, so a
machine that slows down for a while slows every contender alike.
"""
from __future__ import annotations

import resource
import statistics
import subprocess
import time
from dataclasses import dataclass
from collections.abc import Callable


@dataclass(frozen=True)
class Stats:
    median: float
    low: float
    high: float
    n: int

    @classmethod
    def of(cls, samples) -> Stats:
        """Median, min, max and count of ``samples``."""
        return cls(statistics.median(samples), min(samples), max(samples), len(samples))

    def text(self, unit: str = "s", scale: float = 1.0) -> str:
        return (f"{self.median * scale:9.4g} {unit} (min {self.low * scale:.4g}, max {self.high * scale:.4g}, "
                f"n={self.n})")


def interleaved(contenders: dict[str, Callable[[], object]], repeats: int = 5,
                number: int = 1) -> dict[str, Stats]:
    """Time each zero-argument callable ``number`` times per round over ``repeats`` rounds; seconds per call."""
    samples = {name: [] for name in contenders}
    for _ in range(repeats):
        for name, fn in contenders.items():
            start = time.perf_counter()
            for _ in range(number):
                fn()
            samples[name].append((time.perf_counter() - start) / number)
    return {name: Stats.of(s) for name, s in samples.items()}


def child_cpu(command: list[str], **run) -> tuple[float, subprocess.CompletedProcess]:
    """CPU seconds (user + system) of one child process running ``command`` (``subprocess.run`` with ``check=True``
    and the keywords ``run``), by getrusage of the children, so whatever else the machine runs does not count; and
    the finished process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    done = subprocess.run(command, check=True, **run)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime, done


def interleaved_cpu(commands: dict[str, list[str]], repeats: int = 5, number: int = 20) -> dict[str, Stats]:
    """CPU seconds (user + system) per run of each command (a process, its output discarded): ``number`` runs per
    round, rounds interleaved over ``repeats``; the CPU time is the children's (:func:`child_cpu`)."""
    samples = {name: [] for name in commands}
    for _ in range(repeats):
        for name, command in commands.items():
            runs = [child_cpu(command, stdout=subprocess.DEVNULL)[0] for _ in range(number)]
            samples[name].append(sum(runs) / number)
    return {name: Stats.of(s) for name, s in samples.items()}


def tree_env(tree) -> dict:
    """The environment of a child process that runs the source tree ``tree``: its folder first on PYTHONPATH, then
    tree_site/ (whose sitecustomize.py serves the tree's own generated/, templates/ and scenes/, which an editable
    install would map to its own checkout)."""
    import os
    from pathlib import Path

    site = Path(__file__).resolve().parent / "tree_site"
    return {**os.environ, "PYTHONPATH": os.pathsep.join([str(tree), str(site)])}


def ratio(slow: Stats, fast: Stats) -> str:
    """slow/fast at the medians, with the range from the extremes."""
    return (f"{slow.median / fast.median:6.2f}x (range {slow.low / fast.high:.2f}-"
            f"{slow.high / fast.low:.2f})")


def machine() -> str:
    import os
    import platform

    return f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}"


def print_base_this(samples: dict[tuple[str, str], list[float]], repeats: int) -> None:
    """Each measure of ``samples`` ((measure, "base" or "this") -> CPU seconds per round) as the two trees' stats
    and their ratio, in the order measured."""
    print(f"# {machine()}; CPU seconds, median (min, max) of {repeats} interleaved rounds")
    stats = {key: Stats.of(s) for key, s in samples.items()}
    for what in dict.fromkeys(what for what, _ in stats):
        base, this = stats[(what, "base")], stats[(what, "this")]
        print(f"{what}\n  base {base.text()}\n  this {this.text()}\n  base/this {ratio(base, this)}")
