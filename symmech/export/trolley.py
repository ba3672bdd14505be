"""The elastic trolley as an exported model: the invariants of its assembly, the frame table and the outputs.

The physics is the generated module ``elastic_assembly.c`` (:mod:`symmech.trolley.elastic.symbolic_assembly`,
derived per model from the invariants of the compiled engine's record, :mod:`symmech.trolley.elastic.kernels`;
``c/elastic_trolley.c`` reads the frame table and calls it): states q, q' (``<coordinate>``,
``der(<coordinate>)``), M y' = F with M = diag(1, M(q)); the frame's motion along the track at the
prescribed speed as the engine's cubic spline table of the 12 frame channels in t
(:func:`symmech.trolley.elastic.compiled.frame_table`, the same nodes and coefficients) with the arc length
s beside them. Outputs: the native run's columns (``elastic_reactions``, ``roller_deflections``,
``points``); parameters: the rollers' stiffnesses, dampings and (clamped pair law) preloads. The track and
the speed are in the table: they are not parameters, and the FMU has no inputs. The C example program and
Co-Simulation integrate with Radau IIA (the roller modes are stiff).
"""
from __future__ import annotations

import hashlib

import numpy as np
from scipy.interpolate import CubicSpline

from symmech.core.results import Column, Table
from symmech.core.scene import SymmechError
from symmech.export.model import REALS, ExportModel, Variable
from symmech.export.sources import glue

IDENTIFIER = "elastic_trolley"


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
    the engine's state order; the roller coordinates' units are their declaration's (layout.ROLLER_DOFS), the
    beams' modal coordinates are in m."""
    from symmech.trolley.elastic.layout import ROLLER_DOFS

    names = list(system.inv.names)
    units = dict(zip(ROLLER_DOFS.names, ROLLER_DOFS.units))
    return names, [units.get(n, "m") for n in names]


def elastic(setup, run: dict) -> ExportModel:
    """The export model of a prepared elastic setup (``symmech.trolley.elastic.scene.Setup``) whose native
    run (``elastic_scene.simulate``) is ``run``."""
    from symmech.trolley.elastic import compiled as elastic_compiled, simulate as el_sim
    from symmech.trolley.elastic.layout import STATE

    system, drive, t = setup.system, setup.drive, setup.t
    inputs = el_sim.compiled_inputs(system, drive, t, atol_q=1e-12)  # a compiled run's (its table's seed)
    table = elastic_compiled.frame_table(t, setup.rtol, inputs.evaluate, inputs.exact)
    if table is None:
        raise SymmechError("the frame along the track cannot be tabulated within its bound (a non-smooth track "
                           "or speed): `symmech export` needs the compiled engine's table")
    names, units = state_layout(system)
    n, columns = len(names), output_columns(setup.names)
    q0 = np.asarray(run["q"][0])
    qd0 = np.asarray(run["qd"][0])
    # the exported states are the engine's q, q' (the first fields of its state), the derivatives q''
    reals = REALS.sized(X=2 * n, DX=n, Y=len(columns), Z=0, U=0, P=len(parameters(system)) * 5)
    engine = STATE.sized(N=n)
    q, qd, qdd = (reals.offset("x") + engine.offset("q"), reals.offset("x") + engine.offset("qd"),
                  reals.offset("dx"))
    variables = [Variable("time", reals.offset("time"), "independent", "continuous", "s", "simulation time")]
    for i in range(n):
        variables.append(Variable(names[i], q + i, "output", "continuous", units[i], f"coordinate {names[i]}",
                                  float(q0[i]), nominal=_nominal(run["q"][:, i])))
    for i in range(n):
        variables.append(Variable(f"der({names[i]})", qd + i, "output", "continuous", f"{units[i]}/s",
                                  f"rate of {names[i]}", float(qd0[i]), derivative_of=q + i,
                                  nominal=_nominal(run["qd"][:, i])))
    for i in range(n):
        variables.append(Variable(f"der({names[i]},2)", qdd + i, "output", "continuous", f"{units[i]}/s^2",
                                  f"acceleration of {names[i]}", derivative_of=qd + i))
    for k, c in enumerate(columns):
        variables.append(Variable(c.name, reals.offset("y") + k, "output", "continuous", c.unit, c.doc))
    variables += _parameters(system, reals.offset("p"))
    native = Table((Column("t", "s"), Column("s", "m")) + tuple(Column(f"P{i}", "N") for i in range(6)),
                   np.column_stack([t, run["s"], run["P"]]), doc="elastic reactions")
    source = data(system, drive, table) + glue("elastic_trolley.c")
    return ExportModel(IDENTIFIER, "Elastic trolley along its track at the prescribed speed (symmech)", source,
                       tuple(variables), 2 * n, n, n, 0, 0, len(parameters(system)) * 5, native, n_y=len(columns),
                       stiff=True, modules=(("elastic_assembly", assembly_c(system)),), mass_identity=n)


