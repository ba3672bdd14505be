"""Compiled engines register themselves here, as scene kinds do in :mod:`symmech.core.registry`.

An engine is declared by a light module marked ``ROLE = "engine"`` (:mod:`symmech.core.discovery`; no
numba, no physics) that calls :func:`register` at import with an :class:`Engine`: its name, one line for
``--help``, and the module that implements it. ``symmech warm``, its ``--engine`` choices and the run
estimates read this registry, so adding an engine touches no central list (docs/ARCHITECTURE.md, "Adding
an engine").

The protocol, every engine alike (the implementation module provides ``ENGINE``, ``LAYOUTS``, ``Run``, the
frozen dataclass of a run's inputs by name, and ``RUNNER``, a :class:`Runner`)::

    engine = engines.get("grain")
    engine.builder()      # ENGINE, a symmech.numerics.build.Engine: numba's cache and the ahead-of-time build
    engine.warm(...)      # build it now, once per machine (symmech warm)
    engine.load()         # what a run calls: the ahead-of-time build when current, else numba's entries
    engine.run(inputs)    # RUNNER.simulate(inputs): a Run of this engine, results as the reference engine's
    engine.run_many(pop)  # RUNNER.simulate_many(pop): a Population of this engine (one that runs populations)
    engine.describe()     # its declared layouts (LAYOUTS, symmech.core.layout): names, units, offsets
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Protocol

_ENGINES: dict[str, Engine] = {}
_ALL = False  # every engine module imported


class Runner(Protocol):
    """What runs an engine's inputs: ``RUNNER`` in its implementation module, an object of a class of its own whose
    ``simulate(inputs)`` takes that module's ``Run``, the frozen dataclass of a run's inputs by name (the grain's
    ``driver.Run``: model, numerics, start, t_end, on_step, reason; the elastic trolley's ``compiled.Run``: system,
    drive, t, rtol, atol_q, dq0, dqd0, reason), and returns what the reference engine returns. Named inputs and a
    method of a named class, not ``simulate(*args)`` behind the registry: a reader follows a run from the scene
    through :meth:`Engine.run` to the engine's loop."""

    def simulate(self, inputs):
        """The run of ``inputs`` (the implementation module's ``Run``) on this engine."""


class PopulationRunner(Runner, Protocol):
    """A :class:`Runner` of an engine that runs populations: ``simulate_many(inputs)`` takes its module's
    ``Population``, the frozen dataclass of a population's inputs by name (the grain's ``driver.Population``:
    models, numerics, starts, t_end, workers, reason, strict), and returns one result per member, in order, each
    as ``simulate`` returns it (:meth:`Engine.run_many`)."""

    def simulate_many(self, inputs) -> list:
        """The runs of ``inputs`` (the implementation module's ``Population``) on this engine."""


