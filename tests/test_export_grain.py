"""`symmech export fmu|c` of the grain: flight and impacts as state events, checked with FMPy (a client no one
here wrote) against the native engine's impacts (the event loop of symmech.grain: closed-form translation,
DOP853 rotation, Brent's roots), and the derived impact map against the Python reference law
(symmech.grain.coulomb_law, written by hand from Chatterjee and Ruina).

Default tier: the impact map at random states, a short drop (3 impacts) as an FMI 3 Model Exchange FMU and on
into its first landing, the refusals. Slow tier: the C example program through every regime; the default scene up
to just before its first landing (8 impacts), FMI 2 and 3 Model Exchange; its first 50 impacts through four
landings, slips and sticks, FMI 2 and 3, Model Exchange and Co-Simulation."""
from __future__ import annotations

import csv
import io
import shutil
import subprocess

import numpy as np
import pytest

from symmech.cli import main
from symmech.core import pipeline
from symmech.core.scene import scenes_folder
from symmech.generated import grain_motion as gm
from symmech.grain import flight, motion, motion_scene
from symmech.grain.body import Ellipsoid
from symmech.grain.coulomb_law import ImpactLaw
from symmech.grain.vectors import T_AT

fmpy = pytest.importorskip("fmpy")
from fmpy.validation import validate_fmu  # noqa: E402

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="needs a C compiler")
DEFAULT = scenes_folder() / "grain_default.toml"
TIME_TOLERANCE = 1e-8  # s, impact times
POSITION_TOLERANCE = 1e-7  # m, centre at the impacts


def _scene(tmp_path, duration: float, *replacements: tuple[str, str]):
    """The default grain scene over ``duration`` [s] with its text edited by ``replacements``."""
    text = DEFAULT.read_text().replace("duration = 2.0 ", f"duration = {duration!r} ")
    for old, new in replacements:
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "grain.toml"
    path.write_text(text)
    return path


def _native(path) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Impact times (n,), centres at the impacts (n, 3) and the trajectory rows of the native engine's run."""
    m = motion_scene.simulate(pipeline.load(path).setup)
    return np.array([i["t"] for i in m.impacts]), np.array([i["r"] for i in m.impacts]), m.trajectory


def _fmu_impacts(fmu, stop: float, rtol: float | None = 1e-10) -> tuple[np.ndarray, np.ndarray]:
    """Impact times and centres of FMPy's CVode run of a Model Exchange FMU at the relative tolerance ``rtol`` (None:
    the FMU's DefaultExperiment tolerance, as FMPy takes it): the events where its count of impacts rises."""
    res = fmpy.simulate_fmu(str(fmu), solver="CVode", relative_tolerance=rtol, stop_time=stop,
                            output_interval=stop / 50, output=["x", "y", "z", "impacts"], record_events=True)
    at = np.flatnonzero((np.diff(res["time"]) == 0) & (np.diff(res["impacts"]) > 0))
    return res["time"][at], np.column_stack([res[c][at] for c in "xyz"])


def _check_impacts(fmu, path, stop: float, rtol: float | None = 1e-10, first: int | None = None) -> int:
    """The FMU's impacts (the ``first`` of them, all when None) against the native engine's: as many, their
    times within TIME_TOLERANCE, their centres within POSITION_TOLERANCE; their number."""
    t_native, r_native, _ = _native(path)
    t_fmu, r_fmu = _fmu_impacts(fmu, stop, rtol)
    assert len(t_fmu) == len(t_native) > 0
    n = first or len(t_native)
    assert np.abs(t_fmu[:n] - t_native[:n]).max() <= TIME_TOLERANCE
    assert np.abs(r_fmu[:n] - r_native[:n]).max() <= POSITION_TOLERANCE
    return len(t_native)


