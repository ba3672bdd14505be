"""The grain (kind ``grain``) as an exported model: flight, slip and stick as its regimes, impacts, landings,
stops and lift-offs as state events.

The states are the flight's 13 of the generated ``grain_motion`` (centre position and velocity relative to the
vibrating surface in KXYZ, orientation quaternion, body-axis angular velocity), kept through every regime; the
regime (flight, slip, stick) is a discrete state. In flight the rates are ``grain_motion``'s and the event
indicator its contact gap; on the plane the rates and the two indicators are the generated ``grain_sliding``'s
(slip: the slip along its reference direction minus v_stop, and the normal force; stick: the friction cone's
margin and the normal force). At the events the hand-written ``c/grain.c`` takes the native engine's decisions
with its thresholds and calls the generated maps: the impact (``impact_contact``, ``plastic_impulse``,
``coulomb_impulse``, ``impact_state``), the landing (the plastic normal impulse, ``rest_on_plane``), the friction
impulse of a stop or a cone exit (``friction_impulse``), the lift-off. Names: the native trajectory's columns
(``x`` ... ``q3``), the body-axis rates as in the impacts table (``w1`` ... ``w3``). Parameters: the scene's fields
as the generated equations take them (gravity in KXYZ from ``surface``, the vibration, the inertia and mass from
``body``, the impact law, the sliding friction) and the native engine's numerics that decide its transitions.

Covered: accurate mode, the Coulomb law with a friction limit, rotation on, every regime: under Model Exchange the
importer's solver integrates and locates the events, under Co-Simulation and in the C program the FMU's own DOP853
(its events located on its dense output, c/symmech_model.c); anything else is refused in one line
(docs/export.md).
"""
from __future__ import annotations

import inspect
import math

import numpy as np

from symmech.core.context import Context
from symmech.core.layout import Field, Layout
from symmech.core.results import Column, Table
from symmech.core.scene import SymmechError
from symmech.export.model import REALS, ExportModel, Variable
from symmech.export.sources import glue
from symmech.grain.vectors import T_AT, TRAJECTORY_ROW

IDENTIFIER = "grain"
# the native run's trajectory columns the exported run is compared with: time, then the states x ... q3
NATIVE_FIELDS = ("t", "r", "v", "q")
STATE_NAMES = ("x", "y", "z", "vx", "vy", "vz", "q0", "q1", "q2", "q3", "w1", "w2", "w3")
# parameters beyond the flight dynamics' (after them in r[]): name, unit, description
LAW = (("m", "kg", "grain mass (body.mass, or body.density times the ellipsoid's volume)"),
       ("e_n", "1", "normal restitution coefficient (impact.e_n)"),
       ("e_t", "1", "tangential restitution coefficient (impact.e_t)"),
       ("mu", "1", "friction coefficient of the impact (impact.mu)"))
SLIDING = (("mu_s", "1", "sliding friction coefficient (sliding.friction)"),
           ("roll", "1", "1: a sphere, rolling about any axis on the plane; 0: an ellipsoid, turning about the "
                         "normal only (from body.semi_axes)"),
           ("tolerance", "1", "the native engine's tolerance (numerics.tolerance): v_stop = tolerance (|g| + |n|) "
                              "scan_step at a landing"),
           ("scan_step", "s", "the native engine's scan step (numerics.scan_step): v_stop's time scale"),
           ("rest_velocity", "m/s", "a bounce whose contact point leaves slower than this lands "
                                    "(numerics.rest_velocity)"),
           ("period", "s", "vibration period (1 s without vibration): the chatter guard's time scale"),
           ("max_impacts", "1", "the simulation ends at the contact after this many impacts, as the native engine "
                                "stops (numerics.max_impacts)"))
# the discrete states (r[VR_D...]): name, unit, description, exported as an output; the chatter guard's ring of
# the last ZENO_IMPACTS impact times follows them
DISCRETE = (("regime", "1", "regime: 0 flight, 1 slip, 2 stick", True),
            ("v_stop", "m/s", "slip speed at which a slip stops (set at each landing)", True),
            ("ref0", "1", "the slip's reference direction, X component", False),
            ("ref1", "1", "the slip's reference direction, Y component", False),
            ("impacts", "1", "number of impacts so far", True),
            ("last_impact", "s", "time of the latest impact (0 before the first)", True),
            ("rocking", "1", "number of rocking contacts (held on a plane that pulls away: put on the plane, the "
                             "tilting spin dropped, flying on)", True),
            ("stopped", "1", "1 once the simulation ended at numerics.max_impacts impacts", True),
            ("notice", "1", "what the last event update tells the importer (c/grain.c's grain_notice)", False))
