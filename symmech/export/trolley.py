"""The elastic trolley as an exported model: the invariants of its assembly, the frame table and the outputs.

The C side (``c/elastic_trolley.c``, generic sums over the data written here) evaluates the same equations
as the compiled engine (:mod:`symmech.trolley.elastic.kernels`): states q, q' (``<coordinate>``,
``der(<coordinate>)``), M y' = F with M = diag(1, M(q)); the frame's motion along the track at the
prescribed speed as the engine's cubic spline table of the 12 frame channels in t
(:func:`symmech.trolley.elastic.compiled.frame_table`, the same nodes and coefficients) with the arc length
s beside them. Outputs: the native run's columns (``elastic_reactions``, ``roller_deflections``,
``points``); parameters: the rollers' stiffnesses and dampings. The track and the speed are in the table:
they are not parameters, and the FMU has no inputs.
"""
from __future__ import annotations

import numpy as np
from scipy.interpolate import CubicSpline

from symmech.core.results import Column, Table
from symmech.core.scene import SymmechError
from symmech.export.model import ExportModel, Variable
from symmech.export.sources import glue

IDENTIFIER = "elastic_trolley"
ROTATIONS = ("th1", "th2", "th3")  # roller coordinates in rad; the others (u2, u3, beam modes) in m


def load(scene) -> ExportModel:
    """The export model of a trolley scene with an ``[elastic]`` table (``scene`` a loaded pipeline scene);
    SymmechError for what the export does not cover."""
    from symmech.trolley.elastic import scene as elastic_scene

    setup = scene.setup.elastic
    if setup is None or setup.system is None:
        raise SymmechError("kind = 'trolley': `symmech export` covers the elastic trolley (an [elastic] table "
                           "with an elastic effect) and mechanism scenes (docs/export.md)")
    if setup.drive.traction is not None:
        raise SymmechError("effects.traction = true: `symmech export` covers the elastic trolley at a "
                           "prescribed motion.speed so far (docs/export.md)")
    if not setup.system.rollers_on:
        raise SymmechError("elastic.effects.rollers = false: `symmech export` covers the elastic trolley on "
                           "elastic rollers so far (docs/export.md)")
    return elastic(setup, elastic_scene.simulate(setup))


def state_layout(system) -> tuple[list[str], list[str]]:
    """Names and units of the elastic model's coordinates q (its state is (q, q')): the one place that reads
    the engine's state order."""
    names = list(system.inv.names)
    return names, ["rad" if n in ROTATIONS else "m" for n in names]


def elastic(setup, run: dict) -> ExportModel:
    """The export model of a prepared elastic setup (``symmech.trolley.elastic.scene.Setup``) whose native
    run (``elastic_scene.simulate``) is ``run``."""
    from symmech.trolley.elastic import frame as el_frame, simulate as el_sim
    from symmech.trolley.elastic import compiled as elastic_compiled

    system, drive, t = setup.system, setup.drive, setup.t
    line = el_sim.Timeline(system, drive, t)
    V0, dV0 = (np.broadcast_to(np.asarray(x, float), t.shape) for x in drive.speed(t))
    fr = el_frame.frames(drive, line.s_nodes, system.mdl.l)
    table = elastic_compiled.frame_table(system, drive, t, setup.rtol,
                                         elastic_compiled.frame_channels(fr, V0, dV0, system.mdl.g0))
    if table is None:
        raise SymmechError("the frame along the track cannot be tabulated within its bound (a non-smooth track "
                           "or speed): `symmech export` needs the compiled engine's table")
    names, units = state_layout(system)
    n = len(names)
    q0 = np.asarray(run["q"][0])
    qd0 = np.asarray(run["qd"][0])
    variables = [Variable("time", 0, "independent", "continuous", "s", "simulation time")]
    for i in range(n):
        variables.append(Variable(names[i], 1 + i, "output", "continuous", units[i], f"coordinate {names[i]}",
                                  float(q0[i]), nominal=_nominal(run["q"][:, i])))
    for i in range(n):
        variables.append(Variable(f"der({names[i]})", 1 + n + i, "output", "continuous", f"{units[i]}/s",
                                  f"rate of {names[i]}", float(qd0[i]), derivative_of=1 + i,
                                  nominal=_nominal(run["qd"][:, i])))
    for i in range(n):
        variables.append(Variable(f"der({names[i]},2)", 1 + 2 * n + i, "output", "continuous", f"{units[i]}/s^2",
                                  f"acceleration of {names[i]}", derivative_of=1 + n + i))
    columns = output_columns(setup.names)
    for k, c in enumerate(columns):
        variables.append(Variable(c.name, 1 + 3 * n + k, "output", "continuous", c.unit, c.doc))
    variables += _parameters(system, 1 + 3 * n + len(columns))
    native = Table((Column("t", "s"), Column("s", "m")) + tuple(Column(f"P{i}", "N") for i in range(6)),
                   np.column_stack([t, run["s"], run["P"]]), doc="elastic reactions")
    source = data(system, drive, table) + glue("elastic_trolley.c")
    return ExportModel(IDENTIFIER, "Elastic trolley along its track at the prescribed speed (symmech)", source,
                       tuple(variables), 2 * n, n, n, 0, 0, len(PARAMETERS) * 5, native, n_y=len(columns))


# The tunable parameters, in the order c/elastic_trolley.c reads p: the rollers' [elastic.rollers] fields
PARAMETERS = (("stiffness", "N/m", "stiffness"), ("damping", "N s/m", "damping (0 without effects.damping)"))