def _on_grid(times: np.ndarray, centres: np.ndarray, trajectory: np.ndarray) -> tuple[int, float]:
    """How many of ``times`` [s] are native trajectory rows, and the largest distance [m] of ``centres`` (n, 3)
    from the native centres there."""
    matched, error = 0, 0.0
    for t, centre in zip(times, centres):
        same = np.flatnonzero(np.abs(trajectory[:, 0] - t) <= 1e-12)
        if same.size:
            matched += 1
            error = max(error, float(np.abs(centre - trajectory[same[0], 1:4]).max()))
    return matched, error


def test_derived_impact_map_is_the_coulomb_law():
    """impact_contact -> plastic_impulse -> coulomb_impulse -> impact_state equals ImpactLaw.apply at 200 random grains and contact
    velocities (inside and outside the friction cone, approaching or not) to round-off."""
    rng = np.random.default_rng(7)
    worst, outside = 0.0, 0
    for _ in range(200):
        axes = np.array([3.5e-3, 1.6e-3, 1.4e-3]) * rng.uniform(0.5, 1.5, 3)
        mass = 1300 * 4 / 3 * np.pi * np.prod(axes)
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        Q = flight.rotation_matrix(q)
        v, w_body = rng.normal(size=3) * 0.2, rng.normal(size=3) * 30
        law = ImpactLaw("coulomb", e_n=rng.uniform(0, 1), e_t=rng.uniform(-1, 1), mu=rng.uniform(0, 1),
                        check_printed=False)
        want = law.apply(axes[None], np.array([mass]), Q[None], v[None], (Q @ w_body)[None], True)
        y = np.concatenate([[0.0, 0.0, 2e-3], v, q, w_body])
        inertia = Ellipsoid(*axes, mass).inertia
        contact = gm.impact_contact(*y, *inertia, *axes, mass)
        P = gm.coulomb_impulse(*gm.plastic_impulse(*contact), contact[11], law.e_n, law.e_t, law.mu)
        after = gm.impact_state(*y, *inertia, *axes, mass, *P)
        np.testing.assert_array_equal(after[[0, 1, 2, 6, 7, 8, 9]], y[[0, 1, 2, 6, 7, 8, 9]])
        P_t, P_n = np.hypot(P[0], P[1]), P[2]
        outside += bool(P_n > 0 and abs(P_t - law.mu * P_n) <= 1e-9 * P_n)
        worst = max(worst, np.abs(after[3:6] - want["v"][0]).max() / np.abs(want["v"][0]).max(),
                    np.abs(Q @ after[10:] - want["w"][0]).max() / np.abs(want["w"][0]).max())
    assert worst <= 1e-12
    assert outside >= 20  # the cone's branch is exercised


def test_grain_fmu_validates_and_reproduces_the_native_impacts(tmp_path):
    """A drop from 5 mm with three impacts (0.05 s), FMI 3 Model Exchange, CVode at rtol 1e-10."""
    path = _scene(tmp_path, 0.05)
    fmu = tmp_path / "grain.fmu"
    assert main(["export", "fmu", str(path), "--out", str(fmu)]) == 0
    assert validate_fmu(str(fmu)) == []
    md = fmpy.read_model_description(str(fmu))
    assert md.numberOfEventIndicators == 2
    assert float(md.defaultExperiment.tolerance) == 1e-12  # CVode's rtol that meets the targets (slow tests)
    by_name = {v.name: v for v in md.modelVariables}
    assert [by_name[n].unit for n in ("x", "vz", "q0", "w3", "omega", "m", "e_n", "mu_s", "v_stop")] == \
        ["m", "m/s", "1", "rad/s", "rad/s", "kg", "1", "1", "m/s"]
    assert by_name["e_n"].start == "0.4" and by_name["e_n"].causality == "parameter"
    assert by_name["regime"].variability == "discrete" and by_name["regime"].causality == "output"
    assert _check_impacts(fmu, path, 0.05) == 3
    # on past the first landing (0.0826 s, after 13 impacts): the grain slides (regime 1 or 2) until it lifts off
    # at 0.0858 s, never sinks
    res = fmpy.simulate_fmu(str(fmu), solver="CVode", relative_tolerance=1e-10, stop_time=0.085,
                            output=["z", "regime", "impacts"])
    assert res["impacts"][-1] == 13 and res["regime"][-1] in (1.0, 2.0) and res["z"].min() > 1e-3


