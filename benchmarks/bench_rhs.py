"""The generated rhs(t, y, p) / jac(t, y, p): one call against peers, and solve_ivp with the generated
Jacobian vs scipy's finite differences.

    python benchmarks/bench_rhs.py            # 7 repeats
    python benchmarks/bench_rhs.py --quick    # 5 repeats, shorter integrations
    pip install symmech[bench]                # adds the optional peer JiTCODE (symbolic -> C, needs a C compiler)

Grain flight (grain_motion, 13 states, 12 parameters), one rhs call at a seeded point, from the same
sympy derivation (derive_motion.flight_dynamics): JiTCODE's C function, the twin's rhs as kernels.load
gives it (the C path of symmech.numerics.fastcall: rhs_into as a numba cfunc behind a C callable), the
generated numba rhs it stands for (a numba dispatcher); the kernel rhs_scalar; rhs_into called from Python
into one reused out, and stepping an explicit Euler loop compiled with numba, per step; a jitted no-op
taking the same arguments: the price of any call into numba from Python), sympy.lambdify(cse=True) and the
numpy module's rhs. Ratios: time / JiTCODE's, time / lambdify's.
Per call, numpy vs the twin (C path and numba path): smm_spatial_boom (8 states, 21 parameters, a mass
matrix) at a seeded point.
Integration: the rotor boom's damped free response (Radau, rtol 1e-9) over the bundled scene's 2 s
(0.5 s with --quick), with the error against the run's matrix-exponential response.
"""
from __future__ import annotations

import argparse
import tomllib

import numba
import numpy as np
from scipy.integrate import solve_ivp
from timing import Stats, interleaved, machine, ratio

import symmech
from symmech.numerics import kernels
from symmech.core.scene import scenes_folder


def per_call(name: str, repeats: int) -> None:
    import importlib

    module = importlib.import_module(f"symmech.generated.{name}")
    twin = kernels.load(name)
    rng = np.random.default_rng(1)
    y, p = rng.uniform(0.5, 1.5, len(module.STATE)), rng.uniform(0.5, 1.5, len(module.PARAMS))
    twin.rhs(0.1, y, p), twin.jac(0.1, y, p)  # compile outside the timing; binds the C path
    numba_rhs, numba_jac = twin.rhs.__wrapped__, twin.jac.__wrapped__
    numba_rhs(0.1, y, p), numba_jac(0.1, y, p)
    stats = interleaved({"numpy rhs": lambda: module.rhs(0.1, y, p), "C rhs": lambda: twin.rhs(0.1, y, p),
                         "numba rhs": lambda: numba_rhs(0.1, y, p), "numpy jac": lambda: module.jac(0.1, y, p),
                         "C jac": lambda: twin.jac(0.1, y, p), "numba jac": lambda: numba_jac(0.1, y, p)},
                        repeats, number=2000)
    for key, s in stats.items():
        print(f"  {name:18s} {key:10s} {s.text('us', 1e6)}")
    for path in ("C", "numba"):
        print(f"  {name:18s} {path}/numpy rhs {ratio(stats['numpy rhs'], stats[f'{path} rhs'])}, "
              f"jac {ratio(stats['numpy jac'], stats[f'{path} jac'])}")


def _jitcode_rhs(dynamics, p):
    """JiTCODE's compiled f(t, y) of the same rate, its parameters set to ``p``; None when not installed."""
    try:
        import jitcode
    except ImportError:
        return None
    import symengine

    to_y = {a.symbol: jitcode.y(i) for i, a in enumerate(dynamics.state)}
    to_y[dynamics.time.symbol] = jitcode.t
    rate = [symengine.sympify(e).subs(to_y) for e in dynamics.rate]
    ode = jitcode.jitcode(rate, control_pars=[symengine.sympify(a.symbol) for a in dynamics.params], verbose=False)
    ode.compile_C(omp=False, verbose=False)
    ode.jitced.initialise(*p)
    return ode.jitced.f


@numba.njit
def _euler(rhs_into, t, y, p, h, steps):
    """``steps`` explicit Euler steps of size h through ``rhs_into``: each call depends on the last."""
    out = np.empty((1, len(y)))
    for _ in range(steps):
        rhs_into(t, y, p, out)
        for i in range(len(y)):
            y[i] += h * out[0, i]
        t += h
    return y


@numba.njit
def _noop(t, y, p):
    return t


