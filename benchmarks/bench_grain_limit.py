"""The grain engine against its limit: spheres through the public API vs a plain-Python exact flight + brentq,
the layers between a scene and the compiled loop, and a floor measured with the generated kernels alone.

All times are CPU seconds (``time.process_time``: the 2 cores are shared), medians of interleaved repeats
with min/max; every contender runs once per round. Each sphere's impact times are checked against the
reference (tolerance 1e-13) beside its time.

- population: N spheres (random start height and speed), each 20 periods, through ``motion_scene.simulate``
  (the per-grain API), ``motion_scene.simulate_many`` (the population API, one thread), ``compiled.simulate_many``
  (2 threads) and the brentq reference: impacts per CPU-second;
- one sphere, 20 impacts: the same API, ``compiled.simulate``, the compiled loop alone (packed arguments
  reused: no set-up, no result), the floor and the brentq reference, in ms per run;
- per-impact breakdown of the floor: root finding (scan + Brent on the exact gap, the generated
  ``flight_translation_into``) and the impact map (restitution on the relative velocity); bookkeeping is
  the loop alone minus the floor;
- the exact-flight floor (``free_flight_nb``: closed-form translation and rotation, the search certified by
  the gap's curvature bound, Brent) on the same sphere and on a tumbling asymmetric ellipsoid, per impact: root
  finding, impact map (state at contact, restitution, the next flight's records), bookkeeping (the rest);
- ``--flights``: the compiled loop's exact flight (``Numerics.flight = "exact"``) against its DOP853 flight and
  the reference, impacts per CPU-second and impact-time errors: one sphere, a tumbling asymmetric ellipsoid, the
  default scene on one thread, a population of spheres through the public API.

Run: python benchmarks/bench_grain_limit.py [--quick] [--repeats 5] [--exact-flight-only | --flights | --population]
"""
from __future__ import annotations

import argparse
import math
import time
from dataclasses import replace

import numba
import numpy as np

from timing import Stats, machine, ratio

from bench_grain_motion import exact_flight_brentq, sphere_scene

from symmech.generated import grain_motion_nb as gm_nb
from symmech.core import pipeline
from symmech.core.scene import SymmechError
from symmech.grain import contact, flight, free_flight, motion, motion_scene
from symmech.grain import free_flight_nb as ff_nb
from symmech.grain.motion_engine import driver as compiled, loop as compiled_loop
from symmech.grain.motion_engine.layouts import CARRY, IMPACT_WIDTH, PHASES_PER_CALL, STATE, TRAJECTORY_WIDTH
from symmech.numerics.brent import roots

PERIODS = 20.5  # 20 impacts of the period-1 orbit
XTOL = 1e-12  # brentq's and the floor's time tolerance [s]


def cpu_interleaved(contenders: dict, repeats: int, number: int = 1) -> dict[str, Stats]:
    """As ``timing.interleaved`` in CPU seconds of this process (all threads) per call."""
    samples = {name: [] for name in contenders}
    for _ in range(repeats):
        for name, fn in contenders.items():
            start = time.process_time()
            for _ in range(number):
                fn()
            samples[name].append((time.process_time() - start) / number)
    return {name: Stats.of(s) for name, s in samples.items()}


# --------------------------------------------------------------------------- the floor: kernels alone


@numba.njit(cache=True)
def _gap(s, t, out):
    """Gap [m] of the sphere (radius s[15]) at t from the flight state s (16,): the generated exact flight."""
    gm_nb.flight_translation_into(s[0], s[1], s[2], s[3], s[4], s[5], s[6], s[7], s[8], s[9], s[10], s[11],
                                  s[12], s[13], s[14], s[16], t, out)
    return out[0, 0, 2] - s[15]


@numba.njit(cache=True)
def _gap_of(t, args):
    """The gap [m] at t as the root finder calls it (``args`` = (s, out))."""
    return _gap(args[0], t, args[1])


_bracketed = roots(_gap_of).bracketed  # the toolkit's brentq, as the engine's


@numba.njit(cache=True)
def _next_impact(s, t_end, step, xtol, out):
    """The first root of the gap after s[16] (scan at ``step``, Brent), or nan before t_end."""
    a = s[16] + 1e-3 * step  # just after the last impact: the grain leaves the plate
    fa = _gap(s, a, out)
    while a < t_end:
        b = min(a + step, t_end)
        fb = _gap(s, b, out)
        if fb <= 0.0:
            return _bracketed(a, b, fa, fb, xtol, (s, out))
        a, fa = b, fb
    return math.nan