@pytest.mark.slow  # the native run, a compile and a run (~8 s)
def test_grain_c_example_prints_the_native_trajectory(tmp_path):
    """The C program (DOP853 at rtol 1e-12, the indicators' falls located on its dense output) against the native
    trajectory's rows on the sample grid over 0.23 s: 53 impacts, four landings into slips and sticks, lift-offs
    (7.3e-10 m measured: the native run's own error at its tolerance 1e-9)."""
    path = _scene(tmp_path, 0.23)
    folder = tmp_path / "grain_c"
    assert main(["export", "c", str(path), "--out", str(folder)]) == 0
    printed = subprocess.run([str(folder / "example")], check=True, capture_output=True, text=True).stdout
    rows = list(csv.reader(io.StringIO(printed)))
    assert rows[0] == ["t", "x", "y", "z", "vx", "vy", "vz", "q0", "q1", "q2", "q3"]
    got = np.array(rows[1:], dtype=float)
    matched, error = _on_grid(got[:, 0], got[:, 1:4], _native(path)[2])
    assert matched == len(got) == 231 and error <= 2e-9


@pytest.mark.parametrize("replacements, options, says", [
    ([('law = "coulomb"', 'law = "printed"'), ("e_n = 0.4\ne_t = -0.3\nmu = 0.5\ncheck_printed = true",
                                                "e = 0.4\nlambda = 0.7")], [], "impact.law = 'printed'"),
    ([('mode = "accurate"', 'mode = "paper"')], [], "numerics.mode = 'paper'"),
    ([("rotation = true", "rotation = false")], [], "effects.rotation = false"),
    ([("mu = 0.5\n", "")], [], "impact.mu: unset"),
])
def test_refusals_are_one_line(replacements, options, says, tmp_path, capsys):
    """What the FMU does not cover (the printed law, paper mode, no rotation, no friction limit) is refused in one line naming the field and its
    value, exit 2, nothing written."""
    path = _scene(tmp_path, 0.09, *replacements)
    out = tmp_path / "out.fmu"
    assert main(["export", "fmu", str(path), "--out", str(out), *options]) == 2
    err = capsys.readouterr().err
    assert says in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


@pytest.mark.slow  # FMI 2 and 3, 8 impacts (~10 s)
@pytest.mark.parametrize("fmi", [2, 3])
def test_grain_fmu_up_to_the_first_landing(fmi, tmp_path):
    """The default scene until just before it first lands (0.082 s of 0.0826 s; 8 impacts, the later ones closing
    in on the landing, where an impact time's error grows about 2.5x a bounce): Model Exchange under CVode at
    rtol 1e-10 within 1e-8 s and 1e-7 m at every impact (8.3e-9 s, 1.0e-9 m measured)."""
    path = _scene(tmp_path, 0.082)
    fmu = tmp_path / f"grain_{fmi}.fmu"
    assert main(["export", "fmu", str(path), "--out", str(fmu), "--fmi", str(fmi)]) == 0
    assert validate_fmu(str(fmu)) == []
    assert _check_impacts(fmu, path, 0.082) == 8


@pytest.mark.slow  # FMI 2 and 3, the native run and 0.23 s of FMPy at rtol 1e-12 (~15 s)
@pytest.mark.parametrize("fmi", [2, 3])
def test_grain_fmu_through_its_sliding_regimes(fmi, tmp_path):
    """The default scene's first 50 impacts (53 to 0.23 s: five bounce sequences, each landing into a slip, a stick
    or both, lifting off and bouncing again), Model Exchange under CVode at the FMU's DefaultExperiment tolerance
    (rtol 1e-12, which FMPy takes when not given one): every impact of the native
    run (as many, the same landings), the first 50 within 1e-8 s and 1e-7 m (8.1e-9 s at impact 13, the first
    landing's last bounce, and 2.8e-9 m measured); at rtol 1e-10 CVode misses (1.4e-7 s at impact 13, in flight)."""
    path = _scene(tmp_path, 0.23)
    fmu = tmp_path / f"grain_{fmi}.fmu"
    assert main(["export", "fmu", str(path), "--out", str(fmu), "--fmi", str(fmi)]) == 0
    assert validate_fmu(str(fmu)) == []
    assert _check_impacts(fmu, path, 0.23, rtol=None, first=50) == 53


