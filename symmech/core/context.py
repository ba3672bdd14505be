"""Run context: progress bars, the wall-time budget and warnings, passed to every ``run``.

Long loops call ``ctx.progress(total, desc)`` (a tqdm bar on a terminal, silent
otherwise or with ``--quiet``) and ``ctx.tick()`` now and then, which raises a
one-line SymmechError once the run exceeds ``max_time`` — a run never hangs.

Solvers deep below a kind's ``run`` (an engine's fallback, a scipy right-hand side) reach the run's
context through :func:`active` (set by ``with ctx.active():``) rather than through every signature
between: they tick it, and a fallback re-estimates against what is left of the budget
(:meth:`Context.fallback`).
"""
from __future__ import annotations

import sys
import time
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field

from symmech.core.scene import SymmechError

DEFAULT_MAX_TIME = 3600.0  # s; the CLI's --max-time
_ACTIVE: ContextVar[Context | None] = ContextVar("symmech_run_context", default=None)


def active() -> Context | None:
    """The context of the run in progress on this thread (``with ctx.active():``), or None."""
    return _ACTIVE.get()


@dataclass
class Context:
    quiet: bool = False
    max_time: float = DEFAULT_MAX_TIME
    warnings: list[str] = field(default_factory=list)
    started: float = field(default_factory=time.perf_counter)
    sampled: bool = True  # a run's estimate may time samples (a sweep's points: no, the sweep estimated them)
    estimates: list = field(default_factory=list)  # a sweep's estimates told so far, in order (registry.Estimate)

    def elapsed(self) -> float:
        return time.perf_counter() - self.started

    def tick(self, where: str = "") -> None:
        """Raise if the run has used up its time budget (call it inside long loops)."""
        if self.elapsed() > self.max_time:
            at = f" ({where})" if where else ""
            raise SymmechError(f"run stopped after {self.elapsed():.0f} s: over the time budget "
                               f"--max-time {self.max_time:g} s{at}; raise --max-time to go on")

    @contextmanager
    def active(self):
        """Make this the context :func:`active` returns while the block runs."""
        token = _ACTIVE.set(self)
        try:
            yield self
        finally:
            _ACTIVE.reset(token)

    def fallback(self, what: str, seconds: float) -> None:
        """An engine falls back to a slower one expected to take ``seconds`` [s] more: said in one line,
        and refused at once when that overruns ``max_time`` (rather than found out after it)."""
        left = self.max_time - self.elapsed()
        if seconds > left:
            raise SymmechError(f"{what}; re-estimated: ~{seconds:.3g} s more, over the {max(left, 0):.3g} s left "
                               f"of --max-time {self.max_time:g} s; raise --max-time to run it")
        self.say(f"{what}; re-estimated: ~{seconds:.3g} s more")

    def progress(self, total: float, desc: str, unit: str = "it"):
        """A tqdm bar (shown only on a terminal and when not quiet); use as a context manager."""
        from tqdm import tqdm

        show = not self.quiet and sys.stderr.isatty()
        return tqdm(total=total, desc=desc, unit=unit, disable=not show, leave=False,
                    mininterval=0.5, delay=2.0)

    def warn(self, message: str) -> None:
        """Record a warning: echoed on stderr and stored in the summary."""
        self.warnings.append(message)

    def say(self, message: str) -> None:
        """One line of information on stderr (e.g. the cost estimate), unless quiet."""
        if not self.quiet:
            print(f"symmech: {message}", file=sys.stderr)
