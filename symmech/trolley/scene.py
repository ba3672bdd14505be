"""Scene runner for ``kind = "trolley"``: ``run`` and ``precision`` (see docs/scenes-trolley.md).

Outputs of ``run`` in the folder ``out``: ``case1.csv`` (and ``case2.csv`` with the
local-curvature effect) with columns t,V1,V2,V3,a1,a2,a3,P0..P5 (SI, body-frame
components of the centre of mass), ``caseN_overload.csv`` (t, n1, n2, n3 in g),
``track.png``, ``reactions.png``, ``overloads.png``; the returned dict is the summary.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from symmech.core.scene import SceneError, Section, SymmechError
from symmech.trolley import model, tables, track as tracks

CSV_COLUMNS = "t,V1,V2,V3,a1,a2,a3,P0,P1,P2,P3,P4,P5"
G_STANDARD = 9.80665
# Default comfort envelope [g] per body axis (tangential, normal, lateral).
COMFORT = {"x1": (-2.0, 2.0), "x2": (-1.5, 6.0), "x3": (-2.0, 2.0)}


@dataclass
class Setup:
    """Everything a run needs, read and checked from a scene."""

    track: tracks.Track
    body: model.Body
    frame: str
    conventions: str
    t: np.ndarray
    speed: object  # callable t -> (V0, dV0) or None with traction
    traction: object  # callable (t, V0) -> P0 or None
    v_initial: float
    s0: float
    local_curvature: bool
    fd_order: int
    fd_step: float
    lstar_derivative: str
    small_angle_limit: float
    comfort: dict
    paper_tables: bool


def _time_functions(sec: Section, field: str, variables: tuple[str, ...]):
    """Numeric f and df/dt of an expression field in ``variables`` (t first)."""
    import sympy as sp

    expr, syms = tracks.parse_expression(sec.name(field), sec.str(field), variables, {})
    both = tracks.lambdify_arrays([expr, sp.diff(expr, syms[0])], syms)
    return (lambda *a: both(*a)[0]), (lambda *a: both(*a)[1])


def read(scene: Section) -> Setup:
    scene.choice("kind", ("trolley",))
    conventions = scene.choice("conventions", ("physics", "paper"), default="physics")
    frame = scene.choice("frame", ("twist", "frenet"), default="twist")
    track = tracks.build(scene.section("track"))

    eff = scene.section("effects", default={})
    gravity = eff.bool("gravity", default=True)
    local_curvature = eff.bool("local_curvature", default=False)
    traction_on = eff.bool("traction", default=False)
    eff.finish()

    tr = scene.section("trolley")
    mass = tr.float("mass", unit="kg", lo=0.0, lo_open=True)
    com = tr.vector("com", 3, unit="m")
    inertia = tr.vector("inertia", 6, unit="kg m^2", default=[0.0] * 6)
    if min(inertia[:3]) < 0:
        raise SceneError(tr.name("inertia"), f"principal entries {inertia[:3]} must be >= 0 kg m^2")
    axle = tr.float("axle_distance", unit="m", lo=0.0, lo_open=True)
    half = tr.float("half_gauge", unit="m", lo=0.0, lo_open=True)
    tr.finish()

    const = scene.section("constants", default={})
    g0 = const.float("g0", unit="m/s^2", default=G_STANDARD, lo=0.0, lo_open=True)
    const.finish()

    tm = scene.section("time")
    t_end = tm.float("t_end", unit="s", lo=0.0, lo_open=True)
    steps = tm.int("steps", lo=1, hi=10_000_000)
    tm.finish()

    mo = scene.section("motion")
    s0 = mo.float("s0", unit="m", default=0.0, lo=0.0)
    speed = traction = None
    v_initial = 0.0
    if traction_on:
        if conventions == "paper":
            raise SceneError("effects.traction", "traction integration is not available with conventions = \"paper\"")
        traction = _time_functions(mo, "traction", ("t", "v"))[0]
        v_initial = mo.float("initial_speed", unit="m/s", default=0.0)
    else:
        speed = _time_functions(mo, "speed", ("t",))
    mo.finish()

    num = scene.section("numerics", default={})
    fd_order = num.int("fd_order", default=4, lo=2, hi=4)
    if fd_order not in (2, 4):
        raise SceneError(num.name("fd_order"), f"{fd_order} is not 2 or 4")
    # Rounding grows as eps/h² in Λ*'', truncation as h⁴: a few cm balance them.
    fd_step = num.float("fd_step", unit="m", default=min(0.02, 0.05 * axle), lo=0.0, lo_open=True, hi=0.1 * axle)
    lstar_derivative = num.choice("lstar_derivative", ("backward", "central2", "central4"), default="backward")
    small_angle_limit = num.float("small_angle_limit", unit="1", default=0.01, lo=0.0, lo_open=True)
    num.finish()

    comfort = dict(COMFORT)
    cf = scene.section("comfort", default={})
    for axis in COMFORT:
        lo, hi = cf.vector(axis, 2, unit="g", default=list(COMFORT[axis]))
        if not lo < hi:
            raise SceneError(cf.name(axis), f"[{lo:g}, {hi:g}] must be increasing")
        comfort[axis] = (lo, hi)
    cf.finish()

    rep = scene.section("report", default={})
    paper_tables = rep.bool("paper_tables", default=False)
    rep.finish()
    scene.finish()

    t = np.linspace(0.0, t_end, steps + 1)
    body = model.Body(mass, tuple(com), tuple(inertia), axle, half, g0 if gravity else 0.0)
    return Setup(track, body, frame, conventions, t, speed, traction, v_initial, s0, local_curvature,
                 fd_order, fd_step, lstar_derivative, small_angle_limit, comfort, paper_tables)


def arc_length(setup: Setup) -> np.ndarray:
    """s(t) = s0 + ∫ V0 dt on the grid, 8-point Gauss-Legendre per step [m]."""
    t = setup.t
    nodes, weights = np.polynomial.legendre.leggauss(8)
    mid, half = (t[1:] + t[:-1]) / 2, (t[1:] - t[:-1]) / 2
    v = setup.speed[0](mid[:, None] + half[:, None] * nodes)
    return setup.s0 + np.concatenate([[0.0], np.cumsum((v * weights).sum(axis=1) * half)])


def frame_at(setup: Setup, case: int, s) -> model.Frame:
    if case == 1:
        return model.moving_frame(setup.track, s, setup.frame)
    return model.local_curvature_frame(setup.track, s, setup.body.l, setup.frame, setup.fd_order, setup.fd_step)


def integrate_traction(setup: Setup, case: int):
    """s, V0, dV0 on the grid from m a1 = P0 - m g0 ν1 along x1 (a1 = α1 V̇0 + β1 V0²)."""
    from scipy.integrate import solve_ivp

    body = setup.body

    def rates(t, y):
        fr = frame_at(setup, case, np.array([y[0]]))
        alpha, beta = (c[0] for c in model.point_coefficients(fr, body))
        if alpha[0] <= 1e-6:
            raise SymmechError(f"traction: the centre of mass cannot be driven along the track at s = {y[0]:.6g} m "
                               f"(α1 = {alpha[0]:.3g})")
        p0 = float(setup.traction(t, y[1]))
        dv = (p0 / body.m - body.g0 * fr.lam[0, 0, 1] - beta[0] * y[1] ** 2) / alpha[0]
        return [y[1], dv]

    sol = solve_ivp(rates, (setup.t[0], setup.t[-1]), [setup.s0, setup.v_initial], method="DOP853",
                    t_eval=setup.t, rtol=1e-10, atol=1e-10)
    if sol.status != 0 or not np.all(np.isfinite(sol.y)):
        raise SymmechError(f"traction integration failed: {sol.message}")
    s, v = sol.y
    dv = np.array([rates(ti, [si, vi])[1] for ti, si, vi in zip(setup.t, s, v)])
    return s, v, dv


def compute(setup: Setup, conventions: str | None = None) -> dict:
    """Results per case: {1: {...}, 2: {...}} with s, V0, dV0 and :func:`model.body_motion` arrays."""
    conventions = conventions or setup.conventions
    cases = (1, 2) if setup.local_curvature else (1,)
    results = {}
    for case in cases:
        if setup.traction is not None:
            s, v0, dv0 = integrate_traction(setup, case)
        else:
            s = arc_length(setup)
            v0, dv0 = setup.speed[0](setup.t), setup.speed[1](setup.t)
        if conventions == "paper":
            out = model.paper_case(setup.track, s, v0, dv0, setup.body, setup.frame, case == 2,
                                   setup.lstar_derivative)
        else:
            fr = frame_at(setup, case, s)
            out = model.body_motion(fr, v0, dv0, setup.body)
            out["frame"] = fr
        out.update(s=s, V0=v0, dV0=dv0)
        results[case] = out
    return results


def _extremes(t, values, names, unit):
    out = {}
    for i, name in enumerate(names):
        col = values[:, i]
        hi, lo = int(np.argmax(col)), int(np.argmin(col))
        out[name] = {"max": float(col[hi]), "t_max": float(t[hi]), "min": float(col[lo]), "t_min": float(t[lo]),
                     "unit": unit}
    return out


def _comfort(t, overload, comfort):
    out = {}
    for i, (axis, (lo, hi)) in enumerate(comfort.items()):
        bad = (overload[:, i] < lo) | (overload[:, i] > hi)
        out[axis] = {"envelope_g": [lo, hi], "samples_outside": int(bad.sum()),
                     "first_t_outside": float(t[np.argmax(bad)]) if bad.any() else None}
    return out


def _finite(setup, res):
    for case, r in res.items():
        for key in ("V", "a", "P"):
            if not np.all(np.isfinite(r[key])):
                i = int(np.argmax(~np.all(np.isfinite(r[key]), axis=-1)))
                raise SymmechError(f"case {case}: non-finite {key} at t = {setup.t[i]:.6g} s")


def paper_table_rows(setup: Setup, paper: dict, physics: dict) -> dict:
    """Printed Tables 1, 2 beside the paper-conventions and default-physics values."""
    index = {}
    for time_ in tables.TIMES:
        k = int(round(time_ / (setup.t[1] - setup.t[0])))
        if k >= len(setup.t) or abs(setup.t[k] - time_) > 1e-9:
            raise SymmechError(f"report.paper_tables: t = {time_:g} s is not a grid point of this scene")
        index[time_] = k
    rows, reproduced = [], 0
    for table, q, case, time_, value, decimals in tables.entries():
        if case not in paper:
            continue
        k = index[time_]
        pick = lambda r: float(_quantity(r, q)[k])  # noqa: E731
        got = pick(paper[case])
        ok = round(got, decimals) == round(value, decimals)
        reproduced += ok
        rows.append({"table": table, "quantity": q, "case": case, "t": time_, "printed": value,
                     "paper_conventions": got, "default_physics": pick(physics[case]),
                     "reproduced_to_printed_digits": bool(ok)})
    return {"entries": len(rows), "reproduced": reproduced, "rows": rows}


def _write_paper_tables(tab: dict, path: Path) -> None:
    """The printed entries beside both computations, as an aligned text table."""
    lines = [f"{'table':<8} {'qty':<4} {'case':>4} {'t [s]':>6} {'printed':>12} {'paper conv.':>14} "
             f"{'physics':>14}  reproduced"]
    for r in tab["rows"]:
        lines.append(f"{r['table']:<8} {r['quantity']:<4} {r['case']:>4} {r['t']:>6g} {r['printed']:>12.6g} "
                     f"{r['paper_conventions']:>14.6f} {r['default_physics']:>14.6f}  "
                     f"{'yes' if r['reproduced_to_printed_digits'] else 'NO'}")
    lines.append(f"{tab['reproduced']} of {tab['entries']} printed entries reproduced to the printed digits "
                 "in paper conventions")
    path.write_text("\n".join(lines) + "\n")


def _quantity(res, name):
    kind, i = name[0], int(name[1:])
    if kind == "P":
        return res["P"][:, i]
    return res["V" if kind == "V" else "a"][:, i - 1]


def run(scene: Section, out: Path) -> dict:
    start = time.perf_counter()
    setup = read(scene)
    res = compute(setup)
    _finite(setup, res)
    warnings = []
    summary = {"kind": "trolley", "conventions": setup.conventions, "frame": setup.frame,
               "effects": {"gravity": setup.body.g0 > 0, "local_curvature": setup.local_curvature,
                           "traction": setup.traction is not None},
               "steps": len(setup.t) - 1, "cases": {}}
    for case, r in res.items():
        data = np.column_stack([setup.t, r["V"], r["a"], r["P"]])
        np.savetxt(out / f"case{case}.csv", data, delimiter=",", header=CSV_COLUMNS, comments="", fmt="%.10g")
        np.savetxt(out / f"case{case}_overload.csv", np.column_stack([setup.t, r["overload"]]), delimiter=",",
                   header="t,n1,n2,n3", comments="", fmt="%.10g")
        info = {
            "speed": _extremes(setup.t, r["V0"][:, None], ["V0"], "m/s"),
            "velocity": _extremes(setup.t, r["V"], ["V1", "V2", "V3"], "m/s"),
            "acceleration": _extremes(setup.t, r["a"], ["a1", "a2", "a3"], "m/s^2"),
            "reactions": _extremes(setup.t, r["P"], [f"P{i}" for i in range(6)], "N"),
            "overload": _extremes(setup.t, r["overload"], ["n1", "n2", "n3"], "g"),
            "comfort": _comfort(setup.t, r["overload"], setup.comfort),
            "s_end": float(r["s"][-1]),
        }
        if case == 2 and setup.conventions == "physics":
            info.update(_small_angle(setup, r, warnings))
        summary["cases"][f"case{case}"] = info
        for axis, c in info["comfort"].items():
            if c["samples_outside"]:
                warnings.append(f"case {case}: overload along {axis} leaves the comfort envelope "
                                f"{c['envelope_g']} g from t = {c['first_t_outside']:.4g} s")
    if setup.paper_tables:
        other = compute(setup, "physics" if setup.conventions == "paper" else "paper")
        paper, physics = (res, other) if setup.conventions == "paper" else (other, res)
        summary["paper_tables"] = paper_table_rows(setup, paper, physics)
        _write_paper_tables(summary["paper_tables"], out / "paper_tables.txt")
    from symmech.trolley import plots

    summary["files"] = [str(p) for p in plots.write_all(setup, res, out)]
    summary["elapsed_s"] = time.perf_counter() - start
    summary["warnings"] = warnings
    return summary


def _small_angle(setup, r, warnings) -> dict:
    psi = r["frame"].info["psi"]
    k = int(np.argmax(psi))
    defect, _ = model.small_angle_check(r["frame"].info["base"], r["frame"].info["chord"], setup.body.l)
    j = int(np.argmax(defect))
    if defect[j] > setup.small_angle_limit:
        warnings.append(f"case 2: the small-angle correction (13)-(14) is out of its range: orthogonality "
                        f"defect {defect[j]:.3g} > {setup.small_angle_limit:g} at t = {setup.t[j]:.4g} s "
                        f"(chord angle {psi[j]:.3g} rad); the exact rotation Λ* is used")
    return {"chord_angle_max_rad": float(psi[k]), "chord_angle_t_max": float(setup.t[k]),
            "small_angle_defect_max": float(defect[j])}


PRECISION_STEPS = (250, 500, 1000, 2000, 5000, 10000, 20000)
PRECISION_METHODS = ("backward", "central2", "central4")


def _symbolic_chord(setup: Setup):
    """Symbols s, s_A, the midline at both, the tangent at O, and d/ds along the chord
    equation: ∂/∂s + ds_A/ds ∂/∂s_A with ds_A/ds = (ΔR̄·t(s_O)) / (ΔR̄·t(s_A))."""
    import sympy as sp

    tr = setup.track
    if getattr(tr, "exprs", None) is None:
        raise SymmechError("bench precision needs a track given by expressions in s (type helix or expression)")
    s, sa = tr.var, sp.Symbol("s_A", real=True)
    x_o = sp.Matrix(tr.exprs)
    x_a = x_o.subs(s, sa)
    chord = x_a - x_o
    dsa = chord.dot(x_o.diff(s)) / chord.dot(x_a.diff(sa))
    total = lambda m: m.diff(s) + m.diff(sa) * dsa  # noqa: E731
    return s, sa, x_o, chord, total


def _matrix_function(matrices, s, sa):
    """Numeric f(s, s_A) -> tuple of (n, 3, 3) arrays of the sympy 3x3 ``matrices``."""
    f = tracks.lambdify_arrays([e for m in matrices for e in m], (s, sa))

    def value(s_val, sa_val):
        flat = np.stack(f(s_val, sa_val), axis=-1)
        return tuple(flat[..., 9 * k:9 * k + 9].reshape(np.shape(s_val) + (3, 3)) for k in range(len(matrices)))
    return value


def exact_paper_lstar_derivative(setup: Setup):
    """dΛ*/ds of the paper's Λ* (ξ = t × ρ, printed Rodrigues) by symbolic differentiation.

    Returns f(s, s_A) -> (n, 3, 3), s_A(s) from the chord equation.
    """
    import sympy as sp

    from symmech.trolley import printed as printed_formulas

    s, sa, x_o, chord, total = _symbolic_chord(setup)
    t_o = x_o.diff(s)
    rho = chord / setup.body.l
    xi = t_o.cross(rho)
    subs = {printed_formulas.psi: sp.acos(t_o.dot(rho)), printed_formulas.xi1: xi[0],
            printed_formulas.xi2: xi[1], printed_formulas.xi3: xi[2]}
    f = _matrix_function([total(printed_formulas.RODRIGUES.subs(subs))], s, sa)
    return lambda s_val, sa_val: f(s_val, sa_val)[0]


def exact_lstar_derivatives(setup: Setup):
    """Λ*' and Λ*'' of the physically consistent chord rotation, symbolically (Frenet frame).

    Returns f(s, s_A) -> (Λ*', Λ*''), each (n, 3, 3).
    """
    import sympy as sp

    from symmech.trolley import derive

    if setup.frame != "frenet":
        raise SymmechError("bench precision: the exact case 2 reference is built for frame = \"frenet\"")
    s, sa, x_o, chord, total = _symbolic_chord(setup)
    t = x_o.diff(s)
    curv = t.diff(s)
    n = curv / sp.sqrt(curv.dot(curv))
    lam = sp.Matrix.vstack(t.T, n.T, t.cross(n).T)
    rho = lam * chord / setup.body.l
    spec = derive.chord_rotation()
    syms = [a.symbol for a in spec.args]
    lstar = spec.matrix.subs(dict(zip(syms, rho)))
    d1 = total(lstar)
    return _matrix_function([d1, total(d1)], s, sa)


PRECISION_FD_STEPS = (0.3, 0.1, 0.03, 0.01, 0.003, 0.001, 0.0003)


def _timed(fn, repeat: int = 3):
    """Best wall time of ``repeat`` calls [s] and the last result."""
    best = np.inf
    for _ in range(repeat):
        start = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - start)
    return best, result


def precision(scene: Section, out: Path) -> dict:
    """Work-precision of the derivative approximations, against exact symbolic references.

    Paper conventions, case 2: dΛ*/ds by the paper's backward difference, central2 and
    central4 between grid points, for ``PRECISION_STEPS`` (the step count is the knob).
    With ``conventions = "physics"`` also the consistent case 2: Λ*', Λ*'' by central
    differences of order 2 and 4 for ``PRECISION_FD_STEPS`` on the scene's grid.
    Writes ``precision.csv`` (family, method, steps, fd_step_m, time_s, max_abs_error_N)
    and ``precision.png``.
    """
    import dataclasses

    setup = read(scene)
    if not setup.local_curvature or setup.speed is None:
        raise SymmechError("bench precision needs effects.local_curvature = true and a given speed")
    exact = exact_paper_lstar_derivative(setup)
    rows = []
    t_end = setup.t[-1]
    for steps in PRECISION_STEPS:
        st = dataclasses.replace(setup, t=np.linspace(0.0, t_end, steps + 1))
        s, v0, dv0 = arc_length(st), st.speed[0](st.t), st.speed[1](st.t)
        sa = model.chord_point(st.track, s, st.body.l)
        ref = model.paper_case(st.track, s, v0, dv0, st.body, st.frame, True, dlstar=exact(s, sa))["P"]
        for method in PRECISION_METHODS:
            elapsed, got = _timed(lambda: model.paper_case(st.track, s, v0, dv0, st.body, st.frame, True,
                                                           method)["P"])
            rows.append(("paper", method, steps, "", elapsed, float(np.abs(got - ref).max())))
    if setup.conventions == "physics":
        s, v0, dv0 = arc_length(setup), setup.speed[0](setup.t), setup.speed[1](setup.t)
        case2 = lambda **kw: model.body_motion(  # noqa: E731
            model.local_curvature_frame(setup.track, s, setup.body.l, setup.frame, **kw), v0, dv0, setup.body)["P"]
        ref = case2(derivatives=exact_lstar_derivatives(setup))
        for order in (2, 4):
            for h in PRECISION_FD_STEPS:
                elapsed, got = _timed(lambda: case2(fd_order=order, fd_step=h))
                rows.append(("physics", f"central{order}", len(setup.t) - 1, h, elapsed,
                             float(np.abs(got - ref).max())))
    csv = out / "precision.csv"
    with csv.open("w") as fh:
        fh.write("family,method,steps,fd_step_m,time_s,max_abs_error_N\n")
        for family, method, steps, h, elapsed, err in rows:
            fh.write(f"{family},{method},{steps},{h},{elapsed:.6g},{err:.6g}\n")
    from symmech.trolley import plots

    png = plots.work_precision(rows, out / "precision.png")
    return {"files": [str(csv), str(png)], "rows": rows}
