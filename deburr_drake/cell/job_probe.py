"""A whole part's job with touch probing, the cell's side: the moves
planned on the believed part, moved with the part the probe registered.

The job plans its moves once, in joint space, on the part at
``job.pose``. The probe registers the real part as a rigid move x ->
R x + p (deburr_drake.control.mesh_probe.register_part); every cut is cut
on the registered part (its contour moved by that pose), so each move's
ends must move with it: a cut ends, and the next begins, up to the pose
allowance (1 mm and 1 degree about the part's origin) from where the plan
put them. :func:`path_mover` moves the tool's every pose along a planned
path by the registration (inverse kinematics from the planned posture),
so the tool keeps, relative to the registered part, the path the planner
checked for clearance on the believed one.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import JacobianWrtVariable

from deburr_drake.math.rigid import matrix_rotvec, rotvec_matrix

__all__ = ["moved_path", "path_mover"]

#: Gauss-Newton steps per posture at most; a registration moves the tool
#: by millimetres, and each step squares the error.
_STEPS = 8
#: m (and rad): a posture closer than this to the moved pose is taken.
_TOLERANCE = 1e-10


def moved_path(
    model: MultibodyPlant, tool_frame: str, path, registration, context=None
) -> np.ndarray:
    """(k, n): ``path`` (k, n, postures of ``model``) with the pose of its
    ``tool_frame`` at each posture moved by ``registration`` (w, p, ...:
    X -> (Rot(w) R, Rot(w) x + p), world), by Gauss-Newton from each
    planned posture (the step between two postures is carried to the
    next as its first guess). ValueError when a posture does not reach
    its moved pose (out of reach or singular)."""
    path = np.asarray(path, float)
    reg = np.asarray(registration, float)
    if not np.any(reg[:6]):
        return path.copy()
    R_reg, p_reg = rotvec_matrix(reg[:3]), reg[3:6]
    context = model.CreateDefaultContext() if context is None else context
    frame = model.GetFrameByName(tool_frame)
    world = model.world_frame()
    out = np.empty_like(path)
    shift = np.zeros(path.shape[1])
    for i, q_planned in enumerate(path):
        model.SetPositions(context, q_planned)
        X = frame.CalcPoseInWorld(context)
        R_goal = R_reg @ X.rotation().matrix()
        p_goal = R_reg @ X.translation() + p_reg
        q = q_planned + shift
        for _ in range(_STEPS):
            model.SetPositions(context, q)
            X = frame.CalcPoseInWorld(context)
            error = np.concatenate(
                [
                    matrix_rotvec(R_goal @ X.rotation().matrix().T),
                    p_goal - X.translation(),
                ]
            )
            if np.max(np.abs(error)) < _TOLERANCE:
                break
            J = model.CalcJacobianSpatialVelocity(
                context,
                JacobianWrtVariable.kQDot,
                frame,
                np.zeros(3),
                world,
                world,
            )
            q = q + np.linalg.lstsq(J, error, rcond=None)[0]
        else:
            raise ValueError(
                f"posture {i} of a move does not reach its pose moved by "
                f"the registration (left {np.max(np.abs(error)):.3g})"
            )
        out[i] = q
        shift = q - q_planned
    return out


def path_mover(
    model: MultibodyPlant, tool_frame: str
) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """(path, registration) -> :func:`moved_path` on ``model`` (one
    Context of its own, reused: the sequencer calls it once per move)."""
    context = model.CreateDefaultContext()

    def move(path, registration):
        return moved_path(model, tool_frame, path, registration, context)

    return move
