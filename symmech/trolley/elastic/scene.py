"""The optional ``[elastic]`` table of a trolley scene: ``prepare`` and ``run``.

Not a kind of its own (nothing is registered here): the trolley kind validates its
``elastic`` field against :data:`~symmech.trolley.elastic.schema.SCHEMA`, calls :func:`prepare` with the resolved
table and the rigid trolley's body and drive, and :func:`run` returns a
:class:`~symmech.core.results.Result` whose tables sit beside the rigid ones. Field
docs: docs/scenes-trolley-elastic.md.
"""
from __future__ import annotations

from contextlib import nullcontext
from dataclasses import dataclass

import numpy as np

from symmech.core import engines, kinematics as kin, plotting
from symmech.numerics import build
from symmech.core.results import Column, Result, Table as ResultTable
from symmech.core.scene import SceneError, SymmechError
from symmech.trolley.elastic import system as el, body as el_body, frame as el_frame, simulate as el_sim
from symmech.trolley.elastic.body import FORCING
from symmech.trolley import model
from symmech.trolley.comfort import comfort_warning
from symmech.trolley.elastic import modal
from symmech.trolley.elastic.layout import N_ROLLER_DOFS, ROLLER_DOFS
from symmech.trolley.elastic.schema import MAX_INITIAL_DEFLECTION, SCHEMA  # noqa: F401 (SCHEMA: the kind's table, read here)

ROTATIONS = slice(ROLLER_DOFS.offset("th1"), ROLLER_DOFS.offset("th3") + 1)  # θ1…θ3 among q's roller coordinates


@dataclass
class Setup:
    system: el.System | None
    drive: el_frame.Drive
    body: model.Body
    t: np.ndarray
    names: list
    method: str
    rtol: float
    modal_samples: int
    small_rotation: float
    resonance_band: float
    dq0: np.ndarray | None = None  # (N,) coordinates at t = 0 beyond the quasi-static state [m, rad]
    dqd0: np.ndarray | None = None  # (N,) their rates [m/s, rad/s]
    engine: str = "auto"  # numerics.engine as given; engine() says what runs


# Wall time per output step [s] (bundled trolley_elastic_helix on 2 shared cores: compiled ~0.6 s for 1000 steps;
# the Python engine's: el_sim.SECONDS_PER_STEP): the estimate, and the `auto` engine's choice
SECONDS_PER_STEP = {"python": el_sim.SECONDS_PER_STEP, "compiled": 2e-3}

# the columns of the roller_deflections table beside t
DEFLECTIONS = tuple(Column(f"d{i + 1}", "m", f"deflection of the roller of P{i + 1}") for i in range(5))


def engine(setup: Setup, runs: int = 1) -> tuple[str, str]:
    """The engine that integrates the elastic model, "compiled" or "python", and why. ``auto`` takes the
    compiled engine when numba's cache holds it, else whichever answers first over ``runs`` runs of the
    setup (a sweep's points): the Python engine (:func:`simulate` then has the compiled one built in the
    background for the next run) or compiling first."""
    if setup.engine == "python":
        return "python", 'numerics.engine = "python"'
    if setup.method != "Radau":
        return "python", f"numerics.method = \"{setup.method}\": the compiled engine integrates by Radau"
    if setup.engine == "compiled":
        return "compiled", 'numerics.engine = "compiled"'
    compiled = engines.get("elastic").builder()  # imports numba: only when the compiled engine may run
    if not compiled.cold():
        return "compiled", "auto: the compiled engine is built (numba's cache)"
    python = SECONDS_PER_STEP["python"] * (len(setup.t) - 1) * runs
    if python > compiled.seconds:
        return "compiled", f"auto: the Python engine would take ~{python:.3g} s, longer than compiling first"
    return "python", compiled.cold_reason()


