"""Rotations, skew matrices and inertia transforms, written once over two arithmetics.

Every function takes an arithmetic ``ar``: :data:`NUMPY` (floats or arrays; a
leading batch shape broadcast across the arguments, results of shape batch +
(3,) or batch + (3, 3)) or :data:`SYMPY` (sympy expressions, results
``sympy.Matrix``; sympy is imported only when that arithmetic is used, so
runtime modules may import this one). Conventions:

* an *active* rotation R turns a vector: v' = R v; the *passive* matrix of the
  same turn maps fixed-frame components to turned-frame components, Λ = Rᵀ;
* ``skew(a) @ b = a × b`` (the paper's ǎ), ``vee(skew(a)) = a``;
* inertia tensors are 3 x 3 about the stated point [kg m²]; the second moment
  J = ∫ r rᵀ dm relates to the inertia I = ∫ (|r|² E - r rᵀ) dm by I = tr(J) E - J,
  J = ½ tr(I) E - I.
"""
from __future__ import annotations

import numpy as np


class _Numpy:
    """Float / array arithmetic: matrices are arrays of shape batch + (rows, cols)."""

    sin = staticmethod(np.sin)
    cos = staticmethod(np.cos)

    @staticmethod
    def matrix(rows):
        # Float entries (one body, as inside ODE right-hand sides; numpy scalars are floats
        # too) take one np.array call, several times cheaper than broadcasting.
        if all(isinstance(x, float) for row in rows for x in row):
            return np.array(rows)
        flat = [np.asarray(x, dtype=float) for row in rows for x in row]
        shape = np.broadcast_shapes(*(x.shape for x in flat))
        out = np.stack([np.broadcast_to(x, shape) for x in flat], axis=-1)
        return out.reshape(shape + (len(rows), len(rows[0])))

    @staticmethod
    def column(xs):
        xs = [np.asarray(x, dtype=float) for x in xs]
        shape = np.broadcast_shapes(*(x.shape for x in xs))
        return np.stack([np.broadcast_to(x, shape) for x in xs], axis=-1)

    @staticmethod
    def entries(m):
        m = np.asarray(m, dtype=float)
        return [[m[..., i, j] for j in range(m.shape[-1])] for i in range(m.shape[-2])]

    @staticmethod
    def vector(v):
        v = np.asarray(v, dtype=float)
        # one vector: Python floats, whose arithmetic is several times cheaper than 0-d arrays
        return v.tolist() if v.ndim == 1 else [v[..., i] for i in range(3)]

    @staticmethod
    def matmul(a, b):
        return np.asarray(a) @ np.asarray(b)

    @staticmethod
    def transpose(a):
        return np.swapaxes(np.asarray(a), -1, -2)


class _Sympy:
    """sympy arithmetic: matrices are ``sympy.Matrix``."""

    @staticmethod
    def sin(x):
        import sympy

        return sympy.sin(x)

    @staticmethod
    def cos(x):
        import sympy

        return sympy.cos(x)

    @staticmethod
    def matrix(rows):
        import sympy

        return sympy.Matrix(rows)

    @staticmethod
    def column(xs):
        import sympy

        return sympy.Matrix(xs)

    @staticmethod
    def entries(m):
        import sympy

        m = sympy.Matrix(m)
        return [[m[i, j] for j in range(m.cols)] for i in range(m.rows)]

    @staticmethod
    def vector(v):
        return [v[i] for i in range(3)]

    @staticmethod
    def matmul(a, b):
        return a * b

    @staticmethod
    def transpose(a):
        return a.T


NUMPY = _Numpy()
SYMPY = _Sympy()


def skew(v, ar=NUMPY):
    """Cross-product matrix of the 3-vector v: skew(v) b = v × b."""
    x, y, z = ar.vector(v)
    zero = 0 * x
    return ar.matrix([[zero, -z, y], [z, zero, -x], [-y, x, zero]])


def vee(m, ar=NUMPY):
    """Axial vector (shape batch + (3,), or a 3 x 1 Matrix) of the skew part of a 3 x 3 matrix."""
    e = ar.entries(m)
    return ar.column([(e[2][1] - e[1][2]) / 2, (e[0][2] - e[2][0]) / 2, (e[1][0] - e[0][1]) / 2])


