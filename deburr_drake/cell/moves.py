"""Moves between a job's cuts, planned with Drake in free space.

A move joins the end of one cut to the start of the next: retract along
the tool axis, transit, approach along the next cut's tool axis. The cell
for planning is a plant of the arm, its spindle and cutter, and the part as
convex pieces (``deburr_drake.math.convex_pieces``: Drake's distance
queries see a mesh as its hull, which would fill the part's bores and
slots). The arm model carries no collision geometry of its own, so its
drawn shapes are its collision shapes; the arm's own links are not checked
against each other (its joint limits keep them apart), only against the
part.

* The waypoints (retract and approach points): ``InverseKinematics`` with
  the tool tip at the point, the tool axis along the cut's, and
  ``MinimumDistanceLowerBoundConstraint`` at the clearance, nearest the
  cut's own posture.
* The transit: ``KinematicTrajectoryOptimization`` (a B-spline in joint
  space, at rest at both ends, within the joint position and velocity
  limits) with the minimum-distance constraint at samples along the path,
  started from the straight line in joint space; where that stalls (the
  tool turning over far, vertical to horizontal), started again through a
  posture 0.1 m above the two ends with the tool axis halfway.
* The check: a ``SceneGraphCollisionChecker`` on the transit at a fine
  joint step, and the clearance (signed distance to the part) along the
  whole move at as fine a step. On the retract and approach segments the
  cutter itself is in the cut at one end, so its own distance is left out
  there; the spindle's and the arm's are not.

Every program is solved by IPOPT, the wheel's free NLP solver: the pip
wheel enables SNOPT too (``SnoptSolver().available()`` is True), and
``InverseKinematics`` left to choose would use it.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
import time
from typing import NamedTuple

import numpy as np
from pydrake.geometry import (
    CollisionFilterDeclaration,
    Convex,
    Cylinder,
    GeometrySet,
    ProximityProperties,
)
from pydrake.math import RigidTransform
from pydrake.multibody.inverse_kinematics import (
    InverseKinematics,
    MinimumDistanceLowerBoundConstraint,
)
from pydrake.planning import (
    KinematicTrajectoryOptimization,
    RobotDiagramBuilder,
    SceneGraphCollisionChecker,
)
from pydrake.solvers import IpoptSolver
from pydrake.trajectories import BsplineTrajectory

from deburr_drake.cell.robot import add_robot, finalize
from deburr_drake.config import RobotConfig, ToolConfig

__all__ = [
    "Move",
    "MovePlanningError",
    "MoveSettings",
    "PlanningCell",
    "clearance",
    "least_clearance",
    "make_planning_cell",
    "plan_move",
    "tip_positions",
    "waypoint",
]


class MovePlanningError(RuntimeError):
    """A move that cannot be planned: one line naming the edges and where."""


@dataclass(frozen=True)
class MoveSettings:
    """How a move between two cuts is planned."""

    approach: float = 0.02  # m, above the next cut's start, along its axis
    retract: float = 0.02  # m, above the cut's end, along its axis
    clearance: float = 0.005  # m, least distance to the part while moving
    check_step: float = 0.005  # rad, the collision checker's joint step
    samples: int = 25  # -, distance constraints along the transit
    control_points: int = 10  # -, of the transit's B-spline
    # rad/s, each joint's speed on a transit, at most its limit
    max_joint_speed: float = 0.5
    max_joint_acceleration: float = 2.0  # rad/s^2, on a transit
    # m/s, the tool's speed along its axis on the retract and approach
    axial_speed: float = 0.02


class PlanningCell(NamedTuple):
    """The arm, its tool and the part's convex pieces, for planning."""

    diagram: object  # RobotDiagram
    plant: object  # MultibodyPlant (in diagram)
    instance: object  # the robot's ModelInstanceIndex
    tool_frame: object  # Frame, the tool tip, +z up the tool
    checker: SceneGraphCollisionChecker
    cutter: object  # GeometryId of the cutter
    # the diagram's Context the clearance queries pose the robot in (one
    # for every query: making one costs a third of a query)
    context: object


class Move(NamedTuple):
    """A planned move: the joint path and what it measures."""

    path: np.ndarray  # rad, (k, n): retract, transit, approach, sampled
    times: np.ndarray  # s, (k,), at the transit's planned timing
    transit: BsplineTrajectory  # rad, the transit in joint space
    duration_s: float  # s, retract, transit and approach
    travel_m: float  # m, the tool tip's path length
    min_clearance_m: float  # m, least distance to the part on the move
    planning_time_s: float  # s, wall time to plan and check it