def simulate(setup: Setup, **kw) -> dict:
    """The elastic model along the setup's grid on the engine of :func:`engine` (keywords: those of
    :func:`symmech.trolley.elastic.simulate.simulate`, ``method`` and ``analytic_jacobian`` only on the Python engine);
    ``engine`` and ``engine_reason`` in the result name it."""
    start = {"dq0": setup.dq0, "dqd0": setup.dqd0, "rtol": setup.rtol}
    name, why = engine(setup)
    if name == "compiled":
        compiled: engines.Engine = engines.get("elastic")
        if compiled.builder().cold():  # compile under the build lock, or load what a concurrent builder made
            compiled.builder().warm()
        from symmech.trolley.elastic.compiled import Run  # its Python side: numba is imported by the run

        return compiled.run(Run(setup.system, setup.drive, setup.t, **{**start, **kw}, reason=why))
    if why.startswith(build.COLD):  # not when the Python engine runs for another reason
        engines.get("elastic").builder().warm_in_background()
    return el_sim.simulate(setup.system, setup.drive, setup.t, **{"method": setup.method, **start, **kw}, reason=why)


def prepare(elastic: dict, body: model.Body, drive: el_frame.Drive, t, path: str = "elastic") -> Setup:
    """The elastic setup from the resolved ``[elastic]`` table, the rigid trolley's body
    (mass, centre, central inertia, l, ah, g0), its drive and time grid t [s]."""
    eff = el_body.Effects(**elastic["effects"])
    rollers = elastic["rollers"]
    if eff.rollers and rollers is None:
        raise SceneError(f"{path}.rollers", "missing: elastic rollers (effects.rollers = true) need their stiffness")
    beams = []
    for i, b in enumerate(elastic["beams"]):
        axis, plane = np.asarray(b["axis"]), np.asarray(b["plane"])
        if np.linalg.norm(axis) == 0:
            raise SceneError(f"{path}.beams[{i}].axis", f"{b['axis']} has no direction")
        if np.linalg.norm(np.cross(axis, plane)) <= 1e-9 * np.linalg.norm(axis) * np.linalg.norm(plane):
            raise SceneError(f"{path}.beams[{i}].plane", f"{b['plane']} must not be parallel to the axis {b['axis']}")
        _check_axial(b, f"{path}.beams[{i}]")
        beams.append(el_body.Beam(tuple(b["root"]), tuple(axis), tuple(plane), b["length"], b["mass_per_length"],
                             tuple(b["ei"]), b["support"], b["modes"], b["tip_mass"], b["damping_ratio"],
                             b["axial"], b["ea"] or 0.0))
    probes, names = [], []
    for i, p in enumerate(elastic["points"]):
        where = f"{path}.points[{i}]"
        if (p["at"] is None) == (p["beam"] is None or p["xi"] is None):
            raise SceneError(where, "give either `at` or both `beam` and `xi`")
        if p["beam"] is not None and p["beam"] >= len(beams):
            raise SceneError(f"{where}.beam", f"{p['beam']} is not a beam index ({len(beams)} beams given)")
        if p["name"] in names:
            raise SceneError(f"{where}.name", f"{p['name']!r} names an earlier point too")
        probes.append((None, tuple(p["at"])) if p["at"] is not None else (p["beam"], p["xi"]))
        names.append(p["name"])
    rl = None if rollers is None else el_body.Rollers(tuple(rollers["stiffness"]), tuple(rollers["damping"]),
                                                  rollers["law"], tuple(rollers["preload"]))
    mdl = el_body.ElasticModel(body.m, tuple(body.r), tuple(body.inertia), body.l, body.ah, body.g0, rl,
                          tuple(beams), eff)
    if eff.rollers and np.linalg.eigvalsh(kin.inertia_matrix(body.inertia))[0] <= 0:
        raise SceneError("trolley.inertia", f"{list(body.inertia)} kg m^2: elastic rollers need a positive "
                                            "inertia of the trolley about every axis")
    system = el.System(mdl, probes)
    num = elastic["numerics"]
    if not system.N and drive.traction is not None:
        raise SceneError(f"{path}.effects", "with traction, select at least one elastic effect (rollers or body "
                                            "with beams): the rigid traction run is the trolley's own")
    dq0, dqd0 = _initial(elastic["initial"], system, f"{path}.initial")
    return Setup(system if system.N else None, drive, body, np.asarray(t, float), names, num["method"], num["rtol"],
                 num["modal_samples"], num["small_rotation"], num["resonance_band"], dq0, dqd0, num["engine"])


