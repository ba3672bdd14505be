"""Compile an exported model with the system C compiler and pack it: an FMU (zip) or a C folder.

The compiler is ``$CC`` or ``cc``; without one, SymmechError (one line, exit 2). Outputs are written to a
temporary name beside the target and renamed into place.
"""
from __future__ import annotations

import os
import platform
import shutil
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

from symmech.core.integrity import write_atomic
from symmech.core.scene import SymmechError
from symmech.export import description, sources
from symmech.export.model import ExportModel

CFLAGS = ("-std=c99", "-O2", "-fPIC", "-fvisibility=hidden")
MARKER = "symmech_model.h"  # a C folder holding it is an earlier export, which `export c` may replace
MAKEFILE = """# {identifier}: the example program of the exported model (written by symmech export)
CC ?= cc
CFLAGS ?= -std=c99 -O2
SOURCES = symmech_model.c {sources}

example: example.c $(SOURCES) model.h symmech_model.h dop853_tableau.h radau_tableau.h
\t$(CC) $(CFLAGS) -o $@ example.c $(SOURCES) -lm

clean:
\trm -f example
"""


def compiler() -> str:
    """Path of the C compiler (``$CC`` or ``cc``); SymmechError when there is none."""
    name = os.environ.get("CC") or "cc"
    path = shutil.which(name)
    if path is None:
        raise SymmechError(f"no C compiler: '{name}' is not on PATH; install one (e.g. gcc) or set CC")
    return path


def compile_c(folder: Path, files: list[str], output: Path, shared: bool) -> None:
    """Compile ``files`` of ``folder`` into ``output`` (a shared library when ``shared``)."""
    command = [compiler(), *CFLAGS, *(["-shared"] if shared else []), "-o", str(output), *files, "-lm"]
    done = subprocess.run(command, cwd=folder, capture_output=True, text=True)
    if done.returncode != 0:
        first = (done.stderr.strip().splitlines() or ["no message"])[0]
        raise SymmechError(f"the C compiler failed on the exported sources: {first}")


def platform_folder(fmi: int) -> str:
    """``binaries/`` subfolder of this platform in FMI ``fmi`` (2: linux64, 3: x86_64-linux, ...)."""
    machine = {"amd64": "x86_64", "arm64": "aarch64"}.get(platform.machine().lower(), platform.machine().lower())
    system = {"linux": "linux", "darwin": "darwin", "win32": "windows"}.get(sys.platform, sys.platform)
    if fmi == 3:
        return f"{machine}-{system}"
    bits = "64" if sys.maxsize > 2**32 else "32"
    return {"windows": "win", "darwin": "darwin"}.get(system, system) + bits


def library_suffix() -> str:
    return {"darwin": ".dylib", "win32": ".dll"}.get(sys.platform, ".so")


def fmu(model: ExportModel, out: Path, fmi: int = 3, kind: str = "me") -> Path:
    """Write the FMU of ``model`` to ``out``: modelDescription.xml, the sources and this platform's binary."""
    token = sources.token(model)
    texts = sources.files(model) | {f"fmi{fmi}.c": sources.glue(f"fmi{fmi}.c")}
    xml = (description.fmi3 if fmi == 3 else description.fmi2)(model, token, kind)
    out = Path(out).absolute()
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for name, text in texts.items():
            (folder / name).write_text(text, encoding="utf-8")
        library = folder / (model.identifier + library_suffix())
        compile_c(folder, list(description.source_files(model, fmi)), library, shared=True)
        archive = folder / "model.fmu"
        with zipfile.ZipFile(archive, "w", zipfile.ZIP_DEFLATED) as z:
            z.writestr("modelDescription.xml", xml)
            for name, text in sorted(texts.items()):
                z.writestr(f"sources/{name}", text)
            if fmi == 3:
                z.writestr("sources/buildDescription.xml", description.build_description(model))
            z.write(library, f"binaries/{platform_folder(fmi)}/{library.name}")
        _replace(archive, out)
    return out


def c_folder(model: ExportModel, out: Path) -> Path:
    """Write the C folder of ``model`` to ``out`` (headers, sources, example.c, Makefile) and check that it
    compiles; the folder is replaced whole."""
    texts = sources.files(model) | {"example.c": sources.glue("example.c"),
                                    "Makefile": MAKEFILE.format(identifier=model.identifier,
                                                                  sources=" ".join(model.c_files()))}
    out = Path(out).absolute()
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(dir=out.parent, prefix=f".{out.name}."))
    try:
        tmp.chmod(0o755)  # mkdtemp's 0700 would hide the folder from other users
        for name, text in texts.items():
            write_atomic(tmp / name, text)
        compile_c(tmp, ["example.c", "symmech_model.c", *model.c_files()], tmp / "example", shared=False)
        if out.exists():  # moved aside first: `out` is never missing
            old = Path(tempfile.mkdtemp(dir=out.parent, prefix=f".{out.name}.old-"))
            os.rename(out, old / "previous")
            os.rename(tmp, out)
            shutil.rmtree(old, ignore_errors=True)
        else:
            os.rename(tmp, out)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
    return out


def _replace(source: Path, target: Path) -> None:
    """Copy ``source`` beside ``target`` under a temporary name, then rename it into place."""
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=f".{target.name}.", suffix=".tmp")
    os.close(fd)
    try:
        shutil.copyfile(source, tmp)
        os.chmod(tmp, 0o644)
        os.replace(tmp, target)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
