"""The elastic model's modal analysis never sinks a run.

A cantilever rooted at the centre of a level circle, along x1, turns with the frame about
the vertical through its root at Ω = V0/R: the loads on it are axial only (centrifugal
tension), so its quasi-static state is q = 0, reached only to rounding. Its modes are those
of a rotating Euler–Bernoulli cantilever with zero hub radius (Southwell): flapwise (along
the rotation axis) EI w'''' - (T w')' = ρA ω² w, in the plane of rotation with an extra
-ρA Ω² w, T(x) = ρA Ω² (L² - x²)/2; the reference solves them independently by a Ritz
method on the polynomials x², …, x¹¹ (converged to < 1e-9 in the first frequencies).
"""
import json

import numpy as np
import pytest
import scipy.linalg

from symmech.core import pipeline
from symmech.core.context import Context
from symmech.core.scene import SymmechError
from symmech.trolley.elastic import system as el, frame as el_frame, simulate as el_sim
from trolley_util import setup

R, V, L, RHO_A, EI = 2.0, 1.0, 1.0, 2.0, (0.5, 1.0)  # m, m/s, m, kg/m, N m² (flapwise, in-plane)
CIRCLE = {"type": "expression", "x": f"{R}*sin(s/{R})", "y": "0", "z": f"{R} - {R}*cos(s/{R})"}


def _scene(**numerics):
    """The issue's scene: level circle R = 2 m at 1 m/s, no gravity, rigid rollers, one beam
    rooted at the centre of the circle (x3 = R in the trolley frame) along x1."""
    data = setup(track=CIRCLE, trolley={"mass": 100.0, "com": [0.0, 0.0, 0.0], "inertia": [10.0, 20.0, 15.0, 0, 0, 0]},
                 motion={"speed": repr(V)}, time={"t_end": 1.0, "steps": 10}, effects={"gravity": False})
    data["elastic"] = {"effects": {"rollers": False},
                       "beams": [{"root": [0.0, 0.0, R], "axis": [1.0, 0.0, 0.0], "plane": [0.0, 1.0, 0.0],
                                  "length": L, "mass_per_length": RHO_A, "ei": list(EI)}],
                       "numerics": {"modal_samples": 2, **numerics}}
    return data


def rotating_cantilever(ei, omega, in_plane, n=10):
    """Natural frequencies [Hz] of a uniform cantilever (length L, ρA) turning at ``omega``
    [rad/s] about an axis through its root ⟂ to it: Ritz on x^2 … x^(n+1)."""
    x, w = np.polynomial.legendre.leggauss(40)
    x, w = 0.5 * L * (x + 1), 0.5 * L * w
    p = np.arange(2, n + 2)
    phi, d1, d2 = x[:, None] ** p, p * x[:, None] ** (p - 1), p * (p - 1) * x[:, None] ** (p - 2)
    tension = RHO_A * omega**2 * (L**2 - x**2) / 2
    mass = RHO_A * (phi * w[:, None]).T @ phi
    stiff = ei * (d2 * w[:, None]).T @ d2 + (d1 * (tension * w)[:, None]).T @ d1
    if in_plane:
        stiff = stiff - omega**2 * mass
    return np.sqrt(scipy.linalg.eigh(stiff, mass, eigvals_only=True)) / (2 * np.pi)


def test_beam_at_the_centre_of_a_circle_runs_and_its_modes_are_the_rotating_cantilevers(tmp_path):
    """Refused before ("no quasi-static state … residual 1.99e-145": Newton's test was relative
    to q ≈ 1e-20 only). Now the run writes its tables; the first flapwise and in-plane
    frequencies equal the rotating cantilever's to 1e-5 (measured 2.4e-6, 2.0e-6: the model's
    four Ritz functions per plane); without the rotation they would be 4.7 % and 0.39 % lower."""
    _, res = pipeline.run_to(_scene(), tmp_path / "out", Context(quiet=True), plots=False)
    # the modal analysis warns of nothing; 10 output steps are too few to show the modes, as the run says
    assert all(w.startswith("elastic: the outputs are sampled at") for w in res.warnings), res.warnings
    modes = res.tables["modes"]
    first = modes.column("mode_id") == 1
    np.testing.assert_allclose(modes.column("s")[first], [0.0, V * 1.0], atol=1e-12)
    flap, lag = rotating_cantilever(EI[0], V / R, False)[0], rotating_cantilever(EI[1], V / R, True)[0]
    for row in range(2):
        got = modes.column("f")[8 * row:8 * row + 2]  # mode_id 1, 2 of the sample (8 modes each)
        np.testing.assert_allclose(got, [flap, lag], rtol=1e-5)
        assert abs(got[0] / rotating_cantilever(EI[0], 0.0, False)[0] - 1) > 0.04
        assert abs(got[1] / rotating_cantilever(EI[1], 0.0, True)[0] - 1) > 0.003
    np.testing.assert_allclose(modes.column("zeta"), 0.0, atol=1e-12)  # no damping
    assert (tmp_path / "out" / "modes.csv").exists() and (tmp_path / "out" / "elastic_reactions.csv").exists()


