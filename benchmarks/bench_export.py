"""Exported models against the native run: FMU (FMPy, Model Exchange with CVode and Co-Simulation with the
FMU's DOP853, for the elastic trolley its Radau IIA) and the exported C example program, on the bundled mechanism
scenes with a free response, the bundled elastic trolley ride, the same ride under traction (P0 = 100 - 10 V0 N
from 3 m/s: no bundled scene has traction), the default grain scene over its whole 2 s (``grain``: 493 impacts,
landings, slips, sticks and lift-offs; Co-Simulation and the C program, their DOP853 locating the events on its
dense output), and through its sliding regimes under Model Exchange (``sliding``: its first 50 impacts, over 0.23 s,
and the whole 2 s).

The elastic C example program runs Radau IIA with dense output on the generated assembly; its real-time
factor is its CPU time (user + system, the median of >= 5 interleaved rounds of 20 runs) over the ride's duration,
beside a baseline build of the program (``--baseline DIR/example``, e.g. one exported from main) when given.

Native: `numeric.free_response` (the exact modal solution `symmech run` writes as free_response.csv); for the
elastic trolley the compiled engine at the scene's rtol (its reactions P0…P5; under traction also s, V0), and
beside it the same engine at rtol 1e-10 (under traction also the coordinates' atol 1e-14 m) as a reference closer
to the exact solution; for the grain the compiled engine's impacts (times,
centres) and trajectory rows.
Accuracy: `symmech.export.model.deviation`, the largest deviation of each series relative to its largest
magnitude.

    python benchmarks/bench_export.py [--quick] [--only grain|sliding|elastic|traction|mechanism|exports]
        [--baseline PATH]
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

import fmpy
import numpy as np

from symmech.core import pipeline
from symmech.core.scene import scenes_folder
from symmech.export import build, command, model
from symmech.export.model import deviation
from symmech.smm import numeric
from symmech.trolley.elastic import scene as elastic_scene
from timing import interleaved, interleaved_cpu, machine


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="3 rounds instead of 7")
    parser.add_argument("--only", choices=("grain", "sliding", "elastic", "traction", "mechanism", "exports"),
                        help="one model only")
    parser.add_argument("--baseline", help="an elastic helix example program to time beside this tree's")
    args = parser.parse_args()
    repeats = 3 if args.quick else 7
    print(machine())
    for name, bench in (("grain", grain), ("sliding", grain_sliding),
                        ("elastic", lambda repeats: elastic(repeats, args.baseline)), ("traction", traction),
                        ("mechanism", mechanisms), ("exports", exports)):
        if args.only in (None, name):
            bench(repeats)


def exports(repeats: int) -> None:
    """CPU time of `symmech export fmu` (FMI 3 ME) for every bundled scene it accepts, each in a process of its own
    (the native run, the derivation and the compile included), rounds interleaved; target <= 30 s each."""
    with tempfile.TemporaryDirectory() as tmp:
        commands = {}
        for path in sorted(scenes_folder().glob("*.toml")):
            command = [sys.executable, "-m", "symmech", "export", "fmu", str(path), "--out", f"{tmp}/{path.stem}.fmu"]
            if subprocess.run(command, capture_output=True).returncode == 0:  # refused scenes (exit 2) left out
                commands[path.stem] = command
        print("\nsymmech export fmu of each bundled scene it accepts, CPU per export (target <= 30 s):")
        for name, cpu in interleaved_cpu(commands, max(repeats, 5), number=1).items():
            print(f"  {name:28s} {cpu.text()}")


def mechanisms(repeats: int) -> None:
    """The rotor boom and the spatial boom: FMU ME/CS and the C example program against the exact free response."""
    for name in ("smm_rotor_boom", "smm_spatial_boom"):
        exported = model.load(scenes_folder() / f"{name}.toml")
        table = exported.native
        t, q, names = table.data[:, 0], table.data[:, 1:], [c.name for c in table.columns[1:]]
        with tempfile.TemporaryDirectory() as tmp:
            me = build.fmu(exported, Path(tmp) / "me.fmu", 3, "me")
            cs = build.fmu(exported, Path(tmp) / "cs.fmu", 3, "cs")
            example = build.c_folder(exported, Path(tmp) / "c") / "example"
            setup = pipeline.load(scenes_folder() / f"{name}.toml").setup
            num = numeric.assemble(setup.m)
            a, b, c = (x.toarray() for x in (num.a, num.b, num.c))
            ini = setup.scene["initial"]
            q0, v0 = np.array(ini["q"] or [0.0] * len(names)), np.array(ini["qdot"] or [0.0] * len(names))
            runs = {
                "native free_response": lambda: numeric.free_response(a, b, c, q0, v0, t),
                "FMU ME, FMPy CVode rtol 1e-10": lambda: fmpy.simulate_fmu(
                    str(me), solver="CVode", relative_tolerance=1e-10, stop_time=t[-1],
                    output_interval=t[1] - t[0], output=names),
                "FMU ME, CVode at its default (1e-12)": lambda: fmpy.simulate_fmu(  # the DefaultExperiment's
                    str(me), solver="CVode", stop_time=t[-1], output_interval=t[1] - t[0], output=names),
                "FMU CS, DOP853 rtol 1e-10": lambda: fmpy.simulate_fmu(
                    str(cs), relative_tolerance=1e-10, stop_time=t[-1], output_interval=t[1] - t[0], output=names),
                "C example program (DOP853 rtol 1e-12)": lambda: subprocess.run(
                    [str(example)], check=True, capture_output=True, text=True).stdout,
            }
            stats = interleaved(runs, repeats)
            print(f"\n{name}: {len(names)} coordinates, {t[-1]:g} s in {len(t) - 1} output steps")
            for label, run in runs.items():
                result = run()
                if isinstance(result, str):
                    got = _printed(result)[:, 1:]
                elif result.dtype.names:
                    got = np.column_stack([result[n] for n in names])
                else:
                    got = result
                print(f"  {label:40s} {stats[label].text()}  error {deviation(got, q):.2g}")


def _printed(text: str) -> np.ndarray:
    """The rows of the C example program's CSV output."""
    return np.array([row.split(",") for row in text.split()[1:]], dtype=float)


