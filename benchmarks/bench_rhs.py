"""The generated rhs(t, y, p) / jac(t, y, p): one call (numpy vs numba twin), and solve_ivp with the
generated Jacobian vs scipy's finite differences.

    python benchmarks/bench_rhs.py            # 7 repeats
    python benchmarks/bench_rhs.py --quick    # 5 repeats, shorter integrations

Per call: grain_motion (13 states, 12 parameters) and smm_spatial_boom (8 states, 21 parameters) at a
seeded point. Integration: the rotor boom's damped free response (Radau, rtol 1e-9) over the bundled
scene's 2 s (0.5 s with --quick), with the error against the run's matrix-exponential response.
"""
from __future__ import annotations

import argparse
import tomllib

import numpy as np
from scipy.integrate import solve_ivp
from timing import interleaved, machine, ratio

import symmech
from symmech.core import kernels
from symmech.core.scene import scenes_folder


def per_call(name: str, repeats: int) -> None:
    import importlib

    module = importlib.import_module(f"symmech.generated.{name}")
    twin = kernels.load(name)
    rng = np.random.default_rng(1)
    y, p = rng.uniform(0.5, 1.5, len(module.STATE)), rng.uniform(0.5, 1.5, len(module.PARAMS))
    twin.rhs(0.1, y, p), twin.jac(0.1, y, p)  # compile outside the timing
    stats = interleaved({"numpy rhs": lambda: module.rhs(0.1, y, p), "numba rhs": lambda: twin.rhs(0.1, y, p),
                         "numpy jac": lambda: module.jac(0.1, y, p), "numba jac": lambda: twin.jac(0.1, y, p)},
                        repeats, number=2000)
    for key, s in stats.items():
        print(f"  {name:18s} {key:10s} {s.text('us', 1e6)}")
    print(f"  {name:18s} numba/numpy rhs {ratio(stats['numpy rhs'], stats['numba rhs'])}, "
          f"jac {ratio(stats['numpy jac'], stats['numba jac'])}")


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
    print("one call on a state vector:")
    for name in ("grain_motion", "smm_spatial_boom"):
        per_call(name, repeats)
    print("solve_ivp on the rotor boom's free response:")
    integration(repeats, 0.5 if args.quick else 2.0)


if __name__ == "__main__":
    main()
