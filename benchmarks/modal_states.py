"""Would modal states bring a mechanism FMU's Model Exchange run within 1e-7 at CVode rtol 1e-10?

FMPy's own CVode driver (``fmpy.sundials.CVodeSolver``: BDF, dense Newton, atol = rtol x each state's nominal,
max step a fiftieth of the run, one call per output interval, as ``simulate_fmu`` drives it; tests/fmpy_cvode.py)
integrates a
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
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.linalg

from symmech.core import pipeline
from symmech.core.scene import scenes_folder
from symmech.export import model
from symmech.export.model import deviation
from symmech.smm import numeric

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from fmpy_cvode import cvode  # noqa: E402  (FMPy's CVode driver, shared with the tests)


@dataclass
class Mechanism:
    """A mechanism scene's linear equations and native run: a, b, c (n x n), A (2n x 2n) of y' = A y with
    y = (q, q'), the start state y0, the exported states' nominals, the output times t [s] and the exact
    free response q(t) (len(t), n), and the export model."""
    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    A: np.ndarray
    y0: np.ndarray
    nominals: np.ndarray
    t: np.ndarray
    exact: np.ndarray
    exported: model.ExportModel


def mechanism(path: Path) -> Mechanism:
    exported = model.load(path)
    setup = pipeline.load(path).setup
    m = numeric.solve_equilibrium(setup.m)[0] if setup.scene["equilibrium"]["solve"] else setup.m
    num = numeric.assemble(m)
    a, b, c = (x.toarray() for x in (num.a, num.b, num.c))
    n = a.shape[0]
    ini = setup.scene["initial"]
    y0 = np.r_[ini.get("q") or [0.0] * n, ini.get("qdot") or [0.0] * n].astype(float)
    t = np.linspace(0.0, ini["duration"], ini["steps"] + 1)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(a, c), -np.linalg.solve(a, b)]])
    nominals = np.array([v.nominal for v in exported.variables if v.nominal is not None])
    return Mechanism(a, b, c, A, y0, nominals, t, numeric.free_response(a, b, c, y0[:n], y0[n:], t), exported)


def with_initial(name: str, folder: Path) -> Path:
    """The bundled scene; one without an ``[initial]`` table starts from 1 mm or mrad on every coordinate and runs
    1 s in 500 steps (as the tests), written into ``folder``."""
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
    mech = mechanism(path)
    a, b, c, t, exact = mech.a, mech.b, mech.c, mech.t, mech.exact
    n = a.shape[0]
    q0, v0 = mech.y0[:n], mech.y0[n:]
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
    choices["modal, each mode's amplitude x 1e-6 (atol -> 0)"] = choices["modal, each mode's amplitude"] * 1e-6
    print(f"\n{path.stem}: {n} coordinates, ω {omega.min():.3g}…{omega.max():.3g} rad/s, {t[-1]:g} s in "
          f"{len(t) - 1} steps")
    for rtol in (1e-10, 1e-12):
        errors = {f"physical, exported nominals x {scale:g}": deviation(
            cvode(mech.A, mech.y0, mech.nominals * scale, t, rtol)[0][:, :n], exact) for scale in (1.0, 1e-6)}
        for label, nominal in choices.items():
            errors[label] = deviation(cvode(modal, np.r_[e0, ed0], nominal, t, rtol)[0][:, :n] @ phi.T, exact)
        print(f"  rtol {rtol:g}: " + "; ".join(f"{label} {e:.2g}" for label, e in errors.items()))


def main() -> None:
    names = sys.argv[1:] or ["smm_excavator", "smm_spatial_boom", "smm_rotor_boom", "smm_double_pendulum"]
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            study(with_initial(name, Path(tmp)))


if __name__ == "__main__":
    main()
