"""Command-line interface: ``symmech run | sweep | warm | report | codegen | latex | errata | bench | export``.

Errors a user can fix (:class:`SymmechError`) print as one line on stderr with
exit status 2, never a traceback.
"""
from __future__ import annotations

import argparse
import gc
import importlib
import importlib.util
import json
import os
import signal
import sys
import threading
from pathlib import Path

from symmech import __version__
from symmech.core import engines
from symmech.core.context import DEFAULT_MAX_TIME, Context
from symmech.core.scene import SymmechError

def _context(ns):
    return Context(quiet=ns.quiet, max_time=ns.max_time)


def cmd_run(ns) -> int:
    from symmech.core import pipeline

    _, result = pipeline.run_to(ns.scene, ns.out, _context(ns), plots=not ns.no_plots)
    if not ns.quiet and result.brief():
        print(result.brief())
    print(f"wrote {Path(ns.out) / 'summary.json'}")
    return cmd_report(ns) if ns.report else 0


def cmd_sweep(ns) -> int:
    from symmech.core import sweep

    options = {"half_width": ns.half_width} if ns.half_width is not None else {}
    result = sweep.run(ns.scene, ns.out, _context(ns), scheduler=ns.scheduler, workers=ns.workers,
                       connect_timeout=ns.connect_timeout, **options)
    for warning in result.warnings:
        print(f"symmech: warning: {warning}", file=sys.stderr)
    print(f"wrote {Path(ns.out) / 'summary.json'}")
    if not ns.quiet and result.brief():
        print(result.brief())
    return 0


BUILDER_NICENESS = 19  # the lowest priority


def cmd_warm(ns) -> int:
    import time

    say = None if ns.quiet or ns.background else (lambda text: print(f"symmech: {text}", file=sys.stderr))
    if ns.background:  # the run that started this builder, and any started meanwhile, come first on the cores
        os.nice(BUILDER_NICENESS)
    for name, engine in engines.engines().items():
        if ns.engine not in ("all", name):
            continue
        started = time.perf_counter()
        if not engine.warm(wait=not ns.background, say=say, ahead=True):
            continue  # --background: another builder holds the lock
        if not ns.background:
            builder = engine.builder()
            built = builder.ahead_of_time()
            ahead = f"; built ahead of time: {built.__file__}" if built is not None else ""
            print(f"compiled {name} engine ready in {time.perf_counter() - started:.1f} s; cache: "
                  f"{builder.cache_dir()}{ahead}")
    return 0


def cmd_report(ns) -> int:
    from symmech import report

    if getattr(ns, "precision", False):
        print(f"wrote {report.run_precision(Path(ns.out), _context(ns))}")
    print(f"wrote {report.write(Path(ns.out))}")
    return 0


def cmd_bench(ns) -> int:
    from symmech.core import pipeline

    _, result = pipeline.run_to(ns.scene, ns.out, _context(ns), study="precision")
    for name in ["summary.json", *[f"{t}.csv" for t in result.tables], *result.files]:
        print(f"wrote {Path(ns.out) / name}")
    return 0


def cmd_export(ns) -> int:
    from symmech.export.command import export

    print(f"wrote {export(ns.what, ns.scene, ns.out, ns.fmi, ns.type, _context(ns))}")
    return 0


def _default_generated() -> Path:
    """The package's generated/ folder when it sits in a writable checkout; SymmechError otherwise."""
    from symmech.core import codegen

    folder = Path(importlib.util.find_spec("symmech.generated").submodule_search_locations[0])
    checkout = (folder.name == "generated" and folder.parent == codegen.ROOT
                and (folder.parent / "pyproject.toml").is_file())
    if not checkout or not os.access(folder, os.W_OK):
        raise SymmechError(f"codegen: {folder} is an installed package, not a writable symmech checkout; "
                           "regenerate into a folder you name with --dir DIR")
    return folder


