"""CuttingProcess: the plant-side truth of the chamfering force (eq. (3)) and
of the contact threshold c0 of eq. (4). The controller never reads it."""

from __future__ import annotations

import numpy as np
from pydrake.multibody.math import SpatialForce
from pydrake.multibody.plant import (ExternallyAppliedSpatialForce,
                                     MultibodyPlant)
from pydrake.systems.framework import LeafSystem

from deburr_drake.config import ProcessConfig
from deburr_drake.geometry import Contour
from deburr_drake.layout import VectorLayout

__all__ = ["CuttingProcess", "PROCESS_STATE", "cutting_force"]

PROCESS_STATE = VectorLayout("process_state", [
    ("delta", 1),            # m, true chamfer depth at the tool
    ("engagement", 1),       # 0..1, smooth contact onset
    ("g", 1),                # N s/m, g of (3)
    ("f_t", 1),              # N, true ||f_t||
    ("f_threshold", 1),      # N, the c0 part of the normal force
    ("v_t", 1),              # m/s, tangential speed
])


def _smoothstep(x):
    x = min(max(x, 0.0), 1.0)
    return x * x * (3.0 - 2.0 * x)


def cutting_force(config: ProcessConfig, contour: Contour, x_p, xdot_p, *,
                  cut_height: float):
    """(force on the tool (3, N, world), PROCESS_STATE vector).

    ||f_t|| = g |v_t| + h |v_n| + P'_th (3), g = k_c * chamfer area with the
    area delta * cut_height, directed against the tangential motion (the
    direction is regularized below ``smoothing_speed`` so the force is
    continuous); plus the contact threshold c0 along -n1. Both ramp in
    smoothly over the first ``threshold_depth`` of depth."""
    n1 = contour.n1(x_p)
    delta = float(contour.depth(x_p))
    v_n = float(n1 @ xdot_p)
    v_t_vec = xdot_p - v_n * n1
    v_t = float(np.sqrt(v_t_vec @ v_t_vec))
    on = _smoothstep(delta / config.threshold_depth)
    g = config.cutting_coefficient * max(delta, 0.0) * cut_height
    f_t = on * (g * v_t + config.plunge_coefficient * abs(v_n)
                + config.threshold_power_force)
    direction = v_t_vec / np.sqrt(v_t * v_t + config.smoothing_speed ** 2)
    f_c0 = on * config.contact_threshold_force
    force = -f_t * direction - f_c0 * n1
    return force, PROCESS_STATE.pack(delta=delta, engagement=on, g=g,
                                     f_t=f_t * v_t / np.hypot(
                                         v_t, config.smoothing_speed),
                                     f_threshold=f_c0, v_t=v_t)


class CuttingProcess(LeafSystem):
    """Chamfering and threshold forces applied to the tool body.

    .. pydrake_system::

        name: CuttingProcess
        input_ports:
        - plant_state
        output_ports:
        - spatial_forces
        - process_state

    - ``plant_state`` (nq + nv): the true robot state.
    - ``spatial_forces``: list of ExternallyAppliedSpatialForce for the
      plant's ``applied_spatial_force`` input (force at the tool point).
    - ``process_state`` (PROCESS_STATE layout).
    """

    def __init__(self, plant: MultibodyPlant, tool_frame_name: str,
                 contour: Contour, config: ProcessConfig, *,
                 cut_height: float):
        super().__init__()
        config.validate()
        self.set_name("cutting_process")
        self._plant = plant
        self._plant_context = plant.CreateDefaultContext()
        self._frame = plant.GetFrameByName(tool_frame_name)
        self._body_index = self._frame.body().index()
        self._p_BoQ_B = self._frame.GetFixedPoseInBodyFrame().translation()
        self._contour = contour
        self._config = config
        self._cut_height = cut_height
        self._state_port = self.DeclareVectorInputPort(
            "plant_state", plant.num_multibody_states())
        self._cache = self.DeclareCacheEntry(
            "process", _value_producer(self._calc_process),
            prerequisites_of_calc={self._state_port.ticket()})
        self.DeclareAbstractOutputPort(
            "spatial_forces", lambda: _abstract_list(),
            self._calc_spatial_forces,
            prerequisites_of_calc={self._cache.ticket()})
        self.DeclareVectorOutputPort(
            "process_state", PROCESS_STATE.size, self._calc_state,
            prerequisites_of_calc={self._cache.ticket()})

    def _calc_process(self, context, value):
        plant, ctx = self._plant, self._plant_context
        plant.SetPositionsAndVelocities(ctx, self._state_port.Eval(context))
        x_p = self._frame.CalcPoseInWorld(ctx).translation()
        xdot_p = self._frame.CalcSpatialVelocityInWorld(ctx).translational()
        value.set_value(cutting_force(self._config, self._contour, x_p,
                                      xdot_p, cut_height=self._cut_height))

    def _calc_spatial_forces(self, context, output):
        force, _ = self._cache.Eval(context)
        applied = ExternallyAppliedSpatialForce()
        applied.body_index = self._body_index
        applied.p_BoBq_B = self._p_BoQ_B
        applied.F_Bq_W = SpatialForce(np.zeros(3), force)
        output.set_value([applied])

    def _calc_state(self, context, output):
        _, state = self._cache.Eval(context)
        output.SetFromVector(state)


def _abstract_list():
    from pydrake.common.value import AbstractValue
    return AbstractValue.Make([ExternallyAppliedSpatialForce()])


def _value_producer(calc):
    from pydrake.common.value import AbstractValue
    from pydrake.systems.framework import ValueProducer
    return ValueProducer(
        allocate=AbstractValue.Make((np.zeros(3),
                                     np.zeros(PROCESS_STATE.size))).Clone,
        calc=calc)