@numba.njit(cache=True)
def _impact_map(s, t, e, out):
    """Restitution at t: the flight state s restarts from the contact with -e times the relative velocity."""
    _gap(s, t, out)
    for k in range(3):
        s[k] = out[0, 0, k]
        s[3 + k] = out[0, 1, k]
    s[5] = -e * s[5]
    s[16] = t


@numba.njit(cache=True)
def floor_run(s0, t_end, step, xtol, e, times):
    """The whole sphere run with the kernels alone: impact times into ``times``; their count."""
    s = s0.copy()
    out = np.empty((1, 2, 3))
    n = 0
    while n < times.size:
        t = _next_impact(s, t_end, step, xtol, out)
        if math.isnan(t):
            break
        times[n] = t
        _impact_map(s, t, e, out)
        n += 1
    return n


@numba.njit(cache=True)
def floor_roots(s_at, t_end, step, xtol, times):
    """Root finding alone: the next impact from each stored post-impact state (rows of s_at)."""
    out = np.empty((1, 2, 3))
    for k in range(s_at.shape[0]):
        times[k] = _next_impact(s_at[k], t_end, step, xtol, out)


@numba.njit(cache=True)
def floor_maps(s_at, times, e):
    """The impact map alone on stored pre-impact states (rows of s_at) at their impact times."""
    out = np.empty((1, 2, 3))
    s = np.empty(s_at.shape[1])
    for k in range(s_at.shape[0]):
        s[:] = s_at[k]
        _impact_map(s, times[k], e, out)


def flight_state(model: motion.Model, st: motion.State) -> np.ndarray:
    """The floor's state (17,): r, v relative, gravity, vibration, radius, t0."""
    vib = model.vibration
    return np.array([*st.r, *st.v, *model.g_k, vib.amplitude, vib.omega, vib.phase, *vib.direction,
                     model.axes[0], st.t])


def floor_states(s0, times, e):
    """The post-impact flight states (n + 1, 17) before each root search of a floor run."""
    out, s, rows = np.empty((1, 2, 3)), s0.copy(), [s0.copy()]
    for t in times:
        _impact_map(s, t, e, out)
        rows.append(s.copy())
    return np.array(rows)


# --------------------------------------------------------------------------- the exact-flight floor


@numba.njit(cache=True)
def exact_map(st, t, e, env, fl, rot):
    """Impact map of the exact-flight floor: the state at ``t`` into ``st``; the lowest point's normal velocity
    u = v_z + n.(w x R) (R = -D^2 n / |D n| in body axes) turned into -e u through the centre's alone (spin
    kept: a timing model, not the scene's law); the next flight's records. ``env``: g (3), A, omega, phase,
    direction (3), axes (3), inertia (3)."""
    ff_nb.flight_state(t, fl, rot, st)
    q0, q1, q2, q3 = st[7], st[8], st[9], st[10]
    n = (2.0 * (q1 * q3 - q0 * q2), 2.0 * (q2 * q3 + q0 * q1), q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3)
    d = (env[9] ** 2 * n[0], env[10] ** 2 * n[1], env[11] ** 2 * n[2])
    s = math.sqrt(d[0] * n[0] + d[1] * n[1] + d[2] * n[2])
    w = (st[11], st[12], st[13])
    # n.(w x R) with R = -d / s
    u = st[6] - (n[0] * (w[1] * d[2] - w[2] * d[1]) + n[1] * (w[2] * d[0] - w[0] * d[2])
                 + n[2] * (w[0] * d[1] - w[1] * d[0])) / s
    st[6] -= (1.0 + e) * u
    ff_nb.flight_setup(st, env[0:3], env[3], env[4], env[5], env[6:9], env[9:12], env[12:15], fl, rot)


