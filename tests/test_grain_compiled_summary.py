"""The summary of a compiled grain run against the closed form of a drop: a point mass (rotation off) sliding
frictionlessly along x and y while it bounces on a still plate with e = 0.5, started at t0 = 0.3 s; contacts at
t0 + t_c and t0 + 2 t_c (t_c = sqrt(2h/g), the second bounce lasting 2 e t_c), each losing (1 - e²) of its normal
kinetic energy ½ m (e^k g t_c)²; the horizontal velocity kept. Progress is reported once at the end, at t_end (with
no report in between: the wall time between reports made endless)."""
import math

import pytest

from symmech.grain import motion
from symmech.grain.motion_engine import driver as compiled
from test_grain_motion_closed_forms import A, G, H, M, T_C, frictionless, numerics, sphere, state

pytestmark = [pytest.mark.slow, pytest.mark.compiled_engine]  # the engine's build: slow tier (conftest.py)


def test_summary_of_two_bounces_is_the_closed_form_drops(monkeypatch):
    monkeypatch.setattr(motion, "PROGRESS_INTERVAL", math.inf)
    e, t0, duration, vx, vy = 0.5, 0.3, 2.2 * T_C, 0.02, -0.01
    start = state(v=(vx, vy, 0.0))
    start.t = t0
    seen = []
    res = compiled.simulate(sphere(frictionless(e), rotation=False), numerics(), start, t0 + duration, seen.append)
    assert seen == [t0 + duration]
    lost = 0.5 * M * (G * T_C) ** 2 * (1 - e * e) * (1 + e * e)
    energy = 0.5 * M * (vx * vx + vy * vy) + M * G * (A + H)
    assert [i["t"] for i in res.impacts] == pytest.approx([t0 + T_C, t0 + 2 * T_C], abs=1e-9)
    budget = {"start_J": pytest.approx(energy, rel=1e-12), "end_J": pytest.approx(energy - lost, rel=1e-9),
              "input_by_surface_J": 0.0, "lost_in_impacts_J": pytest.approx(lost, rel=1e-9),
              "lost_at_landings_J": 0.0, "lost_in_sliding_J": 0.0, "residual_J": pytest.approx(0.0, abs=1e-9 * lost),
              "relative_residual": pytest.approx(0.0, abs=1e-9), "tolerance": motion.ENERGY_TOLERANCE}
    assert res.summary() == {
        "duration_s": pytest.approx(duration, abs=1e-12),
        "mean_transport_velocity_m_s": [pytest.approx(vx, rel=1e-9), pytest.approx(vy, rel=1e-9)],
        "bounces": 2, "time_fraction": {"flight": pytest.approx(1.0, rel=1e-12), "sliding": 0.0},
        "energy_dissipated_by_impacts_J": pytest.approx(lost, rel=1e-9), "impacts_creating_energy": 0,
        "impacts_where_printed_law_is_inadmissible": 0, "impacts_where_printed_law_creates_energy": 0,
        "landings": 0, "rocking_contacts": 0, "energy_budget": budget, "engine": "compiled",
        "engine_reason": "",
        "implicit_slip_steps": 0, "warnings": []}
    assert res.start is start and math.isclose(res.final.t, t0 + duration)
