"""Would modal states bring a mechanism FMU's Model Exchange run within 1e-7 at CVode rtol 1e-10?

FMPy's own CVode driver (``fmpy.sundials.CVodeSolver``: BDF, dense Newton, atol = rtol x each state's nominal,
max step a fiftieth of the run, one call per output interval, as ``simulate_fmu`` drives it) integrates a
mechanism's linear equations a q'' + b q' + c q = 0 from the scene's start state in two choices of state:

- physical, y = (q, q') with the exported nominals (what the FMU exports; this reproduces the FMU's errors);
- modal, y = (η, η') with q = Φ η (Φ: c φ = ω² a φ, Φᵀ a Φ = I), under four choices of nominal: 1, each mode's
  own amplitude (rates times its ω), the largest mode's amplitude for all, and that divided by 1000.

Error: :func:`symmech.export.model.deviation` of q against ``numeric.free_response`` (exact). The mechanisms
without an ``[initial]`` table start from 1 mm or mrad on every coordinate over 1 s, as the tests do.

    python benchmarks/modal_states.py [scene ...]
"""
from __future__ import annotations

import sys
import tempfile
import tomllib
from pathlib import Path

import numpy as np
import scipy.linalg
from fmpy.sundials import CVodeSolver

from symmech.core import pipeline
from symmech.core.scene import scenes_folder
from symmech.export import model
from symmech.export.model import deviation
from symmech.smm import numeric


class _NoInput:
    def apply(self, t):
        pass


def cvode(A: np.ndarray, y0: np.ndarray, nominals: np.ndarray, t: np.ndarray, rtol: float) -> np.ndarray:
    """y (len(t), n) of y' = A y from y0 by FMPy's CVode driver, its steps as simulate_fmu takes them."""
    state = {"y": np.array(y0, float)}

    def put(values):
        return lambda p, k: np.ctypeslib.as_array(p, (k,)).__setitem__(slice(None), values())

    def set_x(p, k):
        state["y"] = np.ctypeslib.as_array(p, (k,)).copy()

    solver = CVodeSolver(nx=len(y0), nz=0, get_x=put(lambda: state["y"]), set_x=set_x,
                         get_dx=put(lambda: A @ state["y"]), get_z=lambda p, k: None,
                         get_nominals=put(lambda: nominals), set_time=lambda time: None, input=_NoInput(),
                         startTime=t[0], maxStep=(t[-1] - t[0]) / 50, relativeTolerance=rtol)
    out = [state["y"].copy()]
    for k in range(1, len(t)):
        reached = t[k - 1]
        while reached < t[k] - 1e-14 * t[-1]:
            _, _, reached = solver.step(reached, t[k])
        out.append(state["y"].copy())
    return np.array(out)


def _with_initial(name: str, folder: Path) -> Path:
    path = scenes_folder() / f"{name}.toml"
    text = path.read_text()
    data = tomllib.loads(text)
    if "initial" in data:
        return path
    n = len(data["coordinates"])
    path = folder / f"{name}.toml"
    path.write_text(text + f"\n[initial]\nq = [{', '.join(['0.001'] * n)}]\nduration = 1.0\nsteps = 500\n")
    return path


def study(path: Path) -> None:
    exported = model.load(path)
    setup = pipeline.load(path).setup
    m = numeric.solve_equilibrium(setup.m)[0] if setup.scene["equilibrium"]["solve"] else setup.m
    num = numeric.assemble(m)
    a, b, c = (x.toarray() for x in (num.a, num.b, num.c))
    n = a.shape[0]
    ini = setup.scene["initial"]
    q0 = np.array(ini.get("q") or [0.0] * n, float)
    v0 = np.array(ini.get("qdot") or [0.0] * n, float)
    t = np.linspace(0.0, ini["duration"], ini["steps"] + 1)
    exact = numeric.free_response(a, b, c, q0, v0, t)
    physical = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(a, c), -np.linalg.solve(a, b)]])
    nominals = np.array([v.nominal for v in exported.variables if v.nominal is not None])
    w2, phi = scipy.linalg.eigh(c, a)
    modal = np.block([[np.zeros((n, n)), np.eye(n)], [-np.diag(w2), -phi.T @ b @ phi]])
    e0, ed0 = np.linalg.solve(phi, q0), np.linalg.solve(phi, v0)
    omega = np.sqrt(np.maximum(w2, 0.0))
    positive = omega > 1e-6 * omega.max()
    omega = np.where(positive, omega, omega[positive].min())  # a rigid-body mode: the lowest elastic ω
    amplitude = np.maximum(np.abs(e0), np.abs(ed0) / omega)
    amplitude = np.where(amplitude > 1e-9 * amplitude.max(), amplitude, amplitude.max())
    top = amplitude.max()
    choices = {"modal, nominals 1": np.ones(2 * n), "modal, each mode's amplitude": np.r_[amplitude, amplitude * omega],
               "modal, the largest amplitude": np.r_[np.full(n, top), np.full(n, top * omega.min())]}
    choices["modal, the largest amplitude / 1000"] = choices["modal, the largest amplitude"] / 1000
    print(f"\n{path.stem}: {n} coordinates, ω {omega.min():.3g}…{omega.max():.3g} rad/s, {t[-1]:g} s in "
          f"{len(t) - 1} steps")
    for rtol in (1e-10, 1e-12):
        errors = {"physical, exported nominals": deviation(cvode(physical, np.r_[q0, v0], nominals, t, rtol)[:, :n],
                                                           exact)}
        for label, nominal in choices.items():
            errors[label] = deviation(cvode(modal, np.r_[e0, ed0], nominal, t, rtol)[:, :n] @ phi.T, exact)
        print(f"  rtol {rtol:g}: " + "; ".join(f"{label} {e:.2g}" for label, e in errors.items()))


def main() -> None:
    names = sys.argv[1:] or ["smm_excavator", "smm_spatial_boom", "smm_rotor_boom", "smm_double_pendulum"]
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            study(_with_initial(name, Path(tmp)))


if __name__ == "__main__":
    main()