def _cs_rows(fmu, fmi: int, points: np.ndarray) -> dict:
    """FMPy's Co-Simulation instance of ``fmu`` at rtol 1e-10 stepped to each of ``points`` [s] in turn: at each,
    x, y, z, impacts, last_impact and regime."""
    from fmpy.fmi2 import FMU2Slave
    from fmpy.fmi3 import FMU3Slave

    md = fmpy.read_model_description(str(fmu))
    slave = (FMU3Slave if fmi == 3 else FMU2Slave)(guid=md.guid, unzipDirectory=fmpy.extract(str(fmu)),
                                                   modelIdentifier=md.coSimulation.modelIdentifier)
    slave.instantiate()
    if fmi == 3:
        slave.enterInitializationMode(tolerance=1e-10, startTime=0.0, stopTime=points[-1])
    else:
        slave.setupExperiment(tolerance=1e-10, startTime=0.0, stopTime=points[-1])
        slave.enterInitializationMode()
    slave.exitInitializationMode()
    vr = {v.name: v.valueReference for v in md.modelVariables}
    get = slave.getFloat64 if fmi == 3 else slave.getReal
    t, rows = 0.0, {}
    for point in points:
        slave.doStep(t, point - t)
        t = point
        rows[point] = np.array(get([vr[n] for n in ("x", "y", "z", "impacts", "last_impact", "regime")]))
    slave.terminate()
    slave.freeInstance()
    return rows


@pytest.mark.slow  # the native run, an export, 0.085 s of FMPy and of the driver at rtol 1e-10 (~5 s)
def test_grain_model_exchange_error_is_cvodes_own(tmp_path):
    """At rtol 1e-10 the ME FMU's first bounce sequence (impacts 1-13, before the first landing) is 1.4e-7 s off the
    native run at its last bounce, and it is CVode's error: the same CVode driver on the generated numpy flight (no
    FMU: tests/grain_cvode.py) gives the FMU's impact times within 1e-10 s (1.3e-13 s measured; the driver with the
    nominals x 10 is 2.6e-7 s off the FMU), while the FMU is more than 1e-8 s off the native run there
    (docs/export.md, benchmarks/grain_me_error.py)."""
    from grain_cvode import Flight

    stop = 0.085
    path = _scene(tmp_path, stop)
    fmu = tmp_path / "grain.fmu"
    assert main(["export", "fmu", str(path), "--out", str(fmu)]) == 0
    t_fmu, _ = _fmu_impacts(fmu, stop, 1e-10)
    sc = pipeline.load(path).setup
    y0 = np.concatenate([sc.start.r, sc.start.v, sc.start.q, sc.start.w])
    t_cvode = Flight(sc).impacts(0.0, y0, 13, 1e-10, stop / 50)
    t_native, _, _ = _native(path)
    assert np.abs(t_fmu[:13] - t_cvode).max() <= 1e-10
    assert abs(t_fmu[12] - t_native[12]) > TIME_TOLERANCE


