"""Scene runner for ``kind = "mechanism"``: matrices, modes, responses, plots.

``run(scene, out)`` writes matrices.json, modes.csv, free_response.csv,
frequency_response.csv, modes.png, frequency_response.png and the generated
module of the scene's symbolic matrices (``smm_<name>.py``), and returns the
summary. ``precision(scene, out)`` compares the full eigenproblem with
shift-invert Lanczos (``scipy.sparse.linalg.eigsh``) at several tolerances.
Equation contract: a q'' + b q' + c q = Q (SI units by coordinate kind).
"""
from __future__ import annotations

import csv
import importlib.util
import json
import math
import time
from pathlib import Path

import numpy as np
import scipy.linalg

from symmech.core.scene import SceneError, Section, SymmechError
from symmech.smm import numeric
from symmech.smm.model import Effects, Mechanism, from_scene
from symmech.smm.chain import chain_mechanism
from symmech.smm.plots import modes_and_responses, precision_plot

# Above this many coordinates the symbolic matrices are not formed (numeric assembly only).
SYMBOLIC_LIMIT = 60
# `run` solves dense problems up to this size; above it matrices.json would be huge too.
DENSE_RUN_LIMIT = 3000
# Above this size a, b, c are written as sparse triplets (matrices.csv) instead of matrices.json.
JSON_LIMIT = 200
# Warn when the eigenvalue spread costs more than this relative accuracy in omega^2.
CONDITION_WARN = 1e-8
# omega^2 within this many machine epsilons of the largest omega^2 counts as a rigid-body mode.
RIGID_EPS = 100


def mechanism(scene: Section) -> Mechanism:
    """The scene's mechanism: an explicit vector model or a generated uniform ``[chain]``."""
    if scene.has("chain"):
        return chain_mechanism(scene.section("chain"), scene.str("name", default="") or None)
    return from_scene(scene)


def _module(m: Mechanism, out: Path):
    """Render the scene's symbolic matrices with the project emitter and import the module."""
    from symmech.core import emit
    from symmech.smm.derive import module_spec

    spec = module_spec(m)
    path = emit.write(spec, out)
    loader = importlib.util.spec_from_file_location(f"_symmech_scene_{spec.name}", path)
    module = importlib.util.module_from_spec(loader)
    loader.loader.exec_module(module)
    return module, path


