"""Track midlines X0(s) and twist θ1(s): expressions, the paper's helix, point tables.

Every track answers ``derivatives(s, order)``: a list ``[X0, X0', X0'', ...]`` of
arrays of shape (n, 3) [m, 1, 1/m, 1/m², 1/m³] with respect to the arc length s
[m], and ``twist(s)``: θ1, dθ1/ds, d²θ1/ds² as arrays of shape (n,) [rad, rad/m,
rad/m²]. Expression tracks are differentiated symbolically (sympy is imported
when a scene is read, never at module import); tables are fitted by a quintic
spline re-parametrized by arc length.
"""
from __future__ import annotations

import math

import numpy as np

from symmech.core.scene import SceneError, Section, SymmechError

MAX_ORDER = 4
# Functions a scene expression may use; anything else is an error naming the field.
_FUNCTIONS = ("sin", "cos", "tan", "exp", "log", "sqrt", "sinh", "cosh", "tanh", "asinh", "acosh", "atan", "asin",
              "acos", "pi")


def parse_expression(field: str, text: str, variables: tuple[str, ...], constants: dict):
    """sympy expression of ``text`` in ``variables``; SceneError names ``field`` otherwise."""
    import sympy as sp
    from sympy.parsing.sympy_parser import parse_expr, standard_transformations

    names = {v: sp.Symbol(v, real=True) for v in variables}
    local = {f: getattr(sp, f) for f in _FUNCTIONS}
    local.update(names)
    local.update({k: sp.Float(v) for k, v in constants.items()})
    try:
        expr = parse_expr(text, local_dict=local, global_dict={"__builtins__": {}, "Integer": sp.Integer, "Float": sp.Float,
                                       "Rational": sp.Rational, "Symbol": sp.Symbol,
                                       "Function": sp.Function, **local},
                          transformations=standard_transformations)
        expr = sp.sympify(expr)
    except Exception as exc:  # sympy raises many types for bad input
        raise SceneError(field, f"cannot parse {text!r} as an expression in {', '.join(variables)} ({exc})") from None
    from sympy.core.function import AppliedUndef

    unknown = sorted(s.name for s in expr.free_symbols if s.name not in variables)
    unknown += sorted(str(f.func) for f in expr.atoms(AppliedUndef))
    if unknown:
        raise SceneError(field, f"unknown name(s) {', '.join(unknown)} in {text!r}; "
                                f"allowed: {', '.join(variables)}, constants and {', '.join(_FUNCTIONS)}")
    return expr, [names[v] for v in variables]


def lambdify_arrays(exprs, symbols):
    """Numeric function of ``symbols`` returning float arrays broadcast to the arguments' shape."""
    import sympy as sp

    f = sp.lambdify(symbols, exprs, modules="numpy")

    def call(*args):
        shape = np.broadcast_shapes(*(np.shape(a) for a in args))
        return [np.broadcast_to(np.asarray(v, dtype=float), shape) for v in f(*args)]
    return call


class Track:
    """Base: arc-length domain [0, length] (``length`` may be inf)."""

    length = math.inf

    def derivatives(self, s, order: int) -> list[np.ndarray]:
        raise NotImplementedError

    def twist(self, s) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        s = np.asarray(s, dtype=float)
        return tuple(np.broadcast_to(np.asarray(v, dtype=float), s.shape) for v in self._twist(s))

    def _twist(self, s):
        return 0.0, 0.0, 0.0


