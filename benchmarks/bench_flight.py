"""A whole 2 s grain flight at rtol 1e-10: symmech's compiled integration against JiTCODE and solve_ivp.

    python benchmarks/bench_flight.py [--repeats 7]
    pip install symmech[bench]          # the optional peer JiTCODE (symbolic -> C, needs a C compiler)

The generated grain flight (grain_motion, 13 states) from one seeded tumbling state, thrown up so that it
stays clear of the plane for the whole 2 s, all contenders from the same sympy derivation
(derive_motion.flight_dynamics), DOP853 at rtol 1e-10, atol 1e-12, the state at 201 times (every 10 ms)
and at the end only:

- symmech: ``ode.integrate("grain_motion", ...)`` (the toolkit's DOP853, compiled, dense output);
- JiTCODE: its C f(t, y) under scipy's Fortran ``ode('dop853')`` (Hairer's dop853.f), stepping to each
  output time as that wrapper does (no dense output), and through JiTCODE's own ``integrate`` (the same
  Fortran solver);
- ``solve_ivp(method="DOP853")`` on the numba module's ``rhs`` (Python steps).

Error: the largest |y - reference| over the output times, per state relative to that state's largest
|reference|, the worst state; the reference is ``solve_ivp`` DOP853 at rtol 1e-13 on the numpy module.
Set-up (not in the timings): numba compiling the toolkit for the module in this process (not cached
across processes: numerics/ode.py), JiTCODE's code generation and gcc. Interleaved medians (timing.py).
"""
from __future__ import annotations

import argparse
import os
import time

import numpy as np
from scipy.integrate import ode as scipy_ode
from scipy.integrate import solve_ivp
from timing import interleaved, machine, ratio

from symmech.numerics import kernels, ode
from symmech.generated import grain_motion as gm

RTOL, ATOL, SPAN = 1e-10, 1e-12, 2.0


def flight() -> tuple[np.ndarray, np.ndarray]:
    """Parameters (gm.PARAMS) and a state (gm.STATE): a 2 mm x 1.4 mm x 1 mm grain tumbling at ~80 rad/s,
    thrown up at 10 m/s from 5 cm over a plane vibrating at 25 Hz, 0.5 mm (it stays above the plane)."""
    a, b, c, mass = 2e-3, 1.4e-3, 1e-3, 1e-5
    inertia = [mass * (b * b + c * c) / 5, mass * (a * a + c * c) / 5, mass * (a * a + b * b) / 5]
    values = {"gX": 0.0, "gY": -1.2, "gZ": -9.73, "A": 0.5e-3, "omega": 2 * np.pi * 25, "phase": 0.3,
              "dX": 0.0, "dY": 0.6, "dZ": 0.8, "I1": inertia[0], "I2": inertia[1], "I3": inertia[2],
              "a": a, "b": b, "c": c}
    p = np.array([values[name] for name, _, _ in gm.PARAMS])
    q = np.array([0.9, 0.1, -0.3, 0.2])
    y0 = np.concatenate([[0.0, 0.0, 0.05], [0.4, 0.1, 10.0], q / np.linalg.norm(q), [40.0, -25.0, 60.0]])
    return p, y0


def jitcode_f(p):
    """JiTCODE's compiled f(t, y) of the flight with parameters p, the JiTCODE object and its set-up time
    [s]; None when JiTCODE is not installed."""
    try:
        import jitcode
        import symengine
    except ImportError:
        return None
    from symmech.grain.derive_motion import flight_dynamics

    start = time.perf_counter()
    dynamics = flight_dynamics()
    to_y = {a.symbol: jitcode.y(i) for i, a in enumerate(dynamics.state)}
    to_y[dynamics.time.symbol] = jitcode.t
    rate = [symengine.sympify(e).subs(to_y) for e in dynamics.rate]
    peer = jitcode.jitcode(rate, control_pars=[symengine.sympify(a.symbol) for a in dynamics.params],
                           verbose=False)
    peer.compile_C(omp=False, verbose=False)
    peer.set_integrator("dop853", rtol=RTOL, atol=ATOL, nsteps=10**7)
    peer.set_parameters(*p)
    peer.set_initial_value(np.zeros(len(dynamics.state)), 0.0)
    return peer.jitced.f, peer, time.perf_counter() - start


