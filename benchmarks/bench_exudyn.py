"""A clamped beam on a body rotating at constant rate: symmech's elastic trolley against Exudyn.

    python benchmarks/bench_exudyn.py [--repeats 7]
    pip install symmech[bench]          # the optional peer Exudyn (pip wheel)

The beam: a cantilever L = 1 m, rho A = 1 kg/m, EI = 1 N m^2 (first frequency w0 = 3.516 rad/s), clamped
radially at the centre of a body spinning at Omega = 0.5 w0 about an axis normal to the beam. Its flapwise
(out-of-plane) bending obeys EI w'''' - (T w')' + rho A w'' = 0 with the centrifugal tension
T(x) = rho A Omega^2 (L^2 - x^2) / 2 (no Coriolis term out of the plane), so:

- symmech: the elastic trolley model with this beam (8 Ritz functions per plane, the psi fields of the
  centrifugal stiffening on, no rollers) on a level circle of radius R = 10 m at the speed Omega R, the
  root at the circle's centre: ``System.linear_modes`` at that frame state (chordwise and flapwise);
- Exudyn: ANCF Cable2D elements (EA = 1e6 N: inextensible to 1e-6), clamped, the centrifugal load as
  consistent nodal forces, a static solve and the eigenvalues of the pre-stressed beam
  (``ComputeODE2Eigenvalues``): the flapwise frequencies (a planar model of the out-of-plane bending);
- the closed form: Southwell's coefficient K = 1.1933 (Rayleigh, exact cantilever mode) as Omega -> 0:
  w^2 = w0^2 + K Omega^2 flapwise, w0^2 + (K - 1) Omega^2 chordwise.

Printed: w / w0 and (w^2 - w0^2) / Omega^2 of each, the time each takes for that answer (interleaved
medians, timing.py), symmech's set-up (the model, the drive) apart.

``--part transient``: the chordwise (in-plane) free vibration, where the rotating frame acts (centrifugal
stiffening, the -Omega^2 softening, Coriolis): both start from the non-rotating first cantilever mode at
1 mm tip deflection, turning rigidly at Omega, over 10 periods of symmech's linear chordwise frequency.
symmech: the compiled elastic engine (Radau, analytic Jacobian) at several rtol; Exudyn: ANCF Cable2D
elements in the plane of rotation, the root node's slope prescribed as (cos Omega t, sin Omega t)
(a clamp turning at Omega; Exudyn's eigenvalues do not apply to this time-varying model), generalized-
alpha. Printed: each history's largest difference from symmech at rtol 1e-11 (relative to the
amplitude), its frequency from zero crossings, and the time for it (interleaved medians).
"""
from __future__ import annotations

import argparse
import os
import time

import numpy as np
from scipy.interpolate import CubicSpline
from timing import interleaved, machine, ratio

from symmech.core import pipeline
from symmech.trolley.elastic import system as el, body as el_body, simulate as el_sim
from symmech.trolley.elastic import scene as elastic_scene

L, RHO_A, EI, EA = 1.0, 1.0, 1.0, 1e6
W0 = float(1.8751040687119611 ** 2 * np.sqrt(EI / (RHO_A * L ** 4)))
OMEGA, RADIUS, SOUTHWELL = 0.5 * W0, 10.0, 1.1933


def symmech_model():
    """The elastic system (the beam on a trolley with rigid rollers), its drive and its frame state on the circle."""
    beam = el_body.Beam((0, RADIUS, 0), (0, -1, 0), (0, 0, 1), L, RHO_A, (EI, EI), "cantilever", 8)
    mdl = el_body.ElasticModel(100.0, (0, 0, 0), (1, 1, 1, 0, 0, 0), 2.0, 1.0, 0.0, None, (beam,),
                          el_body.Effects(rollers=False, stiffening=True))
    r = f"{RADIUS!r}"
    scene = {"kind": "trolley", "frame": "frenet",
             "track": {"type": "expression", "x": f"{r}*sin(s/{r})", "y": "0", "z": f"{r}*cos(s/{r})"},
             "trolley": {"mass": 100.0, "com": [0.0, 0.0, 0.0], "axle_distance": 2.0, "half_gauge": 1.0},
             "motion": {"speed": repr(float(OMEGA * RADIUS))}, "time": {"t_end": 1.0, "steps": 10},
             "effects": {"gravity": True, "local_curvature": False}}
    system = el.System(mdl)
    drive = elastic_scene.drive_of(pipeline.load(scene).setup, 1)
    return system, drive, el_sim._state_at(drive, 0.0, 0.0)


