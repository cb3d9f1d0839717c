"""ForceSensor: the force/torque sensor between flange and tool (a weld
joint of the plant), reduced to the force of the environment on the tool."""

from __future__ import annotations

import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.framework import BasicVector, LeafSystem

from deburr_drake.config import SensorConfig

__all__ = ["ForceSensor"]


class ForceSensor(LeafSystem):
    """Measured force of the environment on the tool, world frame, through a
    first-order low-pass filter (its state; the output has no direct
    feedthrough, which also breaks the loop controller -> plant reaction
    forces -> controller).

    The raw reading is -F_weld - m_tool g: the weld joint's reaction force on
    the tool with the tool's static weight compensated (a tared sensor);
    the tool's inertial force m_tool a remains, as on a real sensor.

    .. pydrake_system::

        name: ForceSensor
        input_ports:
        - reaction_forces
        - plant_state
        output_ports:
        - tool_force

    - ``reaction_forces``: the plant's reaction forces (one SpatialForce per
      joint, on the child body at the child joint frame, in that frame).
    - ``plant_state`` (nq + nv): to rotate the reading into world.
    - ``tool_force`` (3, N): filtered force on the tool, world frame.
    - Continuous state (3, N): the filter.
    """

    def __init__(self, plant: MultibodyPlant, joint_name: str,
                 config: SensorConfig):
        super().__init__()
        config.validate()
        self.set_name("force_sensor")
        self._plant = plant
        self._plant_context = plant.CreateDefaultContext()
        joint = plant.GetJointByName(joint_name)
        self._joint_index = int(joint.index())
        self._child_frame = joint.frame_on_child()
        tool = joint.child_body()
        self._weight = tool.default_mass() * plant.gravity_field().gravity_vector()
        self._bandwidth = 2.0 * np.pi * config.cutoff_frequency  # rad/s
        self.DeclareContinuousState(BasicVector(np.zeros(3)))
        self._reaction_port = self.DeclareAbstractInputPort(
            "reaction_forces",
            plant.get_reaction_forces_output_port().Allocate())
        self._state_port = self.DeclareVectorInputPort(
            "plant_state", plant.num_multibody_states())
        self.DeclareVectorOutputPort(
            "tool_force", 3, self._calc_output,
            prerequisites_of_calc={self.xc_ticket()})

    def raw_force(self, context) -> np.ndarray:
        """The unfiltered, weight-compensated reading (N, world)."""
        reactions = self._reaction_port.Eval(context)
        F = reactions[self._joint_index]
        self._plant.SetPositionsAndVelocities(
            self._plant_context, self._state_port.Eval(context))
        R_WJ = self._child_frame.CalcPoseInWorld(
            self._plant_context).rotation()
        return -(R_WJ @ F.translational()) - self._weight

    def DoCalcTimeDerivatives(self, context, derivatives):  # noqa: N802
        x = context.get_continuous_state_vector().CopyToVector()
        derivatives.get_mutable_vector().SetFromVector(
            self._bandwidth * (self.raw_force(context) - x))

    def _calc_output(self, context, output):
        output.SetFromVector(
            context.get_continuous_state_vector().CopyToVector())
