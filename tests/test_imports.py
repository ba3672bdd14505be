"""Lazy imports: a command loads only what it needs.

Each case runs in a fresh interpreter and reports which heavy packages ended up in
``sys.modules``; the expected sets are written out, so a new eager import fails here.
"""
import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
# Modules a grain run must not load: derivations (sympy, jinja2), sweeps (dask, distributed),
# the xarray API, pyplot (figures are drawn on the Agg canvas), and the other papers' kinds.
HEAVY = ("sympy", "jinja2", "dask", "distributed", "xarray", "pandas", "matplotlib", "matplotlib.pyplot",
         "symmech.smm", "symmech.trolley")


def _loaded(tmp_path: Path, *args: str, code: str = "") -> list[str]:
    """The HEAVY modules imported by ``symmech <args>`` (or by ``code``) in a fresh process."""
    run = code or f"from symmech.cli import main; assert main({list(args)!r}) == 0"
    probe = f"import json, sys; {run}; print(json.dumps(sorted(m for m in {HEAVY!r} if m in sys.modules)))"
    proc = subprocess.run([sys.executable, "-c", probe], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout.splitlines()[-1])


def _short_grain(tmp_path: Path, output: str = "") -> str:
    text = re.sub(r"(?m)^duration = .*$", "duration = 0.05", (ROOT / "scenes" / "grain_default.toml").read_text())
    path = tmp_path / "g.toml"
    path.write_text(text + output)
    return str(path)


def test_cli_import_loads_no_numerics(tmp_path):
    code = "import symmech.cli; import sys; assert 'numpy' not in sys.modules and 'scipy' not in sys.modules"
    assert _loaded(tmp_path, code=code) == []


def test_grain_run_without_plots_loads_no_heavy_package(tmp_path):
    assert _loaded(tmp_path, "run", _short_grain(tmp_path), "--out", "o", "--no-plots", "--quiet") == []
    assert _loaded(tmp_path, "run", _short_grain(tmp_path, "[output]\nplots = []\n"), "--out", "o2", "--quiet") == []


def test_grain_run_with_its_default_plot_loads_matplotlib_but_not_pyplot(tmp_path):
    assert _loaded(tmp_path, "run", _short_grain(tmp_path), "--out", "o", "--quiet") == ["matplotlib"]
    assert json.loads((tmp_path / "o" / "summary.json").read_text())["files"] == \
        ["impacts.csv", "path.png", "trajectory.csv"]


@pytest.mark.slow
@pytest.mark.compiled_engine
def test_compiled_grain_run_loads_no_scipy_integrate_or_optimize(tmp_path):
    """The compiled engine steps with symmech's own DOP853 tableau and root finders: neither the engine's
    import nor a run that stays compiled (0.05 s of the default scene: no stiff slip handed to Radau)
    loads scipy.integrate or scipy.optimize (~0.15 s of imports). numba itself loads scipy.linalg (BLAS)."""
    code = ("import sys; from symmech.grain.motion_engine import driver as compiled; "
            "print(sorted(m for m in ('scipy.integrate', 'scipy.optimize') if m in sys.modules))")
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert proc.stdout.split() == ["[]"], proc.stderr
    args = ["run", _short_grain(tmp_path), "--out", "o", "--quiet"]
    run = f"from symmech.cli import main; assert main({args!r}) == 0"
    code = (f"import json, sys; {run}; s = json.load(open('o/summary.json')); "
            "print(s['engine'], sorted(m for m in ('scipy.integrate', 'scipy.optimize') if m in sys.modules))")
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert proc.stdout.splitlines()[-1] == "compiled []", proc.stderr


def test_the_command_line_process_tunes_gc_but_a_caller_of_main_does_not(tmp_path):
    """``main()`` on the process's own argv: collections start at 10,000 new objects instead of 700, and as
    the process ends, every live object is frozen out of the garbage collector (the final collections skip
    them); ``main(argv)`` called from Python leaves gc as it was."""
    args = ["run", _short_grain(tmp_path), "--out", "o", "--quiet", "--no-plots"]
    code = ("import gc, sys; from symmech.cli import main; sys.argv = ['symmech', *{args!r}]; "
            "default = gc.get_threshold()[0]; "
            "print(main({call}), default, gc.get_threshold()[0], gc.get_freeze_count() > 10000)")
    for call, tuned in (("", True), (repr(args), False)):
        proc = subprocess.run([sys.executable, "-c", code.format(args=args, call=call)], cwd=tmp_path,
                              capture_output=True, text=True, timeout=600)
        status, default, threshold, frozen = proc.stdout.splitlines()[-1].split()
        assert (status, threshold, frozen) == ("0", "10000" if tuned else default, str(tuned)), proc.stderr


def test_a_kind_is_found_without_importing_the_other_papers(tmp_path):
    code = ("import sys; from symmech.core import registry; registry.get('trolley'); "
            "print(sorted(p for p in ('symmech.grain', 'symmech.smm', 'symmech.trolley') if p in sys.modules))")
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert proc.stdout.split() == ["['symmech.trolley']"], proc.stderr


def test_a_rigid_trolley_run_loads_no_elastic_model(tmp_path):
    """The elastic model (and its generated module) only for a scene with an ``[elastic]`` table: the run's
    ``generated_modules``, which the report derives and typesets, are then the rigid trolley's only."""
    text = (ROOT / "scenes" / "trolley_helix.toml").read_text()
    text = text.replace("steps = 5000", "steps = 50").replace("paper_tables = true", "paper_tables = false")
    (tmp_path / "t.toml").write_text(text)
    code = ("import json, sys; from symmech.cli import main; assert main(['run', 't.toml', '--out', 'o', '--quiet',"
            " '--no-plots']) == 0; print(json.dumps(sorted(m for m in sys.modules if 'elastic' in m)))")
    proc = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert json.loads(proc.stdout.splitlines()[-1]) == ["symmech.trolley.elastic", "symmech.trolley.elastic.schema"]  # the package: a docstring
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert sorted(summary["generated_modules"]) == ["trolley_dynamics", "trolley_frame", "trolley_printed"]