def cmd_codegen(ns) -> int:
    from symmech.core import codegen

    if ns.dir:
        directory = Path(ns.dir)
    elif ns.check:
        directory = Path(importlib.util.find_spec("symmech.generated").submodule_search_locations[0])
    else:
        directory = _default_generated()
    if directory.exists() and not directory.is_dir():
        raise SymmechError(f"codegen --dir: {directory} is not a folder")
    try:
        with Context().progress(len(codegen.producers()), "codegen", unit="module") as bar:  # shown past 2 s
            report = codegen.run(directory, check=ns.check, progress=bar)
    except OSError as exc:
        raise SymmechError(f"codegen --dir: cannot use {exc.filename or directory}: {exc.strerror}") from None
    ran = f"{len(report.derived)} derivation modules run" if report.derived else "nothing derived (cache)"
    if ns.check and report.outdated_keys:
        print(f"note: {len(report.outdated_keys)} files have outdated source keys (output unchanged); "
              "`symmech codegen` refreshes them so --check stays fast", file=sys.stderr)
    if ns.check:
        if report.stale:
            print("stale generated files (run `symmech codegen`):", file=sys.stderr)
            for path in report.stale:
                print(f"  {path}", file=sys.stderr)
            return 1
        print(f"{directory} is up to date ({ran}, {report.seconds:.1f} s)")
        return 0
    for path in report.written:
        print(f"wrote {path}")
    print(f"codegen: {len(report.written)} files written, {ran}, {report.seconds:.1f} s")
    return 0


def _named_matrix(name: str):
    """The derived matrix ``module.function``; a name the generated index does not list is refused before any
    derivation, and only the producer the index names for ``module`` is derived (one paper's, not all)."""
    from symmech.core import codegen
    from symmech.core.schema import did_you_mean
    from symmech.generated import MATRICES, MODULES

    if name not in MATRICES:
        raise SymmechError(f"no derived matrix named '{name}'{did_you_mean(name, MATRICES)} "
                           "(see `symmech latex --list`)")
    specs = codegen.derive(MODULES[name.partition(".")[0]])[0]
    return next(f for s in specs for f in s.functions if f"{s.name}.{f.name}" == name)


def _scene_matrix(name: str):
    """``prefix:rest`` names come from ``symmech.<prefix>.latex_matrices(rest)``."""
    prefix, _, rest = name.partition(":")
    try:
        provider = importlib.import_module(f"symmech.{prefix}")
    except ModuleNotFoundError:
        raise SymmechError(f"unknown matrix namespace '{prefix}:'") from None
    if not hasattr(provider, "latex_matrices"):
        raise SymmechError(f"unknown matrix namespace '{prefix}:'")
    matrices = provider.latex_matrices(rest)
    if name not in matrices:
        raise SymmechError(f"no derived matrix named '{name}' (see `symmech latex --list`)")
    return matrices[name]


def cmd_latex(ns) -> int:
    import sympy

    from symmech.core import emit, latex

    if ns.list or not ns.name:
        from symmech.generated import MATRICES  # the listing codegen wrote: no derivation

        for key, (meaning, equations) in MATRICES.items():
            eq = f"  eqs. {equations}" if equations else ""
            print(f"{key:<40} {meaning}{eq}")
        return 0
    nm = _scene_matrix(ns.name) if ":" in ns.name else _named_matrix(ns.name)
    if ns.cse:
        # The same chunks and CSE symbols as the generated code, shown with the
        # derivation's own symbols.
        back = {sympy.Symbol(a.name): a.symbol for a in nm.args}
        pairs = []
        for chunk in emit.cse_chunks(nm):
            pairs += [(sympy.latex(sym), expr.xreplace(back)) for sym, expr in chunk.replacements]
            pairs += [(latex.entry_tex(nm.name, index), expr.xreplace(back)) for index, expr in chunk.elements]
    else:
        pairs = latex.equations(nm)
    body = latex.lines(pairs)
    print(f"% {ns.name}: {nm.meaning}")
    print(latex.environment(body))
    if ns.tex:
        eqs = f" (eqs. {nm.equations})" if nm.equations else ""
        description = f"{nm.meaning}{eqs}; unit {nm.unit}" + ("; common subexpressions as in the generated code"
                                                               if ns.cse else "")
        Path(ns.tex).write_text(latex.document(f"symmech {__version__}: {ns.name}", [(ns.name, description, body)]))
        print(f"% wrote {ns.tex}")
    return 0


def cmd_errata(ns) -> int:
    from symmech.core import errata

    records = [errata.evaluate(c) for c in errata.all_checks()]
    cov = errata.coverage(records, errata.all_not_compared())
    if ns.json:
        print(json.dumps({"records": records, "coverage": cov}, indent=2))
    else:
        print(errata.report(records))
        print(errata.coverage_report(cov))
    return 0


