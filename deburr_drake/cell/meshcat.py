"""Meshcat for the deburring cell: the arm, tool, part and burrs live or in
a self-contained HTML replay, with the contact force as an arrow and the
edge coloured as it is chamfered (the burrs disappear as the tool passes).

Use: ``meshcat = Meshcat()``, ``make_deburring_diagram(scenario=s,
meshcat=meshcat)``, ``meshcat.StartRecording(frames_per_second=10.0)``,
simulate, then :func:`deburr_drake.runs.replay.write_recording`."""

from __future__ import annotations

from typing import Dict

import numpy as np
from pydrake.geometry import (
    Box,
    Meshcat,
    MeshcatVisualizer,
    MeshcatVisualizerParams,
    Rgba,
    Role,
)
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.multibody.meshcat import ContactVisualizer, ContactVisualizerParams
from pydrake.systems.framework import DiagramBuilder, LeafSystem

from deburr_drake.cell.process import CuttingProcess

__all__ = [
    "EdgeVisualizer",
    "add_meshcat",
    "add_job_meshcat",
    "UNCUT",
    "CUT",
    "BURR",
]

UNCUT = Rgba(0.55, 0.55, 0.6, 1.0)
CUT = Rgba(0.1, 0.8, 0.2, 1.0)
BURR = Rgba(0.85, 0.1, 0.1, 1.0)


