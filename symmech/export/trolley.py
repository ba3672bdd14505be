"""The elastic trolley as an exported model: the invariants of its assembly, the frame table and the outputs.

The physics is the generated module ``elastic_assembly.c`` (:mod:`symmech.trolley.elastic.symbolic_assembly`,
derived per model from the invariants of the compiled engine's record, :mod:`symmech.trolley.elastic.kernels`;
``c/elastic_trolley.c`` reads the frame table and calls it): states q, q' (``<coordinate>``,
``der(<coordinate>)``), M y' = F with M = diag(1, M(q)); the frame's motion along the track at the
prescribed speed as the engine's cubic spline table of the 12 frame channels in t
(:func:`symmech.trolley.elastic.frame.frame_table`, the same nodes and coefficients) with the arc length
s beside them. Outputs: the native run's columns (``elastic_reactions``, ``roller_deflections``,
``points``); parameters: the rollers' stiffnesses, dampings and (clamped pair law) preloads. The track and
the speed are in the table: they are not parameters, and the FMU has no inputs.

Under traction (``effects.traction = true``, :func:`traction`) the arc length s and the speed V0 are states
too (``s``, ``V0`` = der(s), ``der(V0)``), the frame's geometry is the compiled engine's spline table in s
(:func:`symmech.trolley.elastic.frame.tabulation`, over the arc lengths the scene's run visits), the
scene's law P0(t, V0) is printed into the generated assembly, and one input ``traction_force`` [N] adds to it
(a controller drives the trolley; 0 reproduces the scene). The C example program and Co-Simulation integrate
with Radau IIA (the roller modes are stiff).
"""
from __future__ import annotations

import hashlib

import numpy as np
from scipy.interpolate import CubicSpline

from symmech.core import expressions
from symmech.core.context import Context
from symmech.core.results import Column, Table
from symmech.core.scene import SymmechError
from symmech.export.model import REALS, ExportModel, Variable
from symmech.export.sources import glue

IDENTIFIER = "elastic_trolley"


def load(scene, ctx: Context | None = None) -> ExportModel:
    """The export model of a trolley scene with an ``[elastic]`` table (``scene`` a loaded pipeline scene), its native
    run under ``ctx``'s time budget; SymmechError for what the export does not cover."""
    from symmech.trolley.elastic import scene as elastic_scene

    setup = scene.setup.elastic
    if setup is None or setup.system is None:
        raise SymmechError("kind = 'trolley': `symmech export` covers the elastic trolley (an [elastic] table "
                           "with an elastic effect), mechanism and grain scenes (docs/export.md)")
    if not setup.system.rollers_on:
        raise SymmechError("elastic.effects.rollers = false: `symmech export` covers the elastic trolley on "
                           "elastic rollers so far (docs/export.md)")
    ctx = ctx or Context(quiet=True)
    scene.budget(ctx)
    with ctx.active():  # the engines tick it, a fallback re-estimates against what is left
        run = elastic_scene.simulate(setup)
    if setup.drive.traction is None:
        return elastic(setup, run)
    motion = scene.resolved["motion"]
    return traction(setup, run, expressions.parse("motion.traction", motion["traction"], ("t", "v"),
                                                  motion["constants"]))


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
    from symmech.trolley.elastic import frame as el_frame
    from symmech.trolley.elastic.compiled import compiled_inputs

    system, drive, t = setup.system, setup.drive, setup.t
    table = compiled_inputs(system, drive, t, setup.rtol, 1e-12).frame.table  # a compiled run's
    if table is None:
        raise SymmechError("the frame along the track cannot be tabulated within its bound (a non-smooth track "
                           "or speed): `symmech export` needs the compiled engine's table")
    names, units = state_layout(system)
    n, columns = len(names), output_columns(setup.names)
    reals = REALS.sized(X=2 * n, DX=n, Y=len(columns), Z=0, U=0, P=len(parameters(system)) * 5, D=0)
    variables = [time_variable(reals), *_motion_variables(reals, [
        (names[i], units[i], f"coordinate {names[i]}", f"der({names[i]})", run["q"][:, i], run["qd"][:, i])
        for i in range(n)])]
    for k, c in enumerate(columns):
        variables.append(Variable(c.name, reals.offset("y") + k, "output", "continuous", c.unit, c.doc))
    variables += _parameters(system, reals.offset("p"))
    native = Table((Column("t", "s"), Column("s", "m")) + tuple(Column(f"P{i}", "N") for i in range(6)),
                   np.column_stack([t, run["s"], run["P"]]), doc="elastic reactions")
    s_coef = CubicSpline(table.nodes, el_frame.arc_length(drive, table.nodes)).c  # (4, intervals)
    source = data(system, table.nodes, np.concatenate([table.coef, s_coef[:, :, None]], axis=2), False)
    source += glue("elastic_trolley.c")
    return ExportModel(IDENTIFIER, "Elastic trolley along its track at the prescribed speed (symmech)", source,
                       tuple(variables), 2 * n, n, n, 0, 0, len(parameters(system)) * 5, native, n_y=len(columns),
                       stiff=True, modules=(("elastic_assembly", assembly_c(system)),), mass_identity=n,
                       mass_block=True, second_order=True, mass_spd=True)  # M(q) = A Gtr A^T: the kinetic energy's Gram


