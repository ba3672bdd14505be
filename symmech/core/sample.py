"""Estimates that hold on this machine now: a kind's count model scaled by timed samples of the scene.

A kind's ``estimate`` (its count model) says how a run's cost grows with what it counts (impacts, steps,
points); its seconds per count were measured once, on one machine at one load, and are off by the load and
the machine. A kind's ``sample(setup, share)`` gives the same scene on the engine that will run, over about
``share`` of its work (a shorter duration, fewer steps; share 0: the least it can run). :func:`timed` runs the
least sample first, which pays what a process pays once (imports, loading a compiled engine from numba's
cache, starting a background build, whose load then weighs on what follows), then times samples of
:data:`SHARE`, twice that, and so on until one takes :data:`STEADY` and the last two give a meaningful slope
(a short or noisy run is sampled nearly whole). The last two samples' difference in time over the count
model's is this machine's factor now, per count: the estimate is the larger sample's time (its fixed costs
included) and the rest of the run's counts at that factor (at the larger's mean if no slope held, the median of
the samples that large: a scene too small to share is sampled whole, each time, and one preempted sample of
milliseconds would be 10x off).

A compile still to come (``Estimate.once``) is left as the count model has it: a sample would compile. Its
seconds (an idle machine's) are scaled by :func:`slowdown`, the share of a core this process gets now, and so are
the count model's of a scene with no smaller run (``Kind.sample`` gives None; its count model is in an idle
core's seconds).
"""
from __future__ import annotations

import statistics
import time

from symmech.core import registry
from symmech.core.context import Context

SHARE = 0.03  # of the count model's work in the first timed sample; the second takes twice that
STEADY = 0.3  # s; samples double until one takes this long (a time slice of a loaded machine is milliseconds)
PROBE = 0.03  # s of CPU time the slowdown probe spends (tens of time slices)
PROBE_KEPT = 10.0  # s; a slowdown measured this recently is reused (estimates ask for it again and again)
_probed: list[tuple[float, float]] = []  # (when [s, perf_counter], slowdown) of the last probe


def timed(kind: registry.Kind, setup, cost: registry.Estimate, max_time: float) -> registry.Estimate:
    """``cost`` (the count estimate of ``setup``) scaled by timed samples of it on this machine, or ``cost``
    itself when the kind has no sample, a compile is still to come or ``cost`` is over ``max_time`` already
    (refused on counts, with no sample run); times :func:`slowdown` when the scene has no smaller run (the kind's
    sample gives None). A short run is sampled too (its count model may be far off, and
    its samples cost about as little as it does). The samples run quietly within ``max_time`` [s]; they raise
    only what the run itself would raise."""
    repeated = cost.seconds - cost.once
    if kind.sample is None or cost.once > 0.0 or repeated <= 0.0 or cost.seconds > max_time:
        return cost
    least = kind.sample(setup, 0.0)
    if least is None:  # no run of this scene is smaller than its own: the count model's idle-core seconds, scaled
        factor = slowdown()
        return registry.Estimate(cost.seconds * factor, f"{cost.what}; at {factor:.2g}x an idle core's time "
                                                        "(this process's share of a core now)")
    ctx = Context(quiet=True, max_time=max_time)
    kind.run(least, ctx)  # pays the one-off costs of this process
    share, samples = SHARE, [_timed_sample(kind, setup, SHARE, ctx)]
    while len(samples) < 2 or ((samples[-1][1] < STEADY or _slope(*samples[-2:]) is None) and 2.0 * share <= 1.0):
        share *= 2.0
        samples.append(_timed_sample(kind, setup, share, ctx))
    (m1, t1), (m2, t2) = samples[-2:]
    factor = _slope(*samples[-2:])
    if factor is None:  # the samples as large as the last (a scene sampled whole, each time): their median
        t2 = statistics.median(t for m, t in samples if m == m2)
        factor = t2 / m2
    return registry.Estimate(t2 + factor * max(repeated - m2, 0.0),
                             f"{cost.what}; timed samples: {t1:.3g} s and {t2:.3g} s for {m1 / repeated:.0%} and "
                             f"{m2 / repeated:.0%} of it, the rest at {factor:.3g}x the count model")


def slowdown() -> float:
    """How many times longer than on an idle core CPU-bound work in this process takes now [1, at least 1]: the
    wall time over the CPU time of a pure-Python loop of :data:`PROBE` seconds of CPU (other processes' load, this
    process's nice value). What a compile (single-threaded, CPU-bound) and the count model of a scene with no
    smaller run are scaled by."""
    now = time.perf_counter()
    if not _probed or now - _probed[-1][0] > PROBE_KEPT:
        cpu = time.process_time()
        while time.process_time() - cpu < PROBE:
            sum(range(1000))
        _probed[:] = [(now, max((time.perf_counter() - now) / (time.process_time() - cpu), 1.0))]
    return _probed[-1][1]


def _slope(smaller: tuple[float, float], larger: tuple[float, float]) -> float | None:
    """Seconds measured per count-model second between two samples ((model, measured) [s] each), or None where
    the noise of a loaded machine makes it meaningless: not positive, or steeper than twice the larger's mean
    (fixed costs in it)."""
    (m1, t1), (m2, t2) = smaller, larger
    slope = (t2 - t1) / (m2 - m1) if m2 > m1 else 0.0
    return slope if 0.0 < slope <= 2.0 * t2 / m2 else None


def _timed_sample(kind: registry.Kind, setup, share: float, ctx: Context) -> tuple[float, float]:
    """The count model's seconds and the measured wall time [s] of the sample of ``share`` of ``setup``."""
    small = kind.sample(setup, share)
    start = time.perf_counter()
    kind.run(small, ctx)
    return kind.estimate(small).seconds, time.perf_counter() - start