@pytest.mark.slow  # FMI 2 and 3, the native run and 0.23 s in ~400 communication steps (~10 s)
@pytest.mark.parametrize("fmi", [2, 3])
def test_grain_cs_fmu_through_its_sliding_regimes(fmi, tmp_path):
    """The Co-Simulation FMU (DOP853 inside at rtol 1e-10, the indicators' falls located on its dense output) over
    the default scene's 0.23 s: communication points on the sample grid and 1e-8 s before and after each native
    impact. Each impact k of the native run falls between the two (the count k - 1 before, k after), the FMU's
    `last_impact` there within 1e-8 s of it for the first 50 (2.5e-9 s measured) and its centre at the native
    impact time within 1e-7 m (7.3e-10 m); on the grid the regime (flight, or on the plane) is the native one
    at every time and the centre within 2e-9 m (7.4e-10 m)."""
    path = _scene(tmp_path, 0.23)
    fmu = tmp_path / f"grain_{fmi}_cs.fmu"
    assert main(["export", "fmu", str(path), "--out", str(fmu), "--fmi", str(fmi), "--type", "cs"]) == 0
    assert validate_fmu(str(fmu)) == []
    t_native, r_native, trajectory = _native(path)
    grid = np.round(np.arange(1, 231) * 1e-3, 12)
    points = np.unique(np.concatenate([grid, t_native - TIME_TOLERANCE, t_native, t_native + TIME_TOLERANCE]))
    rows = _cs_rows(fmu, fmi, points)
    assert len(t_native) == 53 and rows[points[-1]][3] == 53
    for k, t_k in enumerate(t_native):
        before, at, after = rows[t_k - TIME_TOLERANCE], rows[t_k], rows[t_k + TIME_TOLERANCE]
        assert before[3] == k and after[3] == k + 1
        if k < 50:
            assert abs(after[4] - t_k) <= TIME_TOLERANCE
            assert np.abs(at[:3] - r_native[k]).max() <= POSITION_TOLERANCE
    native_rows = [np.flatnonzero(np.abs(trajectory[:, 0] - g) <= 1e-12)[-1] for g in grid]
    on_plane = trajectory[native_rows, T_AT.regime] == motion.REGIMES.index("sliding")
    assert np.array_equal(np.array([rows[g][5] > 0 for g in grid]), on_plane) and on_plane.sum() > 10
    assert max(np.abs(rows[g][:3] - trajectory[i, 1:4]).max() for g, i in zip(grid, native_rows)) <= 2e-9


@pytest.mark.slow  # 3 scenes, FMI 2 and 3, ME and CS, each with its native run (~1 min)
@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("kind", ["me", "cs"])
@pytest.mark.parametrize("name", sorted(p.stem for p in scenes_folder().glob("grain_*.toml")))
def test_every_bundled_grain_scene(name, kind, fmi, tmp_path):
    """Every bundled grain scene (the default one over 2 s, 493 impacts; the sweeps' grain, which starts on the
    surface, over 0.4 s) exports as an FMU that FMPy validates and that has every impact of the native run:
    Model Exchange under CVode at the FMU's DefaultExperiment tolerance (rtol 1e-12), the first 50 impact times
    within 1e-8 s and centres within 1e-7 m;
    Co-Simulation (rtol 1e-10), each native impact k between the FMU's count k - 1 at 1e-8 s before it and k after,
    every impact's `last_impact` within 1e-8 s."""
    path = scenes_folder() / f"{name}.toml"
    fmu = tmp_path / f"{name}_{kind}_{fmi}.fmu"
    assert main(["export", "fmu", str(path), "--out", str(fmu), "--fmi", str(fmi), "--type", kind]) == 0
    assert validate_fmu(str(fmu)) == []
    duration = pipeline.load(path).setup.duration
    if kind == "me":
        assert _check_impacts(fmu, path, duration, rtol=None, first=50) >= 100
        return
    t_native, _, _ = _native(path)
    rows = _cs_rows(fmu, fmi, np.unique(np.concatenate([t_native - TIME_TOLERANCE, t_native + TIME_TOLERANCE,
                                                       [duration]])))
    assert len(t_native) >= 100 and rows[duration][3] == len(t_native)
    for k, t_k in enumerate(t_native):
        before, after = rows[t_k - TIME_TOLERANCE], rows[t_k + TIME_TOLERANCE]
        assert before[3] == k and after[3] == k + 1 and abs(after[4] - t_k) <= TIME_TOLERANCE