def _collide_as_drawn(plant, scene_graph, instance):
    """The robot's drawn shapes registered as its collision shapes (the
    model has none; before Finalize)."""
    inspector = scene_graph.model_inspector()
    for index in plant.GetBodyIndices(instance):
        body = plant.get_body(index)
        for gid in plant.GetVisualGeometriesForBody(body):
            plant.RegisterCollisionGeometry(
                body,
                inspector.GetPoseInFrame(gid),
                inspector.GetShape(gid),
                inspector.GetName(gid) + "_collision",
                ProximityProperties(),
            )


def make_planning_cell(
    robot: RobotConfig, tool: ToolConfig, pieces, *, settings=MoveSettings()
) -> PlanningCell:
    """The planning cell of ``robot`` with ``tool``'s cutter and the part
    as the convex ``pieces`` (vertex arrays, m, world)."""
    builder = RobotDiagramBuilder(time_step=0.0)
    plant, scene_graph = builder.plant(), builder.scene_graph()
    # The arm and its tool: drawn shapes as collision shapes, the cutter.
    instance = add_robot(plant, robot)
    _collide_as_drawn(plant, scene_graph, instance)
    frame = plant.GetFrameByName(robot.tool_frame, instance)
    cutter = plant.RegisterCollisionGeometry(
        frame.body(),
        frame.GetFixedPoseInBodyFrame()
        @ RigidTransform([0.0, 0.0, tool.cutter_length / 2]),
        Cylinder(tool.cutter_radius, tool.cutter_length),
        "cutter",
        ProximityProperties(),
    )
    # The part: its convex pieces, fixed in the world.
    for i, points in enumerate(pieces):
        plant.RegisterCollisionGeometry(
            plant.world_body(),
            RigidTransform(),
            Convex(np.asarray(points, float).T, f"part_piece_{i}"),
            f"part_piece_{i}",
            ProximityProperties(),
        )
    finalize(plant)
    # Only the robot against the part: its links not against each other.
    robot_geometry = [
        gid
        for index in plant.GetBodyIndices(instance)
        for gid in plant.GetCollisionGeometriesForBody(plant.get_body(index))
    ]
    scene_graph.collision_filter_manager().Apply(
        CollisionFilterDeclaration().ExcludeWithin(GeometrySet(robot_geometry))
    )
    diagram = builder.Build()
    checker = SceneGraphCollisionChecker(
        model=diagram,
        robot_model_instances=[instance],
        edge_step_size=settings.check_step,
        env_collision_padding=0.0,
        self_collision_padding=0.0,
    )
    return PlanningCell(
        diagram,
        plant,
        instance,
        frame,
        checker,
        cutter,
        diagram.CreateDefaultContext(),
    )


def clearance(cell: PlanningCell, q, *, cutter=True, within=0.5) -> float:
    """m, the least signed distance between the robot (with its cutter
    unless ``cutter`` is False) and the part at ``q``; ``within`` if
    nothing is nearer than that."""
    return _nearest(cell, q, cutter=cutter, within=within)[0]


def least_clearance(cell: PlanningCell, qs, *, cutter=True):
    """(m, index, shape) along the postures ``qs``: the least distance
    (:func:`clearance`) and None, "" when the robot stays out of the part;
    else how deep (negative) it stands in it at the first posture that
    does, that posture's index and the robot's shape there."""
    least = math.inf
    for i, q in enumerate(qs):
        distance, shape = _nearest(cell, q, cutter=cutter)
        if distance < 0.0:
            return distance, i, shape
        least = min(least, distance)
    return least, None, ""


def _nearest(cell: PlanningCell, q, *, cutter=True, within=0.5):
    """(m, the least distance as :func:`clearance`; the robot's shape
    there, by name, or "")."""
    plant_context = cell.plant.GetMyContextFromRoot(cell.context)
    cell.plant.SetPositions(plant_context, q)
    query = cell.plant.get_geometry_query_input_port().Eval(plant_context)
    pairs = [
        p
        for p in query.ComputeSignedDistancePairwiseClosestPoints(within)
        if cutter or cell.cutter not in (p.id_A, p.id_B)
    ]
    if not pairs:
        return float(within), ""
    pair = min(pairs, key=lambda p: p.distance)
    inspector = query.inspector()
    names = [inspector.GetName(g) for g in (pair.id_A, pair.id_B)]
    shape = next((n for n in names if "part_piece" not in n), "")
    # a scoped name (arm6::spindle_collision) told as the shape's own
    return float(pair.distance), shape.split("::")[-1].split("_collision")[0]


