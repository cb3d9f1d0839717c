"""Registration of a triangle-mesh part from touches (pure numpy): the
rigid move, in six degrees of freedom, that puts the believed mesh through
points touched on the real part, point to plane, with a hole's size where
the touches tell it, and the move's covariance.

The move T takes the believed part onto the real one, x_real = R x + p
(m, world). Its small changes are written about a pivot c (the touches'
centroid): eps = (omega, v), x -> Rot(omega) (x - c) + c + v, omega (rad)
a rotation vector, v (m) the pivot's move; T' = exp(eps) T. A touch x_i
(m, world) on the real part lies on the believed mesh once moved back,
y_i = T^-1 x_i; its residual is r_i = n_j . (y_i - q_j) (+ ds where the
touched face is one of the sized faces), q_j the point of the mesh's
nearest triangle j to y_i, n_j that triangle's outward normal. The
Jacobian's row of a touch is -[(x_i - c) x m_i, m_i] (+1 for the size),
m_i = R n_j the face's normal on the real part; with the rotation columns
multiplied by 1/L (L the touches' RMS distance from c) every column is in
metres, and 1 / (its smallest singular value) is the noise amplification
of the worst combination of (v, L omega): the measure of how well the
touches pin the six degrees of freedom
(deburr_drake.math.registration.MAX_AMPLIFICATION bounds it, as it does
a planar part's).

- :func:`closest_on_mesh`: the nearest triangle's point and index for
  each point, optionally only among the triangles whose normal agrees
  with a measured contact normal.
- :func:`pose_jacobian` / :func:`pose_amplification` /
  :func:`weakest_direction`: the Jacobian of touches and what it fixes.
- :func:`register_mesh`: Gauss-Newton on the move (and the size), the
  touches kept those most of them agree on within ``max_residual``
  (deburr_drake.math.fits.fit_consensus, as the planar probe: a touch on a
  burr cannot pull the first fit to itself), the covariance
  sigma^2 (J^T J)^-1 of (omega, v[, size]).
- :func:`cylinder_faces`: the faces of a hole (a cylinder about an axis),
  the faces whose uniform offset is a hole's size.
"""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Optional

import numpy as np
from scipy.spatial.transform import Rotation

from deburr_drake.math.fits import fit_consensus
from deburr_drake.math.registration import MAX_AMPLIFICATION

__all__ = [
    "MeshSurface",
    "closest_on_mesh",
    "closest_on_triangles",
    "pose_jacobian",
    "pose_amplification",
    "weakest_direction",
    "MeshFit",
    "register_mesh",
    "cylinder_faces",
    "DEGREES_OF_FREEDOM",
    "NORMAL_AGREEMENT",
]

#: The six degrees of freedom in the order of (omega, v).
DEGREES_OF_FREEDOM = (
    "rotation about x",
    "rotation about y",
    "rotation about z",
    "translation along x",
    "translation along y",
    "translation along z",
)

#: cos of the largest angle between a touch's measured contact normal and
#: the normal of a face it may lie on: 45 deg, far more than a force
#: sensor's noise turns the normal, far less than a hole's rim turns it.
NORMAL_AGREEMENT = math.cos(math.radians(45.0))

_ITERATIONS = 50
_TOLERANCE = 1e-14  # m and rad, a Gauss-Newton step this small: converged


class MeshSurface:
    """A closed triangle mesh (m, world, at the believed pose): ``vertices``
    (V, 3) and ``faces`` (F, 3) wound outwards; ``normals`` (F, 3) the
    faces' unit outward normals, ``corners`` (a, b, c), each (F, 3),
    ``centroid`` (F, 3) theirs, ``reach`` (F,) how far each face's
    corners lie from its centroid."""

    def __init__(self, vertices, faces):
        self.vertices = np.asarray(vertices, float)
        self.faces = np.asarray(faces, int)
        self.corners = tuple(self.vertices[self.faces[:, k]] for k in range(3))
        a, b, c = self.corners
        n = np.cross(b - a, c - a)
        self.normals = n / np.linalg.norm(n, axis=1, keepdims=True)
        self.centroid = (a + b + c) / 3.0  # m, (F, 3)
        self.reach = np.max(
            [np.linalg.norm(v - self.centroid, axis=1) for v in self.corners],
            axis=0,
        )  # m, each face's corners within it of its centroid