# A model of one state s' = 1 whose event indicator dips to -DIP_DEPTH at s = DIP_PERIOD (k + 1/2) and rises back
# within 7.2e-7 s: its C source (the event update prints each event's time), written for the test
DIP_PERIOD, DIP_DEPTH = 0.0113, 1e-8
DIP_SOURCE = f"""#include <math.h>
#include <stddef.h>
#include <stdio.h>
void dip_rate(double t, const double *y, const double *p, double *out) {{ (void)t; (void)y; (void)p; out[0] = 1.0; }}
void dip_event_values(double t, const double *y, const double *p, double *out)
{{
    (void)t; (void)p;
    out[0] = 0.5 * (1.0 + cos(2.0 * 3.141592653589793 * y[0] / {DIP_PERIOD!r})) - {DIP_DEPTH!r};
}}
int dip_event_update(double t, double *y, double *p) {{ (void)y; (void)p; fprintf(stderr, "%.17g\\n", t); return 0; }}
const char *dip_notice(const double *p) {{ (void)p; return NULL; }}
"""


def test_event_search_finds_dips_between_its_samples(tmp_path):
    """The event search of c/symmech_model.c (the example program's calls of symmech_integrate, 0.01 s each, DOP853
    at rtol 1e-12) on an indicator with 88 dips below zero in 1 s, each 7.2e-7 s wide (a grazing contact), far
    narrower than a sample spacing (1/8 of a step of ~1e-3 s): the samples around each are positive, so only the
    search for a local minimum among the samples finds them (the search before it found 1 of the 88). Every dip's fall is found,
    once, within 1e-12 s of its closed form t = (P / 2 pi) (pi - acos(1 - 2 depth)) + k P: those inside a step,
    those straddling two steps and those in the last step of a call."""
    from symmech.export import build
    from symmech.export.model import ExportModel, Variable

    variables = (Variable("time", 0, "independent", "continuous", "s", "time"),
                 Variable("s", 1, "output", "continuous", "1", "the state", 0.0),
                 Variable("der(s)", 2, "output", "continuous", "1/s", "its rate", derivative_of=1),
                 Variable("z", 3, "output", "continuous", "1", "the indicator"))
    dip = ExportModel("dip", "dips between samples", DIP_SOURCE, variables, 1, 1, 0, 0, 0, 0, None, n_z=1,
                      mass_identity=1, event_tolerance=1.0)
    folder = build.c_folder(dip, tmp_path / "dip")
    run = subprocess.run([str(folder / "example")], check=True, capture_output=True, text=True)
    start, *found = np.array(run.stderr.split(), dtype=float)  # the start's update (symmech_start), then the events
    k = np.arange(int(1.0 / DIP_PERIOD - 0.5) + 1)
    want = DIP_PERIOD / (2 * np.pi) * (np.pi - np.arccos(1 - 2 * DIP_DEPTH)) + k * DIP_PERIOD
    assert len(want) == 88 and want[0] > 0.005
    assert start == 0.0 and len(found) == len(want) and np.abs(np.array(found) - want).max() <= 1e-12


def _simulate(fmu, stop: float, output: list[str], capsys) -> tuple[dict, str]:
    """FMPy's run of ``fmu`` to ``stop`` [s] (Model Exchange: CVode at the FMU's default tolerance; Co-Simulation:
    early return allowed, so that a run the FMU ends stops at its time), its ``output`` and its logged messages
    (FMPy's own logger prints them: a logger of the test's would stay registered in FMPy's FMI 2 proxy after the
    run and be called, freed, by later instances)."""
    capsys.readouterr()
    res = fmpy.simulate_fmu(str(fmu), stop_time=stop, output_interval=stop / 100, output=output,
                            early_return_allowed=True)
    return res, capsys.readouterr().out


