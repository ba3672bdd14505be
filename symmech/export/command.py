"""``symmech export fmu|c``: the runtime of the CLI command (the CLI only parses and prints)."""
from __future__ import annotations

from pathlib import Path

from symmech.core import pipeline
from symmech.core.context import Context
from symmech.core.scene import SymmechError
from symmech.export import build, grain, model, trolley
from symmech.export.model import ExportModel

FMI_VERSIONS = (2, 3)
TYPES = ("me", "cs")


def export(what: str, scene, out, fmi: int = 3, kind: str = "me", ctx: Context | None = None) -> Path:
    """Export ``scene`` as an FMU file (``what`` = ``fmu``) or a C folder (``c``) at ``out``; its path. The export
    runs the scene natively (its main table, the FMU's default experiment): that run is estimated first and held to
    ``ctx``'s time budget as `symmech run`'s is (quiet, with the default ``--max-time``, when no ``ctx``)."""
    ctx = ctx or Context(quiet=True)
    if fmi not in FMI_VERSIONS:
        raise SymmechError(f"--fmi {fmi}: expected one of {', '.join(map(str, FMI_VERSIONS))}")
    if kind not in TYPES:
        raise SymmechError(f"--type {kind}: expected one of {', '.join(TYPES)}")
    out = Path(out)
    if what == "fmu" and out.suffix != ".fmu":
        raise SymmechError(f"--out {out}: an FMU file name ends in .fmu")
    if out.exists() and out.is_dir() != (what == "c"):
        raise SymmechError(f"--out {out}: exists and is {'a folder' if out.is_dir() else 'a file'}")
    if what == "c" and out.is_dir() and any(out.iterdir()) and not (out / build.MARKER).is_file():
        raise SymmechError(f"--out {out} is a folder of other files (no {build.MARKER} of an earlier export); "
                           "choose a new or empty folder")
    build.compiler()  # refuse before any work when there is no C compiler
    exported = load(scene, ctx)
    ctx.tick("export: before the C compile")
    return build.fmu(exported, out, fmi, kind) if what == "fmu" else build.c_folder(exported, out)


def load(path, ctx: Context | None = None) -> ExportModel:
    """The export model of the scene at ``path``: an elastic trolley (:mod:`symmech.export.trolley`), a grain
    (:mod:`symmech.export.grain`) or a mechanism (:func:`symmech.export.model.of_scene`, which refuses the other kinds
    in one line); each refuses what it does not cover, then estimates its native run and holds it to ``ctx``'s time
    budget (``pipeline.Scene.budget``)."""
    ctx = ctx or Context(quiet=True)
    scene = pipeline.load(path)
    if scene.kind.name == "grain":
        return grain.load(scene, ctx)
    return (trolley.load if scene.kind.name == "trolley" else model.of_scene)(scene, ctx)
