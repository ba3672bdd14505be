"""The Python grain loop reports its progress once at the end, with the final time, however little wall time the
run took: with the wall clock stopped (the test's own), a drop that flies, lands plastically and slides reports
exactly once, t_end."""
from symmech.grain import motion
from test_grain_motion_closed_forms import T_C, frictionless, numerics, sphere, state


def test_a_run_reports_its_final_time_once_when_no_wall_time_passes(monkeypatch):
    monkeypatch.setattr(motion.time, "monotonic", lambda: 100.0)
    t_end = T_C + 0.002  # contact at sqrt(2h/g), then 2 ms of sliding
    seen = []
    res = motion.simulate(sphere(frictionless(0.0)), numerics(), state(), t_end, on_step=seen.append)
    assert len(res.impacts) == 1 and abs(res.impacts[0]["t"] - T_C) < 1e-12 and res.extra["landings"] == 1
    assert seen == [t_end] and type(seen[0]) is float
