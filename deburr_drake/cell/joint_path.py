"""A continuous joint path of the arm along a 3-D edge, the tool axis
turning with it: :func:`joint_path`.

The planar passes hold the tool vertical, and reach at a few points along
the edge tells whether the arm serves them. Along an edge whose tool axis
turns, the wrist turns with it, and the posture the inverse kinematics
gives at one point may not be the one the arm comes to from the previous
point (a wrist flip), a joint may run into its limit half-way, or the
path may cross a singular posture. So the path is followed as the
controller moves the arm: station by station, each posture solved from
the previous one, and the first station where it breaks is named by its
arc length and the joint.
"""

from __future__ import annotations

import numpy as np

from deburr_drake.cell.arm import (
    MIN_CONDITIONING,
    _arm_instance,
    _arm_positions,
    _solve_pose,
    _ToolTarget,
    _unit_axis,
    tip_jacobian,
)

__all__ = ["MAX_JOINT_STEP", "PathBreak", "joint_path", "joint_names"]

#: The largest change of any joint (rad) between two stations of a joint
#: path. Between stations a few mm apart a joint that follows the edge
#: turns by hundredths of a radian; a wrist flip turns one by about pi.
MAX_JOINT_STEP = 0.5


class PathBreak(RuntimeError):
    """The arm cannot follow the edge continuously at arc length ``arc``
    (m) because of joint ``joint`` (its name; None when no one joint is to
    blame: the point out of reach). The message is one line naming both."""

    def __init__(self, message, arc, joint):
        super().__init__(message)
        self.arc = float(arc)
        self.joint = joint


def joint_names(plant, instance):
    """The names of the instance's joint positions, in the order of
    :func:`deburr_drake.cell.arm.solve_tool_pose`'s q."""
    names = {}
    for index in plant.GetJointIndices(instance):
        joint = plant.get_joint(index)
        for k in range(joint.num_positions()):
            suffix = f"[{k}]" if joint.num_positions() > 1 else ""
            names[joint.position_start() + k] = joint.name() + suffix
    return [names[i] for i in sorted(names)]


def joint_path(
    plant,
    points,
    axes,
    arcs,
    q_start,
    *,
    instance=None,
    tool_frame="tool_tip",
    max_joint_step=MAX_JOINT_STEP,
    min_conditioning=MIN_CONDITIONING,
    tolerance=1e-7,
):
    """The arm's joint angles (n, nq) (rad, solve_tool_pose's order) with
    the tool tip at each of ``points`` (m, world, rows) and the tool axis
    along the matching row of ``axes`` (unit, world), each solved from the
    previous posture (the first from ``q_start``). ``arcs`` (m) are the
    stations' arc lengths along the edge, for the message.

    Raises PathBreak at the first station where the arm does not follow:
    the posture nearest the previous one is out of reach, or past a joint
    limit (named), or a joint turns by more than ``max_joint_step`` (rad)
    from the previous station (a wrist flip; the joint that turns most is
    named), or the conditioning of the tool's Jacobian falls below
    ``min_conditioning`` (named: the joint that moves most along the
    direction the Jacobian loses)."""
    instance = _arm_instance(plant, instance)
    tip = plant.GetFrameByName(tool_frame, instance)
    arm_idx = _arm_positions(plant, instance)
    names = joint_names(plant, instance)
    path, q = [], np.asarray(q_start, float)
    for p, axis, arc in zip(np.asarray(points, float), axes, arcs):
        target = _ToolTarget(np.asarray(p, float), _unit_axis(axis))
        q_next = _station(plant, tip, target, arm_idx, q, tolerance)
        if q_next is None:
            raise _unreachable(plant, tip, target, arm_idx, q, arc, names)
        step = np.abs(q_next - q)
        j = int(np.argmax(step))
        if step[j] > max_joint_step:
            raise PathBreak(
                f"at arc {arc * 1e3:.1f} mm along the edge the arm's joint "
                f"{names[j]!r} turns {step[j]:.2f} rad from the previous "
                f"station (more than {max_joint_step:g} rad: a wrist flip)",
                arc,
                names[j],
            )
        conditioning, j = _lost_direction(plant, tip, instance, q_next)
        if conditioning < min_conditioning:
            raise PathBreak(
                f"at arc {arc * 1e3:.1f} mm along the edge the arm passes "
                f"near a singular posture (Jacobian conditioning "
                f"{conditioning:.2g} < {min_conditioning:g}; joint "
                f"{names[j]!r} moves most along the direction it loses)",
                arc,
                names[j],
            )
        path.append(q_next)
        q = q_next
    return np.array(path)


def _full(plant, arm_idx, q):
    q_full = plant.GetDefaultPositions().copy()
    q_full[arm_idx] = q
    return q_full


def _station(plant, tip, target, arm_idx, q, tolerance, limits=True):
    """The arm's posture at ``target`` nearest q (None if not found).
    SNOPT can report failure when started at its own optimum (the first
    station is often the start): then from 1 mrad off it."""
    for nudge in (0.0, 1e-3):
        try:
            q_full = _solve_pose(
                plant, tip, target, arm_idx, q + nudge, tolerance, limits
            )
            return q_full[arm_idx]
        except RuntimeError:
            continue
    return None


def _unreachable(plant, tip, target, arm_idx, q, arc, names):
    """The PathBreak where no posture within the joint limits is found
    from q: the joint past its limit when the arm reaches the station
    without them, else out of reach."""
    q_free = _station(plant, tip, target, arm_idx, q, 1e-7, limits=False)
    if q_free is not None:
        lower = plant.GetPositionLowerLimits()[arm_idx]
        upper = plant.GetPositionUpperLimits()[arm_idx]
        excess = np.maximum(lower - q_free, q_free - upper)
        j = int(np.argmax(excess))
        if excess[j] > 0:
            bound = lower[j] if q_free[j] < lower[j] else upper[j]
            return PathBreak(
                f"at arc {arc * 1e3:.1f} mm along the edge the arm's joint "
                f"{names[j]!r} would pass its limit ({bound:.3g} rad) by "
                f"{excess[j]:.2f} rad",
                arc,
                names[j],
            )
    return PathBreak(
        f"at arc {arc * 1e3:.1f} mm along the edge the tool tip at "
        f"{np.round(target.p, 4).tolist()} m with the tool axis along "
        f"{np.round(_axis(target), 3).tolist()} is out of the arm's reach",
        arc,
        None,
    )


def _axis(target):
    return np.array([0.0, 0.0, 1.0]) if target.axis is None else target.axis


def _lost_direction(plant, tip, instance, q):
    """(sigma_min / sigma_max of the tool frame's spatial velocity
    Jacobian at q, the index of the joint with the largest share of the
    joint motion along the smallest singular direction)."""
    arm_idx = _arm_positions(plant, instance)
    J = tip_jacobian(plant, tip, _full(plant, arm_idx, q))
    _, sv, vt = np.linalg.svd(J)
    lost = vt[len(sv) - 1]  # past it (n > 6): J's null space
    return float(sv[-1] / sv[0]), int(np.argmax(np.abs(lost)))