def _positive(quantity: str, unit: str):
    """An argparse type: a positive finite number of ``unit`` (argparse reports the error, naming ``quantity``)."""
    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {quantity}, got {text!r}") from None
        if not 0 < value < float("inf"):
            raise argparse.ArgumentTypeError(f"{text} is outside (0, inf) {unit}")
        return value
    return parse


_seconds = _positive("a number of seconds", "s")  # --max-time, --connect-timeout
_speed = _positive("a speed in m/s", "m/s")  # --half-width


def _run_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--quiet", action="store_true", help="no progress bars and no estimate")
    p.add_argument("--max-time", type=_seconds, default=DEFAULT_MAX_TIME, metavar="SECONDS",
                   help="refuse a run estimated to take longer, stop one that does "
                        f"(default {DEFAULT_MAX_TIME:g} s)")


class _Parser(argparse.ArgumentParser):
    """Usage errors as one line naming the problem and where to find help, exit 2."""

    def error(self, message):
        self.exit(2, f"{self.prog}: error: {message} (see `{self.prog} --help`)\n")


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(
        prog="symmech",
        description="Symbolic derivations of three mechanics papers, emitted as numpy modules, "
                    "with simulations and checks against the papers.",
    )
    p.add_argument("--version", action="version", version=f"symmech {__version__}")
    sub = p.add_subparsers(dest="command", required=True)

    r = sub.add_parser("run", help="run a scene file and write results to a folder")
    r.add_argument("scene", help="scene file (TOML); see docs/scenes.md")
    r.add_argument("--out", default="out", help="output folder (default: out)")
    _run_options(r)
    r.add_argument("--no-plots", action="store_true", help="write tables and summary only, no plots")
    r.add_argument("--report", action="store_true", help="also write OUT/report.html (see `symmech report`)")
    r.set_defaults(func=cmd_run)

    sw = sub.add_parser("sweep", help="a scene over a swept plane of its fields (the scene's [sweep]): grain "
                                      "populations (docs/scenes-grain.md), trolley designs "
                                      "(docs/scenes-trolley.md)")
    sw.add_argument("scene", help="grain or trolley scene file (TOML) with a [sweep] table")
    sw.add_argument("--out", default="out-sweep", help="output folder (default: out-sweep)")
    _run_options(sw)
    sw.add_argument("--scheduler", metavar="ADDRESS",
                    help="address of a dask.distributed scheduler (default: a local process pool)")
    sw.add_argument("--connect-timeout", type=_seconds, default=5.0, metavar="SECONDS",
                    help="how long the --scheduler address may take to answer (default 5 s)")
    sw.add_argument("--workers", type=int, metavar="N", help="local worker processes (default: the CPU count)")
    sw.add_argument("--half-width", type=_speed, metavar="M_PER_S",
                    help="grain sweeps: the summary's precision target, grains needed for a mean velocity to "
                         "within this, at 95 %% (default 0.001 m/s)")
    sw.set_defaults(func=cmd_sweep)

    w = sub.add_parser("warm", help="compile the compiled engines into numba's cache now (for containers, "
                                    "clusters, CI); prints where the cache is", description="Compile "
                       "every compiled kernel a run of the chosen engines may need into numba's cache, "
                       "once per cache: NUMBA_CACHE_DIR when set, else "
                       "__pycache__ beside the installed package (numba's user-wide cache when that is read-only). "
                       "With a C compiler, an engine that has an ahead-of-time build (the grain's) is also built "
                       "beside the cache, so that later runs load it without numba. "
                       "A second `symmech warm` on the same cache waits for the first and then finds it built. "
                       "Exit 0 once the cache holds the engine.")
    w.add_argument("--quiet", action="store_true", help="print only the cache location")
    w.add_argument("--engine", choices=engines.Choices(), default="all", metavar="NAME",  # no listing at build
                   help="which compiled engine to build: %(choices)s (default: all; the registered engines, "
                        "docs/ARCHITECTURE.md)")
    w.add_argument("--background", action="store_true", help=argparse.SUPPRESS)  # the detached builder of a run
    w.set_defaults(func=cmd_warm)

    rp = sub.add_parser("report", help="write a self-contained HTML report of a finished run (OUT/report.html)")
    rp.add_argument("out", help="the run's output folder (holds summary.json)")
    rp.add_argument("--precision", action="store_true",
                    help="first run the scene's work-precision study (`symmech bench precision`) into OUT/precision")
    _run_options(rp)
    rp.set_defaults(func=cmd_report)

    c = sub.add_parser("codegen", help="regenerate the numeric modules in generated/")
    c.add_argument("--check", action="store_true",
                   help="write nothing; exit 1 and name the stale, missing or stray files if generated/ "
                        "is out of date")
    c.add_argument("--dir", help="target folder (default: generated/ of the checkout; required when "
                                 "symmech is installed without -e)")
    c.set_defaults(func=cmd_codegen)

    lx = sub.add_parser("latex", help="print a derived matrix as LaTeX")
    lx.add_argument("name", nargs="?", help="matrix name, e.g. grain_impact.H (see --list)")
    lx.add_argument("--list", action="store_true", help="list every derived matrix")
    lx.add_argument("--cse", action="store_true",
                    help="print the common-subexpression form used by the generated code")
    lx.add_argument("--tex", metavar="FILE", help="also write a standalone LaTeX document (compiles with pdflatex)")
    lx.set_defaults(func=cmd_latex)

    e = sub.add_parser("errata", help="compare the papers' printed formulas with the derivations")
    e.add_argument("--json", action="store_true", help="print a JSON list of records")
    e.set_defaults(func=cmd_errata)

    b = sub.add_parser("bench", help="accuracy-versus-time studies")
    bsub = b.add_subparsers(dest="bench", required=True)
    bp = bsub.add_parser("precision", help="work-precision diagram (CSV + PNG) for a scene")
    bp.add_argument("scene", help="scene file (TOML)")
    bp.add_argument("--out", default="out-precision", help="output folder")
    _run_options(bp)
    bp.set_defaults(func=cmd_bench)

    x = sub.add_parser("export", help="the scene's model outside Python: an FMU (FMI 2 or 3) or C sources")
    x.add_argument("what", choices=("fmu", "c"), help="fmu: an FMU file; c: a folder of C sources and an example")
    x.add_argument("scene", help="scene file (TOML): a mechanism, an elastic trolley or a grain (docs/export.md)")
    x.add_argument("--out", required=True, help="the .fmu file (fmu) or the folder (c)")
    x.add_argument("--fmi", type=int, choices=(2, 3), default=3, help="FMI version of the FMU (default 3)")
    x.add_argument("--type", choices=("me", "cs"), default="me",
                   help="me: Model Exchange (the importer integrates), cs: Co-Simulation (DOP853 inside)")
    _run_options(x)  # the export runs the scene natively (its main table): estimated and bounded as `run` is
    x.set_defaults(func=cmd_export)
    return p