# an indicator below -MISSED_EVENT x the length scale without its event: the importer stepped over two of its
# crossings (in flight: the grain has sunk into the surface)
MISSED_EVENT = 1e-6
# the ME FMU's DefaultExperiment tolerance: FMPy's CVode in the relative states meets the first 50 impact times
# within 1e-8 s at rtol 1e-12 (8.1e-9 s), not at 1e-10 (4.2e-7 s) or 1e-11 (4.8e-8 s) (docs/export.md)
ME_TOLERANCE = 1e-12
# The impact map: the generated functions c/grain.c applies in turn at an impact and their outputs (the last, the
# state after the impact, is the dynamics' STATE), each slot named as the later stages' arguments (the derivation's
# symbols: symmech.grain.derive_motion).
CONTACT = Layout("ImpactContact", (
    Field("k", "1/kg", "inverse effective mass K of the lowest point, row by row", (9,)),
    Field("u", "m/s", "velocity of the lowest point before the impact", (3,)),
))
PLASTIC = Layout("PlasticImpulse", (
    Field("P_I", "N s", "plastic normal impulse"),
    Field("D", "N s", "plastic sticking impulse beyond it", (3,)),
))
COULOMB = Layout("CoulombImpulse", (Field("P", "N s", "the energy-consistent Coulomb impulse", (3,)),))
IMPACT_MAP = (("impact_contact", CONTACT), ("plastic_impulse", PLASTIC), ("coulomb_impulse", COULOMB),
              ("impact_state", None))
# the impact map's outputs as c/grain.c names their offsets and sizes (CONTACT_U, CONTACT_SIZE, ...)
C_LAYOUTS = (("CONTACT", CONTACT), ("PLASTIC", PLASTIC), ("COULOMB", COULOMB))
# where each dynamics parameter comes from in the scene
SOURCE = {"gX": "surface.alpha_deg, beta_deg, g", "gY": "surface.alpha_deg, beta_deg, g",
          "gZ": "surface.alpha_deg, beta_deg, g", "A": "vibration.amplitude", "omega": "2 pi vibration.frequency",
          "phase": "vibration.phase_deg", "dX": "vibration.direction", "dY": "vibration.direction",
          "dZ": "vibration.direction", "I1": "body", "I2": "body", "I3": "body", "a": "body.semi_axes",
          "b": "body.semi_axes", "c": "body.semi_axes"}
INDICATORS = (("indicator1", "1", "event indicator 1: in flight the gap [m] (an impact or a landing where it falls "
                                  "through zero), in a slip the slip along its reference direction minus v_stop "
                                  "[m/s] (the slip stops), in a stick the friction cone's margin mu n - |phi| "
                                  "[m/s^2] (a slip starts)"),
              ("indicator2", "1", "event indicator 2: in flight 1, on the plane the normal force per unit mass "
                                  "[m/s^2] (lift-off where it falls through zero)"))


def load(scene, ctx: Context | None = None) -> ExportModel:
    """The export model of a loaded grain scene (``pipeline.load``'s), its native run's trajectory (run under ``ctx``'s
    time budget) the example program's table and the FMU's default experiment. SymmechError (exit 2), naming the field
    and its value, for a scene whose regimes the export does not cover."""
    from symmech.grain import motion_scene

    sc = scene.setup
    law, effects = sc.model.law, sc.model.effects
    if sc.numerics.mode != "accurate":
        raise SymmechError(f"numerics.mode = '{sc.numerics.mode}': `symmech export` covers the grain in accurate "
                           "mode (flight and impacts as state events)")
    if law.kind != "coulomb":
        raise SymmechError(f"impact.law = '{law.kind}': `symmech export` covers the grain with the energy-consistent "
                           "law 'coulomb' (the printed law has no closed-form impact map)")
    if not math.isfinite(law.mu):
        raise SymmechError("impact.mu: unset (no friction limit); `symmech export` needs a finite impact.mu >= 0")
    if not effects.rotation:
        raise SymmechError("effects.rotation = false: `symmech export` covers the rotating grain only (the impact "
                           "map is the rotating body's)")
    ctx = ctx or Context(quiet=True)
    scene.budget(ctx)
    native = motion_scene.simulate_watched(sc, ctx)
    return grain(sc, native_table(native.trajectory, sc.numerics.sample_interval))


def native_table(trajectory: np.ndarray, interval: float) -> Table:
    """The native trajectory's rows on the sample grid (k ``interval`` [s]; the rows at events left out), its
    columns t, x ... q3 (the exported states of the same names)."""
    t = trajectory[:, T_AT.t]
    k = np.round(t / interval)
    on_grid = np.abs(t - k * interval) <= 1e-9 * interval
    _, first = np.unique(k[on_grid], return_index=True)
    exported = [TRAJECTORY_ROW.field(name) for name in NATIVE_FIELDS]
    units = [f.unit for f in exported[1:] for _ in range(f.size)]
    columns = (Column("t", "s", "time"),) + tuple(Column(name, unit) for name, unit in zip(STATE_NAMES, units))
    rows = TRAJECTORY_ROW.split(trajectory[on_grid][first])
    return Table(columns, np.column_stack([rows[name] for name in NATIVE_FIELDS]), doc="trajectory at the sample interval")


