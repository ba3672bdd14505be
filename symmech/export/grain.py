"""The grain (kind ``grain``) as an exported model: flight and impacts as state events.

The flight is the generated dynamics of ``grain_motion`` (13 states: centre position and velocity relative to the
vibrating surface in KXYZ, orientation quaternion, body-axis angular velocity); the event indicator is its generated
contact gap (``event_values``, falling through zero at contact) and the map applied at the event its generated
``impact_contact`` (K and u of the lowest point), ``plastic_impulse``, ``coulomb_impulse`` (the energy-consistent
Coulomb law) and ``impact_state`` in turn, as the FMI Reference FMUs' BouncingBall applies its restitution at the event. Names: the native trajectory's columns (``x`` ... ``q3``), the body-axis
rates as in the impacts table (``w1`` ... ``w3``). Parameters: the scene's fields as the generated equations take
them (gravity in KXYZ from ``surface``, the vibration, the inertia and mass from ``body``, the impact law).

Covered: accurate mode, the Coulomb law with a friction limit, rotation on, flight and impacts until the native
run's first landing (a bounce sequence that ends below ``numerics.rest_velocity``, then sliding): a scene whose
duration reaches it is refused in one line naming the duration and the landing time, as is anything else not
covered (docs/export.md).
"""
from __future__ import annotations

import math

import numpy as np

from symmech.core.layout import Field, Layout
from symmech.core.results import Column, Table
from symmech.core.scene import SymmechError
from symmech.export.model import REALS, ExportModel, Variable
from symmech.grain.vectors import T_AT, TRAJECTORY_ROW

MODULE = "grain_motion"
STATE_NAMES = ("x", "y", "z", "vx", "vy", "vz", "q0", "q1", "q2", "q3", "w1", "w2", "w3")
# the native run's trajectory columns the exported run is compared with: time, then the states x ... q3
NATIVE_FIELDS = ("t", "r", "v", "q")
# parameters of the impact map beyond the dynamics' (after them in r[]): name, unit, description
LAW = (("m", "kg", "grain mass (body.mass, or body.density times the ellipsoid's volume)"),
       ("e_n", "1", "normal restitution coefficient (impact.e_n)"),
       ("e_t", "1", "tangential restitution coefficient (impact.e_t)"),
       ("mu", "1", "friction coefficient of the impact (impact.mu)"))
# The impact map: the generated functions applied in turn at an impact and their outputs (the last, the state
# after the impact, is the dynamics' STATE), each slot named as the later stages' arguments (the derivation's
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
# a gap below -LEFT_FLIGHT x the length scale without an impact: the grain has come to rest on the surface (two
# crossings within one step of the importer, at the end of a bounce sequence) and would slide
LEFT_FLIGHT = 1e-6
# where each dynamics parameter comes from in the scene
SOURCE = {"gX": "surface.alpha_deg, beta_deg, g", "gY": "surface.alpha_deg, beta_deg, g",
          "gZ": "surface.alpha_deg, beta_deg, g", "A": "vibration.amplitude", "omega": "2 pi vibration.frequency",
          "phase": "vibration.phase_deg", "dX": "vibration.direction", "dY": "vibration.direction",
          "dZ": "vibration.direction", "I1": "body", "I2": "body", "I3": "body", "a": "body.semi_axes",
          "b": "body.semi_axes", "c": "body.semi_axes"}


def load(scene) -> ExportModel:
    """The export model of a loaded grain scene (``pipeline.load``'s); SymmechError (exit 2), naming the field
    and its value, for a scene whose regimes the export does not cover."""
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
    trajectory, landing = native_run(sc)
    if landing is not None:
        raise SymmechError(f"duration = {sc.duration:g}: the grain lands on the surface and slides at t = "
                           f"{landing:.6g} s (the native run), a regime the export does not cover; a duration "
                           f"below {landing:.6g} s exports")
    return grain(sc, native_table(trajectory, sc.numerics.sample_interval))


def native_run(sc) -> tuple[np.ndarray, float | None]:
    """The native run's trajectory rows and its first landing (:func:`first_landing`): over 8 periods of the
    surface first, then 4 times longer each time until it lands or reaches the scene's duration (a landing,
    usually within a few periods, costs no run of the whole scene)."""
    from symmech.grain import motion_scene

    span = min(sc.duration, 8 * sc.model.period)
    while True:
        trajectory = motion_scene.simulate(sc, duration=span).trajectory
        landing = first_landing(trajectory)
        if landing is not None or span >= sc.duration:
            return trajectory, landing
        span = min(sc.duration, 4 * span)


