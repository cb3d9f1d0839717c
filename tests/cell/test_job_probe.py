"""A whole-part job with touch probing, planned: the touches on the whole
part pin its six degrees of freedom, the moves' paths move with the
registered part, part errors and steps on a job, and the bad values."""

import numpy as np
import pytest

from deburr_drake.config import ConfigError, load_scenario
from deburr_drake.config.job import JobEdgeConfig
from deburr_drake.math.mesh_registration import pose_amplification
from deburr_drake.math.registration import MAX_AMPLIFICATION
from deburr_drake.math.rigid import rotvec_matrix

ERROR = dict(offset=[5e-4, -5e-4, 5e-4], rpy=list(np.radians([0.5, -0.5, 0.5])))


def _scenario(probe=True):
    """The bore and the 15-degree hole of examples/block_job.yaml,
    probed, the block off by 0.5 mm and 0.5 degree about every axis (the
    bore first: the probe is held as the first cut's tool, upright)."""
    scenario = load_scenario("examples/block_job.yaml")
    scenario.job.edges = [JobEdgeConfig(index=7), JobEdgeConfig(index=10)]
    scenario.job.order = "listed"
    scenario.job.retract = scenario.job.approach = 0.01
    scenario.job.clearance = 0.002
    scenario.localisation.probe.enabled = probe
    scenario.part_error.offset = list(ERROR["offset"])
    scenario.part_error.rpy = list(ERROR["rpy"])
    return scenario


@pytest.fixture(scope="module")
def plan():
    from deburr_drake.cell.job_cell import plan_job_cell

    return plan_job_cell(_scenario())


def test_the_touches_on_the_whole_part_pin_six_degrees_of_freedom(plan):
    probe = plan.cell.mesh_probe
    touches = probe.touches
    assert probe.count == plan.scenario.localisation.probe.points == 8
    # The pose alone: a job's registration fits no hole's size.
    assert probe.sized is None
    assert not plan.scenario.localisation.probe.fit_radius
    amplification = pose_amplification(touches.points, touches.normals)
    assert amplification == pytest.approx(touches.amplification)
    assert amplification < MAX_AMPLIFICATION
    # Fewer than six touches (or all on one face) pin nothing.
    assert pose_amplification(touches.points[:5], touches.normals[:5]) == (
        np.inf
    )
    # Faces of several directions: the top and walls facing apart.
    assert np.linalg.matrix_rank(touches.normals, tol=1e-6) == 3
    # The job's arm reaches every touch clear of the part.
    assert 0.0 < plan.probe_clearance < 0.5
    # The probe's route is in the workspace the guards hold the tool to.
    route = probe.route(plan.scenario.localisation.probe.standoff)
    low, high = plan.workspace.min(axis=0), plan.workspace.max(axis=0)
    assert np.all(route >= low - 1e-12) and np.all(route <= high + 1e-12)


def test_the_loops_believe_the_nominal_part_the_plant_has_the_moved_one(
    plan,
):
    from deburr_drake.runs.pass_metrics import pose_errors

    for believed, real in zip(plan.contour.edges, plan.real):
        x, y = believed.point_at(0.003), real.point_at(0.003)
        assert 2e-4 < np.linalg.norm(x - y) < 3e-3
        # The real edge is the believed one moved by the part error
        # (a zero registration is off by minus that move).
        position, turn = pose_errors(plan.scenario, np.zeros(7), x)
        np.testing.assert_allclose(x - position, y, atol=1e-6)
        assert np.degrees(np.linalg.norm(turn)) == pytest.approx(
            np.degrees(np.linalg.norm(ERROR["rpy"])), rel=0.02
        )


def test_a_move_is_moved_with_the_registered_part(plan):
    from deburr_drake.cell.job_probe import moved_path

    model = plan.cell.model
    frame_name = plan.scenario.robot.tool_frame
    path = plan.cuts[0].move.path
    w, p = np.radians([0.4, -0.6, 0.8]), np.array([8e-4, -5e-4, 1e-3])
    registration = np.concatenate([w, p, [0.0]])
    moved = moved_path(model, frame_name, path, registration)
    assert moved.shape == path.shape
    context = model.CreateDefaultContext()
    frame = model.GetFrameByName(frame_name)
    R = rotvec_matrix(w)
    for q, q_moved in zip(path, moved):
        model.SetPositions(context, q)
        X = frame.CalcPoseInWorld(context)
        model.SetPositions(context, q_moved)
        Y = frame.CalcPoseInWorld(context)
        np.testing.assert_allclose(
            Y.translation(), R @ X.translation() + p, atol=1e-9
        )
        np.testing.assert_allclose(
            Y.rotation().matrix(), R @ X.rotation().matrix(), atol=1e-9
        )
        # Near the planned posture: the arm's branch is kept.
        assert np.max(np.abs(q_moved - q)) < 0.1
    # No registration: the planned path.
    np.testing.assert_array_equal(
        moved_path(model, frame_name, path, np.zeros(7)), path
    )


def test_a_part_step_on_a_job_steps_every_edge_the_loops_believe():
    from deburr_drake.cell.job_cell import plan_job_cell

    scenario = _scenario(probe=False)
    scenario.faults.part_step.time = 3.0
    scenario.faults.part_step.offset = [0.0, 2e-4, 0.0]
    # A turn too, small (0.0057 degree: microns on the block's edges).
    scenario.faults.part_step.rpy = [0.0, 0.0, 1e-4]
    plan = plan_job_cell(scenario)
    time, stepped = plan.contour_step
    assert time == 3.0
    assert len(stepped.edges) == len(plan.contour.edges)
    for before, after in zip(plan.contour.edges, stepped.edges):
        np.testing.assert_allclose(
            after.point_at(0.004) - before.point_at(0.004),
            [0.0, -2e-4, 0.0],
            atol=1e-5,
        )


@pytest.mark.parametrize(
    "change, field",
    [
        (
            lambda s: setattr(s.localisation.online, "enabled", True),
            "localisation.online.enabled",
        ),
        (
            lambda s: setattr(s.part_error, "rpy", [0.0, 4.0, 0.0]),
            "part_error.rpy[1]",
        ),
        (
            lambda s: setattr(s.part_error, "offset", [0.0, float("nan")]),
            "part_error.offset",
        ),
        (
            lambda s: setattr(s.faults.part_step, "rpy", [0.0, 0.0, -4.0]),
            "faults.part_step.rpy[2]",
        ),
        (
            lambda s: setattr(s.localisation.probe, "points", 6),
            "localisation.probe.points",
        ),
    ],
)
def test_a_bad_value_on_a_job_is_one_line_naming_its_field(change, field):
    from deburr_drake.cell.job_cell import plan_job_cell

    scenario = _scenario()
    change(scenario)
    with pytest.raises(ConfigError) as raised:
        plan_job_cell(scenario)
    message = str(raised.value)
    assert "\n" not in message
    assert message.startswith(field), message


def test_a_touch_the_arm_cannot_reach_is_one_line_naming_the_probe(plan):
    from deburr_drake.cell.job_probe import check_probe_route

    route = plan.cell.mesh_probe.route(0.002).copy()
    route[1] += [2.0, 0.0, 0.0]  # 2 m beyond the arm
    with pytest.raises(ConfigError) as raised:
        check_probe_route(
            plan.job.cell,
            plan.cell.model,
            plan.scenario.robot.tool_frame,
            route,
            rotation=plan.cell.start.rotation,
            q_start=plan.cell.start.q,
        )
    message = str(raised.value)
    assert message.startswith("localisation.probe.points: the arm does")
    assert "touch 1's standoff" in message and "\n" not in message
