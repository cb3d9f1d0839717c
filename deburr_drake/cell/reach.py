"""Whether the robot serves the cell: its model (deburr_drake.cell.robot)
and every point of the tool's path within reach."""

from __future__ import annotations

import copy
import math

import numpy as np

from deburr_drake.cell.arm import (
    MIN_CONDITIONING,
    SingularPose,
    _arm_positions,
    _starts,
    check_reach,
    path_conditioning,
    solve_tool_pose,
    tool_conditioning,
)
from deburr_drake.cell.description import notice
from deburr_drake.cell.edge import believed_contour, start_position
from deburr_drake.cell.joint_path import PathBreak, joint_path
from deburr_drake.cell.robot import (
    check_robot,
    ik_seed,
    make_robot_model,
    mount_pose,
)
from deburr_drake.config import ConfigError, Scenario

__all__ = ["check_part_in_reach"]


def _mm(distance: float) -> str:
    """A distance (m) in mm: one decimal, two digits below 0.1 mm."""
    mm = distance * 1e3
    return f"{mm:.1f}" if mm >= 0.1 else f"{mm:.2g}"


def _mtime(robot):
    """The model file's modification time (a file rewritten is checked
    again)."""
    import os

    try:
        return os.stat(robot.model).st_mtime_ns
    except (OSError, TypeError, ValueError):
        return None


#: The spindle's turn in the flange frame (robot.tool_mount.rpy, rad)
#: that points the tool along each axis of the flange frame.
_FLANGE_AXES = {
    "+z": [0.0, 0.0, 0.0],
    "+x": [0.0, math.pi / 2, 0.0],
    "-x": [0.0, -math.pi / 2, 0.0],
    "+y": [-math.pi / 2, 0.0, 0.0],
    "-y": [math.pi / 2, 0.0, 0.0],
    "-z": [math.pi, 0.0, 0.0],
}


def _reaches(robot, points):
    """Whether the arm with the tool frame of ``robot`` reaches every
    point (some posture, the tool vertical, the joint limits)."""
    model = make_robot_model(robot)
    try:
        miss = check_reach(
            model,
            points,
            instance=model.GetFrameByName(robot.tool_frame).model_instance(),
            q_guess=lambda p: ik_seed(robot, p),
            tool_frame=robot.tool_frame,
        )
    except SingularPose:
        return False
    return miss is None or miss[2] == 0.0


def _axis_that_reaches(robot, point):
    """(axis name, robot with the spindle turned along it) of the first
    axis of the flange frame along which the tool reaches ``point``, the
    mount's offset kept; None if none does (or the model holds its own
    tool)."""
    if not robot.flange_frame:
        return None
    current = mount_pose(robot).rotation()
    for axis, rpy in _FLANGE_AXES.items():
        turned = copy.deepcopy(robot)
        turned.tool_mount.rpy = [round(a, 6) for a in rpy]
        turn = current.inverse() @ mount_pose(turned).rotation()
        if turn.IsNearlyIdentity(1e-6):
            continue
        if _reaches(turned, [point]):
            return axis, turned
    return None


def _shown_mount(mount) -> str:
    def numbers(values):
        return "[" + ", ".join(f"{v:.7g}" for v in values) + "]"

    return f"{{xyz: {numbers(mount.xyz)}, rpy: {numbers(mount.rpy)}}}"


def _axis_error(robot, where, p, distance, points):
    """The ConfigError naming robot.tool_mount when the tool turned along
    another axis of the flange frame reaches the point ``p`` the mount as
    written does not; None when the axis does not explain it."""
    found = _axis_that_reaches(robot, p)
    if found is None:
        return None
    axis, turned = found
    z = mount_pose(robot).rotation().matrix()[:, 2]
    whole = (
        "every point of the path"
        if _reaches(turned, points)
        else "that point (not every point of the path)"
    )
    return ConfigError(
        f"robot.tool_mount = {_shown_mount(robot.tool_mount)} is invalid: "
        f"the tool axis, not the distance, puts {where}, tool tip at "
        f"{np.round(p, 4).tolist()} m, out of reach ({_mm(distance)} mm "
        "beyond the nearest reachable tool position with the spindle along "
        f"{np.round(z, 3).tolist()} of robot.flange_frame "
        f"{robot.flange_frame!r}); with the tool along {axis} of that "
        f"frame the arm reaches {whole}: the tool axis points along {axis} "
        "of the flange frame: allowed robot.tool_mount: "
        f"{_shown_mount(turned.tool_mount)} (the spindle's pose in the "
        "flange frame, m and rad)"
    )


