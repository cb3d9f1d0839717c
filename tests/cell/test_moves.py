"""Moves between a job's cuts, planned with Drake on the job's block
(models/parts/block.stl) in front of the 6-joint arm: from the end of the
bore's cut to the start of the slot's."""

from pathlib import Path

import numpy as np
import pytest

from deburr_drake.cell.arm import solve_tool_pose
from deburr_drake.cell.moves import (
    MovePlanningError,
    MoveSettings,
    clearance,
    make_planning_cell,
    plan_move,
)
from deburr_drake.cell.robot import check_robot, ik_seed
from deburr_drake.config import EdgeConfig, PoseConfig, load_scenario
from deburr_drake.math.convex_pieces import convex_pieces, placed_pieces
from deburr_drake.math.mesh_part import load_part

BLOCK = Path(__file__).resolve().parents[2] / "models" / "parts" / "block.stl"
POSE = PoseConfig(xyz=[0.95, 0.0, 0.50], rpy=[0.0, 0.0, 0.0])


@pytest.fixture(scope="module")
def cell():
    scenario = load_scenario("paper_6dof")
    part = load_part(BLOCK, units="mm", xyz=POSE.xyz, rpy=POSE.rpy)
    pieces = placed_pieces(convex_pieces(BLOCK, write=False), part, "mm")
    return scenario, make_planning_cell(scenario.robot, scenario.tool, pieces)


def _cut_ends(scenario, near):
    """(tip, tool axis, q) at the start and at the end of the cut of the
    block's edge nearest ``near`` (m, part frame), the tool on the top."""
    edge = EdgeConfig(
        kind="mesh", file=str(BLOCK), units="mm", near=near, tool_face=[0, 0, 1]
    )
    contour = edge.mesh_path(scenario.tool, POSE)
    model = check_robot(scenario.robot)
    frame = model.GetFrameByName(scenario.robot.tool_frame)
    ends = []
    for s in (0.0, contour.length):
        p, axis = contour.point_at(s), contour.tool_axis_at(s)
        q = solve_tool_pose(
            model,
            p,
            q_guess=ik_seed(scenario.robot, p),
            instance=frame.model_instance(),
            tool_frame=scenario.robot.tool_frame,
            tool_axis=axis,
        )
        ends.append((p, axis, q))
    return ends


@pytest.fixture(scope="module")
def bore_and_slot(cell):
    scenario, _ = cell
    bore = _cut_ends(scenario, [-0.03, 0.015, 0.0])
    slot = _cut_ends(scenario, [0.005, 0.028, 0.0])
    return bore[1], slot[0]


def test_a_move_from_the_bore_to_the_slot_clears_the_part(cell, bore_and_slot):
    _, planning = cell
    settings = MoveSettings()
    end, start = bore_and_slot
    move = plan_move(planning, end, start, settings=settings, label="0 -> 1")
    np.testing.assert_allclose(move.path[0], end[2], atol=1e-12)
    np.testing.assert_allclose(move.path[-1], start[2], atol=1e-12)
    assert np.all(np.diff(move.times) >= 0.0)
    # the retract rises along the bore's tool axis, the approach comes down
    # the slot's
    context = planning.plant.CreateDefaultContext()
    for q, (p, axis, _), distance in (
        (move.transit.value(move.transit.start_time()), end, settings.retract),
        (move.transit.value(move.transit.end_time()), start, settings.approach),
    ):
        planning.plant.SetPositions(context, q.ravel())
        tip = planning.tool_frame.CalcPoseInWorld(context)
        np.testing.assert_allclose(
            tip.translation(), p + distance * axis, atol=1e-4
        )
        np.testing.assert_allclose(tip.rotation().col(2), axis, atol=1e-3)
        assert clearance(planning, q.ravel()) >= settings.clearance - 1e-6
    # the checker's verdict on the transit, at its fine joint step
    t = np.linspace(move.transit.start_time(), move.transit.end_time(), 50)
    q = [move.transit.value(s).ravel() for s in t]
    assert all(
        planning.checker.CheckEdgeCollisionFree(a, b)
        for a, b in zip(q[:-1], q[1:])
    )
    assert 0.0 < move.min_clearance_m < 0.1
    # the tip goes up 20 mm, across about 45 mm and down 20 mm
    assert 0.06 < move.travel_m < 0.3
    assert move.duration_s > (settings.retract + settings.approach) / (
        settings.axial_speed
    )


def test_a_move_that_cannot_be_planned_says_where(cell, bore_and_slot):
    _, planning = cell
    end, start = bore_and_slot
    # the approach point 30 mm down into the block
    inside = MoveSettings(approach=-0.03)
    with pytest.raises(MovePlanningError, match=r"^0 -> 1: approach point: "):
        plan_move(planning, end, start, settings=inside, label="0 -> 1")


def test_a_move_into_the_part_names_the_shape_and_where(cell, bore_and_slot):
    """The chamfer's edge cut with the tool tilted 45 degrees off the top:
    coming down that axis, the spindle meets the top face."""
    scenario, planning = cell
    end, _ = bore_and_slot
    edge = EdgeConfig(
        kind="mesh",
        file=str(BLOCK),
        units="mm",
        near=[0.045, 0.0, 0.0],
        tool_face=[0, 0, 1],
        tilt=-np.pi / 4,
    )
    contour = edge.mesh_path(scenario.tool, POSE)
    p, axis = contour.point_at(0.0), contour.tool_axis_at(0.0)
    model = check_robot(scenario.robot)
    q = solve_tool_pose(
        model,
        p,
        q_guess=ik_seed(scenario.robot, p),
        instance=model.GetFrameByName(
            scenario.robot.tool_frame
        ).model_instance(),
        tool_frame=scenario.robot.tool_frame,
        tool_axis=axis,
    )
    with pytest.raises(
        MovePlanningError,
        match=r"^0 -> 1: approach: the spindle enters the part \d+ % along",
    ):
        plan_move(planning, end, (p, axis, q), label="0 -> 1")
