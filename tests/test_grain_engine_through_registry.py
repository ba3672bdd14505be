"""The grain's run path reaches its compiled engine through the registry (symmech.core.engines), and both
accurate engines report through the one home of their texts and budget (symmech.grain.outcome). No compile:
the registry's engine is replaced by a recording stand-in."""
from dataclasses import replace

from symmech.core import engines, pipeline
from symmech.grain import motion, motion_scene, outcome


class Builder:
    seconds = 80.0

    def __init__(self, built: bool):
        self.built, self.calls = built, []

    def ahead_of_time(self):
        return object() if self.built else None

    def needs_compile(self):
        return not self.built

    def cold(self):
        return not self.built

    def cold_reason(self):
        return "stand-in: cold"

    def warm_in_background(self):
        self.calls.append("background")


class StandIn:
    """What motion_scene may use of a registered engine: builder(), warm(), run() and run_many()."""

    def __init__(self, built: bool):
        self.builder_ = Builder(built)
        self.runs, self.populations = [], []

    def builder(self):
        return self.builder_

    def warm(self, *args, **kwargs):
        self.builder_.calls.append("warm")
        return True

    def run_many(self, inputs):
        self.populations.append((type(inputs).__name__, inputs.models, inputs.starts, inputs.t_end, inputs.workers,
                                 inputs.strict))
        return [motion.Motion(None, motion.ImpactLog([]), {}, [], start, start, {"engine_reason": inputs.reason})
                for start in inputs.starts]

    def run(self, inputs):
        self.runs.append((inputs.model, inputs.numerics.engine, inputs.t_end))
        return motion.Motion(None, motion.ImpactLog([]), {}, [], inputs.start, inputs.start,
                             {"engine": "compiled", "engine_reason": inputs.reason})


def test_a_compiled_run_takes_the_registered_engine(monkeypatch):
    """numerics.engine = "compiled": the run is the registered engine's ``run``, built first when it needs it."""
    sc = pipeline.load("scenes/grain_default.toml").setup
    stand_in = StandIn(built=False)
    monkeypatch.setattr(engines, "get", lambda name: {"grain": stand_in}[name])
    num = replace(sc.numerics, engine="compiled")
    m = motion_scene.simulate(sc, num, duration=0.01)
    assert stand_in.runs == [(sc.model, "compiled", 0.01)] and stand_in.builder_.calls == ["warm"]
    assert m.extra == {"engine": "compiled", "engine_reason": 'numerics.engine = "compiled"'}
    # a population too: one Population of the members by name, through the registry's run_many
    other = replace(sc, numerics=num, duration=0.02, start=replace(sc.start, t=0.005))
    ms = motion_scene.simulate_many([other, other], workers=1, strict=False)
    assert stand_in.populations == [("Population", [sc.model] * 2, [other.start] * 2, 0.02, 1, False)]
    assert [x.start for x in ms] == [other.start] * 2 and ms[0].extra["engine_reason"] == 'numerics.engine = "compiled"'


def test_auto_reads_the_registered_engines_build(monkeypatch):
    """auto: built (ahead of time) -> compiled; cold and a short run -> Python, the build started in the
    background, and the reason is the engine's own."""
    sc = pipeline.load("scenes/grain_default.toml").setup
    built, cold = StandIn(built=True), StandIn(built=False)
    monkeypatch.setattr(engines, "get", lambda name: built)
    assert motion_scene.choose_engine(sc, duration=0.01) == ("compiled", "auto: the compiled engine is built "
                                                                         "(ahead of time)")
    monkeypatch.setattr(engines, "get", lambda name: cold)
    assert motion_scene.choose_engine(sc, duration=1e-4) == ("python", "stand-in: cold")


def test_each_warning_text_has_one_wording():
    """The texts both engines emit, written here as a reader sees them."""
    assert outcome.max_impacts_warning(1.23456789, 7) == ("stopped at t = 1.23457 s after numerics.max_impacts = 7 "
                                                          "impacts")
    assert outcome.chatter_warning(100, 1e-4) == "100 impacts within 0.0001 periods: chattering summed into sliding"
    assert outcome.printed_inadmissible_warning(False) == ("printed impact law: no admissible root; the one used pulls "
                                                           "the grain into the plane (T_z < 0)")
    assert outcome.stalled_error(0.5, 1000, "sliding") == ("grain: the simulation stopped advancing at t = 0.5 s (1000 "
                                                           "regime changes without advancing time, sliding regime)")
    assert outcome.distinct(["b", "a", "b"]) == ["b", "a"]


def test_the_energy_budget_balances_its_parts():
    """Start 2 J, end 1.25 J, work 0.5 J, losses 0.75 + 0.25 + 0.125 J: residual -0.125 J over the largest part, 2 J."""
    report = outcome.EnergyBudget(2.0, 0.5, 0.75, 0.25, 0.125).report(1.25, 1e-6)
    assert report["residual_J"] == -0.125 and report["relative_residual"] == 0.0625 and report["tolerance"] == 1e-6