def _singular_error(robot, scenario, where, e: SingularPose):
    """The ConfigError for a path point the tool reaches only near a
    singular posture: the part's position (or the tool's mount) is what
    to change."""
    return ConfigError(
        f"part.pose.xyz = {list(scenario.part.pose.xyz)} is invalid: "
        f"{where}, tool tip at {np.round(e.point, 4).tolist()} m, is "
        "reached with the tool vertical only near a singular posture of "
        f"the arm (Jacobian conditioning {e.conditioning:.2g} < "
        f"{MIN_CONDITIONING:g}: the designed gains and the J^T law lose a "
        "direction there): allowed a part position (or a robot.tool_mount "
        f"= {_shown_mount(robot.tool_mount)} turned) whose edge the arm "
        "reaches away from its singular postures"
    )


def _check_path_conditioning(model, instance, robot, points, place):
    """ConfigError naming robot.ik_seed when the arm, moving along the
    path from the start pose the seed gives, passes near a singular
    posture."""
    from deburr_drake.cell.arm import solve_tool_pose

    q0 = solve_tool_pose(
        model,
        points[0],
        instance=instance,
        q_guess=ik_seed(robot, points[0]),
        tool_frame=robot.tool_frame,
    )
    conditioning = path_conditioning(
        model, points, q0, instance=instance, tool_frame=robot.tool_frame
    )
    k = int(np.argmin(conditioning))
    if conditioning[k] >= MIN_CONDITIONING:
        return
    raise ConfigError(
        f"robot.ik_seed = {list(robot.ik_seed)} is invalid: from the start "
        f"pose it gives ({np.round(q0, 3).tolist()} rad) the arm passes "
        f"near a singular posture at {place(k)}, tool tip at "
        f"{np.round(points[k], 4).tolist()} m (Jacobian conditioning "
        f"{conditioning[k]:.2g} < {MIN_CONDITIONING:g}): allowed a seed "
        "whose posture stays away from it along the edge (or a "
        "part.pose.xyz that keeps the edge there)"
    )


#: Stations of the joint path along a 3-D edge (m apart at most), and the
#: fewest.
_STATION_SPACING = 0.002
_MIN_STATIONS = 24


#: Turns (rad) of the arm's last joint off the seed tried when the arm
#: does not follow the edge from the posture nearest the seed: the cut
#: does not depend on the tool's spin about its axis, so the arm may take
#: any; the last joint spins the tool about it the most. Then a few
#: seeded postures within the joint limits.
_SPIN_TURNS = np.linspace(-np.pi, np.pi, 8, endpoint=False)[1:]
_OTHER_STARTS = 8


def _shown_pose(pose) -> str:
    return f"{{xyz: {list(pose.xyz)}, rpy: {list(pose.rpy)}}}"


def _edge_stations(scenario: Scenario, contour):
    """(the start point, the stations' points, axes and arc lengths from
    the start) of the joint path along ``contour``."""
    start = start_position(scenario, contour)
    s0 = float(contour.arc_position(start))
    end = s0 + contour.length if contour.closed else contour.length
    count = max(_MIN_STATIONS, int(np.ceil((end - s0) / _STATION_SPACING)))
    arcs = np.linspace(s0, end, count + 1)
    wrapped = np.mod(arcs, contour.length) if contour.closed else arcs
    axes = [contour.tool_axis_at(s) for s in wrapped]
    points = [start] + [contour.point_at(s) for s in wrapped]
    return (
        start,
        points,
        [contour.tool_axis_at(s0)] + axes,
        np.concatenate([[s0], arcs]) - s0,
    )


