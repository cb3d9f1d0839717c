"""Rigid poses as (R, p) pairs (pure numpy): roll-pitch-yaw angles, the
product and the inverse of poses, and the pose of the part the controller
believes in against the real one.

A pose X_AB = (R_AB, p_AB) maps a point given in frame B into frame A:
p_A = R_AB p_B + p_AB. Angles are Drake's RollPitchYaw: R = Rz(yaw)
Ry(pitch) Rx(roll)."""

from __future__ import annotations

import numpy as np

__all__ = [
    "rpy_matrix",
    "matrix_rpy",
    "compose",
    "inverse",
    "believed_from_real",
    "real_from_believed",
    "stepped_belief",
    "rotvec_matrix",
    "matrix_rotvec",
]


# Written out rather than scipy.spatial.transform's: importing
# scipy.spatial costs every command about a second, and every scenario
# reads a part's pose.
def rpy_matrix(rpy) -> np.ndarray:
    """R = Rz(yaw) Ry(pitch) Rx(roll) of ``rpy`` (rad)."""
    roll, pitch, yaw = np.asarray(rpy, float)
    cr, sr = np.cos(roll), np.sin(roll)
    cp, sp = np.cos(pitch), np.sin(pitch)
    cy, sy = np.cos(yaw), np.sin(yaw)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def matrix_rpy(R) -> np.ndarray:
    """(roll, pitch, yaw) (rad) of the rotation matrix ``R``, pitch in
    [-pi/2, pi/2]."""
    R = np.asarray(R, float)
    return np.array(
        [
            np.arctan2(R[2, 1], R[2, 2]),
            np.arctan2(-R[2, 0], np.hypot(R[2, 1], R[2, 2])),
            np.arctan2(R[1, 0], R[0, 0]),
        ]
    )


def compose(a, b):
    """X_AC = X_AB X_BC of ``a`` = (R_AB, p_AB) and ``b`` = (R_BC, p_BC)."""
    Ra, pa = a
    Rb, pb = b
    return Ra @ Rb, Ra @ pb + pa


def inverse(a):
    """X_BA of ``a`` = X_AB."""
    R, p = a
    return R.T, -R.T @ p


def believed_from_real(real, offset, rpy):
    """The believed part's pose in the world: the real part's, ``real``
    = (R_WR, p_WR), turned by ``rpy`` (rad) about the real part frame's
    own axes at its origin, then moved by ``offset`` (m) along the world's
    axes: R_WB = R_WR R(rpy), p_WB = p_WR + offset."""
    R, p = real
    return R @ rpy_matrix(rpy), p + np.asarray(offset, float)


def real_from_believed(believed, offset, rpy):
    """The inverse of :func:`believed_from_real`: the real part's pose
    given the believed one's, R_WR = R_WB R(rpy)^T, p_WR = p_WB -
    offset."""
    R, p = believed
    return R @ rpy_matrix(rpy).T, p - np.asarray(offset, float)


def stepped_belief(real, believed, offset, rpy):
    """The believed part's pose after the real one has stepped by
    (``offset``, ``rpy``) (turned by ``rpy`` about its own axes, moved by
    ``offset`` along the world's) when the simulation keeps the real part
    where it was: the believed part takes the pose against the unmoved
    real part that it has against the stepped one,
    X_WB' = X_WR X_WR'^-1 X_WB."""
    stepped = believed_from_real(real, offset, rpy)
    return compose(real, compose(inverse(stepped), believed))


def rotvec_matrix(w) -> np.ndarray:
    """The rotation by the angle |w| (rad) about the unit w (Rodrigues):
    I + sin(t) K + (1 - cos(t)) K^2, K the cross-product matrix of w / t."""
    w = np.asarray(w, float)
    t = float(np.linalg.norm(w))
    if t < 1e-300:
        return np.eye(3)
    k = w / t
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(t) * K + (1.0 - np.cos(t)) * (K @ K)


def matrix_rotvec(R) -> np.ndarray:
    """The rotation vector w (rad) of ``R``: :func:`rotvec_matrix`'s
    inverse, |w| in [0, pi)."""
    R = np.asarray(R, float)
    axis = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    s = 0.5 * float(np.linalg.norm(axis))
    c = 0.5 * (float(np.trace(R)) - 1.0)
    t = float(np.arctan2(s, c))
    if s < 1e-12:
        return 0.5 * axis  # no turn (or a turn of pi, which no fit gives)
    return t / (2.0 * s) * axis
