"""Where the grain FMU's Model Exchange error at CVode rtol 1e-10 comes from, and whether other states would remove it.

FMPy's own CVode driver (tests/fmpy_cvode.py: BDF, atol = rtol x nominal, max step a fiftieth of 0.23 s, reset at
each event) runs the grain's flight on the generated numpy module ``grain_motion`` (rates, the gap as the event
indicator, the impact map at each zero), no FMU, over the default scene's first three bounce sequences (impacts
1-13 from the start, 14-23 and 24-33 from the native state at the first flight row after the first and second
sliding phase), in three formulations of the centre's motion:

- relative: the FMU's states (the centre relative to the vibrating surface: its flight carries sin and cos);
- inertial: the centre in the inertial frame (a parabola in flight: BDF of order >= 2 is exact on it), the gap and
  the impact map on the relative state (the surface's closed form subtracted);
- exact: the translation in closed form (``flight_translation``), CVode integrating the rotation only (quaternion
  and torque-free Euler equations): the best any choice of translation states could do;

each with the FMU's nominals and with every nominal times 1e-6 (atol -> 0: CVode's pure relative control), the
relative one also with the exact Jacobian (``grain_motion.jac``: FMPy differences the rates). Printed: the largest
impact time error of each sequence [s] against the native compiled engine at tol 1e-12 (the target: 1e-8 s).

    python benchmarks/grain_me_error.py [rtol ...]      (default 1e-10 1e-12)
"""
from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np

from symmech.core import pipeline
from symmech.core.scene import scenes_folder
from symmech.export.grain import nominals
from symmech.generated import grain_motion as gm
from symmech.grain import motion, motion_scene
from symmech.grain.vectors import TRAJECTORY_ROW

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from fmpy_cvode import Driven  # noqa: E402  (FMPy's CVode driver, shared with the tests)

SPAN = 0.23  # s: the default scene's first 53 impacts, as bench_export.py --only sliding
SEQUENCES = 3