def grain(sc, native: Table | None) -> ExportModel:
    """The export model of a prepared grain scene (``symmech.grain.motion_scene.GrainScene``) whose native run's
    trajectory on the sample grid is ``native``: the hand-written regimes of ``c/grain.c`` over the C twins of the
    generated ``grain_motion`` and ``grain_sliding``, their layouts read from the numpy modules (no sympy)."""
    import importlib.resources

    from symmech.generated import grain_motion as gm
    from symmech.grain import motion

    model, start = sc.model, sc.start
    vib = model.vibration
    params = [name for name, _, _ in gm.PARAMS] + [name for name, _, _ in LAW + SLIDING]
    values = dict(zip(params, (*model.g_k, vib.amplitude, vib.omega, vib.phase, *vib.direction, *model.inertia,
                               *model.axes, model.mass, model.law.e_n, model.law.e_t, model.law.mu, model.mu,
                               1.0 if max(model.axes) == min(model.axes) else 0.0, sc.numerics.tolerance,
                               sc.numerics.scan_step, sc.numerics.rest_velocity, model.period,
                               sc.numerics.max_impacts)))
    y0 = np.concatenate([start.r, start.v, start.q, start.w])
    nominal = nominals(sc)
    n = len(gm.STATE)
    n_d = len(DISCRETE) + motion.ZENO_IMPACTS
    reals = REALS.sized(X=n, DX=n, Y=0, Z=len(INDICATORS), U=0, P=len(params), D=n_d)
    x, dx = reals.offset("x"), reals.offset("dx")
    variables = [Variable("time", reals.offset("time"), "independent", "continuous", "s", "simulation time")]
    for i, (name, (_, unit, meaning)) in enumerate(zip(STATE_NAMES, gm.STATE)):
        variables.append(Variable(name, x + i, "output", "continuous", unit, meaning, float(y0[i]),
                                  nominal=nominal[i]))
    rate_unit = {"m": "m/s", "m/s": "m/s^2", "1": "1/s", "rad/s": "rad/s^2"}
    for i, (name, (_, unit, _)) in enumerate(zip(STATE_NAMES, gm.STATE)):
        variables.append(Variable(f"der({name})", dx + i, "output", "continuous", rate_unit[unit],
                                  f"rate of {name}", derivative_of=x + i))
    variables += [Variable(name, reals.offset("z") + k, "output", "continuous", unit, meaning)
                  for k, (name, unit, meaning) in enumerate(INDICATORS)]
    units = {name: unit for name, unit, _ in gm.PARAMS}
    meanings = {name: f"{meaning} (from {SOURCE[name]})" for name, _, meaning in gm.PARAMS}
    units.update((name, unit) for name, unit, _ in LAW + SLIDING)
    meanings.update((name, meaning) for name, _, meaning in LAW + SLIDING)
    variables += [Variable(name, reals.offset("p") + k, "parameter", "tunable", units[name], meanings[name],
                           float(values[name])) for k, name in enumerate(params)]
    variables += [Variable(name, reals.offset("d") + k, "output", "discrete", unit, meaning, 0.0)
                  for k, (name, unit, meaning, shown) in enumerate(DISCRETE) if shown]
    source = "\n".join(_prelude(params)) + "\n" + glue("grain.c")
    modules = tuple((name, importlib.resources.files("symmech.generated").joinpath(f"{name}.c").read_text(
        encoding="utf-8")) for name in ("grain_motion", "grain_sliding"))
    return ExportModel(IDENTIFIER, "Grain on a vibrating plane: flight, impacts, slip and stick (symmech)", source,
                       tuple(variables), n, n, 0, 0, 0, len(params), native, n_z=len(INDICATORS), n_d=n_d,
                       modules=modules, event_tolerance=MISSED_EVENT * nominal[0], mass_identity=n,
                       me_tolerance=ME_TOLERANCE)


# the generated functions c/grain.c calls (module, function), each through a gatherer call_<function>(t, y, p, a,
# out) of its arguments: the time, the state y, the parameters and discrete states p, the rest in order from a
CALLED = (("grain_sliding", ("normal_force", "slip", "stick_force", "slip_direction", "slip_rate", "stick_rate",
                             "slip_events", "stick_events", "friction_impulse", "rest_on_plane")),
          ("grain_motion", ("impact_contact", "plastic_impulse", "coulomb_impulse", "impact_state")))