class ExpressionTrack(Track):
    """X0 given by three expressions in ``s`` (arc length) or in ``u`` (any parameter)."""

    exprs = None
    var = None

    def __init__(self, exprs, var, twist_expr, twist_var, field: str, u_range=None):
        import sympy as sp

        self.field = field
        exprs = [sp.sympify(e) for e in exprs]
        if var.name == "u":
            self._init_u(exprs, var, u_range)
        else:
            self.length = math.inf
            self.exprs, self.var = exprs, var  # kept for exact (symbolic) references
            ders = [exprs]
            for _ in range(MAX_ORDER):
                ders.append([sp.diff(e, var) for e in ders[-1]])
            self._f = lambdify_arrays([e for d in ders for e in d], [var])
            self._check_unit_speed()
        tw = sp.sympify(twist_expr)
        self._tw = lambdify_arrays([tw, sp.diff(tw, twist_var), sp.diff(tw, twist_var, 2)], [twist_var])

    def _init_u(self, exprs, u, u_range):
        import sympy as sp

        speed = sp.sqrt(sum(sp.diff(e, u) ** 2 for e in exprs))
        ders = [exprs]
        for _ in range(MAX_ORDER):
            ders.append([sp.diff(e, u) / speed for e in ders[-1]])
        fu = lambdify_arrays([e for d in ders for e in d], [u])
        speed_f = lambdify_arrays([speed], [u])
        arc = ArcLength(lambda x: speed_f(x)[0], *u_range, self.field)
        self.length = arc.length
        self._f = lambda s: fu(arc.parameter(np.asarray(s, dtype=float)))

    def _check_unit_speed(self):
        s = np.linspace(0.0, 50.0, 101)
        t = np.stack(self._f(s)[3:6], axis=-1)
        err = float(np.abs(np.linalg.norm(t, axis=-1) - 1.0).max())
        if err > 1e-6:
            raise SceneError(self.field, f"|dX0/ds| deviates from 1 by {err:.3g}: the expressions are not "
                                         "parametrized by arc length; use parameter = \"u\"")

    def derivatives(self, s, order):
        s = np.asarray(s, dtype=float)
        vals = self._f(s)
        return [np.stack(vals[3 * k:3 * k + 3], axis=-1) for k in range(order + 1)]

    def _twist(self, s):
        return self._tw(s)


class ArcLength:
    """s(u) = ∫ |dX0/du| du on [u0, u1] and its inverse u(s).

    Gauss-Legendre per grid interval gives s at the nodes; a cubic Hermite spline
    with the exact slope |dX0/du| interpolates between them (error ~h⁴), and u(s)
    is found by Newton steps on that spline.
    """

    def __init__(self, speed, u0: float, u1: float, field: str, intervals: int = 4000):
        from scipy.interpolate import CubicHermiteSpline

        grid = np.linspace(u0, u1, intervals + 1)
        sigma = speed(grid)
        if not np.all(sigma > 1e-12):
            raise SceneError(field, "dX0/du vanishes: the parametrization is singular there")
        nodes, weights = np.polynomial.legendre.leggauss(8)
        mid, half = (grid[1:] + grid[:-1]) / 2, (grid[1:] - grid[:-1]) / 2
        seg = (speed(mid[:, None] + half[:, None] * nodes) * weights).sum(axis=1) * half
        s_grid = np.concatenate([[0.0], np.cumsum(seg)])
        self.length = float(s_grid[-1])
        self._s = CubicHermiteSpline(grid, s_grid, sigma)
        self._grid, self._s_grid, self._speed = grid, s_grid, speed

    def parameter(self, s: np.ndarray) -> np.ndarray:
        u = np.interp(s, self._s_grid, self._grid)
        for _ in range(3):
            u = u + (s - self._s(u)) / self._speed(u)
        return u