@numba.njit(cache=True)
def exact_floor_run(st0, env, t_end, step, xtol, e, times):
    """The whole run on the exact-flight kernels: impact times into ``times``; their count."""
    fl, rot = np.empty(ff_nb.FLIGHT_SIZE), np.empty(ff_nb.ROTATION_SIZE)
    st, buf = st0.copy(), np.empty((1, 2, 3))
    ff_nb.flight_setup(st, env[0:3], env[3], env[4], env[5], env[6:9], env[9:12], env[12:15], fl, rot)
    t_from, n = st[0] + 1e-3 * step, 0  # just after the start: the grain leaves the plate
    while n < times.size and ff_nb.gap(t_from, fl, rot, buf)[0] > 0.0:  # not resting on the plate
        t = ff_nb.next_contact(fl, rot, t_from, t_end, step, xtol, buf)
        if math.isnan(t):
            break
        times[n] = t
        n += 1
        exact_map(st, t, e, env, fl, rot)
        t_from = t + 1e-3 * step
    return n


@numba.njit(cache=True)
def exact_floor_roots(fls, rots, t_from, t_end, step, xtol, times):
    """Root finding alone: the next contact of each stored flight (rows of fls, rots) from t_from."""
    buf = np.empty((1, 2, 3))
    for k in range(fls.shape[0]):
        times[k] = ff_nb.next_contact(fls[k], rots[k], t_from[k], t_end, step, xtol, buf)


@numba.njit(cache=True)
def exact_floor_maps(fls, rots, times, e, env):
    """The impact map alone on each stored flight at its contact time."""
    st, fl, rot = np.empty(14), np.empty(ff_nb.FLIGHT_SIZE), np.empty(ff_nb.ROTATION_SIZE)
    for k in range(times.size):
        fl[:] = fls[k]
        rot[:] = rots[k]
        exact_map(st, times[k], e, env, fl, rot)


def exact_floor_flights(st0, env, times, e, step):
    """The records of every flight of a run (n + 1 rows each) and the start of each search."""
    fl, rot, st = np.empty(ff_nb.FLIGHT_SIZE), np.empty(ff_nb.ROTATION_SIZE), st0.copy()
    ff_nb.flight_setup(st, env[0:3], env[3], env[4], env[5], env[6:9], env[9:12], env[12:15], fl, rot)
    fls, rots, starts = [fl.copy()], [rot.copy()], [st0[0] + 1e-3 * step]
    for t in times:
        exact_map(st, t, e, env, fl, rot)
        fls.append(fl.copy())
        rots.append(rot.copy())
        starts.append(t + 1e-3 * step)
    return np.array(fls), np.array(rots), np.array(starts)


def python_exact_times(model, st0, t_end, step, n):
    """The same run on the scipy reference (free_flight.ExactRotation, contact.first_contact): impact times."""
    vib, axes, inertia, e = model.vibration, model.axes, model.inertia, model.law.e_n
    st, times = st0, []
    while len(times) < n:
        rot = free_flight.ExactRotation(inertia, st.q, st.w, st.t)

        def gap(t, st=st, rot=rot):
            (r, v), (q, w) = flight.translate(st.r, st.v, model.g_k, vib, st.t, t), rot.state(t)
            Q = flight.rotation_matrix(q)
            return float(r[2] - contact.support_distance(axes, Q)), float(free_flight.gap_rate(v[2], axes, Q[2], w))

        curvature = free_flight.gap_curvature_bound(model.g_k[2], vib, axes, inertia, rot.max_rate)
        t = contact.first_contact(gap, curvature, st.t + 1e-3 * step, t_end, step, XTOL)
        if t is None:
            break
        times.append(t)
        r, v = flight.translate(st.r, st.v, model.g_k, vib, st.t, t)
        q, w = rot.state(t)
        Q = flight.rotation_matrix(q)
        u = float(v[2] + np.cross(Q @ w, contact.contact_offset(axes, Q))[2])
        st = motion.State(t, r, np.array([v[0], v[1], v[2] - (1 + e) * u]), q, w)
    return np.array(times)


def tumbling_ellipsoid():
    """The sphere scene's plate with an asymmetric ellipsoid (3.5, 1.6, 1.4) mm spinning at (40, 60, 90) rad/s,
    restitution 0.9 (it keeps bouncing)."""
    model, st = sphere_scene()
    axes = (3.5e-3, 1.6e-3, 1.4e-3)
    model = replace(model, axes=axes, mass=1300 * 4 / 3 * math.pi * math.prod(axes),
                    law=replace(model.law, e_n=0.9), effects=motion.Effects(rotation=True))
    return model, replace(st, r=np.array([0.0, 0.0, 4e-3]), w=np.array([40.0, 60.0, 90.0]))


