"""Declared layouts (symmech.core.layout) and the engines' vectors declared with them: offsets, pack/unpack
round trips, the numba types derived from a declaration, and a drift test of the declarations against every
place that reads them (the compiled loops index through the layouts' offsets, never by hand)."""
import ast
import pickle
import re
from pathlib import Path

import numba
import numpy as np
import pytest

from symmech.core.layout import Bundle, Field, Layout
from symmech.grain import motion
from symmech.grain.motion_engine import driver as compiled, layouts as compiled_layout
from symmech.numerics import radau
from symmech.trolley.elastic import layout as elastic_layout

ROOT = Path(__file__).resolve().parents[1] / "symmech"
SMALL = Layout("Small", (Field("a", "m", "a scalar"), Field("b", "m/s", "a vector", (3,)),
                         Field("c", "1", "a matrix", (2, 2))))


def test_offsets_slices_and_labels_follow_the_declaration_order():
    assert SMALL.size == 8 and SMALL.names == ("a", "b", "c") and SMALL.units == ("m", "m/s", "1")
    assert (SMALL.offset("a"), SMALL.offset("b"), SMALL.offset("c")) == (0, 1, 4)
    assert SMALL.slice("b") == slice(1, 4) and SMALL.slice("c") == slice(4, 8)
    assert tuple(SMALL.slots) == (0, 1, 4) and SMALL.slots.c == 4
    assert SMALL.labels == ("a", "b[0]", "b[1]", "b[2]", "c[0]", "c[1]", "c[2]", "c[3]")


def test_pack_then_unpack_gives_back_every_value():
    c = np.array([[5.0, 6.0], [7.0, 8.0]])
    vec = SMALL.pack(a=0.5, b=(1.0, 2.0, 3.0), c=c)
    assert vec.dtype == float and vec.tolist() == [0.5, 1.0, 2.0, 3.0, 5.0, 6.0, 7.0, 8.0]  # c row by row
    back = SMALL.unpack(vec)
    assert type(back["a"]) is float and back["a"] == 0.5
    assert back["b"].tolist() == [1.0, 2.0, 3.0] and np.array_equal(back["c"], c)
    assert np.shares_memory(back["b"], vec) and np.shares_memory(back["c"], vec)  # views, not copies
    assert np.array_equal(SMALL.pack(**SMALL.unpack(vec)), vec)


@pytest.mark.parametrize("values, error, text", [
    ({"a": 0.5, "b": (1.0, 2.0)}, TypeError, "'c'"),  # missing
    ({"a": 0.5, "b": (1.0, 2.0, 3.0), "c": np.zeros((2, 2)), "d": 1.0}, TypeError, "'d'"),  # unknown
    ({"a": 0.5, "b": (1.0, 2.0), "c": np.zeros((2, 2))}, ValueError, "b has shape (2,), expected (3,)"),
    ({"a": (0.5, 1.0), "b": (1.0, 2.0, 3.0), "c": np.zeros((2, 2))}, ValueError, "a has shape (2,), expected ()"),
    ({"a": 0.5, "b": (1.0, 2.0, 3.0), "c": np.zeros(4)}, ValueError, "c has shape (4,), expected (2, 2)"),
    ({"a": "x", "b": (1.0, 2.0, 3.0), "c": np.zeros((2, 2))}, ValueError, "not a number"),
])
def test_pack_refuses_values_that_do_not_fit_and_names_the_field(values, error, text):
    with pytest.raises(error, match=None) as err:
        SMALL.pack(**values)
    assert text in str(err.value)


def test_unpack_refuses_a_vector_of_another_length():
    with pytest.raises(ValueError, match=r"Small.unpack: a vector of shape \(8,\) expected, got \(7,\)"):
        SMALL.unpack(np.zeros(7))


@pytest.mark.parametrize("fields", [
    (Field("a", "m", ""), Field("a", "m", "")),       # twice
    (Field("_a", "m", ""),),                          # private
    (Field("a b", "m", ""),),                         # not an identifier
    (Field("a", "m", "", (2,), "int64"),),            # a layout holds float64 only
])
def test_a_layout_refuses_names_it_could_not_offer_as_attributes(fields):
    with pytest.raises(ValueError):
        Layout("Bad", fields)