@pytest.mark.slow  # a native run, 4 exports and FMPy runs (~10 s)
@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("kind", ["me", "cs"])
def test_max_impacts_ends_the_simulation_at_the_native_stop(kind, fmi, tmp_path, capsys):
    """numerics.max_impacts = 2 on the default drop (3 contacts in 0.05 s): the native engine stops at its third
    contact (t = 0.04376 s) without applying it, with a warning; the FMU ends the simulation there the FMI way
    (Model Exchange: terminateSimulation from the event update; Co-Simulation: fmi2Discard with fmi2Terminated,
    fmi3DoStep's terminateSimulation), within 1e-8 s of the native stop, after exactly 2 impacts, and logs why."""
    path = _scene(tmp_path, 0.05, ("tolerance = 1e-9", "tolerance = 1e-9\nmax_impacts = 2"))
    run = motion_scene.simulate(pipeline.load(path).setup)
    assert len(run.impacts) == 2 and any("max_impacts = 2" in w for w in run.warnings)
    fmu = tmp_path / f"grain_{kind}_{fmi}.fmu"
    assert main(["export", "fmu", str(path), "--out", str(fmu), "--fmi", str(fmi), "--type", kind]) == 0
    assert validate_fmu(str(fmu)) == []
    res, messages = _simulate(fmu, 0.05, ["impacts", "z"], capsys)
    assert res["impacts"][-1] == 2 and abs(res["time"][-1] - run.final.t) <= TIME_TOLERANCE
    assert run.final.t < 0.045 and messages.count("numerics.max_impacts") == 1


def _grazing_scene(tmp_path, depth: float = 1e-9):
    """A sphere (radius 1.5 mm) 0.1 mm above a surface vibrating along its normal (1 mm, 50 Hz, from its top: the
    surface accelerating down at A w^2 = 99 m/s^2 > g), falling towards it at the speed v0 whose relative path
    z(t) = z0 + v0 t - g t^2 / 2 - A (cos w t - 1) reaches at most ``depth`` [m] below the surface (a closed form
    minimised by scipy): the grain grazes the surface for 2 sqrt(2 depth / (A w^2 - g)) = 9.5e-6 s at 1.5 ms."""
    from scipy.optimize import brentq, minimize_scalar

    amplitude, omega, g, radius, gap0 = 1e-3, 2 * np.pi * 50.0, 9.81, 1.5e-3, 1e-4

    def lowest(v0):
        path = minimize_scalar(lambda t: gap0 + v0 * t - g * t * t / 2 - amplitude * (np.cos(omega * t) - 1),
                               bounds=(0.0, 4e-3), method="bounded", options={"xatol": 1e-14})
        return path.fun

    v0 = brentq(lambda v: lowest(v) + depth, -0.2, -0.1, xtol=1e-16)
    path = tmp_path / "graze.toml"
    path.write_text(f"""kind = "grain"
duration = 0.01
[body]
semi_axes = [{radius}, {radius}, {radius}]
density = 1300.0
[surface]
alpha_deg = 0.0
[vibration]
amplitude = {amplitude}
frequency = 50.0
phase_deg = 90.0
direction = "normal"
[impact]
law = "coulomb"
e_n = 0.4
e_t = -0.3
mu = 0.5
[sliding]
friction = 0.5
[initial]
position = [0.0, 0.0, {radius + gap0!r}]
velocity = [0.0, 0.0, {v0!r}]
[numerics]
mode = "accurate"
tolerance = 1e-9
""")
    return path


@pytest.mark.slow  # a native run, 3 exports, FMPy (~8 s)
def test_grazing_contact_is_found_by_co_simulation_and_the_c_program(tmp_path):
    """A grazing contact 1e-9 m deep and 9.5e-6 s long inside one DOP853 step (the search before this one missed
    it: no impact, the grain flying on through the surface's round-off): the native engine bounces there
    (t = 1.5463 ms, at 3.9e-4 m/s); the Co-Simulation FMU (FMI 2 and 3, one communication step over the 10 ms)
    has that one impact within 1e-8 s, and the C program's trajectory on the sample grid is the native one within
    1e-9 m (missing the bounce moves the centre by ~4e-6 m by the end)."""
    path = _grazing_scene(tmp_path)
    t_native, _, trajectory = _native(path)
    assert len(t_native) == 1
    for fmi in (2, 3):
        fmu = tmp_path / f"graze_{fmi}.fmu"
        assert main(["export", "fmu", str(path), "--out", str(fmu), "--fmi", str(fmi), "--type", "cs"]) == 0
        assert validate_fmu(str(fmu)) == []
        end = _cs_rows(fmu, fmi, np.array([0.01]))[0.01]
        assert end[3] == 1 and abs(end[4] - t_native[0]) <= TIME_TOLERANCE
    folder = tmp_path / "graze_c"
    assert main(["export", "c", str(path), "--out", str(folder)]) == 0
    printed = subprocess.run([str(folder / "example")], check=True, capture_output=True, text=True).stdout
    got = np.array(list(csv.reader(io.StringIO(printed)))[1:], dtype=float)
    matched, error = _on_grid(got[:, 0], got[:, 1:4], trajectory)
    assert matched == len(got) == 21 and error <= 1e-9