def symmech_frequencies(system, fs):
    """Chordwise and flapwise first frequencies [rad/s] (chordwise lies below once spinning)."""
    w = np.sort(system.linear_modes(fs, np.zeros(system.N))[0])
    return w[0], w[1]


def exudyn_flapwise(elements: int) -> float:
    """First flapwise frequency [rad/s]: the pre-stressed ANCF cantilever's lowest eigenvalue."""
    import exudyn as exu
    from exudyn.itemInterface import (CoordinateConstraint, Force, MarkerNodeCoordinate, MarkerNodePosition,
                                      NodePoint2DSlope1, NodePointGround, ObjectANCFCable2D)

    mbs = exu.SystemContainer().AddSystem()
    ground = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=mbs.AddNode(NodePointGround()), coordinate=0))
    le = L / elements
    nodes = [mbs.AddNode(NodePoint2DSlope1(referenceCoordinates=[i * le, 0, 1, 0])) for i in range(elements + 1)]
    for i in range(elements):
        mbs.AddObject(ObjectANCFCable2D(nodeNumbers=[nodes[i], nodes[i + 1]], length=le, massPerLength=RHO_A,
                                        bendingStiffness=EI, axialStiffness=EA))
    for k in (0, 1, 3):  # clamped: position and the slope's lateral component
        mbs.AddObject(CoordinateConstraint(markerNumbers=[ground, mbs.AddMarker(
            MarkerNodeCoordinate(nodeNumber=nodes[0], coordinate=k))]))
    for i in range(1, elements + 1):  # rho A Omega^2 x on the hat function of node i (the linear interpolant)
        share = i * le * le if i < elements else (i * le) * le / 2 - le * le / 6
        marker = mbs.AddMarker(MarkerNodePosition(nodeNumber=nodes[i]))
        mbs.AddLoad(Force(markerNumber=marker, loadVector=[RHO_A * OMEGA ** 2 * share, 0, 0]))
    mbs.Assemble()
    settings = exu.SimulationSettings()
    settings.staticSolver.verboseMode = 0
    settings.solution.file.write = False  # Exudyn writes solution/ into the working folder otherwise
    settings.staticSolver.newton.relativeTolerance = 1e-10
    settings.staticSolver.newton.absoluteTolerance = 1e-6
    settings.linearSolver.solverType = exu.LinearSolverType.EigenDense
    mbs.SolveStatic(settings, updateInitialValues=True)
    values, _ = mbs.ComputeODE2Eigenvalues(computeComplexEigenvalues=False, useAbsoluteValues=True)
    return float(np.sqrt(np.sort(np.abs(values))[0]))


# ------------------------------------------------------------------ the chordwise transient

AMPLITUDE = 1e-3  # m, initial chordwise tip deflection: linear (the geometric terms are ~1e-6 of it)
PERIODS = 10
OUTPUTS = 1000  # output intervals over the span; Exudyn's steps are a multiple of it
BETA = 1.8751040687119611  # first root of cosh b cos b = -1


def cantilever_mode(x):
    """The first mode of the non-rotating cantilever and its slope at x [m] (n,), tip deflection 1."""
    sigma = (np.sinh(BETA) - np.sin(BETA)) / (np.cosh(BETA) + np.cos(BETA))
    shape = lambda b: np.cosh(b) - np.cos(b) - sigma * (np.sinh(b) - np.sin(b))  # noqa: E731
    b = BETA * np.asarray(x) / L
    slope = BETA / L * (np.sinh(b) + np.sin(b) - sigma * (np.cosh(b) - np.cos(b)))
    return shape(b) / shape(BETA), slope / shape(BETA)


def chordwise_grid(system, fs) -> np.ndarray:
    """Output times [s] (OUTPUTS + 1,) over PERIODS periods of symmech's linear chordwise frequency."""
    return np.linspace(0.0, PERIODS * 2 * np.pi / symmech_frequencies(system, fs)[0], OUTPUTS + 1)