def _solve(prog, what):
    result = IpoptSolver().Solve(prog)
    if not result.is_success():
        raise MovePlanningError(f"{what}: {result.get_solution_result()}")
    return result


def waypoint(cell: PlanningCell, point, axis, q_near, gap: float) -> np.ndarray:
    """Joint angles with the tool tip at ``point`` (m, world), the tool
    axis along ``axis`` (unit, world, away from the part), every shape
    ``gap`` (m) or more from the part, nearest ``q_near``
    (MovePlanningError if none is found)."""
    context = cell.diagram.CreateDefaultContext()
    plant_context = cell.plant.GetMyContextFromRoot(context)
    ik = InverseKinematics(cell.plant, plant_context, with_joint_limits=True)
    world = cell.plant.world_frame()
    point = np.asarray(point, float)
    ik.AddPositionConstraint(cell.tool_frame, [0, 0, 0], world, point, point)
    # The axis by a point 0.1 m up it (an angle constraint's gradient is
    # undefined at zero angle, where IPOPT then stalls).
    up = point + 0.1 * np.asarray(axis, float)
    slack = np.full(3, 1e-5)
    ik.AddPositionConstraint(
        cell.tool_frame, [0, 0, 0.1], world, up - slack, up + slack
    )
    prog = ik.get_mutable_prog()
    q = ik.q()
    prog.AddQuadraticErrorCost(np.eye(len(q)), q_near, q)
    # First the pose alone: from the cut's posture, where the cutter
    # touches the part and the distance's gradient is undefined, the
    # solvers stop at once.
    prog.SetInitialGuess(q, q_near)
    result = _solve(prog, "no posture there within the joint limits")
    ik.AddMinimumDistanceLowerBoundConstraint(gap, 0.05)
    prog.SetInitialGuess(q, result.GetSolution(q))
    result = _solve(prog, "no posture there with the clearance")
    return result.GetSolution(q)


def _transit(
    cell: PlanningCell, q_a, q_b, settings: MoveSettings, extra=(), via=None
):
    """The transit from ``q_a`` to ``q_b`` (both at rest), the distance
    constraint at ``settings.samples`` points and at the path parameters
    ``extra`` (in [0, 1]), started from the straight line in joint space
    (through the posture ``via`` when given)."""
    plant = cell.plant
    n = plant.num_positions()
    trajopt = KinematicTrajectoryOptimization(n, settings.control_points)
    prog = trajopt.get_mutable_prog()
    trajopt.AddDurationCost(1.0)
    trajopt.AddPathLengthCost(1.0)
    trajopt.AddPositionBounds(
        plant.GetPositionLowerLimits(), plant.GetPositionUpperLimits()
    )
    speed = np.minimum(plant.GetVelocityUpperLimits(), settings.max_joint_speed)
    trajopt.AddVelocityBounds(-speed, speed)
    accel = np.full(n, settings.max_joint_acceleration)
    trajopt.AddAccelerationBounds(-accel, accel)
    trajopt.AddDurationConstraint(0.05, 60.0)
    trajopt.AddPathPositionConstraint(q_a, q_a, 0.0)
    trajopt.AddPathPositionConstraint(q_b, q_b, 1.0)
    zero = np.zeros(n)
    trajopt.AddPathVelocityConstraint(zero, zero, 0.0)
    trajopt.AddPathVelocityConstraint(zero, zero, 1.0)
    # The straight line in joint space (through via), at the speed limit,
    # to start from.
    if via is None:
        line = np.linspace(q_a, q_b, settings.control_points).T
        span = np.abs(q_b - q_a)
    else:
        half = settings.control_points // 2
        line = np.vstack(
            [
                np.linspace(q_a, via, half, endpoint=False),
                np.linspace(via, q_b, settings.control_points - half),
            ]
        ).T
        span = np.abs(via - q_a) + np.abs(q_b - via)
    duration = max(1.0, float(np.max(span / speed)) * 1.5)
    guess = BsplineTrajectory(
        trajopt.basis(),
        [line[:, [i]] for i in range(settings.control_points)],
    )
    trajopt.SetInitialGuess(guess)
    prog.SetInitialGuess(trajopt.duration(), duration)
    context = cell.diagram.CreateDefaultContext()
    plant_context = plant.GetMyContextFromRoot(context)
    constraint = MinimumDistanceLowerBoundConstraint(
        plant, settings.clearance, plant_context, None, 0.05
    )
    for s in np.union1d(np.linspace(0.0, 1.0, settings.samples), extra):
        trajopt.AddPathPositionConstraint(constraint, s)
    result = _solve(prog, "no collision-free transit")
    return trajopt.ReconstructTrajectory(result)


