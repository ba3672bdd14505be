"""The ``trolley`` kind's scene schema: the track (midline and twist as expressions or tables), the rigid body,
the motion, the cases and their cross-checks, with the admissible ranges (docs/scenes-trolley.md is generated
from it)."""
from __future__ import annotations

import numpy as np

from symmech.core import expressions
from symmech.core import schema as sc
from symmech.core.scene import SceneError
from symmech.trolley import plots
from symmech.trolley.comfort import COMFORT
from symmech.trolley import sweep as design_sweep
from symmech.trolley.elastic import schema as elastic_schema

G_STANDARD = 9.80665
MAX_SPEED = 1e4  # m/s: admissible |V0| (and traction speeds checked up to it)
MAX_LENGTH = 1e7  # m: coordinates and arc lengths


def _expression(doc, type_doc, default=sc.REQUIRED):
    """An expression field (a number is a constant expression): syntax and size checked here,
    names and domain in the table's checks."""
    def parse(path, value):
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            value = repr(sc.check_real(path, value, "", -MAX_LENGTH, MAX_LENGTH, False, False))
        expressions.tree(path, value, None)
        return value
    return sc.Custom(doc, parse=parse, type_doc=type_doc, default=default)


def _constants_of(variables: tuple[str, ...]):
    """The parser of a table of names (not ``variables``) to numbers."""
    def parse(path, value):
        if not isinstance(value, dict):
            raise SceneError(path, f"expected a table of names to numbers, got {value!r}"[:200])
        return {expressions.check_name(f"{path}.{k}", k, variables): sc.check_real(f"{path}.{k}", v, "", -MAX_LENGTH,
                                                                                  MAX_LENGTH, False, False)
                for k, v in value.items()}
    return parse


def _track_expressions(tr, path):
    """Parse every expression of the track table with its variable and constants."""
    var = tr.get("parameter") or "s"
    constants = tr.get("constants") or {}
    for key in ("x", "y", "z"):
        if key in tr:
            expressions.parse(f"{path}.{key}", tr[key], (var,), constants)
    expressions.parse(f"{path}.twist", tr["twist"], ("s",), constants)
    if var == "u":
        if tr["u_range"] is None:
            raise SceneError(f"{path}.u_range", "required with parameter = \"u\"")
        if not tr["u_range"][0] < tr["u_range"][1]:
            raise SceneError(f"{path}.u_range", f"{tr['u_range']} must be increasing")
    if tr.get("points") is not None and np.abs(tr["points"]).max() > MAX_LENGTH:
        raise SceneError(f"{path}.points", f"coordinates beyond {MAX_LENGTH:g} m")


TRACK = sc.Table("the track: midline X0(s) and twist θ1(s)", {
    "type": sc.Choice("how the midline is given", choices=("helix", "expression", "table")),
    "twist": _expression("twist θ1(s) of the cross-section, differentiated symbolically (frame = \"twist\")",
                         "expression in `s`, rad", default="0"),
}, variants=("type", {
    "helix": {
        "radius": sc.Float("helix radius R (axis X3, horizontal)", unit="m", lo=0.01, hi=1e5),
        "rise": sc.Float("rise λ per radian: X03 = λ φ, φ = s/√(R²+λ²)", unit="m/rad", lo=0.0, hi=1e5),
    },
    "expression": {
        **{key: _expression(f"X0{i}, the {axis} coordinate of the midline", "expression in `s` or `u` "
                            "(see `parameter`) and the `constants`, m")
           for i, (key, axis) in enumerate((("x", "horizontal X1"), ("y", "upward X2"), ("z", "horizontal X3")), 1)},
        "parameter": sc.Choice("`s`: the expressions are in arc length (checked: ‖dX0/ds‖ = 1 within 1e-6); "
                               "`u`: any parameter, arc length computed", choices=("s", "u"), default="s"),
        "u_range": sc.Vector("parameter range [u0, u1] (s = 0 at u0), with parameter = \"u\"", n=2,
                             lo=-MAX_LENGTH, hi=MAX_LENGTH, default=None),
        "constants": sc.Custom("names usable in the expressions", parse=_constants_of(("s", "u")),
                               type_doc="table of names to numbers", default={}),
    },
    "table": {
        "points": sc.Rows("points [x, y, z] in order along the track; fitted by a quintic spline "
                          "re-parametrized by arc length", n=3, unit="m", min_rows=6),
        "max_turn_deg": sc.Float("largest turn between successive table segments", unit="deg", lo=0.0,
                                 lo_open=True, hi=90.0, default=20.0),
        "smoothing": sc.Float("fit tolerance: 0 interpolates the points; > 0 fits the smoothest quintic "
                              "spline within this RMS distance of them (for a noise σ per coordinate about "
                              "√3 σ or a little more)",
                              unit="m", lo=0.0, hi=1.0, default=0.0),
    },
}), checks=(_track_expressions,))


