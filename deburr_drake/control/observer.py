"""ChamferObserver: the chamfer quantities both control loops use, from the
measured robot state, the part geometry and the force sensor (Sec. II).

Use: ``ChamferObserver(plant, "tool_tip", contour,
min_tangential_speed=scenario.command.min_tangential_speed)``; its
``chamfer_state`` (layout ``deburr_drake.control.layout.CHAMFER_STATE``) feeds
the command generator, the estimator and the controller."""

from __future__ import annotations

import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.framework import LeafSystem

from deburr_drake.control.kinematics import ToolPoint
from deburr_drake.control.layout import CHAMFER_STATE
from deburr_drake.math.geometry import Contour, contour_at, direction_of_motion
from deburr_drake.math.registration import moved_contour, registration_size

__all__ = [
    "ChamferObserver",
    "RegisteredContour",
    "chamfer_quantities",
    "chamfer_kinematics",
]


class RegisteredContour:
    """The contour a system works on, moved by the value of its
    ``registration`` input port (None: no port, the contour as it is).
    Memo of the last moved contour (not state: a function of the port's
    value)."""

    def __init__(self, port):
        self.port = port
        self._last = None  # (contour id, registration bytes, moved)

    def __call__(self, context, contour):
        """(contour moved by the port's registration, the registration's
        bytes: a memo key)."""
        if self.port is None:
            return contour, b""
        reg = self.port.Eval(context)
        key = (id(contour), reg.tobytes())
        if self._last is None or self._last[:2] != key:
            self._last = (*key, moved_contour(contour, reg))
        return self._last[2], key[1]


def chamfer_quantities(
    contour: Contour, x_p, xdot_p, force, *, min_tangential_speed: float
) -> np.ndarray:
    """The CHAMFER_STATE vector for tool point x_p (m), its velocity (m/s)
    and the measured force on the tool ``force`` (N, world):
    n1 and delta from the contour (eq. 2 with the n1 approximation at x_p),
    n2 the direction of motion (R5), ||f_n|| = -f.n1, ||f_t|| = -f.n2."""
    out = chamfer_kinematics(
        contour, x_p, xdot_p, min_tangential_speed=min_tangential_speed
    )
    _set_force(out, force)
    return out


def chamfer_kinematics(
    contour: Contour, x_p, xdot_p, *, min_tangential_speed: float
) -> np.ndarray:
    """:func:`chamfer_quantities` without the force (f_n = f_t = 0)."""
    n1, tangent, delta, arc = contour.frame(x_p)
    n2 = direction_of_motion(tangent, xdot_p, min_tangential_speed)
    return CHAMFER_STATE.pack(
        x_p=x_p,
        xdot_p=xdot_p,
        n1=n1,
        n2=n2,
        delta=delta,
        delta_dot=float(n1 @ xdot_p),
        f_n=0.0,
        f_t=0.0,
        arc_position=arc,
        n1_rate=contour.n1_rate(x_p, xdot_p),
    )


_N1 = CHAMFER_STATE.slice("n1")
_N2 = CHAMFER_STATE.slice("n2")
_F_N = CHAMFER_STATE.slice("f_n").start
_F_T = CHAMFER_STATE.slice("f_t").start


def _set_force(chamfer, force):
    chamfer[_F_N] = -float(force @ chamfer[_N1])
    chamfer[_F_T] = -float(force @ chamfer[_N2])


class ChamferObserver(LeafSystem):
    """Tool point, chamfer frame, depth and force magnitudes.

    .. pydrake_system::

        name: ChamferObserver
        input_ports:
        - plant_state
        - measured_force
        - registration (optional)
        output_ports:
        - chamfer_state

    - ``plant_state`` (nq + nv): robot positions (m or rad) and velocities.
    - ``measured_force`` (3, N): the force sensor's reading of the force
      of the environment on the tool, world.
    - ``chamfer_state`` (CHAMFER_STATE layout): x_p, xdot_p, n1, n2, delta,
      delta_dot, ||f_n||, ||f_t||, arc position.
    - ``registration`` (only with ``registered=True``;
      deburr_drake.math.registration.registration_size of the contour):
      dx, dy (m), dyaw (rad), dradius (m), or on a 3-D edge the pose and
      size (w (rad), p (m), size (m)): the believed part moved by it
      (deburr_drake.math.registration.moved_contour), from touch probing
      or registration while cutting.

    ``plant`` is a kinematic model of the robot (it is not simulated here);
    its Context is scratch memory for kinematics, not state. A ``tool_point``
    for that frame may be shared with other systems that read the same
    state (its memo then serves all of them). ``contour_step`` (time (s),
    contour) replaces ``contour`` from that time on (a part that moves in
    its fixture, as the controller then sees it).
    """

    def __init__(
        self,
        plant: MultibodyPlant,
        tool_frame_name: str,
        contour: Contour,
        *,
        min_tangential_speed: float,
        tool_point: ToolPoint = None,
        contour_step=None,
        registered: bool = False,
    ):
        super().__init__()
        self.set_name("chamfer_observer")
        self._tool_point = tool_point or ToolPoint(
            plant, plant.GetFrameByName(tool_frame_name)
        )
        self._contour = contour
        self._contour_step = contour_step
        self._min_speed = min_tangential_speed
        nx = plant.num_multibody_states()
        self._state_port = self.DeclareVectorInputPort("plant_state", nx)
        self._force_port = self.DeclareVectorInputPort("measured_force", 3)
        self._registration = RegisteredContour(
            self.DeclareVectorInputPort(
                "registration", registration_size(contour)
            )
            if registered
            else None
        )
        # The kinematic part changes with the plant state only. Drake's
        # cache tracks changes, not values: the output is recomputed at
        # every force sample and after the integrator perturbs and
        # restores the state, where the memo saves the kinematics.
        self._last = None  # (plant state's bytes, its kinematics): a memo
        # Narrow: the state, the force and (a part that moves) the time;
        # not every discrete update of the diagram.
        prerequisites = {self._state_port.ticket(), self._force_port.ticket()}
        if contour_step is not None:
            prerequisites.add(self.time_ticket())
        self.DeclareVectorOutputPort(
            "chamfer_state",
            CHAMFER_STATE.size,
            self._calc,
            prerequisites_of_calc=prerequisites,
        )

    def tool_point(self, plant_state):
        """(x_p, xdot_p) in world for a plant state vector."""
        return self._tool_point(plant_state)

    def _calc(self, context, output):
        state = self._state_port.Eval(context)
        contour, reg = self._registration(
            context,
            contour_at(self._contour, self._contour_step, context.get_time()),
        )
        key = (state.tobytes(), id(contour), reg)
        if self._last is None or key != self._last[0]:
            x_p, xdot_p = self.tool_point(state)
            self._last = (
                key,
                chamfer_kinematics(
                    contour, x_p, xdot_p, min_tangential_speed=self._min_speed
                ),
            )
        chamfer = self._last[1].copy()
        _set_force(chamfer, self._force_port.Eval(context))
        output.SetFromVector(chamfer)