EXAMPLE = "C example program (Radau IIA rtol 1e-8)"


def elastic(repeats: int, baseline: str | None = None) -> None:
    """The bundled elastic helix: FMU ME/CS and the C example program against the compiled engine's run;
    ``baseline`` another build of its example program, timed beside this one's."""
    _ride("elastic helix", scenes_folder() / "trolley_elastic_helix.toml", [f"P{i}" for i in range(6)],
          lambda run: run["P"], {"rtol": 1e-10}, slice(2, None), repeats, baseline)


# the bundled helix under traction: P0 = 100 - 10 V0 N from 3 m/s
TRACTION = (('speed = "3*t + 7*sin(t/2)"', 'traction = "100 - 10*v"\ninitial_speed = 3.0'),
            ("local_curvature = false", "local_curvature = false\ntraction = true"),
            ("modal_samples = 10", "modal_samples = 0"))


def traction(repeats: int) -> None:
    """The bundled elastic helix under traction: FMU ME/CS and the C example program against the compiled engine's
    traction run (P0…P5, s, V0)."""
    text = (scenes_folder() / "trolley_elastic_helix.toml").read_text()
    for old, new in TRACTION:
        text = text.replace(old, new)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "traction_helix.toml"
        path.write_text(text)
        _ride("elastic helix under traction", path, [f"P{i}" for i in range(6)] + ["s", "V0"],
              lambda run: np.column_stack([run["P"], run["s"], run["V0"]]), {"rtol": 1e-10, "atol_q": 1e-14},
              [3, 4, 5, 6, 7, 8, 1, 2], repeats)


def _ride(title: str, path: Path, names: list[str], series, reference: dict, columns, repeats: int,
          baseline: str | None = None) -> None:
    """FMU ME/CS and the C example program of the elastic scene at ``path`` against the compiled engine's run:
    ``series(run)`` the compared columns ``names`` of a native run, ``reference`` the keywords of a tighter native
    run beside it, ``columns`` those of the example program's table; ``baseline`` another build of the example
    program, its CPU time measured beside this one's."""
    setup = pipeline.load(path).setup.elastic
    exported = command.load(path)
    t = exported.native.data[:, 0]
    tight = series(elastic_scene.simulate(setup, **reference))
    with tempfile.TemporaryDirectory() as tmp:
        me = build.fmu(exported, Path(tmp) / "me.fmu", 3, "me")
        cs = build.fmu(exported, Path(tmp) / "cs.fmu", 3, "cs")
        example = build.c_folder(exported, Path(tmp) / "c") / "example"
        runs = {
            "native, compiled engine (Radau)": lambda: series(elastic_scene.simulate(setup)),
            "FMU ME, FMPy CVode rtol 1e-10": lambda: fmpy.simulate_fmu(
                str(me), solver="CVode", relative_tolerance=1e-10, stop_time=t[-1], output_interval=t[1] - t[0],
                output=names),
            "FMU CS, Radau IIA rtol 1e-10": lambda: fmpy.simulate_fmu(
                str(cs), relative_tolerance=1e-10, stop_time=t[-1], output_interval=t[1] - t[0], output=names),
            EXAMPLE: lambda: _printed(subprocess.run(
                [str(example)], check=True, capture_output=True, text=True).stdout)[:, columns],
        }
        stats = interleaved(runs, repeats)
        native = runs["native, compiled engine (Radau)"]()
        tolerances = ", ".join(f"{k} {v:g}" for k, v in reference.items())
        print(f"\n{title}: {t[-1]:g} s in {len(t) - 1} output steps; native vs its run at {tolerances} "
              f"{deviation(native, tight):.2g}")
        for label, run in runs.items():
            result = run()
            got = np.column_stack([result[n] for n in names]) if result.dtype.names else result
            print(f"  {label:40s} {stats[label].text()}  error {deviation(got, native):.2g} "
                  f"(vs {tolerances}: {deviation(got, tight):.2g})")
        programs = {"this tree": [str(example)], **({"baseline": [baseline]} if baseline else {})}
        for label, cpu in interleaved_cpu(programs, max(repeats, 5)).items():
            print(f"  C example program, {label}: CPU {cpu.text()}, real-time factor {cpu.median / t[-1]:.3g}")