def _initial(initial: dict, system: el.System, path: str) -> tuple[np.ndarray, np.ndarray]:
    """Offsets (N,) of the coordinates and of their rates at t = 0 from the resolved
    ``[elastic.initial]`` table, checked against the model."""
    dq0, dqd0 = np.zeros(system.N), np.zeros(system.N)
    for key, target in (("rollers", dq0), ("roller_rates", dqd0)):
        if any(initial[key]):
            if not system.rollers_on:
                raise SceneError(f"{path}.{key}", f"{initial[key]}: the rollers are rigid (effects.rollers = false)")
            target[:N_ROLLER_DOFS] = initial[key]
    seen = set()
    for i, entry in enumerate(initial["beams"]):
        where = f"{path}.beams[{i}]"
        beam, plane, mode = entry["beam"], entry["plane"], entry["mode"]
        if beam >= len(system.mdl.beams):
            raise SceneError(f"{where}.beam", f"{beam} is not a beam index ({len(system.mdl.beams)} beams given)")
        b = system.mdl.beams[beam]
        if not system.mdl.effects.body:
            raise SceneError(where, "the beams are rigid (effects.body = false): they have no modes to deflect")
        if mode > b.modes:
            raise SceneError(f"{where}.mode", f"{mode} is outside [1, {b.modes}] (the beam's `modes`)")
        bound = MAX_INITIAL_DEFLECTION * b.length
        if abs(entry["amplitude"]) > bound:
            raise SceneError(f"{where}.amplitude", f"{entry['amplitude']:g} m is outside [{-bound:g}, {bound:g}] m "
                                                   f"({MAX_INITIAL_DEFLECTION:g} of the beam's length: the beam "
                                                   "model assumes small slopes)")
        if (beam, plane, mode) in seen:
            raise SceneError(where, f"beam {beam}, plane {plane}, mode {mode} is given by an earlier entry too")
        seen.add((beam, plane, mode))
        shape = el.beam_mode(system, beam, plane, mode)
        dq0 += entry["amplitude"] * shape
        dqd0 += entry["velocity"] * shape
    return dq0, dqd0


def _check_axial(beam: dict, where: str) -> None:
    """Held ends need two supports (``pinned``) and the axial stiffness."""
    if beam["axial"] != "held":
        return
    if beam["support"] != "pinned":
        raise SceneError(f"{where}.axial", f"`held` needs support = `pinned` (a {beam['support']} has a free end)")
    if beam["ea"] is None:
        raise SceneError(f"{where}.ea", "missing: held ends (axial = `held`) need the axial stiffness EA "
                                        "in (0, 1e+15] N")


def run(setup: Setup, ctx=None, comfort: dict | None = None) -> Result:
    """Reactions elastic beside rigid, roller and body deflections, overloads against the
    ``comfort`` envelope ({axis: (lo, hi)} [g]), energy balance and modes, with plots."""
    t = setup.t
    if setup.system is None:
        # no elastic effect: the rigid model itself, on the rigid scene's grid (bit for bit)
        s = el_frame.arc_length(setup.drive, t)
        V0, dV0 = setup.drive.speed(t)
        rigid = model.body_motion(setup.drive.frames(s), V0, dV0, setup.body)
        cols = [Column("t", "s")] + [Column(f"P{i}", "N") for i in range(6)]
        return Result("trolley", {"elastic": "no elastic effect selected: rigid model"},
                      {"elastic_reactions": ResultTable(cols, np.column_stack([t, rigid["P"]]))})
    if ctx is not None:
        ctx.tick("elastic model")
    with ctx.active() if ctx is not None else nullcontext():  # the engines tick it, a fallback re-estimates
        r = simulate(setup)
    modes, failed = _modal_analysis(setup, r)
    tables = {"elastic_reactions": _reactions_table(r), "energy": _energy_table(r)}
    if setup.system.rollers_on:
        tables["roller_deflections"] = ResultTable((Column("t", "s"), *DEFLECTIONS), np.column_stack([t, r["deflection"]]))
    if setup.names:
        tables["points"] = _points_table(setup.names, r)
    if modes is not None:
        tables["modes"] = _modes_table(modes, setup.names)
    summary, warnings = _summary(setup, r, comfort)
    warnings += failed + _warnings(setup, r, modes)

    def draw(folder, output=None):
        """The elastic figures ``output`` (an ``[output]`` table) asks for; all of them by default."""
        from symmech.trolley import plots

        figures = plots.elastic_figures(setup, r, modes, comfort)
        return plotting.draw(figures, output or {"plots": list(figures), "formats": ["png"]}, folder)
    return Result("trolley", summary, tables, plots=draw, warnings=warnings)


