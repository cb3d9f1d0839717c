"""JointFriction: smooth Coulomb friction in the robot's joints, the part of
the D term of (1) that the model file's viscous damping does not carry."""

from __future__ import annotations

import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.framework import LeafSystem

from deburr_drake.config import ConfigError, RobotConfig

__all__ = ["JointFriction"]


class JointFriction(LeafSystem):
    """tau_f = -F_c tanh(v / v_s) per generalized velocity.

    .. pydrake_system::

        name: JointFriction
        input_ports:
        - plant_state
        output_ports:
        - generalized_force

    - ``plant_state`` (nq + nv): only the velocities are read.
    - ``generalized_force`` (nv, N or N m): for the plant's
      ``applied_generalized_force`` input.
    """

    def __init__(self, plant: MultibodyPlant, config: RobotConfig):
        super().__init__()
        config.validate()
        self.set_name("joint_friction")
        nv = plant.num_velocities()
        friction = np.asarray(config.joint_coulomb_friction, float)
        if friction.size != nv:
            raise ConfigError(
                f"robot.joint_coulomb_friction = {config.joint_coulomb_friction}"
                f" is invalid: allowed a list of {nv} numbers >= 0 (one per "
                "joint) or an empty list")
        self._friction = friction
        self._nq = plant.num_positions()
        self._speed = config.friction_smoothing_speed
        self._state_port = self.DeclareVectorInputPort(
            "plant_state", plant.num_multibody_states())
        self.DeclareVectorOutputPort("generalized_force", nv, self._calc)

    def _calc(self, context, output):
        v = self._state_port.Eval(context)[self._nq:]
        output.SetFromVector(-self._friction * np.tanh(v / self._speed))
