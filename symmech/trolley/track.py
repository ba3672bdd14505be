"""Track midlines X0(s) and twist θ1(s): expressions, the paper's helix, point tables.

Every track answers ``derivatives(s, order)``: a list ``[X0, X0', X0'', ...]`` of
arrays of shape (n, 3) [m, 1, 1/m, 1/m², 1/m³] with respect to the arc length s
[m], and ``twist(s)``: θ1, dθ1/ds, d²θ1/ds² as arrays of shape (n,) [rad, rad/m,
rad/m²]. Expression tracks are differentiated symbolically (sympy is imported
when a scene is read, never at module import); tables are fitted by a quintic
spline (interpolating, or smoothing within a stated tolerance) re-parametrized by
arc length, and their measurement noise and its effect on the curvature are
estimated from the data.
"""
from __future__ import annotations

import math

import numpy as np

from symmech.core import expressions
from symmech.core.scene import SceneError, SymmechError

MAX_ORDER = 4


def lambdify_arrays(exprs, symbols):
    """Numeric function of ``symbols`` returning float arrays broadcast to the arguments' shape. The expressions
    share one common-subexpression elimination: derivatives of a track repeat their lower orders, and printed
    whole they cost seconds to compile and ~40 times the evaluation time (the exact Λ*' and Λ*'' of a catenary)."""
    import sympy as sp

    f = sp.lambdify(symbols, exprs, modules="numpy", cse=True)

    def call(*args):
        shape = np.broadcast_shapes(*(np.shape(a) for a in args))
        return [np.broadcast_to(np.asarray(v, dtype=float), shape) for v in f(*args)]
    return call


class Track:
    """Base: arc-length domain [0, length] (``length`` may be inf) and the twist θ1(s)."""

    length = math.inf
    twist_expr = None

    def derivatives(self, s, order: int) -> list[np.ndarray]:
        raise NotImplementedError

    def set_twist(self, expr) -> None:
        """θ1(s) from a sympy expression in ``s`` (differentiated symbolically)."""
        self.twist_expr = expr
        self._tw = lambdify_arrays(expressions.derivatives("track.twist", expr, "s", 2), [expressions.symbol("s")])

    def twist(self, s) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        s = np.asarray(s, dtype=float)
        if self.twist_expr is None:
            return tuple(np.zeros(s.shape) for _ in range(3))
        return tuple(self._tw(s))

    def check_domain(self, field: str, lo: float, hi: float) -> None:
        """SceneError naming ``field`` (the track table) if [lo, hi] [m] leaves the track or an
        expression of it is singular there."""
        if self.twist_expr is not None:
            _check_with_derivatives(f"{field}.twist", self.twist_expr, "s", lo, hi, 2, "m")


def _check_with_derivatives(field, expr, var, lo, hi, order, unit):
    """The expression over [lo, hi] with its singularity guards, and its derivatives up to
    ``order`` by dense samples (a derivative can be infinite where the expression is finite)."""
    expressions.check_domain(field, expr, var, lo, hi, unit=unit)
    for d in expressions.derivatives(field, expr, var, order)[1:]:
        expressions.check_domain(field, d, var, lo, hi, unit=unit, guards=False)


