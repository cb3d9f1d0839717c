"""Bring your own robot: the deburring arm from a model file.

``robot.model`` (deburr_drake.config.RobotConfig) is a shipped name
(:data:`SHIPPED_ROBOTS`: ``cartesian_tool``, the 5-DOF ``arm5``, the 6-DOF
``arm6``) or a path to a URDF or SDF file. Drake's parser reads it; the
``package://`` URIs inside resolve as Drake resolves them (the
``package.xml`` files in the directories above the model file, and
``ROS_PACKAGE_PATH``), plus ``deburr_drake_models`` (this repository's
``models/``). A base link without a joint to the world is welded at the
world origin.

The tool is mounted one of two ways:

- the model holds it (arm5, cartesian_tool): a body with frame
  ``robot.tool_frame`` at the tool tip, hanging from the weld joint
  ``robot.sensor_joint`` (the force/torque sensor);
- the model is a bare arm with a mounting face, frame ``robot.flange_frame``:
  :func:`add_robot` welds the sensor (joint ``robot.sensor_joint``) and a
  spindle body ``tool`` of ``robot.tool_mass`` there, at
  ``robot.tool_mount`` in the flange frame (default identity: the tool
  along the flange's +z, ISO 9409-1), tip ``robot.tool_length`` along the
  spindle's +z, the tool frame's +z pointing back to the flange (the
  cutter stands on +z from the tip, as on arm5).

The controller maps the task-space law through the tool frame's 6 x n
Jacobian, tau = J_v^T f + J_w^T m (deburr_drake.control.controller), which needs
nothing of the arm's kinematics: with 5 joints the tool axis is held
vertical and the rotation about it (two orientation axes; the third is not
in J_w's range), with 6 the full orientation, with more also the start
posture, by a joint PD in J's null space (``controller.null_space_*``).
The joint limits and
effort limits are the model file's (the inverse kinematics, the guards and
the drives read them from the plant); the joint friction is
``robot.joint_coulomb_friction``, one value per joint; the controller's
model masses are ``controller.model_mass_scale`` times the file's.

:func:`check_robot` turns every problem with a model (missing file or
frame, too few or too many actuated joints, a friction list or IK seed of
the wrong length) into one ConfigError line naming the field, before
anything runs; ``deburr_drake.cell.reach.check_part_in_reach`` adds the part out
of reach.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path

import numpy as np
from pydrake.geometry import Cylinder
from pydrake.math import RigidTransform, RollPitchYaw, RotationMatrix
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, MultibodyPlant
from pydrake.multibody.tree import (
    FixedOffsetFrame,
    FrameIndex,
    JacobianWrtVariable,
    JointActuatorIndex,
    JointIndex,
    SpatialInertia,
    UnitInertia,
    WeldJoint,
)
from pydrake.systems.framework import DiagramBuilder

from deburr_drake.cell.arm import ARM_URL, default_q_guess
from deburr_drake.cell.description import (
    add_packages,
    model_path,
    notice,
    prepared_model,
)
from deburr_drake.cell.models import POINT_MASS_URL, make_parser
from deburr_drake.config import ConfigError, RobotConfig

__all__ = [
    "ARM6_URL",
    "SHIPPED_ROBOTS",
    "MIN_JOINTS",
    "add_robot",
    "make_robot_model",
    "check_robot",
    "robot_joints",
    "ik_seed",
    "tool_frame_of",
    "finalize",
    "LIMITS_NOTE",
    "spindle_inertia",
    "mount_pose",
    "start_pose",
    "loop_numbers",
]

ARM6_URL = "package://deburr_drake_models/arm6.sdf"

#: Shipped model name -> its URL in models/.
SHIPPED_ROBOTS = {
    "cartesian_tool": POINT_MASS_URL,
    "arm5": ARM_URL,
    "arm6": ARM6_URL,
}
assert tuple(SHIPPED_ROBOTS) == RobotConfig.SHIPPED  # one list of names

#: Actuated joints an arm needs: 3 for the position, 2 to hold the tool
#: axis vertical.
MIN_JOINTS = 5

_SPINDLE_RADIUS = 0.03  # m, the spindle's solid cylinder (as on arm5)


def spindle_inertia(mass: float, length: float) -> SpatialInertia:
    """The sensor and spindle about the tool tip, tool frame: a solid
    cylinder of radius 30 mm over the upper 80 % of the flange-to-tip
    ``length`` (m) (arm5's spindle: 1.5 kg, 0.10 m, centre 0.07 m up)."""
    h = 0.8 * length
    com = np.array([0.0, 0.0, length - 0.5 * h])
    unit = UnitInertia.SolidCylinder(_SPINDLE_RADIUS, h, [0.0, 0.0, 1.0])
    return SpatialInertia(mass, com, unit.ShiftFromCenterOfMass(-com))


def _add_models(plant: MultibodyPlant, config: RobotConfig):
    parser = make_parser(plant)
    if not config.is_file():
        return parser.AddModels(url=SHIPPED_ROBOTS[config.model])
    package_map = parser.package_map()
    add_packages(package_map, config)
    path = model_path(package_map, config)
    add_packages(package_map, config, path)  # the package.xml files above
    text, kind, path, notes = prepared_model(package_map, config)
    for line in notes:
        notice(f"robot.model {Path(path).name}: {line}")
    try:
        return parser.AddModelsFromString(text, kind)
    except RuntimeError as e:
        first = str(e).strip().splitlines()[0] if str(e).strip() else ""
        raise ConfigError(
            f"robot.model = {config.model!r} is invalid: "
            f"Drake cannot parse it ({first})"
        ) from None


def _set_reflected_inertia(plant, instance, config: RobotConfig):
    """robot.reflected_inertia (kg m^2 per joint, in joint order) as the
    drives' rotor inertia at gear ratio 1."""
    if not config.reflected_inertia:
        return
    # Before Finalize: the moving joints in index order (a chain's order).
    joints = [plant.get_joint(i) for i in plant.GetJointIndices(instance)]
    joints = [j for j in joints if j.num_velocities() > 0]
    if len(joints) != len(config.reflected_inertia):
        raise ConfigError(
            f"robot.reflected_inertia = {config.reflected_inertia} is "
            f"invalid: allowed a list of {len(joints)} numbers >= 0 (kg m^2,"
            f" one per joint: {[j.name() for j in joints]}) or an empty list"
        )
    # (GetJointActuatorIndices(instance) is empty before Finalize.)
    by_joint = {
        plant.get_joint_actuator(JointActuatorIndex(i))
        .joint()
        .index(): JointActuatorIndex(i)
        for i in range(plant.num_actuators())
    }
    for joint, inertia in zip(joints, config.reflected_inertia):
        if joint.index() in by_joint:
            actuator = plant.get_mutable_joint_actuator(by_joint[joint.index()])
            actuator.set_default_rotor_inertia(float(inertia))
            actuator.set_default_gear_ratio(1.0)


def _frame_names(plant, instance):
    """The instance's body frames and named frames (not its joints' frames,
    not __model__)."""
    joint_frames = set()
    for index in plant.GetJointIndices(instance):
        joint = plant.get_joint(index)
        joint_frames |= {
            joint.frame_on_parent().index(),
            joint.frame_on_child().index(),
        }
    names = []
    for i in range(plant.num_frames()):
        frame = plant.get_frame(FrameIndex(i))
        if (
            frame.model_instance() == instance
            and frame.index() not in joint_frames
            and frame.name() != "__model__"
        ):
            names.append(frame.name())
    return sorted(set(names))


def _joint_names(plant, instance):
    return [plant.get_joint(i).name() for i in plant.GetJointIndices(instance)]


def _attach_spindle(plant, instance, config: RobotConfig):
    if not plant.HasFrameNamed(config.flange_frame, instance):
        raise ConfigError(
            f"robot.flange_frame = {config.flange_frame!r} is invalid: "
            f"allowed a frame of {config.model!r}: "
            f"{_frame_names(plant, instance)}"
        )
    for kind, exists in (
        ("tool_frame", plant.HasFrameNamed),
        ("sensor_joint", plant.HasJointNamed),
    ):
        name = getattr(config, kind)
        if exists(name, instance):
            raise ConfigError(
                f"robot.{kind} = {name!r} is invalid: {config.model!r} "
                f"already has it, and robot.flange_frame = "
                f"{config.flange_frame!r} asks the cell to add it: allowed "
                "another name, or flange_frame: '' to use the model's"
            )
    flange = plant.GetFrameByName(config.flange_frame, instance)
    tool = plant.AddRigidBody(
        "tool", instance, spindle_inertia(config.tool_mass, config.tool_length)
    )
    # Tip tool_length out along the spindle's +z; tool +z back to the
    # spindle. The spindle sits at tool_mount in the flange frame.
    X_ST = RigidTransform(
        RotationMatrix.MakeXRotation(math.pi), [0.0, 0.0, config.tool_length]
    )
    X_FT = mount_pose(config) @ X_ST
    plant.AddJoint(
        WeldJoint(config.sensor_joint, flange, tool.body_frame(), X_FT)
    )
    plant.AddFrame(
        FixedOffsetFrame(config.tool_frame, tool.body_frame(), RigidTransform())
    )
    if plant.geometry_source_is_registered():
        shape_pose = RigidTransform([0.0, 0.0, 0.6 * config.tool_length])
        plant.RegisterVisualGeometry(
            tool,
            shape_pose,
            Cylinder(_SPINDLE_RADIUS, 0.8 * config.tool_length),
            "spindle",
            np.array([0.3, 0.3, 0.35, 1.0]),
        )


def mount_pose(config: RobotConfig) -> RigidTransform:
    """X_FS, the spindle's pose in the flange frame: ``robot.tool_mount``
    (URDF's fixed-axis roll, pitch, yaw)."""
    mount = config.tool_mount
    return RigidTransform(RollPitchYaw(mount.rpy), np.asarray(mount.xyz, float))


def _weld_free_base(plant, instance):
    """A model whose base link has no joint to the world (many URDFs) stands
    welded at the world origin, as arm5 and arm6 do."""
    children = {
        plant.get_joint(i).child_body().index()
        for i in plant.GetJointIndices(instance)
    }
    roots = [i for i in plant.GetBodyIndices(instance) if i not in children]
    if len(roots) == 1:
        plant.WeldFrames(
            plant.world_frame(), plant.get_body(roots[0]).body_frame()
        )


def _robot_instance(plant, instances, config: RobotConfig):
    if len(instances) != 1:
        raise ConfigError(
            f"robot.model = {config.model!r} is invalid: allowed a file with "
            f"one robot model, it has {len(instances)}"
        )
    return instances[0]


def add_robot(plant: MultibodyPlant, config: RobotConfig, *, cutter=None):
    """Add ``config.model`` to ``plant`` (before Finalize), with the
    spindle at ``config.flange_frame`` if one is named, and the cutter
    (``part.register_cutter``'s keyword arguments, e.g. cutter_radius) on
    the tool frame's body when ``cutter`` is a dict and the plant has a
    SceneGraph. Returns the model instance. Names are checked
    (ConfigError) but the joint count only by :func:`check_robot`."""
    instance = _robot_instance(plant, _add_models(plant, config), config)
    _weld_free_base(plant, instance)
    _set_reflected_inertia(plant, instance, config)
    if config.flange_frame:
        _attach_spindle(plant, instance, config)
    frame = tool_frame_of(plant, instance, config)
    if cutter is not None:
        from deburr_drake.cell.part import register_cutter

        register_cutter(
            plant, frame.body(), X_BT=frame.GetFixedPoseInBodyFrame(), **cutter
        )
    return instance


#: Drake's warning at Finalize of a continuous plant whose joints have
#: limits (three lines a user cannot act on), and what replaces it.
_LIMITS_WARNING = "Currently MultibodyPlant does not handle joint limits"
LIMITS_NOTE = (
    "joint limits: the start pose is solved within them; the "
    "continuous plant does not enforce them during the run (the "
    "guards stop a run whose torque, force, depth or tool "
    "position leaves its bounds)"
)


class _JointLimitsNote(logging.Filter):
    def filter(self, record):
        if record.getMessage().startswith(_LIMITS_WARNING):
            notice(LIMITS_NOTE)
            return False
        return True


_LIMITS_FILTER = _JointLimitsNote()


def finalize(plant):
    """plant.Finalize(); Drake's joint-limit warning (logged at the first
    dynamics evaluation of a continuous plant with limits) is replaced by
    one line, :data:`LIMITS_NOTE`, once per process (a filter on the
    ``drake`` logger)."""
    logger = logging.getLogger("drake")
    if _LIMITS_FILTER not in logger.filters:
        logger.addFilter(_LIMITS_FILTER)
    plant.Finalize()


def _require_named(
    config: RobotConfig, field: str, exists, what: str, names, added: str
):
    """ConfigError listing ``names()`` unless ``exists(robot.<field>)``."""
    name = getattr(config, field)
    if not exists(name):
        raise ConfigError(
            f"robot.{field} = {name!r} is invalid: allowed {what} of "
            f"{config.model!r}: {names()} (or name the mounting face in "
            f"robot.flange_frame and the cell adds the {added})"
        )


def tool_frame_of(plant, instance, config: RobotConfig):
    """The tool frame of the robot; ConfigError listing the model's frames
    if it has none of that name."""
    _require_named(
        config,
        "tool_frame",
        lambda name: plant.HasFrameNamed(name, instance),
        "a frame at the tool tip",
        lambda: _frame_names(plant, instance),
        "tool",
    )
    return plant.GetFrameByName(config.tool_frame, instance)


def make_robot_model(config: RobotConfig) -> MultibodyPlant:
    """A standalone, finalized MultibodyPlant of the robot and its tool
    alone (no geometry): the controller's and the observers' model."""
    return _robot_model(config)[0]


def _parse_with_geometry(config: RobotConfig):
    """Parses the model into a plant with a SceneGraph, so that the
    visual and collision geometry (their mesh URIs) are read too."""
    builder = DiagramBuilder()
    plant, _ = AddMultibodyPlantSceneGraph(builder, 0.0)
    add_robot(plant, config)


def _robot_model(config: RobotConfig):
    plant = MultibodyPlant(0.0)
    instance = add_robot(plant, config)
    finalize(plant)
    return plant, instance


def robot_joints(plant, instance=None):
    """The joints of the robot (those with a position), in position order."""
    indices = (
        plant.GetJointIndices(instance)
        if instance is not None
        else [JointIndex(i) for i in range(plant.num_joints())]
    )
    joints = [plant.get_joint(i) for i in indices]
    return sorted(
        (j for j in joints if j.num_positions() > 0),
        key=lambda j: j.position_start(),
    )


def check_robot(config: RobotConfig) -> MultibodyPlant:
    """Raises ConfigError (one line, naming the field) if the robot cannot
    serve the cell: a file Drake cannot parse, a missing tool or flange
    frame or sensor joint, fewer than 5 actuated joints (an arm; the
    shipped cartesian_tool has 3), a joint without an actuator,
    a joint_coulomb_friction or ik_seed list of the wrong length. Returns
    the robot's model (:func:`make_robot_model`)."""
    config.validate()
    _parse_with_geometry(config)  # every URI in the file resolves
    plant, instance = _robot_model(config)
    tool = tool_frame_of(plant, instance, config)
    _require_named(
        config,
        "sensor_joint",
        lambda name: plant.HasJointNamed(name, instance),
        "the weld joint holding the tool",
        lambda: _joint_names(plant, instance),
        "sensor",
    )
    sensor = plant.GetJointByName(config.sensor_joint, instance)
    if (
        sensor.num_velocities() != 0
        or sensor.child_body().index() != tool.body().index()
    ):
        raise ConfigError(
            f"robot.sensor_joint = {config.sensor_joint!r} is invalid: "
            "allowed a weld joint whose child body holds robot.tool_frame "
            f"{config.tool_frame!r} (it is a {sensor.type_name()} joint to "
            f"{sensor.child_body().name()!r})"
        )
    joints = robot_joints(plant)
    n = len(joints)
    actuated = {
        plant.get_joint_actuator(i).joint().index()
        for i in plant.GetJointActuatorIndices()
    }
    loose = [j.name() for j in joints if j.index() not in actuated]
    if loose:
        raise ConfigError(
            f"robot.model = {config.model!r} is invalid: joints {loose} "
            "have no actuator: allowed a fully actuated arm (SDF: an "
            "<effort> limit on each joint; URDF: a <transmission> or an "
            "effort limit above 0 on each joint)"
        )
    if plant.num_positions() != plant.num_velocities():
        raise ConfigError(
            f"robot.model = {config.model!r} is invalid: allowed revolute "
            "or prismatic joints, welded to the world (a floating or ball "
            "joint has no single actuator)"
        )
    if config.model != "cartesian_tool" and n < MIN_JOINTS:
        raise ConfigError(
            f"robot.model = {config.model!r} is invalid: it has {n} "
            f"actuated joints ({[j.name() for j in joints]}), allowed "
            f"at least {MIN_JOINTS} (3 for the tool's position, 2 to hold "
            "its axis vertical)"
        )
    friction = config.joint_coulomb_friction
    if friction and len(friction) != n:
        raise ConfigError(
            f"robot.joint_coulomb_friction = {friction} is invalid: allowed "
            f"a list of {n} numbers >= 0 (one per joint: "
            f"{[j.name() for j in joints]}) or an empty list"
        )
    if config.ik_seed and len(config.ik_seed) != n:
        raise ConfigError(
            f"robot.ik_seed = {config.ik_seed} is invalid: allowed a list of "
            f"{n} angles (rad, one per joint: {[j.name() for j in joints]}) "
            "or an empty list"
        )
    return plant


def ik_seed(config: RobotConfig, p_W_tip):
    """The inverse kinematics' initial guess (rad, one per joint) for a
    tool tip target p_W_tip (m): ``robot.ik_seed``; else arm5's ready pose
    turned towards the target; else None (the model's default positions)."""
    if config.ik_seed:
        return np.asarray(config.ik_seed, float)
    if config.model == "arm5":
        return default_q_guess(p_W_tip)
    return None


def start_pose(scenario):
    """The arm's joint angles (rad) at the start of the scenario's pass:
    the tool tip at the start of the believed contour, the tool vertical
    (what the cell sets as the plant's default positions)."""
    from deburr_drake.cell.arm import solve_tool_pose
    from deburr_drake.cell.edge import believed_contour, start_position

    robot = scenario.robot
    plant = make_robot_model(robot)
    x0 = start_position(scenario, believed_contour(scenario))
    if robot.model == "cartesian_tool":
        return x0
    frame = plant.GetFrameByName(robot.tool_frame)
    return solve_tool_pose(
        plant,
        x0,
        instance=frame.model_instance(),
        q_guess=ik_seed(robot, x0),
        tool_frame=robot.tool_frame,
    )


def loop_numbers(scenario, q=None, *, model=None) -> dict:
    """The numbers that set a robot's gains
    (docs/own-robot-measurements.md, "Gains designed from the model"),
    at joint angles ``q`` (default :func:`start_pose`), from the robot
    model alone:

    - ``gravity_error_force`` (3, N, world) and ``gravity_error_moment``
      (3, N m): the wrench at the tool frame whose J^T equals the
      controller's gravity error (model_mass_scale - 1) tau_g (least
      squares on a 5-DOF arm): what the fuzzy terms must learn on the fuzzy
      axes, and what leaves e_k = f_k / (K_k lambda_k) on the others;
    - ``static_error`` (3, m): that last quotient on every task axis;
    - ``lightest_task_mass`` (kg): the smallest eigenvalue of
      (J_v M^-1 J_v^T)^-1, the tool point's lightest direction;
    - ``sampled_rate``: max Re eig(M^-1 D) T, D = J_v^T K J_v + J_w^T K_o
      J_w, T the control period: the sampled loop's fastest decay per
      period (arm5 with paper.yaml: 0.30; its measured limit, at K = 5000
      on x1, x2: about 1.6).

    ``model``: the robot's model (:func:`make_robot_model`) if the caller
    holds it."""
    c = scenario.controller
    plant = make_robot_model(scenario.robot) if model is None else model
    if q is None:
        q = start_pose(scenario)
    context = plant.CreateDefaultContext()
    plant.SetPositions(context, q)
    frame = plant.GetFrameByName(scenario.robot.tool_frame)
    J = plant.CalcJacobianSpatialVelocity(
        context,
        JacobianWrtVariable.kV,
        frame,
        np.zeros(3),
        plant.world_frame(),
        plant.world_frame(),
    )
    M = plant.CalcMassMatrix(context)
    error = (c.model_mass_scale - 1.0) * plant.CalcGravityGeneralizedForces(
        context
    )
    wrench = np.linalg.lstsq(J.T, error, rcond=None)[0]
    K = np.asarray(c.sliding_gain, float)
    lam = np.asarray(c.sliding_lambda, float)
    D = (
        J[3:].T @ np.diag(K) @ J[3:]
        + J[:3].T @ np.diag(np.asarray(c.orientation_gain, float)) @ J[:3]
    )
    Jv_Minv = J[3:] @ np.linalg.inv(M)
    period = c.control_period
    return {
        "gravity_error_moment": wrench[:3],
        "gravity_error_force": wrench[3:],
        "static_error": wrench[3:] / (K * lam),
        "lightest_task_mass": float(
            np.min(np.linalg.eigvalsh(np.linalg.inv(Jv_Minv @ J[3:].T)))
        ),
        "sampled_rate": float(
            np.max(np.linalg.eigvals(np.linalg.solve(M, D)).real) * period
        )
        if period > 0
        else 0.0,
    }