def _inertia(body, path):
    i11, i22, i33, i12, i23, i13 = body["inertia"]
    tensor = np.array([[i11, i12, i13], [i12, i22, i23], [i13, i23, i33]])
    if not tensor.any():
        return  # a point mass, as in the paper
    principal = np.linalg.eigvalsh(tensor)
    scale = np.abs(principal).max()
    if principal[0] <= 1e-12 * scale:
        raise SceneError(f"{path}.inertia", f"{body['inertia']} kg m^2 is not positive definite (principal "
                                            f"moments {', '.join(f'{p:.6g}' for p in principal)}); give all six "
                                            "zeros for a point mass")
    if principal[0] + principal[1] < principal[2] * (1 - 1e-12):
        raise SceneError(f"{path}.inertia", f"principal moments {', '.join(f'{p:.6g}' for p in principal)} "
                                            "kg m^2 violate the triangle inequality I1 + I2 >= I3 of a rigid body")


TROLLEY = sc.Table("the rigid body on the trolley", {
    "mass": sc.Float("mass of the body (trolley + load)", unit="kg", lo=1e-3, hi=1e7),
    "com": sc.Vector("centre of mass in the body frame (origin O on the midline at the rear axle)", n=3,
                     unit="m", lo=-100.0, hi=100.0),
    "inertia": sc.Vector("central inertia [I11, I22, I33, I12, I23, I13] (tensor entries); all zeros: a point "
                         "mass, as in the paper; otherwise positive definite with the triangle inequalities", n=6,
                         unit="kg m^2", lo=-1e9, hi=1e9, default=[0.0] * 6),
    "axle_distance": sc.Float("l = OA", unit="m", lo=0.01, hi=100.0),
    "half_gauge": sc.Float("a = OB = OC", unit="m", lo=0.01, hi=10.0),
}, checks=(_inertia,))


def _increasing(table, path):
    for axis, (lo, hi) in table.items():
        if not lo < hi:
            raise SceneError(f"{path}.{axis}", f"[{lo:g}, {hi:g}] g must be increasing")


def _fd_order(path, value):
    if value not in (2, 4) or isinstance(value, bool):
        raise SceneError(path, f"{value!r} is not 2 or 4")
    return value


def _cross_checks(scene, path):
    tr, motion, effects = scene["track"], scene["motion"], scene["effects"]
    if scene["frame"] == "frenet" and tr["twist"].strip() != "0":
        raise SceneError("track.twist", f"{tr['twist']!r}: the Frenet frame fixes the roll, so a twist cannot be "
                                        "honoured; use frame = \"twist\" or remove the twist")
    if effects["traction"]:
        if scene["conventions"] == "paper":
            raise SceneError("effects.traction", "traction integration is not available with conventions = "
                                                 "\"paper\"")
        if motion["traction"] is None:
            raise SceneError("motion.traction", "required with effects.traction = true")
        if motion["speed"] is not None:
            raise SceneError("motion.speed", "the speed follows from motion.traction with effects.traction = "
                                             "true; remove it")
    else:
        if motion["speed"] is None:
            raise SceneError("motion.speed", "required (or set effects.traction = true with motion.traction)")
        if motion["traction"] is not None:
            raise SceneError("motion.traction", "used only with effects.traction = true")
    axle, step = scene["trolley"]["axle_distance"], scene["numerics"]["fd_step"]
    if step is not None and step > 0.1 * axle:
        raise SceneError("numerics.fd_step", f"{step:g} m is outside (0, {0.1 * axle:g}] m (0.1 axle_distance)")