def test_a_layout_vector_is_the_array_type_numba_gives_the_packed_vector():
    assert SMALL.numba_type() == numba.typeof(SMALL.pack(a=0.0, b=(0, 0, 0), c=np.zeros((2, 2))))


FAMILY = Layout("Family", (Field("q", "m", "coordinates", ("N",)), Field("e", "J", "an energy"),
                           Field("psi", "1", "pairs", ("P",))))


def test_a_layout_family_sized_for_a_model_has_the_offsets_of_its_sizes():
    member = FAMILY.sized(N=3, P=2)
    assert FAMILY.dims == ("N", "P") and member.dims == () and member.size == 6
    assert (member.offset("e"), member.slice("psi")) == (3, slice(4, 6))
    assert member.edges().tolist() == [0, 3, 4, 6] and member.edges().dtype == np.int64
    assert FAMILY.positions == member.positions and tuple(FAMILY.positions) == (0, 1, 2)
    assert FAMILY.sized(N=3, P=2) is member  # one member per sizes
    assert member.pack(q=[1.0, 2.0, 3.0], e=4.0, psi=[5.0, 6.0]).tolist() == [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]


@pytest.mark.parametrize("sizes", [{"N": 3}, {"N": 3, "P": 2, "M": 1}, {"N": -1, "P": 2}, {"N": 1.5, "P": 2}])
def test_a_layout_family_refuses_sizes_that_do_not_fit_its_dimensions(sizes):
    with pytest.raises(ValueError, match=r"Family.sized: sizes of \('N', 'P'\)"):
        FAMILY.sized(**sizes)


def test_a_layout_family_has_no_offsets_until_its_sizes_are_given():
    with pytest.raises(ValueError, match="sizes of .* are open"):
        FAMILY.offset("e")


def test_the_elastic_states_keep_the_order_both_engines_were_built_with():
    """The state [q, q̇, E_d, W(, s, V0)] of a model of 4 coordinates, offsets written down independently; the
    state without traction is the traction state's first fields (the output rows read either through it)."""
    plain, traction = elastic_layout.state(4, False), elastic_layout.state(4, True)
    assert plain.edges().tolist() == [0, 4, 8, 9, 10]
    assert traction.edges().tolist() == [0, 4, 8, 9, 10, 11, 12]
    assert traction.fields[:len(plain.fields)] == plain.fields
    assert elastic_layout.FIELDS.sized(N=4, P=3).edges().tolist() == [0, 1, 5, 8]
    assert elastic_layout.TRACTION_UNKNOWNS.sized(N=4).edges().tolist() == [0, 4, 5]
    assert elastic_layout.TRACTION_COLUMNS.sized(N=4).edges().tolist() == [0, 4, 8, 9, 10]
    assert elastic_layout.ROLLER_DOFS.names == ("u2", "u3", "th1", "th2", "th3")


def test_a_bundle_packs_a_record_of_its_dtypes_that_numba_types_as_declared_and_pickles():
    bundle = Bundle("Probe", __name__, (Field("x", "m", "", ("n",)), Field("k", "", "", ("n", 2), "int64")))
    record = bundle.pack(x=[1, 2], k=[[1, 2], [3, 4]])
    assert record.x.dtype == np.float64 and record.k.dtype == np.int64 and record.k.flags.c_contiguous
    assert bundle.numba_type() == numba.typeof(record)
    assert bundle.unpack(record).keys() == {"x", "k"}
    with pytest.raises(ValueError, match="k has 1 dimensions, expected 2"):
        bundle.pack(x=[1.0], k=[1])
    # numba's cache pickles the record's class by reference: the declaring module binds it under its name
    model = elastic_layout.MODEL.pack(**{f.name: np.zeros((1,) * len(f.shape), f.dtype)
                                         for f in elastic_layout.MODEL.fields})
    assert type(pickle.loads(pickle.dumps(model))) is elastic_layout.ElasticModel


