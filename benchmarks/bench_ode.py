"""The compiled ODE toolkit end to end (``symmech.numerics.ode.integrate``) against ``solve_ivp`` on the numba
right-hand side of the same generated module (``smm_rotor_boom_nb.rhs``, and its ``jac`` for Radau): the
rotor boom's damped free response over the bundled scene's 2 s, output every 1 ms (dense output), at the same
tolerances; the two take the same steps, so the errors against the run's exact matrix exponential are equal
(printed side by side). Interleaved medians (benchmarks/timing.py); the toolkit's compile is done before timing.

Usage: python benchmarks/bench_ode.py [--repeats 5]
"""
import argparse
import tomllib

import numpy as np
from scipy.integrate import solve_ivp
from timing import interleaved, machine, ratio

import symmech
from symmech.numerics import ode
from symmech.core.scene import scenes_folder
from symmech.generated import smm_rotor_boom_nb as rb


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ns = ap.parse_args()
    scene = symmech.load(tomllib.loads((scenes_folder() / "smm_rotor_boom.toml").read_text()))
    data = scene.run().tables["free_response"].data
    t, q_exact = data[:, 0], data[:, 1:]
    m = scene.setup.m
    p = np.array([m.parameters[name].value for name, _, _ in rb.PARAMS])
    ini = scene.resolved["initial"]
    y0 = np.concatenate([ini["q"], ini["qdot"] or np.zeros(len(ini["q"]))])
    n = q_exact.shape[1]
    print(f"machine: {machine()}; rotor boom, {t[-1] - t[0]:g} s, {t.size} output times")
    for method, rtol in (("DOP853", 1e-10), ("Radau", 1e-8)):
        atol = rtol * 1e-3 * np.abs(y0).max()
        jac = {"jac": rb.jac} if method == "Radau" else {}
        runs = {"toolkit": lambda: ode.integrate("smm_rotor_boom", p, y0, t, t0=t[0], method=method, rtol=rtol,
                                                 atol=atol).y,
                "solve_ivp": lambda: solve_ivp(rb.rhs, (t[0], t[-1]), y0, method=method, t_eval=t, args=(p,),
                                               rtol=rtol, atol=atol, **jac).y}
        errors = {k: np.abs(f()[:n].T - q_exact).max() / np.abs(q_exact).max() for k, f in runs.items()}
        stats = interleaved(runs, ns.repeats)
        for k in runs:
            print(f"  {method:<7} {k:<10} {stats[k].text('ms', 1e3)}  error {errors[k]:.2e} (relative to max |q|)")
        print(f"  {method:<7} solve_ivp / toolkit: {ratio(stats['solve_ivp'], stats['toolkit'])}")


if __name__ == "__main__":
    main()
