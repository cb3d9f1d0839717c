"""Touch points planned on a mesh part's faces (pure numpy and scipy), so
that touch probing pins every degree of freedom of the part's pose.

A candidate touch is a face's centroid, approached along the face's
outward normal. It is reachable when the face does not face down more
than ``min_normal_z`` allows (the tool comes from above) and the probe,
a ball of ``probe_radius`` about the tool's axis point (the cutter's
radius), has a clear way: its centre at p + r n, moved out along the
normal by ``clearance`` (the standoff before the guarded move) and from
there straight up by ``rise`` (the way in from above), keeps at least
r (less a sampling margin) from every point of the part. The touches are
chosen greedily, each the reachable candidate that most raises
log det(J^T J) of the scaled point-to-plane Jacobian
(deburr_drake.math.mesh_registration: rotation columns / L, all in
metres), until ``count`` are chosen.

The measure of the plan, stated: its noise amplification, 1 / the
smallest singular value of that Jacobian about the touches' centroid
(mesh_registration.pose_amplification): the standard deviation of the
worst combination of (v, L omega) per unit touch noise. A plan whose
amplification exceeds ``max_amplification`` (default
deburr_drake.math.registration.MAX_AMPLIFICATION, as for a planar part)
is a ValueError naming the degree of freedom it pins least.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Optional

import numpy as np
from scipy.spatial import cKDTree

from deburr_drake.math.mesh_registration import (
    MeshSurface,
    pose_amplification,
    pose_jacobian,
    weakest_direction,
)
from deburr_drake.math.registration import MAX_AMPLIFICATION

__all__ = ["TouchPlan", "plan_touches", "reachable_faces"]

#: m, the spacing of the points sampled on the part's surface the
#: probe's clearance is checked against (about the check's margin).
_SURFACE_SPACING = 1.0e-3
#: The probe's way is checked at points this far apart, in probe radii.
_PATH_STEP = 0.25


@dataclass(frozen=True)
class TouchPlan:
    """``points`` (N, 3) m, world, on the believed part; ``normals`` (N,
    3) the faces' outward normals (each touch approached along minus
    it); ``faces`` (N,) their indices; ``amplification`` the plan's
    measure (module docstring)."""

    points: np.ndarray
    normals: np.ndarray
    faces: np.ndarray
    amplification: float


def _surface_samples(surface: MeshSurface) -> np.ndarray:
    """Points on the part's surface about _SURFACE_SPACING apart: on every
    face about one per spacing squared (seeded, uniform on the face),
    along every edge one per spacing, and the corners."""
    a, b, c = surface.corners
    area = 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)
    per_face = np.maximum(1, np.ceil(area / _SURFACE_SPACING**2)).astype(int)
    rows = np.repeat(np.arange(len(a)), per_face)
    u, v = np.random.default_rng(0).random((2, len(rows)))
    fold = u + v > 1.0
    u[fold], v[fold] = 1.0 - u[fold], 1.0 - v[fold]
    inside = a[rows] + u[:, None] * (b - a)[rows] + v[:, None] * (c - a)[rows]
    points = [surface.vertices, inside]
    for p, q in ((a, b), (b, c), (c, a)):
        steps = np.ceil(np.linalg.norm(q - p, axis=1) / _SURFACE_SPACING)
        rows = np.repeat(np.arange(len(p)), steps.astype(int))
        start = np.cumsum(steps.astype(int)) - steps.astype(int)
        t = (np.arange(len(rows)) - start[rows]) / steps[rows]
        points.append(p[rows] + t[:, None] * (q - p)[rows])
    return np.vstack(points)


def reachable_faces(
    surface: MeshSurface,
    *,
    probe_radius: float,
    clearance,
    rise: float,
    min_normal_z: float = 0.0,
) -> np.ndarray:
    """(F,) bool: the faces whose centroid the probe reaches (module
    docstring); ``clearance`` (m) one for every face or (F,) each its
    own."""
    facing = surface.normals[:, 2] >= min_normal_z
    tree = cKDTree(_surface_samples(surface))
    margin = _SURFACE_SPACING
    step = _PATH_STEP * probe_radius
    faces = np.flatnonzero(facing)
    out = np.broadcast_to(np.asarray(clearance, float), facing.shape)[faces]
    steps = int(math.ceil(float(out.max(initial=0.0)) / step))
    along = out[:, None] * np.arange(1, steps + 1)[None, :] / max(steps, 1)
    up = np.arange(0.0, rise + step, step)
    n = surface.normals[faces]
    centre = surface.centroid[faces] + probe_radius * n
    # (faces, points on the way, 3): out along the normal, then up.
    way = np.concatenate(
        [
            centre[:, None, :] + along[:, :, None] * n[:, None, :],
            (centre + out[:, None] * n)[:, None, :]
            + up[None, :, None] * np.array([0.0, 0.0, 1.0]),
        ],
        axis=1,
    )
    distance, _ = tree.query(way.reshape(-1, 3))
    clear = np.all(
        distance.reshape(len(faces), -1) >= probe_radius - margin, axis=1
    )
    ok = np.zeros(len(surface.faces), bool)
    ok[faces] = clear
    return ok


def plan_touches(
    surface: MeshSurface,
    *,
    count: int,
    reachable: np.ndarray,
    max_amplification: float = MAX_AMPLIFICATION,
    sized_faces: Optional[np.ndarray] = None,
) -> TouchPlan:
    """``count`` touches among the ``reachable`` faces ((F,) bool, e.g.
    :func:`reachable_faces`) chosen greedily to pin the pose (and, with
    ``sized_faces``, a hole's size: its column joins the Jacobian). A
    plan that cannot pin a degree of freedom within ``max_amplification``
    is a ValueError naming it."""
    candidates = np.flatnonzero(reachable)
    if not len(candidates):
        raise ValueError("no face of the part is reachable for a touch")
    p, n = surface.centroid[candidates], surface.normals[candidates]
    pivot = np.mean(surface.centroid, axis=0)
    length = float(
        np.sqrt(np.mean(np.sum((surface.centroid - pivot) ** 2, axis=1)))
    )
    sized = None if sized_faces is None else sized_faces[candidates]
    J = pose_jacobian(p, n, pivot=pivot, sized=sized)
    J[:, :3] /= length
    # Greedy D-optimal: a small ridge keeps log det finite until six
    # touches span the pose.
    ridge = 1e-9 * np.eye(J.shape[1])
    information = ridge.copy()
    chosen: list[int] = []
    for _ in range(count):
        inverse = np.linalg.inv(information)
        # log det(M + j j^T) - log det M = log(1 + j^T M^-1 j)
        gain = np.einsum("ij,jk,ik->i", J, inverse, J)
        gain[chosen] = -np.inf
        best = int(np.argmax(gain))
        if not math.isfinite(gain[best]):
            break
        chosen.append(best)
        information += np.outer(J[best], J[best])
    idx = np.array(chosen, int)
    amplification = pose_amplification(
        p[idx], n[idx], sized=None if sized is None else sized[idx]
    )
    if amplification > max_amplification:
        what = (
            weakest_direction(p[idx], n[idx])
            if pose_amplification(p[idx], n[idx]) > max_amplification
            else "the hole's size"
        )
        raise ValueError(
            f"{len(idx)} touches on the part's reachable faces do not pin "
            f"{what} (noise amplification {amplification:.3g} > "
            f"{max_amplification:g})"
        )
    return TouchPlan(p[idx], n[idx], candidates[idx], amplification)