def test_the_elastic_model_record_of_a_system_has_the_declared_numba_type():
    """The signature the elastic engine is compiled for (elastic_compiled._entry_signatures) is the record
    type derived from MODEL: it must be the type of the record System.record hands the kernels."""
    import sys

    sys.path.insert(0, str(Path(__file__).parent))
    from test_elastic_compiled import helix

    from symmech.trolley.elastic import compiled as elastic_compiled

    record = helix().system.record
    assert numba.typeof(record) == elastic_layout.MODEL.numba_type()
    for entry, signature in elastic_compiled._entry_signatures().items():
        assert signature[0] == numba.typeof(record), entry
    flags = elastic_layout.FLAGS.unpack(record.flags)
    assert flags["n"] == record.stiffness.shape[0] and flags["f"] == record.gram_trace.shape[0]
    n, pairs = int(flags["n"]), record.pair_i.size  # the edges the kernels read: those of the sized layouts
    assert record.state_at.tolist() == [0, n, 2 * n, 2 * n + 1, 2 * n + 2, 2 * n + 3, 2 * n + 4]
    assert record.fields_at.tolist() == [0, 1, 1 + n, 1 + n + pairs] and 1 + n + pairs == flags["f"]
    assert record.unknowns_at.tolist() == [0, n, n + 1]
    assert record.columns_at.tolist() == [0, n, 2 * n, 2 * n + 1, 2 * n + 2]


def test_the_grain_layouts_keep_the_slots_the_engine_was_built_with():
    """The offsets of the grain's declarations, written down independently (the hand-numbered constants they
    replaced): a change of order is a change of the engine's interface (ahead-of-time builds, saved rows)."""
    P, C, S, I = compiled_layout.P_AT, compiled_layout.C_AT, compiled_layout.S_AT, compiled_layout.I_AT
    sizes = [x.size for x in (compiled_layout.PARAMS, compiled_layout.SLIDE, compiled_layout.CARRY,
                              compiled_layout.IMPACT_ROW, compiled_layout.STATE)]
    assert sizes == [32, 36, 17, 31, 14]
    assert (P.axes, P.mass, P.inertia, P.g, P.amplitude, P.direction, P.law, P.e_n, P.check_printed, P.mu,
            P.tolerance, P.max_impacts, P.period, P.exact_flight) == (0, 3, 4, 7, 10, 13, 16, 17, 22, 23, 25, 28, 30, 31)
    assert (S.g, S.direction, S.mu, S.r0, S.rb, S.sphere, S.m, S.mass, S.inertia, S.ref, S.v_stop, S.event,
            S.aniso, S.v_stiff) == (0, 6, 9, 10, 13, 16, 17, 26, 27, 30, 32, 33, 34, 35)
    assert (C.regime, C.work, C.rows, C.nimp, C.nwarn, C.rocking, C.implicit, C.e_start, C.e_end) == \
        (0, 6, 10, 11, 12, 13, 14, 15, 16)
    assert (I.t, I.r, I.impulse, I.u_after, I.ke_before, I.admissible, I.converged) == (0, 1, 16, 22, 25, 27, 30)
    Z, RO = compiled_layout.Z_AT, compiled_layout.RO_AT  # the sliding vector and a flight's rotation
    assert (Z.r, Z.v, Z.w, Z.q, Z.work, Z.loss, compiled_layout.N_SLIDING) == (0, 2, 4, 7, 11, 12, 13)
    assert (RO.q, RO.w, compiled_layout.N_ROTATION) == (0, 4, 7)
    assert tuple(radau.ST_AT) == tuple(range(7)) and radau.N_RADAU == 7  # Radau's solver state


def test_a_flights_rotation_is_the_states_orientation_and_spin_in_their_order():
    """The loop copies the state's (q, w) into a flight's rotation state and a flight's record's (q0, w0) out
    of it whole: the rotation layout must be the state's last two fields, in the same order and shapes."""
    L = compiled_layout
    state = [(f.name, f.shape) for f in L.STATE.fields]
    assert [(f.name, f.shape) for f in L.ROTATION.fields] == state[-2:] == [("q", (4,)), ("w", (3,))]
    assert L.X_AT.q + L.ROTATION.size == L.STATE.size and L.FL_AT.w0 == L.FL_AT.q0 + L.RO_AT.w


def _fields(layout, names) -> list:
    return [(f.name, f.shape) for f in layout.fields if f.name in names]


