"""Where a mechanism FMU's Model Exchange error at CVode rtol 1e-10 comes from: the FMU or the importer's integrator?

For each bundled mechanism (those without an ``[initial]`` table from 1 mm or mrad, 1 s, as the tests), against
the exact free response (``numeric.free_response``), largest deviation of each coordinate series relative to its
largest magnitude (:func:`symmech.export.model.deviation`):

- the FMU (FMI 3 ME) under ``fmpy.simulate_fmu`` (CVode) at rtol 1e-10, its error at a quarter, half and the whole
  run (growth), and at rtol 1e-8…1e-12 (the slope of log error over log rtol);
- the same CVode (FMPy's driver, tests/fmpy_cvode.py) on the native equations y' = A y, no FMU: as simulate_fmu
  drives it, with no max step, with a max step of the run / 2000, with the exact Jacobian A, with the nominals
  times 1e-3 and 1e-6 (atol -> 0: CVode's relative control alone), every 10th output;
- independent integrators on y' = A y: scipy's BDF (NDF, orders 1–5), LSODA (ODEPACK, Adams/BDF), Radau IIA and
  DOP853, all at rtol 1e-10, atol 1e-10 x each state's nominal (what FMPy hands CVode);
- the FMU's rates against A y at 200 random states (relative to the largest rate).

    python benchmarks/me_error.py [scene ...]
"""
from __future__ import annotations

import sys
import tempfile
from ctypes import c_double
from pathlib import Path

import fmpy
import numpy as np
import scipy.integrate
from fmpy import extract, instantiate_fmu, read_model_description

from modal_states import cvode, mechanism, with_initial
from symmech.export import build
from symmech.export.model import deviation

RTOL = 1e-10


def fmu_run(fmu: Path, t: np.ndarray, names: list[str], rtol: float) -> np.ndarray:
    result = fmpy.simulate_fmu(str(fmu), solver="CVode", relative_tolerance=rtol, stop_time=t[-1],
                               output_interval=t[1] - t[0], output=names)
    return np.column_stack([result[name] for name in names])


def rate_deviation(fmu: Path, A: np.ndarray, nominals: np.ndarray) -> float:
    """Largest |f_FMU(y) - A y| over 200 random states y (each state ~ its nominal), relative to max |A y|."""
    n = len(nominals)
    instance = instantiate_fmu(extract(str(fmu)), read_model_description(str(fmu)), fmi_type="ModelExchange")
    instance.enterInitializationMode()
    instance.exitInitializationMode()
    instance.enterContinuousTimeMode()
    worst, rates = 0.0, (c_double * n)()
    for y in np.random.default_rng(1).standard_normal((200, n)) * nominals:
        instance.setContinuousStates((c_double * n)(*y), n)
        instance.getContinuousStateDerivatives(rates, n)
        worst = max(worst, float(np.abs(np.array(rates[:]) - A @ y).max() / np.abs(A @ y).max()))
    instance.terminate()
    instance.freeInstance()
    return worst


def study(path: Path, folder: Path) -> None:
    mech = mechanism(path)
    t, exact, n = mech.t, mech.exact, mech.a.shape[0]
    names = [c.name for c in mech.exported.native.columns[1:]]
    fmu = build.fmu(mech.exported, folder / f"{path.stem}.fmu", 3, "me")
    lam = np.linalg.eigvals(mech.A)
    oscillating = lam[lam.imag > 0]
    print(f"\n{path.stem}: {n} coordinates, {t[-1]:g} s; modes {', '.join(f'{w:.3g}' for w in np.sort(oscillating.imag) / (2 * np.pi))} Hz, "
          f"damping ratios up to {np.max(-oscillating.real / np.abs(oscillating)):.2g}; "
          f"{t[-1] * oscillating.imag.max() / (2 * np.pi):.0f} periods of the fastest mode")
    got = fmu_run(fmu, t, names, RTOL)
    marks = [len(t) // 4, len(t) // 2, len(t) - 1]
    growth = ", ".join(f"{t[k]:g} s {deviation(got[:k + 1], exact[:k + 1]):.2g}" for k in marks)
    print(f"  FMU, simulate_fmu CVode rtol {RTOL:g}: {deviation(got, exact):.3g} (up to {growth})")
    rtols = [1e-8, 1e-9, 1e-10, 1e-11, 1e-12]
    errors = [deviation(fmu_run(fmu, t, names, r), exact) for r in rtols]
    slope = np.polyfit(np.log10(rtols), np.log10(errors), 1)[0]
    print("  FMU at rtol " + ", ".join(f"{r:g}: {e:.2g}" for r, e in zip(rtols, errors)) + f"; error ~ rtol^{slope:.2f}")
    reference, _ = cvode(mech.A, mech.y0, mech.nominals, t, RTOL)
    print(f"  FMU against CVode on A y (the same driver, no FMU): {deviation(got, reference[:, :n]):.2g}; "
          f"the FMU's rates against A y: {rate_deviation(fmu, mech.A, mech.nominals):.2g}")
    variants = {"as simulate_fmu (max step run/50)": {}, "no max step": {"max_step": np.inf},
                "max step run/2000": {"max_step": t[-1] / 2000}, "exact Jacobian": {"jacobian": True},
                "nominals x 1e-3": {"scale": 1e-3}, "nominals x 1e-6 (atol -> 0)": {"scale": 1e-6}}
    for label, options in variants.items():
        scale = options.pop("scale", 1.0)
        y, steps = cvode(mech.A, mech.y0, mech.nominals * scale, t, RTOL, **options)
        print(f"  CVode on A y, {label:34s} {deviation(y[:, :n], exact):.3g} ({steps} steps)")
    y, steps = cvode(mech.A, mech.y0, mech.nominals, t[::10], RTOL)
    print(f"  CVode on A y, {'every 10th output time':34s} {deviation(y[:, :n], exact[::10]):.3g} ({steps} steps)")
    for method in ("BDF", "LSODA", "Radau", "DOP853"):
        jac = {} if method == "DOP853" else {"jac": lambda time, y: mech.A}
        sol = scipy.integrate.solve_ivp(lambda time, y: mech.A @ y, (t[0], t[-1]), mech.y0, method=method, t_eval=t,
                                        rtol=RTOL, atol=RTOL * mech.nominals, **jac)
        print(f"  scipy {method:6s} rtol {RTOL:g}: {deviation(sol.y[:n].T, exact):.3g} ({sol.nfev} rate evaluations)")


def main() -> None:
    names = sys.argv[1:] or ["smm_excavator", "smm_spatial_boom", "smm_rotor_boom", "smm_double_pendulum"]
    with tempfile.TemporaryDirectory() as tmp:
        for name in names:
            study(with_initial(name, Path(tmp)), Path(tmp))


if __name__ == "__main__":
    main()