def grain(repeats: int) -> None:
    """The default grain scene over its 2 s (493 impacts through every regime): the CS FMU (FMI 3, DOP853 at
    rtol 1e-10 inside; FMPy's simulate_fmu on the sample grid) and the C example program (DOP853 rtol 1e-12)
    against the compiled engine: centres on the sample grid, and the CS FMU's impact times (its ``last_impact``
    1e-8 s after each native impact, stepped there by FMPy's Co-Simulation instance) and centres at the native
    impact times, against the compiled engine at the scene's tolerance 1e-9 and at 1e-12."""
    from symmech.grain import motion_scene

    path = scenes_folder() / "grain_default.toml"
    with tempfile.TemporaryDirectory() as tmp:
        tight_path = Path(tmp) / "grain_tight.toml"
        tight_path.write_text(path.read_text().replace("tolerance = 1e-9", "tolerance = 1e-12"))
        tight = motion_scene.simulate(pipeline.load(tight_path).setup)
        sc = pipeline.load(path).setup
        exported = command.load(path)
        t = exported.native.data[:, 0]
        cs = build.fmu(exported, Path(tmp) / "cs.fmu", 3, "cs")
        example = build.c_folder(exported, Path(tmp) / "c") / "example"
        runs = {
            "native, compiled engine": lambda: motion_scene.simulate(sc),
            "FMU CS, DOP853 rtol 1e-10": lambda: fmpy.simulate_fmu(
                str(cs), relative_tolerance=1e-10, stop_time=t[-1], output_interval=t[1] - t[0],
                output=["x", "y", "z", "impacts"]),
            "C example program (DOP853 rtol 1e-12)": lambda: _printed(subprocess.run(
                [str(example)], check=True, capture_output=True, text=True).stdout)[:, 1:4],
        }
        stats = interleaved(runs, repeats)
        native = runs["native, compiled engine"]()
        t_native = np.array([i["t"] for i in native.impacts])
        r_native = np.array([i["r"] for i in native.impacts])
        on_grid = exported.native.data[:, 1:4]
        print(f"\ngrain, default scene over {t[-1]:g} s ({len(t_native)} impacts, {native.extra['engine']} engine)")
        for label, run in runs.items():
            result = run()
            error = ""
            if label.startswith("FMU CS"):
                got = np.column_stack([result[c] for c in "xyz"])
                error = (f"{int(result['impacts'][-1])} impacts; centres on the sample grid "
                         f"{np.abs(got - on_grid).max():.2g} m; {_cs_impacts(cs, t_native, r_native)}; against the "
                         "native run at tol 1e-12: " + _cs_impacts(cs, np.array([i["t"] for i in tight.impacts]),
                                                                   np.array([i["r"] for i in tight.impacts])))
            elif label.startswith("C example"):
                error = f"centres on the sample grid {np.abs(result - on_grid).max():.2g} m"
            print(f"  {label:40s} {stats[label].text()}  {error}")


