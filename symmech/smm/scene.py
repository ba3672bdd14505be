"""Scene kind ``mechanism``: matrices, modes, responses, plots (registered at import).

``prepare`` builds the mechanism from the validated scene (``symmech.smm.schema``)
and checks it (``symmech.smm.build``, numeric assembly and a regular inertia
matrix); ``run`` returns a Result with the tables ``modes``, ``free_response``,
``frequency_response``, the files ``matrices.json`` (or ``matrices.csv`` above
JSON_LIMIT coordinates) and ``smm_<name>.py`` (the scene's symbolic matrices
emitted with the project emitter). ``precision`` compares the full eigenproblem
with shift-invert Lanczos (``scipy.sparse.linalg.eigsh``) at several tolerances.
Equation contract: a q'' + b q' + c q = Q (SI units by coordinate kind).
"""
from __future__ import annotations

import csv
import importlib.util
import io
import json
import math
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import scipy.linalg

from symmech.core import integrity, plotting, registry
from symmech.core.results import Column, Headline, Result, Table, at_most
from symmech.core.scene import SceneError, SymmechError
from symmech.core.watchdog import watchdog
from symmech.smm import build, numeric
from symmech.smm.chain import chain_spec, exact_omega2
from symmech.smm.model import Effects, Mechanism
from symmech.smm.plots import FIGURES, modes_and_responses, precision_plot
from symmech.smm.schema import SCHEMA

ROLE = "kind"  # found by symmech.core.discovery

# Above this many coordinates the symbolic matrices are not formed (numeric assembly only).
SYMBOLIC_LIMIT = 60
# `run` solves dense problems up to this size; above it matrices.json would be huge too.
DENSE_RUN_LIMIT = 3000
# Above this size a, b, c are written as sparse triplets (matrices.csv) instead of matrices.json.
JSON_LIMIT = 200
# Warn when the eigenvalue spread costs more than this relative accuracy in omega^2.
CONDITION_WARN = 1e-8
EQUILIBRIUM_TOLERANCE = 1e-8  # |dPi/dq| relative to the largest stiffness entry (times 1 m or 1 rad)
FLOP_SECONDS = 1e-10  # rough seconds per dense floating-point operation (LAPACK, one idle core), for estimates


@dataclass
class Setup:
    """A validated mechanism scene: the model, its coordinate count and the resolved scene."""

    m: Mechanism
    n: int
    scene: dict


def prepare(resolved: dict) -> Setup:
    """Build and check the mechanism; SceneError naming the field for anything inadmissible."""
    m = build.model(resolved)
    n = len(m.coordinates)
    for section, key in (("initial", "q"), ("initial", "qdot"), ("forcing", "Q")):
        values = (resolved[section] or {}).get(key)
        if values is not None and len(values) != n:
            raise SceneError(f"{section}.{key}", f"expected {n} values (one per coordinate), got {len(values)}")
    forcing = resolved["forcing"]
    if forcing and forcing["point"] is not None and forcing["point"] not in m.points:
        raise SceneError("forcing.point", f"point '{forcing['point']}' is not defined")
    if resolved["chain"] is None and n <= DENSE_RUN_LIMIT:
        # zero-length elements, indeterminate or unbalanced "equilibrium" preloads, singular inertia
        numeric.check_mass(m, numeric.assemble(m).a.toarray())
    return Setup(m, n, resolved)


def estimate(setup: Setup) -> registry.Estimate:
    """Dense eigenproblems (the inertia check's and the modes'), state-space eigenvalues, responses: O(n^3)
    flops each (the count model :func:`symmech.core.sample.timed` scales by :func:`sample`'s timed runs)."""
    n, sc = setup.n, setup.scene
    if n > DENSE_RUN_LIMIT:
        return registry.Estimate(0.0, f"{n} coordinates: refused by `run`")
    damped = bool(setup.m.dampers or setup.m.torsion_dampers) and sc["effects"]["damping"]
    flops = 16.0 * n**3 + (80.0 * n**3 if damped else 0.0)
    if sc["initial"]:
        flops += 60.0 * n**3 + sc["initial"]["steps"] * 8.0 * n**2
    if sc["forcing"]:
        flops += sc["forcing"]["samples"] * 3.0 * n**3
    seconds = FLOP_SECONDS * flops
    what = f"{n} coordinates, dense eigenproblems"
    if n <= SYMBOLIC_LIMIT:
        seconds += _symbolic_seconds(setup.m)
        what += ", the symbolic a, b, c"
    return registry.Estimate(seconds, what)


