"""What an exported model is made of: a scene's generated C module and its variables.

Variables are Float64 and live in one array indexed by their FMI value reference (the C side's ``r[]``):
time (0), the continuous states, the state derivatives that are not states themselves, the inputs, the
parameters. A mechanism (``kind = "mechanism"``, the structural model method) exports its linear equations
a q'' + b q' + c q = Q: states q and q' (named ``<coordinate>`` and ``der(<coordinate>)``), outputs also
q'' (``der(<coordinate>,2)``), inputs Q (``Q_<coordinate>``, added to the rows of a q'' in M y' = F), the
scene's parameters as tunable parameters.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass

import numpy as np
import scipy.linalg

from symmech.core import pipeline
from symmech.core.context import Context
from symmech.core.layout import Field, Layout
from symmech.core.results import Table
from symmech.core.scene import SymmechError

IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
# The real variables of an exported model in the order of their value references (the C side's r[]), sized per
# model (:meth:`ExportModel.reals`); each variable carries its own unit.
REALS = Layout("ExportReals", (
    Field("time", "s", "simulation time"),
    Field("x", "", "the continuous states", ("X",)),
    Field("dx", "", "the state derivatives that are not states (y'[dx_first:])", ("DX",)),
    Field("y", "", "the calculated outputs", ("Y",)),
    Field("z", "", "the event indicators", ("Z",)),
    Field("u", "", "the inputs", ("U",)),
    Field("p", "", "the parameters", ("P",)),
    Field("d", "", "the discrete states (a model with regimes), read by its functions of (t, y, p) at p[N_P + i]",
          ("D",)),
))
# generalized force unit by coordinate unit
FORCE_UNIT = {"m": "N", "rad": "N m"}


@dataclass(frozen=True)
class Variable:
    """One FMI variable: ``vr`` its value reference, ``derivative_of`` the value reference of the state it is
    the derivative of (None otherwise); ``start`` None where the model computes it (initial="calculated")."""

    name: str
    vr: int
    causality: str  # independent, parameter, input, output
    variability: str  # continuous, tunable
    unit: str
    description: str
    start: float | None = None
    derivative_of: int | None = None
    nominal: float | None = None  # a state's magnitude: importers scale their absolute tolerance by it

    @property
    def initial(self) -> str | None:
        if self.causality in ("independent", "input"):
            return None
        return "exact" if self.start is not None else "calculated"


@dataclass(frozen=True)
class ExportModel:
    """A scene ready for C: the generated module ``identifier`` (its C99 text ``c_source``), the variable
    layout (``n_x`` states, ``n_dx`` derivative outputs that are y'[dx_first:], ``n_u`` inputs added to the
    rows ``u_row``... of F, ``n_p`` parameters) and the native run's main table (`symmech run`'s, None when
    the scene has none)."""

    identifier: str
    description: str
    c_source: str
    variables: tuple[Variable, ...]
    n_x: int
    n_dx: int
    dx_first: int
    n_u: int
    u_row: int
    n_p: int
    native: Table | None
    n_y: int = 0  # calculated outputs beyond the derivatives (MODEL_OUTPUTS), r[VR_Y:VR_Y + n_y]
    stiff: bool = False  # integrated by Radau IIA in C (Co-Simulation, the example program), else DOP853
    modules: tuple[tuple[str, str], ...] = ()  # (name, C99 text) of generated modules compiled beside c_source
    mass_identity: int = 0  # M = diag(I, M22) with this many identity rows (only M22 is factored; n_x: M = I,
    # no ``rate_mass`` generated)
    # the model writes F and M22 alone in one function (``<identifier>_rate_and_mass_block``) instead of M whole
    mass_block: bool = False
    mass_spd: bool = False  # M22 is symmetric positive definite by construction (Cholesky: its lower triangle read)
    second_order: bool = False  # y = (x, x') with F's first n_x/2 rows x' (a stiff model's Radau uses it)
    # the Model Exchange FMU's DefaultExperiment tolerance: the relative tolerance at which FMPy's CVode (BDF,
    # atol = rtol x nominal) reproduces the native run within the export's targets (docs/export.md)
    me_tolerance: float = 1e-10

    def c_files(self) -> tuple[str, ...]:
        """The model's C files (the physics), ``<identifier>.c`` first."""
        return (f"{self.identifier}.c", *(f"{name}.c" for name, _ in self.modules))
    # state events: n_z event indicators r[VR_Z:VR_Z + n_z] (``<identifier>_event_values``) and, where one falls
    # through zero, ``<identifier>_event_update`` of the state and the n_d discrete states r[VR_D:VR_D + n_d]
    n_z: int = 0
    n_d: int = 0
    event_tolerance: float = 0.0  # an indicator below -event_tolerance without its event: the model left its regime

    def layout(self) -> dict[str, int]:
        """First value reference of each block of ``r[]`` (:data:`REALS`) and its size (``N_REAL``)."""
        reals = REALS.sized(X=self.n_x, DX=self.n_dx, Y=self.n_y, Z=self.n_z, U=self.n_u, P=self.n_p, D=self.n_d)
        return {**{f"VR_{name.upper()}": reals.offset(name) for name in reals.names}, "N_REAL": reals.size}


def _structured(name: str) -> str:
    """``name`` as an FMI structured name: an identifier as it is, anything else quoted."""
    return name if IDENTIFIER.match(name) else "'" + name.replace("\\", "\\\\").replace("'", "\\'") + "'"


def load(path) -> ExportModel:
    """The export model of the mechanism scene at ``path`` (validated as `symmech run` does): :func:`of_scene`."""
    return of_scene(pipeline.load(path))