def closest_on_triangles(p, a, b, c):
    """(N, F, 3): the point of each triangle (a, b, c: (F, 3)) nearest each
    point of ``p`` (N, 3) (Ericson, Real-Time Collision Detection 5.1.5,
    by regions of the triangle's plane)."""
    p = p[:, None, :]
    ab, ac = b - a, c - a
    ap, bp, cp = p - a, p - b, p - c
    d1, d2 = np.sum(ab * ap, -1), np.sum(ac * ap, -1)
    d3, d4 = np.sum(ab * bp, -1), np.sum(ac * bp, -1)
    d5, d6 = np.sum(ab * cp, -1), np.sum(ac * cp, -1)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2

    def ratio(num, den):
        return num / np.where(den == 0.0, 1.0, den)

    # Inside the triangle, then each edge and corner region over it, the
    # corners last (they win where regions touch).
    total = va + vb + vc
    v, w = ratio(vb, total), ratio(vc, total)
    out = a + ab * v[..., None] + ac * w[..., None]
    bc = (va <= 0) & (d4 - d3 >= 0) & (d5 - d6 >= 0)
    t = ratio(d4 - d3, (d4 - d3) + (d5 - d6))
    out = np.where(bc[..., None], b + (c - b) * t[..., None], out)
    on_ac = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
    t = ratio(d2, d2 - d6)
    out = np.where(on_ac[..., None], a + ac * t[..., None], out)
    on_ab = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
    t = ratio(d1, d1 - d3)
    out = np.where(on_ab[..., None], a + ab * t[..., None], out)
    corner_c = (d6 >= 0) & (d5 <= d6)
    out = np.where(corner_c[..., None], c + 0.0 * p, out)
    corner_b = (d3 >= 0) & (d4 <= d3)
    out = np.where(corner_b[..., None], b + 0.0 * p, out)
    corner_a = (d1 <= 0) & (d2 <= 0)
    return np.where(corner_a[..., None], a + 0.0 * p, out)


def closest_on_mesh(surface: MeshSurface, points, normals=None):
    """(closest points (N, 3), face indices (N,)) on ``surface`` of
    ``points`` (N, 3), m. ``normals`` (N, 3), a measured outward contact
    normal per point (a row of NaN: none): only the faces whose normal is
    within 45 deg of it (NORMAL_AGREEMENT) are candidates, so a touch
    near a rim is put on the face it touched (ValueError if no face
    agrees)."""
    p = np.atleast_2d(np.asarray(points, float))
    allowed = np.ones((len(p), len(surface.faces)), bool)
    if normals is not None:
        m = np.atleast_2d(np.asarray(normals, float))
        given = np.all(np.isfinite(m), axis=1)
        unit = m[given] / np.linalg.norm(m[given], axis=1, keepdims=True)
        allowed[given] = unit @ surface.normals.T >= NORMAL_AGREEMENT
        if not np.all(allowed.any(axis=1)):
            raise ValueError(
                "a touch's contact normal agrees with no face of the part "
                "(within 45 deg)"
            )
    # A face's centroid lies on it (its distance bounds the nearest from
    # above) and its corners within its radius of the centroid (the
    # distance less that radius bounds it from below): the exact nearest
    # point is searched only on the faces the bounds leave.
    centroid = surface.centroid
    reach = surface.reach
    a, b, c = surface.corners
    q = np.empty_like(p)
    j = np.empty(len(p), int)
    for i, x in enumerate(p):
        d = np.linalg.norm(centroid - x, axis=1)
        upper = np.min(np.where(allowed[i], d, np.inf))
        near = np.flatnonzero(allowed[i] & (d - reach <= upper))
        qi = closest_on_triangles(x[None, :], a[near], b[near], c[near])[0]
        k = int(np.argmin(np.sum((qi - x) ** 2, axis=1)))
        q[i], j[i] = qi[k], near[k]
    return q, j


def _pivot_and_length(points):
    c = np.mean(points, axis=0)
    L = float(np.sqrt(np.mean(np.sum((points - c) ** 2, axis=1))))
    return c, max(L, 1e-12)


