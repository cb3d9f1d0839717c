"""ToolPoint: a frame's origin and its velocity in world from a plant state,
its orientation and Jacobian, and the robot's gravity forces: cheap when the
same state comes back, exactly or perturbed by a rounding-size amount."""

from __future__ import annotations

from typing import Tuple

import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.multibody.tree import Frame, JacobianWrtVariable

from deburr_drake.config import ConfigError

__all__ = ["ToolPoint"]


class _Anchor:
    """The kinematics at one q (arrays read-only); gravity on request."""

    __slots__ = ("q", "key", "x", "J", "R", "gravity", "mass_matrix")

    def __init__(self, q, key, x, J, R):
        self.q, self.key = q.copy(), key  # key: q as a list, to compare
        self.x, self.J, self.R = x, J, R  # J: spatial, rows angular first
        for array in (x, J, R):
            array.flags.writeable = False
        self.gravity = None
        self.mass_matrix = None


class ToolPoint:
    """x_p (m) and xdot_p (m/s) in world of ``frame``'s origin for a state
    vector [q; v] of ``plant`` (float; its Context here is scratch memory),
    the frame's orientation and spatial Jacobian, and the plant's
    generalized gravity forces. Systems that read the same state share one
    ToolPoint: the first to ask evaluates the plant, the others reuse it.

    cenic linearizes every system that feeds the plant by finite
    differences: per step it evaluates them at the state and at ``nv``
    states whose v differs by about 1.5e-8 and whose q differs by h N dv
    (about 4e-11 rad). Within ``reuse_tolerance`` (rad or m, max norm) of
    the q of the last full evaluation this returns x0 + J0 (q - q0) and
    J0 v, J0 = dx/dq there; the error is second order in q - q0 (below
    1e-16 m at the default 1e-9). The orientation, Jacobian and gravity
    forces are the anchor's (first-order error). Farther away it evaluates
    the plant's kinematics. With a quaternion joint (nq != nv) it reuses
    only the exact q.
    """

    def __init__(
        self,
        plant: MultibodyPlant,
        frame: Frame,
        *,
        reuse_tolerance: float = 1e-9,
    ):
        if not reuse_tolerance >= 0.0:
            raise ConfigError(
                f"reuse_tolerance = {reuse_tolerance!r} is invalid: allowed "
                "a number >= 0 (rad or m)"
            )
        self._plant = plant
        self._context = plant.CreateDefaultContext()
        self._frame = frame
        self._world = plant.world_frame()
        self._nq = plant.num_positions()
        self._tolerance = (
            reuse_tolerance if self._nq == plant.num_velocities() else -1.0
        )
        # The last few anchors: a step evaluates at the states before and
        # after it in turn.
        self._anchors = []
        self._context_anchor = None  # the anchor whose q the context holds
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
        q, v = state[: self._nq], state[self._nq :]
        anchor, dq = self._anchor(q)
        Jv = anchor.J[3:]
        return (
            anchor.x.copy() if dq is None else anchor.x + Jv @ dq,
            Jv @ v,
            Jv,
        )

    def rotation(self, state) -> np.ndarray:
        """R_WF, the frame's orientation in world (3 x 3, read-only): that of
        the anchor, so within ``reuse_tolerance`` of the exact one."""
        return self._anchor_of(state).R

    def control_terms(self, state):
        """(J, R_WF, tau_g) at the anchor, read-only: the spatial Jacobian
        with [omega; xdot_p] = J v in world (6 x nv, rows angular then
        translational), the frame's orientation, and the plant's
        generalized gravity forces tau_g(q) (nv, computed on first
        request)."""
        anchor = self._anchor_of(state)
        if anchor.gravity is None:
            self._set_positions(anchor)
            anchor.gravity = self._plant.CalcGravityGeneralizedForces(
                self._context
            )
            anchor.gravity.flags.writeable = False
        return anchor.J, anchor.R, anchor.gravity

    def mass_matrix(self, state) -> np.ndarray:
        """M(q) of the plant at the anchor (nv x nv, read-only; computed on
        first request)."""
        anchor = self._anchor_of(state)
        if anchor.mass_matrix is None:
            self._set_positions(anchor)
            anchor.mass_matrix = self._plant.CalcMassMatrix(self._context)
            anchor.mass_matrix.flags.writeable = False
        return anchor.mass_matrix

    def _set_positions(self, anchor):
        # Setting the same q again would drop the context's kinematics.
        if self._context_anchor is not anchor:
            self._plant.SetPositions(self._context, anchor.q)
            self._context_anchor = anchor

    def _anchor_of(self, state) -> _Anchor:
        return self._anchor(np.asarray(state, float)[: self._nq])[0]

    def _anchor(self, q):
        """(the anchor for q, q - its q or None when q is exactly its q)."""
        tolerance = self._tolerance
        key = q.tolist()
        for anchor in self._anchors:
            if key == anchor.key:
                return anchor, None
            if all(abs(a - b) <= tolerance for a, b in zip(key, anchor.key)):
                return anchor, q - anchor.q
        plant, ctx = self._plant, self._context
        plant.SetPositions(ctx, q)
        X_WF = self._frame.CalcPoseInWorld(ctx)
        J = plant.CalcJacobianSpatialVelocity(
            ctx,
            JacobianWrtVariable.kV,
            self._frame,
            np.zeros(3),
            self._world,
            self._world,
        )
        anchor = _Anchor(
            q, key, X_WF.translation(), J, X_WF.rotation().matrix()
        )
        self._context_anchor = anchor
        self._anchors.insert(0, anchor)
        del self._anchors[self._MAX_ANCHORS :]
        self.full_evaluations += 1
        return anchor, None