def run(scene: Section, out: Path) -> dict:
    m = mechanism(scene)
    warnings: list[str] = []
    eq = scene.section("equilibrium", default={})
    solve = eq.bool("solve", default=False)
    eq.finish()
    eq_report = None
    if solve:
        m, eq_report = numeric.solve_equilibrium(m)
    n = len(m.coordinates)
    if n > DENSE_RUN_LIMIT:
        raise SymmechError(f"mechanism '{m.name}' has {n} coordinates; `symmech run` solves the dense eigenproblem "
                           f"up to {DENSE_RUN_LIMIT}: use `symmech bench precision` (sparse shift-invert) for the "
                           "lowest modes of larger systems")
    num = numeric.assemble(m)
    a, b, c = (x.toarray() for x in (num.a, num.b, num.c))
    numeric.check_mass(m, a)
    # dPi/dq [N or N m] against the stiffness scale times 1 m (or 1 rad)
    res = float(np.abs(num.residual).max())
    if res > 1e-8 * max(np.abs(c).max(), 1.0):
        worst = m.coordinate_names[int(np.argmax(np.abs(num.residual)))]
        warnings.append(f"the configuration is not an equilibrium: dPi/dq = {res:.3g} on '{worst}' (eq. (5)); "
                        "set [equilibrium] solve = true or fix the preloads")
    generated = None
    if n <= SYMBOLIC_LIMIT:
        module, path = _module(m, out)
        values = [p.value for p in m.parameters.values()]
        for key, ref in (("a", a), ("b", b), ("c", c)):
            got = getattr(module, key)(*values)
            if not np.allclose(got, ref, rtol=1e-9, atol=1e-12 * max(np.abs(ref).max(), 1.0)):
                raise RuntimeError(f"generated {key} disagrees with the numeric assembly")  # a bug, not input
        generated = str(path)

    md = numeric.modes(a, b, c)
    w2 = md.omega2
    wmax = max(abs(w2).max(), 1e-300)
    # rigid-body modes: omega^2 at round-off level of the largest one
    zero = RIGID_EPS * np.finfo(float).eps * wmax
    rigid = [i for i, x in enumerate(w2) if abs(x) <= zero]
    unstable = [i for i, x in enumerate(w2) if x < -zero]
    if unstable:
        warnings.append(f"{len(unstable)} mode(s) have negative omega^2 (unstable equilibrium), "
                        f"lowest {w2[0]:.4g} 1/s^2")
    elastic = [x for x in w2 if x > zero]
    if elastic:
        spread = max(elastic) / min(elastic)
        if spread * np.finfo(float).eps > CONDITION_WARN:
            warnings.append(f"stiffness spread omega_max^2/omega_min^2 = {spread:.3g}: the lowest frequencies keep "
                            f"only about {max(0.0, -math.log10(spread * np.finfo(float).eps)):.0f} correct digits "
                            "(very stiff springs closing loops?)")
    omega = [math.sqrt(x) if x > 0 and i not in rigid else 0.0 if i in rigid else None
             for i, x in enumerate(w2)]
    overdamped = [i + 1 for i, z in enumerate(md.zeta) if z is None and omega[i]]
    if overdamped and np.any(b):
        warnings.append(f"mode(s) {', '.join(map(str, overdamped))} have real damped eigenvalues (overdamped): "
                        "no damping ratio reported")
    eff_report = _effects_report(m, w2, warnings)

    out = Path(out)
    matrices_file = _write_matrices(out, m, num)
    _write_modes(out / "modes.csv", m, omega, md)
    response = _responses(scene, m, a, b, c, out)
    plots = scene.section("output", default={})
    make_plots = plots.bool("plots", default=True)
    plots.finish()
    files = [matrices_file, "modes.csv"] + response["files"]
    if make_plots:
        files += modes_and_responses(m, md, omega, response, out)
    _header(scene)
    scene.finish()
    return {
        "mechanism": m.name,
        "coordinates": [{"name": co.name, "type": co.kind, "unit": co.unit} for co in m.coordinates],
        "effects": {"damping": m.effects.damping, "preload": m.effects.preload, "gravity": m.effects.gravity},
        "equilibrium": eq_report,
        "equilibrium_residual": res,
        "omega2_1_per_s2": w2.tolist(),
        "frequencies_rad_s": omega,
        "frequencies_hz": [None if w is None else w / (2 * math.pi) for w in omega],
        "rigid_body_modes": len(rigid),
        "damping_ratios": md.zeta,
        "neglected_effects": eff_report,
        "generated_module": generated,
        "files": files,
        "warnings": warnings,
    }


def _header(scene: Section) -> None:
    """Mark the descriptive top-level fields as read (``kind`` and ``name`` are read elsewhere)."""
    scene.str("kind")
    scene.str("name", default="")
    scene.str("description", default="")


def _effects_report(m: Mechanism, w2: np.ndarray, warnings: list) -> dict:
    """How much the effects the scene leaves out would change omega^2 and the stiffness."""
    full_eff = Effects(True, True, True)
    if m.effects == full_eff:
        return {}
    full = numeric.assemble(m, full_eff)
    fa, fc = full.a.toarray(), full.c.toarray()
    kept = numeric.assemble(m).c.toarray()
    w2_full, phi = scipy.linalg.eigh(fc, fa)
    scale = max(abs(w2_full).max(), 1e-300)
    rel = [float(abs(x - y) / max(abs(y), 1e-12 * scale)) for x, y in zip(np.sort(w2), w2_full)]
    # share of each full mode's modal stiffness phi^T c phi carried by the dropped terms
    dropped_c = fc - kept
    share = [float(abs(p @ dropped_c @ p) / max(abs(p @ fc @ p), 1e-12 * scale)) for p in phi.T]
    dropped = [k for k, v in (("preload", m.effects.preload), ("gravity", m.effects.gravity),
                              ("damping", m.effects.damping)) if not v]
    worst = int(np.argmax(share)) if share else 0
    if share and share[worst] > 0.25:
        warnings.append(f"dropping {', '.join(dropped)} removes {100 * share[worst]:.0f}% of the stiffness of "
                        f"mode {worst + 1} (omega^2 {w2_full[worst]:.4g} 1/s^2 with all effects); in pendulums "
                        "and pretensioned strings these terms are the stiffness")
    return {"dropped": dropped, "modal_stiffness_share_dropped": share,
            "omega2_with_all_effects": w2_full.tolist(), "omega2_relative_change": rel}