def _summary(setup: Setup, r, comfort) -> tuple[dict, list]:
    peak = np.abs(r["P"]).max(0)
    peak_rigid = np.abs(r["P_rigid"]).max(0)
    residual = energy_residual(r)
    scale = max(np.abs(r["work"]).max(), np.abs(r["E"] - r["E"][0]).max(), r["dissipated"][-1], 1e-300)
    info = {
        "coordinates": r["names"],
        "dynamic_amplification": {f"P{i}": float(peak[i] / peak_rigid[i]) if peak_rigid[i] > 0 else None
                                  for i in range(6)},
        "max_roller_deflection_m": float(np.abs(r["deflection"]).max()),
        "max_roller_rotation_rad": float(np.abs(r["q"][:, ROTATIONS]).max()) if setup.system.rollers_on else 0.0,
        "dissipated_J": float(r["dissipated"][-1]),
        "track_work_J": float(r["work"][-1]),
        "energy_residual_max_J": float(np.abs(residual).max()),
        "energy_residual_relative": float(np.abs(residual).max() / scale),
        "function_evaluations": int(r["nfev"]),
        "engine": r["engine"],
        "engine_reason": r["engine_reason"],
    }
    if r["engine"] == "compiled":
        info["frame_table_nodes"] = int(r["frame_table_nodes"])
        info["frame_interpolation_error"] = float(r["frame_interpolation_error"])
    warnings = []
    if comfort and setup.names:
        info["comfort"] = {}
        for j, name in enumerate(setup.names):
            info["comfort"][name] = {}
            for k, (axis, (lo, hi)) in enumerate(comfort.items()):
                n = r["probe_overload"][:, j, k]
                bad = (n < lo) | (n > hi)
                info["comfort"][name][axis] = {"envelope_g": [lo, hi], "min_g": float(n.min()), "max_g": float(n.max()),
                                               "samples_outside": int(bad.sum())}
                if bad.any():
                    warnings.append(comfort_warning(f"elastic: overload of point {name}", axis, (lo, hi),
                                                    r["t"][np.argmax(bad)]))
    return {"elastic": info}, warnings


def energy_residual(r) -> np.ndarray:
    """E(t) - E(0) - W(t) + E_d(t) [J]: zero when the total energy changes by the work of the
    track forces W less the dissipated energy E_d (up to the integration error)."""
    return r["E"] - r["E"][0] - r["work"] + r["dissipated"]


CURVATURE_RATE_FLOOR = 1e-9  # 1/m: |Ω'|/max|Ω| below this is rounding (a uniform helix), not forcing


def forcing_frequencies(l: float, V0, W, dW, W_max: float) -> np.ndarray:
    """(n, 3) [Hz] of :data:`FORCING` at speeds V0 [m/s] (n,), Darboux vectors Ω [rad/m] and Ω'
    [rad/m²] (n, 3): the rear axle meets each track feature l/|V0| after the front one; gravity
    and the frame loads turn in the body frame at |ω| = |V0| |Ω|; the loads vary as Ω does,
    at |V0| |Ω'| / max|Ω| (for Ω = Ω0 sin(2π s/λ) at most |V0|/λ). Zero where undefined."""
    speed = np.abs(np.asarray(V0, float))
    rate = np.linalg.norm(dW, axis=-1) / W_max if W_max > 0 else 0 * speed
    rate = np.where(rate > CURVATURE_RATE_FLOOR, rate, 0.0)
    curvature = speed * rate / (2 * np.pi)
    return np.column_stack([speed / l, speed * np.linalg.norm(W, axis=-1) / (2 * np.pi), curvature])


def sign_changes(P: np.ndarray, P_rigid: np.ndarray) -> dict[int, tuple[str, int]]:
    """The roller reactions P1…P5 (columns 1-5 of ``P``, ``P_rigid`` (n, 6) [N], elastic and rigid) whose sign
    is not kept, beyond a thousandth of the largest rigid reaction: {i: ("flip", first sample) where P_i has the
    rigid one's opposite sign, else ("lift-off", first sample) where it changes sign (the roller would lift off)}."""
    threshold = 1e-3 * np.abs(P_rigid).max()
    out = {}
    for i in range(1, 6):
        flips = (np.sign(P[:, i]) != np.sign(P_rigid[:, i])) & (np.abs(P[:, i]) > threshold)
        if np.any(flips):
            out[i] = ("flip", int(np.argmax(flips)))
        elif P[:, i].max() > threshold and P[:, i].min() < -threshold:
            out[i] = ("lift-off", int(np.argmax(np.sign(P[1:, i]) != np.sign(P[:-1, i]))) + 1)
    return out


