"""The whole ``kind = "mechanism"`` scene, declared once (validation, defaults, docs).

:data:`SCHEMA` types and range-checks every field; expression fields are parsed
against the whitelist of :func:`symmech.smm.model.check_expression` (size, power
and arity bounded) but evaluated only in :func:`symmech.smm.build.mechanism`,
once the parameters are known. Ranges of evaluated quantities (masses, moments,
stiffnesses) are the ``*_RANGE`` constants, stated in the field docs.
"""
from __future__ import annotations

from symmech.core.scene import SceneError
from symmech.core.schema import (Bool, Choice, Custom, Float, Int, Mapping, Str, Table, TableList, Vector,
                                 check_real, plot_output)
from symmech.core import expressions
from symmech.smm.model import EQUILIBRIUM, GENERATED_NAMES, number_text
from symmech.smm.plots import FIGURES

NAME = r"[A-Za-z][A-Za-z0-9_]{0,63}"
MASS_RANGE = (1e-12, 1e12)       # kg, or exactly 0 (a link with inertia only)
INERTIA_RANGE = (1e-18, 1e15)    # kg m^2, or exactly 0
COEF_MAX = 1e30                  # stiffness [N/m, N m/rad] and viscosity [N s/m, N m s/rad]
FORCE_MAX = 1e15                 # preloads [N, N m]
LENGTH_MAX = 1e6                 # m, every evaluated geometry component
MAX_ELEMENTS = 10_000            # points, bodies, springs ... of an explicit model


def _expression(path, value) -> str:
    """A number or an expression string of the parameters, as expression text."""
    if isinstance(value, str):
        expressions.tree(path, value, None)  # names are checked once the parameters are known
        return value
    return number_text(check_real(path, value, "", None, None, False, False))


def _vector(path, value) -> tuple[str, str, str]:
    """2 or 3 components (numbers or expressions); a missing z is 0."""
    if not isinstance(value, list) or len(value) not in (2, 3):
        raise SceneError(path, f"expected a list of 2 or 3 components (numbers or expressions), got {value!r}"[:200])
    comps = [_expression(f"{path}[{i}]", v) for i, v in enumerate(value)]
    return tuple(comps + ["0"] * (3 - len(comps)))


def _names(path, value) -> tuple[str, ...]:
    if not isinstance(value, list) or len(value) > 1000 or not all(isinstance(v, str) for v in value):
        raise SceneError(path, f"expected a list of names, got {value!r}"[:200])
    return tuple(value)


def _pair(path, value) -> tuple[str, str]:
    names = _names(path, value)
    if len(names) != 2:
        raise SceneError(path, f"expected two names, got {list(names)!r}"[:200])
    return names


def _numbers(path, value) -> list[float]:
    """A list of finite numbers (its length, the number of coordinates, is checked in prepare)."""
    if not isinstance(value, list) or len(value) > 10**6:
        raise SceneError(path, f"expected a list of numbers, got {value!r}"[:200])
    return [check_real(f"{path}[{i}]", v, "", -1e12, 1e12, False, False) for i, v in enumerate(value)]


def _preload(path, value):
    return value if value == EQUILIBRIUM else _expression(path, value)


def _parameter(path, value) -> dict:
    """``name = number`` or ``name = {value, unit, meaning}``."""
    if not isinstance(value, dict):
        value = {"value": value}
    return PARAMETER.check(path, value)


def _principal_axes(path, value):
    if not isinstance(value, list) or len(value) != 3:
        raise SceneError(path, f"expected three axes of 3 components, got {value!r}"[:200])
    axes = tuple(_vector(f"{path}[{i}]", v) for i, v in enumerate(value))
    for i, (_v, raw) in enumerate(zip(axes, value)):
        if len(raw) != 3:
            raise SceneError(f"{path}[{i}]", f"expected 3 components, got {raw!r}"[:200])
    return axes