def _parameters(system, vr: int) -> list[Variable]:
    """The rollers' stiffnesses and dampings from value reference ``vr`` on (``elastic.rollers.stiffness[1]``
    … as the scene's fields): they enter only the roller forces, so they stay tunable."""
    from symmech.trolley.elastic import kernels as ek

    roll = ek.pack(system).roll  # (3, 5): stiffness, damping as the engine applies it, preload
    out = []
    for row, (field, unit, what) in enumerate(PARAMETERS):
        for r in range(5):
            out.append(Variable(f"elastic.rollers.{field}[{r + 1}]", vr + 5 * row + r, "parameter", "tunable", unit,
                                f"{what} of the roller of P{r + 1}", float(roll[row, r])))
    return out


def output_columns(points: list[str]) -> tuple[Column, ...]:
    """The calculated outputs in the order ``elastic_trolley_outputs`` writes them: the native run's columns."""
    cols = [Column("s", "m", "arc length of O along the track"), Column("P0", "N", "track force along x1")]
    cols += [Column(f"P{i}", "N", f"force of roller {i}") for i in range(1, 6)]
    cols += [Column(f"d{i}", "m", f"deflection of the roller of P{i}") for i in range(1, 6)]
    for name in points:
        cols += [Column(f"{name}_u{k}", "m", "displacement relative to the track frame") for k in (1, 2, 3)]
        cols += [Column(f"{name}_e{k}", "m", "elastic deflection of the body") for k in (1, 2, 3)]
        cols += [Column(f"{name}_n{k}", "g", "overload (a - g)/g0") for k in (1, 2, 3)]
    return tuple(cols)


def _nominal(series: np.ndarray) -> float:
    """A state's magnitude over the native run (1 where it stays zero)."""
    top = float(np.abs(series).max())
    return top if top > 0 else 1.0


def data(system, drive, table) -> str:
    """C definitions of the invariants (``elastic_kernels.pack``), the frame table with s(t) beside it and the
    probe fields that ``c/elastic_trolley.c`` reads."""
    from symmech.trolley.elastic import simulate as el_sim
    from symmech.trolley.elastic import kernels as ek
    from symmech.trolley.elastic.layout import F_AT, N_CHANNELS

    mdl = ek.pack(system)
    flags, idx, size = mdl.flags, mdl.block_index, mdl.block_size
    inv = system.inv
    n, f = int(flags[F_AT.n]), int(flags[F_AT.f])
    nodes = table.nodes
    s_coef = CubicSpline(nodes, el_sim.arc_length(drive, nodes)).c  # (4, intervals)
    coef = np.concatenate([table.coef, s_coef[:, :, None]], axis=2)  # (4, intervals, 13)
    elastic = np.zeros(f)
    elastic[1 + inv.n_roll:1 + n] = 1.0
    elastic[1 + n:] = [1.0 if i >= inv.n_roll else 0.0 for i, _ in inv.pairs]
    g_ref = system.mdl.g0 if system.mdl.g0 > 0 else 9.80665
    width = idx.shape[1]
    lines = ["/* The elastic trolley's data, written by `symmech export` from symmech.trolley.elastic.kernels.pack "
             "and the compiled engine's frame table (do not edit). */",
             f"#define EL_N {n}", f"#define EL_F {f}", f"#define EL_PAIRS {mdl.pair_i.size}", f"#define EL_CHANNELS {N_CHANNELS}",
             f"#define EL_NODES {nodes.size}", f"#define EL_MASS {float(flags[F_AT.mass])!r}",
             f"#define EL_ROLLERS_ON {int(flags[F_AT.rollers])}", f"#define EL_CLAMPED {int(flags[F_AT.law])}",
             f"#define EL_BLOCKS {size.size}", f"#define EL_BLOCK_WIDTH {width}",
             f"#define EL_PROBES {inv.probe_points.shape[0]}", f"#define EL_G_REF {float(g_ref)!r}",
             _ints("EL_PTR", mdl.ptr), _ints("EL_COL", mdl.col), _ints("EL_QI", mdl.qi),
             _ints("EL_PAIR_I", mdl.pair_i), _ints("EL_PAIR_J", mdl.pair_j), _doubles("EL_GX", mdl.gram_x),
             _doubles("EL_GTR", mdl.gram_trace), _doubles("EL_C", mdl.rollers_map), _doubles("EL_PRELOAD", mdl.roll[2]),
             _ints("EL_BLOCK_INDEX", idx), _ints("EL_BLOCK_SIZE", size), _doubles("EL_BLOCK_H", mdl.block_h),
             _doubles("EL_BLOCK_C", mdl.block_c), _doubles("EL_S1", mdl.s1), _doubles("EL_K", mdl.stiffness),
             _doubles("EL_D", mdl.damping), _doubles("EL_TIMES", nodes), _doubles("EL_TABLE", coef.transpose(1, 2, 0)),
             _doubles("EL_PROBE_FIELDS", inv.probe_fields), _doubles("EL_PROBE_POINTS", inv.probe_points),
             _doubles("EL_ELASTIC", elastic), ""]
    return "\n".join(lines)


def _doubles(name: str, values) -> str:
    flat = np.asarray(values, float).ravel()
    body = ",".join(repr(float(x)) for x in flat) if flat.size else "0.0"
    return f"static const double {name}[{max(flat.size, 1)}] = {{{body}}};"


def _ints(name: str, values) -> str:
    flat = np.asarray(values).ravel()
    body = ",".join(str(int(x)) for x in flat) if flat.size else "0"
    return f"static const int {name}[{max(flat.size, 1)}] = {{{body}}};"
