"""Time to form symbolic a and c: SMM vs sympy.physics.mechanics (Lagrange, Kane); SMM at scale.

System: an n-link planar pendulum hanging in equilibrium, relative joint angles,
point masses m_i at the link ends, torsion springs k_i at the joints, and a
vertical spring (stiffness K_i, tension T_i in equilibrium) from each mass to
the ground below it; gravity g. Each (method, n) runs in a subprocess and is
stopped past the time limit; larger n are then skipped for that method.

Then SMM at scale: the n-link pendulum with relative angles (dense a, c) assembled from the
sparse structural matrices vs the term lists, and the lowest 10 modes of a long chain (time,
error against the closed form, peak memory).

    python benchmarks/bench_smm.py            # n = 2 ... 32; pendulum 1000, chain 100,000
    python benchmarks/bench_smm.py --quick    # n = 2, 4, 8 (mechanics up to 4); pendulum 200, chain 20,000
"""
from __future__ import annotations

import argparse
import multiprocessing as mp
import statistics
import time

LIMIT = 120.0


def smm_mechanism(n: int):
    from symmech.smm.model import Body, Coordinate, Link, Mechanism, Parameter, Point, Torsion

    params = {}
    for i in range(n):
        for name, unit in ((f"m{i}", "kg"), (f"l{i}", "m"), (f"k{i}", "N m/rad"), (f"K{i}", "N/m"),
                           (f"T{i}", "N"), (f"h{i}", "m")):
            params[name] = Parameter(name, 1.0, unit, name)
    params["g"] = Parameter("g", 9.81, "m/s^2", "gravity")
    coords = [Coordinate(f"q{i}", "angle", ("0", "0", "1")) for i in range(n)]
    points = {"O": Point("O", None, ("0", "0", "0"))}
    bodies, springs, torsion = [], [], []
    depth = "0"
    for i in range(n):
        prev = "O" if i == 0 else f"P{i - 1}"
        points[f"P{i}"] = Point(f"P{i}", prev, ("0", f"-l{i}", "0"), tuple(f"q{j}" for j in range(i + 1)))
        depth = f"{depth} - l{i}"
        points[f"G{i}"] = Point(f"G{i}", None, ("0", f"{depth} - h{i}", "0"))
        bodies.append(Body(f"b{i}", f"m{i}", ("0", "0", "0"), f"P{i}", tuple(f"q{j}" for j in range(i + 1))))
        springs.append(Link(f"s{i}", f"P{i}", f"G{i}", f"K{i}", f"T{i}"))
        torsion.append(Torsion(f"t{i}", "ground" if i == 0 else f"b{i - 1}", f"b{i}", f"k{i}", ("0", "0", "1")))
    return Mechanism(f"pendulum{n}", params, coords, points, bodies, springs, [], torsion, [], "g")


def run_smm(n: int):
    from symmech.smm.derive import matrices

    m = smm_mechanism(n)
    t0 = time.perf_counter()
    out = matrices(m)
    return time.perf_counter() - t0, out["a"], out["c"]