class ExpressionTrack(Track):
    """X0 given by three sympy expressions in ``s`` (arc length) or in ``u`` (any parameter)."""

    exprs = None
    var = None

    def __init__(self, exprs, var: str, field: str, u_range=None):
        self.field = field
        sym = expressions.symbol(var)
        if var == "u":
            for name, e in zip("xyz", exprs):
                _check_with_derivatives(f"{field}.{name}", e, "u", *u_range, 1, "")
            self._init_u(exprs, sym, u_range)
        else:
            self.exprs, self.var = exprs, sym  # kept for exact (symbolic) references
            ders = [expressions.derivatives(f"{field}.{name}", e, "s", MAX_ORDER) for name, e in zip("xyz", exprs)]
            self._f = lambdify_arrays([ders[i][k] for k in range(MAX_ORDER + 1) for i in range(3)], [sym])

    def _init_u(self, exprs, u, u_range):
        import sympy as sp

        speed = sp.sqrt(sum(sp.diff(e, u) ** 2 for e in exprs))
        ders = [expressions.derivatives(f"{self.field}.{name}", e, "u", MAX_ORDER, speed)
                for name, e in zip("xyz", exprs)]
        fu = lambdify_arrays([ders[i][k] for k in range(MAX_ORDER + 1) for i in range(3)], [u])
        speed_f = lambdify_arrays([speed], [u])
        arc = ArcLength(lambda x: speed_f(x)[0], *u_range, f"{self.field}.u_range")
        self.length = arc.length
        self._f = lambda s: fu(arc.parameter(np.asarray(s, dtype=float)))

    def check_domain(self, field, lo, hi):
        super().check_domain(field, lo, hi)
        if self.var is None:  # parameter u: checked over u_range when built
            return _check_inside(self.length, lo, hi)
        for name, e in zip("xyz", self.exprs):
            _check_with_derivatives(f"{field}.{name}", e, "s", lo, hi, MAX_ORDER, "m")
        s = np.linspace(lo, hi, 2001)
        t = self.derivatives(s, 1)[1]  # dX0/ds
        dev = np.abs(np.linalg.norm(t, axis=-1) - 1.0)
        if dev.max() > 1e-6:
            raise SceneError(f"{field}.x", f"|dX0/ds| deviates from 1 by {dev.max():.3g} at s = "
                                           f"{s[np.argmax(dev)]:.6g} m: the expressions are not parametrized "
                                           "by arc length; use parameter = \"u\"")

    def derivatives(self, s, order):
        s = np.asarray(s, dtype=float)
        vals = self._f(s)
        return [np.stack(vals[3 * k:3 * k + 3], axis=-1) for k in range(order + 1)]


def _check_inside(length, lo, hi, what="track"):
    # The room of rounding only: difference stencils stay inside the run's range (one-sided at its ends).
    margin = 1e-9 * length
    if lo < -margin or hi > length + margin:
        raise SceneError("motion.speed", f"the motion leaves the {what}: s from {lo:.6g} to {hi:.6g} m "
                                         f"(with the front axle in case 2), track length {length:.6g} m")


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
            at = grid[np.argmax(~(sigma > 1e-12))]
            raise SceneError(field, f"dX0/du vanishes at u = {at:.6g}: the parametrization is singular there")
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


# Bootstrap replicates for the curvature error of a fitted table.
NOISE_REPLICATES = 8


class TableTrack(Track):
    """A smooth track through a table of points (n, 3) [m], in order along the track.

    ``smoothing`` [m] = 0 interpolates the points; > 0 fits a smoothing quintic spline
    whose RMS distance from the points is ``smoothing`` (the stated tolerance). ``noise``
    holds the estimates from the data (see :func:`_noise_estimate`).
    """

    def __init__(self, points, field: str, max_turn_deg: float, smoothing: float = 0.0):
        p = np.asarray(points, dtype=float)
        u = _chord_parameter(p, field, max_turn_deg)
        chord_spline = _fit(u, p, smoothing, field)
        self.noise = _noise_estimate(u, p, smoothing, chord_spline)
        dspline = chord_spline.derivative()
        arc = ArcLength(lambda x: np.linalg.norm(dspline(x), axis=-1), u[0], u[-1], field)
        self.length = arc.length
        n = 10 * len(p)
        s = np.linspace(0.0, self.length, n)
        dense = chord_spline(arc.parameter(s))
        _check_self_intersection(dense, s, field)
        from scipy.interpolate import make_interp_spline

        spline = make_interp_spline(s, dense, k=5)
        self._ders = [spline] + [spline.derivative(k) for k in range(1, MAX_ORDER + 1)]

    def check_domain(self, field, lo, hi):
        super().check_domain(field, lo, hi)
        _check_inside(self.length, lo, hi, "track table")

    def derivatives(self, s, order):
        s = np.asarray(s, dtype=float)
        margin = 1e-3 * self.length
        if np.any(s < -margin) or np.any(s > self.length + margin):
            raise SymmechError(f"the motion leaves the track table: s from {s.min():.6g} to {s.max():.6g} m, "
                               f"track length {self.length:.6g} m")
        return [d(s) for d in self._ders[:order + 1]]


def _chord_parameter(p, field, max_turn_deg):
    """Cumulative chord length u (n,) [m] of the polyline; refuses coinciding points and kinks."""
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
    return np.concatenate([[0.0], np.cumsum(seg)])


