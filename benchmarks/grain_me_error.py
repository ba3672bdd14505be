"""Where the grain FMU's Model Exchange error at CVode rtol 1e-10 comes from, and whether other states would remove it.

FMPy's own CVode driver (tests/fmpy_cvode.py: BDF, atol = rtol x nominal, max step a fiftieth of 0.23 s, reset at
each event) runs the grain's flight on the generated numpy module ``grain_motion`` (rates, the gap as the event
indicator, the impact map at each zero: tests/grain_cvode.py), no FMU, over the default scene's first three bounce sequences (impacts
1-13 from the start, 14-23 and 24-33 from the native state at the first flight row after the first and second
sliding phase), in four formulations of the centre's motion:

- relative: the FMU's states (the centre relative to the vibrating surface: its flight carries sin and cos);
- inertial: the centre in the inertial frame (a parabola in flight: BDF of order >= 2 is exact on it), the gap and
  the impact map on the relative state (the surface's closed form subtracted);
- ballistic: the inertial centre's deviation from its straight line at the flight's start (g (t - t0)^2 / 2: a
  parabola from zero at each flight's start) and its rate;
- exact: the translation in closed form (``flight_translation``), CVode integrating the rotation only;

the rotation as the FMU's quaternion and body rates (torque-free Euler equations), or (``+momentum``) the quaternion
and the angular momentum in KXYZ (constant in flight); with the FMU's nominals or every nominal times 1e-3 or 1e-6
(atol -> 0: CVode's pure relative control), the relative one also with the exact Jacobian (``grain_motion.jac``:
FMPy differences the rates). Printed: the largest
impact time error of each sequence [s] against the native compiled engine at tol 1e-12 (the target: 1e-8 s).

With ``--fmu``: the exported FMU itself (FMI 3 ME, the default scene over 0.23 s at its tolerance 1e-9) under
``fmpy.simulate_fmu`` at rtol 1e-10 with its state nominals scaled (positions, velocities, rotation), the largest
error of its first 50 impact times against that native run.

    python benchmarks/grain_me_error.py [rtol ...]      (default 1e-10 1e-12)
    python benchmarks/grain_me_error.py --fmu
"""
from __future__ import annotations

import dataclasses
import sys
import tempfile
from pathlib import Path

import fmpy
import numpy as np

from symmech.core import pipeline
from symmech.core.scene import scenes_folder
from symmech.export import build
from symmech.export import grain as exported_grain
from symmech.generated import grain_motion as gm
from symmech.grain import motion, motion_scene
from symmech.grain.vectors import TRAJECTORY_ROW

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from fmpy_cvode import Driven  # noqa: E402  (FMPy's CVode driver, shared with the tests)
from grain_cvode import Flight, bounces  # noqa: E402  (the grain's flight under it, shared with the tests)

SPAN = 0.23  # s: the default scene's first 53 impacts, as bench_export.py --only sliding
SEQUENCES = 3
# (formulation, nominals' scale, CVode handed the exact Jacobian)
VARIANTS = (("relative", 1.0, False), ("relative", 1.0, True), ("relative", 1e-6, False), ("inertial", 1.0, False),
            ("inertial", 1e-6, False), ("ballistic", 1.0, False), ("ballistic", 1e-3, False),
            ("ballistic", 1e-6, False), ("ballistic+momentum", 1e-6, False), ("exact", 1.0, False),
            ("exact", 1e-6, False), ("exact+momentum", 1e-6, False))


class Grain(Flight):
    """The default scene's flight, the native run at tol 1e-12 and the starts (t [s], relative state) of its bounce
    sequences."""

    def __init__(self, folder: Path):
        text = (scenes_folder() / "grain_default.toml").read_text()
        path = folder / "grain.toml"
        path.write_text(text.replace("duration = 2.0 ", f"duration = {SPAN!r} ")
                        .replace("tolerance = 1e-9", "tolerance = 1e-12"))
        sc = pipeline.load(path).setup
        super().__init__(sc)
        native = motion_scene.simulate(sc)
        self.native_impacts = np.array([i["t"] for i in native.impacts])
        regime = np.ravel(TRAJECTORY_ROW.split(native.trajectory)["regime"])
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