def run_mechanics(n: int, method: str):
    import sympy
    from sympy.physics import mechanics as me

    t0 = time.perf_counter()
    q = me.dynamicsymbols(f"q0:{n}")
    u = me.dynamicsymbols(f"u0:{n}")
    m = sympy.symbols(f"m0:{n}")
    l = sympy.symbols(f"l0:{n}")
    k = sympy.symbols(f"k0:{n}")
    K = sympy.symbols(f"K0:{n}")
    T = sympy.symbols(f"T0:{n}")
    h = sympy.symbols(f"h0:{n}")
    g = sympy.Symbol("g")
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    frames, points, particles = [], [], []
    prev_f, prev_p, depth = N, O, 0
    V = 0
    loads = []
    for i in range(n):
        F = prev_f.orientnew(f"F{i}", "Axis", (q[i], prev_f.z))
        P = prev_p.locatenew(f"P{i}", -l[i] * F.y)
        P.v2pt_theory(prev_p, N, F)
        depth -= l[i]
        anchor = O.locatenew(f"G{i}", (depth - h[i]) * N.y)
        d = P.pos_from(anchor)
        length = sympy.sqrt(d.dot(d))
        stretch = length - h[i]
        frames.append(F)
        points.append(P)
        particles.append(me.Particle(f"pa{i}", P, m[i]))
        V += m[i] * g * P.pos_from(O).dot(N.y) + k[i] * q[i] ** 2 / 2 + K[i] * stretch**2 / 2 + T[i] * stretch
        if method == "kane":
            loads.append((P, -m[i] * g * N.y - (K[i] * stretch + T[i]) * d / length))
            loads.append((F, -k[i] * q[i] * N.z))
            if i > 0:
                loads.append((prev_f, k[i] * q[i] * N.z))
        prev_f, prev_p = F, P
    op = {s: 0 for s in q}
    qd = [s.diff() for s in q]
    if method == "lagrange":
        Lg = me.Lagrangian(N, *particles) - V
        LM = me.LagrangesMethod(Lg, q)
        LM.form_lagranges_equations()
        op.update({s: 0 for s in qd})
        M, A, B = LM.linearize(q_ind=q, qd_ind=qd, op_point=op, A_and_B=False)[:3]
    else:
        KM = me.KanesMethod(N, q_ind=q, u_ind=u, kd_eqs=[a - b for a, b in zip(qd, u)])
        KM.kanes_equations(particles, loads)
        op.update({s: 0 for s in u})
        M, A, B = KM.linearize(op_point=op, A_and_B=False)[:3]
    a = M.subs(op)[n:, n:]
    c = -A.subs(op)[n:, :n]
    return time.perf_counter() - t0, a, c


def _worker(kind, n, queue):
    try:
        sec, a, c = run_smm(n) if kind == "smm" else run_mechanics(n, kind)
        queue.put((sec, a.shape))
    except Exception as exc:  # report, do not hide
        queue.put((None, repr(exc)))


def timed(kind: str, n: int, limit: float):
    queue = mp.Queue()
    proc = mp.Process(target=_worker, args=(kind, n, queue))
    proc.start()
    proc.join(limit)
    if proc.is_alive():
        proc.terminate()
        proc.join()
        return None
    sec, info = queue.get()
    if sec is None:
        raise RuntimeError(f"{kind} n={n}: {info}")
    return sec


def check_agreement(n: int = 3) -> float:
    """Largest |SMM - Lagrange| over a and c at random parameter values (sanity, not timing)."""
    import random

    import sympy

    _, a1, c1 = run_smm(n)
    _, a2, c2 = run_mechanics(n, "lagrange")
    rnd = random.Random(1)
    syms = sorted((a1.free_symbols | c1.free_symbols | a2.free_symbols | c2.free_symbols), key=str)
    vals = {s: rnd.uniform(0.5, 2.0) for s in syms}
    by_name = {str(s): v for s, v in vals.items()}
    sub = {s: by_name[str(s)] for s in syms}
    diff = (a1.subs(sub) - a2.subs(sub)).norm() + (c1.subs(sub) - c2.subs(sub)).norm()
    return float(sympy.N(diff))


