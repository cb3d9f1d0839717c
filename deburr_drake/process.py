"""CuttingProcess: the plant-side truth of the chamfering force (eq. (3)),
the contact threshold c0 of eq. (4), the burrs, and the surface finish the
pass leaves. The controller never reads it."""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.multibody.math import SpatialForce
from pydrake.multibody.plant import (ExternallyAppliedSpatialForce,
                                     MultibodyPlant)
from pydrake.systems.framework import LeafSystem, ValueProducer

from deburr_drake.config import BurrConfig, ProcessConfig
from deburr_drake.geometry import Contour
from deburr_drake.layout import VectorLayout
from deburr_drake.metrics import arc_distance

__all__ = ["CuttingProcess", "PROCESS_STATE", "cutting_force",
           "burr_profile", "FinishBins"]

PROCESS_STATE = VectorLayout("process_state", [
    ("delta", 1),            # m, true chamfer depth at the tool
    ("engagement", 1),       # 0..1, smooth contact onset
    ("g", 1),                # N s/m, g of (3)
    ("f_t", 1),              # N, true ||f_t||
    ("f_threshold", 1),      # N, the c0 part of the normal force
    ("v_t", 1),              # m/s, tangential speed
    ("burr_area", 1),        # m^2, burr cross-section at the tool
    ("arc_position", 1),     # m, of the tool on the edge
])


def _smoothstep(x):
    x = min(max(x, 0.0), 1.0)
    return x * x * (3.0 - 2.0 * x)


def burr_profile(arc, burrs: Sequence[BurrConfig], edge_length: float,
                 closed: bool):
    """Burr height (m) at arc positions ``arc`` (m): raised-cosine bumps
    h (1 + cos(2 pi (s - c) / L)) / 2 for |s - c| < L / 2, the centre c a
    fraction of the edge length; on a closed edge the distance wraps."""
    arc = np.asarray(arc, float)
    height = np.zeros_like(arc)
    for burr in burrs:
        d = arc_distance(arc, burr.center_fraction * edge_length,
                         edge_length, closed)
        inside = np.abs(d) < burr.length / 2
        bump = burr.height * 0.5 * (1 + np.cos(2 * np.pi * d / burr.length))
        height = np.maximum(height, np.where(inside, bump, 0.0))
    return height