class EdgeVisualizer(LeafSystem):
    """Draws the part's edge in ``segments`` pieces, each grey until the
    cutter has chamfered it, then green, and the burrs in red until the
    cutter removes them. Publishes every ``publish_period``; while Meshcat
    records, the changes are keyframed at the simulated time.

    .. pydrake_system::

        name: EdgeVisualizer
        input_ports:
        - finish_depth
        - burr_height

    Both inputs are the CuttingProcess's outputs of the same names (m per
    bin of its FinishBins). The visualizer remembers what it last sent to
    Meshcat (a cache of the browser's scene, not simulation state).
    """

    def __init__(
        self,
        meshcat: Meshcat,
        process: CuttingProcess,
        *,
        edge_points,
        burr_initial,
        edge_axes=None,
        segments: int = 120,
        publish_period: float = 0.1,
        prefix: str = "deburring",
    ):
        super().__init__()
        self.set_name("edge_visualizer")
        self._meshcat = meshcat
        self._prefix = prefix
        n_bins = process.bins.count
        edges = np.linspace(0, n_bins, segments + 1).astype(int)
        self._groups = [
            slice(a, b) for a, b in zip(edges[:-1], edges[1:]) if b > a
        ]
        self._finish_port = self.DeclareVectorInputPort("finish_depth", n_bins)
        self._burr_port = self.DeclareVectorInputPort("burr_height", n_bins)
        self.DeclarePeriodicPublishEvent(publish_period, 0.0, self._publish)
        self.DeclareForcedPublishEvent(self._publish)
        self._shown: Dict[str, bool] = {}
        points = np.asarray(edge_points, float)  # (n_bins, 3) on the edge
        burr_initial = np.asarray(burr_initial, float)
        up = _edge_up(edge_axes, len(points))
        for k, g in enumerate(self._groups):
            a, b = points[g.start], points[g.stop - 1]
            mid = 0.5 * (a + b)
            along = b - a
            length = max(float(np.linalg.norm(along)), 2e-4)
            X = _segment_pose(mid, along, up[(g.start + g.stop - 1) // 2])
            for state, color in (("uncut", UNCUT), ("cut", CUT)):
                path = f"{prefix}/edge/{state}/{k}"
                meshcat.SetObject(path, Box(length, 0.0008, 0.0008), color)
                meshcat.SetTransform(path, X)
            height = float(burr_initial[g].max())
            if height > 0:
                path = f"{prefix}/burrs/{k}"
                meshcat.SetObject(path, Box(length, 0.001, height), BURR)
                meshcat.SetTransform(
                    path, X @ RigidTransform([0.0, 0.0, height / 2])
                )
        self._burr_groups = [
            k for k, g in enumerate(self._groups) if burr_initial[g].max() > 0
        ]

    def _set(self, path, visible, time):
        if self._shown.get(path) is not visible:
            self._meshcat.SetProperty(path, "visible", visible, time)
            self._shown[path] = visible

    def _publish(self, context):
        finish = self._finish_port.Eval(context)
        burr = self._burr_port.Eval(context)
        t = context.get_time()
        p = self._prefix
        for k, g in enumerate(self._groups):
            cut = bool(np.any(finish[g] > 0.0))
            self._set(f"{p}/edge/cut/{k}", cut, t)
            self._set(f"{p}/edge/uncut/{k}", not cut, t)
        for k in self._burr_groups:
            self._set(
                f"{p}/burrs/{k}", bool(np.any(burr[self._groups[k]] > 0.0)), t
            )


def _edge_up(edge_axes, n):
    """The burrs' up direction per bin: the tool axis (out of the part)
    along a 3-D edge, else vertical."""
    if edge_axes is None:
        return np.tile([0.0, 0.0, 1.0], (n, 1))
    return np.asarray(edge_axes, float).reshape(n, 3)


def _segment_pose(mid, along, up) -> RigidTransform:
    """x along the segment, z the part's up (the burr's height) made
    perpendicular to it."""
    x = np.asarray(along, float)
    x = x / max(np.linalg.norm(x), 1e-12)
    y = np.cross(np.asarray(up, float), x)
    y = y / max(np.linalg.norm(y), 1e-12)
    z = np.cross(x, y)
    return RigidTransform(RotationMatrix(np.column_stack([x, y, z])), mid)


def add_meshcat(
    builder: DiagramBuilder,
    meshcat: Meshcat,
    *,
    plant,
    scene_graph,
    process: CuttingProcess,
    edge_points,
    edge_axes=None,
    publish_period: float = 0.1,
) -> None:
    """Adds the illustration (the part's own mesh along a CAD edge),
    contact-force arrows and the edge to ``meshcat`` (named systems
    ``meshcat_visualizer``, ``contact_visualizer``, ``edge_visualizer``),
    and points the camera at the part from above and in front of the arm.
    ``edge_axes`` (n_bins, 3): the tool axis at each bin, which way the
    burrs stand along a 3-D edge (None: up)."""
    edge_points = np.asarray(edge_points, float)
    _add_cell(
        builder,
        meshcat,
        plant,
        scene_graph,
        edge_points.mean(axis=0),
        publish_period,
    )
    _add_edge(builder, meshcat, process, edge_points, edge_axes, publish_period)


def add_job_meshcat(
    builder: DiagramBuilder,
    meshcat: Meshcat,
    *,
    plant,
    scene_graph,
    edges,
    publish_period: float = 0.1,
) -> None:
    """:func:`add_meshcat` for a job's cell: ``edges`` is a (process, edge
    points, edge axes) per cut edge, each drawn by an
    ``edge_visualizer_<k>`` under ``deburring/edge_<k>``; the camera on
    the middle of them all."""
    center = np.mean([np.mean(points, axis=0) for _, points, _ in edges], 0)
    _add_cell(builder, meshcat, plant, scene_graph, center, publish_period)
    for k, (process, points, axes) in enumerate(edges):
        _add_edge(builder, meshcat, process, points, axes, publish_period, k=k)


def _add_cell(builder, meshcat, plant, scene_graph, center, publish_period):
    """The cell's illustration and its contact forces, the camera on
    ``center`` (m, world) from above and in front of the arm."""
    meshcat.SetCameraPose(center + np.array([0.10, -0.16, 0.12]), center)
    params = MeshcatVisualizerParams(
        role=Role.kIllustration, publish_period=publish_period
    )
    visualizer = MeshcatVisualizer.AddToBuilder(
        builder, scene_graph, meshcat, params
    )
    visualizer.set_name("meshcat_visualizer")
    contact = ContactVisualizer.AddToBuilder(
        builder,
        plant,
        meshcat,
        ContactVisualizerParams(
            publish_period=publish_period,
            newtons_per_meter=200.0,
            radius=0.0015,
        ),
    )
    contact.set_name("contact_visualizer")


def _add_edge(
    builder, meshcat, process, points, axes, publish_period, *, k=None
):
    """An EdgeVisualizer of ``process``'s edge (``edge_visualizer`` under
    ``deburring``, or ``edge_visualizer_<k>`` under
    ``deburring/edge_<k>``), fed by its finish and burrs."""
    edge = EdgeVisualizer(
        meshcat,
        process,
        edge_points=points,
        burr_initial=process.initial_burr_height(),
        edge_axes=axes,
        publish_period=publish_period,
        prefix="deburring" if k is None else f"deburring/edge_{k}",
    )
    if k is not None:
        edge.set_name(f"edge_visualizer_{k}")
    builder.AddSystem(edge)
    builder.Connect(
        process.GetOutputPort("finish_depth"), edge.GetInputPort("finish_depth")
    )
    builder.Connect(
        process.GetOutputPort("burr_height"), edge.GetInputPort("burr_height")
    )
