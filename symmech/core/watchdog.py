"""A time-budget watchdog for computations that offer no callback of their own.

``with watchdog(ctx):`` calls ``ctx.tick()`` every ``period`` seconds from a
SIGALRM timer while the block runs, so a loop deep inside a solver that stops
advancing (a creeping event sequence, a stalled integrator) ends with the
context's one-line "over the time budget" error instead of hanging. Signals are
delivered to the main thread only: elsewhere (worker threads) the block runs
unguarded and the computation's own ``ctx.tick()`` calls are the only check.
"""
from __future__ import annotations

import signal
import threading
from contextlib import contextmanager

from symmech.core.context import Context


@contextmanager
def watchdog(ctx: Context, period: float = 0.25, where: str = ""):
    """Run the block under ``ctx``'s time budget, checked every ``period`` seconds [s]."""
    usable = hasattr(signal, "setitimer") and threading.current_thread() is threading.main_thread()
    if not usable:
        yield
        return

    def on_alarm(_signum, _frame):
        ctx.tick(where)

    previous = signal.signal(signal.SIGALRM, on_alarm)
    signal.setitimer(signal.ITIMER_REAL, period, period)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)
