"""ChamferObserver: the chamfer quantities both control loops use, from the
measured robot state, the part geometry and the force sensor (Sec. II)."""

from __future__ import annotations

import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.framework import LeafSystem

from deburr_drake.geometry import Contour
from deburr_drake.layout import CHAMFER_STATE

__all__ = ["ChamferObserver", "chamfer_quantities"]


def chamfer_quantities(contour: Contour, x_p, xdot_p, force, *,
                       min_tangential_speed: float) -> np.ndarray:
    """The CHAMFER_STATE vector for tool point x_p (m), its velocity (m/s)
    and the measured force on the tool ``force`` (N, world):
    n1 and delta from the contour (eq. 2 with the n1 approximation at x_p),
    n2 the direction of motion (R5), ||f_n|| = -f.n1, ||f_t|| = -f.n2."""
    n1, _, delta, arc = contour.frame(x_p)
    n2 = contour.n2(x_p, xdot_p, min_tangential_speed)
    return CHAMFER_STATE.pack(
        x_p=x_p, xdot_p=xdot_p, n1=n1, n2=n2, delta=delta,
        delta_dot=float(n1 @ xdot_p), f_n=-float(force @ n1),
        f_t=-float(force @ n2), arc_position=arc)


class ChamferObserver(LeafSystem):
    """Tool point, chamfer frame, depth and force magnitudes.

    .. pydrake_system::

        name: ChamferObserver
        input_ports:
        - plant_state
        - tool_force
        output_ports:
        - chamfer_state

    - ``plant_state`` (nq + nv): robot positions (m or rad) and velocities.
    - ``tool_force`` (3, N): force of the environment on the tool, world.
    - ``chamfer_state`` (CHAMFER_STATE layout): x_p, xdot_p, n1, n2, delta,
      delta_dot, ||f_n||, ||f_t||, arc position.

    ``plant`` is a kinematic model of the robot (it is not simulated here);
    its Context is scratch memory for kinematics, not state.
    """

    def __init__(self, plant: MultibodyPlant, tool_frame_name: str,
                 contour: Contour, *, min_tangential_speed: float):
        super().__init__()
        self.set_name("chamfer_observer")
        self._plant = plant
        self._plant_context = plant.CreateDefaultContext()
        self._frame = plant.GetFrameByName(tool_frame_name)
        self._contour = contour
        self._min_speed = min_tangential_speed
        nx = plant.num_multibody_states()
        self._state_port = self.DeclareVectorInputPort("plant_state", nx)
        self._force_port = self.DeclareVectorInputPort("tool_force", 3)
        self.DeclareVectorOutputPort("chamfer_state", CHAMFER_STATE.size,
                                     self._calc)

    def tool_point(self, plant_state):
        """(x_p, xdot_p) in world for a plant state vector."""
        plant, ctx = self._plant, self._plant_context
        plant.SetPositionsAndVelocities(ctx, plant_state)
        x_p = self._frame.CalcPoseInWorld(ctx).translation()
        xdot_p = self._frame.CalcSpatialVelocityInWorld(ctx).translational()
        return x_p, xdot_p

    def _calc(self, context, output):
        x_p, xdot_p = self.tool_point(self._state_port.Eval(context))
        output.SetFromVector(chamfer_quantities(
            self._contour, x_p, xdot_p, self._force_port.Eval(context),
            min_tangential_speed=self._min_speed))