def sample(setup: Setup, share: float) -> Setup | None:
    """A ``[chain]`` scene with about ``share`` of its dense work, for :func:`symmech.core.sample.timed`: the same
    chain of n share^(1/3) masses (the work grows as n^3; enough masses to take the run's path: no symbolic
    matrices, matrices.csv above :data:`JSON_LIMIT`), its initial state and forcing cut to them. None for a chain of
    :data:`SYMBOLIC_LIMIT` coordinates or fewer and for an explicit mechanism: their run is mostly the symbolic
    a, b, c of their own points, which no smaller run repeats (the count model stands)."""
    sc = setup.scene
    least = next((limit + 1 for limit in (JSON_LIMIT, SYMBOLIC_LIMIT) if setup.n > limit), None)
    if sc["chain"] is None or least is None:
        return None
    n = min(max(least, round(setup.n * share ** (1.0 / 3.0))), setup.n)
    small = {**sc, "chain": {**sc["chain"], "n": n}}
    if sc["initial"]:
        small["initial"] = {**sc["initial"], **{k: sc["initial"][k] and sc["initial"][k][:n] for k in ("q", "qdot")}}
    if sc["forcing"]:
        point = sc["forcing"]["point"]
        inside = point is None or not point.startswith("P") or int(point[1:]) <= n
        small["forcing"] = {**sc["forcing"], "Q": sc["forcing"]["Q"] and sc["forcing"]["Q"][:n],
                            "point": point if inside else f"P{n}"}
    return prepare(small)


# The symbolic a, b, c (derivation, CSE, printing, import) of the bundled mechanisms in CPU seconds (an idle core's
# wall time; symmech.core.sample scales them by the share of a core now), within 15%: seconds per point and
# coordinate, times SPATIAL_FACTOR when an axis leaves z (rotations compose in 3-D), plus sympy's import when this
# process has not imported it yet.
SYMBOLIC_SECONDS = 0.0025
SPATIAL_FACTOR = 16.0
SYMPY_IMPORT_SECONDS = 0.25


def _symbolic_seconds(m: Mechanism) -> float:
    """Expected wall time [s] of the symbolic a, b, c of ``m`` (see :data:`SYMBOLIC_SECONDS`)."""
    planar = all(tuple(c.axis) == ("0", "0", "1") or c.kind == "slide" for c in m.coordinates)
    seconds = SYMBOLIC_SECONDS * len(m.points) * len(m.coordinates) * (1.0 if planar else SPATIAL_FACTOR)
    return seconds + (0.0 if "sympy" in sys.modules else SYMPY_IMPORT_SECONDS)


def _module_texts(m: Mechanism) -> tuple[str, dict[str, str]]:
    """File name of the scene's symbolic matrices rendered with the project emitter, and {file name: text} of that
    module and of its MathML twin (what ``symmech report`` typesets, so that a later report needs no sympy; its
    source key is the sha256 of the module's text, which ties the twin to the module beside it)."""
    from symmech.core import emit
    from symmech.smm.derive import module_spec

    spec = module_spec(m)
    text = emit.render(spec)
    name = emit.NUMPY.file(spec.name)
    return name, {name: text, emit.MATHML.file(spec.name): emit.render(spec, emit.MATHML, integrity.sha256(text))}


def _import_text(name: str, text: str):
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / name
        path.write_text(text)
        loader = importlib.util.spec_from_file_location(f"_symmech_scene_{path.stem}", path)
        module = importlib.util.module_from_spec(loader)
        loader.loader.exec_module(module)
    return module