class Grain:
    """The default scene's parameters, the native run at tol 1e-12 and the starts of its bounce sequences."""

    def __init__(self, folder: Path):
        text = (scenes_folder() / "grain_default.toml").read_text()
        path = folder / "grain.toml"
        path.write_text(text.replace("duration = 2.0 ", f"duration = {SPAN!r} ")
                        .replace("tolerance = 1e-9", "tolerance = 1e-12"))
        sc = pipeline.load(path).setup
        vib, model = sc.model.vibration, sc.model
        self.p = np.array([*model.g_k, vib.amplitude, vib.omega, vib.phase, *vib.direction, *model.inertia,
                           *model.axes])
        self.law = (model.mass, model.law.e_n, model.law.e_t, model.law.mu)
        self.nominals = np.array(nominals(sc))
        native = motion_scene.simulate(sc)
        self.impacts = np.array([i["t"] for i in native.impacts])
        rows = TRAJECTORY_ROW.split(native.trajectory)
        regime = np.ravel(rows["regime"])
        flying = regime == motion.REGIMES.index("flight")
        lifts = np.flatnonzero(flying[1:] & (regime[:-1] == motion.REGIMES.index("sliding"))) + 1
        self.starts = [(0.0, np.concatenate([sc.start.r, sc.start.v, sc.start.q, sc.start.w]))]
        for k in lifts[:SEQUENCES - 1]:
            q = native.trajectory[k, 7:11]
            w_body = np.asarray(gm.rotation_matrix(*q)).T @ native.trajectory[k, 11:14]
            self.starts.append((native.trajectory[k, 0], np.concatenate([native.trajectory[k, 1:7], q, w_body])))

    def surface(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """The surface's displacement [m] and velocity [m/s] at ``t``."""
        kin = gm.surface_kinematics(*self.p[3:9], t)
        return kin[0], kin[1]

    def bounce(self, y: np.ndarray) -> np.ndarray:
        """The relative state after the impact map at the relative state ``y``."""
        args = (*y, *self.p[9:], self.law[0])
        contact = gm.impact_contact(*args)
        plastic = gm.plastic_impulse(*contact[:12])
        impulse = gm.coulomb_impulse(plastic[0], *plastic[1:4], contact[11], *self.law[1:])
        return np.asarray(gm.impact_state(*args, *impulse), float)


class Formulation:
    """The states CVode integrates (``x``) against the relative state (``relative``) in one flight from t0."""

    def __init__(self, name: str, grain: Grain):
        self.name, self.grain = name, grain

    def start(self, t0: float, y: np.ndarray) -> np.ndarray:
        self.t0, self.y0 = t0, y.copy()
        if self.name == "relative":
            return y.copy()
        if self.name == "inertial":
            s, ds = self.grain.surface(t0)
            return np.concatenate([y[:3] + s, y[3:6] + ds, y[6:]])
        return y[6:].copy()

    def relative(self, t: float, x: np.ndarray) -> np.ndarray:
        if self.name == "relative":
            return x
        if self.name == "inertial":
            s, ds = self.grain.surface(t)
            return np.concatenate([x[:3] - s, x[3:6] - ds, x[6:]])
        translation = np.ravel(gm.flight_translation(*self.y0[:6], *self.grain.p[:9], self.t0, t))
        return np.concatenate([translation, x])

    def rate(self, t: float, x: np.ndarray) -> np.ndarray:
        f = gm.rhs(t, self.relative(t, x), self.grain.p)
        if self.name == "relative":
            return f
        if self.name == "inertial":
            return np.concatenate([x[3:6], self.grain.p[:3], f[6:]])
        return f[6:]

    def nominals(self, scale: float) -> np.ndarray:
        return self.grain.nominals[6:] * scale if self.name == "exact" else self.grain.nominals * scale


def sequence(form: Formulation, t0: float, y0: np.ndarray, count: int, rtol: float, scale: float,
             jacobian: bool) -> np.ndarray:
    """The times [s] of the first ``count`` impacts after ``t0`` of CVode's run from the relative state ``y0``."""
    grain = form.grain
    x = form.start(t0, y0)
    jac = (lambda t, y: gm.jac(t, y, grain.p)) if jacobian else None
    run = Driven(form.rate, x, form.nominals(scale), t0, rtol, SPAN / 50, nz=1, jacobian=jac, max_steps=100_000,
                 events=lambda t, y: np.ravel(gm.event_values(t, *form.relative(t, y), *grain.p)))
    times, t = [], t0
    while len(times) < count:
        event, t = run.step(t, t0 + SPAN)
        if not event:
            raise RuntimeError(f"{form.name}: no impact by {t:g} s")
        y = form.relative(t, run.state["y"])
        if gm.impact_contact(*y, *grain.p[9:], grain.law[0])[11] < 0:  # approaching: a bounce
            times.append(t)
            run.state["y"] = form.start(t, grain.bounce(y))
        run.reset(t)
    return np.array(times)


def main() -> None:
    rtols = [float(a) for a in sys.argv[1:]] or [1e-10, 1e-12]
    with tempfile.TemporaryDirectory() as tmp:
        grain = Grain(Path(tmp))
    bounds = [0, 13, 23, 33]  # the native run's impacts closing each sequence (its landings follow them)
    print(f"largest impact time error of bounce sequences 1-{SEQUENCES} (impacts 1-13, 14-23, 24-33) against the "
          "native engine at tol 1e-12 [s]")
    for rtol in rtols:
        for name, scale, jacobian in (("relative", 1.0, False), ("relative", 1.0, True), ("relative", 1e-6, False),
                                      ("inertial", 1.0, False), ("inertial", 1e-6, False), ("exact", 1.0, False),
                                      ("exact", 1e-6, False)):
            form = Formulation(name, grain)
            errors = []
            for (t0, y0), first, last in zip(grain.starts, bounds, bounds[1:]):
                times = sequence(form, t0, y0, last - first, rtol, scale, jacobian)
                errors.append(np.abs(times - grain.impacts[first:last]).max())
            label = f"{name}, nominals x {scale:g}{', exact Jacobian' if jacobian else ''}"
            print(f"  rtol {rtol:g}  {label:42s} " + "  ".join(f"{e:.2g}" for e in errors))


if __name__ == "__main__":
    main()
