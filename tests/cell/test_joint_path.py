"""The arm along a 3-D edge: IK with a given tool axis, the continuous
joint path (wrist flips, joint limits, reach) and its one-line refusals,
on paper_6dof's 6-joint arm round a circle in a plane inclined 30 deg."""

import numpy as np
import pytest

from deburr_drake.cell.arm import solve_tool_pose
from deburr_drake.cell.joint_path import PathBreak, joint_path
from deburr_drake.cell.reach import check_part_in_reach
from deburr_drake.cell.robot import ik_seed, make_robot_model
from deburr_drake.config import ConfigError, load_scenario

INCLINE = np.radians(30.0)
REACHABLE = [0.95, 0.0, 0.5]  # m: by paper_6dof's tube


@pytest.fixture(scope="module")
def cell():
    scenario = load_scenario("paper_6dof")
    model = make_robot_model(scenario.robot)
    frame = model.GetFrameByName(scenario.robot.tool_frame)
    return scenario, model, frame


def _pose_axis(model, frame, q):
    context = model.CreateDefaultContext()
    model.SetPositions(context, q)
    X = frame.CalcPoseInWorld(context)
    return X.translation(), X.rotation().matrix()[:, 2]


def _stations(edge, count=25):
    arcs = np.linspace(0.0, edge.length, count)
    points = [edge.point_at(s) for s in arcs]
    return arcs, points, [edge.tool_axis_at(s) for s in arcs]


def test_tool_pose_along_a_given_axis(cell, tilted_circle):
    """The tool's +z along the plane's normal at the tip target; None
    keeps it vertical."""
    scenario, model, frame = cell
    edge = tilted_circle(REACHABLE, 0.01, INCLINE)
    p, a = edge.point_at(0.01), edge.tool_axis_at(0.01)
    q = solve_tool_pose(
        model,
        p,
        instance=frame.model_instance(),
        q_guess=ik_seed(scenario.robot, p),
        tool_frame=frame.name(),
        tool_axis=2.0 * a,  # any length: normalised
    )
    tip, axis = _pose_axis(model, frame, q)
    np.testing.assert_allclose(tip, p, atol=1e-7)
    np.testing.assert_allclose(axis, a, atol=1e-6)
    assert a[2] == pytest.approx(np.cos(INCLINE))
    q = solve_tool_pose(
        model,
        p,
        instance=frame.model_instance(),
        q_guess=ik_seed(scenario.robot, p),
        tool_frame=frame.name(),
    )
    np.testing.assert_allclose(
        _pose_axis(model, frame, q)[1], [0, 0, 1], atol=1e-6
    )
    with pytest.raises(ValueError, match="tool_axis"):
        solve_tool_pose(
            model, p, instance=frame.model_instance(), tool_axis=[0, 0, 0]
        )


def test_joint_path_round_a_reachable_edge(cell, tilted_circle):
    """Round the whole circle the posture follows, joint steps small, the
    tool on the edge with its axis along the normal at every station."""
    scenario, model, frame = cell
    edge = tilted_circle(REACHABLE, 0.01, INCLINE)
    arcs, points, axes = _stations(edge)
    q0 = solve_tool_pose(
        model,
        points[0],
        instance=frame.model_instance(),
        q_guess=ik_seed(scenario.robot, points[0]),
        tool_frame=frame.name(),
        tool_axis=axes[0],
    )
    path = joint_path(
        model,
        points,
        axes,
        arcs,
        q0,
        instance=frame.model_instance(),
        tool_frame=frame.name(),
    )
    assert path.shape == (len(arcs), 6)
    assert np.abs(np.diff(path, axis=0)).max() < 0.1
    for q, p, a in zip(path, points, axes):
        tip, axis = _pose_axis(model, frame, q)
        np.testing.assert_allclose(tip, p, atol=1e-6)
        np.testing.assert_allclose(axis, a, atol=1e-5)
    # The planar pass's check is the 3-D one here, and passes.
    check_part_in_reach(scenario, edge)


def test_joint_path_refuses_a_flip_naming_arc_and_joint(cell, tilted_circle):
    """The axis turned 1.2 rad between two stations 1 mm apart: the
    wrist would swing past the step bound; one line naming the arc (mm)
    and the joint."""
    scenario, model, frame = cell
    edge = tilted_circle(REACHABLE, 0.01, INCLINE)
    start, axis = edge.point_at(0.0), np.array([0.0, 0.0, 1.0])
    q0 = solve_tool_pose(
        model,
        start,
        instance=frame.model_instance(),
        q_guess=ik_seed(scenario.robot, start),
        tool_frame=frame.name(),
    )
    turned = np.array([np.sin(1.2), 0.0, np.cos(1.2)])
    with pytest.raises(PathBreak) as error:
        joint_path(
            model,
            [start, start + [0.0, 0.001, 0.0]],
            [axis, turned],
            [0.0, 0.001],
            q0,
            instance=frame.model_instance(),
            tool_frame=frame.name(),
        )
    message = str(error.value)
    assert "\n" not in message
    assert message.startswith("at arc 1.0 mm along the edge the arm's joint")
    assert error.value.joint in message and "wrist flip" in message


def test_joint_path_refuses_a_point_out_of_reach(cell, tilted_circle):
    """A path leaving the arm's reach: PathBreak at the first station out
    of it (its arc), and the whole edge out of reach refused in one line."""
    scenario, model, frame = cell
    edge = tilted_circle(REACHABLE, 0.01, INCLINE)
    start, axis = edge.point_at(0.0), edge.tool_axis_at(0.0)
    q0 = solve_tool_pose(
        model,
        start,
        instance=frame.model_instance(),
        q_guess=ik_seed(scenario.robot, start),
        tool_frame=frame.name(),
        tool_axis=axis,
    )
    arcs = np.linspace(0.0, 1.5, 16)
    points = [start + [s, 0.0, 0.0] for s in arcs]
    with pytest.raises(PathBreak) as error:
        joint_path(
            model,
            points,
            [axis] * len(arcs),
            arcs,
            q0,
            instance=frame.model_instance(),
            tool_frame=frame.name(),
        )
    assert 0.0 < error.value.arc <= 1.5
    assert f"at arc {error.value.arc * 1e3:.1f} mm" in str(error.value)
    far = tilted_circle([2.5, 0.0, 0.5], 0.01, INCLINE)
    with pytest.raises(ConfigError, match="out of the arm's reach"):
        check_part_in_reach(scenario, far)