def test_the_grain_rows_and_scratch_vectors_mirror_what_they_are_copied_from():
    """The loop copies a state wholesale into a flight's record (t0 ... w0) and the state's t, r, v, q into a
    trajectory row; a trajectory row has the columns of the Python loop's trajectory; a sliding step ends with a
    whole sliding-parameter vector. Sizes written down independently: 39 = 14 + 3 + 1 + 1 + 1 + 7 + 1 + 1 + 1 + 1
    + 7 + 1, a rotation step 2 + 7 + 7 x 7, a sliding step 2 + 13 + 1 + 36."""
    L = compiled_layout
    state = [(f.name, f.shape) for f in L.STATE.fields]
    assert [(name[:-1], shape) for name, shape in _fields(L.FLIGHT_RECORD, ("t0", "r0", "v0", "q0", "w0"))] == state
    assert [L.FL_AT.t0, L.FL_AT.w0 + 3] == [0, L.STATE.size]
    assert _fields(L.TRAJECTORY_ROW, ("t", "r", "v", "q")) == state[:4] and L.T_AT.q == L.X_AT.q
    assert L.TRAJECTORY_ROW.size == len(motion.TRAJECTORY_COLUMNS) == L.TRAJECTORY_WIDTH == 15
    assert [L.T_AT.w, L.T_AT.regime] == [motion.TRAJECTORY_COLUMNS.index(c) for c in ("wx", "regime")]
    assert (L.FLIGHT_RECORD.size, L.ROTATION_STEP.size, L.SLIDE_STEP.size, L.SAMPLER.size) == (39, 58, 52, 4)
    assert L.SS_AT.sp + L.SLIDE.size == L.SLIDE_STEP.size and L.RS_AT.dense + 49 == L.ROT_WIDTH
    assert (L.N_FLIGHT, L.N_SLIDE_STEP, L.N_SAMPLER, L.WARNING_WIDTH) == (39, 52, 4, 3)


def test_the_grain_state_vector_round_trips_through_the_engines_python_side():
    y = compiled_layout.STATE.pack(t=0.25, r=(1.0, 2.0, 3.0), v=(4.0, 5.0, 6.0), q=(1.0, 0.0, 0.0, 0.0),
                                   w=(7.0, 8.0, 9.0))
    st = compiled.state_view(y)
    assert st.t == 0.25 and st.r.tolist() == [1.0, 2.0, 3.0] and st.q.tolist() == [1.0, 0.0, 0.0, 0.0]
    assert st.w.tolist() == [7.0, 8.0, 9.0] and np.shares_memory(st.v, y)


# --------------------------------------------------------------------------- drift

# The vectors each file indexes, and the offsets (named tuples of a layout) each may be indexed with.
GRAIN_VECTORS = {"p": "P_AT", "sp": "S_AT", "carry": "C_AT", "log": "I_AT", "imps": "I_AT", "rows": "T_AT",
                 "warns": "WR_AT", "tab": "RS_AT", "row": "RS_AT", "rec": "SM_AT",
                 "ctx": ("FL_AT", "SS_AT")}  # ctx: a flight's record, or a sliding step (the root finders take both)
ELASTIC_VECTORS = {"flags": "F_AT", "ch": "CH_AT", "g": "G_AT", "dg": "G_AT", "roll": "RL_AT"}
OFFSETS = {"P_AT": compiled_layout.PARAMS, "S_AT": compiled_layout.SLIDE, "C_AT": compiled_layout.CARRY,
           "I_AT": compiled_layout.IMPACT_ROW, "X_AT": compiled_layout.STATE, "F_AT": elastic_layout.FLAGS,
           "CH_AT": elastic_layout.CHANNELS, "G_AT": elastic_layout.GEOMETRY, "T_AT": compiled_layout.TRAJECTORY_ROW,
           "WR_AT": compiled_layout.WARNING_ROW, "FL_AT": compiled_layout.FLIGHT_RECORD,
           "RS_AT": compiled_layout.ROTATION_STEP, "SS_AT": compiled_layout.SLIDE_STEP, "SM_AT": compiled_layout.SAMPLER,
           "RO_AT": compiled_layout.ROTATION, "Z_AT": compiled_layout.SLIDE_STATE, "ST_AT": radau.RADAU_STATE, "RL_AT": elastic_layout.ROLLER,
           "Y_AT": elastic_layout.TRACTION_STATE, "FC_AT": elastic_layout.FIELDS, "U_AT": elastic_layout.TRACTION_UNKNOWNS,
           "CO_AT": elastic_layout.TRACTION_COLUMNS}
