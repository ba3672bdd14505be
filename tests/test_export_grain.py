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
