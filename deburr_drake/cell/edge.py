"""The part's edge as the scenario configures it (pure numpy): the real
part's zero-depth path (the plant's truth), the part the controller
believes in (``part_error``, ``faults.part_step``), the start position and
points on the edge for drawing."""

from __future__ import annotations

import copy

import numpy as np

from deburr_drake.config import Scenario
from deburr_drake.config.cell import PoseConfig
from deburr_drake.math.geometry import CircularContour, Contour, StraightContour
from deburr_drake.math.rigid import (
    believed_from_real,
    matrix_rpy,
    rpy_matrix,
    stepped_belief,
)

__all__ = [
    "make_contour",
    "straight_frame",
    "profile_center",
    "believed_scenario",
    "believed_contour",
    "believed_contour_step",
    "start_position",
    "edge_points",
]


def straight_frame(scenario: Scenario):
    """(edge midpoint on the wall face at the top, travel direction,
    material normal) of a straight edge."""
    part = scenario.part
    edge = part.edge
    mid = np.array(part.pose.xyz, float)
    mid[2] += edge.height
    tangent = np.array([np.cos(edge.heading), np.sin(edge.heading), 0.0])
    normal = np.array([tangent[1], -tangent[0], 0.0])  # material on the right
    return mid, tangent, normal


def profile_center(scenario: Scenario) -> np.ndarray:
    """(x, y, z) of a profile's origin at the height the cutter tip runs."""
    part, tool = scenario.part, scenario.tool
    center = np.array(part.pose.xyz, float)
    center[2] += part.edge.height - tool.engagement
    return center


def make_contour(scenario: Scenario, *, grow: float = 0.0) -> Contour:
    """The zero-depth path of the tool tip: the part's edge offset by the
    cutter radius, at the height where the cutter tip runs. ``grow`` (m):
    a profile grown outward by it (the believed part's radius error). A
    mesh edge: its ``EdgeContour`` (the part read once per file)."""
    part, tool = scenario.part, scenario.tool
    edge = part.edge
    if edge.kind == "mesh":  # the real part: moved by part_error
        return part.mesh_path(tool, part.real_pose(scenario.part_error))
    if edge.kind == "profile":
        return edge.profile_path(
            profile_center(scenario), tool.cutter_radius, grow=grow
        )
    if edge.kind == "straight":
        mid, tangent, normal = straight_frame(scenario)
        start = mid - tool.cutter_radius * normal - 0.5 * edge.length * tangent
        start[2] -= tool.engagement
        return StraightContour(start, tangent, normal, length=edge.length)
    center = np.array(part.pose.xyz, float)
    center[2] += edge.height - tool.engagement
    return CircularContour(
        center,
        edge.inner_radius - tool.cutter_radius,
        start_angle=edge.start_angle,
        direction=edge.direction,
    )


def believed_scenario(scenario: Scenario) -> Scenario:
    """The scenario with the part the controller believes in
    (``part_error`` applied to ``part``); the scenario itself
    when there is no error."""
    e = scenario.part_error
    if not e.moves() and e.radius == 0.0:
        return scenario
    believed = copy.deepcopy(scenario)
    real, part = scenario.part, believed.part
    believed.part_error = type(e)()
    if real.edge.kind == "mesh":  # part.pose is the believed pose
        return believed
    yaw = e.planar_yaw()
    part.pose.xyz = [p + d for p, d in zip(real.pose.xyz, e.offset)]
    part.edge.inner_radius += e.radius
    if real.edge.kind == "straight":
        part.edge.heading += yaw
    else:
        part.edge.start_angle += yaw
    if real.edge.kind == "profile":  # turned about part.pose.xyz
        c, s = np.cos(yaw), np.sin(yaw)
        part.edge.vertices = [
            [c * x - s * y, s * x + c * y] for x, y in real.edge.vertices
        ]
    return believed


def believed_contour(scenario: Scenario) -> Contour:
    """The zero-depth path on the part the controller believes in (a
    profile: moved, turned and grown by ``part_error``; a mesh edge: the
    file at ``part.pose``)."""
    grow = (
        scenario.part_error.radius
        if scenario.part.edge.kind == "profile"
        else 0.0
    )
    return make_contour(believed_scenario(scenario), grow=grow)


def believed_contour_step(scenario: Scenario):
    """(time (s), believed contour from then on) of ``faults.part_step``:
    the believed part's pose against the unmoved real part what it is
    against the stepped one (deburr_drake.math.rigid.stepped_belief);
    None without a step."""
    step = scenario.faults.part_step
    if not step.active():
        return None
    after = copy.deepcopy(scenario)
    e, part = scenario.part_error, scenario.part
    if not any(step.rpy) and part.edge.kind != "mesh":
        # A pure move of a planar part: the believed part moved back by it
        # (exactly, as the offsets subtract). A mesh part's belief is the
        # file at its nominal pose, which part_error does not move.
        after.part_error.offset = [x - d for x, d in zip(e.offset, step.offset)]
        return step.time, believed_contour(after)
    real = part.real_pose(e)
    X_WR = (rpy_matrix(real.rpy), np.asarray(real.xyz, float))
    if part.edge.kind == "mesh":
        X_WB = (rpy_matrix(part.pose.rpy), np.asarray(part.pose.xyz, float))
    else:
        X_WB = believed_from_real(X_WR, e.offset, [0.0, 0.0, e.planar_yaw()])
    R, p = stepped_belief(X_WR, X_WB, step.offset, step.rpy)
    if part.edge.kind == "mesh":
        pose = PoseConfig(
            xyz=[float(x) for x in p], rpy=[float(a) for a in matrix_rpy(R)]
        )
        return step.time, part.mesh_path(scenario.tool, pose)
    # The error against the (unturned) real part: a turn about the
    # vertical, as a planar part's.
    after.part_error.offset = [float(x) for x in p - X_WR[1]]
    after.part_error.yaw = 0.0
    after.part_error.rpy = [0.0, 0.0, float(matrix_rpy(R)[2])]
    return step.time, believed_contour(after)


def start_position(scenario: Scenario, contour=None) -> np.ndarray:
    """Tool tip at the contour start, ``initial_depth`` into the material."""
    contour = contour or make_contour(scenario)
    p = contour.point_at(0.0)
    return p + scenario.simulation.initial_depth * contour.n1(p)


def edge_points(scenario: Scenario, arc) -> np.ndarray:
    """Points (m, world) on the part's top edge at contour arc positions
    ``arc`` (m): where the chamfer is cut, for drawing."""
    contour = make_contour(scenario)
    part, tool = scenario.part, scenario.tool
    if part.edge.kind == "mesh":
        return np.array([contour.edge_point(s) for s in np.asarray(arc)])
    top = part.pose.xyz[2] + part.edge.height
    points = []
    for s in np.asarray(arc, float):
        p = contour.point_at(s)
        q = p + tool.cutter_radius * contour.n1(p)
        q[2] = top
        points.append(q)
    return np.array(points)
