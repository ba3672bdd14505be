"""The optional ``[elastic]`` table of a trolley scene: schema, ``prepare`` and ``run``.

Not a kind of its own (nothing is registered here): the trolley kind validates its
``elastic`` field against :data:`SCHEMA`, calls :func:`prepare` with the resolved
table and the rigid trolley's body and drive, and :func:`run` returns a
:class:`~symmech.core.results.Result` whose tables sit beside the rigid ones. Field
docs: docs/scenes-trolley-elastic.md (generated from SCHEMA by ``schema.markdown``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from symmech.core import kinematics as kin
from symmech.core.results import Column, Result, Table as ResultTable
from symmech.core.scene import SceneError
from symmech.core.schema import Bool, Choice, Float, Int, Str, Table, TableList, Vector
from symmech.trolley import elastic as el
from symmech.trolley import model

ROLLERS = Table("elastic, damped rollers carrying P1…P5 (B, C, A along x2; O, A along x3)", {
    "law": Choice("force law: `linear` P = -k d - c ḋ; `clamped_pair` two rollers clamping the rail, "
                  "each compressed by `preload`", choices=("linear", "clamped_pair"), default="linear"),
    "stiffness": Vector("roller stiffness k of P1…P5", n=5, unit="N/m", lo=0.0, lo_open=True, hi=1e12),
    "damping": Vector("roller damping c of P1…P5", n=5, unit="N s/m", lo=0.0, hi=1e9, default=[0.0] * 5),
    "preload": Vector("preload of each roller of a clamped pair (negative: a gap per side)", n=5, unit="m",
                      lo=-1.0, hi=1.0, default=[0.0] * 5),
}, default=None)

BEAM = Table("an Euler–Bernoulli beam fixed to the trolley", {
    "root": Vector("root point (trolley frame)", n=3, unit="m", lo=-1e3, hi=1e3),
    "axis": Vector("direction of the beam axis (normalised)", n=3, unit="1", lo=-1e3, hi=1e3),
    "plane": Vector("first bending direction (its part across the axis is used)", n=3, unit="1", lo=-1e3, hi=1e3),
    "length": Float("length", unit="m", lo=0.0, lo_open=True, hi=1e3),
    "mass_per_length": Float("mass per unit length ρA", unit="kg/m", lo=0.0, lo_open=True, hi=1e6),
    "ei": Vector("bending stiffness EI in the first and second plane", n=2, unit="N m^2", lo=0.0, lo_open=True,
                 hi=1e15),
    "support": Choice("`cantilever` (clamped at the root) or `pinned` (pinned at both ends)",
                      choices=("cantilever", "pinned"), default="cantilever"),
    "modes": Int("Ritz functions per bending plane", lo=1, hi=8, default=4),
    "tip_mass": Float("point mass at the far end", unit="kg", lo=0.0, hi=1e6, default=0.0),
    "damping_ratio": Float("damping ratio of the first mode of each plane (stiffness-proportional)", unit="1",
                           lo=0.0, hi=1.0, hi_open=True, default=0.0),
    "axial": Choice("far end of a `pinned` beam along its axis: `free` (slides: inextensible) or `held` "
                    "(immovable supports: mid-plane stretching, needs `ea`)", choices=("free", "held"),
                    default="free"),
    "ea": Float("axial stiffness EA (held ends)", unit="N", lo=0.0, lo_open=True, hi=1e15, default=None),
})

POINT = Table("a body point whose deflection and overload are reported", {
    "name": Str("name used in the column headers", pattern=r"[A-Za-z_][A-Za-z0-9_]*"),
    "at": Vector("a point of the rigid trolley (trolley frame)", n=3, unit="m", lo=-1e3, hi=1e3, default=None),
    "beam": Int("index of the beam (0 = first [[elastic.beams]])", lo=0, hi=99, default=None),
    "xi": Float("position along that beam, x/L", unit="1", lo=0.0, hi=1.0, default=None),
})

SCHEMA = Table("elastic model of the trolley (seed 002, issue 10)", {
    "effects": Table("which elastic effects to include", {
        "rollers": Bool("elastic rollers (the five roller DOFs)", default=True),
        "body": Bool("elastic beams (else they are rigid masses)", default=True),
        "stiffening": Bool("quadratic fields ψ_ij of the beams (geometric stiffening)", default=True),
        "damping": Bool("roller and beam damping", default=True),
        "membrane": Bool("mid-plane stretching of beams with held ends (quartic energy, Duffing stiffening)",
                         default=True),
    }, default={}),
    "rollers": ROLLERS,
    "beams": TableList("elastic beams on the trolley", item=BEAM, max_items=50, default=[]),
    "points": TableList("report points", item=POINT, max_items=100, default=[]),
    "numerics": Table("integration", {
        "method": Choice("integrator (implicit ones use the analytic Jacobian)",
                         choices=("Radau", "BDF", "LSODA", "DOP853", "RK45"), default="Radau"),
        "rtol": Float("relative tolerance", unit="1", lo=1e-13, hi=1e-2, default=1e-7),
        "modal_samples": Int("instants of the modal analysis along the track", lo=0, hi=1000, default=20),
        "small_rotation": Float("roller rotation beyond which the quadratic approximation is flagged",
                                unit="rad", lo=0.0, lo_open=True, hi=1.0, default=0.05),
    }, default={}),
})


@dataclass
class Setup:
    system: el.System | None
    drive: el.Drive
    body: model.Body
    t: np.ndarray
    names: list
    method: str
    rtol: float
    modal_samples: int
    small_rotation: float


def prepare(elastic: dict, body: model.Body, drive: el.Drive, t, path: str = "elastic") -> Setup:
    """The elastic setup from the resolved ``[elastic]`` table, the rigid trolley's body
    (mass, centre, central inertia, l, ah, g0), its drive and time grid t [s]."""
    eff = el.Effects(**elastic["effects"])
    rollers = elastic["rollers"]
    if eff.rollers and rollers is None:
        raise SceneError(f"{path}.rollers", "missing: elastic rollers (effects.rollers = true) need their stiffness")
    beams = []
    for i, b in enumerate(elastic["beams"]):
        axis, plane = np.asarray(b["axis"]), np.asarray(b["plane"])
        if np.linalg.norm(axis) == 0 or np.linalg.norm(np.cross(axis, plane)) <= 1e-9 * np.linalg.norm(axis) * \
                np.linalg.norm(plane):
            raise SceneError(f"{path}.beams[{i}].plane", f"{b['plane']} must not be parallel to the axis {b['axis']}")
        _check_axial(b, f"{path}.beams[{i}]")
        beams.append(el.Beam(tuple(b["root"]), tuple(axis), tuple(plane), b["length"], b["mass_per_length"],
                             tuple(b["ei"]), b["support"], b["modes"], b["tip_mass"], b["damping_ratio"],
                             b["axial"], b["ea"] or 0.0))
    probes, names = [], []
    for i, p in enumerate(elastic["points"]):
        where = f"{path}.points[{i}]"
        if (p["at"] is None) == (p["beam"] is None or p["xi"] is None):
            raise SceneError(where, "give either `at` or both `beam` and `xi`")
        if p["beam"] is not None and p["beam"] >= len(beams):
            raise SceneError(f"{where}.beam", f"{p['beam']} is not a beam index ({len(beams)} beams given)")
        probes.append((None, tuple(p["at"])) if p["at"] is not None else (p["beam"], p["xi"]))
        names.append(p["name"])
    rl = None if rollers is None else el.Rollers(tuple(rollers["stiffness"]), tuple(rollers["damping"]),
                                                  rollers["law"], tuple(rollers["preload"]))
    mdl = el.ElasticModel(body.m, tuple(body.r), tuple(body.inertia), body.l, body.ah, body.g0, rl,
                          tuple(beams), eff)
    if eff.rollers and np.linalg.eigvalsh(kin.inertia_matrix(body.inertia))[0] <= 0:
        raise SceneError("trolley.inertia", f"{list(body.inertia)} kg m^2: elastic rollers need a positive "
                                            "inertia of the trolley about every axis")
    system = el.System(mdl, probes)
    num = elastic["numerics"]
    return Setup(system if system.N else None, drive, body, np.asarray(t, float), names, num["method"], num["rtol"],
                 num["modal_samples"], num["small_rotation"])


def _check_axial(beam: dict, where: str) -> None:
    """Held ends need two supports (``pinned``) and the axial stiffness."""
    if beam["axial"] != "held":
        return
    if beam["support"] != "pinned":
        raise SceneError(f"{where}.axial", f"`held` needs support = `pinned` (a {beam['support']} has a free end)")
    if beam["ea"] is None:
        raise SceneError(f"{where}.ea", "missing: held ends (axial = `held`) need the axial stiffness EA "
                                        "in (0, 1e+15] N")


def run(setup: Setup, ctx=None) -> Result:
    """Reactions elastic beside rigid, roller and body deflections, overloads, energy and modes."""
    t = setup.t
    if setup.system is None:
        # no elastic effect: the rigid model itself, on the rigid scene's grid (bit for bit)
        s = el.arc_length(setup.drive, t)
        V0, dV0 = setup.drive.speed(t)
        rigid = model.body_motion(el.frames(setup.drive, s, setup.body.l), V0, dV0, setup.body)
        cols = [Column("t", "s")] + [Column(f"P{i}", "N") for i in range(6)]
        return Result("trolley", {"elastic": "no elastic effect selected: rigid model"},
                      {"elastic_reactions": ResultTable(cols, np.column_stack([t, rigid["P"]]))})
    r = el.simulate(setup.system, setup.drive, t, setup.method, setup.rtol)
    warnings = _warnings(setup, r)
    tables = {"elastic_reactions": _reactions_table(r), "energy": _energy_table(r)}
    if setup.system.rollers_on:
        tables["roller_deflections"] = ResultTable(
            [Column("t", "s")] + [Column(f"d{i + 1}", "m", f"deflection of the roller of P{i + 1}") for i in range(5)],
            np.column_stack([t, r["deflection"]]))
    if setup.names:
        tables["points"] = _points_table(setup.names, r)
    if setup.modal_samples:
        tables["modes"] = _modes_table(setup, r)
    peak = np.abs(r["P"]).max(0)
    peak_rigid = np.abs(r["P_rigid"]).max(0)
    summary = {"elastic": {
        "coordinates": r["names"],
        "dynamic_amplification": {f"P{i}": float(peak[i] / peak_rigid[i]) if peak_rigid[i] > 0 else None
                                  for i in range(6)},
        "max_roller_deflection_m": float(np.abs(r["deflection"]).max()),
        "max_roller_rotation_rad": float(np.abs(r["q"][:, 2:5]).max()) if setup.system.rollers_on else 0.0,
        "dissipated_J": float(r["dissipated"][-1]),
        "function_evaluations": int(r["nfev"]),
    }}
    return Result("trolley", summary, tables, warnings=warnings)


def _warnings(setup: Setup, r) -> list:
    out = []
    if setup.system.rollers_on:
        rot = np.abs(r["q"][:, 2:5]).max()
        if rot > setup.small_rotation:
            out.append(f"elastic: roller rotation {rot:.3g} rad exceeds {setup.small_rotation:g} rad: the quadratic "
                       "approximation of the rotations is out of its range")
    for i in range(1, 6):
        flips = np.sign(r["P"][:, i]) != np.sign(r["P_rigid"][:, i])
        big = np.abs(r["P"][:, i]) > 1e-3 * np.abs(r["P_rigid"]).max()
        if np.any(flips & big):
            k = int(np.argmax(flips & big))
            out.append(f"elastic: P{i} has the opposite sign of the rigid model's at t = {r['t'][k]:.4g} s")
    return out


def _reactions_table(r) -> ResultTable:
    cols = [Column("t", "s"), Column("s", "m")] + [Column(f"P{i}", "N", "elastic") for i in range(6)] + \
           [Column(f"P{i}_rigid", "N", "rigid model") for i in range(6)]
    return ResultTable(cols, np.column_stack([r["t"], r["s"], r["P"], r["P_rigid"]]))


def _energy_table(r) -> ResultTable:
    cols = [Column("t", "s"), Column("h", "J", "T2 - T0 + Π + V_g (constant on a steady frame without damping)"),
            Column("dissipated", "J", "energy dissipated by the dampers")]
    return ResultTable(cols, np.column_stack([r["t"], r["h"], r["dissipated"]]))


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


def _modes_table(setup: Setup, r) -> ResultTable:
    system = setup.system
    idx = np.unique(np.linspace(0, len(r["t"]) - 1, setup.modal_samples).astype(int))
    n = system.N
    rows = []
    fr = el.frames(setup.drive, r["s"][idx], system.mdl.l)
    for j, i in enumerate(idx):
        fs = el.frame_state(fr, j, r["V0"][i], r["dV0"][i])
        # 2n state-space roots: at least n have Im >= 0 (the first n by modulus are kept)
        omega, zeta = system.linear_modes(fs, system.quasi_static(fs, r["q"][i]))
        rows.append(np.r_[r["t"][i], r["s"][i], r["V0"][i], omega[:n] / (2 * np.pi), zeta[:n]])
    cols = [Column("t", "s"), Column("s", "m"), Column("V0", "m/s")] + \
           [Column(f"f{k + 1}", "Hz", "natural frequency of the linearisation") for k in range(n)] + \
           [Column(f"zeta{k + 1}", "1", "damping ratio") for k in range(n)]
    return ResultTable(cols, np.array(rows))


def drive_of(trolley_setup, case: int) -> el.Drive:
    """The drive of a rigid trolley setup (:class:`symmech.trolley.scene.Setup`) for case 1 or 2."""
    if trolley_setup.traction is not None:
        raise SceneError("effects.traction", "the elastic model runs with a prescribed speed V0(t) only")
    f, df = trolley_setup.speed
    return el.Drive(trolley_setup.track, trolley_setup.frame, case == 2, lambda t: (f(t), df(t)),
                    trolley_setup.s0, trolley_setup.fd_order, trolley_setup.fd_step, trolley_setup.plan)