@dataclass(frozen=True)
class Engine:
    """One compiled engine.

    name            ``symmech warm --engine NAME``; the name of its :class:`symmech.numerics.build.Engine`
    summary         one line for ``symmech warm --help``
    implementation  dotted name of the module that provides ``ENGINE`` (a :class:`symmech.numerics.build.Engine`),
                    ``Run`` (the frozen dataclass of a run's inputs), ``RUNNER`` (a :class:`Runner` of them) and
                    ``LAYOUTS`` (its declared layouts, :mod:`symmech.core.layout`)
    """

    name: str
    summary: str
    implementation: str

    def module(self):
        """The implementation module (imported on first use: it may import numba)."""
        return importlib.import_module(self.implementation)

    def builder(self):
        """The engine's :class:`symmech.numerics.build.Engine`: numba's cache, the build lock, the ahead-of-time build."""
        return self.module().ENGINE

    def warm(self, wait: bool = True, say=None, ahead: bool = False) -> bool:
        """:meth:`symmech.numerics.build.Engine.warm`: build the engine now unless it is built."""
        return self.builder().warm(wait=wait, say=say, ahead=ahead)

    def load(self):
        """What a run calls: the ahead-of-time build (a module) when current, else numba's cached entries (a
        dict of dispatchers to the argument types they are compiled for; they compile on first call)."""
        builder = self.builder()
        return builder.ahead_of_time() or builder.entries()

    def runner(self) -> Runner:
        """The engine's :class:`Runner` (``RUNNER``)."""
        return self.module().RUNNER

    def run(self, inputs):
        """The run of ``inputs``, a ``Run`` of this engine's implementation module (TypeError for another's: the
        inputs name their engine), by its :class:`Runner`."""
        self.check(inputs, "Run")
        runner = self.runner()
        return runner.simulate(inputs)

    def run_many(self, inputs) -> list:
        """The runs of a population, ``inputs`` a ``Population`` of this engine's implementation module (an engine
        that runs populations: its ``RUNNER`` is a :class:`PopulationRunner`), one result per member, in order."""
        self.check(inputs, "Population")
        runner: PopulationRunner = self.module().RUNNER
        return runner.simulate_many(inputs)

    def check(self, inputs, kind_name: str) -> None:
        """TypeError unless ``inputs`` are of the class ``kind_name`` of this engine's implementation module."""
        kind = type(inputs)
        if (kind.__module__, kind.__qualname__) != (self.implementation, kind_name):
            raise TypeError(f"engine {self.name!r} runs {self.implementation}.{kind_name}, "
                            f"not {kind.__module__}.{kind.__qualname__}")

    def compile_seconds(self) -> float:
        """The wall time [s] a run starting now spends compiling first: the cold compile (an idle machine's
        seconds times :func:`symmech.core.sample.slowdown` now), or 0."""
        from symmech.core import sample

        builder = self.builder()
        return builder.seconds * sample.slowdown() if builder.needs_compile() else 0.0

    def describe(self) -> str:
        """Its name, summary and declared layouts, one line per field: offset (or, for an array or a layout
        sized by the model, dimensions), name, unit, meaning."""
        from symmech.core.layout import Layout  # numpy: not at import (the CLI's start)

        lines = [f"{self.name}: {self.summary}"]
        for layout in self.module().LAYOUTS:
            lines.append(f"  {layout.name}")
            for f in layout.fields:
                where = f"{layout.offset(f.name):>4}" if isinstance(layout, Layout) and not layout.dims else \
                    f"{f.dtype}({', '.join(map(str, f.shape))})"
                lines.append(f"    {where} {f.name} [{f.unit}] {f.meaning}")
        return "\n".join(lines)


def register(engine: Engine) -> Engine:
    """Add ``engine`` (called by its declaring module at import time)."""
    if _ENGINES.get(engine.name, engine) != engine:
        raise ValueError(f"compiled engine {engine.name!r} registered twice")
    _ENGINES[engine.name] = engine
    return engine


def _discover(until: str | None = None) -> None:
    """Import engine modules until engine ``until`` is registered (all of them when None), those whose name
    contains it first: a grain run imports no other paper's package."""
    from symmech.core import discovery  # not at import (the CLI's start)

    for name in sorted(discovery.modules("engine"), key=lambda module: until is None or until not in module):
        if until in _ENGINES:
            return
        importlib.import_module(name)


def engines() -> dict[str, Engine]:
    """Every registered engine by name (every module declaring ``ROLE = "engine"`` imported once)."""
    global _ALL
    if not _ALL:
        _discover()
        _ALL = True
    return dict(sorted(_ENGINES.items()))


def get(name: str) -> Engine:
    """The engine called ``name`` (KeyError naming the registered ones otherwise); once registered, a dict lookup
    (the run paths ask for their engine at every run)."""
    if name not in _ENGINES:
        _discover(until=name)
    if name in _ENGINES:
        return _ENGINES[name]
    raise KeyError(f"no compiled engine {name!r}; registered: {', '.join(engines())}")


class Choices:
    """The ``--engine`` choices, "all" and every registered name, read when argparse checks a value or prints
    help (building the parser imports no engine module)."""

    def __contains__(self, name) -> bool:
        return name == "all" or name in engines()

    def __iter__(self):
        return iter(("all", *engines()))