def _line(q_a, q_b, step):
    count = max(2, int(np.ceil(np.max(np.abs(q_b - q_a)) / step)) + 1)
    return np.linspace(q_a, q_b, count)


def tip_positions(cell: PlanningCell, path) -> np.ndarray:
    """m, (k, 3): the tool tip in the world at each row of ``path`` (joint
    angles, rad)."""
    context = cell.plant.CreateDefaultContext()
    tips = []
    for q in path:
        cell.plant.SetPositions(context, q)
        tips.append(
            cell.tool_frame.CalcPoseInWorld(context).translation().copy()
        )
    return np.reshape(tips, (-1, 3))


def _tip_travel(cell: PlanningCell, path) -> float:
    tips = tip_positions(cell, path)
    return float(np.sum(np.linalg.norm(np.diff(tips, axis=0), axis=1)))


def _transit_or_via(cell, cut_end, next_start, segments, settings, label):
    """:func:`_clear_transit` from the straight line in joint space, or,
    where that local program stalls (the tool turning over far, vertical
    to horizontal), started again through a posture above the part with
    the axis halfway."""
    try:
        return _clear_transit(cell, segments, settings, label)
    except MovePlanningError as e:
        via = _via(cell, cut_end, next_start, segments, settings)
        if via is None:
            raise
        try:
            return _clear_transit(cell, segments, settings, label, via=via)
        except MovePlanningError:
            raise MovePlanningError(
                f"{e}, nor through a posture {_VIA_RISE * 1e3:.0f} mm above "
                "the two ends"
            ) from None


def plan_move(
    cell: PlanningCell,
    cut_end,
    next_start,
    *,
    settings: MoveSettings = MoveSettings(),
    label: str = "move",
) -> Move:
    """The move from ``cut_end`` to ``next_start``, each (tip point m,
    tool axis, joint angles rad) of a cut: retract ``settings.retract``
    up the first axis, transit, approach from ``settings.approach`` up the
    second. MovePlanningError (one line, starting with ``label``) names the
    segment that cannot be planned or that the check refuses."""
    started = time.perf_counter()
    q_a, q_b = cut_end[2], next_start[2]
    segments = _waypoints(cell, cut_end, next_start, settings, label)
    transit, times, middle, distances = _transit_or_via(
        cell, cut_end, next_start, segments, settings, label
    )
    ends = (transit.start_time(), transit.end_time())
    step = settings.check_step
    retract = _line(np.asarray(q_a), segments["retract"], step)
    approach = _line(segments["approach"], np.asarray(q_b), step)
    # The clearance along the move; the cutter's own left out where it is
    # in the cut, at the retract's start and the approach's end.
    least = float(np.min(distances))
    if least < 0.0:
        i = int(np.argmin(distances))
        raise MovePlanningError(
            f"{label}: transit: the {_nearest(cell, middle[i])[1]} enters "
            f"the part at {times[i] - ends[0]:.3g} s of "
            f"{ends[1] - ends[0]:.3g} s ({-least * 1e3:.2g} mm deep there)"
        )
    for name, qs in (("retract", retract), ("approach", approach)):
        distance, i, shape = least_clearance(cell, qs, cutter=False)
        if i is not None:
            raise MovePlanningError(
                f"{label}: {name}: the {shape} enters the part "
                f"{100 * i / max(1, len(qs) - 1):.0f} % along it "
                f"({-distance * 1e3:.2g} mm deep there)"
            )
        least = min(least, distance)
    side = [
        settings.retract / settings.axial_speed,
        settings.approach / settings.axial_speed,
    ]
    path = np.vstack([retract, middle, approach])
    times = np.concatenate(
        [
            np.linspace(0.0, side[0], len(retract)),
            side[0] + times - ends[0],
            side[0]
            + ends[1]
            - ends[0]
            + np.linspace(0.0, side[1], len(approach)),
        ]
    )
    return Move(
        path=path,
        times=times,
        transit=transit,
        duration_s=float(times[-1]),
        travel_m=_tip_travel(cell, path),
        min_clearance_m=least,
        planning_time_s=time.perf_counter() - started,
    )


