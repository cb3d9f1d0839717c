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

import math
from typing import Callable

import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import JacobianWrtVariable

from deburr_drake.cell.moves import PlanningCell, clearance
from deburr_drake.config import ConfigError
from deburr_drake.math.rigid import matrix_rotvec, rotvec_matrix

__all__ = ["check_probe_route", "moved_path", "path_mover"]

#: Gauss-Newton steps per posture at most; a registration moves the tool
#: by millimetres, and each step squares the error.
_STEPS = 8
#: m (and rad): a posture closer than this to the moved pose is taken.
_TOLERANCE = 1e-10
#: rad, the largest joint step of one Gauss-Newton step (far targets:
#: the probe's route).
_MAX_STEP = 0.2
#: Gauss-Newton steps at most for a point of the probe's route.
_ROUTE_STEPS = 60


def _solve(model, context, frame, R_goal, p_goal, q, steps=_STEPS):
    """(q, what is left (m or rad, the largest)): ``frame``'s pose at
    (R_goal, p_goal) by Gauss-Newton on its spatial Jacobian from ``q``,
    each step at most _MAX_STEP rad."""
    world = model.world_frame()
    left = math.inf
    for _ in range(steps):
        model.SetPositions(context, q)
        X = frame.CalcPoseInWorld(context)
        error = np.concatenate(
            [
                matrix_rotvec(R_goal @ X.rotation().matrix().T),
                p_goal - X.translation(),
            ]
        )
        left = float(np.max(np.abs(error)))
        if left < _TOLERANCE:
            break
        J = model.CalcJacobianSpatialVelocity(
            context, JacobianWrtVariable.kQDot, frame, np.zeros(3), world, world
        )
        step = np.linalg.lstsq(J, error, rcond=None)[0]
        q = q + step * min(1.0, _MAX_STEP / max(np.max(np.abs(step)), 1e-300))
    return q, left


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
    out = np.empty_like(path)
    shift = np.zeros(path.shape[1])
    for i, q_planned in enumerate(path):
        model.SetPositions(context, q_planned)
        X = frame.CalcPoseInWorld(context)
        R_goal = R_reg @ X.rotation().matrix()
        p_goal = R_reg @ X.translation() + p_reg
        q, left = _solve(
            model, context, frame, R_goal, p_goal, q_planned + shift
        )
        if left >= _TOLERANCE:
            raise ValueError(
                f"posture {i} of a move does not reach its pose moved by "
                f"the registration (left {left:.3g})"
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


def check_probe_route(
    cell: PlanningCell,
    model: MultibodyPlant,
    tool_frame: str,
    route,
    *,
    rotation,
    q_start,
) -> float:
    """m, the least clearance between the arm (its cutter, the probe,
    left out: it touches) and the part (``cell``, the planning cell's
    convex pieces) with the tool at every point of the probe's ``route``
    ((2 N, 3) m, world: each touch's standoff, then the point above each
    at the safe height; deburr_drake.control.mesh_probe.MeshProbePlan.
    route), the tool's ``rotation`` the start's (the loops hold it while
    probing), each posture solved from the last (the first from
    ``q_start``). ConfigError naming ``localisation.probe.points``
    when the arm does not reach a touch or stands in the part there."""
    frame = model.GetFrameByName(tool_frame)
    context = model.CreateDefaultContext()
    rotation = np.asarray(rotation, float)
    count = len(route) // 2
    q, least = np.asarray(q_start, float), math.inf
    for i, x in enumerate(np.asarray(route, float)):
        where = "standoff" if i < count else "way in from above"
        touch = i % count
        q, left = _solve(model, context, frame, rotation, x, q, _ROUTE_STEPS)
        if left >= 1e-6:
            raise ConfigError(
                f"localisation.probe.points: the arm does not reach touch "
                f"{touch}'s {where} at {np.round(x, 4).tolist()} m with "
                f"the tool held as at the start ({left:.3g} m or rad off)"
            )
        distance = clearance(cell, q, cutter=False)
        if distance <= 0.0:
            raise ConfigError(
                f"localisation.probe.points: at touch {touch}'s {where} "
                f"the arm stands {-distance * 1e3:.2g} mm in the part"
            )
        least = min(least, distance)
    return least
