"""Scene kinds register themselves here; nothing else lists them.

A paper package declares a kind in a module marked ``ROLE = "kind"``
(:mod:`symmech.core.discovery`) that calls :func:`register` at import time. The
CLI, the Python API, the docs and the fuzzer find every kind through
:func:`kinds`, which imports those modules on first use, or :func:`get`, which
imports them only until the kind asked for is found (a grain run never loads the
mechanism's or the trolley's modules) — adding a kind touches no central list.

The life of a run (see ``symmech.core.pipeline``)::

    resolved = schema.validate(kind.schema, toml_data)   # every field, before any work
    setup    = kind.prepare(resolved)                     # admissibility, expressions over
                                                          # their domain; cheap, no I/O
    cost     = kind.estimate(setup)                       # refuse past --max-time
    result   = kind.run(setup, context)                   # the computation -> Result
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Any
from collections.abc import Callable

from symmech.core.schema import Table

_KINDS: dict[str, Kind] = {}
_ALL = False  # every scene module imported


@dataclass(frozen=True)
class Estimate:
    """Expected cost of a run, told to the user and checked against ``--max-time``."""

    seconds: float
    what: str  # e.g. "20000 steps, ~40 impacts"
    once: float = 0.0  # of the seconds, a one-off cost not repeated by further runs (e.g. a numba compile)


@dataclass(frozen=True)
class Kind:
    """One scene kind.

    name      the scene's ``kind`` value
    summary   one line for ``--help`` and docs
    schema    the whole scene (including ``kind``) as a declarative Table
    prepare   resolved scene dict -> setup object; raises SceneError for anything
              physically inadmissible; evaluates expressions over their domain; no I/O
    run       (setup, Context) -> symmech.core.results.Result
    estimate  setup -> Estimate (optional; runs expected to finish in < 2 s may omit it): the count model
    sample    (setup, share) -> setup: the same scene on the same engine over about ``share`` of its work, or None
              when no smaller run of that scene exists (optional; symmech.core.sample times it to scale
              ``estimate`` to this machine now)
    precision (setup, Context) -> Result of a work-precision study (optional)
    sweep     (raw scene dict, out folder, Context, **options) -> Result: ``symmech sweep`` over the
              scene's ``[sweep]`` table, written into the folder (optional; symmech.core.sweep)
    population list of setups -> per setup, what the kind's sweep reads of its run, or its SymmechError: the runs
              together, each as ``run`` would run it (optional; the kind's sweep calls it through here, since the
              kind's module imports its sweep)
    docs      path of the kind's docs page in the repository (for messages)
    """

    name: str
    summary: str
    schema: Table
    prepare: Callable[[dict], Any]
    run: Callable[[Any, Any], Any]
    estimate: Callable[[Any], Estimate] | None = None
    precision: Callable[[Any, Any], Any] | None = None
    docs: str = ""
    sweep: Callable[..., Any] | None = None
    sample: Callable[[Any, float], Any] | None = None
    population: Callable[[list], list] | None = None


def register(kind: Kind) -> Kind:
    """Add ``kind`` (called by the kind's own module at import time)."""
    if _KINDS.get(kind.name, kind) is not kind:
        raise ValueError(f"scene kind {kind.name!r} registered twice")
    _KINDS[kind.name] = kind
    return kind


def _discover(until: str | None = None) -> None:
    """Import scene modules until kind ``until`` is registered (all of them when None): a run
    imports only its own paper's modules, not every kind's dependencies. Modules whose name
    contains the kind's are tried first, and among them ``scene`` or ``<kind>_scene``
    (``symmech.trolley.scene`` for ``trolley``, before ``symmech.trolley.elastic.scene``)."""
    def rank(module: str) -> tuple[bool, bool]:
        last = module.rpartition(".")[2]
        return until is None or until not in module, last not in ("scene", f"{until}_scene")

    from symmech.core import discovery

    for name in sorted(discovery.modules("kind"), key=rank):
        if until in _KINDS:
            return
        importlib.import_module(name)


def kinds() -> dict[str, Kind]:
    """Every registered kind by name (discovery of all runs once, even if a kind registered itself before)."""
    global _ALL
    if not _ALL:
        _discover()
        _ALL = True
    return dict(sorted(_KINDS.items()))


def get(name) -> Kind:
    """The kind called ``name``; a one-line SceneError naming the field ``kind`` otherwise."""
    from symmech.core.scene import SceneError
    from symmech.core.schema import did_you_mean

    if isinstance(name, str):
        _discover(until=name)
        if name in _KINDS:
            return _KINDS[name]
    available = kinds()
    if not isinstance(name, str) or name not in available:
        raise SceneError("kind", f"unknown scene kind {name!r}{did_you_mean(name, available)}; "
                                 f"choose one of {', '.join(available)}")
    return available[name]
