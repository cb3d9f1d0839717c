"""The 5-DOF arm model (models/arm5.sdf) and its tool-vertical IK
(deburr_drake.cell.arm)."""

import math
import xml.etree.ElementTree as ET

import numpy as np
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
from pydrake.multibody.tree import JacobianWrtVariable
from pydrake.systems.framework import DiagramBuilder
import pytest

from deburr_drake.cell.arm import (
    ARM_JOINTS,
    ARM_URL,
    DEFAULT_PART_POSITION,
    Q_READY,
    add_arm,
    solve_tool_pose,
)
from deburr_drake.cell.models import make_kinematic_model, models_dir
from deburr_drake.cell.part import add_cartesian_tool

TIP_Z = 0.048  # m: 2 mm below the tube's top edge at z = 0.05 m


def _sdf_joint_values():
    root = ET.parse(models_dir() / "arm5.sdf").getroot()
    ns = "{http://drake.mit.edu}"
    out = {}
    for joint in root.iter("joint"):
        if joint.get("type") == "revolute":
            out[joint.get("name")] = (
                float(joint.find(f"{ns}rotor_inertia").text),
                float(joint.find(f"{ns}gear_ratio").text),
                float(joint.find("axis/limit/effort").text),
                float(joint.find("axis/dynamics/damping").text),
            )
    return out


@pytest.fixture(scope="module")
def plant():
    return make_kinematic_model(ARM_URL)


def _circle(radius, n=12):
    cx, cy, _ = DEFAULT_PART_POSITION
    return [
        np.array([cx + radius * math.cos(t), cy + radius * math.sin(t), TIP_Z])
        for t in np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    ]


def test_model_loads(plant):
    assert plant.num_positions() == 5 and plant.num_velocities() == 5
    assert plant.num_actuators() == 5
    values = _sdf_joint_values()
    assert tuple(values) == ARM_JOINTS
    for name, (rotor, gear, effort, damping) in values.items():
        joint = plant.GetJointByName(name)
        actuator = plant.GetJointActuatorByName(name)
        assert actuator.joint().index() == joint.index()
        assert actuator.default_rotor_inertia() == pytest.approx(rotor)
        assert actuator.default_gear_ratio() == pytest.approx(gear)
        assert actuator.default_reflected_inertia() == pytest.approx(
            gear**2 * rotor
        )
        assert actuator.effort_limit() == pytest.approx(effort)
        assert joint.default_damping() == pytest.approx(damping)
        assert 1e-4 <= rotor <= 3e-4 and gear == 100
    ft = plant.GetJointByName("ft_sensor")
    assert ft.type_name() == "weld"
    assert (
        ft.parent_body().name() == "flange" and ft.child_body().name() == "tool"
    )
    base = plant.GetJointByName("base_weld")
    assert (
        base.type_name() == "weld"
        and base.parent_body().index() == plant.world_body().index()
    )
    tip = plant.GetFrameByName("tool_tip")
    assert tip.body().name() == "tool"
    assert np.allclose(tip.GetFixedPoseInBodyFrame().GetAsMatrix4(), np.eye(4))
    context = plant.CreateDefaultContext()
    assert np.allclose(
        plant.GetFrameByName("base").CalcPoseInWorld(context).GetAsMatrix4(),
        np.eye(4),
    )
    # Reflected inertia enters the mass matrix diagonal.
    plant.SetPositions(context, Q_READY)
    M = plant.CalcMassMatrix(context)
    reflected = np.array(
        [
            plant.GetJointActuatorByName(j).default_reflected_inertia()
            for j in ARM_JOINTS
        ]
    )
    assert np.all(np.diag(M) > reflected)


def test_add_arm_with_cutter():
    builder = DiagramBuilder()
    plant, _ = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
    instance = add_arm(plant, cutter_radius=0.003, cutter_length=0.02)
    plant.Finalize()
    tool = plant.GetBodyByName("tool", instance)
    assert len(plant.GetCollisionGeometriesForBody(tool)) == 1
    for name in ("base", "link1", "link2", "link3", "link4", "link5", "flange"):
        assert (
            plant.GetCollisionGeometriesForBody(
                plant.GetBodyByName(name, instance)
            )
            == []
        )


@pytest.mark.parametrize("radius", [0.017, 0.030, 0.057])
def test_ik_circle_tool_vertical(plant, radius):
    context = plant.CreateDefaultContext()
    tip = plant.GetFrameByName("tool_tip")
    lower, upper = (
        plant.GetPositionLowerLimits(),
        plant.GetPositionUpperLimits(),
    )
    effort = np.array(
        [plant.GetJointActuatorByName(j).effort_limit() for j in ARM_JOINTS]
    )
    q_prev = None
    for p in _circle(radius):
        q = solve_tool_pose(plant, p, q_guess=q_prev)
        q_prev = q
        assert q.shape == (5,)
        plant.SetPositions(context, q)
        X_WT = tip.CalcPoseInWorld(context)
        assert np.linalg.norm(X_WT.translation() - p) < 1e-6
        z_axis = X_WT.rotation().matrix()[:, 2]
        assert math.acos(min(1.0, z_axis[2])) < 1e-6
        assert (
            np.min(np.minimum(q - lower, upper - q)) > 0.5
        )  # rad of margin to every limit
        assert q[1] > 0 and q[3] < 0  # elbow up: shoulder forward, wrist back
        tau_g = plant.CalcGravityGeneralizedForces(context)
        assert np.all(np.abs(tau_g) < 0.5 * effort)


