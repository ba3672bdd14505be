"""The rigid grain's kinematics in numba, for every phase of the compiled loop: rotation matrix, lowest point,
surface motion, effective mass, kinetic and absolute energy, and the contact tests at a state (gap, contact
velocity and their round-off floors). The physics comes from the generated scalar kernels (``grain_motion_nb``).

``p`` is the parameter vector (layout :data:`layouts.PARAMS`), ``y`` the state (14,) (``STATE``)."""
from __future__ import annotations

import math

import numpy as np

from symmech.numerics import kernels
from symmech.numerics.jit import jit
from symmech.grain.motion_engine.layouts import P_AT, X_AT

gm = kernels.load("grain_motion")


EPS = float(np.finfo(float).eps)


@jit
def cross(a, b):
    return np.array(cross_xyz(a, b))


@jit
def cross_xyz(a, b):
    """a x b as 3 floats; a, b: 3 floats or (3,) (no array built)."""
    return a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]


@jit
def dot3(a, b):
    """a . b of two 3-vectors (floats or (3,)) summed in index order: no BLAS call for 3 products."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@jit
def turn(Q, a):
    """Q a as 3 floats: a body vector's KXYZ components (a: 3 floats or (3,))."""
    return (Q[0, 0] * a[0] + Q[0, 1] * a[1] + Q[0, 2] * a[2], Q[1, 0] * a[0] + Q[1, 1] * a[1] + Q[1, 2] * a[2],
            Q[2, 0] * a[0] + Q[2, 1] * a[1] + Q[2, 2] * a[2])


@jit
def turn_back(Q, a):
    """Q^T a as 3 floats: a KXYZ vector's body components."""
    return (Q[0, 0] * a[0] + Q[1, 0] * a[1] + Q[2, 0] * a[2], Q[0, 1] * a[0] + Q[1, 1] * a[1] + Q[2, 1] * a[2],
            Q[0, 2] * a[0] + Q[1, 2] * a[1] + Q[2, 2] * a[2])


@jit
def rotation(q):
    """Q (3, 3) of a quaternion, normalised here (generated ``rotation_matrix``)."""
    s = math.sqrt(q[0] ** 2 + q[1] ** 2 + q[2] ** 2 + q[3] ** 2)
    return gm.rotation_matrix_scalar(q[0] / s, q[1] / s, q[2] / s, q[3] / s)


@jit
def contact_offset(p, Q):
    """Contact offset R (3,) [m] of the lowest point, KXYZ (:func:`contact_offset_xyz` as an array)."""
    return np.array(contact_offset_xyz(p, Q))


@jit
def contact_offset_xyz(p, Q):
    """Contact offset R [m] of the lowest point, KXYZ, as 3 floats (generated ``contact_offset_body``, turned)."""
    body = gm.contact_offset_body_scalar(p[P_AT.axes], p[P_AT.axes + 1], p[P_AT.axes + 2], Q[2, 0], Q[2, 1], Q[2, 2])
    return turn(Q, body)


@jit
def support(p, Q):
    return gm.support_distance_scalar(p[P_AT.axes], p[P_AT.axes + 1], p[P_AT.axes + 2], Q[2, 0], Q[2, 1], Q[2, 2])


@jit
def surface(p, t):
    """Rows displacement, velocity, acceleration (3, 3) of the surface at t."""
    d = P_AT.direction
    return gm.surface_kinematics_scalar(p[P_AT.amplitude], p[P_AT.omega], p[P_AT.phase], p[d], p[d + 1], p[d + 2], t)


@jit
def normal_force(p, t):
    """Normal force per unit mass n(t) [m/s^2] of a grain on the plane."""
    return surface(p, t)[2, 2] - p[P_AT.g + 2]


@jit
def inertia_solve(p, Q, c):
    """I^-1 c [rad/s] in KXYZ of a KXYZ vector c [N m s] (an angular impulse), as 3 floats: sum over the body axes
    q_k (columns of Q) of q_k (q_k . c) / I_k [kg m^2], the world inverse inertia Q diag(1/I) Q^T applied."""
    x, y, z = 0.0, 0.0, 0.0
    for k in range(3):
        s = (Q[0, k] * c[0] + Q[1, k] * c[1] + Q[2, k] * c[2]) / p[P_AT.inertia + k]
        x, y, z = x + Q[0, k] * s, y + Q[1, k] * s, z + Q[2, k] * s
    return x, y, z


