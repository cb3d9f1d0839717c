"""Touch probing of a mesh part, the cell's side: the touches planned on
the believed part (once per run, into the plan) and the contact the probe
feels on the real part.

- :func:`plan_mesh_probe`: the believed part's surface, its hole's faces
  (the edge's loop round a cylindrical wall), the touches
  (deburr_drake.math.touch_plan: reachable along the face's normal and
  straight up to the safe height) and the safe height, as a
  deburr_drake.control.mesh_probe.MeshProbePlan.
- :class:`TouchContact`: while the sequence touches, the real part's
  surface pushes the probe (a ball of the cutter's radius about the tool
  point) along the nearest face's normal, with the contact law the probe's
  stiffness model has (``localisation.probe``: F = c depth^n exp(-b
  depth), c such that F / depth is ``contact_stiffness`` at
  ``force_threshold``) and the material's Hunt-Crossley dissipation; the
  compliant band along the edge (the material the cut meets) is then
  cancelled on the tool, so a touch near the edge feels the part's
  surface once. From the entry on it applies nothing.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.multibody.math import SpatialForce
from pydrake.multibody.plant import ExternallyAppliedSpatialForce
from pydrake.systems.framework import LeafSystem

from deburr_drake.cell.process import PROCESS_STATE
from deburr_drake.config import ConfigError, Scenario
from deburr_drake.control.kinematics import ToolPoint
from deburr_drake.control.mesh_probe import MeshProbePlan
from deburr_drake.math.mesh_registration import (
    MeshSurface,
    closest_on_triangles,
    cylinder_faces,
)
from deburr_drake.math.touch_plan import (
    TouchPlan,
    plan_touches,
    reachable_faces,
)

__all__ = [
    "plan_mesh_probe",
    "real_surface",
    "TouchContact",
    "TouchGate",
    "touch_law",
]

#: m, the probe's travels keep this much more above the part's top than
#: the standoff: the real part sits up to about 1 mm and 1 degree off.
_SAFE_MARGIN = 0.003
#: m, a hole's faces: every corner within this of the hole's radius.
_HOLE_TOLERANCE = 2.0e-4
#: m, the ball this much farther from every face than its radius: no
#: face is held (nothing to touch before the next sample).
_NEAR = 0.005
#: The fewest touches that pin six degrees of freedom and a size.
_FEWEST = 7


def _surface(part) -> MeshSurface:
    return MeshSurface(part.mesh.vertices, part.mesh.faces)


def _hole_faces(surface: MeshSurface, curve):
    """(F,) bool: the faces of the hole the edge runs round (its loop on
    a cylindrical wall, deburr_drake.math.mesh_part.hole_axis), None when
    the edge is not round a hole. The radius: the edge's points' mean
    distance from the axis through their centroid."""
    from deburr_drake.math.mesh_part import hole_axis

    hole = hole_axis(curve.chain)
    if hole is None:
        return None
    axis = hole[0]
    points = np.asarray(curve.chain.points, float)
    centre = points.mean(axis=0)
    d = points - centre
    radius = float(
        np.mean(np.linalg.norm(d - np.outer(d @ axis, axis), axis=1))
    )
    faces = cylinder_faces(
        surface,
        point=centre,
        axis=axis,
        radius=radius,
        tolerance=_HOLE_TOLERANCE,
    )
    return faces if faces.any() else None


def _allowance(surface: MeshSurface, origin, probe) -> np.ndarray:
    """(F,) m: how far each face's centroid may move along its normal
    when the part is off by up to ``pose_offset_allowance`` along and
    ``pose_turn_allowance`` about each axis through ``origin`` (small
    turns: omega . ((c - o) x m))."""
    m = surface.normals
    arm = surface.centroid - np.asarray(origin, float)
    return probe.pose_offset_allowance * np.abs(m).sum(
        axis=1
    ) + probe.pose_turn_allowance * np.abs(np.cross(arm, m)).sum(axis=1)


def _toured(touches: TouchPlan, start) -> TouchPlan:
    """The touches in the order a nearest-neighbour tour from ``start``
    (m) visits them (the order does not change what they pin)."""
    left = list(range(len(touches.points)))
    order, here = [], np.asarray(start, float)
    while left:
        k = min(left, key=lambda i: np.linalg.norm(touches.points[i] - here))
        order.append(k)
        left.remove(k)
        here = touches.points[k]
    return dataclasses.replace(
        touches,
        points=touches.points[order],
        normals=touches.normals[order],
        faces=touches.faces[order],
    )


def plan_mesh_probe(scenario: Scenario, start) -> MeshProbePlan:
    """The touches of ``localisation.probe`` on the believed mesh part
    (``part.pose``): ``points`` of them (at least 7: six degrees of
    freedom and a hole's size) on the faces the probe reaches along
    their normal and from above, pinning the pose within the touch plan's
    measure. ConfigError naming ``localisation.probe.points`` when they
    cannot (the degree of freedom they pin least). The touches are
    visited nearest first from ``start`` (m, the tool's)."""
    part, probe = scenario.part, scenario.localisation.probe
    if probe.points < _FEWEST:
        raise ConfigError(
            f"localisation.probe.points = {probe.points!r} is invalid on a "
            f"mesh part: allowed >= {_FEWEST} (six degrees of freedom and "
            "a hole's size)"
        )
    mesh, curve, _ = part.edge.mesh_edge(part.pose)
    surface = _surface(mesh)
    radius = scenario.tool.cutter_radius
    allowance = _allowance(surface, part.pose.xyz, probe)
    clearance = max(probe.standoff, probe.retract) + allowance
    top = float(surface.vertices[:, 2].max())
    safe = top + radius + float(clearance.max()) + _SAFE_MARGIN
    bottom = float(surface.vertices[:, 2].min())
    reachable = reachable_faces(
        surface,
        probe_radius=radius,
        clearance=clearance,
        rise=safe - bottom,
    )
    sized = _hole_faces(surface, curve) if probe.fit_radius else None
    try:
        touches = plan_touches(
            surface, count=probe.points, reachable=reachable, sized_faces=sized
        )
    except ValueError as e:
        raise ConfigError(f"localisation.probe.points = {probe.points}: {e}")
    touches = _toured(touches, start)
    return MeshProbePlan(
        surface, sized, touches, safe, radius, allowance[touches.faces]
    )


def real_surface(scenario: Scenario) -> MeshSurface:
    """The real part's surface (m, world): the file at ``part.pose``
    moved by ``part_error``."""
    part = scenario.part
    mesh, _, _ = part.edge.mesh_edge(part.real_pose(scenario.part_error))
    return _surface(mesh)


def touch_law(scenario: Scenario):
    """(c, n, b): the probe's contact law F = c depth^n exp(-b depth)
    (N, m), c such that F / depth is ``contact_stiffness`` at
    ``force_threshold``."""
    p = scenario.localisation.probe
    n, b = p.contact_exponent, p.contact_exponent_slope
    depth = p.force_threshold / p.contact_stiffness
    return p.force_threshold / (depth**n * math.exp(-b * depth)), n, b


class TouchContact(LeafSystem):
    """The probe's contact with the real part while the sequence touches.

    .. pydrake_system::

        name: TouchContact
        input_ports:
        - plant_state
        - touching
        - contact_results
        - body_poses
        output_ports:
        - spatial_forces

    - ``plant_state`` (nq + nv): the true robot state.
    - ``touching`` (1): the sequence's (1 until the entry).
    - ``contact_results``, ``body_poses``: the plant's.
    - ``spatial_forces``: on the tool body, while touching: the part's
      push on the ball about the tool point, F = c d^n exp(-b d) (1 +
      h d'), d the ball's radius less its centre's distance to the real
      part's (``surface``) nearest point, h the Hunt-Crossley
      dissipation (s/m), along the way from that point to the centre;
      and minus the compliant band's contact force on the tool's
      geometries. Nothing otherwise.
    - Discrete state (4): the nearest face's point and its normal's
      index, sampled every ``sample_period`` (the tool moves microns in
      one: the face's plane serves between samples).
    """

    def __init__(
        self,
        plant,
        *,
        tool_frame: str,
        surface: MeshSurface,
        radius: float,
        law,
        dissipation: float,
        sample_period: float,
        tool_point: ToolPoint,
    ):
        super().__init__()
        self.set_name("touch_contact")
        self._surface = surface
        self._radius = radius
        self._law = law
        self._dissipation = dissipation
        self._tool_point = tool_point
        frame = plant.GetFrameByName(tool_frame)
        body = frame.body()
        self._body = body.index()
        self._geometries = set(plant.GetCollisionGeometriesForBody(body))
        self._p_BT = np.asarray(frame.GetFixedPoseInBodyFrame().translation())
        corners = np.stack(surface.corners)  # (3, F, 3)
        self._low, self._high = corners.min(axis=0), corners.max(axis=0)
        self._state_port = self.DeclareVectorInputPort(
            "plant_state", plant.num_multibody_states()
        )
        self._touching = self.DeclareVectorInputPort("touching", 1)
        self._results = self.DeclareAbstractInputPort(
            "contact_results",
            plant.get_contact_results_output_port().Allocate(),
        )
        self._poses = self.DeclareAbstractInputPort(
            "body_poses", plant.get_body_poses_output_port().Allocate()
        )
        # The nearest face: its point (m) and index.
        self._face = self.DeclareDiscreteState(np.array([0, 0, 0, -1.0]))
        self.DeclarePeriodicDiscreteUpdateEvent(
            sample_period, 0.0, self._update
        )
        self.DeclareInitializationDiscreteUpdateEvent(self._update)
        # The plant's contact results depend on its state alone (a
        # continuous plant), but the plant reports them as fed through
        # from its geometry input, which its applied forces feed: a loop
        # in name only. The output says what it depends on: the plant's
        # state (through the ports that carry it), the flag, the face.
        self.DeclareAbstractOutputPort(
            "spatial_forces",
            lambda: AbstractValue.Make([ExternallyAppliedSpatialForce()]),
            self._calc,
            prerequisites_of_calc={
                self._state_port.ticket(),
                self._touching.ticket(),
                self._poses.ticket(),
                self.discrete_state_ticket(self._face),
            },
        )

    def _update(self, context, discrete_state):
        none = [0.0, 0.0, 0.0, -1.0]
        if self._touching.Eval(context)[0] < 0.5:
            discrete_state.set_value(self._face, none)
            return
        x_p, _, _ = self._tool_point.evaluate(self._state_port.Eval(context))
        x = np.asarray(x_p, float)
        # Each face's box is no nearer than the face: the faces whose box
        # lies within the nearest corner's distance hold the nearest point.
        gap = np.maximum(self._low - x, 0.0) + np.maximum(x - self._high, 0.0)
        box = np.einsum("ij,ij->i", gap, gap)
        corner = float(np.min(np.sum((self._surface.vertices - x) ** 2, 1)))
        near = np.flatnonzero(box <= corner)
        if box[near].min() > (self._radius + _NEAR) ** 2:
            discrete_state.set_value(self._face, none)  # far from the part
            return
        a, b, c = (k[near] for k in self._surface.corners)
        q = closest_on_triangles(x[None, :], a, b, c)[0]
        k = int(np.argmin(np.sum((q - x) ** 2, axis=1)))
        discrete_state.set_value(self._face, [*q[k], float(near[k])])

    def _calc(self, context, output):
        if self._touching.Eval(context)[0] < 0.5:
            output.set_value([])
            return
        forces = self._band_cancelled(context)
        face = context.get_discrete_state(self._face).get_value()
        j = int(face[3])
        if j >= 0:
            x_p, xdot_p, _ = self._tool_point.evaluate(
                self._state_port.Eval(context)
            )
            # The ball's overlap with the part: its radius less the
            # distance to the face's nearest point (off a facet's middle,
            # by a crease, that point is on the crease: the distance
            # along the face's normal alone would overstate the overlap);
            # pushed out along the way to that point.
            m = self._surface.normals[j]
            d = np.asarray(x_p) - face[:3]
            along = float(m @ d)
            length = float(np.linalg.norm(d))
            if along > 0.0 and length > 0.0:
                m, along = d / length, length
            depth = self._radius - along
            if depth > 0.0:
                c, n, b = self._law
                rate = -float(m @ np.asarray(xdot_p))
                push = (
                    c
                    * depth**n
                    * math.exp(-b * depth)
                    * max(0.0, 1.0 + self._dissipation * rate)
                )
                f = ExternallyAppliedSpatialForce()
                f.body_index = self._body
                f.p_BoBq_B = self._p_BT
                f.F_Bq_W = SpatialForce(np.zeros(3), push * m)
                forces.append(f)
        output.set_value(forces)

    def _band_cancelled(self, context) -> list:
        """Minus every hydroelastic contact force on the tool's geometries,
        shifted to the tool body's origin."""
        results = self._results.Eval(context)
        X_WB = self._poses.Eval(context)[int(self._body)]
        p_WBo = np.asarray(X_WB.translation())
        moment, force = np.zeros(3), np.zeros(3)
        any_contact = False
        for i in range(results.num_hydroelastic_contacts()):
            info = results.hydroelastic_contact_info(i)
            surface = info.contact_surface()
            if surface.id_M() in self._geometries:
                sign = 1.0
            elif surface.id_N() in self._geometries:
                sign = -1.0
            else:
                continue
            F = info.F_Ac_W()
            f_Ac = sign * np.asarray(F.translational())
            # The force at Ac, moved to the body's origin.
            arm = np.asarray(surface.centroid()) - p_WBo
            moment += sign * np.asarray(F.rotational()) + np.cross(arm, f_Ac)
            force += f_Ac
            any_contact = True
        if not any_contact:
            return []
        f = ExternallyAppliedSpatialForce()
        f.body_index = self._body
        f.p_BoBq_B = np.zeros(3)
        f.F_Bq_W = SpatialForce(-moment, -force)
        return [f]


class TouchGate(LeafSystem):
    """The process's state as the guards see it: while the probe touches a
    mesh part the true chamfer depth (the tool point against the edge,
    far from it on most touches) is 0; from the entry on unchanged.

    .. pydrake_system::

        name: TouchGate
        input_ports:
        - touching
        - process_state
        output_ports:
        - process_state
    """

    def __init__(self):
        super().__init__()
        self.set_name("touch_gate")
        self._touching = self.DeclareVectorInputPort("touching", 1)
        self._process = self.DeclareVectorInputPort(
            "process_state", PROCESS_STATE.size
        )
        self.DeclareVectorOutputPort(
            "process_state", PROCESS_STATE.size, self._calc
        )

    def _calc(self, context, output):
        state = self._process.Eval(context).copy()
        if self._touching.Eval(context)[0] > 0.5:
            state[PROCESS_STATE.slice("delta")] = 0.0
        output.SetFromVector(state)
