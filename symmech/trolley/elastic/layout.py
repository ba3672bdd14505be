"""The elastic trolley engine's declared layouts (:mod:`symmech.core.layout`), shared by its kernels
(:mod:`symmech.trolley.elastic.kernels`) and its driver (:mod:`symmech.trolley.elastic.compiled`): the
model record the kernels take whole, its flags vector and roller rows, the 12 frame channels of the spline table in t and
the 15 geometry channels of the traction table in s. No numba here.

N is the number of generalised coordinates (5 rigid-body coordinates of the trolley on its rollers, then
the beams' modal coordinates), F = 1 + N + (number of pairs) the number of fields (r, the φ_a, the ψ_ab of
the pairs a <= b), B the number of membrane blocks (beams with held ends) and W their largest size."""
from __future__ import annotations

from symmech.core.layout import Bundle, Field, Layout

FLAGS = Layout("ElasticFlags", (
    Field("n", "", "number N of generalised coordinates"),
    Field("f", "", "number F of fields"),
    Field("mass", "kg", "mass of the whole body"),
    Field("g0", "m/s^2", "gravity"),
    Field("rollers", "1", "1: the rollers are elastic"),
    Field("law", "1", "roller law: 0 linear, 1 clamped pair"),
))
# The rows of the model's roller table ``roll`` (ROLLER.size, 5): one column per roller P1…P5.
ROLLER = Layout("ElasticRoller", (
    Field("stiffness", "N/m", "roller stiffness"),
    Field("damping", "N s/m", "roller damping (0 when damping is off)"),
    Field("preload", "m", "preload deflection of the clamped pair law (negative: a gap)"),
))
# The vectors whose length follows the model's N coordinates and P pairs (families, core.layout.Layout.sized): the
# compiled loops read their edges from the model record (``mdl.state_at``...) indexed by the constant positions
# (Y_AT, FC_AT...), the Python side slices a member sized for the model.
# The state both engines integrate; a run with traction adds s and V0 (TRACTION_STATE: STATE's fields first).
STATE = Layout("ElasticState", (
    Field("q", "m or rad", "generalised coordinates: the five roller DOFs (elastic rollers), then the beams'", ("N",)),
    Field("qd", "m/s or rad/s", "their rates", ("N",)),
    Field("dissipated", "J", "energy E_d dissipated by the roller and beam dampers"),
    Field("work", "J", "work W of the forces of the track"),
))
TRACTION_STATE = Layout("ElasticTractionState", STATE.fields + (
    Field("s", "m", "arc length of O along the track"),
    Field("speed", "m/s", "speed V0 of O along the track"),
))
# The coefficients of a body point's position r̃ = r + Σ q_a φ_a + ½ Σ q_a q_b ψ_ab over the F = 1 + N + P fields.
FIELDS = Layout("ElasticFields", (
    Field("r", "1", "the undeformed position r"),
    Field("phi", "m or rad", "the coordinates' fields φ_a", ("N",)),
    Field("psi", "m^2, m rad or rad^2", "the pairs' fields ψ_ab, a <= b (pair_i, pair_j)", ("P",)),
))
# The roller coordinates, the first of q when the rollers are elastic (body.ROLLER_NAMES).
ROLLER_DOFS = Layout("ElasticRollerDofs", (
    Field("u2", "m", "translation of the trolley along x2"), Field("u3", "m", "translation along x3"),
    Field("th1", "rad", "small rotation about x1"), Field("th2", "rad", "about x2"), Field("th3", "rad", "about x3"),
))
# (i, j) of the rotation pairs of ψ0 (0-based in q0 = (u2, u3, th1, th2, th3)): 44, 45, 46, 55, 56, 66
ROTATION_PAIRS = ((2, 2), (2, 3), (2, 4), (3, 3), (3, 4), (4, 4))
# The columns of the generated ``trolley_elastic.rigid_fields`` (P, 3, columns): the rigid displacement's first and
# second derivatives at q0 = 0 (symmech.trolley.elastic.derive.rigid_fields).
RIGID_FIELDS = Layout("ElasticRigidFields", (
    Field("phi", "1 or m", "φ0: derivative by each roller coordinate (ROLLER_DOFS)", (ROLLER_DOFS.size,)),
    Field("psi", "m", "ψ0: second derivative by each rotation pair (ROTATION_PAIRS)", (len(ROTATION_PAIRS),)),
))
# With traction, q̈ and V̇0 solve one linear system together: its unknowns, and the columns of its derivative
# by the state (the state without E_d and W, which the equations do not read).
TRACTION_UNKNOWNS = Layout("ElasticTractionUnknowns", (
    Field("qdd", "m/s^2 or rad/s^2", "accelerations of the coordinates", ("N",)),
    Field("dspeed", "m/s^2", "rate V̇0 of the speed"),
))
TRACTION_COLUMNS = Layout("ElasticTractionColumns", tuple(TRACTION_STATE.field(n) for n in ("q", "qd", "s", "speed")))
MODEL = Bundle("ElasticModel", __name__, (
    Field("flags", "", "the flags vector (FLAGS)", (FLAGS.size,)),
    Field("ptr", "", "row pointers of the ψ entries of A, per coordinate", ("N+1",), "int64"),
    Field("col", "", "field index (column of A) of each ψ entry", ("entries",), "int64"),
    Field("qi", "", "coordinate multiplying each ψ entry", ("entries",), "int64"),
    Field("pair_i", "", "first coordinate of each pair a <= b", ("pairs",), "int64"),
    Field("pair_j", "", "second coordinate of each pair", ("pairs",), "int64"),
    Field("gram_x", "kg m^2", "Gram tensor G (F, F, 3, 3) as G_kl[i, j] at row 9 k + 3 i + j, column l",
          ("9F", "F")),
    Field("gram_trace", "kg m^2", "trace of G over its 3 x 3 blocks (Gtr)", ("F", "F")),
    Field("rollers_map", "1", "roller deflections from the 5 rigid-body coordinates", (5, 5)),
    Field("roll", "", "per roller (columns): rows of ROLLER, stiffness [N/m], damping [N s/m], preload [m]",
          (ROLLER.size, 5)),
    Field("block_index", "", "coordinates of each membrane block (padded)", ("B", "W"), "int64"),
    Field("block_size", "", "number of coordinates of each membrane block", ("B",), "int64"),
    Field("block_h", "1", "slope Gram H of each held beam (padded): Π_m = c (qᵀ H q)²", ("B", "W", "W")),
    Field("block_c", "N/m^3", "c = EA / (8 L³) of each held beam", ("B",)),
    Field("s1", "kg m", "first moments Σ w f_k of the fields", ("F", 3)),
    Field("stiffness", "N/m", "constant stiffness K of the beams", ("N", "N")),
    Field("damping", "N s/m", "constant damping D of the beams", ("N", "N")),
    Field("pair_field", "", "field index of ψ_ab for coordinates (a, b), -1 for none (dA)", ("N", "N"), "int64"),
    Field("gram_9", "kg m^2", "Gram tensor G as G_kl at row F k + l, flattened 3 x 3 block", ("F*F", 9)),
    Field("state_at", "", "edges of the state (TRACTION_STATE sized for the model; STATE its first fields)", (7,),
          "int64"),
    Field("fields_at", "", "edges of the field coefficients (FIELDS sized for the model)", (4,), "int64"),
    Field("unknowns_at", "", "edges of the traction unknowns (TRACTION_UNKNOWNS sized)", (3,), "int64"),
    Field("columns_at", "", "edges of the traction Jacobian's columns (TRACTION_COLUMNS sized)", (5,), "int64"),
))
ElasticModel = MODEL.record  # bound here under its own name: numba's cache pickles the class by reference
# Frame channels of the table in t (columns).
CHANNELS = Layout("ElasticChannels", (
    Field("load", "m/s^2", "a0 + g0 ν: acceleration of the frame's origin plus gravity, body components", (3,)),
    Field("omega", "rad/s", "angular velocity ω of the frame", (3,)),
    Field("domega", "rad/s^2", "angular acceleration ω̇ of the frame", (3,)),
    Field("v0", "m/s", "velocity of the frame's origin", (3,)),
))
# Geometry channels of the traction table in the arc length s (columns; model.Frame); the frame's motion at
# V0, V̇0 follows from them (kernels._motion).
GEOMETRY = Layout("ElasticGeometry", (
    Field("e", "1", "unit tangent e", (3,)),
    Field("k", "1/m", "e' + Ω × e", (3,)),
    Field("nu", "1", "unit vertical ν in the frame", (3,)),
    Field("om", "rad/m", "rotation rate Ω of the frame per arc length", (3,)),
    Field("dom", "rad/m^2", "Ω'", (3,)),
))
F_AT, CH_AT, G_AT, RL_AT = FLAGS.slots, CHANNELS.slots, GEOMETRY.slots, ROLLER.slots
Y_AT, FC_AT = TRACTION_STATE.positions, FIELDS.positions
U_AT, CO_AT = TRACTION_UNKNOWNS.positions, TRACTION_COLUMNS.positions
N_CHANNELS, N_GEOMETRY, N_ROLLER_DOFS = CHANNELS.size, GEOMETRY.size, ROLLER_DOFS.size
LAYOUTS = (MODEL, FLAGS, ROLLER, CHANNELS, GEOMETRY, ROLLER_DOFS, STATE, TRACTION_STATE, FIELDS, TRACTION_UNKNOWNS,
           TRACTION_COLUMNS, RIGID_FIELDS)  # symmech.core.engines: describe


def state(n: int, traction: bool) -> Layout:
    """The state of a run of a model of n coordinates: STATE, or TRACTION_STATE with traction."""
    return (TRACTION_STATE if traction else STATE).sized(N=n)


def edges(n: int, pairs: int) -> dict:
    """The record's edges of the sized vectors (MODEL's ``*_at`` fields) of a model of n coordinates and pairs."""
    return {"state_at": TRACTION_STATE.sized(N=n).edges(), "fields_at": FIELDS.sized(N=n, P=pairs).edges(),
            "unknowns_at": TRACTION_UNKNOWNS.sized(N=n).edges(), "columns_at": TRACTION_COLUMNS.sized(N=n).edges()}