def elementary(axis: int, angle, ar=NUMPY, passive: bool = True):
    """Rotation by ``angle`` [rad] about coordinate axis ``axis`` (0, 1, 2); passive by default."""
    c, s = ar.cos(angle), ar.sin(angle)
    one, zero = 1 + 0 * c, 0 * c
    if not passive:
        s = -s
    rows = [[one, zero, zero], [zero, one, zero], [zero, zero, one]]
    i, j = (axis + 1) % 3, (axis + 2) % 3
    rows[i][i], rows[i][j], rows[j][i], rows[j][j] = c, s, -s, c
    return ar.matrix(rows)


def sequence(axes, angles, ar=NUMPY, passive: bool = True):
    """Rotation of the turns ``angles[k]`` about ``axes[k]``, first turn first, each about
    the axis of the frame turned so far. Passive: Λ = Λ_last ⋯ Λ_first (fixed -> turned
    components); active: R = R_first ⋯ R_last = Λᵀ."""
    mats = [elementary(a, t, ar, passive) for a, t in zip(axes, angles)]
    order = reversed(mats) if passive else mats
    out = None
    for m in order:
        out = m if out is None else ar.matmul(out, m)
    return out


def rodrigues(axis, angle, ar=NUMPY):
    """Active rotation by ``angle`` about the unit vector ``axis``:
    R = cos Ψ E + sin Ψ ξ̌ + (1 - cos Ψ) ξ ξᵀ."""
    x = ar.vector(axis)
    c, s = ar.cos(angle), ar.sin(angle)
    k = ar.entries(skew(axis, ar))
    return ar.matrix([[(1 - c) * x[i] * x[j] + s * k[i][j] + (c if i == j else 0 * c) for j in range(3)]
                      for i in range(3)])


def inertia_matrix(six, ar=NUMPY):
    """3 x 3 inertia tensor from [I11, I22, I33, I12, I23, I13] [kg m²]."""
    if ar is NUMPY:
        six = np.asarray(six, dtype=float)
        six = [six[..., k] for k in range(6)]
    i11, i22, i33, i12, i23, i13 = six
    return ar.matrix([[i11, i12, i13], [i12, i22, i23], [i13, i23, i33]])


def _combine(ar, a, b, fa, fb):
    ea, eb = ar.entries(a), ar.entries(b)
    return ar.matrix([[fa * ea[i][j] + fb * eb[i][j] for j in range(3)] for i in range(3)])


def _identity_times(ar, x):
    zero = 0 * x
    return ar.matrix([[x, zero, zero], [zero, x, zero], [zero, zero, x]])


def second_moment(inertia, ar=NUMPY):
    """J = ∫ r rᵀ dm = ½ tr(I) E - I from the inertia tensor I about the same point."""
    e = ar.entries(inertia)
    half_trace = (e[0][0] + e[1][1] + e[2][2]) / 2
    return _combine(ar, _identity_times(ar, half_trace), inertia, 1, -1)


def inertia_from_second_moment(second, ar=NUMPY):
    """I = tr(J) E - J [kg m²] from the second moment J = ∫ r rᵀ dm about the same point
    (the inverse of :func:`second_moment`)."""
    e = ar.entries(second)
    return _combine(ar, _identity_times(ar, e[0][0] + e[1][1] + e[2][2]), second, 1, -1)


def parallel_axis(inertia_central, mass, offset, ar=NUMPY):
    """Inertia about a point P from the central inertia, mass [kg] and the centre of mass
    relative to P [m]: I_P = I_C + m (|d|² E - d dᵀ)."""
    d = ar.vector(offset)
    d2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
    shift = ar.matrix([[mass * ((d2 if i == j else 0 * d2) - d[i] * d[j]) for j in range(3)] for i in range(3)])
    return _combine(ar, inertia_central, shift, 1, 1)


def rotate_tensor(rotation, tensor, ar=NUMPY):
    """R T Rᵀ: the tensor T given in frame components, expressed after the active turn R
    (or, with R = Λ passive, its components in the turned frame)."""
    return ar.matmul(ar.matmul(rotation, tensor), ar.transpose(rotation))