def exact_env(model):
    vib = model.vibration
    return np.array([*model.g_k, vib.amplitude, vib.omega, vib.phase, *vib.direction, *model.axes, *model.inertia])


def exact_flight_floor(repeats: int, floor_us: float | None):
    """Per impact on the exact-flight kernels: the sphere (against the generated-kernel floor) and a tumbling
    ellipsoid (impact times checked against the scipy reference)."""
    print("exact-flight floor (free_flight_nb), per impact (CPU us, medians):")
    for label, (model, st) in (("sphere", sphere_scene()), ("tumbling ellipsoid", tumbling_ellipsoid())):
        T, e, env = model.period, model.law.e_n, exact_env(model)
        t_end, step = PERIODS * T, T / 40
        st0 = np.array([st.t, *st.r, *st.v, *st.q, *st.w])
        times = np.empty(64)
        n = exact_floor_run(st0, env, t_end, step, XTOL, e, times)
        times = times[:n]
        ref = python_exact_times(model, st, t_end, step, n)
        error = float(np.max(np.abs(times - ref)) / T) if len(ref) == n else math.inf
        if label == "sphere":  # and against the plain-Python parabola + brentq, independent of the rotation
            plain = np.array(exact_flight_brentq(model, st, t_end, XTOL))
            print(f"  sphere vs plain-Python parabola + brentq: impact-time error "
                  f"{float(np.max(np.abs(times - plain[:n])) / T):.1e} T")
        fls, rots, starts = exact_floor_flights(st0, env, times, e, step)
        at, out = np.empty(len(fls)), np.empty(64)
        stats = cpu_interleaved({
            "whole run": lambda: exact_floor_run(st0, env, t_end, step, XTOL, e, out),
            "root finding": lambda: exact_floor_roots(fls, rots, starts, t_end, step, XTOL, at),
            "impact map": lambda: exact_floor_maps(fls, rots, times, e, env)}, repeats, number=200)
        whole = stats["whole run"].median * 1e6 / n
        roots = stats["root finding"].median * 1e6 / len(fls)
        maps = stats["impact map"].median * 1e6 / n
        print(f"  {label}, {n} impacts in {PERIODS} periods (impact-time error vs the scipy reference {error:.1e} T):")
        print(f"    root finding (certified scan + Brent on the closed-form gap)  {roots:8.2f}"
              f"  ({stats['root finding'].text('us', 1e6 / len(fls))})")
        print(f"    impact map (state at contact, restitution, next records)      {maps:8.2f}")
        print(f"    bookkeeping (whole run - roots - maps)                        {whole - roots - maps:8.2f}")
        print(f"    whole run per impact                                          {whole:8.2f}  -> "
              f"{1e6 / whole:,.0f} impacts per CPU-second")
        if label == "sphere" and floor_us is not None:
            print(f"    vs the generated-kernel floor ({floor_us:.2f} us): {floor_us / whole:.2f}x its speed")
    print()


# --------------------------------------------------------------------------- contenders


def sphere_grain(k: int):
    """Sphere k of the population: the period-1 scene started at a random height (0-0.3 mm) and speed (+-3 %): all stay on bouncing orbits (the reference has no sliding)."""
    model, st = sphere_scene()
    rng = np.random.default_rng(k)
    st = replace(st, r=st.r + np.array([0.0, 0.0, rng.uniform(0, 0.3e-3)]),
                 v=st.v * rng.uniform(0.97, 1.03))
    return model, st


def scene_of(model, st, num):
    return motion_scene.GrainScene(model, replace(num, engine="compiled"), st, PERIODS * model.period,
                                   (0.0, 0.0), {}, {})


def loop_alone(model, num, st, t_end):
    """The compiled loop with its arguments packed once: each call copies the state and carry only."""
    built = compiled.ENGINE.ahead_of_time()
    run = built.run if built is not None else compiled_loop.run
    p = compiled.pack(model, num)
    y0 = STATE.pack(t=st.t, r=st.r, v=st.v, q=st.q, w=(0.0, 0.0, 0.0))
    rows = np.empty((int(t_end / num.sample_interval) + 64, TRAJECTORY_WIDTH))
    imps, warns = np.empty((64, IMPACT_WIDTH)), np.empty((8, 3))

    def call():
        return run(p, y0.copy(), t_end, rows, imps, warns, CARRY.zeros(), PHASES_PER_CALL)
    return call