def pose_jacobian(points, normals, *, pivot, sized=None) -> np.ndarray:
    """(N, 6 or 7): d r / d (omega, v[, size]) of touches at ``points``
    (N, 3) on faces of outward ``normals`` (N, 3) on the real part
    (module docstring); ``sized`` (N,) bool: a touch on a sized face
    (the size column added)."""
    x = np.asarray(points, float) - np.asarray(pivot, float)
    m = np.asarray(normals, float)
    J = -np.hstack([np.cross(x, m), m])
    if sized is not None:
        J = np.column_stack([J, np.asarray(sized, float)])
    return J


def _scaled(J, length):
    S = J.copy()
    S[:, :3] *= 1.0 / length
    return S


def pose_amplification(points, normals, *, sized=None) -> float:
    """The noise amplification of touches at ``points`` on faces of
    ``normals``: 1 / the smallest singular value of their Jacobian with
    its rotation columns scaled to metres (module docstring), about their
    centroid; inf when they do not fix every degree of freedom (and the
    size, ``sized``)."""
    p = np.asarray(points, float)
    if len(p) < 6 + (sized is not None):
        return math.inf
    c, L = _pivot_and_length(p)
    J = _scaled(pose_jacobian(p, normals, pivot=c, sized=sized), L)
    smallest = np.linalg.svd(J, compute_uv=False)[-1]
    return math.inf if smallest <= 1e-9 else float(1.0 / smallest)


def weakest_direction(points, normals) -> str:
    """The degree of freedom touches at ``points`` on faces of ``normals``
    pin least (DEGREES_OF_FREEDOM): the largest component of the right
    singular vector of the smallest singular value, rotations scaled to
    metres at the touches' RMS distance from their centroid."""
    p = np.asarray(points, float)
    c, L = _pivot_and_length(p)
    J = _scaled(pose_jacobian(p, normals, pivot=c), L)
    if len(p) < 6:
        J = np.vstack([J, np.zeros((6 - len(p), 6))])
    _, _, vt = np.linalg.svd(J)
    return DEGREES_OF_FREEDOM[int(np.argmax(np.abs(vt[-1])))]


def _exp(eps, c):
    """exp(eps) as (R, p): x -> Rot(omega) (x - c) + c + v."""
    R = Rotation.from_rotvec(eps[:3]).as_matrix()
    return R, c - R @ c + eps[3:6]


def _apply(move, x):
    R, p = move
    return x @ R.T + p


@dataclass(frozen=True)
class MeshFit:
    """A registration of a mesh part from touches.

    ``rotation``, ``translation``: the move T from the believed part onto
    the real one, x_real = R x + p (m, world). ``pivot`` (m, world): the
    point its covariance's rotation turns about. ``covariance`` (6 or 7
    square): of e = (omega (rad), v (m)[, size (m)]), the fit's error
    T_true = exp(e) T (:meth:`error_of`), sigma^2 (J^T J)^-1 of the kept
    touches, sigma the touch noise given (else estimated from the kept
    residuals, N - 6 (7) degrees of freedom).
    ``size`` (m): how much larger the sized faces' hole is than the
    mesh's (their uniform offset into the material), None when not
    fitted (no sized faces, or the touches cannot tell it from the move).
    ``kept`` (N,) bool, ``residuals`` (N,) m (> 0: the touch lies outside
    the fitted surface), ``rms`` (m, of the kept), ``amplification``:
    pose_amplification of the kept touches."""

    rotation: np.ndarray
    translation: np.ndarray
    pivot: np.ndarray
    covariance: np.ndarray
    size: Optional[float]
    kept: np.ndarray
    residuals: np.ndarray
    rms: float
    amplification: float

    def move(self, points) -> np.ndarray:
        """``points`` (N, 3) of the believed part, on the real one."""
        return _apply((self.rotation, self.translation), np.asarray(points))

    def error_of(self, rotation, translation) -> np.ndarray:
        """e = (omega, v) of the true move (``rotation``, ``translation``)
        against this fit, T_true = exp(e) T (its covariance is
        ``covariance``'s first 6 x 6)."""
        R = np.asarray(rotation) @ self.rotation.T
        p = np.asarray(translation) - R @ self.translation
        omega = Rotation.from_matrix(R).as_rotvec()
        return np.concatenate([omega, R @ self.pivot + p - self.pivot])


