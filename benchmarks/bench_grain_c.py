"""The grain scene's exported C model as an engine: what its build costs beside numba's, how fast it runs the
scene and how close its impacts come to the compiled engine's.

``symmech export c`` writes a grain scene's model as C99: the generated flight, impact and sliding modules, the
hand-written event glue and the generic DOP853 / Radau IIA of ``symmech_model.c``. This script builds those sources
with a small timing program of its own (written next to them: it runs the scene from its start values to the
scene's duration with no output, ``runs`` times, and prints its CPU per run from ``clock()``; with ``--log`` it
prints each impact's time instead, caught by wrapping the model's event update at link time), then measures, side
by side in interleaved rounds:

- the C compile (``cc -std=c99 -O2`` of the model and the program, the Makefile's flags): CPU of the compiler;
- a run of the scene: the C program (its own clock, median of its runs) against ``motion_scene.simulate`` on the
  compiled engine (numba, its cache warm: run ``symmech warm --engine grain`` first), CPU per run;
- the impact times of both at each tolerance (the C program's DOP853 rtol = the engine's ``numerics.tolerance``).

Run: python benchmarks/bench_grain_c.py [--scene scenes/grain_default.toml] [--repeats 5] [--runs 20]
"""
from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from timing import Stats, child_cpu, machine

from symmech.core import pipeline
from symmech.grain import motion_scene
from symmech.grain.motion_engine import driver

TOLERANCES = (1e-9, 1e-10, 1e-12)
ATOL = 1e-15  # the C program's absolute tolerance: the example program's; the relative one decides
CFLAGS = ["-std=c99", "-O2"]

PROGRAM = r"""
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "symmech_model.h"
FILE *impact_log = NULL;
int model_update(double t, double *y, double *p);
/* the model's event update (renamed model_update at compile time), its impacts logged */
int grain_event_update(double t, double *y, double *p)
{
    double before = p[N_P + D_IMPACTS];
    int status = model_update(t, y, p);
    if (impact_log && p[N_P + D_IMPACTS] > before) fprintf(impact_log, "%.17g\n", t);
    return status;
}
static void quiet(void *env, double t, const char *message) { (void)env; (void)t; (void)message; }
int main(int argc, char **argv)
{
    double rtol = atof(argv[1]), t_end = atof(argv[2]);
    int runs = atoi(argv[3]), log = argc > 4;
    static SymmechModel m;
    clock_t start = clock();
    for (int k = 0; k < runs; k++) {
        impact_log = log ? stdout : NULL;
        symmech_reset(&m);
        m.notice = quiet;
        m.horizon = t_end;
        if (symmech_start(&m) != 0 || symmech_integrate(&m, t_end, rtol, %ATOL%) < 0) return 1;
    }
    if (!log) printf("%.9g %d\n", (double)(clock() - start) / CLOCKS_PER_SEC / runs, (int)m.r[VR_D + D_IMPACTS]);
    return 0;
}
"""


def discrete_index(model_h: str, name: str) -> int:
    """The index of discrete state ``name`` among the N_D, from model.h's variable listing and its VR_D."""
    first = int(re.search(r"#define VR_D (\d+)", model_h).group(1))
    listed = (line.split() for line in model_h.splitlines() if line.startswith("     "))
    return next(int(words[0]) for words in listed if words[1:2] == [name]) - first


def export(scene: str, folder: Path) -> float:
    """``symmech export c`` of the scene into ``folder``; its CPU (the export and its example's compile)."""
    cpu, _ = child_cpu([sys.executable, "-m", "symmech", "export", "c", scene, "--out", str(folder)],
                       capture_output=True)
    return cpu


def compile_program(folder: Path) -> float:
    """Write the timing program and compile it with the model: the CPU of ``cc``."""
    model_h = (folder / "model.h").read_text()
    source = PROGRAM.replace("%ATOL%", repr(ATOL)).replace(
        "#include <time.h>", f"#include <time.h>\n#define D_IMPACTS {discrete_index(model_h, 'impacts')}")
    (folder / "timing.c").write_text(source)
    sources = ["symmech_model.c", "grain_motion.c", "grain_sliding.c"]
    cpu, _ = child_cpu(["cc", *CFLAGS, "-c", "-Dgrain_event_update=model_update", "grain.c", "-o", "grain.o"],
                       cwd=folder)
    more, _ = child_cpu(["cc", *CFLAGS, "-o", "timing", "timing.c", "grain.o", *sources, "-lm"], cwd=folder)
    return cpu + more


def c_run(folder: Path, rtol: float, t_end: float, runs: int) -> tuple[float, int]:
    """CPU seconds per run of the C program (its own clock) and its impact count."""
    out = subprocess.run([str(folder / "timing"), repr(rtol), repr(t_end), str(runs)], check=True,
                         capture_output=True, text=True).stdout.split()
    return float(out[0]), int(out[1])


def c_impacts(folder: Path, rtol: float, t_end: float) -> np.ndarray:
    out = subprocess.run([str(folder / "timing"), repr(rtol), repr(t_end), "1", "log"], check=True,
                         capture_output=True, text=True).stdout
    return np.array([float(x) for x in out.split()])


def native_run(sc, tol: float, runs: int) -> tuple[float, np.ndarray]:
    """CPU seconds per ``motion_scene.simulate`` on the compiled engine, and its impact times."""
    num = replace(sc.numerics, tolerance=tol, engine="compiled")
    start = time.process_time()
    for _ in range(runs):
        m = motion_scene.simulate(sc, num)
    return (time.process_time() - start) / runs, np.asarray(m.impact_times())


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scene", default="scenes/grain_default.toml")
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--runs", type=int, default=20, help="runs of the scene per round and contender")
    a = p.parse_args()
    if driver.ENGINE.cold():
        sys.exit("the compiled grain engine is not built: run `symmech warm --engine grain` first")
    sc = pipeline.load(a.scene).setup
    t_end = sc.duration
    print(machine())
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        print(f"symmech export c {a.scene}: {export(a.scene, folder):.2f} s CPU (its example program compiled)")
        builds = Stats.of([compile_program(folder) for _ in range(a.repeats)])
        print(f"cc {' '.join(CFLAGS)} of the model and the timing program: {builds.text()}")
        for tol in TOLERANCES:
            c_times, n_times, counts = [], [], set()
            for _ in range(a.repeats):
                cpu, count = c_run(folder, tol, t_end, a.runs)
                c_times.append(cpu)
                counts.add(count)
                n_times.append(native_run(sc, tol, a.runs)[0])
            c_stats, n_stats = Stats.of(c_times), Stats.of(n_times)
            c_imp, n_imp = c_impacts(folder, tol, t_end), native_run(sc, tol, 1)[1]
            k = min(len(c_imp), len(n_imp))
            dev = np.abs(c_imp[:k] - n_imp[:k]).max() if k else float("nan")
            print(f"tolerance {tol:g}: C {c_stats.text('ms', 1e3)}, compiled engine {n_stats.text('ms', 1e3)}, "
                  f"C / engine {c_stats.median / n_stats.median:.2f}; impacts C {sorted(counts)} / engine "
                  f"{len(n_imp)}, largest |t_C - t_engine| over the first {k}: {dev:.2e} s")


if __name__ == "__main__":
    main()