# The whole scene; the optional ``[elastic]`` table (docs/scenes-trolley-elastic.md) adds the
# elastic model beside the rigid one.
SCHEMA = sc.Table("a trolley scene", {
    "kind": sc.Choice("scene kind", choices=("trolley",)),
    "title": sc.Str("free text: the report's title", default=""),
    "conventions": sc.Choice("`physics`: the consistent model; `paper`: the paper's conventions (Tables 1, 2)",
                             choices=("physics", "paper"), default="physics"),
    "frame": sc.Choice("moving frame: `twist` (aircraft angles with the twist θ1(s)) or `frenet` (x2 = principal "
                       "normal; a rotation-minimising frame where the curvature vanishes)",
                       choices=("twist", "frenet"), default="twist"),
    "track": TRACK,
    "trolley": TROLLEY,
    "constants": sc.Table("physical constants", {
        "g0": sc.Float("gravitational acceleration (the paper uses 9.81)", unit="m/s^2", lo=0.0, lo_open=True,
                       hi=100.0, default=G_STANDARD)}, default={}),
    "motion": sc.Table("the drive", {
        "speed": _expression("V0(t), without traction; s(t) = s0 + ∫V0 dt (8-point Gauss per step)",
                             "expression in `t`, m/s", default=None),
        "traction": _expression("P0(t, v) along x1 at O, with effects.traction", "expression in `t`, `v`, N",
                                default=None),
        "initial_speed": sc.Float("V0(0) with traction", unit="m/s", lo=0.0, hi=MAX_SPEED, default=0.0),
        "s0": sc.Float("arc length at t = 0", unit="m", lo=0.0, hi=MAX_LENGTH, default=0.0),
        "constants": sc.Custom("names usable in `speed` and `traction` (e.g. for `symmech sweep` to vary)",
                               parse=_constants_of(("t", "v")), type_doc="table of names to numbers", default={}),
    }),
    "time": sc.Table("the time grid t = 0 … t_end", {
        "t_end": sc.Float("duration", unit="s", lo=0.0, lo_open=True, hi=1e6),
        "steps": sc.Int("grid intervals (the whole grid is one vectorized batch)", lo=1, hi=1_000_000),
    }),
    "effects": sc.Table("what the model includes", {
        "gravity": sc.Bool("gravity along -X2 (off: the generated reactions_no_gravity)", default=True),
        "local_curvature": sc.Bool("also case 2: the body frame turned onto the chord O→A", default=False),
        "traction": sc.Bool("integrate the speed from motion.traction (DOP853, rtol 1e-10), per case",
                            default=False),
    }, default={}),
    "numerics": sc.Table("numerical settings", {
        "fd_order": sc.Custom("order of the differences for Λ*', Λ*'' in case 2 (physics): central, one-sided at the "
                              "ends of the run",
                              parse=_fd_order, type_doc="2 or 4", default=4),
        "fd_step": sc.Float("their step (rounding ~eps/h², truncation ~h⁴); default min(0.02, 0.05 l); at most "
                            "0.1 l", unit="m", lo=1e-5, hi=10.0, default=None),
        "lstar_derivative": sc.Choice("dΛ*/ds in paper conventions (the paper's: backward difference)",
                                      choices=("backward", "central2", "central4"), default="backward"),
        "small_angle_limit": sc.Float("largest orthogonality defect of the first-order Λ̄ (13)-(14) before a "
                                      "warning", unit="1", lo=0.0, lo_open=True, hi=1.0, default=0.01),
        "min_curvature": sc.Float("frame = \"frenet\": below this curvature the principal normal is "
                                  "meaningless and a rotation-minimising frame is used", unit="1/m", lo=0.0,
                                  lo_open=True, hi=1.0, default=1e-4),
    }, default={}),
    "comfort": sc.Table("comfort envelope of the overloads (leaving it is a warning)", {
        axis: sc.Vector(f"[lo, hi] along {axis}", n=2, unit="g", lo=-100.0, hi=100.0, default=list(bounds))
        for axis, bounds in COMFORT.items()}, default={}, checks=(_increasing,)),
    "report": sc.Table("extra outputs", {
        "paper_tables": sc.Bool("list the printed Tables 1, 2 beside both computations (paper example grid)",
                                default=False)}, default={}),
    "elastic": elastic_schema.SCHEMA,
    "sweep": design_sweep.SWEEP,
    "output": sc.plot_output(plots.FIGURES, default=tuple(plots.FIGURES)),
}, checks=(_cross_checks,))