GRAIN_READERS = ("driver", "flight_path", "flight_phase", "impact_law", "kinematics", "landing", "loop", "roots", "rows",
                 "sliding_phase", "slip", "steppers")  # the grain engine's modules that read a declared vector
STATE_READERS = ("flight_phase", "impact_law", "kinematics", "landing", "loop", "sliding_phase")  # y: the state
# Other vectors by module: z the sliding vector, y a flight's rotation (q, w), st Radau's solver state.
OWN_VECTORS = {"slip": {"z": "Z_AT", "out": "Z_AT", "J": "Z_AT", "y": "X_AT"}, "sliding_phase": {"z": "Z_AT"},
               "roots": {"z": "Z_AT"}, "steppers": {"y": ("RO_AT", "Z_AT"), "out": ("RO_AT", "Z_AT")},
               "flight_path": {"y": ("RO_AT", "X_AT")}}
READERS = {**{f"grain/motion_engine/{name}.py": {**GRAIN_VECTORS, **OWN_VECTORS.get(name, {})}
              for name in GRAIN_READERS},
           **{f"grain/motion_engine/{name}.py": {**GRAIN_VECTORS, "y": "X_AT", "after": "X_AT", "out": "X_AT",
                                                 **OWN_VECTORS.get(name, {})} for name in STATE_READERS},
           "numerics/radau.py": {"st": "ST_AT"},
           "trolley/elastic/kernels.py": ELASTIC_VECTORS, "trolley/elastic/frame.py": {}}  # (k, 12) tables there


def _names(node) -> set:
    return {n.id for n in ast.walk(node) if isinstance(n, ast.Name)}


def _by_hand(part, offsets: set) -> bool:
    """Whether an index expression holds a number but not the vector's offsets (``p[3]``, not ``p[P_AT.g + 2]``,
    ``p[d + 1]`` after ``d = P_AT.direction``, or a loop's ``ch[j]``)."""
    return any(isinstance(n, ast.Constant) for n in ast.walk(part)) and not _names(part) & offsets


@pytest.mark.parametrize("path", sorted(READERS))
def test_every_read_of_a_declared_vector_goes_through_its_layout(path):
    """Every ``X_AT.name`` names a field of X's layout; every ``mdl.name`` a field of the elastic model; and no
    declared vector (p, sp, carry, the impact row; the elastic flags and channels) is indexed by a bare number:
    each index is built from the vector's own offsets, so a reordered declaration moves every reader with it."""
    tree = ast.parse((ROOT / path).read_text(encoding="utf-8"))
    vectors = READERS[path]
    aliases = {t.id for n in ast.walk(tree) if isinstance(n, ast.Assign) and _names(n.value) & OFFSETS.keys()
               for target in n.targets for t in ast.walk(target) if isinstance(t, ast.Name)}  # d = P_AT.direction
    packs = {n for f in ast.walk(tree) if isinstance(f, ast.FunctionDef) and f.name == "pack" for n in ast.walk(f)}
    seen = 0
    for node in ast.walk(tree):
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name):
            if node.value.id in OFFSETS:
                assert node.attr in OFFSETS[node.value.id].names, f"{path}:{node.lineno} {node.value.id}.{node.attr}"
                seen += 1
            if node.value.id == "mdl" and node not in packs:  # pack reads the scene's model, also called mdl
                assert node.attr in elastic_layout.MODEL.names, f"{path}:{node.lineno} mdl.{node.attr}"
        if isinstance(node, ast.Subscript) and isinstance(node.value, ast.Name) and node.value.id in vectors:
            index = node.slice  # each dimension of a table (rows[n, T_AT.regime]) on its own
            parts = [b for i in (index.elts if isinstance(index, ast.Tuple) else [index])
                     for b in ([i.lower, i.upper] if isinstance(i, ast.Slice) else [i])]
            for part in (p for p in parts if p is not None):
                own = vectors[node.value.id]
                assert not _by_hand(part, ({own} if isinstance(own, str) else set(own)) | aliases), \
                    f"{path}:{node.lineno} {ast.unparse(node)} indexes a declared vector by hand"
    assert seen > 0