def pendulum_scene(n: int) -> dict:
    """n links hanging from O, relative angles (dense a and c), bobs, torsion springs, gravity."""
    points = [{"name": "O", "at": [0, 0]}]
    points += [{"name": f"P{i}", "from": "O" if i == 0 else f"P{i - 1}", "vector": [0, "-l"],
                "turns": [f"q{j}" for j in range(i + 1)]} for i in range(n)]
    return {"kind": "mechanism", "name": f"pendulum_{n}",
            "parameters": {"m": {"value": 1.0, "unit": "kg"}, "l": {"value": 0.1, "unit": "m"},
                           "k": {"value": 50.0, "unit": "N m/rad"}, "g": {"value": 9.81, "unit": "m/s^2"}},
            "coordinates": [{"name": f"q{i}", "type": "angle"} for i in range(n)], "points": points,
            "bodies": [{"name": f"b{i}", "mass": "m", "com": f"P{i}"} for i in range(n)],
            "torsion_springs": [{"name": f"t{i}", "bodies": ["ground" if i == 0 else f"b{i - 1}", f"b{i}"],
                                 "stiffness": "k"} for i in range(n)],
            "gravity": {"g": "g"}}


def _model(scene: dict):
    from symmech.core.schema import validate
    from symmech.smm.build import model
    from symmech.smm.schema import SCHEMA

    return model(validate(SCHEMA, scene))


def dense_pendulum(n: int, form: str) -> tuple[float, float]:
    """Seconds to build, assemble (``structural`` or ``terms``) and solve all modes of the n-link
    pendulum, and its omega^2 [1/s^2] (compared between the forms by the caller)."""
    import numpy as np

    from symmech.smm import numeric
    from symmech.smm.model import NumericArith

    t0 = time.perf_counter()
    m = _model(pendulum_scene(n))
    if form == "structural":
        num = numeric.assemble(m)
    else:
        num = numeric.assemble_terms(m, NumericArith(m.values()), m.effects, {})
    md = numeric.modes(num.a.toarray(), num.b.toarray(), num.c.toarray())
    return time.perf_counter() - t0, np.asarray(md.omega2)


def long_chain(n: int) -> tuple[float, float]:
    """Seconds to build, assemble and find the lowest 10 modes of an n-mass fixed-fixed chain (eigsh
    shift-invert), and the largest relative error of omega^2 against the closed form."""
    import numpy as np
    import scipy.sparse.linalg

    from symmech.smm import numeric

    t0 = time.perf_counter()
    m = _model({"kind": "mechanism", "chain": {"n": n, "mass": 0.1, "stiffness": 1e4, "spacing": 0.01}})
    num = numeric.assemble(m)
    w = np.sort(scipy.sparse.linalg.eigsh(num.c.tocsc(), k=10, M=num.a.tocsc(), sigma=0.0,
                                          return_eigenvectors=False))
    seconds = time.perf_counter() - t0
    exact = np.array([2e5 * (1 - np.cos(j * np.pi / (n + 1))) for j in range(1, 11)])
    return seconds, float(np.max(np.abs(w - exact) / exact))


def _memory_worker(n, queue):
    import resource

    seconds, err = long_chain(n)
    queue.put((seconds, err, resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024))


def chain_memory(n: int) -> tuple[float, float, float]:
    """(seconds, error, peak resident MB) of :func:`long_chain` in a fresh process."""
    queue = mp.Queue()
    proc = mp.Process(target=_memory_worker, args=(n, queue))
    proc.start()
    result = queue.get()
    proc.join()
    return result