def of_scene(scene, ctx: Context | None = None) -> ExportModel:
    """The export model of a loaded mechanism scene (``pipeline.load``'s), its native run under ``ctx``'s time budget;
    SymmechError (exit 2) for another kind or a size the export does not cover, before any work."""
    from symmech.smm.scene import SYMBOLIC_LIMIT

    if scene.kind.name != "mechanism":
        raise SymmechError(f"kind = '{scene.kind.name}': `symmech export` covers mechanism, elastic trolley "
                           "and grain scenes so far (docs/export.md)")
    if scene.setup.n > SYMBOLIC_LIMIT:
        raise SymmechError(f"mechanism '{scene.setup.m.name}' has {scene.setup.n} coordinates; `symmech export` "
                           f"forms its equations symbolically, up to {SYMBOLIC_LIMIT} coordinates")
    ctx = ctx or Context(quiet=True)
    scene.budget(ctx)
    native = scene.kind.run(scene.setup, ctx).tables.get("free_response")
    return mechanism(scene.setup, native)


def mechanism(setup, native: Table | None) -> ExportModel:
    """The export model of a prepared mechanism scene (``symmech.smm.scene.Setup``) whose native run's main
    table is ``native``."""
    from symmech.core import emit
    from symmech.smm import numeric
    from symmech.smm.derive import module_spec

    m, sc = setup.m, setup.scene
    reserved = sorted(set(m.parameters) & emit.C99.reserved)
    if reserved:
        raise SymmechError(f"parameters.{reserved[0]}: a reserved word in C; rename it to export the scene")
    if sc["equilibrium"]["solve"]:
        m, _ = numeric.solve_equilibrium(m)
    spec = module_spec(m)
    n = len(m.coordinates)
    ini = sc["initial"] or {}
    q0 = list(ini.get("q") or [0.0] * n)
    v0 = list(ini.get("qdot") or [0.0] * n)
    q_nominal, v_nominal = _nominals(m, q0, v0)
    names = [_structured(c.name) for c in m.coordinates]
    reals = REALS.sized(X=2 * n, DX=n, Y=0, Z=0, U=n, P=len(m.parameters), D=0)  # x = (q, q'), dx = q'', u = Q
    q, qd, qdd = reals.offset("x"), reals.offset("x") + n, reals.offset("dx")
    variables = [Variable("time", reals.offset("time"), "independent", "continuous", "s", "simulation time")]
    for i, c in enumerate(m.coordinates):
        variables.append(Variable(names[i], q + i, "output", "continuous", c.unit,
                                  f"coordinate {c.name} ({c.kind})", q0[i], nominal=q_nominal))
    for i, c in enumerate(m.coordinates):
        variables.append(Variable(f"der({names[i]})", qd + i, "output", "continuous", f"{c.unit}/s",
                                  f"rate of {c.name}", v0[i], derivative_of=q + i, nominal=v_nominal))
    for i, c in enumerate(m.coordinates):
        variables.append(Variable(f"der({names[i]},2)", qdd + i, "output", "continuous", f"{c.unit}/s^2",
                                  f"acceleration of {c.name}", derivative_of=qd + i))
    for i, c in enumerate(m.coordinates):
        variables.append(Variable(_structured(f"Q_{c.name}"), reals.offset("u") + i, "input", "continuous",
                                  FORCE_UNIT[c.unit], f"generalized force on {c.name} (a q'' + b q' + c q = Q)", 0.0))
    for k, p in enumerate(m.parameters.values()):
        variables.append(Variable(_structured(p.name), reals.offset("p") + k, "parameter", "tunable", p.unit,
                                  p.meaning or f"parameter {p.name}", float(p.value)))
    clash = {v.name for v in variables if [w.name for w in variables].count(v.name) > 1}
    if clash:
        raise SymmechError(f"parameters and coordinates share the names {sorted(clash)}: rename them to export")
    # CVode's BDF leaves a phase error on undamped modes that grows with the periods run: 8.2e-7 of the spatial
    # boom's largest coordinate at rtol 1e-10, 1.5e-8 at 1e-12
    return ExportModel(spec.name, spec.doc, emit.render(spec, emit.C99), tuple(variables), 2 * n, n, n, n, n,
                       len(m.parameters), native, me_tolerance=1e-12)


def _nominals(m, q0: list, v0: list) -> tuple[float, float]:
    """Magnitudes of the coordinates and rates of the free motion from (q0, v0): the larger of the start
    amplitudes, coordinates and rates related by the lowest positive natural frequency (the smaller rate
    scale, so that an importer's absolute tolerance resolves the slowest mode too); 1 at rest."""
    from symmech.smm import numeric

    num = numeric.assemble(m)
    w2 = scipy.linalg.eigvals(num.c.toarray(), num.a.toarray())
    positive = np.abs(w2[np.isfinite(w2) & (w2.real > 0)])
    omega = math.sqrt(float(positive.min())) if positive.size else 1.0
    q = max(max(map(abs, q0)), max(map(abs, v0)) / omega)
    return (q, q * omega) if q > 0 else (1.0, 1.0)


# Accuracy of an exported run (tests, benchmarks). A series below this fraction of the largest coordinate series
# vanishes in exact arithmetic (a coordinate the start state does not excite, moved only by the round-off of the
# assembled c, ~1e-17 of the motion): its own magnitude is round-off, so it is compared against the largest.
VANISHING = 1e-9


def deviation(got: np.ndarray, native: np.ndarray) -> float:
    """Largest deviation of the columns of ``got`` from ``native``, each relative to the native series' largest
    magnitude (a vanishing series: relative to the largest of all)."""
    scale = np.abs(native).max(axis=0)
    scale = np.where(scale < VANISHING * scale.max(), scale.max(), scale)
    return float(np.max(np.abs(got - native).max(axis=0) / scale))
