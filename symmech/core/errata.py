"""Printed formula vs derivation, compared numerically at run time.

Each paper package may have an ``errata`` module with ``checks()`` returning
:class:`Check` objects: a sampler of seeded random inputs and two numeric
functions, one evaluating the formula as printed (hand transcription), one the
derivation. :func:`evaluate` turns a check into a record; nothing in a record
is typed in, every difference is computed.
"""
from __future__ import annotations

import importlib
from dataclasses import dataclass
from collections.abc import Callable

import numpy as np

AGREE_RTOL = 1e-9


@dataclass(frozen=True)
class Check:
    """One printed formula: ``printed(x)`` and ``derived(x)`` for inputs ``x = sample(rng, n)``.

    ``sample`` returns a dict of arrays with a leading axis of length n; both
    functions return arrays with that leading axis.
    """

    seed: str
    equation: str
    description: str
    sample: Callable[[np.random.Generator, int], dict]
    printed: Callable[[dict], np.ndarray]
    derived: Callable[[dict], np.ndarray]
    note: str = ""


def evaluate(check: Check, n: int = 200, seed: int = 20261121) -> dict:
    """Record for ``check``: status, largest relative difference, worst example."""
    rng = np.random.default_rng(seed)
    x = check.sample(rng, n)
    p = np.asarray(check.printed(x), dtype=float).reshape(n, -1)
    d = np.asarray(check.derived(x), dtype=float).reshape(n, -1)
    scale = np.maximum(np.abs(d).max(axis=1), np.abs(p).max(axis=1))
    diff = np.abs(p - d).max(axis=1)
    rel = np.where(scale > 0, diff / np.where(scale > 0, scale, 1.0), 0.0)
    rel = np.where(np.isfinite(rel), rel, np.inf)
    worst = int(np.argmax(rel))
    max_rel = float(rel[worst])
    status = "agrees" if max_rel <= AGREE_RTOL else "differs"
    return {
        "seed": check.seed,
        "equation": check.equation,
        "description": check.description,
        "status": status,
        "max_rel_diff": max_rel,
        "samples": n,
        "example": {
            "inputs": {k: np.asarray(v)[worst].tolist() for k, v in x.items()},
            "printed": p[worst].tolist(),
            "derived": d[worst].tolist(),
        },
        "note": check.note,
    }


@dataclass(frozen=True)
class NotCompared:
    """A printed item that is inventoried but not compared numerically, and why
    (illegible in the seed's text, no numeric content, a definition only, ...)."""

    seed: str
    equation: str
    description: str
    reason: str


def modules(package: str | None = None) -> list:
    """The errata modules (``ROLE = "errata"``) of every paper package, or of ``package`` only (``"smm"``: the
    others' derivations are not imported), imported, in name order."""
    from symmech.core import discovery

    return [importlib.import_module(name) for name in discovery.modules("errata")
            if package is None or name.startswith(f"symmech.{package}.")]


def all_checks() -> list[Check]:
    """Checks from every paper package's errata modules (``ROLE = "errata"``)."""
    return [c for module in modules() for c in module.checks()]


def all_not_compared() -> list[NotCompared]:
    """The printed items each paper's errata modules list as not compared (``not_compared()``)."""
    return [n for module in modules() if hasattr(module, "not_compared")
            for n in module.not_compared()]


def coverage(records: list[dict], skipped: list[NotCompared]) -> dict:
    """Per seed: printed items inventoried, compared (agree/differ) and not compared with the reason."""
    out = {}
    for r in records:
        c = out.setdefault(r["seed"], {"compared": 0, "agree": 0, "differ": 0, "not_compared": []})
        c["compared"] += 1
        c["agree" if r["status"] == "agrees" else "differ"] += 1
    for n in skipped:
        c = out.setdefault(n.seed, {"compared": 0, "agree": 0, "differ": 0, "not_compared": []})
        c["not_compared"].append({"equation": n.equation, "description": n.description, "reason": n.reason})
    for c in out.values():
        c["inventoried"] = c["compared"] + len(c["not_compared"])
    return dict(sorted(out.items()))


def report(records: list[dict]) -> str:
    """Human-readable table of records, with the counterexample of each difference."""
    lines = []
    for r in records:
        lines.append(f"{r['seed']}  {r['equation']:<10} {r['status']:<8} "
                     f"max rel diff {r['max_rel_diff']:.3g}  {r['description']}")
        if r["status"] == "differs":
            ex = r["example"]
            inputs = ", ".join(f"{k}={_fmt(v)}" for k, v in ex["inputs"].items())
            lines.append(f"    at {inputs}")
            lines.append(f"    printed {_fmt(ex['printed'])}")
            lines.append(f"    derived {_fmt(ex['derived'])}")
        if r["note"]:
            lines.append(f"    note: {r['note']}")
    differs = sum(r["status"] == "differs" for r in records)
    lines.append(f"{len(records)} formulas checked: {len(records) - differs} agree, {differs} differ")
    return "\n".join(lines)


def coverage_report(cov: dict) -> str:
    """Coverage per seed: what is compared and what is not, with the reason."""
    lines = []
    for seed, c in cov.items():
        lines.append(f"seed {seed}: {c['inventoried']} printed items inventoried, {c['compared']} compared "
                     f"({c['agree']} agree, {c['differ']} differ), {len(c['not_compared'])} not compared")
        lines += [f"    not compared {n['equation']}: {n['description']} — {n['reason']}" for n in c["not_compared"]]
    return "\n".join(lines)


def _fmt(v) -> str:
    if isinstance(v, list):
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
    return f"{v:.6g}" if isinstance(v, float) else str(v)