# The vectors whose length follows the model (the elastic state, field coefficients, traction unknowns and
# columns): each file's names for them. Every index into them is built from the sized layouts (offsets bound from
# Y_AT, FC_AT, U_AT, CO_AT positions, or a sized layout's offset/slice), never from a number or the size n alone.
# The axes of each that are sized (None: all of them; a table's rows are not).
SIZED = {"trolley/elastic/kernels.py": {**dict.fromkeys(("y", "out", "f", "J", "L", "rhs", "x", "G", "dx", "z", "Z",
                                                         "Zt", "S1", "p2", "q", "qd", "R")), "Y": (1,)},
         "trolley/elastic/compiled.py": {"y": None, "Y": (1,)},
         "trolley/elastic/simulate.py": {**dict.fromkeys(("y", "out", "mask")), "Y": (1,), "q": (1,), "qd": (1,)},
         "trolley/elastic/system.py": dict.fromkeys(("rr", "out", "q", "qd", "R", "Rq", "Rqd", "mask")),
         "trolley/elastic/scene.py": {"target": None, "q": (1,)}, "trolley/elastic/body.py": {"dA": None}}
# The vectors and generated outputs outside the engines that a declared layout numbers (read through its offsets,
# slices or split), by file: a Python reference's states (the sliding contact's, a flight's rotation), the
# trajectory rows, the generated rigid fields' columns, the assembly's frame and geometry channels and fields.
SIZED.update({
    "grain/sliding.py": {"y": None}, "grain/flight.py": {"y": None}, "grain/plots.py": {"tr": None},
    "grain/motion_scene.py": {"tr": None}, "export/grain.py": {"trajectory": None, "rows": None},
    "trolley/elastic/body.py": {"dA": None, "rigid": None}, "trolley/elastic/system.py": {
        **SIZED["trolley/elastic/system.py"], "f": None},
    "trolley/elastic/symbolic_assembly.py": dict.fromkeys(("channels", "values", "out", "z", "CHANNELS", "GEOMETRY")),
})
SIZE_NAMES = {"n", "N"}
LAYOUT_CALLS = {"offset", "slice"}  # a sized layout's offsets, from Python


def _layout_names(tree) -> set:
    """Names bound to what reads a sized layout: ``iq = at[Y_AT.q]``, ``iq, iqd = st.slice("q"), ...`` (element by
    element where both sides are tuples), ``ROTATIONS = slice(ROLLER_DOFS.offset(...), ...)``."""
    def reads(value) -> bool:
        return bool(_names(value) & OFFSETS.keys()) or any(
            isinstance(c, ast.Call) and isinstance(c.func, ast.Attribute) and c.func.attr in LAYOUT_CALLS
            for c in ast.walk(value))

    out = set()
    for node in ast.walk(tree):
        if not isinstance(node, ast.Assign):
            continue
        for target in node.targets:
            pairs = zip(target.elts, node.value.elts) if isinstance(target, ast.Tuple) and \
                isinstance(node.value, ast.Tuple) and len(target.elts) == len(node.value.elts) else [(target, node.value)]
            out |= {t.id for tg, value in pairs if reads(value) for t in ast.walk(tg) if isinstance(t, ast.Name)}
    return out


def _sized_by_hand(part, allowed: set) -> bool:
    """Whether an index into a sized vector holds a number or the size alone (``y[n:2 * n]``, ``rr[0]``, ``q[:5]``)
    and nothing that reads its layout."""
    numbers = any(isinstance(n, ast.Constant) and type(n.value) in (int, float) for n in ast.walk(part))
    calls = any(isinstance(c, ast.Call) and isinstance(c.func, ast.Attribute) and c.func.attr in LAYOUT_CALLS
                for c in ast.walk(part))
    return (numbers or bool(_names(part) & SIZE_NAMES)) and not (calls or _names(part) & allowed)