def _write_matrices(out: Path, m: Mechanism, num) -> str:
    """a, b, c as matrices.json (dense) or, above JSON_LIMIT coordinates, matrices.csv (nonzeros)."""
    if len(m.coordinates) <= JSON_LIMIT:
        (out / "matrices.json").write_text(json.dumps({
            "coordinates": m.coordinate_names,
            "units": [co.unit for co in m.coordinates],
            "equation": "a q'' + b q' + c q = Q",
            "parameters": {p.name: {"value": p.value, "unit": p.unit} for p in m.parameters.values()},
            "a": num.a.toarray().tolist(), "b": num.b.toarray().tolist(), "c": num.c.toarray().tolist()},
            indent=1) + "\n")
        return "matrices.json"
    total = (abs(num.a) + abs(num.b) + abs(num.c)).tocoo()
    with (out / "matrices.csv").open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["row", "column", "a", "b", "c"])
        for i, j in sorted(zip(total.row.tolist(), total.col.tolist())):
            w.writerow([m.coordinate_names[i], m.coordinate_names[j], repr(float(num.a[i, j])),
                        repr(float(num.b[i, j])), repr(float(num.c[i, j]))])
    return "matrices.csv"


def _write_modes(path: Path, m: Mechanism, omega, md) -> None:
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["mode", "omega2_1_per_s2", "omega_rad_s", "f_hz", "zeta"] + m.coordinate_names)
        for i in range(len(omega)):
            w.writerow([i + 1, repr(float(md.omega2[i])), "" if omega[i] is None else repr(omega[i]),
                        "" if omega[i] is None else repr(omega[i] / (2 * math.pi)),
                        "" if md.zeta[i] is None else repr(md.zeta[i])] + [repr(float(x)) for x in md.shapes[:, i]])


def _point_force(scene_sec: Section, m: Mechanism) -> np.ndarray:
    """Generalized force of a force F [N] at a point: Q_a = F . dr/dq_a."""
    from symmech.smm import forms
    from symmech.smm.model import NumericArith

    n = len(m.coordinates)
    if scene_sec.has("Q"):
        return np.array(scene_sec.vector("Q", n, unit="N or N m"))
    point = scene_sec.str("point")
    if point not in m.points:
        raise SceneError(scene_sec.name("point"), f"point '{point}' is not defined")
    raw = scene_sec.raw("force")
    force = np.zeros(3)
    size = len(raw) if isinstance(raw, list) and len(raw) in (2, 3) else 3
    force[:size] = scene_sec.vector("force", size, unit="N")
    g = forms.Geometry(m, NumericArith(m.values()))
    kin = forms.chain_kinematics(g, point, False)
    Q = np.zeros(n)
    for a, d in kin.D.items():
        Q[g.index[a]] = float(np.dot(force, d))
    return Q


