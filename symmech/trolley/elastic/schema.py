"""Schema of the optional ``[elastic]`` table of a trolley scene (docs/scenes-trolley-elastic.md is
generated from :data:`SCHEMA`). Apart from the elastic model so that validating a rigid trolley scene does
not import it (nor its generated module)."""
from symmech.core.schema import Bool, Choice, Float, Int, Str, Table, TableList, Vector

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
    "length": Float("length", unit="m", lo=1e-3, hi=1e3),  # shorter than 1 mm it is no beam (its modes singular)
    "mass_per_length": Float("mass per unit length ρA", unit="kg/m", lo=1e-3, hi=1e6),  # 1 g/m at least
    "ei": Vector("bending stiffness EI in the first and second plane", n=2, unit="N m^2", lo=1e-6,
                 hi=1e15),  # softer than a hair its first mode is zero in floating point (its damping undefined)
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

# Largest initial beam deflection, a fraction of its length: the beam model assumes small slopes.
MAX_INITIAL_DEFLECTION = 0.1

POINT = Table("a body point whose deflection and overload are reported", {
    "name": Str("name used in the column headers", pattern=r"[A-Za-z_][A-Za-z0-9_]*"),
    "at": Vector("a point of the rigid trolley (trolley frame)", n=3, unit="m", lo=-1e3, hi=1e3, default=None),
    "beam": Int("index of the beam (0 = first [[elastic.beams]])", lo=0, hi=99, default=None),
    "xi": Float("position along that beam, x/L", unit="1", lo=0.0, hi=1.0, default=None),
})

INITIAL_BEAM = Table("a beam deflected in one of its own modes at t = 0", {
    "beam": Int("index of the beam (0 = first [[elastic.beams]])", lo=0, hi=49),
    "plane": Int("bending plane: 1 along the beam's `plane`, 2 along axis × plane", lo=1, hi=2),
    "mode": Int("mode of the beam alone on a fixed trolley (tip mass included) in that plane, 1 = lowest; at "
                "most the beam's `modes`", lo=1, hi=8, default=1),
    "amplitude": Float("largest deflection along the beam (positive: along the plane's direction there); "
                       f"in magnitude at most {MAX_INITIAL_DEFLECTION:g} of the beam's length", unit="m",
                       lo=-100.0, hi=100.0, default=0.0),
    "velocity": Float("largest deflection rate along the beam, same shape", unit="m/s", lo=-1e3, hi=1e3,
                      default=0.0),
})

INITIAL = Table("the state at t = 0: offsets added to the quasi-static state there (free vibrations)", {
    "rollers": Vector("roller coordinates u2, u3 [m], θ1, θ2, θ3 [rad] (needs effects.rollers)", n=5,
                      unit="m or rad", lo=-0.1, hi=0.1, default=[0.0] * 5),
    "roller_rates": Vector("their rates u̇2, u̇3 [m/s], θ̇1, θ̇2, θ̇3 [rad/s]", n=5, unit="m/s or rad/s",
                           lo=-100.0, hi=100.0, default=[0.0] * 5),
    "beams": TableList("beams deflected in their modes (needs effects.body); the modes add up", item=INITIAL_BEAM,
                       max_items=100, default=[]),
}, default={})

SCHEMA = Table("elastic model of the trolley (seed 002)", {
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
    "initial": INITIAL,
    "numerics": Table("integration", {
        "engine": Choice("`compiled`: the assembly in numba, integrated by the compiled Radau IIA with the analytic "
                         "Jacobian (symmech.trolley.elastic.compiled; compiled once per installation, ~2 CPU-minutes, "
                         "then loaded from numba's cache; `symmech warm` builds it); the frame along the track is "
                         "tabulated per run and its interpolation error checked against the exact frame. "
                         "`python`: scipy's `solve_ivp` on the numpy assembly (the reference). `auto`: `compiled` "
                         "when numba's cache holds it, else `python` while the compiled engine is built in the "
                         "background for the next run (no builder with `SYMMECH_BACKGROUND_BUILD=0`; `compiled` "
                         "at once when the Python engine's estimate exceeds the compile). A `method` other than "
                         "Radau runs on `python`",
                         choices=("auto", "compiled", "python"), default="auto"),
        "method": Choice("integrator (implicit ones use the analytic Jacobian)",
                         choices=("Radau", "BDF", "LSODA", "DOP853", "RK45"), default="Radau"),
        "rtol": Float("relative tolerance", unit="1", lo=1e-13, hi=1e-2, default=1e-7),
        "modal_samples": Int("instants of the modal analysis along the track", lo=0, hi=1000, default=20),
        "small_rotation": Float("roller rotation beyond which the quadratic approximation is flagged",
                                unit="rad", lo=0.0, lo_open=True, hi=1.0, default=0.05),
        "resonance_band": Float("a natural frequency within this fraction of a forcing frequency is flagged",
                                unit="1", lo=0.0, lo_open=True, hi=1.0, default=0.1),
    }, default={}),
}, default=None)