def _warnings(setup: Setup, r, modes) -> list:
    out = []
    if setup.system.rollers_on:
        rot = np.abs(r["q"][:, ROTATIONS]).max()
        if rot > setup.small_rotation:
            out.append(f"elastic: roller rotation {rot:.3g} rad exceeds {setup.small_rotation:g} rad: the quadratic "
                       "approximation of the rotations is out of its range")
    for i, (kind, k) in sign_changes(r["P"], r["P_rigid"]).items():
        out.append(f"elastic: P{i} has the opposite sign of the rigid model's at t = {r['t'][k]:.4g} s"
                   if kind == "flip" else
                   f"elastic: P{i} changes sign at t = {r['t'][k]:.4g} s: a roller pressing on one side only "
                   "would lift off")
    if modes is not None:
        out += _resonances(setup, modes) + _mode_warnings(modes)
    return out


TRACKING_MAC = 0.5  # a matched MAC below this between consecutive samples: the identity is uncertain
CURVATURE_FLAG = 1e-3  # relative frequency change by the left-out curvature energy that is flagged


def _mode_warnings(modes) -> list:
    """Mode tracking left uncertain by sparse samples; frequencies shifted by the quasi-static
    deflection beyond the model's consistent order (the left-out curvature energy)."""
    out = []
    if modes["mac_min"].size and modes["mac_min"].min() < TRACKING_MAC:
        j = int(np.argmin(modes["mac_min"]))
        out.append(f"elastic: mode tracking is uncertain between t = {modes['t'][j]:.4g} s and "
                   f"{modes['t'][j + 1]:.4g} s (a matched MAC of {modes['mac_min'][j]:.2f}): more "
                   "numerics.modal_samples follow the shapes more closely")
    shift = np.abs(modes["curvature_shift"])
    if shift.max() > CURVATURE_FLAG:
        j, k = np.unravel_index(np.argmax(shift), shift.shape)
        out.append(f"elastic: the quasi-static beam deflection (slope {modes['slope'][j]:.3g}) shifts mode "
                   f"{k + 1} ({modes['label'][j][k]}, f = {modes['f'][j, k]:.4g} Hz) at t = {modes['t'][j]:.4g} s "
                   f"by {100 * modes['deflection_shift']:+.3g} %, beyond the model's consistent order: the nonlinear "
                   f"curvature energy of that order, left out, would change it by "
                   f"{100 * modes['curvature_shift'][j, k]:+.3g} % (flagged above {100 * CURVATURE_FLAG:g} %)")
    return out


def _resonances(setup: Setup, modes) -> list:
    out = []
    f, forcing = modes["f"], modes["forcing"]
    for j, (_name, doc) in enumerate(FORCING):
        fj = forcing[:, j:j + 1]
        near = (fj > 0) & (f > 0) & (np.abs(f - fj) <= setup.resonance_band * fj)
        if near.any():
            i, k = np.argwhere(near)[0]
            out.append(f"elastic: natural frequency of mode {k + 1} ({modes['label'][i][k]}) {f[i, k]:.4g} Hz is "
                       f"within {100 * setup.resonance_band:g} % of the {doc} = {fj[i, 0]:.4g} Hz at t = "
                       f"{modes['t'][i]:.4g} s (s = {modes['s'][i]:.4g} m)")
    return out


def _reactions_table(r) -> ResultTable:
    cols = [Column("t", "s"), Column("s", "m")] + [Column(f"P{i}", "N", "elastic") for i in range(6)] + \
           [Column(f"P{i}_rigid", "N", "rigid model") for i in range(6)]
    return ResultTable(cols, np.column_stack([r["t"], r["s"], r["P"], r["P_rigid"]]))