def _on_sigterm(signum, frame):
    raise KeyboardInterrupt  # clean up like Ctrl-C: temporary folder and lock removed


def main(argv=None) -> int:
    """Run one command; user errors exit 2, Ctrl-C 130, internal errors 3 — one line each.

    ``argv`` None: the process's own command line. Its imports (numba, matplotlib) build ~10^5 long-lived
    objects that the garbage collector would walk again and again, so collections start at 10,000 new objects
    instead of 700; and as the process ends after the command, every object still alive is frozen out of the
    collector (``gc.freeze``), which spares the final collections. Together ~0.5-0.75 s of the main job
    (``benchmarks/bench_pipeline.py``: "gc untuned")."""
    if argv is None:
        gc.set_threshold(10_000)
    ns = build_parser().parse_args(argv)
    in_main = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGTERM, _on_sigterm) if in_main else None
    try:
        return ns.func(ns)
    except SymmechError as exc:
        print(f"symmech: error: {_one_line(exc)}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        kept = f"; {ns.out} keeps its previous content" if getattr(ns, "out", None) else ""
        print(f"symmech: interrupted{kept}", file=sys.stderr)
        return 130
    except BrokenPipeError:  # output piped into `head` and the like
        return 0
    except Exception as exc:  # a bug: one line, the traceback only on request
        if os.environ.get("SYMMECH_TRACEBACK"):
            raise
        print(f"symmech: internal error: {type(exc).__name__}: {_one_line(exc)} (please report; "
              "SYMMECH_TRACEBACK=1 shows the traceback)", file=sys.stderr)
        return 3
    finally:
        if in_main:
            signal.signal(signal.SIGTERM, previous)
        if argv is None:
            gc.freeze()


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split()) or type(exc).__name__


if __name__ == "__main__":
    sys.exit(main())