@pytest.mark.parametrize("path", sorted(SIZED))
def test_every_index_into_a_vector_sized_by_the_model_reads_its_layout(path):
    tree = ast.parse((ROOT / path).read_text(encoding="utf-8"))
    allowed = _layout_names(tree) | OFFSETS.keys() | {"N_ROLLER_DOFS"}
    seen = 0
    for node in ast.walk(tree):
        if isinstance(node, ast.Subscript) and isinstance(node.value, ast.Name) and node.value.id in SIZED[path]:
            index, axes = node.slice, SIZED[path][node.value.id]
            dims = index.elts if isinstance(index, ast.Tuple) else [index]
            parts = [b for axis, i in enumerate(dims) if axes is None or axis in axes
                     for b in ([i.lower, i.upper, i.step] if isinstance(i, ast.Slice) else [i])]
            for part in (p for p in parts if p is not None):
                assert not _sized_by_hand(part, allowed), f"{path}:{node.lineno} {ast.unparse(node)} numbers a slot by hand"
                seen += 1
    assert seen > 0


def _c_indices_by_hand(tree) -> list[str]:
    """The C expressions written with a number in their index (``f"s0[{9 + i}]"``): an f-string whose text before a
    value ends in ``[`` and whose value is a number or arithmetic with one, but for a 1-based label (``[{r + 1}]``)."""
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.JoinedStr):
            continue
        for before, value in zip(node.values, node.values[1:]):
            if not (isinstance(before, ast.Constant) and str(before.value).endswith("[")
                    and isinstance(value, ast.FormattedValue)):
                continue
            expr = value.value
            label = isinstance(expr, ast.BinOp) and isinstance(expr.op, ast.Add) and \
                isinstance(expr.right, ast.Constant) and expr.right.value == 1
            offset = isinstance(expr, ast.Constant) or isinstance(expr, ast.BinOp) and any(
                isinstance(n, ast.Constant) and type(n.value) is int for n in ast.walk(expr))
            if offset and not label:  # a number, or an offset added to an index (a size, max(n, 1), passes)
                found.append(ast.unparse(node))
    return found


@pytest.mark.parametrize("path", ["export/grain.py", "export/trolley.py", "export/model.py"])
def test_the_exports_c_expressions_index_through_declared_layouts(path):
    """The export writes C expressions of its buffers (``s0[i]``: a generated stage's outputs) from the stages'
    declared layouts, never an offset by hand."""
    tree = ast.parse((ROOT / path).read_text(encoding="utf-8"))
    assert _c_indices_by_hand(tree) == []
    assert _c_indices_by_hand(ast.parse('x = f"s0[{9 + i}]"; y = f"P{i}[{r + 1}]"')) == ["f's0[{9 + i}]'"]


# The vectors the export's hand-written C glue indexes whose slots a declaration numbers (the state, the
# parameters and discrete states, the impact map's stages and their arguments, the nominals): its names for them.
C_VECTORS = ("y", "p", "d", "after", "nominal", "contact", "contact_after", "plastic", "coulomb", "impulse")
C_SUBSCRIPT = re.compile(r"\b(" + "|".join(C_VECTORS) + r")\[([^\]]*)\]")


def _c_slots_by_hand(text: str) -> list[str]:
    """The subscripts of those vectors, declarations' sizes included, that hold a number but no macro (``y[2]``,
    ``contact[12]``; not ``contact[CONTACT_U + 2]``, ``y[i]``): the macros are the offsets and sizes the export
    writes before the glue from the layouts."""
    return [m.group(0) for m in C_SUBSCRIPT.finditer(text)
            if re.search(r"\b\d", m.group(2)) and not re.search(r"\b[A-Z][A-Z0-9_]*\b", m.group(2))]


def test_the_exports_c_glue_indexes_through_declared_offsets():
    """No literal slot or size of a declared vector in symmech/export/c/*.c (the macros are checked by the
    compiles of tests/test_export_grain.py)."""
    assert _c_slots_by_hand("double contact[12]; x = y[2] + p[N_P + 1] + y[i] + contact[CONTACT_U + 2];") == \
        ["contact[12]", "y[2]"]
    for path in sorted((ROOT / "export" / "c").glob("*.c")):
        assert _c_slots_by_hand(path.read_text(encoding="utf-8")) == [], path.name