def _energy_table(r) -> ResultTable:
    cols = [Column("t", "s"), Column("h", "J", "T2 - T0 + Π + V_g (constant on a steady frame without damping)"),
            Column("E", "J", "total energy T + Π + V_g in the fixed frame"),
            Column("work", "J", "work of the track forces on the body"),
            Column("dissipated", "J", "energy dissipated by the dampers"),
            Column("residual", "J", "E - E(0) - work + dissipated (zero up to the integration error)")]
    return ResultTable(cols, np.column_stack([r["t"], r["h"], r["E"], r["work"], r["dissipated"],
                                              energy_residual(r)]))


def _points_table(names, r) -> ResultTable:
    cols, data = [Column("t", "s")], [r["t"]]
    for j, name in enumerate(names):
        for k in range(3):
            cols.append(Column(f"{name}_u{k + 1}", "m", "displacement relative to the track frame"))
            data.append(r["probe_displacement"][:, j, k])
        for k in range(3):
            cols.append(Column(f"{name}_e{k + 1}", "m", "elastic deflection of the body"))
            data.append(r["probe_elastic"][:, j, k])
        for k in range(3):
            cols.append(Column(f"{name}_n{k + 1}", "g", "overload (a - g)/g0"))
            data.append(r["probe_overload"][:, j, k])
    return ResultTable(cols, np.column_stack(data))


def _modal_analysis(setup: Setup, r) -> tuple[dict | None, list]:
    """:func:`_modes` when asked for, and the warning that replaces it when it fails: an
    auxiliary analysis never discards the finished integration (the modes table and the
    Campbell plot are then left out)."""
    if not setup.modal_samples:
        return None, []
    try:
        return _modes(setup, r), []
    except (SymmechError, np.linalg.LinAlgError, ArithmeticError) as exc:
        return None, [f"elastic: modal analysis (modes table, Campbell plot) failed and is left out: {exc}"]


def _modes(setup: Setup, r) -> dict:
    """The linearisation about the quasi-static state at ``modal_samples`` instants, its modes
    followed by shape (:mod:`symmech.trolley.elastic.modal`): per sample (n,) t, s, V0 and the forcing
    frequencies (n, 3); per sample and mode_id (n, N) the frequency f [Hz], damping ratio,
    dominant component (beam, plane, mode number, roller DOF, label), its participation and its
    group's, the left-out curvature energy's relative shift; the shapes at the report points
    (n, N, P, 3) relative to the mode's mass-weighted RMS displacement; the smallest MAC between
    consecutive samples (n - 1,) and the largest beam slope of each quasi-static state (n,)."""
    system = setup.system
    idx = np.unique(np.linspace(0, len(r["t"]) - 1, setup.modal_samples).astype(int))
    n = system.N
    fr = setup.drive.frames(r["s"][idx])
    comp = modal.components(system)
    states, samples, omegas, zetas = [], [], [], []
    for j, i in enumerate(idx):
        fs = el_frame.frame_state(fr, j, r["V0"][i], r["dV0"][i])
        q = system.quasi_static(fs, r["q"][i])
        # 2n state-space roots: at least n have Im >= 0 (the first n by modulus are kept)
        omega, z, X = system.linear_modes(fs, q, shapes=True)
        bad = ~(np.isfinite(omega[:n]).all() & np.isfinite(z[:n]).all() & np.isfinite(X[:, :n]).all())
        if bad:
            raise SymmechError(f"non-finite natural frequencies at t = {r['t'][i]:.4g} s")
        states.append(q)
        samples.append((system.mass(q), X[:, :n]))
        omegas.append(omega[:n])
        zetas.append(z[:n])
    order, shapes, worst = modal.track(samples)
    rows = [_identity(system, comp, q, M, X, omegas[j][order[j]]) for j, (q, (M, _), X)
            in enumerate(zip(states, samples, shapes))]
    out = {key: np.array([row[key] for row in rows]) for key in rows[0]}
    out["label"] = [row["label"] for row in rows]
    out["zeta"] = np.array([z[o] for z, o in zip(zetas, order)])
    j, k = np.unravel_index(np.argmax(np.abs(out["curvature_shift"])), out["f"].shape)
    out["deflection_shift"] = _deflection_shift(system, el_frame.frame_state(fr, j, r["V0"][idx[j]], r["dV0"][idx[j]]),
                                                samples[j][0], shapes[j][:, k], out["f"][j, k])
    W_max = float(np.linalg.norm(r["W"], axis=1).max())
    forcing = forcing_frequencies(system.mdl.l, r["V0"][idx], r["W"][idx], r["dW"][idx], W_max)
    return {**out, "t": r["t"][idx], "s": r["s"][idx], "V0": r["V0"][idx], "forcing": forcing, "mac_min": worst,
            "slope": np.array([modal.beam_slope(system, q) for q in states])}