def _residuals(surface, move, x, normals, sized_faces):
    """(r, faces, normals on the real part) of touches ``x`` on
    ``surface`` moved by ``move`` (rotation, translation), the size
    left out."""
    R, p = move
    y = (x - p) @ R  # T^-1 x
    bel_normals = None if normals is None else normals @ R
    q, j = closest_on_mesh(surface, y, bel_normals)
    n = surface.normals[j]
    r = np.sum(n * (y - q), axis=1)
    sized = None if sized_faces is None else sized_faces[j]
    return r, sized, n @ R.T


def _gauss_newton(surface, x, normals, sized_faces, pivot, move, size):
    """(move, size, J, r) at the solution minimising the residuals of
    touches ``x`` (module docstring) from ``move`` and ``size``;
    ``sized_faces`` (F,) bool or None (no size)."""
    for _ in range(_ITERATIONS):
        r, sized, m = _residuals(surface, move, x, normals, sized_faces)
        J = pose_jacobian(x, m, pivot=pivot, sized=sized)
        if sized is not None:
            r = r + size * sized
        step, *_ = np.linalg.lstsq(J, -r, rcond=None)
        move = _compose(_exp(step, pivot), move)
        if sized is not None:
            size += step[6]
        if np.max(np.abs(step)) < _TOLERANCE:
            break
    r, sized, m = _residuals(surface, move, x, normals, sized_faces)
    if sized is not None:
        r = r + size * sized
    return move, size, pose_jacobian(x, m, pivot=pivot, sized=sized), r


def _compose(a, b):
    Ra, pa = a
    Rb, pb = b
    return Ra @ Rb, Ra @ pb + pa


@dataclass
class _LinearTrial:
    """A fit of the touches' linearised residuals r0 + J eps, each touch a
    row [J, r0] (fit_consensus's interface)."""

    eps: np.ndarray
    residuals: np.ndarray

    def residuals_of(self, rows) -> np.ndarray:
        rows = np.asarray(rows, float)
        return rows[:, -1] + rows[:, :-1] @ self.eps

    @property
    def rms(self) -> float:
        return float(np.sqrt(np.mean(self.residuals**2)))


def _linear_fit(length):
    """fit(rows) -> _LinearTrial; ValueError when the rows do not fix the
    move (and the size): the consensus's trials, each a small least
    squares problem, not a search of the mesh."""

    def fit(rows):
        rows = np.asarray(rows, float)
        J, r = rows[:, :-1], rows[:, -1]
        if len(J) < J.shape[1]:
            raise ValueError("too few touches")
        U, S, Vt = np.linalg.svd(_scaled(J, length), full_matrices=False)
        if S[-1] <= 1.0 / MAX_AMPLIFICATION:
            raise ValueError("the touches do not fix the move")
        eps = -Vt.T @ ((U.T @ r) / S)
        eps[:3] /= length  # the rotation's columns were scaled by 1/L
        return _LinearTrial(eps, r + J @ eps)

    return fit


def _consensus(surface, x, normals, sized_faces, max_residual):
    """(kept, move, size): the touches most agree on within
    ``max_residual`` and the move and size fitted to them. The
    consensus's trials fit the residuals linearised at a pose (first the
    believed one, then the pose fitted to the first consensus, where the
    linearisation's error, a faceted curve's sag and the turn's second
    order, has gone)."""
    pivot, length = _pivot_and_length(x)
    move, size = (np.eye(3), np.zeros(3)), 0.0
    minimal = 6 if sized_faces is None else 7
    kept = np.ones(len(x), bool)
    for _ in range(2):
        r, sized, m = _residuals(surface, move, x, normals, sized_faces)
        J = pose_jacobian(x, m, pivot=pivot, sized=sized)
        if sized is not None:
            r = r + size * sized
        if len(x) > minimal:
            _, kept = fit_consensus(
                _linear_fit(length),
                np.column_stack([J, r]),
                minimal=minimal,
                max_residual=max_residual,
            )
        n_k = None if normals is None else normals[kept]
        move, size, *_ = _gauss_newton(
            surface, x[kept], n_k, sized_faces, pivot, move, size
        )
    return kept, move, size


