"""core.kinematics: the same formulas in sympy and numpy, against independent constructions."""
import numpy as np
import pytest
import sympy as sp

from symmech.core import kinematics as kin
from symmech.generated import trolley_frame as frm

RNG = np.random.default_rng(20261123)


def _sym(fun, *args):
    """Evaluate a kinematics function in sympy arithmetic at numeric arguments."""
    return np.array(sp.Matrix(fun(*args, ar=kin.SYMPY)).evalf(), dtype=float)


def test_skew_vee_cross_products():
    a, b = RNG.normal(size=(2, 5, 3))
    assert np.allclose(kin.skew(a) @ b[..., None], np.cross(a, b)[..., None], rtol=0, atol=1e-14)
    assert np.allclose(kin.vee(kin.skew(a)), a, rtol=0, atol=0)
    assert np.allclose(_sym(kin.skew, sp.Matrix(a[0])), kin.skew(a[0]), atol=1e-15)


def test_aircraft_sequence_is_lambda_of_the_rigid_model():
    th = RNG.uniform(-np.pi, np.pi, (3, 20))
    lam = kin.sequence((1, 2, 0), (th[1], th[2], th[0]))
    assert np.abs(lam - frm.Lambda(*th)).max() < 1e-14
    active = kin.sequence((1, 2, 0), (th[1], th[2], th[0]), passive=False)
    assert np.abs(active - np.swapaxes(lam, -1, -2)).max() < 1e-14
    s = sp.symbols("a b c")
    sym = kin.sequence((1, 2, 0), s, kin.SYMPY)
    val = np.array(sym.subs(dict(zip(s, th[[1, 2, 0], 0]))).evalf(), dtype=float)
    assert np.abs(val - lam[0]).max() < 1e-14


def test_rodrigues_turns_about_its_axis_by_its_angle():
    axis = RNG.normal(size=(10, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    angle = RNG.uniform(-3, 3, 10)
    R = kin.rodrigues(axis, angle)
    assert np.abs(R @ np.swapaxes(R, -1, -2) - np.eye(3)).max() < 1e-14
    assert np.abs((R @ axis[..., None])[..., 0] - axis).max() < 1e-14
    assert np.allclose(np.trace(R, axis1=-2, axis2=-1), 1 + 2 * np.cos(angle), atol=1e-14)
    # about x3 it is the active elementary rotation
    assert np.abs(kin.rodrigues(np.array([0, 0, 1.0]), 0.7) - kin.elementary(2, 0.7, passive=False)).max() < 1e-15
    assert np.abs(_sym(kin.rodrigues, sp.Matrix(axis[0]), angle[0]) - R[0]).max() < 1e-14


def test_inertia_transforms_match_a_point_cloud():
    pts = RNG.normal(size=(30, 3))
    m = RNG.uniform(0.5, 2, 30)
    com = (m[:, None] * pts).sum(0) / m.sum()

    def inertia(points):
        return sum(mi * (p @ p * np.eye(3) - np.outer(p, p)) for mi, p in zip(m, points))

    central = inertia(pts - com)
    point = RNG.normal(size=3)
    assert np.allclose(kin.parallel_axis(central, m.sum(), com - point), inertia(pts - point), rtol=1e-13)
    J = sum(mi * np.outer(p, p) for mi, p in zip(m, pts - com))
    assert np.allclose(kin.second_moment(central), J, rtol=1e-13)
    assert np.allclose(kin.inertia_from_second_moment(J), central, rtol=1e-13)
    assert np.allclose(_sym(kin.inertia_from_second_moment, sp.Matrix(J)), central, rtol=1e-13)
    R = kin.rodrigues(np.array([0.6, 0.0, 0.8]), 1.1)
    assert np.allclose(kin.rotate_tensor(R, central), inertia((pts - com) @ R.T), rtol=1e-13)
    six = [central[0, 0], central[1, 1], central[2, 2], central[0, 1], central[1, 2], central[0, 2]]
    assert np.array_equal(kin.inertia_matrix(six), central)
    sym = _sym(kin.parallel_axis, sp.Matrix(central), m.sum(), sp.Matrix(com - point))
    assert np.allclose(sym, inertia(pts - point), rtol=1e-13)


@pytest.mark.parametrize("passive", [True, False])
def test_sequence_numpy_and_sympy_agree(passive):
    th = RNG.uniform(-2, 2, 3)
    num = kin.sequence((0, 1, 2), th, passive=passive)
    sym = np.array(kin.sequence((0, 1, 2), [sp.Float(x) for x in th], kin.SYMPY, passive).evalf(), dtype=float)
    assert np.abs(num - sym).max() < 1e-14


def test_single_vectors_and_batches_give_the_same_matrices():
    """One vector takes the scalar path of the numpy arithmetic, a stack the batch path; rows of the
    stack must equal the single results bit for bit, and mixed scalar/batch arguments broadcast."""
    v = RNG.normal(size=(4, 3))
    angle = RNG.uniform(-3, 3, 4)
    assert kin.skew(v[0]).shape == (3, 3)
    for k in range(4):
        assert np.array_equal(kin.skew(v)[k], kin.skew(v[k]))
        assert np.array_equal(kin.elementary(1, angle)[k], kin.elementary(1, angle[k]))
        assert np.array_equal(kin.rodrigues(v[0], angle)[k], kin.rodrigues(v[0], angle[k]))
    # a stack of three vectors is a (3, 3) batch, not one matrix of scalars
    assert kin.skew(v[:3]).shape == (3, 3, 3)
    c, s = np.cos(angle[0]), np.sin(angle[0])
    assert np.array_equal(kin.elementary(2, angle[0], passive=False), [[c, -s, 0], [s, c, 0], [0, 0, 1]])
    shift = kin.parallel_axis(np.zeros((3, 3)), np.array([1.0, 2.0]), v[0])
    d = v[0]
    assert np.allclose(shift[1], 2 * (d @ d * np.eye(3) - np.outer(d, d)), rtol=1e-15, atol=0)


def test_elementary_rotations_are_passive_by_default():
    """Without `passive`, the matrix of a frame turned by +0.3 rad about each axis (the coordinates of a fixed
    vector in the turned frame), written out; the active rotation is its transpose."""
    c, s = np.cos(0.3), np.sin(0.3)
    written = {0: [[1, 0, 0], [0, c, s], [0, -s, c]], 1: [[c, 0, -s], [0, 1, 0], [s, 0, c]],
               2: [[c, s, 0], [-s, c, 0], [0, 0, 1]]}
    for axis, matrix in written.items():
        np.testing.assert_allclose(kin.elementary(axis, 0.3), matrix, rtol=0, atol=1e-16)
        np.testing.assert_allclose(kin.elementary(axis, 0.3, passive=False), np.transpose(matrix), rtol=0,
                                   atol=1e-16)
