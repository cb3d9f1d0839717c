"""ForceSensor: the force/torque sensor between flange and tool (a weld
joint of the plant), sampled and low-pass filtered like a real one.

Use: ``ForceSensor(plant, "ft_sensor", scenario.sensor)`` on a plant with
a weld joint between flange and tool; its ``measured_force`` output is
what the observer and the controller read."""

from __future__ import annotations

import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.framework import BasicVector, LeafSystem

from deburr_drake.config import ConfigError, SensorConfig
from deburr_drake.control.kinematics import ToolPoint

__all__ = ["ForceSensor"]


class ForceSensor(LeafSystem):
    """Measured force of the environment on the tool, world frame.

    Every ``sample_period`` the sensor reads the weld joint's reaction force,
    adds ``noise_std`` times the ``noise`` input (a unit Gaussian sample,
    e.g. from a seeded RandomSource) and passes it through a first-order
    low-pass of cutoff ``cutoff_frequency`` (the exact discretization,
    y += (1 - exp(-2 pi f_c T_s)) (raw - y)). The output is the filter's
    state, so it has no direct feedthrough: that also breaks the loop
    controller -> plant reaction forces -> controller.

    The raw reading is -F_weld - m_tool g + f_applied: the weld's reaction
    force on the tool with the tool's static weight compensated (a tared
    sensor), plus the cutting force, which the cell applies through the
    joints (the equivalent generalized force J^T f_applied, computed in
    C++): the weld would carry it if it were applied to the tool body, and
    the motion is the same either way. The tool's inertial force m_tool a
    remains, as on a real sensor.

    .. pydrake_system::

        name: ForceSensor
        input_ports:
        - reaction_forces
        - plant_state
        - applied_force (optional)
        - noise
        output_ports:
        - measured_force

    - ``reaction_forces``: the plant's reaction forces (one SpatialForce per
      joint, on the child body at the child joint frame, in that frame).
    - ``plant_state`` (nq + nv): to rotate the reading into world.
    - ``applied_force`` (3, N, world): force on the tool applied through
      the joints (zero if unconnected).
    - ``noise`` (3): unit-variance samples, scaled by ``noise_std`` (N).
    - ``measured_force`` (3, N): filtered force on the tool, world frame.
    - Discrete state (3, N): the filter, updated every ``sample_period``.
    - Numeric parameter (1, N): ``noise_std`` (:meth:`set_noise_std`).

    A ``tool_point`` (a ToolPoint of a frame on the sensor's child body, on
    a model with the plant's joints) shares its kinematics for the reading's
    rotation into world; without one the sensor computes it itself.
    """

    def __init__(
        self,
        plant: MultibodyPlant,
        joint_name: str,
        config: SensorConfig,
        *,
        tool_point: ToolPoint | None = None,
    ):
        super().__init__()
        config.validate()
        self.set_name("force_sensor")
        self._plant = plant
        self._plant_context = plant.CreateDefaultContext()
        joint = plant.GetJointByName(joint_name)
        self._joint_index = int(joint.index())
        self._child_frame = joint.frame_on_child()
        tool = joint.child_body()
        self._tool_point = tool_point
        if tool_point is not None:
            # R_WJ = R_WF R_FJ, F the tool point's frame, fixed on the body.
            frame = plant.GetFrameByName(tool_point.frame.name())
            if frame.body().index() != tool.index():
                raise ConfigError(
                    f"tool_point's frame {frame.name()!r} is not on the "
                    f"sensor's child body {tool.name()!r}"
                )
            context = plant.CreateDefaultContext()
            self._R_FJ = (
                frame.CalcPoseInWorld(context).rotation().inverse()
                @ self._child_frame.CalcPoseInWorld(context).rotation()
            ).matrix()
        self._weight = tool.default_mass() * np.asarray(
            plant.gravity_field().gravity_vector()
        )
        # noise_std is a numeric parameter: the analyses switch the noise
        # off in a Context.
        self._noise_std = self.DeclareNumericParameter(
            BasicVector([config.noise_std])
        )
        self._alpha = 1.0 - np.exp(
            -2.0 * np.pi * config.cutoff_frequency * config.sample_period
        )
        self._state_index = self.DeclareDiscreteState(3)
        self._reaction_port = self.DeclareAbstractInputPort(
            "reaction_forces",
            plant.get_reaction_forces_output_port().Allocate(),
        )
        self._state_port = self.DeclareVectorInputPort(
            "plant_state", plant.num_multibody_states()
        )
        self._applied_port = self.DeclareVectorInputPort("applied_force", 3)
        self._noise_port = self.DeclareVectorInputPort("noise", 3)
        self.DeclarePeriodicDiscreteUpdateEvent(
            config.sample_period, 0.0, self._update
        )
        self.DeclareStateOutputPort("measured_force", self._state_index)

    def set_noise_std(self, context, noise_std: float):
        """The noise's standard deviation (N) in the sensor's
        ``context``."""
        context.get_mutable_numeric_parameter(self._noise_std).SetAtIndex(
            0, noise_std
        )

    def raw_force(self, context) -> np.ndarray:
        """The unfiltered, noise-free, weight-compensated reading (N,
        world)."""
        F = self._reaction_port.Eval(context)[self._joint_index]
        state = self._state_port.Eval(context)
        if self._tool_point is not None:
            R_WJ = self._tool_point.rotation(state) @ self._R_FJ
        else:
            self._plant.SetPositionsAndVelocities(self._plant_context, state)
            R_WJ = (
                self._child_frame.CalcPoseInWorld(self._plant_context)
                .rotation()
                .matrix()
            )
        raw = -(R_WJ @ F.translational()) - self._weight
        if self._applied_port.HasValue(context):
            raw = raw + self._applied_port.Eval(context)
        return raw

    def _update(self, context, discrete_state):
        y = context.get_discrete_state(self._state_index).get_value()
        noise_std = context.get_numeric_parameter(self._noise_std).GetAtIndex(0)
        raw = self.raw_force(context) + noise_std * self._noise_port.Eval(
            context
        )
        discrete_state.set_value(self._state_index, y + self._alpha * (raw - y))