def register_mesh(
    surface: MeshSurface,
    points,
    *,
    normals=None,
    max_residual: float,
    touch_noise: Optional[float] = None,
    touch_error: float = 0.0,
    sized_faces=None,
) -> MeshFit:
    """The move of ``surface`` (the believed part) onto the real part
    through touches at ``points`` ((N, 3), m, world, on the real part's
    surface: detection depth and bias already taken off) with their
    measured outward contact ``normals`` ((N, 3), a row of NaN: not
    measured; None: none measured). The touches kept are those the fit
    most of them agree on within ``max_residual`` (m) (fit_consensus;
    7 or more touches to find an outlier). ``sized_faces`` ((F,) bool):
    faces whose uniform offset, a hole's size, is fitted too where the
    touches tell it from the move (pose_amplification with the size at
    most MAX_AMPLIFICATION), else the mesh's size is held.
    ``touch_noise`` (m): the standard deviation of a touch along the
    normal, for the covariance (None: estimated from the residuals, and
    no smaller than ``touch_error`` (m), the per-touch error the touches'
    model is known to leave: with 8 touches for 7 unknowns the residuals
    have one degree of freedom, and a small residual by chance would
    report a covariance far smaller than the error).
    ValueError: touches that do not fix the six degrees of freedom, one
    line naming the one they pin least."""
    x = np.asarray(points, float)
    if normals is not None:
        normals = np.asarray(normals, float)
    _, j0 = closest_on_mesh(surface, x, normals)
    gain = pose_amplification(x, surface.normals[j0])
    if gain > MAX_AMPLIFICATION:
        raise ValueError(
            f"the {len(x)} touches do not fix the part's pose (noise "
            f"amplification {gain:.3g} > {MAX_AMPLIFICATION:g}): "
            f"{weakest_direction(x, surface.normals[j0])} is not pinned"
        )
    if sized_faces is not None:
        sized_faces = np.asarray(sized_faces, bool)
        told = pose_amplification(x, surface.normals[j0], sized=sized_faces[j0])
        if told > MAX_AMPLIFICATION:
            sized_faces = None
    kept, move, size = _consensus(
        surface, x, normals, sized_faces, max_residual
    )
    # The final fit about the kept touches' centroid, its covariance there.
    pivot = np.mean(x[kept], axis=0)
    n_k = None if normals is None else normals[kept]
    move, size, J, _ = _gauss_newton(
        surface, x[kept], n_k, sized_faces, pivot, move, size
    )
    r, sized, m = _residuals(surface, move, x, normals, sized_faces)
    if sized is not None:
        r = r + size * sized
    dof = max(int(kept.sum()) - J.shape[1], 1)
    sigma = (
        touch_noise
        if touch_noise is not None
        else max(touch_error, float(np.sqrt(np.sum(r[kept] ** 2) / dof)))
    )
    return MeshFit(
        rotation=move[0],
        translation=move[1],
        pivot=pivot,
        covariance=sigma**2 * np.linalg.inv(J.T @ J),
        size=None if sized_faces is None else float(size),
        kept=kept,
        residuals=r,
        rms=float(np.sqrt(np.mean(r[kept] ** 2))),
        amplification=pose_amplification(x[kept], m[kept]),
    )


def cylinder_faces(
    surface: MeshSurface, *, point, axis, radius: float, tolerance: float
) -> np.ndarray:
    """(F,) bool: the faces of a hole of ``radius`` (m) about the axis
    through ``point`` along ``axis`` (m, world): every corner within
    ``tolerance`` (m) of the radius from the axis, the outward normal
    facing the axis (the material is outside the hole)."""
    a = np.asarray(axis, float)
    a = a / np.linalg.norm(a)
    o = np.asarray(point, float)
    inside = np.ones(len(surface.faces), bool)
    for corner in surface.corners:
        d = corner - o
        radial = d - np.outer(d @ a, a)
        inside &= np.abs(np.linalg.norm(radial, axis=1) - radius) <= tolerance
    d = surface.centroid - o
    radial = d - np.outer(d @ a, a)
    facing = np.sum(surface.normals * radial, axis=1) < 0.0
    return inside & facing