def run(setup: Setup, ctx) -> Result:
    """The scene's matrices, modes and responses; stopped past the budget of ``ctx`` between (not within) its
    dense solves by the watchdog. LAPACK runs on one thread: OpenBLAS's threads wait for each other by spinning,
    and on a loaded machine a 800 x 800 eigenproblem took 45x longer on two threads than on one (on an idle
    machine one thread costs at most the second core)."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="blas"), watchdog(ctx, where=f"mechanism '{setup.m.name}'"):
        return _solved(setup, ctx)


def _solved(setup: Setup, ctx) -> Result:
    m, sc = setup.m, setup.scene
    if setup.n > DENSE_RUN_LIMIT:
        raise SymmechError(f"mechanism '{m.name}' has {setup.n} coordinates; `symmech run` solves the dense "
                           f"eigenproblem up to {DENSE_RUN_LIMIT}: use `symmech bench precision` (sparse "
                           "shift-invert) for the lowest modes of larger systems")
    warnings: list[str] = []
    eq_report = None
    if sc["equilibrium"]["solve"]:
        m, eq_report = numeric.solve_equilibrium(m)
    num = numeric.assemble(m)
    a, b, c = (x.toarray() for x in (num.a, num.b, num.c))
    numeric.check_mass(m, a)
    # dPi/dq [N or N m] against the stiffness scale times 1 m (or 1 rad)
    res = float(np.abs(num.residual).max())
    equilibrium = at_most("equilibrium: max |∂Π/∂q| / stiffness scale (eq. (5))", res / max(np.abs(c).max(), 1.0),
                          EQUILIBRIUM_TOLERANCE, otherwise="warn")
    if equilibrium.verdict != "pass":
        worst = m.coordinate_names[int(np.argmax(np.abs(num.residual)))]
        warnings.append(f"the configuration is not an equilibrium: dPi/dq = {res:.3g} on '{worst}' (eq. (5)); "
                        "set [equilibrium] solve = true or fix the preloads")
    files = {}
    name = None
    if setup.n <= SYMBOLIC_LIMIT:
        name, texts = _module_texts(m)
        module = _import_text(name, texts[name])
        values = [p.value for p in m.parameters.values()]
        for key, ref in (("a", a), ("b", b), ("c", c)):
            got = getattr(module, key)(*values)
            if not np.allclose(got, ref, rtol=1e-9, atol=1e-12 * max(np.abs(ref).max(), 1.0)):
                raise RuntimeError(f"generated {key} disagrees with the numeric assembly")  # a bug, not input
        files.update(texts)
    ctx.tick("modes")
    md = numeric.modes(a, b, c)
    w2 = md.omega2
    cls = md.kinds
    rigid = [i for i, k in enumerate(cls) if k == "rigid"]
    if any(k == "unstable" for k in cls):
        warnings.append(f"{cls.count('unstable')} mode(s) have negative omega^2 (unstable equilibrium), "
                        f"lowest {w2[0]:.4g} 1/s^2")
    eps = np.finfo(float).eps
    if md.spread * eps > CONDITION_WARN:
        warnings.append(f"stiffness spread omega_max^2/omega_min^2 = {md.spread:.3g}: the normwise error bound "
                        f"leaves the lowest frequencies only about {max(0.0, -math.log10(md.spread * eps)):.0f} "
                        "guaranteed digits (very stiff springs closing loops?)")
    omega = [0.0 if k == "rigid" else math.sqrt(x) if k == "elastic" else None for k, x in zip(cls, w2)]
    overdamped = [i + 1 for i, z in enumerate(md.zeta) if z is None and omega[i]]
    if overdamped and np.any(b):
        warnings.append(f"mode(s) {', '.join(map(str, overdamped))} have real damped eigenvalues (overdamped): "
                        "no damping ratio reported")
    eff_report = _effects_report(m, w2, warnings)
    files.update(_matrices_file(m, num))
    tables = {"modes": _modes_table(m, omega, md)}
    response = _responses(sc, m, a, b, c, tables)
    plots = (lambda folder: modes_and_responses(m, md, omega, response, Path(folder), sc["output"])) \
        if sc["output"]["plots"] else None
    summary = {
        "mechanism": m.name,
        "coordinates": [{"name": co.name, "type": co.kind, "unit": co.unit} for co in m.coordinates],
        "effects": {"damping": m.effects.damping, "preload": m.effects.preload, "gravity": m.effects.gravity},
        "equilibrium": eq_report,
        "equilibrium_residual": res,
        "omega2_1_per_s2": w2.tolist(),
        "frequencies_rad_s": omega,
        "frequencies_hz": [None if w is None else w / (2 * math.pi) for w in omega],
        "rigid_body_modes": len(rigid),
        "conditioning": {"stiffness_spread": md.spread, "scaled_stiffness_condition": md.condition,
                         "omega2_error_bound_1_per_s2": float(eps * len(w2) * np.abs(w2).max())},
        "damping_ratios": md.zeta,
        "neglected_effects": eff_report,
        "generated_module": name,
        "captions": plotting.captions(FIGURES, sc["output"]),
    }
    checks = [equilibrium, at_most("unstable modes (negative ω²)", cls.count("unstable"), 0),
              at_most("round-off of the lowest ω² (stiffness spread × machine epsilon)", md.spread * eps,
                      CONDITION_WARN, otherwise="warn")]
    return Result("mechanism", summary, tables, files, plots, warnings, headline=_headline(m, omega, md, tables),
                  checks=checks)


HEADLINE_MODES = 6  # natural frequencies in the headline (all are in modes.csv)


def _headline(m: Mechanism, omega: list, md, tables: dict) -> list[Headline]:
    """The lowest natural frequencies with their damping ratios, rigid-body modes, the largest responses."""
    elastic = [(i, w) for i, w in enumerate(omega) if w]
    out = [Headline(f"natural frequency f{i + 1}", w / (2 * math.pi), "Hz",
                    "overdamped" if md.zeta[i] is None else f"damping ratio {md.zeta[i]:.3g}")
           for i, w in elastic[:HEADLINE_MODES]]
    if md.kinds.count("rigid"):
        out.append(Headline("rigid-body modes", md.kinds.count("rigid"), "1",
                            "ω = 0: the mechanism can move freely"))
    if "free_response" in tables:
        q = tables["free_response"]
        coordinates = q.select([co.name for co in m.coordinates])
        i, j = np.unravel_index(np.argmax(np.abs(coordinates)), coordinates.shape)
        co = m.coordinates[j]
        out.append(Headline(f"largest free response, {co.name}", coordinates[i, j], co.unit,
                            "largest |q| of free_response.csv", f"t = {q.column('t')[i]:.4g} s"))
    if "frequency_response" in tables:
        h = tables["frequency_response"]
        amplitude = h.select([f"abs_{co.name}" for co in m.coordinates])
        i, j = np.unravel_index(np.argmax(amplitude), amplitude.shape)
        co, omega = m.coordinates[j], h.column("omega")[i]
        out.append(Headline(f"largest frequency response, {co.name}", amplitude[i, j], co.unit,
                            "amplitude of q for a unit harmonic force (frequency_response.csv)",
                            f"f = {omega / (2 * math.pi):.4g} Hz (ω = {omega:.4g} rad/s)"))
    return out


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


def _matrices_file(m: Mechanism, num) -> dict[str, str]:
    """a, b, c as matrices.json (dense) or, above JSON_LIMIT coordinates, matrices.csv (nonzeros)."""
    if len(m.coordinates) <= JSON_LIMIT:
        return {"matrices.json": json.dumps({
            "coordinates": m.coordinate_names,
            "units": [co.unit for co in m.coordinates],
            "equation": "a q'' + b q' + c q = Q",
            "parameters": {p.name: {"value": p.value, "unit": p.unit} for p in m.parameters.values()},
            "a": num.a.toarray().tolist(), "b": num.b.toarray().tolist(), "c": num.c.toarray().tolist()},
            indent=1) + "\n"}
    total = (abs(num.a) + abs(num.b) + abs(num.c)).tocoo()
    text = io.StringIO()
    w = csv.writer(text)
    w.writerow(["row", "column", "a", "b", "c"])
    names = m.coordinate_names  # built on each access
    for i, j in sorted(zip(total.row.tolist(), total.col.tolist())):
        w.writerow([names[i], names[j], repr(float(num.a[i, j])),
                    repr(float(num.b[i, j])), repr(float(num.c[i, j]))])
    return {"matrices.csv": text.getvalue()}


def _coordinate_columns(m: Mechanism, prefix: str = "", unit_of=None) -> list[Column]:
    return [Column(f"{prefix}{co.name}", unit_of(co) if unit_of else co.unit, f"coordinate {co.name}")
            for co in m.coordinates]


def _modes_table(m: Mechanism, omega, md) -> Table:
    """One row per mode: omega^2, omega and f (0 for rigid and unstable modes; see ``class``),
    the mass-normalised shape (phi^T a phi = 1); text columns class and zeta."""
    cols = [Column("mode", "1"), Column("omega2", "1/s^2", "eigenvalue of c phi = omega^2 a phi"),
            Column("omega", "rad/s"), Column("f", "Hz")]
    cols += _coordinate_columns(m, "phi_", lambda co: f"{co.unit}/sqrt(kg {co.unit}^2)")
    w = np.array([x or 0.0 for x in omega])
    data = np.column_stack([np.arange(1, len(w) + 1), md.omega2, w, w / (2 * math.pi), md.shapes.T])
    return Table(tuple(cols), data, "undamped modes",
                 {"class": list(md.kinds), "zeta": ["" if z is None else repr(z) for z in md.zeta]})


def _point_force(forcing: dict, m: Mechanism) -> np.ndarray:
    """Generalized force of a force F [N] at a point: Q_a = F . dr/dq_a."""
    from symmech.smm import forms
    from symmech.smm.model import NumericArith

    if forcing["Q"] is not None:
        return np.array(forcing["Q"])
    g = forms.Geometry(m, NumericArith(m.values()))
    kin = forms.chain_kinematics(g, forcing["point"], False)
    Q = np.zeros(len(m.coordinates))
    for a, d in kin.D.items():
        Q[g.index[a]] = float(np.dot(forcing["force"], d))
    return Q


def _responses(sc: dict, m: Mechanism, a, b, c, tables: dict) -> dict:
    """Free and frequency responses into ``tables``; returns the curves for the plots."""
    n = len(m.coordinates)
    result = {}
    ini = sc["initial"]
    if ini is not None:
        q0 = np.array(ini["q"] or [0.0] * n)
        v0 = np.array(ini["qdot"] or [0.0] * n)
        t = np.linspace(0.0, ini["duration"], ini["steps"] + 1)
        q = numeric.free_response(a, b, c, q0, v0, t)
        tables["free_response"] = Table((Column("t", "s"), *_coordinate_columns(m)), np.column_stack([t, q]),
                                        "free response q(t) from the initial state")
        result["free"] = (t, q)
    frc = sc["forcing"]
    if frc is not None:
        omegas = np.linspace(*frc["omega"], frc["samples"])
        H = numeric.frequency_response(a, b, c, _point_force(frc, m), omegas)
        cols = (Column("omega", "rad/s"), *_coordinate_columns(m, "abs_"),
                *_coordinate_columns(m, "phase_", lambda co: "rad"))
        tables["frequency_response"] = Table(cols, np.column_stack([omegas, np.abs(H), np.angle(H)]),
                                             "amplitude and phase of q for Q e^{i omega t}")
        result["frf"] = (omegas, H)
    return result


def precision(setup: Setup, ctx) -> Result:
    """Frequencies of the lowest modes: full dense eigenproblem vs eigsh shift-invert at several
    tolerances; table ``precision`` (error vs time) and precision.png. The reference is the closed
    form for ``[chain]`` scenes, else the dense solution (else eigsh at tol 0)."""
    m, n, sc = setup.m, setup.n, setup.scene
    modes_n = sc["precision"]["modes"] or max(1, min(10, n - 1))
    if modes_n > max(1, n - 1):
        raise SceneError("precision.modes", f"{modes_n} must be below the number of coordinates {n}")
    exact = None
    if sc["chain"] is not None:
        exact = np.array(exact_omega2(chain_spec(sc["chain"], sc["name"]))[:modes_n])
    t0 = time.perf_counter()
    num = numeric.assemble(m)
    t_asm = time.perf_counter() - t0
    rows = []
    if n <= sc["precision"]["dense_limit"]:
        t0 = time.perf_counter()
        w = scipy.linalg.eigh(num.c.toarray(), num.a.toarray(), eigvals_only=True, subset_by_index=[0, modes_n - 1])
        rows.append(("dense eigh", 0.0, time.perf_counter() - t0, w))
    # omega^2 scale of the whole spectrum (Gershgorin-like): round-off of a rigid mode's omega^2 is
    # relative to it. Shift 0 separates the lowest modes best; with rigid-body modes c is singular and a
    # small negative shift keeps the factorization regular.
    top = float(np.max(np.abs(num.c.diagonal()) / num.a.diagonal().clip(1e-300)))
    for tol in (1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 0.0) if modes_n < n else ():
        ctx.tick("precision")
        t0 = time.perf_counter()
        w = _eigsh(num, modes_n, tol, -1e-6 * top)
        rows.append((f"eigsh tol={tol:g}", tol, time.perf_counter() - t0, w))
    reference, ref = (("closed form", exact) if exact is not None
                      else (rows[0][0], rows[0][3]) if n <= sc["precision"]["dense_limit"]
                      else ("eigsh tol=0", rows[-1][3]))
    floor = 100 * n * np.finfo(float).eps * top
    errors = [float(np.max(np.abs(w - ref) / np.maximum(np.abs(ref), floor))) for *_, w in rows]
    table = Table((Column("tol", "1", "eigsh tolerance (0: machine precision)"),
                   Column("seconds", "s", "wall time of the solve"),
                   Column("max_rel_error_omega2", "1", f"largest relative error of the lowest {modes_n} omega^2 "
                          "(rigid modes: relative to 100 n eps max(c_ii/a_ii))"),
                   Column("assembly_seconds", "s", "sparse assembly of a, c"), Column("dof", "1")),
                  np.array([[tol, sec, err, t_asm, n] for (_, tol, sec, _), err in zip(rows, errors)]),
                  f"reference: {reference}", {"method": [r[0] for r in rows]})

    def plot(folder):
        return precision_plot(Path(folder), [(name, sec, err) for (name, _, sec, _), err in zip(rows, errors)],
                              modes_n, f"{m.name}: {n} DOF, assembly {t_asm:.2f} s; reference: {reference}")

    summary = {"mechanism": m.name, "dof": n, "modes": modes_n, "reference": reference,
               "assembly_seconds": t_asm, "omega2_reference_1_per_s2": np.asarray(ref).tolist()}
    return Result("mechanism", summary, {"precision": table}, plots=plot)


def _eigsh(num, k: int, tol: float, fallback: float) -> np.ndarray:
    """Lowest k omega^2 by shift-invert Lanczos at 0; at ``fallback`` if c is exactly singular."""
    import scipy.sparse.linalg

    for sigma in (0.0, fallback):
        try:
            return np.sort(scipy.sparse.linalg.eigsh(num.c.tocsc(), k=k, M=num.a.tocsc(), sigma=sigma, which="LM",
                                                     tol=tol, return_eigenvectors=False))
        except RuntimeError:  # "Factor is exactly singular"
            continue
    raise SymmechError("shift-invert Lanczos failed at both shifts (singular c - sigma a)")


KIND = registry.register(registry.Kind(
    name="mechanism", summary="linear(ized) lumped-parameter mechanism: SMM matrices, modes, responses (seed 003)",
    schema=SCHEMA, prepare=prepare, run=run, estimate=estimate, sample=sample, precision=precision,
    docs="docs/scenes-mechanism.md"))