def one_sphere(repeats: int):
    model, st = sphere_scene()
    T = model.period
    t_end = PERIODS * T
    base = motion.Numerics(scan_step=T / 40, sample_interval=T, engine="compiled")
    ref = np.array([i["t"] for i in motion.simulate(model, replace(base, tolerance=1e-13), st, t_end).impacts])
    num = replace(base, tolerance=1e-10)
    dop853 = replace(num, flight="dop853")  # the path before the closed form became the default for spheres
    sc = scene_of(model, st, num)
    s0 = flight_state(model, st)
    times = np.empty(64)
    loop = loop_alone(model, num, st, t_end)
    runs = {"public API motion_scene.simulate": lambda: motion_scene.simulate(sc),
            "compiled.simulate": lambda: compiled.simulate(model, num, st, t_end),
            "compiled.simulate, DOP853 flight": lambda: compiled.simulate(model, dop853, st, t_end),
            "compiled loop alone": loop,
            "floor: generated kernels + Brent": lambda: floor_run(s0, t_end, T / 40, XTOL, model.law.e_n, times),
            "plain Python flight + brentq": lambda: exact_flight_brentq(model, st, t_end, XTOL)}
    n = floor_run(s0, t_end, T / 40, XTOL, model.law.e_n, times)
    got = {"public API motion_scene.simulate": [i["t"] for i in runs["public API motion_scene.simulate"]().impacts],
           "compiled.simulate": [i["t"] for i in runs["compiled.simulate"]().impacts],
           "compiled.simulate, DOP853 flight": [i["t"] for i in runs["compiled.simulate, DOP853 flight"]().impacts],
           "floor: generated kernels + Brent": times[:n],
           "plain Python flight + brentq": runs["plain Python flight + brentq"]()}
    loop()
    stats = cpu_interleaved(runs, repeats, number=20)
    print(f"one sphere, {len(ref)} impacts in {PERIODS} periods (CPU ms per run; impact-time error / T):")
    for label, s in stats.items():
        g = np.asarray(got.get(label, got["compiled.simulate"]))
        error = float(np.max(np.abs(g - ref)) / T) if len(g) == len(ref) else math.inf
        print(f"  {label:<36} {s.text('ms', 1e3)}  error {error:.1e}")
    brent = stats["plain Python flight + brentq"]
    for label in ("public API motion_scene.simulate", "compiled.simulate", "compiled.simulate, DOP853 flight",
                  "compiled loop alone", "floor: generated kernels + Brent"):
        print(f"  time / reference's, {label:<34} {stats[label].median / brent.median:6.3f} "
              f"(reference / this {ratio(brent, stats[label])})")
    print("  (target: public API <= 0.5 of the reference's time)")
    return stats, len(ref), s0, times[:n], model


def breakdown(stats, impacts, s0, times, model, repeats):
    """Per impact: the layers between the API and the loop, and the floor's root finding and impact map."""
    T = model.period
    pre = floor_states(s0, times, model.law.e_n)  # the flight state before each root search (n + 1, 17)
    at = np.empty(len(pre))
    parts = cpu_interleaved({"root finding": lambda: floor_roots(pre, PERIODS * T, T / 40, XTOL, at),
                             "impact map": lambda: floor_maps(pre[:-1], times, model.law.e_n)}, repeats, number=200)
    us = 1e6 / impacts
    api, sim, loop, floor = (stats[k].median * us for k in ("public API motion_scene.simulate",
                                                            "compiled.simulate", "compiled loop alone",
                                                            "floor: generated kernels + Brent"))
    roots, maps = parts["root finding"].median * 1e6 / len(pre), parts["impact map"].median * 1e6 / len(times)
    print(f"per impact (CPU us, medians; {impacts} impacts a run):")
    print(f"  public API set-up and results (API - compiled.simulate)  {api - sim:8.2f}")
    print(f"  compiled.simulate's packing and results (- loop alone)    {sim - loop:8.2f}")
    print(f"  loop bookkeeping and its flight/contact (loop - floor)    {loop - floor:8.2f}")
    print(f"  floor: root finding (scan + Brent on the exact gap)       {roots:8.2f}")
    print(f"  floor: impact map                                         {maps:8.3f}")
    print(f"  floor, whole run per impact                               {floor:8.2f}")
    print(f"  -> the API's run per impact is {api / floor:.1f}x the floor's; floor limit "
          f"{1e6 / floor:,.0f} impacts per CPU-second\n")
    return floor