def _check_parameters(params: dict, path: str) -> None:
    for name in params:
        field = f"{path}.{name}"
        expressions.check_name(field, name)
        if name in GENERATED_NAMES:
            raise SceneError(field, f"the name {name!r} is reserved (used by the generated modules)")


EXPR = "number or expression of the parameters"
VEC = "2 or 3 components (numbers or expressions)"


def expr(doc, **kw) -> Custom:
    return Custom(doc, parse=_expression, type_doc=EXPR, **kw)


def vec(doc, **kw) -> Custom:
    return Custom(doc, parse=_vector, type_doc=VEC, **kw)


def names(doc, **kw) -> Custom:
    return Custom(doc, parse=_names, type_doc="list of names", **kw)


def pair(doc) -> Custom:
    return Custom(doc, parse=_pair, type_doc="list of 2 names")


PARAMETER = Table("a named parameter", {
    "value": Float("value in SI units"),
    "unit": Str("SI unit (documentation; `1` if dimensionless)", default="1"),
    "meaning": Str("what it is (argument doc of the generated functions)", default=None),
})


def _one_end(point: dict, path: str) -> None:
    if (point["at"] is None) == (point["from"] is None):
        raise SceneError(f"{path}.at" if point["at"] is not None else f"{path}.from",
                         "give either `at` (a root) or `from` with `vector` (a chain vector)")
    if point["from"] is not None and point["vector"] is None:
        raise SceneError(f"{path}.vector", "missing (required with `from`)")
    if point["at"] is not None and (point["vector"] is not None or point["turns"] or point["slides"]):
        raise SceneError(f"{path}.at", "a root point takes no vector, turns or slides")


def _preload_or_free(spring: dict, path: str) -> None:
    if spring["preload"] is not None and spring["free_length"] is not None:
        raise SceneError(f"{path}.free_length", "give either preload or free_length, not both")


def _one_force(forcing: dict, path: str) -> None:
    if (forcing["Q"] is None) == (forcing["point"] is None):
        raise SceneError(f"{path}.point", "give either `Q` (generalized forces) or `point` with `force`")
    if forcing["point"] is not None and forcing["force"] is None:
        raise SceneError(f"{path}.force", "missing (required with `point`)")
    low, high = forcing["omega"]
    if high <= low:
        raise SceneError(f"{path}.omega", f"expected [low, high] with low < high, got [{low:g}, {high:g}]")


def _force(path, value) -> list[float]:
    if not isinstance(value, list) or len(value) not in (2, 3):
        raise SceneError(path, f"expected 2 or 3 force components [N], got {value!r}"[:200])
    comps = [check_real(f"{path}[{i}]", v, "N", -FORCE_MAX, FORCE_MAX, False, False) for i, v in enumerate(value)]
    return comps + [0.0] * (3 - len(comps))


def _chain_or_model(scene: dict, path: str) -> None:
    model = ("coordinates", "points", "bodies", "springs", "dampers", "torsion_springs", "torsion_dampers")
    if scene["chain"] is not None:
        given = [k for k in model if scene[k]]
        if given:
            raise SceneError(given[0], "a `[chain]` scene generates its model: remove this table")
    elif not scene["coordinates"]:
        raise SceneError("coordinates", "a mechanism needs at least one generalized coordinate "
                                        "(or a `[chain]` table)")


def _items(doc, fields, **kw) -> TableList:
    return TableList(doc, item=Table(doc, fields, **kw), default=[], max_items=MAX_ELEMENTS)