def traction(setup, run: dict, law) -> ExportModel:
    """The export model of a prepared elastic setup under traction whose native run is ``run``; ``law`` the
    scene's P0(t, v) [N] as a sympy expression (:func:`symmech.core.expressions.parse`)."""
    from symmech.trolley.elastic.compiled import compiled_inputs

    system, drive, t = setup.system, setup.drive, setup.t
    frame = compiled_inputs(system, drive, t, setup.rtol, 1e-12).frame  # a compiled run's (its table, span)
    table, (lo, hi) = frame.table, frame.span
    if table is None:
        raise SymmechError("the frame along the track cannot be tabulated in s within its bound (a non-smooth "
                           "track): `symmech export` needs the compiled engine's table")
    names, units = state_layout(system)
    n = len(names)
    coordinates = [(names[i], units[i], f"coordinate {names[i]}", f"der({names[i]})", run["q"][:, i],
                    run["qd"][:, i]) for i in range(n)]
    coordinates.append(("s", "m", f"arc length of O along the track (tabulated over [{lo:.6g}, {hi:.6g}] m)", "V0",
                        run["s"], run["V0"]))
    columns = [c for c in output_columns(setup.names) if c.name != "s"]  # s is a state
    m = len(coordinates)
    reals = REALS.sized(X=2 * m, DX=m, Y=len(columns), Z=0, U=1, P=len(parameters(system)) * 5, D=0)
    variables = [time_variable(reals), *_motion_variables(reals, coordinates)]
    variables += [Variable(c.name, reals.offset("y") + k, "output", "continuous", c.unit, c.doc)
                  for k, c in enumerate(columns)]
    variables += [Variable("traction_force", reals.offset("u"), "input", "continuous", "N", "force along the track "
                           "(x1 at O) added to the scene's traction P0(t, V0): 0 runs the scene as it is", 0.0)]
    variables += _parameters(system, reals.offset("p"))
    native = Table((Column("t", "s"), Column("s", "m"), Column("V0", "m/s")) + tuple(Column(f"P{i}", "N")
                                                                                     for i in range(6)),
                   np.column_stack([t, run["s"], run["V0"], run["P"]]), doc="elastic reactions")
    source = "#define EL_TRACTION 1\n" + data(system, table.nodes, table.coef, True) + glue("elastic_trolley.c")
    return ExportModel(IDENTIFIER, "Elastic trolley along its track under traction (symmech)", source,
                       tuple(variables), 2 * n + 2, n + 1, n + 1, 1, 2 * n + 1, len(parameters(system)) * 5, native,
                       n_y=len(columns), stiff=True, modules=(("elastic_assembly", assembly_c(system, law)),),
                       mass_identity=n + 1, mass_block=True, second_order=True)  # L: M(q) bordered by the traction law's row