def _identity(system: el.System, comp: modal.Components, q, M, X, omega) -> dict:
    """Per mode (k,) at one instant (state q, mass M, modes X (N, k) of frequencies ω [rad/s]):
    f [Hz], the dominant component, its and its group's shares, the left-out curvature shift,
    and the shapes at the report points (k, P, 3)."""
    share = modal.participation(comp, M, X)
    top = np.argmax(share, axis=0)
    return {"f": omega / (2 * np.pi), "beam": comp.beam[top], "plane": comp.plane[top],
            "mode_number": comp.mode_number[top], "dof": comp.dof[top],
            "participation": share[top, np.arange(len(top))],
            "group_participation": np.array([share[comp.group == comp.group[k], m].sum() for m, k in enumerate(top)]),
            "label": [comp.labels[k] for k in top], "curvature_shift": modal.curvature_shift(system, q, omega, X),
            "shape": _probe_shapes(system, q, M, X)}


def _deflection_shift(system: el.System, fs: el_frame.FrameState, M, x, f: float) -> float:
    """f / f_0 - 1 of the mode x (N,) of frequency f [Hz]: f_0 the frequency of the mode of the
    linearisation about the undeformed state (q = 0, same frame) closest to x by MAC."""
    omega, _, X = system.linear_modes(fs, np.zeros(system.N), shapes=True)
    best = int(np.argmax(modal.mac(M, x[:, None], X[:, :system.N])[0]))
    return float(2 * np.pi * f / omega[best] - 1)


def _probe_shapes(system: el.System, q, M, X) -> np.ndarray:
    """Real shapes (k, P, 3) of the modes X (N, k) at the report points, each relative to the
    mode's mass-weighted RMS displacement √(xᴴ M x / m) of the whole body."""
    _, A = system.coefficients(q)
    u = np.einsum("ak,af,fpi->kpi", X, A, system.inv.probe_fields)
    rms = np.sqrt(np.real(np.einsum("ak,ab,bk->k", X.conj(), M, X)) / system.inv.mass)
    return np.real(u) / rms[:, None, None]


MODE_KEYS = (("beam", "1", "beam of the dominant component (-1: the rollers)"),
             ("plane", "1", "its bending plane (1: along the beam's plane, 2: axis × plane; 0: rollers)"),
             ("mode_number", "1", "its mode of the beam alone on a fixed trolley (1 = lowest; 0: rollers)"),
             ("dof", "1", "roller DOF of the dominant component (1…5: u2, u3, θ1, θ2, θ3; 0: a beam)"),
             ("participation", "1", "share of the mode's kinetic norm in the dominant component"),
             ("group_participation", "1", "share in the dominant component's beam plane (or all roller DOFs)"),
             ("curvature_shift", "1", "relative change of f by the curvature energy the model leaves out "
                                      "(first order; docs/trolley-elastic.md)"))


def _modes_table(modes: dict, names: list) -> ResultTable:
    """One row per sample and mode_id (samples outer)."""
    n_s, n = modes["f"].shape
    rep = lambda a: np.repeat(np.asarray(a), n, axis=0)  # noqa: E731  per sample -> per row
    cols = [Column("t", "s"), Column("s", "m"), Column("V0", "m/s"),
            Column("mode_id", "1", "the mode followed along the track by its shape (1…N: frequency order at "
                                   "the first sample)"),
            Column("f", "Hz", "natural frequency of the linearisation"), Column("zeta", "1", "damping ratio")] + \
           [Column(key, unit, doc) for key, unit, doc in MODE_KEYS] + \
           [Column(f"shape_{name}_{k + 1}", "1", f"mode shape at the report point along x{k + 1}, relative to the "
                   "mode's mass-weighted RMS displacement") for name in names for k in range(3)] + \
           [Column(f"forcing_{name}", "Hz", doc) for name, doc in FORCING]
    data = [rep(modes[key]) for key in ("t", "s", "V0")] + [np.tile(np.arange(1.0, n + 1), n_s)] + \
           [modes[key].ravel() for key in ("f", "zeta")] + [modes[key].ravel() for key, _, _ in MODE_KEYS] + \
           [modes["shape"][:, :, p, k].ravel() for p in range(len(names)) for k in range(3)] + \
           [rep(modes["forcing"][:, j]) for j in range(len(FORCING))]
    return ResultTable(cols, np.column_stack(data), text={"component": [x for row in modes["label"] for x in row]},
                       grid={"t": "t", "mode": "mode_id"})