def population_loop(grains, num, t_end):
    """The compiled population loop alone (``run_many``), its arguments packed once: no set-up, no results."""
    models, starts = [m for m, _ in grains], [st for _, st in grains]
    ps = np.array([compiled.pack(m, num) for m in models])
    ys = compiled.start_vectors(models, starts)
    run_many, hint = compiled.entry_many(), compiled.row_hint(t_end, num)

    def call():
        return run_many(ps, ys.copy(), np.full(len(grains), t_end), hint, np.zeros((len(grains), CARRY.size)),
                        np.empty(len(grains), np.int64))
    return call


def every_field(m: motion.Motion) -> tuple:
    """What a sweep reads of a result and more: every field (the impact times, not the log's dicts)."""
    return m.trajectory, m.impact_times(), m.time_in, m.warnings, m.start, m.final, m.extra


def population(n: int, repeats: int):
    """Impacts per CPU-second of n spheres: the public API grain by grain and as a population (impact times read
    from the results, as the reference returns them; every field of each result read; and with each result's
    impact log built, a dict per impact), the engine's threads, the compiled loop alone, the reference; the
    largest impact-time error."""
    grains = [sphere_grain(k) for k in range(n)]
    T = grains[0][0].period
    num = motion.Numerics(scan_step=T / 40, sample_interval=T, tolerance=1e-10, engine="compiled")
    scenes = [scene_of(m, st, num) for m, st in grains]
    t_end = PERIODS * T
    loop = population_loop(grains, num, t_end)
    runs = {
        "public API motion_scene.simulate, per grain": lambda: [motion_scene.simulate(sc).impact_times()
                                                                 for sc in scenes],
        "public API motion_scene.simulate_many": lambda: [m.impact_times()
                                                          for m in motion_scene.simulate_many(scenes, workers=1)],
        "simulate_many, every field read": lambda: [every_field(m)[1]  # its impact times
                                                     for m in motion_scene.simulate_many(scenes, workers=1)],
        "simulate_many, each impact log built": lambda: [[i["t"] for i in m.impacts]
                                                          for m in motion_scene.simulate_many(scenes, workers=1)],
        "compiled.simulate_many, 2 threads": lambda: [m.impact_times() for m in compiled.simulate_many(
            [m for m, _ in grains], num, [st for _, st in grains], t_end, workers=2)],
        "compiled population loop alone": loop,
        "plain Python flight + brentq": lambda: [exact_flight_brentq(m, st, t_end, XTOL) for m, st in grains]}
    got = {label: run() for label, run in runs.items() if label != "compiled population loop alone"}
    ref = got["plain Python flight + brentq"]
    impacts = sum(len(times) for times in ref)
    stats = cpu_interleaved(runs, repeats)
    print(f"population of {n} spheres x {PERIODS} periods, {impacts} impacts (impacts per CPU-second; CPU s per "
          f"population; largest impact-time error / T against the reference):")
    base = stats["plain Python flight + brentq"]
    for label, s in stats.items():
        errors = [np.max(np.abs(np.asarray(a) - b), initial=0.0) / T if len(a) == len(b) else math.inf
                  for a, b in zip(got.get(label, ref), ref)]
        error = f"error {max(errors):.1e}" if label in got else "(no results)"
        print(f"  {label:<44} {impacts / s.median:>10,.0f} /s  {ratio(base, s)} the reference  ({s.text()})  {error}")
    print("  (target: >= 5x the reference, >= 2.5e5 impacts per CPU-second)\n")


# --------------------------------------------------------------------------- the compiled loop's two flights


def flight_case(label, runs, impacts, errors, unit="ms", scale=1e3, repeats=5, number=1):
    """Time the contenders (label -> call) interleaved and print CPU per run, impacts per CPU-second, the error
    (label -> impact-time error / T) and each one's time over the DOP853 flight's."""
    stats = cpu_interleaved(runs, repeats, number)
    dop = stats["compiled, DOP853 flight"]
    print(f"{label} (CPU {unit} per run; impacts per CPU-second; impact-time error / T):")
    for name, st in stats.items():
        print(f"  {name:<36} {st.text(unit, scale)}  {impacts[name] / st.median:>10,.0f} /s  error "
              f"{errors[name]:.1e}  time / DOP853's {st.median / dop.median:5.2f}")
    return stats