class FinishBins:
    """Bins of at most ``bin_length`` along an edge of ``length``."""

    def __init__(self, length: float, bin_length: float):
        if not math.isfinite(length):
            raise ValueError("the surface-finish record needs a finite edge "
                             f"length, got {length}")
        self.count = max(1, math.ceil(length / bin_length - 1e-9))
        self.width = length / self.count
        self.centers = (np.arange(self.count) + 0.5) * self.width

    def index(self, s: float) -> int:
        return min(max(int(s // self.width), 0), self.count - 1)


def cutting_force(config: ProcessConfig, contour: Contour, x_p, xdot_p, *,
                  cut_height: float, burr_area: float = 0.0):
    """(force on the tool (3, N, world), PROCESS_STATE vector).

    ||f_t|| = g |v_t| + h |v_n| + P'_th (3), g = k_c (chamfer area + burr
    area), chamfer area = delta * cut_height, v_t the speed along the edge
    (R5: motion along the wall's vertical cuts no chamfer), directed against
    that motion (the direction is regularized below ``smoothing_speed`` so
    the force is continuous); plus the contact threshold c0 along -n1. Both
    ramp in smoothly over the first ``threshold_depth`` of depth."""
    n1, tangent, delta, arc = contour.frame(x_p)
    return _force(config, n1, tangent, delta, arc,
                  np.asarray(xdot_p, float), cut_height, burr_area)


def _force(config: ProcessConfig, n1, tangent, delta, arc, xdot_p,
           cut_height, burr_area):
    v_n = float(n1 @ xdot_p)
    v_along = float(tangent @ xdot_p)
    v_t = abs(v_along)
    on = _smoothstep(delta / config.threshold_depth)
    g = config.cutting_coefficient * (max(delta, 0.0) * cut_height
                                      + burr_area)
    magnitude = on * (g * v_t + config.plunge_coefficient * abs(v_n)
                      + config.threshold_power_force)
    regularized = np.sqrt(v_t * v_t + config.smoothing_speed ** 2)
    f_c0 = on * config.contact_threshold_force
    force = (-magnitude * v_along / regularized) * tangent - f_c0 * n1
    return force, PROCESS_STATE.pack(
        delta=delta, engagement=on, g=g, f_t=magnitude * v_t / regularized,
        f_threshold=f_c0, v_t=v_t, burr_area=burr_area, arc_position=arc)


class CuttingProcess(LeafSystem):
    """Chamfering and threshold forces applied to the tool body; burrs and
    the surface finish along the edge.

    .. pydrake_system::

        name: CuttingProcess
        input_ports:
        - plant_state
        output_ports:
        - spatial_forces
        - process_state
        - burr_height
        - finish_depth

    - ``plant_state`` (nq + nv): the true robot state.
    - ``spatial_forces``: list of ExternallyAppliedSpatialForce for the
      plant's ``applied_spatial_force`` input (force at the tool point).
    - ``process_state`` (PROCESS_STATE layout).
    - ``burr_height`` (bins, m): burr left on the edge.
    - ``finish_depth`` (bins, m): the deepest chamfer cut so far in each bin
      of at most ``finish_bin_length`` of arc (the paper's Fig. 8).
    - Discrete state: burr_height and finish_depth, updated every
      ``record_period``: the bin under the tool records its depth, and
      the burr is removed from the bins the cutter has swept. The burr
      area in g is the one at the cutter's front (arc position + r; the
      tool runs toward +arc).
    """

    def __init__(self, plant: MultibodyPlant, tool_frame_name: str,
                 contour: Contour, config: ProcessConfig, *,
                 cut_height: float, cutter_radius: float):
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
        self._cutter_radius = cutter_radius
        self._bins = FinishBins(contour.length, config.finish_bin_length)
        self._thickness = np.array([self._burr_thickness(s)
                                    for s in self._bins.centers])
        self._burr_index = self.DeclareDiscreteState(
            self.initial_burr_height())
        self._finish_index = self.DeclareDiscreteState(self._bins.count)
        self._state_port = self.DeclareVectorInputPort(
            "plant_state", plant.num_multibody_states())
        self._cache = self.DeclareCacheEntry(
            "process", ValueProducer(
                allocate=AbstractValue.Make(
                    (np.zeros(3), np.zeros(PROCESS_STATE.size))).Clone,
                calc=self._calc_process),
            prerequisites_of_calc={self._state_port.ticket(),
                                   self.xd_ticket()})
        self.DeclareAbstractOutputPort(
            "spatial_forces",
            lambda: AbstractValue.Make([ExternallyAppliedSpatialForce()]),
            self._calc_spatial_forces,
            prerequisites_of_calc={self._cache.ticket()})
        self.DeclareVectorOutputPort(
            "process_state", PROCESS_STATE.size, self._calc_state,
            prerequisites_of_calc={self._cache.ticket()})
        self.DeclareStateOutputPort("burr_height", self._burr_index)
        self.DeclareStateOutputPort("finish_depth", self._finish_index)
        self.DeclarePeriodicDiscreteUpdateEvent(
            config.record_period, 0.0, self._record)

    @property
    def bins(self) -> FinishBins:
        return self._bins

    def initial_burr_height(self) -> np.ndarray:
        """Burr height (m) per bin before the pass."""
        return burr_profile(self._bins.centers, self._config.burrs,
                            self._contour.length, self._contour.closed)

    def _calc_process(self, context, value):
        plant, ctx = self._plant, self._plant_context
        plant.SetPositionsAndVelocities(ctx, self._state_port.Eval(context))
        x_p = self._frame.CalcPoseInWorld(ctx).translation()
        xdot_p = self._frame.CalcSpatialVelocityInWorld(ctx).translational()
        n1, tangent, delta, arc = self._contour.frame(x_p)
        burr = context.get_discrete_state(self._burr_index).get_value()
        k = self._bins.index(self._leading_edge(arc))
        area = burr[k] * self._thickness[k]
        value.set_value(_force(self._config, n1, tangent, delta, arc,
                               xdot_p, self._cut_height, area))

    def _leading_edge(self, s):
        """Arc position of the cutter's front (the traversal direction is
        +arc): the burr is cut there."""
        lead = s + self._cutter_radius
        return lead % self._contour.length if self._contour.closed else lead

    def _burr_thickness(self, s):
        # The thickness of the burr whose span covers s (they do not
        # overlap in the shipped scenarios; the thickest wins otherwise).
        thickness = 0.0
        L, closed = self._contour.length, self._contour.closed
        for burr in self._config.burrs:
            d = arc_distance(s, burr.center_fraction * L, L, closed)
            if abs(d) < burr.length / 2:
                thickness = max(thickness, burr.thickness)
        return thickness

    def _record(self, context, discrete_state):
        _, state = self._cache.Eval(context)
        delta = PROCESS_STATE.get(state, "delta")
        if delta <= 0.0:
            return
        s = PROCESS_STATE.get(state, "arc_position")
        finish = discrete_state.get_mutable_value(self._finish_index)
        k = self._bins.index(s)
        finish[k] = max(finish[k], delta)
        # The cutter (diameter 2 r) has swept the burr behind its front.
        burr = discrete_state.get_mutable_value(self._burr_index)
        d = arc_distance(self._bins.centers, s, self._contour.length,
                         self._contour.closed)
        r, w = self._cutter_radius, self._bins.width
        burr[(d >= -r) & (d < r - w)] = 0.0

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
