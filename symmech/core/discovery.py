"""The one walker that finds what the paper packages declare: producers, errata, scene kinds and engines.

A module says what it is by one module-level line ``ROLE = "<role>"`` (one of :data:`ROLES`), read from its
text, so finding the producers imports no sympy and choosing a kind imports no other paper:

- ``derivation``: ``module_specs()`` of derived modules (:mod:`symmech.core.codegen`, the report);
- ``printed``: ``module_specs()`` of modules emitted as printed (codegen);
- ``errata``: ``checks()`` (and optionally ``not_compared()``) of :mod:`symmech.core.errata`;
- ``kind``: registers a scene kind at import (:mod:`symmech.core.registry`);
- ``engine``: registers a compiled engine at import (:mod:`symmech.core.engines`).

Every paper package is walked with its subpackages (``symmech/trolley/elastic/``); file names play no part.
"""
from __future__ import annotations

import functools
import pkgutil
import re
from pathlib import Path

import symmech

ROLES = ("derivation", "printed", "errata", "kind", "engine")
NOT_PAPERS = ("core", "export", "generated", "templates", "scenes")  # the packages that declare nothing
_MARKER = re.compile(r'^ROLE = "(\w+)"', re.MULTILINE)


def _walk(folder: Path, prefix: str):
    """(module name, source file) of every module under ``folder``, subpackages included, nothing imported
    (``pkgutil.walk_packages`` would import each subpackage, and with it its paper)."""
    for module in pkgutil.iter_modules([str(folder)]):
        if module.ispkg:
            yield prefix + module.name, folder / module.name / "__init__.py"
            yield from _walk(folder / module.name, f"{prefix}{module.name}.")
        else:
            yield prefix + module.name, folder / f"{module.name}.py"


@functools.cache
def declared() -> dict[str, str]:
    """{module name: role} of every declaring module of the paper packages, in name order (nothing imported)."""
    found = {}
    root = Path(symmech.__file__).resolve().parent
    for paper in pkgutil.iter_modules([str(root)]):
        if not paper.ispkg or paper.name in NOT_PAPERS:
            continue
        for name, path in _walk(root / paper.name, f"symmech.{paper.name}."):
            marker = _MARKER.search(path.read_text(encoding="utf-8"))
            if marker:
                if marker.group(1) not in ROLES:
                    raise ValueError(f"{name}: ROLE {marker.group(1)!r} is not one of {ROLES}")
                found[name] = marker.group(1)
    return dict(sorted(found.items()))


def modules(*roles: str) -> list[str]:
    """Names of the modules declaring any of ``roles``, in name order (nothing imported)."""
    return [name for name, role in declared().items() if role in roles]