def test_ik_on_plant_with_other_models():
    builder = DiagramBuilder()
    plant, _ = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
    arm = add_arm(plant)
    add_cartesian_tool(plant)  # also has a body `tool` and a frame `tool_tip`
    plant.Finalize()
    p = _circle(0.030)[0]
    q = solve_tool_pose(plant, p)
    context = plant.CreateDefaultContext()
    plant.SetPositions(context, arm, q)
    assert (
        np.linalg.norm(
            plant.GetFrameByName("tool_tip", arm)
            .CalcPoseInWorld(context)
            .translation()
            - p
        )
        < 1e-6
    )


def test_ik_failure_raises(plant):
    with pytest.raises(RuntimeError, match="p_W_tip"):
        solve_tool_pose(plant, [1.5, 0.0, TIP_Z])


def test_ik_bad_arguments(plant):
    with pytest.raises(ValueError, match="p_W_tip"):
        solve_tool_pose(plant, [0.4, 0.0])
    with pytest.raises(ValueError, match="q_guess"):
        solve_tool_pose(plant, [0.4, 0.0, TIP_Z], q_guess=np.zeros(4))


def test_task_space_inertia_positive(plant):
    context = plant.CreateDefaultContext()
    plant.SetPositions(context, solve_tool_pose(plant, _circle(0.030)[0]))
    M = plant.CalcMassMatrix(context)
    J = plant.CalcJacobianTranslationalVelocity(
        context,
        JacobianWrtVariable.kV,
        plant.GetFrameByName("tool_tip"),
        np.zeros(3),
        plant.world_frame(),
        plant.world_frame(),
    )
    Lam = np.linalg.inv(J @ np.linalg.solve(M, J.T))
    eig = np.linalg.eigvalsh(0.5 * (Lam + Lam.T))
    assert np.all(eig > 1.0) and np.all(eig < 100.0)  # kg


def test_check_reach_follows_the_edge_and_names_another_seed(monkeypatch):
    """A point the seed's inverse kinematics misses is tried from the
    previous point's solution; one reached only from the nearest reachable
    posture gives distance 0 and that posture, never "0.0 mm beyond"."""
    from deburr_drake.cell import arm

    plant = make_kinematic_model(ARM_URL)
    x, y, z = DEFAULT_PART_POSITION
    points = [[x + 0.03, y, 0.048], [x, y + 0.03, 0.048]]
    real, calls = arm.solve_tool_pose, []

    def misses_from_the_seed(plant_, p, *, q_guess=None, **kw):
        calls.append(q_guess)
        if len(calls) in (
            2,
            3,
        ):  # the second point: from the seed and from the first
            raise RuntimeError("missed")
        return real(plant_, p, q_guess=q_guess, **kw)

    monkeypatch.setattr(arm, "solve_tool_pose", misses_from_the_seed)
    k, p, distance, q = arm.check_reach(
        plant, points, q_guess=arm.default_q_guess
    )
    assert (k, distance) == (1, 0.0)
    np.testing.assert_allclose(p, points[1])
    np.testing.assert_allclose(real(plant, points[1], q_guess=q), q, atol=1e-6)
    # The previous point's solution was tried before the nearest posture.
    np.testing.assert_allclose(calls[2], real(plant, points[0]), atol=1e-6)
    # Out of reach: the true distance, no posture.
    far = np.array([x + 2.0, y, 0.048])
    monkeypatch.setattr(arm, "solve_tool_pose", real)
    k, p, distance, q = arm.check_reach(plant, [far])
    assert k == 0 and q is None and distance > 1.0


def test_a_pose_below_the_conditioning_bound_is_refused(plant):
    """solve_tool_pose returns postures above MIN_CONDITIONING; asked for
    more than any posture has, it raises SingularPose with the best one
    it found."""
    from deburr_drake.cell.arm import (
        MIN_CONDITIONING,
        SingularPose,
        tool_conditioning,
    )

    p = _circle(0.030)[0]
    c = tool_conditioning(plant, solve_tool_pose(plant, p))
    assert MIN_CONDITIONING < c < 1.0
    with pytest.raises(SingularPose, match="singular") as e:
        solve_tool_pose(plant, p, min_conditioning=0.9)
    assert MIN_CONDITIONING < e.value.conditioning < 0.9
    np.testing.assert_allclose(e.value.point, p)


def test_a_singular_path_point_names_the_tube_and_where(monkeypatch):
    """A path point reached only near a singular posture is refused
    before the run: one line naming part.pose.xyz and the point."""
    from deburr_drake.cell import reach
    from deburr_drake.cell.arm import SingularPose
    from deburr_drake.config import ConfigError, load_scenario

    def singular(*args, **kw):
        e = SingularPose("singular", [0.4, 0.03, 0.048], 0.004)
        e.index = 3
        raise e

    monkeypatch.setattr(reach, "check_reach", singular)
    # A cell checked earlier in the session is remembered as reachable.
    monkeypatch.setattr(reach, "_REACHED", set())
    with pytest.raises(ConfigError) as e:
        reach.check_part_in_reach(load_scenario("paper"))
    message = str(e.value)
    assert message.startswith("part.pose.xyz = ") and "\n" not in message
    assert "the edge point at arc" in message and "0.004 < 0.02" in message


def test_a_path_through_a_singular_posture_names_the_seed(monkeypatch):
    """The arm followed from the start pose along the edge: a posture
    below the bound (here the bound raised above arm5's 0.09) names
    robot.ik_seed and where along the edge."""
    from deburr_drake.cell import reach
    from deburr_drake.config import ConfigError, load_scenario

    monkeypatch.setattr(reach, "MIN_CONDITIONING", 0.5)
    monkeypatch.setattr(reach, "_REACHED", set())
    with pytest.raises(ConfigError) as e:
        reach.check_part_in_reach(load_scenario("paper"))
    message = str(e.value)
    assert message.startswith("robot.ik_seed = ") and "\n" not in message
    assert "near a singular posture at the" in message