def _fit(u, p, smoothing, field):
    """Quintic spline X(u) (a scipy BSpline of values (3,)): through the points, or the
    smoothest one within RMS distance ``smoothing`` [m] of them."""
    from scipy.interpolate import BSpline, make_interp_spline, splprep

    if smoothing == 0:
        return make_interp_spline(u, p, k=5)
    (knots, coef, k), _ = splprep(p.T, u=u, k=5, s=len(p) * smoothing**2, quiet=2)
    spline = BSpline(knots, np.array(coef).T, k)
    if not np.all(np.isfinite(spline(u))):
        raise SceneError(field.replace("points", "smoothing"), f"no smoothing fit within {smoothing:g} m")
    return spline


def _curvature(spline, u):
    d1, d2 = spline.derivative(1)(u), spline.derivative(2)(u)
    return np.linalg.norm(np.cross(d1, d2), axis=-1) / np.linalg.norm(d1, axis=-1) ** 3


def _noise_estimate(u, p, smoothing, spline) -> dict:
    """What the data say about the fit's curvature.

    point_noise_m: σ from fourth differences (std σ √70 for white noise); curvature_error_per_m:
    RMS spread of the curvature over refits of the fitted points plus that noise;
    curvature_overshoot: how far the fit's curvature rises above the three-point
    (circumscribed-circle) curvature of the neighbouring points, as a fraction of the
    largest of those — a spline rings at a curvature jump of the data.
    """
    d4 = np.diff(p, 4, axis=0)
    sigma = float(np.median(np.abs(d4)) / 0.6745 / math.sqrt(70.0)) if len(d4) else 0.0
    fine = np.linspace(u[0], u[-1], 20 * len(u))
    # The ends of a table are poorly determined by any fit; judge the interior.
    inner = (fine > u[2]) & (fine < u[-3])
    kappa = _curvature(spline, fine)
    rng = np.random.default_rng(0)
    base = spline(u)
    spread = [_curvature(_fit(u, base + rng.normal(scale=sigma, size=p.shape), smoothing, ""), fine) - kappa
              for _ in range(NOISE_REPLICATES)] if sigma > 0 else [np.zeros_like(fine)]
    err = np.sqrt(np.mean(np.square(spread), axis=0))
    three = np.concatenate([[0.0], _three_point_curvature(p), [0.0]])
    near = np.clip(np.searchsorted(u, fine), 1, len(u) - 1)
    bound = np.max([three[np.clip(near + j, 0, len(u) - 1)] for j in (-2, -1, 0, 1)], axis=0)
    excess = np.where(inner, kappa - bound, -np.inf)
    k = int(np.argmax(excess))
    return {"point_noise_m": sigma, "smoothing_m": smoothing,
            "curvature_error_per_m": float(err[inner].max()) if inner.any() else 0.0,
            "curvature_max_per_m": float(kappa[inner].max()) if inner.any() else 0.0,
            "curvature_overshoot": float(max(excess[k], 0.0) / max(three.max(), 1e-300)),
            "overshoot_near_m": float(fine[k])}


def _three_point_curvature(p):
    """Curvature of the circle through each three consecutive points (n - 2,) [1/m]."""
    a, b = p[1:-1] - p[:-2], p[2:] - p[1:-1]
    twice_area = np.linalg.norm(np.cross(a, b), axis=1)
    return 2 * twice_area / (np.linalg.norm(a, axis=1) * np.linalg.norm(b, axis=1) * np.linalg.norm(a + b, axis=1))


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


def build(spec: dict, field: str = "track") -> Track:
    """Track from the resolved scene table ``[track]`` (see docs/scenes-trolley.md)."""
    constants = spec.get("constants") or {}
    kind = spec["type"]
    if kind == "table":
        track = TableTrack(spec["points"], f"{field}.points", spec["max_turn_deg"], spec["smoothing"])
    else:
        if kind == "helix":
            texts, var = helix_expressions(spec["radius"], spec["rise"]), "s"
        else:
            texts, var = [spec[k] for k in "xyz"], spec["parameter"]
        exprs = [expressions.parse(f"{field}.{k}", t, (var,), constants) for k, t in zip("xyz", texts)]
        track = ExpressionTrack(exprs, var, field, spec.get("u_range"))
    twist = expressions.parse(f"{field}.twist", spec["twist"], ("s",), constants)
    if twist != 0:
        track.set_twist(twist)
    return track