@jit
def inverse_effective_mass(p, Q, R):
    """K [1/kg] (``coulomb_law.inverse_effective_mass``; a point mass without rotation), symmetric: its entries
    (K_xx, K_xy, K_xz, K_yy, K_yz, K_zz) as 6 floats. K = 1/m + Rx A Rx^T with A = Q diag(1/I) Q^T, i.e. 1/m plus
    the sum over the body axes q_k of c c^T / I_k, c = R x q_k: six sums of squares and products, no matrix built."""
    k = 1.0 / p[P_AT.mass]
    xx, xy, xz, yy, yz, zz = k, 0.0, 0.0, k, 0.0, k
    if p[P_AT.rotation] != 0.0:
        for j in range(3):
            c = cross_xyz(R, (Q[0, j], Q[1, j], Q[2, j]))
            d = 1.0 / p[P_AT.inertia + j]
            xx, xy, xz = xx + d * c[0] * c[0], xy + d * c[0] * c[1], xz + d * c[0] * c[2]
            yy, yz, zz = yy + d * c[1] * c[1], yz + d * c[1] * c[2], zz + d * c[2] * c[2]
    return xx, xy, xz, yy, yz, zz


@jit
def kinetic(p, Q, v, w):
    """Kinetic energy [J]; v, w (3 floats or (3,)) in KXYZ."""
    if w[0] == 0.0 and w[1] == 0.0 and w[2] == 0.0:  # no spin: the same sum without the product Q^T w
        return 0.5 * p[P_AT.mass] * dot3(v, v)
    wb = turn_back(Q, w)
    I = p[P_AT.inertia:P_AT.inertia + 3]
    return 0.5 * p[P_AT.mass] * dot3(v, v) + 0.5 * (I[0] * wb[0] ** 2 + I[1] * wb[1] ** 2 + I[2] * wb[2] ** 2)


@jit
def is_sphere(p):
    a = P_AT.axes
    return max(p[a], p[a + 1], p[a + 2]) == min(p[a], p[a + 1], p[a + 2])


@jit
def contact_velocity(p, y):
    w = y[X_AT.w:X_AT.w + 3]
    if w[0] == 0.0 and w[1] == 0.0 and w[2] == 0.0:  # no spin: the centre's, no rotation matrix to build
        return y[X_AT.v + 2]
    Q = rotation(y[X_AT.q:X_AT.q + 4])
    return y[X_AT.v + 2] + cross_xyz(turn(Q, y[X_AT.w:X_AT.w + 3]), contact_offset_xyz(p, Q))[2]


@jit
def gap(p, y):
    return y[X_AT.r + 2] - support(p, rotation(y[X_AT.q:X_AT.q + 4]))


@jit
def gap_noise(p, y):
    return 64 * EPS * (max(p[P_AT.axes], p[P_AT.axes + 1], p[P_AT.axes + 2]) + abs(y[X_AT.r + 2]) + p[P_AT.amplitude])


@jit
def velocity_noise(p, y):
    a = P_AT.axes
    v, w = y[X_AT.v:X_AT.v + 3], y[X_AT.w:X_AT.w + 3]
    scale = (math.sqrt(v @ v) + math.sqrt(w @ w) * max(p[a], p[a + 1], p[a + 2])
             + p[P_AT.amplitude] * p[P_AT.omega])
    return 1e3 * EPS * scale


@jit
def energy(p, y):
    """Absolute energy [J]: kinetic in the inertial frame plus the potential of gravity (the start and the end of
    the energy budget, :mod:`symmech.grain.outcome`)."""
    s = surface(p, y[X_AT.t])
    v = y[X_AT.v:X_AT.v + 3] + s[1]
    I = p[P_AT.inertia:P_AT.inertia + 3]
    w = y[X_AT.w:X_AT.w + 3]
    return (p[P_AT.mass] * (0.5 * (v @ v) - p[P_AT.g:P_AT.g + 3] @ (y[X_AT.r:X_AT.r + 3] + s[0]))
            + 0.5 * (I[0] * w[0] ** 2 + I[1] * w[1] ** 2 + I[2] * w[2] ** 2))