def first_landing(trajectory: np.ndarray) -> float | None:
    """Time [s] where a native run (its trajectory rows) first lands on the surface (the row before its first
    sliding or sticking row: the last impact, or the start), None when it never does."""
    from symmech.grain import motion

    (off,) = np.nonzero(trajectory[:, T_AT.regime] == motion.REGIMES.index("sliding"))
    return float(trajectory[max(off[0] - 1, 0), T_AT.t]) if off.size else None


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
    trajectory on the sample grid is ``native``: the generated ``grain_motion`` module's C twin, its layouts
    read from the numpy module (no sympy)."""
    import importlib.resources
    import inspect

    from symmech.generated import grain_motion as gm

    model, start = sc.model, sc.start
    vib = model.vibration
    params = [name for name, _, _ in gm.PARAMS]
    p = dict(zip(params, (*model.g_k, vib.amplitude, vib.omega, vib.phase, *vib.direction, *model.inertia,
                          *model.axes)))
    p.update(m=model.mass, e_n=model.law.e_n, e_t=model.law.e_t, mu=model.law.mu)
    y0 = np.concatenate([start.r, start.v, start.q, start.w])
    nominal = _nominals(sc)
    n = len(gm.STATE)
    reals = REALS.sized(X=n, DX=n, Y=0, Z=len(gm.EVENTS), U=0, P=len(gm.PARAMS) + len(LAW))
    x, dx = reals.offset("x"), reals.offset("dx")
    variables = [Variable("time", reals.offset("time"), "independent", "continuous", "s", "simulation time")]
    for i, (name, (_, unit, meaning)) in enumerate(zip(STATE_NAMES, gm.STATE)):
        variables.append(Variable(name, x + i, "output", "continuous", unit, meaning, float(y0[i]),
                                  nominal=nominal[i]))
    rate_unit = {"m": "m/s", "m/s": "m/s^2", "1": "1/s", "rad/s": "rad/s^2"}
    for i, (name, (_, unit, _)) in enumerate(zip(STATE_NAMES, gm.STATE)):
        variables.append(Variable(f"der({name})", dx + i, "output", "continuous", rate_unit[unit],
                                  f"rate of {name}", derivative_of=x + i))
    ((_, _, _, unit, meaning),) = gm.EVENTS
    variables.append(Variable("gap", reals.offset("z"), "output", "continuous", unit,
                              f"{meaning} (the event indicator: an impact where it falls through zero)"))
    vr = reals.offset("p")
    for k, (name, unit, meaning) in enumerate(gm.PARAMS):
        variables.append(Variable(name, vr + k, "parameter", "tunable", unit, f"{meaning} (from {SOURCE[name]})",
                                  float(p[name])))
    vr += len(gm.PARAMS)
    for k, (name, unit, meaning) in enumerate(LAW):
        variables.append(Variable(name, vr + k, "parameter", "tunable", unit, meaning, float(p[name])))
    # the impact map's stages, each output slot named as the later stages' arguments; arguments as C expressions
    where = {name: f"y[{i}]" for i, (name, _, _) in enumerate(gm.STATE)}
    where.update((name, f"p[{k}]") for k, name in enumerate(params + [x[0] for x in LAW]))
    for stage, (_, outputs) in enumerate(IMPACT_MAP[:-1]):
        where.update((name, f"s{stage}[{i}]") for i, name in enumerate(slot_names(outputs)))
    stages = tuple((f"{MODULE}_{name}", tuple(where[a] for a in inspect.signature(getattr(gm, name)).parameters),
                    n if outputs is None else outputs.size) for name, outputs in IMPACT_MAP)
    source = importlib.resources.files("symmech.generated").joinpath(f"{MODULE}.c").read_text(encoding="utf-8")
    return ExportModel(MODULE, gm.__doc__.strip().splitlines()[0], source, tuple(variables), n, n, 0, 0, 0,
                       len(gm.PARAMS) + len(LAW), native, n_z=1, event_map=stages,
                       event_tolerance=LEFT_FLIGHT * nominal[0], mass_identity=n)


def slot_names(layout: Layout) -> list[str]:
    """The name of each slot of ``layout`` as a generated function's argument: the field's name for a scalar, its
    name and the index for a vector (``k0`` ... ``k8``)."""
    return [f.name if f.shape == () else f"{f.name}{i}" for f in layout.fields for i in range(f.size)]


def _nominals(sc) -> list[float]:
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