COORDINATE = {
    "name": Str("unique name", pattern=NAME),
    "type": Choice("`angle` [rad] or `slide` [m]", choices=("angle", "slide")),
}
SCHEMA = Table("a mechanism scene (structural model method, seed 003)", {
    "kind": Choice("scene kind", choices=("mechanism",)),
    "name": Str("mechanism name; the generated module is `smm_<name>` (default `mechanism`, for a chain "
                 "`chain_<n>_<ends>_<motion>`)", pattern=r"[A-Za-z0-9_.-]{1,64}", default=None),
    "title": Str("free text: the report's title", default=""),
    "description": Str("free text", default=""),
    "parameters": Mapping("named parameters: `name = number` or `name = {value, unit, meaning}`; they become "
                          "the arguments (in file order) of the generated functions; not `x<digits>` nor a "
                          "reserved name", value=Custom("parameter", parse=_parameter,
                                                        type_doc="number or {value, unit, meaning}"),
                          key_pattern=NAME, default={}),
    "coordinates": _items("generalized coordinates, measured from equilibrium", COORDINATE, variants=("type", {
        "angle": {"axis": vec("rotation axis in equilibrium (unit length)", default=("0", "0", "1"))},
        "slide": {"axis": vec("slide direction in equilibrium (unit length)")},
    })),
    "points": _items("characteristic points: roots (`at`) and chain vectors (`from`, `vector`)", {
        "name": Str("unique name", pattern=NAME),
        "at": vec("position of a fixed root [m]", default=None),
        "from": Str("parent point of a chain vector", default=None),
        "vector": vec("chain vector from the parent in equilibrium [m]", default=None),
        "turns": names("angle coordinates turning this vector, outermost first", default=()),
        "slides": names("slide coordinates lengthening this vector", default=()),
    }, checks=(_one_end,)),
    "bodies": _items("rigid bodies", {
        "name": Str("unique name", pattern=NAME),
        "mass": expr(f"mass [kg]: 0 or in [{MASS_RANGE[0]:g}, {MASS_RANGE[1]:g}]"),
        "inertia": Custom(f"principal central moments [kg m^2] (one number: about z), each 0 (not "
                          f"modelled) or in [{INERTIA_RANGE[0]:g}, {INERTIA_RANGE[1]:g}]; three non-zero moments "
                          "must satisfy the triangle inequalities",
                          parse=lambda p, v: _vector(p, v) if isinstance(v, list) else ("0", "0", _expression(p, v)),
                          type_doc=f"{EXPR}, or 3 of them", default=("0", "0", "0")),
        "principal_axes": Custom("principal central axes in equilibrium (orthonormal, global components)",
                                 parse=_principal_axes, type_doc="3 lists of 3 components", default=None),
        "com": Str("centre-of-mass point"),
        "turns": names("angle coordinates rotating the body (default: those of `com`)", default=None),
    }),
    "springs": _items("springs between points", {
        "name": Str("unique name (among all springs and dampers)", pattern=NAME),
        "ends": pair("the two end points"),
        "stiffness": expr(f"stiffness [N/m] in [0, {COEF_MAX:g}]"),
        "preload": Custom(f"tension in equilibrium [N] (|T| <= {FORCE_MAX:g}), or `\"equilibrium\"` (from eq. (5))",
                          parse=_preload, type_doc=f"{EXPR} or \"equilibrium\"", default=None),
        "free_length": expr("free length [m] (instead of preload)", default=None),
    }, checks=(_preload_or_free,)),
    "dampers": _items("dampers between points", {
        "name": Str("unique name", pattern=NAME),
        "ends": pair("the two end points"),
        "viscosity": expr(f"viscosity [N s/m] in [0, {COEF_MAX:g}]"),
    }),
    "torsion_springs": _items("torsion springs on the relative rotation of two bodies", {
        "name": Str("unique name", pattern=NAME),
        "bodies": pair("bodies A, B (`ground` for the frame), A != B"),
        "stiffness": expr(f"stiffness [N m/rad] in [0, {COEF_MAX:g}]"),
        "axis": vec("twist axis (unit length)", default=("0", "0", "1")),
        "preload": Custom(f"moment in equilibrium [N m] (|M| <= {FORCE_MAX:g}), or `\"equilibrium\"`",
                          parse=_preload, type_doc=f"{EXPR} or \"equilibrium\"", default=None),
    }),
    "torsion_dampers": _items("torsion dampers on the relative rotation of two bodies", {
        "name": Str("unique name", pattern=NAME),
        "bodies": pair("bodies A, B (`ground` for the frame), A != B"),
        "viscosity": expr(f"viscosity [N m s/rad] in [0, {COEF_MAX:g}]"),
        "axis": vec("twist axis (unit length)", default=("0", "0", "1")),
    }),
    "gravity": Table("gravity", {
        "g": expr("gravitational acceleration [m/s^2] in [0, 1e4]", default="0"),
        "direction": vec("direction of gravity (unit length)", default=("0", "-1", "0")),
    }, default={}),
    "effects": Table("which terms enter the matrices", {
        "damping": Bool("damping matrix b (10)", default=True),
        "preload": Bool("spring preload terms of c (7)", default=True),
        "gravity": Bool("gravity terms of c (7)", default=True),
    }, default={}),
    "equilibrium": Table("equilibrium configuration", {
        "solve": Bool("find the equilibrium (6) by Newton's method from the drawn configuration", default=False),
    }, default={}),
    "initial": Table("free response from an initial state", {
        "q": Custom("initial coordinates [m or rad], one per coordinate (default 0)", parse=_numbers,
                    type_doc="list of numbers in [-1e12, 1e12]", default=None),
        "qdot": Custom("initial rates [m/s or rad/s], one per coordinate (default 0)", parse=_numbers,
                       type_doc="list of numbers in [-1e12, 1e12]", default=None),
        "duration": Float("duration", unit="s", lo=0.0, lo_open=True, hi=1e6),
        "steps": Int("time steps (exact state-transition steps)", lo=2, hi=10**6, default=1000),
    }, default=None),
    "forcing": Table("harmonic forcing: frequency response", {
        "Q": Custom("generalized force amplitudes [N or N m], one per coordinate", parse=_numbers,
                    type_doc="list of numbers in [-1e12, 1e12]", default=None),
        "point": Str("point where `force` acts", default=None),
        "force": Custom("force amplitude [N], 2 or 3 components", parse=_force, type_doc="list of 2 or 3 numbers",
                        default=None),
        "omega": Vector("[low, high] angular frequency range", n=2, unit="rad/s", lo=0.0, hi=1e9),
        "samples": Int("frequencies sampled", lo=2, hi=10**5, default=400),
    }, checks=(_one_force,), default=None),
    "chain": Table("generated uniform chain of point masses (instead of points, bodies, springs)", {
        "n": Int("number of masses", lo=1, hi=10**6),
        "ends": Choice("boundary conditions", choices=("fixed-fixed", "fixed-free", "free-free"),
                       default="fixed-fixed"),
        "motion": Choice("`axial` (along x) or `transverse` (a pretensioned string)",
                         choices=("axial", "transverse"), default="axial"),
        "mass": Float("mass of each particle", unit="kg", lo=MASS_RANGE[0], hi=MASS_RANGE[1]),
        "stiffness": Float("stiffness of each spring", unit="N/m", lo=0.0, hi=COEF_MAX),
        "spacing": Float("spring length in equilibrium", unit="m", lo=1e-9, hi=LENGTH_MAX),
        "tension": Float("spring tension in equilibrium", unit="N", lo=-FORCE_MAX, hi=FORCE_MAX, default=0.0),
        "name": Str("mechanism name (default: from n, ends, motion)", default=None),
    }, default=None),
    "precision": Table("`symmech bench precision`: lowest modes, dense eigh vs sparse eigsh", {
        "modes": Int("modes compared (default min(10, coordinates - 1))", lo=1, hi=200, default=None),
        "dense_limit": Int("largest size also solved by the dense eigh", lo=2, hi=20_000, default=3000),
    }, default={}),
    "output": plot_output(FIGURES, default=tuple(FIGURES)),
}, checks=(_chain_or_model, lambda s, _p: _check_parameters(s["parameters"], "parameters")))