def assembly_c(system) -> str:
    """The C99 module of the model's assembly (rate, rate_mass, outputs), derived from its invariants (once per
    process and model: an export in each FMI version and type derives it once)."""
    names, units = state_layout(system)
    model = assembly_model(system)
    key = hashlib.sha256(repr((model, names, units)).encode()).hexdigest()
    if key not in _DERIVED:
        from symmech.core import emit
        from symmech.trolley.elastic import symbolic_assembly  # sympy: only when exporting

        _DERIVED[key] = emit.render(symbolic_assembly.assembly_spec(model, names, units), emit.C99)
    return _DERIVED[key]


_DERIVED: dict[str, str] = {}  # C text by the digest of the model's invariants


# The tunable parameters, in the order c/elastic_trolley.c reads p: the rollers' [elastic.rollers] fields (the
# generated assembly's first parameters); the preloads only under the clamped pair law, the one that reads them
PARAMETERS = (("stiffness", "N/m", "stiffness"), ("damping", "N s/m", "damping (0 without effects.damping)"),
              ("preload", "m", "preload (clamped pair law)"))


def parameters(system) -> tuple:
    """The rows of PARAMETERS the model has."""
    return PARAMETERS if system.mdl.rollers.law == "clamped_pair" else PARAMETERS[:2]


def _parameters(system, vr: int) -> list[Variable]:
    """The rollers' stiffnesses, dampings and (clamped pair law) preloads from value reference ``vr`` on
    (``elastic.rollers.stiffness[1]`` … as the scene's fields): they enter only the roller forces, so they
    stay tunable."""
    from symmech.trolley.elastic.layout import ROLLER

    roll = system.record.roll  # rows of ROLLER: stiffness, damping as the engine applies it, preload
    out = []
    for row, (field, unit, what) in enumerate(parameters(system)):
        for r in range(5):
            out.append(Variable(f"elastic.rollers.{field}[{r + 1}]", vr + 5 * row + r, "parameter", "tunable", unit,
                                f"{what} of the roller of P{r + 1}", float(roll[ROLLER.offset(field), r])))
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


def assembly_model(system) -> dict:
    """The invariants :func:`symmech.trolley.elastic.symbolic_assembly.assembly_spec` reads, as nested lists: the
    engine's record (``System.record``) and the probes."""
    from symmech.trolley.elastic.layout import F_AT

    mdl = system.record
    inv = system.inv
    f = int(mdl.flags[F_AT.f])
    model = {name: getattr(mdl, name).tolist() for name in (
        "ptr", "col", "qi", "pair_i", "pair_j", "rollers_map", "block_index", "block_size", "block_h", "block_c",
        "s1", "stiffness", "damping", "gram_trace")}
    model.update(gram_x=mdl.gram_x.reshape(f, 9, f).tolist(),
                 mass=float(mdl.flags[F_AT.mass]), rollers=bool(mdl.flags[F_AT.rollers]),
                 clamped=bool(mdl.flags[F_AT.law]), probe_fields=inv.probe_fields.tolist(),
                 probe_points=inv.probe_points.tolist(), elastic=system.beam_fields.astype(float).tolist(),
                 g_ref=float(system.mdl.g0 if system.mdl.g0 > 0 else 9.80665))
    return model


def data(system, drive, table) -> str:
    """C definitions of the frame table with s(t) beside it, which ``c/elastic_trolley.c`` reads."""
    from symmech.trolley.elastic import simulate as el_sim
    from symmech.trolley.elastic.layout import N_CHANNELS

    nodes = table.nodes
    s_coef = CubicSpline(nodes, el_sim.arc_length(drive, nodes)).c  # (4, intervals)
    coef = np.concatenate([table.coef, s_coef[:, :, None]], axis=2)  # (4, intervals, 13)
    lines = ["/* The elastic trolley's frame table, written by `symmech export` from the compiled engine's (do not "
             "edit). */",
             f"#define EL_N {system.N}", f"#define EL_CHANNELS {N_CHANNELS}", f"#define EL_NODES {nodes.size}",
             f"#define EL_ROLLER_PARAMS {5 * len(parameters(system))}",
             _doubles("EL_TIMES", nodes), _doubles("EL_TABLE", coef.transpose(1, 2, 0)), ""]
    return "\n".join(lines)


def _doubles(name: str, values) -> str:
    flat = np.asarray(values, float).ravel()
    body = ",".join(repr(float(x)) for x in flat) if flat.size else "0.0"
    return f"static const double {name}[{max(flat.size, 1)}] = {{{body}}};"
