"""Joint friction: smooth Coulomb friction in the robot's joints, the part of
the D term of (1) that the model file's viscous damping does not carry."""

from __future__ import annotations

from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import (
    DoorHinge,
    DoorHingeConfig,
    JointIndex,
    RevoluteJoint,
)

from deburr_drake.config import ConfigError, RobotConfig

__all__ = ["add_joint_friction"]


def add_joint_friction(plant: MultibodyPlant, config: RobotConfig):
    """Adds tau_f = -F_c tanh(v / v_s) to each joint of ``plant`` (before
    Finalize), F_c from ``config.joint_coulomb_friction`` in joint order,
    v_s = ``config.friction_smoothing_speed``; none if the list is empty.

    Drake's DoorHinge force element is that law when its spring, catch,
    static and viscous terms are zero (its dynamic friction torque is
    -k_df tanh(qdot / qdot_0)): the friction is part of the robot model
    and evaluated in C++. It works on revolute joints only. cenic treats
    force elements explicitly; that is stable while F_c / v_s h stays
    below the joint inertia (paper arm: 0.6 of it at most at h = 2.5 ms).
    Returns the DoorHinge elements."""
    config.validate()
    if not config.joint_coulomb_friction:
        return []
    joints = [plant.get_joint(JointIndex(i)) for i in range(plant.num_joints())]
    moving = [j for j in joints if j.num_velocities() > 0]
    friction = config.joint_coulomb_friction
    if len(friction) != len(moving):
        raise ConfigError(
            f"robot.joint_coulomb_friction = {friction} is invalid: allowed "
            f"a list of {len(moving)} numbers >= 0 (one per joint) or an "
            "empty list"
        )
    elements = []
    for joint, torque in zip(moving, friction):
        if not isinstance(joint, RevoluteJoint):
            raise ConfigError(
                f"robot.joint_coulomb_friction = {friction} is invalid: "
                f"joint '{joint.name()}' is a {joint.type_name()} joint; "
                "joint friction is modelled on revolute joints only "
                "(allowed: an empty list for this robot)"
            )
        if torque == 0.0:
            continue
        hinge = DoorHingeConfig(
            spring_zero_angle_rad=0.0,
            spring_constant=0.0,
            dynamic_friction_torque=torque,
            static_friction_torque=0.0,
            viscous_friction=0.0,
            catch_width=1.0,
            catch_torque=0.0,
            motion_threshold=config.friction_smoothing_speed,
        )
        elements.append(plant.AddForceElement(DoorHinge(joint, hinge)))
    return elements