# the parameters and discrete states c/grain.c reads by name: its macro, the first name
READ = (("P_G", "gX"), ("P_AMPLITUDE", "A"), ("P_OMEGA", "omega"), ("P_AXES", "a"), ("P_MU_S", "mu_s"),
        ("P_TOLERANCE", "tolerance"), ("P_SCAN_STEP", "scan_step"), ("P_REST_VELOCITY", "rest_velocity"),
        ("P_PERIOD", "period"), ("P_MAX_IMPACTS", "max_impacts"))


def _prelude(params: list[str]) -> list[str]:
    """The C lines before ``c/grain.c``: the offsets it reads (parameters, discrete states, the state's Y_<name>,
    the impact map's outputs <LAYOUT>_<field> and <LAYOUT>_SIZE, each gatherer's arguments from a:
    <FUNCTION>_ARG_<name> and <FUNCTION>_ARGS), the chatter guard's constants and the gatherers of the generated
    functions' arguments (read from the numpy modules' signatures)."""
    import importlib

    from symmech.generated import grain_motion as gm
    from symmech.grain import motion

    discrete = [name for name, _, _, _ in DISCRETE]
    lines = [f"/* {IDENTIFIER}: the regimes of c/grain.c over the generated grain_motion and grain_sliding (written "
             "by `symmech export`) */", '#include "model.h"']
    lines += [f"#define {macro} {params.index(name)}" for macro, name in READ]
    lines += [f"#define D_{name.upper()} {k}" for k, name in enumerate(discrete) if name not in ("ref0", "ref1")]
    lines += [f"#define D_REF {discrete.index('ref0')}", f"#define D_TIMES {len(discrete)}",
              f"#define ZENO_IMPACTS {motion.ZENO_IMPACTS}", f"#define ZENO_INTERVAL {motion.ZENO_INTERVAL!r}"]
    lines += [f"#define Y_{name.upper()} {i}" for i, (name, _, _) in enumerate(gm.STATE)]
    for prefix, layout in C_LAYOUTS:
        lines += [f"#define {prefix}_{name.upper()} {offset}" for name, offset in zip(layout.names, layout.slots)]
        lines.append(f"#define {prefix}_SIZE {layout.size}")
    lines += [f"void grain_motion_{f}(double t, const double *y, const double *p, double *out);"
              for f in ("rate", "event_values")]
    where = {"t": "t"}
    where.update((name, f"y[{i}]") for i, (name, _, _) in enumerate(gm.STATE))
    where.update((name, f"p[{k}]") for k, name in enumerate(params))
    where.update((name, f"p[N_P + {discrete.index(name)}]") for name in ("v_stop", "ref0", "ref1"))
    for module, functions in CALLED:
        generated = importlib.import_module(f"symmech.generated.{module}")
        for f in functions:
            names = list(inspect.signature(getattr(generated, f)).parameters)
            rest = [a for a in names if a not in where]
            args = ", ".join(where.get(a) or f"a[{rest.index(a)}]" for a in names)
            if rest:
                lines += [f"#define {f.upper()}_ARG_{a.upper()} {k}" for k, a in enumerate(rest)]
                lines.append(f"#define {f.upper()}_ARGS {len(rest)}")
            lines += [f"void {module}_{f}(const double *arg, double *out);",
                      f"static void call_{f}(double t, const double *y, const double *p, const double *a, double *out)",
                      "{", "    (void)t; (void)y; (void)p; (void)a;", f"    const double arg[] = {{{args}}};",
                      f"    {module}_{f}(arg, out);", "}"]
    return lines


def slot_names(layout: Layout) -> list[str]:
    """The name of each slot of ``layout`` as a generated function's argument: the field's name for a scalar, its
    name and the index for a vector (``k0`` ... ``k8``)."""
    return [f.name if f.shape == () else f"{f.name}{i}" for f in layout.fields for i in range(f.size)]


def nominals(sc) -> list[float]:
    """Magnitudes of the 13 states (importers scale their absolute tolerances by them): positions the larger of
    the largest semi-axis, the start height and the amplitude [m]; velocities the larger of the surface's speed
    amplitude A omega, the speed of a fall from the start height and the start speed [m/s]; the quaternion 1;
    the rates the start rate, at least 1 rad/s."""
    model, start = sc.model, sc.start
    vib = model.vibration
    length = max(max(model.axes), abs(start.r[2]), vib.amplitude)
    g = float(np.linalg.norm(model.g_k))
    speed = max(vib.amplitude * vib.omega, math.sqrt(2 * g * abs(start.r[2])), float(np.linalg.norm(start.v)))
    rate = max(float(np.linalg.norm(start.w)), 1.0)
    return [length] * 3 + [speed] * 3 + [1.0] * 4 + [rate] * 3