def symmech_transient(system, drive, t, rtol: float, atol_q: float = 1e-12) -> np.ndarray:
    """Chordwise tip deflection [m] at t (n,): the compiled engine from the non-rotating first
    chordwise mode (Ritz, plane 2 = axis x plane: the track's tangent) at AMPLITUDE, relative rates 0."""
    from symmech.trolley.elastic import compiled as elastic_compiled

    idx = [system.inv.names.index(f"beam0_p2_m{k + 1}") for k in range(system.mdl.beams[0].modes)]
    out = elastic_compiled.simulate(system, drive, t, rtol, atol_q, dq0=AMPLITUDE * el.beam_mode(system, 0, 2, 1))
    assert out["engine"] == "compiled", out["engine_reason"]
    return out["q"][:, idx] @ el_body.beam_basis("cantilever", np.ones(1))[0][0, 0, :len(idx)]


def exudyn_transient(elements: int, steps: int, t) -> np.ndarray:
    """Chordwise tip deflection [m] at t (n,): ANCF Cable2D elements in the plane of rotation, the root
    node at the centre, its slope prescribed (cos Omega t, sin Omega t) (a clamp turning at Omega);
    from the exact cantilever mode at AMPLITUDE turning rigidly at Omega; generalized-alpha, ``steps``
    steps; the tip's position turned into the rotating frame."""
    import exudyn as exu
    from exudyn.itemInterface import (CoordinateConstraint, MarkerNodeCoordinate, NodePoint2DSlope1,
                                      NodePointGround, ObjectANCFCable2D, SensorNode)

    mbs = exu.SystemContainer().AddSystem()
    ground = mbs.AddMarker(MarkerNodeCoordinate(nodeNumber=mbs.AddNode(NodePointGround()), coordinate=0))
    x = np.linspace(0.0, L, elements + 1)
    w, dw = (AMPLITUDE * f for f in cantilever_mode(x))
    nodes = [mbs.AddNode(NodePoint2DSlope1(referenceCoordinates=[x[i], 0, 1, 0],
                                           initialCoordinates=[0, w[i], 0, dw[i]],
                                           initialVelocities=[-OMEGA * w[i], OMEGA * x[i], -OMEGA * dw[i], OMEGA]))
             for i in range(elements + 1)]
    for i in range(elements):
        mbs.AddObject(ObjectANCFCable2D(nodeNumbers=[nodes[i], nodes[i + 1]], length=L / elements,
                                        massPerLength=RHO_A, bendingStiffness=EI, axialStiffness=EA))
    clamp = {0: None, 1: None, 2: lambda mbs, time, item, offset: np.cos(OMEGA * time) - 1,
             3: lambda mbs, time, item, offset: np.sin(OMEGA * time)}
    for k, offset in clamp.items():
        mbs.AddObject(CoordinateConstraint(markerNumbers=[ground, mbs.AddMarker(MarkerNodeCoordinate(
            nodeNumber=nodes[0], coordinate=k))], **({} if offset is None else {"offsetUserFunction": offset})))
    sensor = mbs.AddSensor(SensorNode(nodeNumber=nodes[-1], outputVariableType=exu.OutputVariableType.Position,
                                      storeInternal=True, writeToFile=False))
    mbs.Assemble()
    settings = exu.SimulationSettings()
    settings.solution.file.write = False
    settings.solution.sensors.writePeriod = 0.5 * t[-1] / steps
    settings.timeIntegration.numberOfSteps = steps
    settings.timeIntegration.endTime = t[-1]
    settings.timeIntegration.verboseMode = 0
    settings.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    mbs.SolveDynamic(settings)
    data = mbs.GetSensorStoredData(sensor)  # every step; Exudyn shortens steps where Newton fails
    x, y = CubicSpline(data[:, 0], data[:, 1:3])(t).T  # 4th order: ~1e-9 of the amplitude at >= 4000 steps
    return -np.sin(OMEGA * t) * x + np.cos(OMEGA * t) * y


def crossing_frequency(t, w) -> float:
    """Frequency [rad/s] from the first and last zero crossings of w (n,) (linear interpolation)."""
    k = np.flatnonzero(np.sign(w[1:]) != np.sign(w[:-1]))
    tc = t[k] - w[k] * (t[k + 1] - t[k]) / (w[k + 1] - w[k])
    return np.pi * (len(tc) - 1) / (tc[-1] - tc[0])


