"""--max-time on every engine path: the elastic trolley's Python engine stops at the budget, wherever it runs
(chosen, or the compiled engine's fallback when the frame along the track cannot be tabulated), and a
fallback re-estimates against what is left of the budget and says so in one line. The target: an overrun of
at most 10 % or 5 s."""
import copy
import re
import subprocess
import sys
import time

import pytest

from badinput import SCENES, bundled
from symmech.core import pipeline
from symmech.core.context import Context
from symmech.core.scene import SymmechError
from symmech.trolley.elastic import simulate as el_sim

HELIX = bundled("trolley_elastic_helix")  # 3 s on 1000 steps: ~30 s on the Python engine


def elastic_setup(speed=None, t_end=None, steps=None):
    doc = copy.deepcopy(HELIX)
    doc["elastic"]["numerics"] = {"modal_samples": 0}
    if speed is not None:
        doc["motion"]["speed"] = speed
        doc["time"] = {"t_end": t_end, "steps": steps}
    return pipeline.load(doc).setup.elastic


def test_the_python_engine_stops_at_the_budget():
    setup = elastic_setup()
    ctx = Context(quiet=True, max_time=1.0)
    with ctx.active(), pytest.raises(SymmechError) as info:
        el_sim.simulate(setup.system, setup.drive, setup.t)
    # one right-hand side past the budget (milliseconds), far inside the 5 s allowed; the run needs ~30 s
    assert 1.0 < ctx.elapsed() < 2.0, ctx.elapsed()
    assert str(info.value).startswith("run stopped after 1 s: over the time budget --max-time 1 s (elastic model, "
                                      "Python engine at t = ")


def test_a_fallback_past_the_budget_is_refused_before_it_runs():
    """A kink in V0 at t = 1.5 s: the compiled engine cannot tabulate the frame, and the Python engine would
    need ~0.1 s x 1000 steps, over the 20 s budget: refused at once, naming the fallback and both times."""
    from symmech.trolley.elastic import compiled as elastic_compiled

    setup = elastic_setup("3 + 20*abs(t - 1.5)", 3.0, 1000)
    ctx = Context(quiet=True, max_time=20.0)
    with ctx.active(), pytest.raises(SymmechError) as info:
        elastic_compiled.simulate(setup.system, setup.drive, setup.t, setup.rtol)
    message = str(info.value)
    assert message.startswith("elastic model on the Python engine: the frame along the track could not be "
                              "tabulated") and "\n" not in message
    assert "re-estimated: ~100 s more, over the " in message and "of --max-time 20 s" in message
    assert ctx.elapsed() < 20.0


def test_a_fallback_within_the_budget_says_so_and_runs(capsys):
    from symmech.trolley.elastic import compiled as elastic_compiled

    setup = elastic_setup("3 + 20*abs(t - 0.003)", 0.006, 3)  # the kink mid-way: 3 steps, ~1 s
    ctx = Context(quiet=False, max_time=60.0)
    with ctx.active():
        out = elastic_compiled.simulate(setup.system, setup.drive, setup.t, 1e-6)
    assert out["engine"] == "python" and "tabulated" in out["engine_reason"]
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("symmech: elastic model on the Python engine: the frame along")
    assert err[0].endswith("re-estimated: ~0.3 s more")


@pytest.mark.slow
@pytest.mark.compiled_elastic  # waits for the session's build of the engine (tests/conftest.py)
def test_command_line_fallback_holds_max_time(tmp_path):
    """`symmech run` of the bundled elastic helix with a kink in V0 on the compiled engine, --max-time 30: the
    estimate's timed sample (or the run) falls back to the Python engine, which re-estimates and is refused in
    one line, exit 2, within 30 s (it ran ~33 s, unbounded by --max-time, before the fallback re-estimated)."""
    text = (SCENES / "trolley_elastic_helix.toml").read_text(encoding="utf-8")
    assert 'speed = "3*t + 7*sin(t/2)"' in text and "[elastic.numerics]\n" in text
    scene = tmp_path / "kink.toml"
    scene.write_text(text.replace('speed = "3*t + 7*sin(t/2)"', 'speed = "3 + 20*abs(t - 1.5)"')
                     .replace("[elastic.numerics]\n", '[elastic.numerics]\nengine = "compiled"\n'))
    started = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "symmech", "run", str(scene), "--out", str(tmp_path / "o"),
                           "--max-time", "30"], capture_output=True, text=True, timeout=300)
    seconds = time.perf_counter() - started
    error = proc.stderr.splitlines()[-1]
    assert proc.returncode == 2 and len(proc.stderr.splitlines()) <= 2, proc.stderr  # an estimate told, at most
    assert error.startswith("symmech: error: elastic model on the Python engine: the frame along the track")
    assert re.search(r"re-estimated: ~[\d.]+ s more, over the [\d.]+ s left of --max-time 30 s", error) and seconds < 30.0
    assert not (tmp_path / "o").exists()