def _rocking_scene(tmp_path):
    """The separation sweep's crop grain of tests/test_grain_hard_cases.py at 1 mm, 32 Hz over 0.04 s: its bounces
    accumulate at 0.03561 s while the surface accelerates away (a rocking contact of the native engine)."""
    text = (scenes_folder() / "grain_separation.toml").read_text().split("[sweep.x]")[0]
    for old, new in (("semi_axes = [3.5e-3, 1.6e-3, 1.4e-3]", "semi_axes = [0.0035082751372901796, "
                      "0.0017441483828242994, 0.0013003646915614976]\norientation = [5.960540267916768, "
                      "1.9566358746946042, 2.659838524324996]\n#"),
                     ("frequency = 25.0", "frequency = 32.0\n#"), ("duration = 0.4", "duration = 0.04\n#")):
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "rocking.toml"
    path.write_text(text)
    return path


@pytest.mark.slow  # a native run, 3 exports, FMPy (~8 s)
def test_rocking_contact_as_the_native_engine(tmp_path, capsys):
    """The native engine's rocking contact (17 impacts, the last at 0.035611228 s after which the next hop would
    stay within the gap's round-off on a plane that pulls away: the grain put on the plane, its tilting spin
    dropped, flying on, one rocking contact warned): the Co-Simulation FMU (FMI 2 and 3) and the C program do the
    same at the contact that ends that hop (4e-9 s later), count it (output `rocking`) and log it; the FMU's 17
    impact times (its `last_impact` halfway to the next native impact) are within 1e-8 s of the native ones, and
    the C program's trajectory on the sample grid after it
    within 1e-9 m of the native one (2.0e-10 m measured)."""
    path = _rocking_scene(tmp_path)
    run = motion_scene.simulate(pipeline.load(path).setup)
    t_native = np.array([i["t"] for i in run.impacts])
    assert run.extra["rocking_contacts"] == 1 and len(t_native) == 17
    for fmi in (2, 3):
        fmu = tmp_path / f"rocking_{fmi}.fmu"
        assert main(["export", "fmu", str(path), "--out", str(fmu), "--fmi", str(fmi), "--type", "cs"]) == 0
        assert validate_fmu(str(fmu)) == []
        after = np.append((t_native[:-1] + t_native[1:]) / 2, 0.04)  # the last impacts are 1e-8 s apart
        rows = _cs_rows(fmu, fmi, after)
        for k, t_k in enumerate(t_native):
            assert rows[after[k]][3] == k + 1 and abs(rows[after[k]][4] - t_k) <= TIME_TOLERANCE
        res, messages = _simulate(fmu, 0.04, ["impacts", "rocking"], capsys)
        assert res["impacts"][-1] == 17 and res["rocking"][-1] == 1 and res["time"][-1] == pytest.approx(0.04)
        assert messages.count("rocking contact") == 1
    folder = tmp_path / "rocking_c"
    assert main(["export", "c", str(path), "--out", str(folder)]) == 0
    ran = subprocess.run([str(folder / "example")], check=True, capture_output=True, text=True)
    assert ran.stderr.count("rocking contact") == 1
    got = np.array(list(csv.reader(io.StringIO(ran.stdout)))[1:], dtype=float)
    matched, error = _on_grid(got[:, 0], got[:, 1:4], run.trajectory)
    assert matched == len(got) == 52 and error <= 1e-9