def _follow(model, robot, instance, stations, q_guess):
    """(the start posture nearest ``q_guess``, the joint path from it);
    PathBreak or RuntimeError as joint_path and solve_tool_pose."""
    start, points, axes, arcs = stations
    q0 = solve_tool_pose(
        model,
        start,
        instance=instance,
        q_guess=q_guess,
        tool_frame=robot.tool_frame,
        tool_axis=axes[0],
    )
    path = joint_path(
        model,
        points,
        axes,
        arcs,
        q0,
        instance=instance,
        tool_frame=robot.tool_frame,
    )
    return q0, path


def _free_spin(model, robot, instance, stations):
    """The start posture, among those from the seed with the arm's last
    joint turned by ``_SPIN_TURNS`` (the tool spun about its axis) and
    ``_OTHER_STARTS`` seeded ones, from which the arm follows the whole
    edge with the most margin to its joint limits (rad, the least along
    the path), then the best conditioning at the start; None if none
    does."""
    arm = _arm_positions(model, instance)
    lower = model.GetPositionLowerLimits()[arm]
    upper = model.GetPositionUpperLimits()[arm]
    seed = ik_seed(robot, stations[0])
    if seed is None:
        seed = model.GetPositions(model.CreateDefaultContext(), instance)
    spun = [np.array(seed, float) for _ in _SPIN_TURNS]
    for q_guess, turn in zip(spun, _SPIN_TURNS):
        q_guess[-1] += turn
    best = None
    for q_guess in spun + _starts(model, arm, _OTHER_STARTS):
        try:
            q0, path = _follow(model, robot, instance, stations, q_guess)
        except (PathBreak, RuntimeError):
            continue
        margin = float(np.min(np.minimum(path - lower, upper - path)))
        score = (
            round(margin, 2),
            tool_conditioning(
                model, q0, instance=instance, tool_frame=robot.tool_frame
            ),
        )
        if best is None or score > best[0]:
            best = (score, q0)
    return None if best is None else best[1]


def _check_edge_path(scenario: Scenario, model, contour):
    """None when the arm, from the start pose ``robot.ik_seed`` gives,
    follows the edge continuously with the tool along its axis
    (deburr_drake.cell.joint_path); else the start posture with the tool
    spun about its axis (``_free_spin``) from which it does; else a
    ConfigError in one line naming the arc length (mm) and the joint
    where it does not from the seed's."""
    robot = scenario.robot
    instance = model.GetFrameByName(robot.tool_frame).model_instance()
    stations = _edge_stations(scenario, contour)
    try:
        _follow(model, robot, instance, stations, ik_seed(robot, stations[0]))
        return None
    except (PathBreak, RuntimeError) as e:
        refusal = e
    q0 = _free_spin(model, robot, instance, stations)
    if q0 is not None:
        notice(
            "the arm does not follow the edge from the posture nearest "
            f"robot.ik_seed ({refusal}); it does from "
            f"{np.round(q0, 3).tolist()} rad (the tool spun about its "
            "axis, or another posture), chosen for the most margin to the "
            "joint limits along the edge: the run starts there"
        )
        return q0
    if isinstance(refusal, SingularPose):
        raise ConfigError(
            f"part.pose = {_shown_pose(scenario.part.pose)} is invalid: the "
            f"arm meets the edge's start only near a singular posture "
            f"({refusal}), from the seed, with the tool spun about its axis "
            "and from other postures: allowed a part pose (or "
            "part.edge.tool_face / tool_rule) whose tool axis the arm holds "
            "away from its singular postures"
        ) from None
    if isinstance(refusal, PathBreak):
        raise ConfigError(
            f"part.edge is not followed by the arm: {refusal} (from the "
            f"start pose robot.ik_seed = {list(robot.ik_seed)} gives, nor "
            "with the tool spun about its axis): allowed a part.pose, "
            "part.edge.tool_rule or seed with which the arm follows the "
            "whole edge"
        ) from None
    raise ConfigError(
        f"part.edge is out of the arm's reach at its start (arc 0.0 "
        f"mm): {refusal}: allowed a part.pose or robot.ik_seed from which "
        "the arm reaches it with the tool along the edge's axis"
    ) from None