def max_error(times, ref, period):
    times, ref = np.asarray(times), np.asarray(ref)
    return float(np.max(np.abs(times - ref)) / period) if len(times) == len(ref) and len(ref) else math.inf


def compiled_times(model, num, st, t_end):
    return [i["t"] for i in compiled.simulate(model, num, st, t_end).impacts]


def default_grain(sc, k: int) -> motion.State:
    """Grain k of a population around the default scene: start height, velocity and spin drawn with seed k (as
    ``bench_grain_motion.py``'s population)."""
    rng = np.random.default_rng(k)
    return replace(sc.start, r=sc.start.r + np.array([0.0, 0.0, rng.uniform(0, 3e-3)]),
                   v=rng.normal(scale=0.05, size=3), w=rng.normal(scale=20, size=3))


def population_run(model, num, starts, duration):
    """A call running every start one after another on one thread: its impact count (a grain a guard stops
    counts none)."""
    def run():
        total = 0
        for st in starts:
            try:
                total += len(compiled.simulate(model, num, st, duration).impacts)
            except SymmechError:
                pass
        return total
    return run


def flights(repeats: int, population_size: int):
    """The compiled loop's exact flight (closed form, certified contact search) against its DOP853 flight and the
    reference at equal tolerance: a sphere, a tumbling ellipsoid, the default scene, a population of spheres."""
    print("compiled loop: exact flight vs DOP853 flight vs the reference\n")
    model, st = sphere_scene()
    T = model.period
    t_end = PERIODS * T
    num = motion.Numerics(scan_step=T / 40, sample_interval=T, tolerance=1e-10, engine="compiled",
                          flight="dop853")
    ref = compiled_times(model, replace(num, tolerance=1e-13), st, t_end)
    exact = replace(num, flight="exact")
    runs = {"compiled, DOP853 flight": lambda: compiled.simulate(model, num, st, t_end),
            "compiled, exact flight": lambda: compiled.simulate(model, exact, st, t_end),
            "plain Python flight + brentq": lambda: exact_flight_brentq(model, st, t_end, XTOL)}
    got = {"compiled, DOP853 flight": compiled_times(model, num, st, t_end),
           "compiled, exact flight": compiled_times(model, exact, st, t_end),
           "plain Python flight + brentq": exact_flight_brentq(model, st, t_end, XTOL)}
    flight_case(f"one sphere, {len(ref)} impacts, tolerance 1e-10", runs, {k: len(v) for k, v in got.items()},
                {k: max_error(v, ref, T) for k, v in got.items()}, repeats=repeats, number=20)

    model, st = tumbling_ellipsoid()
    ref = compiled_times(model, replace(num, tolerance=1e-13), st, t_end)
    python_exact, tight = replace(exact, engine="python"), replace(num, tolerance=1e-12)
    runs = {"compiled, DOP853 flight": lambda: compiled.simulate(model, num, st, t_end),
            "compiled, DOP853 flight, tol 1e-12": lambda: compiled.simulate(model, tight, st, t_end),
            "compiled, exact flight": lambda: compiled.simulate(model, exact, st, t_end),
            "Python loop, exact flight (scipy)": lambda: motion.simulate(model, python_exact, st, t_end)}
    got = {"compiled, DOP853 flight": compiled_times(model, num, st, t_end),
           "compiled, DOP853 flight, tol 1e-12": compiled_times(model, tight, st, t_end),
           "compiled, exact flight": compiled_times(model, exact, st, t_end),
           "Python loop, exact flight (scipy)": [i["t"] for i in runs["Python loop, exact flight (scipy)"]().impacts]}
    flight_case(f"tumbling asymmetric ellipsoid, {len(ref)} impacts, tolerance 1e-10 (error vs DOP853 at 1e-13)",
                runs, {k: len(v) for k, v in got.items()}, {k: max_error(v, ref, T) for k, v in got.items()},
                repeats=repeats, number=5)

    sc = pipeline.load("scenes/grain_default.toml").setup
    sc = replace(sc, numerics=replace(sc.numerics, flight="dop853"))
    duration, T = 0.5, sc.model.period
    ref = compiled_times(sc.model, replace(sc.numerics, tolerance=1e-12), sc.start, duration)
    exact, tight = replace(sc.numerics, flight="exact"), replace(sc.numerics, tolerance=1e-11)
    runs = {"compiled, DOP853 flight": lambda: compiled.simulate(sc.model, sc.numerics, sc.start, duration),
            "compiled, DOP853 flight, tol 1e-11": lambda: compiled.simulate(sc.model, tight, sc.start, duration),
            "compiled, exact flight": lambda: compiled.simulate(sc.model, exact, sc.start, duration)}
    got = {"compiled, DOP853 flight": compiled_times(sc.model, sc.numerics, sc.start, duration),
           "compiled, DOP853 flight, tol 1e-11": compiled_times(sc.model, tight, sc.start, duration),
           "compiled, exact flight": compiled_times(sc.model, exact, sc.start, duration)}
    flight_case(f"default scene (ellipsoid, sliding), {duration} s, {len(ref)} impacts, tolerance 1e-9, one thread "
                "(error vs DOP853 at 1e-12)", runs, {k: len(v) for k, v in got.items()},
                {k: max_error(v, ref, T) for k, v in got.items()}, repeats=repeats)

    starts = [default_grain(sc, k) for k in range(population_size // 10)]
    runs = {name: population_run(sc.model, num, starts, duration)
            for name, num in (("compiled, DOP853 flight", sc.numerics), ("compiled, exact flight", exact))}
    impacts = {name: run() for name, run in runs.items()}
    flight_case(f"population of {len(starts)} default-scene grains (random height, velocity, spin) x {duration} s, "
                "one thread", runs, impacts, {name: math.nan for name in runs}, unit="s", scale=1.0, repeats=repeats)

    grains = [sphere_grain(k) for k in range(population_size)]
    T = grains[0][0].period
    num = motion.Numerics(scan_step=T / 40, sample_interval=T, tolerance=1e-10, engine="compiled",
                          flight="dop853")
    scenes = {"compiled, DOP853 flight": [scene_of(m, s, num) for m, s in grains],
              "compiled, exact flight": [scene_of(m, s, replace(num, flight="exact")) for m, s in grains]}

    def api(name):
        return lambda: sum(len(motion_scene.simulate(sc).impacts) for sc in scenes[name])
    runs = {name: api(name) for name in scenes}
    runs["plain Python flight + brentq"] = lambda: sum(len(exact_flight_brentq(m, s, t_end, XTOL)) for m, s in grains)
    impacts = {name: run() for name, run in runs.items()}
    flight_case(f"population of {population_size} spheres through motion_scene.simulate, {PERIODS} periods", runs,
                impacts, {name: math.nan for name in runs}, unit="s", scale=1.0, repeats=repeats)


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="100 spheres instead of 400")
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--exact-flight-only", action="store_true",
                   help="only the exact-flight floor (no compiled engine, no population)")
    p.add_argument("--flights", action="store_true",
                   help="only the compiled loop's exact flight against its DOP853 flight and the reference")
    p.add_argument("--population", action="store_true",
                   help="only the population (in a fresh process: the sections before it leave garbage and "
                        "threads that load the threaded contenders)")
    args = p.parse_args()
    print(f"machine: {machine()}; numba threads {numba.get_num_threads()}\n")
    if args.population:
        population(100 if args.quick else 400, args.repeats)
        return
    if args.flights:
        flights(args.repeats, 100 if args.quick else 400)
        return
    if args.exact_flight_only:
        model, st = sphere_scene()
        s0, times = flight_state(model, st), np.empty(64)
        n = floor_run(s0, PERIODS * model.period, model.period / 40, XTOL, model.law.e_n, times)
        floor = cpu_interleaved({"floor": lambda: floor_run(s0, PERIODS * model.period, model.period / 40, XTOL,
                                                            model.law.e_n, times)}, args.repeats, number=200)
        exact_flight_floor(args.repeats, floor["floor"].median * 1e6 / n)
        return
    stats, impacts, s0, times, model = one_sphere(args.repeats)
    floor = breakdown(stats, impacts, s0, times, model, args.repeats)
    exact_flight_floor(args.repeats, floor)
    population(100 if args.quick else 400, args.repeats)


if __name__ == "__main__":
    main()