class TableTrack(Track):
    """A smooth track through a table of points (n, 3) [m], in order along the track."""

    def __init__(self, points, field: str, max_turn_deg: float):
        from scipy.interpolate import make_interp_spline

        p = np.asarray(points, dtype=float)
        seg = np.linalg.norm(np.diff(p, axis=0), axis=1)
        if np.any(seg <= 0):
            i = int(np.argmin(seg))
            raise SceneError(field, f"points {i} and {i + 1} coincide; a track table needs distinct points")
        d = np.diff(p, axis=0) / seg[:, None]
        turn = np.degrees(np.arccos(np.clip((d[1:] * d[:-1]).sum(axis=1), -1.0, 1.0)))
        if turn.size and turn.max() > max_turn_deg:
            i = int(np.argmax(turn)) + 1
            raise SceneError(field, f"track is not smooth: it turns by {turn.max():.1f} deg at point {i} "
                                    f"(max_turn_deg = {max_turn_deg:g}); add points or smooth the table")
        u = np.concatenate([[0.0], np.cumsum(seg)])
        chord_spline = make_interp_spline(u, p, k=5)
        dspline = chord_spline.derivative()
        arc = ArcLength(lambda x: np.linalg.norm(dspline(x), axis=-1), u[0], u[-1], field)
        self.length = arc.length
        n = 10 * len(p)
        s = np.linspace(0.0, self.length, n)
        dense = chord_spline(arc.parameter(s))
        _check_self_intersection(dense, s, field)
        spline = make_interp_spline(s, dense, k=5)
        self._ders = [spline] + [spline.derivative(k) for k in range(1, MAX_ORDER + 1)]

    def derivatives(self, s, order):
        s = np.asarray(s, dtype=float)
        # A little extrapolation serves the difference stencils at the ends of the table.
        margin = 1e-3 * self.length
        if np.any(s < -margin) or np.any(s > self.length + margin):
            raise SymmechError(f"the motion leaves the track table: s from {s.min():.6g} to {s.max():.6g} m, "
                               f"track length {self.length:.6g} m")
        return [d(s) for d in self._ders[:order + 1]]


def _check_self_intersection(points: np.ndarray, s: np.ndarray, field: str) -> None:
    """Reject tracks that come back within a small distance of themselves."""
    from scipy.spatial import cKDTree

    spacing = float(np.diff(s).max())
    pairs = cKDTree(points).query_pairs(0.5 * spacing, output_type="ndarray")
    if len(pairs):
        far = np.abs(s[pairs[:, 0]] - s[pairs[:, 1]]) > 4 * spacing
        if np.any(far):
            i, j = pairs[far][0]
            raise SceneError(field, f"track intersects itself near s = {s[i]:.4g} m and s = {s[j]:.4g} m")


def helix_expressions(radius: float, rise: float) -> list[str]:
    """The paper's helix X01 = R cos φ, X02 = R sin φ, X03 = λ φ, φ = s / sqrt(R² + λ²)."""
    root = math.sqrt(radius**2 + rise**2)
    return [f"{radius!r}*cos(s/{root!r})", f"{radius!r}*sin(s/{root!r})", f"{rise!r}*s/{root!r}"]


def build(sec: Section) -> Track:
    """Track from the scene table ``[track]`` (see docs/scenes-trolley.md)."""
    kind = sec.choice("type", ("helix", "expression", "table"))
    twist_text = sec.str("twist", default="0")
    if kind == "table":
        if twist_text != "0":
            raise SceneError(sec.name("twist"), "a twist is not supported for track tables")
        points = sec.rows("points", 3, unit="m", min_rows=6)
        turn = sec.float("max_turn_deg", unit="deg", default=20.0, lo=0.0, hi=90.0, lo_open=True)
        track = TableTrack(points, sec.name("points"), turn)
        sec.finish()
        return track
    constants = {}
    if kind == "helix":
        radius = sec.float("radius", unit="m", lo=0.0, lo_open=True)
        rise = sec.float("rise", unit="m/rad", lo=0.0)
        texts, var = helix_expressions(radius, rise), "s"
    else:
        if sec.has("constants"):
            c = sec.section("constants")
            constants = {k: c.float(k, unit="(scene constant)") for k in c.keys()}
            c.finish()
        var = sec.choice("parameter", ("s", "u"), default="s")
        texts = [sec.str(k) for k in ("x", "y", "z")]
    parsed = [parse_expression(sec.name(k), t, (var,), constants) for k, t in zip("xyz", texts)]
    exprs, sym = [e for e, _ in parsed], parsed[0][1][0]
    twist, (s_sym,) = parse_expression(sec.name("twist"), twist_text, ("s",), constants)
    u_range = None
    if var == "u":
        u_range = sec.vector("u_range", 2, unit="(parameter)")
        if not u_range[1] > u_range[0]:
            raise SceneError(sec.name("u_range"), f"{u_range} must be increasing")
    track = ExpressionTrack(exprs, sym, twist, s_sym, sec.name("x"), u_range)
    sec.finish()
    return track