def fortran(f, y0, t):
    """Fortran dop853 (scipy's ``ode``) on f(t, y), stepping to each of t[1:]: the states (n, len(t)) and
    the evaluations of f (dop853.f's IWORK(17), summed over the calls)."""
    solver = scipy_ode(f).set_integrator("dop853", rtol=RTOL, atol=ATOL, nsteps=10**7)
    solver.set_initial_value(y0, t[0])
    states, nfev = [y0], 0
    for ti in t[1:]:
        states.append(solver.integrate(ti))
        nfev += int(solver._integrator.iwork[16])
    return np.array(states).T, nfev


def through_jitcode(peer, y0, t):
    peer.set_initial_value(y0, t[0])
    return np.array([y0] + [peer.integrate(ti) for ti in t[1:]]).T


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    repeats = parser.parse_args().repeats
    print(f"{machine()}; load average {os.getloadavg()[0]:.1f} at the start")
    p, y0 = flight()
    twin = kernels.load("grain_motion")
    grid, end = np.linspace(0.0, SPAN, 201), np.array([0.0, SPAN])
    start = time.perf_counter()
    ode.integrate("grain_motion", p, y0, end, rtol=RTOL, atol=ATOL)
    print(f"set-up: numba compiles the toolkit for grain_motion in {time.perf_counter() - start:.1f} s (wall)")
    peer = jitcode_f(p)
    if peer is None:
        print("JiTCODE not installed (pip install symmech[bench]): its rows are skipped")
    else:
        print(f"set-up: JiTCODE generates and compiles its C in {peer[2]:.1f} s (wall)")
    contenders = {}
    for label, t in (("201 times", grid), ("end only", end)):
        contenders[f"symmech ode.integrate, {label}"] = (
            lambda t=t: ode.integrate("grain_motion", p, y0, t, rtol=RTOL, atol=ATOL).y)
        if peer:
            contenders[f"JiTCODE f + Fortran dop853, {label}"] = lambda t=t: fortran(peer[0], y0, t)[0]
            contenders[f"JiTCODE integrate (dop853), {label}"] = lambda t=t: through_jitcode(peer[1], y0, t)
        contenders[f"solve_ivp DOP853 on numba rhs, {label}"] = (
            lambda t=t: solve_ivp(twin.rhs, (0.0, SPAN), y0, method="DOP853", t_eval=t, args=(p,), rtol=RTOL,
                                  atol=ATOL).y)
    reference = {len(t): solve_ivp(gm.rhs, (0.0, SPAN), y0, method="DOP853", t_eval=t, args=(p,), rtol=1e-13,
                                   atol=1e-16).y for t in (grid, end)}
    for label, t in (("201 times", grid), ("end only", end)):
        ivp = solve_ivp(twin.rhs, (0.0, SPAN), y0, method="DOP853", t_eval=t, args=(p,), rtol=RTOL, atol=ATOL)
        fortran_nfev = f", Fortran dop853 {fortran(peer[0], y0, t)[1]}" if peer else ""
        print(f"evaluations of f, {label}: symmech {ode.integrate('grain_motion', p, y0, t, rtol=RTOL, atol=ATOL).nfev}"
              f"{fortran_nfev}, solve_ivp {ivp.nfev}")
    errors = {}
    for name, run in contenders.items():
        y = run()
        ref = reference[y.shape[1]]
        errors[name] = (np.abs(y - ref).max(axis=1) / np.abs(ref).max(axis=1)).max()
    stats = interleaved(contenders, repeats, number=3)
    print(f"whole {SPAN:g} s flight, DOP853 at rtol {RTOL:g}, atol {ATOL:g}; load average "
          f"{os.getloadavg()[0]:.1f} at the end")
    for label in ("201 times", "end only"):
        base = f"JiTCODE f + Fortran dop853, {label}"
        for name, s in stats.items():
            if name.endswith(label):
                versus = f"  {ratio(s, stats[base])} the Fortran's time" if base in stats else ""
                print(f"  {name:48s} {s.text('ms', 1e3)}  error {errors[name]:.1e}{versus}")


if __name__ == "__main__":
    main()
