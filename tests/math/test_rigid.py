"""Tests of deburr_drake.math.rigid: roll-pitch-yaw, composition and the
believed, real and stepped part poses."""

import numpy as np
from pydrake.common.eigen_geometry import AngleAxis
from pydrake.math import RotationMatrix

from deburr_drake.math.rigid import (
    believed_from_real,
    compose,
    inverse,
    matrix_rotvec,
    matrix_rpy,
    real_from_believed,
    rotvec_matrix,
    rpy_matrix,
    stepped_belief,
)


def _rz(a):
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def test_rpy_is_drakes_rz_ry_rx():
    r, p, y = 0.1, -0.2, 0.3
    cr, sr, cp, sp = np.cos(r), np.sin(r), np.cos(p), np.sin(p)
    Rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    Ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    np.testing.assert_allclose(rpy_matrix([r, p, y]), _rz(y) @ Ry @ Rx)
    np.testing.assert_allclose(matrix_rpy(rpy_matrix([r, p, y])), [r, p, y])


def test_believed_turns_about_the_real_frames_axes_then_moves():
    real = (rpy_matrix([0.0, -np.pi / 2, 0.0]), np.array([1.0, 2.0, 3.0]))
    R, p = believed_from_real(real, [0.001, 0.0, 0.0], [0.0, 0.0, 0.1])
    # turned about the real part's own z, which is the world's -x
    np.testing.assert_allclose(R, real[0] @ _rz(0.1))
    np.testing.assert_allclose(R @ [0, 0, 1], real[0] @ [0, 0, 1])
    np.testing.assert_allclose(p, [1.001, 2.0, 3.0])
    back = real_from_believed((R, p), [0.001, 0.0, 0.0], [0.0, 0.0, 0.1])
    np.testing.assert_allclose(back[0], real[0], atol=1e-15)
    np.testing.assert_allclose(back[1], real[1], atol=1e-15)


def test_compose_and_inverse():
    a = (rpy_matrix([0.3, 0.2, -0.1]), np.array([0.1, -0.2, 0.3]))
    R, p = compose(a, inverse(a))
    np.testing.assert_allclose(R, np.eye(3), atol=1e-15)
    np.testing.assert_allclose(p, 0.0, atol=1e-15)


def test_stepped_belief_keeps_the_error_against_the_stepped_part():
    real = (rpy_matrix([0.2, 0.0, 0.5]), np.array([0.5, 0.0, 0.4]))
    believed = believed_from_real(real, [0.001, -0.002, 0.0], [0.01, 0, 0])
    offset, rpy = [0.0, 0.003, -0.001], [0.0, 0.02, -0.03]
    after = stepped_belief(real, believed, offset, rpy)
    stepped = believed_from_real(real, offset, rpy)
    # believed against stepped real == new belief against unmoved real
    want = compose(inverse(stepped), believed)
    got = compose(inverse(real), after)
    np.testing.assert_allclose(got[0], want[0], atol=1e-14)
    np.testing.assert_allclose(got[1], want[1], atol=1e-14)
    # a pure move: the belief moves back by it
    moved = stepped_belief(real, believed, offset, [0.0, 0.0, 0.0])
    np.testing.assert_allclose(moved[0], believed[0], atol=1e-15)
    np.testing.assert_allclose(moved[1], believed[1] - offset, atol=1e-15)


def test_rpy_round_trip_over_the_angles():
    rng = np.random.default_rng(0)
    for _ in range(200):
        rpy = rng.uniform(-np.pi, np.pi, 3)
        rpy[1] = rng.uniform(-1.5, 1.5)
        R = rpy_matrix(rpy)
        np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-14)
        np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-14)
        np.testing.assert_allclose(rpy_matrix(matrix_rpy(R)), R, atol=1e-14)
        np.testing.assert_allclose(matrix_rpy(R), rpy, atol=1e-12)


def test_rotation_vector_round_trip_against_drake():
    rng = np.random.default_rng(3)
    for _ in range(20):
        axis = rng.normal(size=3)
        w = axis / np.linalg.norm(axis) * rng.uniform(0.0, 3.0)  # < pi
        R = rotvec_matrix(w)
        axis = w / np.linalg.norm(w)
        expected = RotationMatrix(AngleAxis(np.linalg.norm(w), axis))
        np.testing.assert_allclose(R, expected.matrix(), atol=1e-14)
        np.testing.assert_allclose(matrix_rotvec(R), w, atol=1e-12)
    np.testing.assert_array_equal(rotvec_matrix(np.zeros(3)), np.eye(3))
    np.testing.assert_allclose(
        matrix_rotvec(rotvec_matrix([1e-9, 0, 0])), [1e-9, 0, 0], rtol=1e-6
    )
