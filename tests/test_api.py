"""The Python API: symmech.load -> validated scene -> run() -> Result -> xarray with units.

Exercised on a small kind registered by the test (a harmonic oscillator with a
closed form), so the contract is checked independently of any paper's kind.
"""
import json
import math
import subprocess
import sys

import numpy as np
import pytest

import symmech
from symmech.core import registry, schema
from symmech.core.results import Column, Result, Table
from symmech.core.scene import SceneError

OSCILLATOR = schema.Table("scene", {
    "kind": schema.Str("kind"),
    "omega": schema.Float("angular frequency", unit="rad/s", lo=0.0, lo_open=True, hi=1e3),
    "amplitude": schema.Float("amplitude", unit="m", lo=0.0, default=0.1),
    "duration": schema.Float("duration", unit="s", lo=0.0, lo_open=True, hi=100.0, default=2.0),
})


def _run(setup: dict, ctx) -> Result:
    t = np.linspace(0.0, setup["duration"], 201)
    x = setup["amplitude"] * np.cos(setup["omega"] * t)
    motion = Table((Column("t", "s", "time"), Column("x", "m", "displacement")), np.column_stack([t, x]),
                   doc="free motion", text={"phase": ["up" if s >= 0 else "down" for s in -np.sin(setup["omega"] * t)]})
    k = np.arange(int(setup["omega"] * setup["duration"] / math.pi + 0.5))
    crossings = Table((Column("t", "s", "zero crossing time"), Column("v", "m/s", "velocity")),
                      np.column_stack([(k + 0.5) * math.pi / setup["omega"],
                                       -setup["amplitude"] * setup["omega"] * np.sin((k + 0.5) * math.pi)]))
    return Result("test_oscillator", {"period_s": 2 * math.pi / setup["omega"]},
                  tables={"motion": motion, "crossings": crossings}, events="crossings")


@pytest.fixture
def oscillator(monkeypatch):
    kind = registry.Kind("test_oscillator", "harmonic oscillator (tests only)", OSCILLATOR,
                         prepare=lambda resolved: dict(resolved), run=_run)
    registry.kinds()  # discover the real kinds before adding the test kind
    monkeypatch.setitem(registry._KINDS, kind.name, kind)
    return kind


def test_load_validates_and_resolves(oscillator):
    scene = symmech.load({"kind": "test_oscillator", "omega": 3})
    assert scene.kind is oscillator
    assert scene.resolved == {"kind": "test_oscillator", "omega": 3.0, "amplitude": 0.1, "duration": 2.0}
    with pytest.raises(SceneError, match=r"omega.*\(0, 1000\] rad/s"):
        symmech.load({"kind": "test_oscillator", "omega": -1})


def test_run_to_xarray_with_units(oscillator):
    result = symmech.load({"kind": "test_oscillator", "omega": 2.5, "duration": 3.0}).run()
    ds = result.to_xarray()
    assert list(ds.coords) == ["t"] and ds["x"].dims == ("t",)
    assert ds["t"].attrs == {"units": "s", "long_name": "time"}
    assert ds["x"].attrs == {"units": "m", "long_name": "displacement"}
    t = np.linspace(0.0, 3.0, 201)
    np.testing.assert_allclose(ds["x"].values, 0.1 * np.cos(2.5 * t), rtol=0, atol=1e-15)
    np.testing.assert_allclose(ds["x"].sel(t=ds["t"].values[100]).item(), 0.1 * math.cos(2.5 * 1.5), atol=1e-15)
    assert ds["phase"].values[1] == "down"
    assert ds.attrs["kind"] == "test_oscillator" and ds.attrs["table"] == "motion"
    assert json.loads(ds.attrs["summary"])["period_s"] == pytest.approx(2 * math.pi / 2.5, rel=1e-15)