class Formulation:
    """The states CVode integrates (``x``) against the relative state (``relative``) in one flight from t0: the
    translation (``relative``, ``inertial``, ``ballistic``: the inertial centre's deviation from its line at the
    flight's start, R0 + V0 (t - t0), and its rate, or ``exact``: none) and the rotation (``body``: quaternion and body
    rates; ``momentum``: quaternion and the angular momentum in KXYZ, constant in flight)."""

    def __init__(self, name: str, grain: Grain):
        self.grain = grain
        self.translation, _, rotation = name.partition("+")
        self.rotation = rotation or "body"
        self.inertia = grain.p[9:12]

    def start(self, t0: float, y: np.ndarray) -> np.ndarray:
        """x at the flight's start ``t0`` [s] from the relative state ``y`` (13,)."""
        self.t0, self.y0 = t0, y.copy()
        s, ds = self.grain.surface(t0)
        self.line = (y[:3] + s, y[3:6] + ds)
        translation = {"relative": y[:6], "inertial": np.r_[self.line[0], self.line[1]], "ballistic": np.zeros(6),
                       "exact": np.zeros(0)}[self.translation]
        q, w = y[6:10], y[10:13]
        rotation = y[6:] if self.rotation == "body" else np.r_[q, np.asarray(gm.rotation_matrix(*q)) @ (self.inertia * w)]
        return np.r_[translation, rotation]

    def relative(self, t: float, x: np.ndarray) -> np.ndarray:
        """The relative state (13,) at ``t`` [s] from x."""
        s, ds = self.grain.surface(t)
        if self.translation == "relative":
            translation = x[:6]
        elif self.translation == "inertial":
            translation = np.r_[x[:3] - s, x[3:6] - ds]
        elif self.translation == "ballistic":
            r0, v0 = self.line
            translation = np.r_[r0 + v0 * (t - self.t0) + x[:3] - s, v0 + x[3:6] - ds]
        else:
            translation = np.ravel(gm.flight_translation(*self.y0[:6], *self.grain.p[:9], self.t0, t))
        rotation = x[len(x) - 7:]
        if self.rotation == "momentum":
            q = rotation[:4]
            rotation = np.r_[q, np.asarray(gm.rotation_matrix(*q)).T @ rotation[4:] / self.inertia]
        return np.r_[translation, rotation]

    def rate(self, t: float, x: np.ndarray) -> np.ndarray:
        f = self.grain.rate(t, self.relative(t, x))
        free_fall = np.r_[x[3:6], self.grain.p[:3]]
        translation = {"relative": f[:6], "inertial": free_fall, "ballistic": free_fall,
                       "exact": np.zeros(0)}[self.translation]
        return np.r_[translation, f[6:] if self.rotation == "body" else np.r_[f[6:10], np.zeros(3)]]

    def nominals(self, scale: float) -> np.ndarray:
        """The FMU's nominals of x's states (a momentum's: the rates' times the largest inertia) times ``scale``."""
        n = self.grain.nominals
        translation = n[:0] if self.translation == "exact" else n[:6]
        rotation = n[6:] if self.rotation == "body" else np.r_[n[6:10], n[10:13] * self.inertia.max()]
        return np.r_[translation, rotation] * scale


def sequence(form: Formulation, t0: float, y0: np.ndarray, count: int, rtol: float, scale: float,
             jacobian: bool) -> np.ndarray:
    """The times [s] of the first ``count`` impacts after ``t0`` of CVode's run from the relative state ``y0``."""
    grain = form.grain

    def bounce(t, x):
        after = grain.bounce(form.relative(t, x))
        return None if after is None else form.start(t, after)

    run = Driven(form.rate, form.start(t0, y0), form.nominals(scale), t0, rtol, SPAN / 50, nz=1, max_steps=100_000,
                 events=lambda t, y: grain.gap(t, form.relative(t, y)),
                 jacobian=(lambda t, y: gm.jac(t, y, grain.p)) if jacobian else None)
    return bounces(run, count, SPAN / 50, bounce)


def fmu_nominals(folder: Path) -> None:
    """The FMU at rtol 1e-10 with its position, velocity and rotation nominals scaled: first 50 impact times."""
    path = folder / "grain.toml"
    path.write_text((scenes_folder() / "grain_default.toml").read_text()
                    .replace("duration = 2.0 ", f"duration = {SPAN!r} "))
    scene = pipeline.load(path)
    native = np.array([i["t"] for i in motion_scene.simulate(scene.setup).impacts])
    model = exported_grain.load(scene)
    groups = {"x": 0, "y": 0, "z": 0, "vx": 1, "vy": 1, "vz": 1}  # the rest: the rotation (2)
    print("the FMU (FMI 3 ME) under simulate_fmu, rtol 1e-10, first 50 impact times against the native run (tol 1e-9)")
    for scales in ((1, 1, 1), (1e-2, 1, 1), (1e-3, 1, 1), (1, 1, 1e-2), (1e-2, 1, 1e-2), (1e-2, 1e-2, 1e-2)):
        variables = tuple(dataclasses.replace(v, nominal=v.nominal * scales[groups.get(v.name, 2)])
                          if v.nominal is not None else v for v in model.variables)
        fmu = build.fmu(dataclasses.replace(model, variables=variables), folder / "grain.fmu", 3, "me")
        label = "nominals x " + " / ".join(f"{f:g}" for f in scales) + " (positions / velocities / rotation)"
        try:
            res = fmpy.simulate_fmu(str(fmu), solver="CVode", relative_tolerance=1e-10, stop_time=SPAN,
                                    output_interval=SPAN / 50, output=["impacts"], record_events=True)
        except RuntimeError as error:
            print(f"  {label}: CVode stopped: {str(error)[-80:]}")
            continue
        at = np.flatnonzero((np.diff(res["time"]) == 0) & (np.diff(res["impacts"]) > 0))
        n = min(50, len(at), len(native))
        print(f"  {label}: {len(at)} impacts ({len(native)} native), first {n} within "
              f"{np.abs(res['time'][at][:n] - native[:n]).max():.2g} s")


def main() -> None:
    if sys.argv[1:] == ["--fmu"]:
        with tempfile.TemporaryDirectory() as tmp:
            fmu_nominals(Path(tmp))
        return
    rtols = [float(a) for a in sys.argv[1:]] or [1e-10, 1e-12]
    with tempfile.TemporaryDirectory() as tmp:
        grain = Grain(Path(tmp))
    bounds = [0, 13, 23, 33]  # the native run's impacts closing each sequence (its landings follow them)
    print(f"largest impact time error of bounce sequences 1-{SEQUENCES} (impacts 1-13, 14-23, 24-33) against the "
          "native engine at tol 1e-12 [s]")
    for rtol in rtols:
        for name, scale, jacobian in VARIANTS:
            form = Formulation(name, grain)
            errors = []
            for (t0, y0), first, last in zip(grain.starts, bounds, bounds[1:]):
                times = sequence(form, t0, y0, last - first, rtol, scale, jacobian)
                errors.append(np.abs(times - grain.native_impacts[first:last]).max())
            label = f"{name}, nominals x {scale:g}{', exact Jacobian' if jacobian else ''}"
            print(f"  rtol {rtol:g}  {label:42s} " + "  ".join(f"{e:.2g}" for e in errors))


if __name__ == "__main__":
    main()