PRECISION_RTOLS = (1e-4, 1e-6, 1e-8)
# (name, simulate options, tolerances): explicit DOP853 is bound by the stability of its steps
# on stiff rollers (the same time at every rtol on the bundled scene), so it is run once; the
# compiled engine (Radau, analytic J) where the scene can run it.
PRECISION_METHODS = (("Radau, analytic J", {"method": "Radau"}, PRECISION_RTOLS),
                     ("BDF, analytic J", {"method": "BDF"}, PRECISION_RTOLS),
                     ("Radau, FD J", {"method": "Radau", "analytic_jacobian": False}, PRECISION_RTOLS),
                     ("DOP853", {"method": "DOP853"}, PRECISION_RTOLS[:1]))
COMPILED_METHOD = "Radau, analytic J, compiled"
PRECISION_REFERENCE = {"method": "Radau", "rtol": 1e-11, "atol_q": 1e-17}


def precision(setup: Setup, ctx) -> Result:
    """Work-precision of the elastic model on the scene's grid: integrators (implicit with the
    analytic or a differenced Jacobian, explicit; the compiled engine's Radau) over relative tolerances
    (absolute: rtol x 1e-6 m on the coordinates); error max|P - P_ref| / max|P_ref| of the reactions, the
    reference by the Python engine's Radau at rtol 1e-11 (steps small enough to resolve every mode)."""
    from symmech.core import precision as wp

    if setup.system is None:
        raise SymmechError("bench precision of an elastic trolley needs an elastic effect (elastic.effects)")
    with ctx.active():  # the Python engine stops at --max-time within a run, not only between runs
        ctx.tick("elastic precision: reference")
        python = Setup(**{**setup.__dict__, "engine": "python"})
        ref = simulate(python, **PRECISION_REFERENCE)["P"]
        scale = max(np.abs(ref).max(), 1e-300)
        runs = [(name, python, kw, rtols) for name, kw, rtols in PRECISION_METHODS]
        compiled = Setup(**{**setup.__dict__, "engine": "compiled", "method": "Radau"})
        if engine(compiled)[0] == "compiled":
            engines.get("elastic").builder().warm()  # its first compile is not a cost of any row (imports numba)
            runs.append((COMPILED_METHOD, compiled, {}, PRECISION_RTOLS))
        rows = []
        for name, st, kw, rtols in runs:
            for rtol in rtols:
                ctx.tick(f"elastic precision: {name}, rtol {rtol:g}")
                seconds, out = wp.best_time(lambda: simulate(st, rtol=rtol, atol_q=rtol * 1e-6, **kw), repeats=1,
                                            min_seconds=0.0)
                rows.append({"method": name, "knob": "rtol", "value": rtol, "seconds": seconds,
                             "error": float(np.abs(out["P"] - ref).max() / scale)})
    reference = (f"Radau (Python engine) at rtol {PRECISION_REFERENCE['rtol']:g}, atol "
                 f"{PRECISION_REFERENCE['atol_q']:g} m (coordinates); error max|P - P_ref| / max|P_ref| over the grid")
    return wp.result("trolley", rows, "precision_elastic", "Elastic trolley: work-precision (reactions P0…P5)",
                     reference)


def drive_of(trolley_setup, case: int) -> el_frame.Drive:
    """The drive of a rigid trolley setup (:class:`symmech.trolley.scene.Setup`) for case 1 or 2:
    its speed V0(t), or its traction P0(t, V0) with the initial speed."""
    st = trolley_setup
    if st.traction is not None:
        return el_frame.Drive(st.frames(case), speed=None, s0=st.s0, traction=st.traction, v_initial=st.v_initial)
    f, df = st.speed
    return el_frame.Drive(st.frames(case), speed=lambda t: (f(t), df(t)), s0=st.s0)