def grain_flight(repeats: int) -> None:
    import sympy

    from symmech.generated import grain_motion as module
    from symmech.grain.derive_motion import flight_dynamics

    twin = kernels.load("grain_motion")
    dynamics = flight_dynamics()
    rng = np.random.default_rng(1)
    y, p = rng.uniform(0.5, 1.5, len(module.STATE)), rng.uniform(0.5, 1.5, len(module.PARAMS))
    symbols = [dynamics.time.symbol, *(a.symbol for a in dynamics.state), *(a.symbol for a in dynamics.params)]
    lam = sympy.lambdify(symbols, dynamics.rate, modules="numpy", cse=True)
    jit = _jitcode_rhs(dynamics, p)
    steps, y_euler, out = 1000, y.copy(), np.empty((1, len(y)))
    _euler(twin.rhs_into, 0.1, y_euler, p, 1e-9, 1), twin.rhs(0.1, y, p), _noop(0.1, y, p)  # compile outside
    numba_rhs = twin.rhs.__wrapped__  # the generated rhs the C path stands for
    numba_rhs(0.1, y, p)
    if type(twin.rhs).__name__ != "Kernel":
        print("  no C path here (no C compiler?): its row times the numba rhs")
    in_loop = "numba rhs_into, per step of a numba loop"
    contenders = {"JiTCODE f (C)": (lambda: jit(0.1, y)) if jit else None,
                  "twin rhs, C path (fastcall)": lambda: twin.rhs(0.1, y, p),
                  in_loop: lambda: _euler(twin.rhs_into, 0.1, y_euler, p, 1e-9, steps),
                  "numba rhs_into from Python, out reused": lambda: twin.rhs_into(0.1, y, p, out),
                  "numba: a jitted no-op, same arguments": lambda: _noop(0.1, y, p),
                  "numba rhs_scalar": lambda: twin.rhs_scalar(0.1, y, p),
                  "numba rhs (the generated function)": lambda: numba_rhs(0.1, y, p),
                  "lambdify(cse=True)": lambda: lam(0.1, *y, *p),
                  "numpy rhs": lambda: module.rhs(0.1, y, p)}
    reference = module.rate(0.1, *y, *p)
    twin.rhs_into(0.1, y, p, out)
    results = {"C path rhs": twin.rhs(0.1, y, p), "numba rhs": numba_rhs(0.1, y, p), "numba rhs_into": out.copy(),
               "lambdify(cse=True)": lam(0.1, *y, *p),
               "numpy rhs": module.rhs(0.1, y, p)} | ({"JiTCODE f (C)": jit(0.1, y)} if jit else {})
    if jit is None:
        print("  JiTCODE not installed (pip install symmech[bench]): its row is skipped")
    stats = interleaved({k: f for k, f in contenders.items() if f}, repeats, number=2000)
    s = stats[in_loop]
    stats[in_loop] = Stats(s.median / steps, s.low / steps, s.high / steps, s.n)
    for name, s in stats.items():
        versus = [f"{ratio(s, stats[base])} {label}" for base, label in (("JiTCODE f (C)", "JiTCODE's time"),
                  ("lambdify(cse=True)", "lambdify's time")) if base in stats]
        print(f"  {name:42s} {s.text('us', 1e6)}  {'; '.join(versus)}")
    print("  max |difference| to numpy rate(): " + ", ".join(
        f"{name} {np.abs(np.ravel(r) - reference).max():.1e}" for name, r in results.items()))


def integration(repeats: int, span: float) -> None:
    from symmech.generated import smm_rotor_boom as rb

    scene = symmech.load(tomllib.loads((scenes_folder() / "smm_rotor_boom.toml").read_text()))
    table = scene.run().tables["free_response"]
    t = table.data[:, 0]
    keep = t <= span
    t, q_run = t[keep], table.data[keep, 1:]
    p = [scene.setup.m.parameters[name].value for name, _, _ in rb.PARAMS]
    y0 = np.array([1e-3, 0.0, 0.0, 0.0])
    runs = {}

    def solve(jac):
        sol = solve_ivp(rb.rhs, (0.0, t[-1]), y0, method="Radau", t_eval=t, args=(p,), jac=jac, rtol=1e-9,
                        atol=1e-15)
        runs[jac is not None] = sol
        return sol

    stats = interleaved({"generated jac": lambda: solve(rb.jac), "finite differences": lambda: solve(None)}, repeats)
    for with_jac, key in ((True, "generated jac"), (False, "finite differences")):
        sol = runs[with_jac]
        error = np.abs(sol.y[:2].T - q_run).max() / np.abs(q_run).max()
        print(f"  Radau, {key:18s} {stats[key].text('s')}  nfev {sol.nfev}, njev {sol.njev}, "
              f"max error / amplitude {error:.1e}")
    print(f"  generated jac vs finite differences: {ratio(stats['finite differences'], stats['generated jac'])}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    repeats = 5 if args.quick else 7
    print(machine())
    print("grain flight, one rhs call (ratio: time / the peer's time, range from the extremes):")
    grain_flight(repeats)
    print("one call on a state vector, numpy module vs numba twin:")
    per_call("smm_spatial_boom", repeats)
    print("solve_ivp on the rotor boom's free response:")
    integration(repeats, 0.5 if args.quick else 2.0)


if __name__ == "__main__":
    main()
