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
N_CHANNELS, N_GEOMETRY = CHANNELS.size, GEOMETRY.size
LAYOUTS = (MODEL, FLAGS, ROLLER, CHANNELS, GEOMETRY)  # symmech.core.engines: describe