def test_event_log_is_a_table(oscillator):
    result = symmech.load({"kind": "test_oscillator", "omega": 2.0, "duration": 5.0}).run()
    events = result.event_log()
    # zero crossings of cos(2 t) in [0, 5]: t = (k + 1/2) pi / 2, k = 0..2
    np.testing.assert_allclose(events["t"].values, [math.pi / 4, 3 * math.pi / 4, 5 * math.pi / 4], rtol=1e-15)
    np.testing.assert_allclose(np.abs(events["v"].values), 0.2, rtol=1e-15)
    assert events["t"].dims == ("row",) and events["v"].attrs["units"] == "m/s"
    with pytest.raises(KeyError, match="no table 'nope'; tables: motion, crossings"):
        result.to_xarray("nope")


def test_import_stays_light():

    code = "import symmech, sys; assert 'sympy' not in sys.modules and 'xarray' not in sys.modules; print('ok')"
    assert subprocess.run([sys.executable, "-c", code], capture_output=True, text=True).stdout == "ok\n"


def test_api_matches_the_command_line(tmp_path):
    """A bundled scene through the API gives the numbers `symmech run` writes (the CLI is a shell over it)."""
    from pathlib import Path

    from symmech.cli import main

    scene = Path(__file__).resolve().parents[1] / "scenes" / "trolley_helix.toml"
    text = scene.read_text().replace("steps = 5000", "steps = 200").replace("paper_tables = true", "paper_tables = false")
    (tmp_path / "s.toml").write_text(text)
    ds = symmech.load(tmp_path / "s.toml").run().to_xarray("case1")
    assert main(["run", str(tmp_path / "s.toml"), "--out", str(tmp_path / "o")]) == 0
    lines = (tmp_path / "o" / "case1.csv").read_text().splitlines()
    header = [h.split(" [") for h in lines[0].split(",")]
    data = np.array([[float(x) for x in l.split(",")] for l in lines[1:]])
    assert header[0] == ["t", "s]"] and ds["t"].attrs["units"] == "s"
    for j, (name, unit) in enumerate(header[1:], start=1):
        assert ds[name].attrs["units"] == unit.rstrip("]")
        np.testing.assert_allclose(ds[name].values, data[:, j], rtol=1e-12, atol=1e-12)


def test_discovery_finds_every_kind_after_one_registered_itself():
    """Importing one kind's module first (as a test or a user script may) must not hide the others."""
    code = ("import symmech.smm.scene; from symmech.core import registry; "
            "print(sorted(registry.kinds()))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "['grain', 'impact', 'mechanism', 'trolley']"


def test_a_scene_given_as_a_dict_is_held_to_the_nesting_bound_of_a_file():
    """A dict scene nested 40 arrays deep (a file's bound is 32) is refused in one line naming the first field past
    the bound, as a TOML file would be, before its schema reads it."""
    from symmech.core import pipeline

    deep = 0
    for _ in range(40):
        deep = [deep]
    with pytest.raises(SceneError) as err:
        pipeline.load({"kind": "grain", "grain": deep})
    assert str(err.value) == "scene field 'grain" + "[0]" * 32 + "': nested deeper than 32 tables or arrays"


def test_an_estimate_is_timed_on_this_machine_only_when_asked(oscillator, monkeypatch):
    """The count model ω·duration/100 s as it is, and timed by the kind's samples within max_time when sampled."""
    import dataclasses

    from symmech.core import sample

    counted = dataclasses.replace(oscillator, estimate=lambda setup: registry.Estimate(
        setup["omega"] * setup["duration"] / 100, "steps"))
    monkeypatch.setitem(registry._KINDS, counted.name, counted)
    monkeypatch.setattr(sample, "timed", lambda kind, setup, cost, max_time: registry.Estimate(
        2 * cost.seconds, f"{cost.what}, timed within {max_time:g} s"))
    scene = symmech.load({"kind": "test_oscillator", "omega": 4.0, "duration": 5.0})
    assert scene.estimate() == registry.Estimate(0.2, "steps")
    assert scene.estimate(7.0, sampled=True) == registry.Estimate(0.4, "steps, timed within 7 s")