def _cs_impacts(fmu: Path, t_native: np.ndarray, r_native: np.ndarray, delta: float = 1e-8) -> str:
    """The CS FMU's (FMI 3) impact times and centres against the native ones: stepped to delta [s] before, at and
    after each native impact, its count must rise there; its ``last_impact`` after it and its centre at it."""
    from fmpy.fmi3 import FMU3Slave

    md = fmpy.read_model_description(str(fmu))
    slave = FMU3Slave(guid=md.guid, unzipDirectory=fmpy.extract(str(fmu)),
                      modelIdentifier=md.coSimulation.modelIdentifier)
    slave.instantiate()
    slave.enterInitializationMode(tolerance=1e-10, startTime=0.0)
    slave.exitInitializationMode()
    vr = [{v.name: v.valueReference for v in md.modelVariables}[n] for n in ("x", "y", "z", "impacts", "last_impact")]
    t, dt, dr, outside = 0.0, [], [], 0
    for k, t_k in enumerate(t_native):
        seen = []
        for point in (t_k - delta, t_k, t_k + delta):
            slave.doStep(t, point - t)
            t = point
            seen.append(slave.getFloat64(vr))
        outside += not (seen[0][3] == k and seen[2][3] == k + 1)
        dt.append(abs(seen[2][4] - t_k))
        dr.append(np.abs(np.array(seen[1][:3]) - r_native[k]).max())
    slave.terminate()
    slave.freeInstance()
    n = min(50, len(dt))
    return (f"impact times first {n} {max(dt[:n]):.2g} s, all {max(dt):.2g} s; centres first {n} {max(dr[:n]):.2g} m, "
            f"all {max(dr):.2g} m; {outside} impacts outside +-{delta:g} s")


def grain_sliding(repeats: int) -> None:
    """The default grain scene through its landings, slips, sticks and lift-offs, over 0.23 s (its first 50
    impacts) and 2 s: the ME FMU's impact times and centres under FMPy's CVode at rtol 1e-10 and at the FMU's
    DefaultExperiment tolerance (1e-12: simulate_fmu without relative_tolerance) against the compiled engine at the
    scene's tolerance 1e-9 and at 1e-12."""
    from symmech.grain import motion_scene

    def impacts(run) -> tuple[np.ndarray, np.ndarray]:
        return np.array([i["t"] for i in run.impacts]), np.array([i["r"] for i in run.impacts])

    for duration in (0.23, 2.0):
        text = (scenes_folder() / "grain_default.toml").read_text().replace("duration = 2.0 ",
                                                                          f"duration = {duration!r} ")
        with tempfile.TemporaryDirectory() as tmp:
            path, tight_path = Path(tmp) / "grain.toml", Path(tmp) / "grain_tight.toml"
            path.write_text(text)
            tight_path.write_text(text.replace("tolerance = 1e-9", "tolerance = 1e-12"))
            sc = pipeline.load(path).setup
            tight = impacts(motion_scene.simulate(pipeline.load(tight_path).setup))
            fmu = build.fmu(command.load(path), Path(tmp) / "me.fmu", 3, "me")
            runs = {"native, compiled engine (tol 1e-9)": lambda: motion_scene.simulate(sc)}
            for rtol in (1e-10, None):
                label = f"rtol {rtol:g}" if rtol else "at its default (1e-12)"
                runs[f"FMU ME, FMPy CVode {label}"] = lambda rtol=rtol: fmpy.simulate_fmu(
                    str(fmu), solver="CVode", relative_tolerance=rtol, stop_time=duration,
                    output_interval=duration / 50, output=["x", "y", "z", "impacts"], record_events=True)
            stats = interleaved(runs, repeats)
            native = impacts(runs["native, compiled engine (tol 1e-9)"]())
            print(f"\ngrain through its sliding regimes, default scene over {duration:g} s ({len(native[0])} impacts); "
                  f"native at tol 1e-9 vs 1e-12: {_impact_errors(native, tight)}")
            for label, run in runs.items():
                result = run()
                if label.startswith("native"):
                    print(f"  {label:40s} {stats[label].text()}")
                    continue
                at = np.flatnonzero((np.diff(result["time"]) == 0) & (np.diff(result["impacts"]) > 0))
                got = result["time"][at], np.column_stack([result[c][at] for c in "xyz"])
                print(f"  {label:40s} {stats[label].text()}  {len(at)} impacts; vs native "
                      f"{_impact_errors(got, native)}; vs native at 1e-12 {_impact_errors(got, tight)}")


def _impact_errors(got: tuple[np.ndarray, np.ndarray], reference: tuple[np.ndarray, np.ndarray]) -> str:
    """The largest time [s] and centre [m] errors of the first 50 impacts of ``got`` (times, centres) against
    ``reference``, and of all of them when there are more."""
    if len(got[0]) != len(reference[0]):
        return f"{len(got[0])} impacts against {len(reference[0])}"
    text = []
    for n in sorted({min(50, len(got[0])), len(got[0])}):
        dt = np.abs(got[0][:n] - reference[0][:n]).max()
        dr = np.abs(got[1][:n] - reference[1][:n]).max()
        text.append(f"first {n}: times {dt:.2g} s, centres {dr:.2g} m")
    return "; ".join(text)


if __name__ == "__main__":
    main()