def scale(quick: bool, repeats: int = 5) -> None:
    """SMM at scale, medians of interleaved repeats (min..max): dense pendulum (structural vs the
    term lists at a size they finish), long chain's lowest modes and its peak memory."""
    import numpy as np

    n_dense, n_terms, n_chain = (200, 60, 20_000) if quick else (1000, 120, 100_000)
    cases = {f"pendulum n={n_dense} structural": lambda: dense_pendulum(n_dense, "structural"),
             f"pendulum n={n_terms} structural": lambda: dense_pendulum(n_terms, "structural"),
             f"pendulum n={n_terms} term lists": lambda: dense_pendulum(n_terms, "terms"),
             f"chain n={n_chain} lowest 10 modes": lambda: long_chain(n_chain)}
    times = {k: [] for k in cases}
    outputs = {}
    for _ in range(repeats):
        for name, fn in cases.items():
            sec, out = fn()
            times[name].append(sec)
            outputs[name] = out
    ref = outputs[f"pendulum n={n_terms} term lists"]
    mine = outputs[f"pendulum n={n_terms} structural"]
    errors = {f"pendulum n={n_terms} structural": float(np.max(np.abs(mine - ref)) / np.abs(ref).max()),
              f"pendulum n={n_terms} term lists": 0.0,
              f"pendulum n={n_dense} structural": float("nan"),
              f"chain n={n_chain} lowest 10 modes": outputs[f"chain n={n_chain} lowest 10 modes"]}
    print(f"\nSMM at scale ({repeats} interleaved repeats; build + assembly + eigenproblem)")
    print(f"{'case':<36} {'median [s]':>11} {'min..max [s]':>17} {'error':>10}")
    for name, ts in times.items():
        err = errors[name]
        print(f"{name:<36} {np.median(ts):>11.3f} {min(ts):>8.3f}..{max(ts):<8.3f} "
              f"{'-' if err != err else f'{err:.2g}':>10}")
    ratio = np.median(times[f"pendulum n={n_terms} term lists"]) / np.median(times[f"pendulum n={n_terms} structural"])
    print(f"structural vs term lists at n={n_terms}: {ratio:.1f}x faster (error column: omega^2 vs term lists "
          f"relative to max omega^2; chain: vs closed form)")
    sec, err, mb = chain_memory(n_chain)
    print(f"chain n={n_chain} in a fresh process: {sec:.2f} s, peak resident memory {mb:.0f} MB, error {err:.2g}")


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="small sizes only")
    p.add_argument("--limit", type=float, default=LIMIT, help="seconds before a method is stopped")
    p.add_argument("--repeats", type=int, default=5, help="interleaved runs per method and size")
    ns = p.parse_args()
    sizes = [2, 4, 8] if ns.quick else [2, 4, 8, 16, 32]
    mech_max = 4 if ns.quick else 32
    print(f"SMM vs sympy.physics.mechanics agreement at n=3: max |difference| = {check_agreement():.3g}")
    print(f"medians of {ns.repeats} interleaved runs, each in a fresh process; min-max in brackets")
    print(f"{'n':>4} {'SMM [s]':>22} {'Lagrange [s]':>22} {'Kane [s]':>22} {'Kane/SMM':>9} {'Lagrange/SMM':>13}")
    alive = {"lagrange": True, "kane": True}
    for n in sizes:
        kinds = ["smm"] + [k for k in ("lagrange", "kane") if alive[k] and n <= mech_max]
        runs = {k: [] for k in kinds}
        for _ in range(ns.repeats):  # rounds: every method once per round
            for kind in kinds:
                if None not in runs[kind]:
                    runs[kind].append(timed(kind, n, ns.limit))
        # float seconds, None (stopped past the limit in some run) or absent (skipped)
        med = {k: None if None in v else statistics.median(v) for k, v in runs.items()}
        for kind in ("lagrange", "kane"):
            alive[kind] = alive[kind] and med.get(kind, 0) is not None

        def fmt(kind):
            if kind not in runs:
                return "-"
            if med[kind] is None:
                return f">{ns.limit:.0f}"
            return f"{med[kind]:.3f} [{min(runs[kind]):.3f}-{max(runs[kind]):.3f}]"

        def ratio(kind):
            if kind not in runs or med["smm"] is None:
                return "-"
            # a method stopped at the limit gives a lower bound on the ratio
            return f">{ns.limit / med['smm']:.0f}x" if med[kind] is None else f"{med[kind] / med['smm']:.0f}x"
        print(f"{n:>4} {fmt('smm'):>22} {fmt('lagrange'):>22} {fmt('kane'):>22} "
              f"{ratio('kane'):>9} {ratio('lagrange'):>13}", flush=True)
    scale(ns.quick)


if __name__ == "__main__":
    main()