def _waypoints(cell, cut_end, next_start, settings, label):
    """{"retract": q, "approach": q}: the postures ``settings.retract`` up
    the first cut's tool axis and ``settings.approach`` up the next's."""
    segments = {}
    for name, (p, axis, q), distance in (
        ("retract", cut_end, settings.retract),
        ("approach", next_start, settings.approach),
    ):
        try:
            segments[name] = waypoint(
                cell,
                np.asarray(p) + distance * np.asarray(axis),
                axis,
                q,
                settings.clearance,
            )
        except MovePlanningError as e:
            raise MovePlanningError(f"{label}: {name} point: {e}") from None
    return segments


def _clear_transit(cell, segments, settings, label, via=None):
    """``_checked_transit``, then checked by the collision checker edge
    by edge (MovePlanningError where it collides)."""
    transit, times, middle, distances = _checked_transit(
        cell, segments, settings, label, via=via
    )
    end = transit.end_time()
    for i, (a, b) in enumerate(zip(middle[:-1], middle[1:])):
        if not cell.checker.CheckEdgeCollisionFree(a, b):
            raise MovePlanningError(
                f"{label}: transit collides at {times[i]:.3g} s of "
                f"{end:.3g} s (SceneGraphCollisionChecker)"
            )
    return transit, times, middle, distances


#: m, how far above the higher of a move's ends its via posture's tip is
_VIA_RISE = 0.10


def _via(cell, cut_end, next_start, segments, settings):
    """A posture between a move's ends for its transit to pass through:
    the tool tip ``_VIA_RISE`` above the higher of the retract and
    approach points, halfway between them, the tool axis halfway between
    the two cuts' (or up), clear of the part; None if there is none."""
    ends = [
        np.asarray(p) + d * np.asarray(axis)
        for (p, axis, _), d in (
            (cut_end, settings.retract),
            (next_start, settings.approach),
        )
    ]
    point = 0.5 * (ends[0] + ends[1])
    point[2] = max(ends[0][2], ends[1][2]) + _VIA_RISE
    axis = np.asarray(cut_end[1]) + np.asarray(next_start[1])
    norm = np.linalg.norm(axis)
    axis = axis / norm if norm > 1e-6 else np.array([0.0, 0.0, 1.0])
    q_near = 0.5 * (segments["retract"] + segments["approach"])
    try:
        return waypoint(cell, point, axis, q_near, settings.clearance)
    except MovePlanningError:
        return None


def _checked_transit(cell, segments, settings, label, rounds=3, via=None):
    """The transit between the retract and the approach points, sampled
    at ``settings.check_step``: (trajectory, times, q, clearances). Where
    the clearance between the constraint's points dips under
    ``settings.clearance``, solved again with the constraint there too
    (up to ``rounds`` times). ``via``: a posture the first guess passes
    through."""
    extra = np.zeros(0)
    for _ in range(rounds):
        try:
            transit = _transit(
                cell,
                segments["retract"],
                segments["approach"],
                settings,
                extra,
                via,
            )
        except MovePlanningError as e:
            raise MovePlanningError(f"{label}: transit: {e}") from None
        t0, t1 = transit.start_time(), transit.end_time()
        count = max(
            2, int(np.ceil(_max_joint_travel(transit) / settings.check_step))
        )
        times = np.linspace(t0, t1, count + 1)
        q = np.array([transit.value(t).ravel() for t in times])
        distances = np.array([clearance(cell, x) for x in q])
        low = (times[distances < settings.clearance] - t0) / (t1 - t0)
        if len(low) == 0:
            break
        extra = np.union1d(extra, low[:: max(1, len(low) // 10)])
    return transit, times, q, distances


def _max_joint_travel(trajectory) -> float:
    """rad, the largest joint travel along ``trajectory`` (a fine
    sampling's total variation)."""
    t = np.linspace(trajectory.start_time(), trajectory.end_time(), 200)
    q = np.array([trajectory.value(s).ravel() for s in t])
    return float(np.max(np.sum(np.abs(np.diff(q, axis=0)), axis=0)))