def time_variable(reals) -> Variable:
    """The independent variable at its place in ``reals`` (:data:`symmech.export.model.REALS` sized)."""
    return Variable("time", reals.offset("time"), "independent", "continuous", "s", "simulation time")


def _motion_variables(reals, coordinates) -> list[Variable]:
    """The states x = (values, rates) and the accelerations dx at their places in ``reals`` (REALS sized with
    X = 2 m, DX = m): ``coordinates`` (m of them: name, unit, description, name of its rate, values (k,), rates
    (k,) over the native run) give their values, then their rates, then the accelerations
    (``der(<coordinate>,2)``, or ``der(<rate>)`` when the rate has a name of its own); starts and nominals from
    the native run."""
    m = len(coordinates)
    value, rate_at, acceleration_at = reals.offset("x"), reals.offset("x") + m, reals.offset("dx")
    out = []
    for i, (name, unit, what, _, x, _) in enumerate(coordinates):
        out.append(Variable(name, value + i, "output", "continuous", unit, what, float(x[0]), nominal=_nominal(x)))
    for i, (name, unit, _, rate, _, v) in enumerate(coordinates):
        out.append(Variable(rate, rate_at + i, "output", "continuous", f"{unit}/s", f"rate of {name}", float(v[0]),
                            derivative_of=value + i, nominal=_nominal(v)))
    for i, (name, unit, _, rate, _, _) in enumerate(coordinates):
        acceleration = f"der({name},2)" if rate == f"der({name})" else f"der({rate})"
        out.append(Variable(acceleration, acceleration_at + i, "output", "continuous", f"{unit}/s^2",
                            f"acceleration of {name}", derivative_of=rate_at + i))
    return out


def assembly_c(system, law=None) -> str:
    """The C99 module of the model's assembly (rate, rate_mass, outputs, rate_and_mass_block), derived from its invariants
    (once per process, model and traction ``law``, None at a prescribed speed: an export in each FMI version and
    type derives it once)."""
    names, units = state_layout(system)
    model = assembly_model(system)
    key = hashlib.sha256(repr((model, names, units, law)).encode()).hexdigest()
    if key not in _DERIVED:
        from symmech.core import emit
        from symmech.trolley.elastic import symbolic_assembly as sa  # sympy: only when exporting

        if law is None:
            spec = sa.assembly_spec(model, names, units)
        else:
            t, v = expressions.symbol("t"), expressions.symbol("v")
            spec = sa.traction_spec(model, names, units, law.xreplace({t: sa.TIME, v: sa.SPEED}))
        _DERIVED[key] = emit.render(spec, emit.C99)
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
                 g0=float(mdl.flags[F_AT.g0]),
                 g_ref=float(system.mdl.g0 if system.mdl.g0 > 0 else 9.80665))
    return model


def data(system, nodes, coef, traction: bool) -> str:
    """C definitions of the frame table ``c/elastic_trolley.c`` reads: nodes (k,) [s, or m under traction] and
    cubic coefficients (4, k - 1, columns): the 12 frame channels and s in t, or the 15 geometry channels in s."""
    lines = ["/* The elastic trolley's frame table, written by `symmech export` from the compiled engine's (do not "
             "edit). */",
             f"#define EL_N {system.N}", f"#define EL_COLUMNS {coef.shape[2]}", f"#define EL_NODES {nodes.size}",
             f"#define EL_ROLLER_PARAMS {5 * len(parameters(system))}",
             _doubles("EL_NODES_AT", nodes), _doubles("EL_TABLE", coef.transpose(1, 2, 0)), ""]
    return "\n".join(lines)


def _doubles(name: str, values) -> str:
    flat = np.asarray(values, float).ravel()
    body = ",".join(repr(float(x)) for x in flat) if flat.size else "0.0"
    return f"static const double {name}[{max(flat.size, 1)}] = {{{body}}};"