def transient(repeats: int) -> None:
    """The chordwise transient: histories against symmech's tightest, frequencies, time for the answer."""
    system, drive, fs = symmech_model()
    t = chordwise_grid(system, fs)
    linear = symmech_frequencies(system, fs)[0]
    reference = symmech_transient(system, drive, t, 1e-11)
    print(f"chordwise, {PERIODS} periods ({t[-1]:.3f} s) from the first cantilever mode at {AMPLITUDE * 1e3:g} mm; "
          f"symmech linear_modes w/w0 {linear / W0:.6f}; reference: symmech compiled at rtol 1e-11, "
          f"zero crossings w/w0 {crossing_frequency(t, reference) / W0:.6f}")
    contenders = {}
    for rtol, atol in SYMMECH_TOLERANCES:
        contenders[f"symmech compiled, rtol {rtol:g}, atol {atol:g} m"] = \
            lambda r=rtol, a=atol: symmech_transient(system, drive, t, r, a)
    try:
        import exudyn
    except ImportError:
        print("Exudyn not installed (pip install symmech[bench]): its rows are skipped")
    else:
        for elements, steps in EXUDYN_RUNS:
            contenders[f"Exudyn {exudyn.__version__} {elements} el., {steps} steps"] = \
                lambda e=elements, s=steps: exudyn_transient(e, s, t)
    for name, run in contenders.items():
        w = run()
        print(f"  {name:36s} max |w - reference| / amplitude {np.abs(w - reference).max() / AMPLITUDE:.2e}, "
              f"zero crossings w/w0 {crossing_frequency(t, w) / W0:.6f}")
    stats = interleaved(contenders, repeats)
    first = next(iter(stats.values()))
    print(f"time for the answer (load average {os.getloadavg()[0]:.1f} at the end):")
    for name, s in stats.items():
        print(f"  {name:36s} {s.text('s')}  {ratio(s, first)} the first")


# the default atol_q (1e-12 m) resolves the stiff high Ritz functions: 37708 steps at rtol 1e-4, 1811 at 1e-8 m
SYMMECH_TOLERANCES = ((1e-4, 1e-12), (1e-4, 1e-8))
EXUDYN_RUNS = ((16, 4000), (16, 16000), (32, 16000))  # 64 elements, 8000 steps: no answer within 15 min


def coefficient(w: float) -> float:
    return (w * w - W0 * W0) / OMEGA ** 2


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--part", choices=("frequency", "transient"), default="frequency")
    args = parser.parse_args()
    if args.part == "transient":
        print(f"{machine()}; load average {os.getloadavg()[0]:.1f} at the start")
        return transient(args.repeats)
    repeats = args.repeats
    print(f"{machine()}; load average {os.getloadavg()[0]:.1f} at the start")
    start = time.perf_counter()
    system, _, fs = symmech_model()
    print(f"symmech set-up (model, drive, frame state): {time.perf_counter() - start:.2f} s")
    chord, flap = symmech_frequencies(system, fs)
    print(f"Omega = {OMEGA / W0:g} w0, w0 = {W0:.6f} rad/s; Southwell (Omega -> 0): K = {SOUTHWELL} flapwise, "
          f"K - 1 = {SOUTHWELL - 1:.4f} chordwise")
    print(f"  symmech  flapwise w/w0 {flap / W0:.6f}, coefficient {coefficient(flap):.5f}; chordwise w/w0 "
          f"{chord / W0:.6f}, coefficient {coefficient(chord):.5f}")
    contenders = {"symmech linear_modes": lambda: symmech_frequencies(system, fs)}
    try:
        import exudyn
    except ImportError:
        print("Exudyn not installed (pip install symmech[bench]): its rows are skipped")
    else:
        w = {}
        for elements in (8, 16, 32, 64):
            w[elements] = exudyn_flapwise(elements)
            print(f"  Exudyn {exudyn.__version__} ANCF, {elements:2d} elements: flapwise w/w0 {w[elements] / W0:.7f}, "
                  f"coefficient {coefficient(w[elements]):.5f}, relative to symmech {w[elements] / flap - 1:+.1e}")
        limit = (4 * w[64] - w[32]) / 3  # the element's error falls like h^2
        print(f"  Exudyn, Richardson from 32 and 64 elements: w/w0 {limit / W0:.7f}, symmech relative to it "
              f"{flap / limit - 1:+.1e}")
        for elements in (16, 32, 64):
            contenders[f"Exudyn {elements} elements, static + eigenvalues"] = lambda e=elements: exudyn_flapwise(e)
    stats = interleaved(contenders, repeats)
    print(f"time for the answer (load average {os.getloadavg()[0]:.1f} at the end):")
    for name, s in stats.items():
        versus = f"  {ratio(s, stats['symmech linear_modes'])} symmech's time" if len(stats) > 1 else ""
        print(f"  {name:42s} {s.text('ms', 1e3)}{versus}")


if __name__ == "__main__":
    main()