def _responses(scene: Section, m: Mechanism, a, b, c, out: Path) -> dict:
    n = len(m.coordinates)
    files = []
    result = {"files": files}
    ini = scene.section("initial", default=None) if scene.has("initial") else None
    if ini is not None:
        q0 = np.array(ini.vector("q", n, unit="m or rad", default=[0.0] * n))
        v0 = np.array(ini.vector("qdot", n, unit="m/s or rad/s", default=[0.0] * n))
        duration = ini.float("duration", unit="s", lo=0, lo_open=True)
        steps = ini.int("steps", default=1000, lo=2, hi=10**6)
        ini.finish()
        t = np.linspace(0.0, duration, steps + 1)
        q = numeric.free_response(a, b, c, q0, v0, t)
        with (out / "free_response.csv").open("w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["t_s"] + m.coordinate_names)
            for ti, row in zip(t, q):
                w.writerow([repr(float(ti))] + [repr(float(x)) for x in row])
        files.append("free_response.csv")
        result["free"] = (t, q)
    frc = scene.section("forcing", default=None) if scene.has("forcing") else None
    if frc is not None:
        Q = _point_force(frc, m)
        lo, hi = frc.vector("omega", 2, unit="rad/s", lo=0)
        if hi <= lo:
            raise SceneError(frc.name("omega"), f"expected [low, high] with low < high, got [{lo}, {hi}]")
        samples = frc.int("samples", default=400, lo=2, hi=10**6)
        frc.finish()
        omegas = np.linspace(lo, hi, samples)
        H = numeric.frequency_response(a, b, c, Q, omegas)
        with (out / "frequency_response.csv").open("w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["omega_rad_s"] + [f"abs_{x}" for x in m.coordinate_names]
                       + [f"phase_{x}_rad" for x in m.coordinate_names])
            for wi, row in zip(omegas, H):
                w.writerow([repr(float(wi))] + [repr(float(abs(x))) for x in row]
                           + [repr(float(np.angle(x))) for x in row])
        files.append("frequency_response.csv")
        result["frf"] = (omegas, H)
    return result


def precision(scene: Section, out: Path) -> dict:
    """Frequencies of the lowest modes: full dense eigenproblem vs eigsh shift-invert at
    several tolerances; error vs time as precision.csv and precision.png. The reference is
    the closed form for ``[chain]`` scenes, else the dense solution (else eigsh at tol 0)."""
    import scipy.sparse.linalg

    from symmech.smm.chain import build_chain, exact_omega2, read_chain

    bench = scene.section("precision", default={})
    modes_n = bench.int("modes", default=10, lo=1, hi=200)
    dense_limit = bench.int("dense_limit", default=3000, lo=2)
    bench.finish()
    exact = None
    if scene.has("chain"):
        spec = read_chain(scene.section("chain"), scene.str("name", default="") or None)
        m = build_chain(spec)
        exact = np.array(exact_omega2(spec)[:modes_n])
    else:
        m = mechanism(scene)
    t0 = time.perf_counter()
    num = numeric.assemble(m)
    t_asm = time.perf_counter() - t0
    n = num.a.shape[0]
    if modes_n >= n:
        raise SceneError("precision.modes", f"{modes_n} must be below the number of coordinates {n}")
    rows = []
    if n <= dense_limit:
        t0 = time.perf_counter()
        w = scipy.linalg.eigh(num.c.toarray(), num.a.toarray(), eigvals_only=True, subset_by_index=[0, modes_n - 1])
        rows.append(("dense eigh", 0.0, time.perf_counter() - t0, w))
    # a small negative shift keeps the factorization regular when there are rigid-body modes
    shift = -1e-6 * float(np.max(num.c.diagonal() / num.a.diagonal()))
    for tol in (1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 0.0):
        t0 = time.perf_counter()
        w = scipy.sparse.linalg.eigsh(num.c.tocsc(), k=modes_n, M=num.a.tocsc(), sigma=shift, which="LM",
                                      tol=tol, return_eigenvectors=False)
        rows.append((f"eigsh tol={tol:g}", tol, time.perf_counter() - t0, np.sort(w)))
    reference, ref = (("closed form", exact) if exact is not None
                      else (rows[0][0], rows[0][3]) if n <= dense_limit else ("eigsh tol=0", rows[-1][3]))
    ref_w = np.sqrt(np.abs(ref))
    floor = 1e-12 * ref_w.max()

    def error(w):
        return float(np.max(np.abs(np.sqrt(np.abs(w)) - ref_w) / np.maximum(ref_w, floor)))

    with (Path(out) / "precision.csv").open("w", newline="") as fh:
        wr = csv.writer(fh)
        wr.writerow(["method", "tol", "seconds", "max_rel_error_omega", "reference", "assembly_seconds", "dof"])
        for name, tol, sec, w in rows:
            wr.writerow([name, tol, repr(sec), repr(error(w)), reference, repr(t_asm), n])
    precision_plot(out, [(name, sec, error(w)) for name, tol, sec, w in rows], modes_n,
                   f"{m.name}: {n} DOF, assembly {t_asm:.2f} s; reference: {reference}")
    _header(scene)
    return {"files": [str(Path(out) / "precision.csv"), str(Path(out) / "precision.png")]}
