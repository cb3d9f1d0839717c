"""ToolPoint: a frame's origin and its velocity in world from a plant state,
cheap when the same state comes back perturbed by a rounding-size amount."""

from __future__ import annotations

from typing import Tuple

import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import Frame, JacobianWrtVariable

__all__ = ["ToolPoint"]


class ToolPoint:
    """x_p (m) and xdot_p (m/s) in world of ``frame``'s origin for a state
    vector [q; v] of ``plant`` (float; its Context here is scratch memory),
    and the frame's orientation.

    cenic linearizes every system that feeds the plant by finite
    differences: per step it evaluates them at the state and at ``nv``
    states whose v differs by about 1.5e-8 and whose q differs by h N dv
    (about 4e-11 rad). Within ``reuse_tolerance`` (rad or m, max norm) of
    the q of the last full evaluation this returns x0 + J0 (q - q0) and
    J0 v, J0 = dx/dq there; the error is second order in q - q0 (below
    1e-16 m at the default 1e-9). Farther away it evaluates the plant's
    kinematics. With a quaternion joint (nq != nv) it always does.
    """

    def __init__(self, plant: MultibodyPlant, frame: Frame, *,
                 reuse_tolerance: float = 1e-9):
        if not reuse_tolerance >= 0.0:
            raise ValueError("reuse_tolerance must be >= 0, got "
                             f"{reuse_tolerance}")
        self._plant = plant
        self._context = plant.CreateDefaultContext()
        self._frame = frame
        self._world = plant.world_frame()
        self._nq = plant.num_positions()
        self._tolerance = (reuse_tolerance
                           if self._nq == plant.num_velocities() else -1.0)
        # The last few anchors (q0, x0, J0, R0): a step evaluates at the
        # states before and after it in turn.
        self._anchors = []
        self.full_evaluations = 0

    _MAX_ANCHORS = 3

    @property
    def frame(self) -> Frame:
        return self._frame

    def __call__(self, state) -> Tuple[np.ndarray, np.ndarray]:
        x, xdot, _ = self.evaluate(state)
        return x, xdot

    def evaluate(self, state) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(x_p, xdot_p, J) with J = dx_p/dv (3 x nv, read-only)."""
        state = np.asarray(state, float)
        q, v = state[:self._nq], state[self._nq:]
        (q0, x0, J0, _), dq = self._anchor(q)
        return (x0.copy() if dq is None else x0 + J0 @ dq), J0 @ v, J0

    def rotation(self, state) -> np.ndarray:
        """R_WF, the frame's orientation in world (3 x 3, read-only): that of
        the anchor, so within ``reuse_tolerance`` of the exact one."""
        state = np.asarray(state, float)
        return self._anchor(state[:self._nq])[0][3]

    def _anchor(self, q):
        """((q0, x0, J0, R0), q - q0 or None when q is a new anchor)."""
        tolerance = self._tolerance
        for anchor in self._anchors:
            dq = q - anchor[0]
            if max(map(abs, dq.tolist())) <= tolerance:
                return anchor, dq
        plant, ctx = self._plant, self._context
        plant.SetPositions(ctx, q)
        X_WF = self._frame.CalcPoseInWorld(ctx)
        J0 = plant.CalcJacobianTranslationalVelocity(
            ctx, JacobianWrtVariable.kV, self._frame, np.zeros(3),
            self._world, self._world)
        anchor = (q.copy(), X_WF.translation(), J0,
                  X_WF.rotation().matrix())
        for array in anchor[1:]:
            array.flags.writeable = False
        self._anchors.insert(0, anchor)
        del self._anchors[self._MAX_ANCHORS:]
        self.full_evaluations += 1
        return anchor, None