#: Scenarios already checked (the robot, part and tool as text): a diagram
#: built again for the same cell (the analysis builds many) checks once.
_REACHED = {}


def _reach_key(scenario: Scenario, samples: int) -> str:
    """What a reach check depends on: a cell checked once is remembered."""
    robot = scenario.robot
    return repr(
        (
            robot,
            _mtime(robot),
            scenario.part,
            scenario.part_error,
            scenario.tool,
            samples,
        )
    )


def check_part_in_reach(
    scenario: Scenario, contour=None, *, samples=24, model=None
):
    """Raises ConfigError if the robot cannot serve the cell
    (deburr_drake.cell.robot.check_robot: the model file, its frames, its
    joints), or naming the first point of the tool's path (the start, then
    ``samples`` points along the edge) the arm cannot reach with the tool
    vertical, and how far out of reach it is; when the tool turned along
    another axis of the flange frame (the spindle's mount) reaches it, the
    error names ``robot.tool_mount`` and that axis instead. Along a 3-D
    edge (``contour.varying_frame``) the arm's whole joint path with the
    tool along the edge's axis is checked instead (``_check_edge_path``:
    None, or the start posture it is followed from if not the seed's,
    returned). ``model``: check_robot's, if the caller has it."""
    robot = scenario.robot
    key = _reach_key(scenario, samples) if contour is None else None
    if key is not None and key in _REACHED:
        return _REACHED[key]
    model = check_robot(robot) if model is None else model
    if robot.model == "cartesian_tool":
        return  # the Cartesian tool reaches everywhere
    contour = contour or believed_contour(scenario)
    if contour.varying_frame:
        q_start = _check_edge_path(scenario, model, contour)
        if key is not None:
            _REACHED[key] = q_start
        return q_start
    arcs = np.linspace(
        0.0, contour.length, samples, endpoint=not contour.closed
    )
    points = [start_position(scenario, contour)] + [
        contour.point_at(s) for s in arcs
    ]
    instance = model.GetFrameByName(robot.tool_frame).model_instance()

    def place(k):
        return (
            "the start point"
            if k == 0
            else f"the edge point at arc {arcs[k - 1] * 1e3:.1f} mm"
        )

    try:
        miss = check_reach(
            model,
            points,
            instance=instance,
            q_guess=lambda p: ik_seed(robot, p),
            tool_frame=robot.tool_frame,
        )
    except SingularPose as e:
        raise _singular_error(robot, scenario, place(e.index), e) from None
    if miss is None:
        _check_path_conditioning(model, instance, robot, points, place)
        if key is not None:
            _REACHED[key] = None
        return None
    if miss is not None:
        k, p, distance, q_other = miss
        where = place(k)
        if q_other is not None:
            raise ConfigError(
                f"robot.ik_seed = {list(robot.ik_seed)} is invalid: {where},"
                f" tool tip at {np.round(p, 4).tolist()} m, is in reach, but "
                "the inverse kinematics (tool vertical, joint limits) does "
                "not find it from the seed nor along the edge; it does from "
                f"{np.round(q_other, 3).tolist()} rad: allowed a seed "
                "near that posture"
            )
        axis_error = _axis_error(robot, where, p, distance, points)
        if axis_error is not None:
            raise axis_error
        raise ConfigError(
            f"part.pose.xyz = {list(scenario.part.pose.xyz)} is out of the "
            f"arm's reach: {where}, tool tip at {np.round(p, 4).tolist()} m, "
            f"is {_mm(distance)} mm beyond the nearest reachable tool "
            "position (tool vertical, joint limits): allowed a part whose "
            f"edge the arm reaches (arm5: [0.40, 0.0, 0.0]; {robot.model!r}"
            ": see its robot.ik_seed and the model's joint limits)"
        )
