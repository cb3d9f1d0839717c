"""The edges of a job as one contour for the controller's systems.

A job cuts several edges with one observer, one command generator and one
controller. :class:`JobContour` presents their paths as one
:class:`~deburr_drake.math.geometry.Contour`: a point is answered by the
edge whose path is nearest it (the edge being cut: the tool is on it),
and arc positions are the edge's own shifted by ``SPACING`` per edge (edge
k owns the arcs within SPACING / 2 of k SPACING), so the command's arc,
the chamfer state's and the progress a cut has made each name their edge.
The tool's desired rotation turns, along edge k, from the rotation the
cut starts with: ``axis_turn`` holds each edge's start rotation relative
to the first's.

No state: the nearest edge is a function of the point (an edge's path
box, nearer than the best distance found, is the only one projected on),
so answers do not depend on the order of the queries."""

from __future__ import annotations

from typing import Sequence

import numpy as np

from deburr_drake.math.geometry import Contour

__all__ = ["JobContour", "SPACING"]

#: m, the arc offset from one edge to the next (an edge's arc stays
#: within SPACING / 2 of its offset: a path of up to 3 m run for more than
#: one lap still does)
SPACING = 10.0


class JobContour(Contour):
    """The paths ``edges`` (Contours, world, with a turning tool frame) as
    one contour; ``start_rotations`` (3 x 3 each): the tool's rotation at
    each edge's start (the first is the controller's
    ``desired_rotation``)."""

    varying_frame = True

    def __init__(self, edges: Sequence[Contour], start_rotations):
        if not edges:
            raise ValueError("a job contour needs one edge at least")
        if len(start_rotations) != len(edges):
            raise ValueError(
                f"{len(start_rotations)} start rotations for {len(edges)} edges"
            )
        for k, edge in enumerate(edges):
            if edge.length > SPACING / 3:
                raise ValueError(
                    f"edge {k}: a path of {edge.length:.3g} m is longer "
                    f"than a job contour's {SPACING / 3:.3g} m"
                )
        self._edges = list(edges)
        first = np.asarray(start_rotations[0], float)
        # R_d along edge k = axis_turn_k(s) R_k = [axis_turn_k(s) R_k
        # R_0^T] R_0, the controller holding R_0.
        self._relative = [
            np.asarray(R, float) @ first.T for R in start_rotations
        ]
        boxes = []
        for edge in self._edges:
            samples = np.array(
                [edge.point_at(s) for s in np.linspace(0.0, edge.length, 65)]
            )
            boxes.append((samples.min(axis=0), samples.max(axis=0)))
        self._low = np.array([b[0] for b in boxes])
        self._high = np.array([b[1] for b in boxes])

    # ----- the edges -----
    @property
    def edges(self):
        return tuple(self._edges)

    def offset(self, k: int) -> float:
        """m, the arc of edge k's start."""
        return k * SPACING

    def edge_of_arc(self, s) -> int:
        """The edge that owns arc position ``s``."""
        k = int(np.floor(float(s) / SPACING + 0.5))
        return min(max(k, 0), len(self._edges) - 1)

    def nearest(self, p) -> int:
        """The edge whose path is nearest the point ``p`` (m, world)."""
        p = np.asarray(p, float)
        outside = np.maximum(self._low - p, 0.0) + np.maximum(
            p - self._high, 0.0
        )
        box = np.einsum("ij,ij->i", outside, outside)
        best, best_d2 = 0, np.inf
        for k in np.argsort(box):
            if box[k] >= best_d2:
                break
            d = self._edges[k].project(p) - p
            d2 = float(d @ d)
            if d2 < best_d2:
                best, best_d2 = int(k), d2
        return best

    def _local(self, s):
        k = self.edge_of_arc(s)
        return k, float(s) - self.offset(k)

    # ----- Contour -----
    @property
    def length(self) -> float:
        k = len(self._edges) - 1
        return self.offset(k) + self._edges[k].length

    @property
    def closed(self) -> bool:
        return False

    @property
    def height(self) -> float:
        return self._edges[0].height

    def phi(self, p):
        return self._edges[self.nearest(p)].phi(p)

    def grad_phi(self, p):
        return self._edges[self.nearest(p)].grad_phi(p)

    def n1(self, p):
        return self._edges[self.nearest(p)].n1(p)

    def tangent(self, p):
        return self._edges[self.nearest(p)].tangent(p)

    def project(self, p):
        return self._edges[self.nearest(p)].project(p)

    def arc_position(self, p) -> float:
        k = self.nearest(p)
        return self.offset(k) + self._edges[k].arc_position(p)

    def point_at(self, s):
        k, local = self._local(s)
        return self._edges[k].point_at(local)

    def curvature(self, p) -> float:
        return self._edges[self.nearest(p)].curvature(p)

    def n1_rate(self, p, v):
        return self._edges[self.nearest(p)].n1_rate(p, v)

    def frame(self, p):
        k = self.nearest(p)
        n1, tangent, depth, arc = self._edges[k].frame(p)
        return n1, tangent, depth, self.offset(k) + arc

    def unwrapped_arc_position(self, p, reference_s) -> float:
        """On the edge nearest ``p``, the arc nearest ``reference_s``
        when that is the same edge's, else nearest the edge's start."""
        k = self.nearest(p)
        reference = float(reference_s) - self.offset(k)
        if abs(reference) > SPACING / 2:
            reference = 0.0
        edge = self._edges[k]
        return self.offset(k) + edge.unwrapped_arc_position(p, reference)

    def advance(self, p, ds):
        k = self.nearest(p)
        return self._edges[k].advance(p, ds)

    def tool_axis_at(self, s):
        k, local = self._local(s)
        return self._edges[k].tool_axis_at(local)

    def axis_turn(self, s):
        k, local = self._local(s)
        return self._edges[k].axis_turn(local) @ self._relative[k]

    def task_frame(self, s):
        k, local = self._local(s)
        return self._edges[k].task_frame(local)

    def chamfer_scale(self, s, delta, height):
        k, local = self._local(s)
        return self._edges[k].chamfer_scale(local, delta, height)