def test_quasi_static_state_zero_converges_from_rounding_noise():
    """Newton from q ≈ 1e-20 (the integrated state) to the exact q = 0: accepted at once with
    the absolute floor, where a purely relative test could never pass."""
    from trolley_util import prepared

    st = prepared(_scene())
    system = st.elastic.system
    fs = el_frame.frame_state(st.elastic.drive.frames(np.array([0.5])), 0, V, 0.0)
    q = system.quasi_static(fs, np.full(system.N, 1e-20))
    assert np.abs(q).max() <= el.Q_FLOOR
    # a loaded state still converges to its own (relative) tolerance: gravity bends the soft beam
    loaded = prepared({**_scene(), "effects": {"gravity": True, "local_curvature": False}})
    fs = el_frame.frame_state(loaded.elastic.drive.frames(np.array([0.5])), 0, V, 0.0)
    q = loaded.elastic.system.quasi_static(fs)
    R_ = loaded.elastic.system.evaluate(fs, q, np.zeros_like(q), np.zeros_like(q))
    assert np.abs(q).max() > 1e-3 and np.abs(R_).max() < 1e-9


def test_a_failed_modal_analysis_keeps_the_integration_and_warns(tmp_path, monkeypatch):
    """The modal analysis forced to fail: the integration's tables are still written, the
    modes table and Campbell plot are left out, and a warning names the analysis and why."""
    def broken(self, fs, q, shapes=False):
        raise SymmechError("forced failure for the test")

    monkeypatch.setattr(el.System, "linear_modes", broken)
    _, res = pipeline.run_to(_scene(), tmp_path / "out", Context(quiet=True), plots=True)
    out = tmp_path / "out"
    assert "modes" not in res.tables and not (out / "modes.csv").exists()
    assert (out / "elastic_reactions.csv").exists() and (out / "energy.csv").exists()
    assert not (out / "campbell.png").exists() and (out / "elastic_reactions.png").exists()
    warning, = [w for w in res.warnings if "modal analysis" in w]
    assert "forced failure for the test" in warning
    summary = json.loads((out / "summary.json").read_text())
    assert warning in summary["warnings"]


@pytest.mark.parametrize("broken", [np.linalg.LinAlgError("Singular matrix"), FloatingPointError("overflow")])
def test_numerical_failures_of_the_modal_analysis_are_warnings_too(tmp_path, monkeypatch, broken):
    def fail(self, fs, q, shapes=False):
        raise broken

    monkeypatch.setattr(el.System, "linear_modes", fail)
    _, res = pipeline.run_to(_scene(), tmp_path / "out", Context(quiet=True), plots=False)
    assert any("modal analysis" in w and str(broken) in w for w in res.warnings)
    assert (tmp_path / "out" / "elastic_reactions.csv").exists()


def test_roller_frequencies_closed_form_at_q0_and_the_sagged_states_difference():
    """docs/trolley-elastic.md: the closed-form roller frequencies (2-DOF bounce/pitch, 3-DOF
    lateral/roll/yaw, -m g0 c2 on roll and pitch) are those of the linearisation at q = 0, with
    gravity too (1e-12); the `modes` table linearises about the sagged quasi-static state, whose
    frequencies differ by first order in the sag: 4.0e-4 at k ~ 1e5 N/m, 10x less at 10x k
    (the 100 kg trolley of tests/test_trolley_elastic.py, centre of mass 0.5 m high)."""
    from test_trolley_elastic import closed_form_roller_frequencies, roller_model, straight

    g0, com, inertia = 9.81, (0.8, 0.5, 0.0), (10.0, 20.0, 15.0)
    differences = []
    for scale in (1e5, 1e6):
        k = tuple(scale * np.array([1.0, 1.0, 2.0, 1.5, 1.0]))
        system = el.System(roller_model(g0, k, com=com, inertia=inertia + (0, 0, 0)))
        fs = el_sim._state_at(straight(), 0.0, 0.0)
        vertical, lateral = closed_form_roller_frequencies(100.0, com, inertia, k, 2.0, 1.0, g0)
        closed = np.sort(np.r_[vertical, lateral])
        np.testing.assert_allclose(system.linear_modes(fs, np.zeros(system.N))[0], closed, rtol=1e-12)
        sagged = system.linear_modes(fs, system.quasi_static(fs))[0]
        differences.append(np.abs(sagged / closed - 1).max())
    assert 3e-4 < differences[0] < 5e-4
    assert differences[0] / differences[1] == pytest.approx(10.0, rel=0.01)