def test_the_exported_impact_maps_stages_name_their_outputs_as_the_next_stages_arguments():
    """Each stage's declared outputs are its generated function's output size and the names of the derivation's
    arguments the later stages read (symmech.grain.derive_motion: K row by row and u, P_I and D, P)."""
    import inspect

    from symmech.export import grain as export_grain
    from symmech.generated import grain_motion as gm

    args = {name: list(inspect.signature(getattr(gm, name)).parameters) for name, _ in export_grain.IMPACT_MAP}
    y = [0.0] * 13
    outputs = {"impact_contact": gm.impact_contact(*y, 1.0, 2.0, 3.0, 0.3, 0.2, 0.1, 1.0),
               "plastic_impulse": gm.plastic_impulse(2, 0, 0, 0, 2, 0, 0, 0, 2, 0.1, 0.2, -1.0),
               "coulomb_impulse": gm.coulomb_impulse(0.5, 0.1, 0.2, 0.0, -1.0, 0.5, 0.0, 0.3)}
    for name, layout in export_grain.IMPACT_MAP[:-1]:
        names = export_grain.slot_names(layout)
        assert outputs[name].shape == (layout.size,), name
        assert set(names) <= {a for stage, _ in export_grain.IMPACT_MAP for a in args[stage]}, name
    assert export_grain.slot_names(export_grain.CONTACT) == args["plastic_impulse"]  # k0 ... k8, u0, u1, u2
    assert export_grain.slot_names(export_grain.PLASTIC) == args["coulomb_impulse"][:4]  # P_I, D0, D1, D2
    assert export_grain.slot_names(export_grain.COULOMB) == args["impact_state"][-3:]  # P0, P1, P2


def test_the_generated_rigid_fields_have_the_declared_columns():
    """trolley_elastic.rigid_fields returns φ0 of the five roller coordinates then ψ0 of the rotation pairs
    (the derivation's order, symmech.trolley.elastic.derive): the layout that splits them must agree."""
    from symmech.generated import trolley_elastic as gen

    out = gen.rigid_fields(np.array([0.5]), np.array([0.25]), np.array([-1.0]))
    parts = elastic_layout.RIGID_FIELDS.split(out)
    assert out.shape == (1, 3, elastic_layout.RIGID_FIELDS.size) == (1, 3, 11)
    assert parts["phi"].shape[-1] == elastic_layout.ROLLER_DOFS.size == 5
    assert parts["psi"].shape[-1] == len(elastic_layout.ROTATION_PAIRS) == 6
    # φ0 of u2 is the unit vector x2 (a translation), ψ0_44 of a point r = (x1, x2, x3) is -(0, x2, x3) (th1 twice)
    assert parts["phi"][0, :, 0].tolist() == [0.0, 1.0, 0.0]
    assert np.allclose(parts["psi"][0, :, 0], [0.0, -0.25, 1.0], rtol=0, atol=1e-15)
    with pytest.raises(ValueError, match="ElasticRigidFields.split: a last axis of 11 expected"):
        elastic_layout.RIGID_FIELDS.split(out[..., :10])


def test_an_exported_models_value_references_follow_the_declared_reals():
    """r[] of an export: time, 4 states, 2 derivatives, 3 outputs, 1 event indicator, 2 inputs, 5 parameters,
    3 discrete states; the first value reference of each block written down independently."""
    from symmech.export.model import ExportModel

    model = ExportModel("m", "", "", (), 4, 2, 2, 2, 0, 5, None, n_y=3, n_z=1, n_d=3)
    assert model.layout() == {"VR_TIME": 0, "VR_X": 1, "VR_DX": 5, "VR_Y": 7, "VR_Z": 10, "VR_U": 11, "VR_P": 13,
                              "VR_D": 18, "N_REAL": 21}


def test_the_elastic_builds_record_covers_its_declared_layouts():
    """The kernels freeze the layouts' offsets into numba's cache: the build's record must list the declaring file,
    so that a changed declaration counts the cache as stale (numba keys its cache on the kernels' file alone)."""
    from symmech.numerics import artifacts
    from symmech.trolley.elastic import kernels

    assert elastic_layout.__file__ in artifacts.sources(kernels)
