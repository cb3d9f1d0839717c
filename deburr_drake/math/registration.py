"""Registration of the believed part (pure numpy): the correction
``r = (dx, dy, dyaw, dradius)`` (m, m, rad, m) that moves the believed edge
onto the real one, the contour it gives, and ``r`` from probed points.

- :func:`moved_contour`: the believed contour turned by dyaw about its
  pivot (:func:`pivot_of`) and moved by (dx, dy); a circle also with a
  radius dradius larger, a profile grown outward by dradius
  (``ProfileContour``: its vertices turn and move, the fillets are
  unchanged; a straight edge has no size: dradius must be 0). The pivot
  moves with (dx, dy), so two registrations compose by adding them.
  A 3-D edge's (a mesh part's) registration is a pose and a size
  (:data:`POSE_REGISTRATION_SIZE`: the rotation vector w (rad), the
  translation p (m) of x_real = Rot(w) x + p, and the hole's size (m)):
  its contour is a :class:`PosedContour`.
- :func:`registration_from_points`: the rigid move and the size (a
  circle's radius, a profile's growth, where the touches tell it) that
  put the contour through touch points on the real edge's zero-depth
  path: the circle and straight-edge fits of deburr_drake.math.fits in
  closed form, any other contour (a profile) by Gauss-Newton on the
  signed distances; the touches kept are those the fit most of them agree
  on within ``max_residual`` (deburr_drake.math.fits.fit_consensus: a
  touch on a burr is left out).
- while cutting (:func:`contact_regressor`, :func:`rls_update`,
  :func:`registration_of`): the contact force against the depth on a
  reference contour, ||f_n|| = c0 + c1 (delta_0 - d), shows how far the
  real edge lies beyond it, d = w . n1 + psi (z x (p - pivot)) . n1 (the
  normal displacement of the rigid move (w, psi) at the tool point p),
  the move estimated together with the contact parameters by recursive
  least squares.
"""

from __future__ import annotations

from dataclasses import dataclass
import functools
import math

import numpy as np

from deburr_drake.math.fits import fit_circle, fit_consensus, fit_line
from deburr_drake.math.geometry import (
    CircularContour,
    Contour,
    StraightContour,
)
from deburr_drake.math.profile import ProfileContour
from deburr_drake.math.rigid import rotvec_matrix

__all__ = [
    "REGISTRATION_SIZE",
    "POSE_REGISTRATION_SIZE",
    "registration_size",
    "PosedContour",
    "pivot_of",
    "moved_contour",
    "ProbeFit",
    "registration_from_points",
    "rigid_fit_amplification",
    "size_amplification",
    "MAX_AMPLIFICATION",
    "ONLINE_PARAMETERS",
    "contact_regressor",
    "onset_regressor",
    "learning_curvature",
    "registration_of",
    "rls_update",
]

#: (dx, dy, dyaw, dradius).
REGISTRATION_SIZE = 4

#: A 3-D edge's: (w (3), rad; p (3), m; size, m): x_real = Rot(w) x + p,
#: the hole's faces ``size`` into the material.
POSE_REGISTRATION_SIZE = 7


def registration_size(contour: Contour) -> int:
    """The length of ``contour``'s registration: a pose and a size
    (POSE_REGISTRATION_SIZE) on an edge whose frame turns (a mesh part's),
    else (dx, dy, dyaw, dradius)."""
    return (
        POSE_REGISTRATION_SIZE if contour.varying_frame else (REGISTRATION_SIZE)
    )


#: The largest noise amplification a profile's touches may have: the
#: standard deviation of the worst combination of (dx, dy, L dyaw) per
#: unit touch noise (L the touches' RMS distance from the pivot). Evenly
#: spread around a closed edge it is about sqrt(2 / N); touches all on
#: one straight side fix no position along it (infinite).
MAX_AMPLIFICATION = 10.0


def _rot(yaw):
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s], [s, c]])


def pivot_of(contour: Contour) -> np.ndarray:
    """(x, y, z) m, world: the point a registration's dyaw turns the
    contour about. A circle: its centre; a straight edge: its midpoint
    (its start when it is endless); a profile: the centroid (mean) of its
    polygon's vertices."""
    if isinstance(contour, CircularContour):
        return contour.center
    if isinstance(contour, StraightContour):
        half = 0.5 * contour.length if math.isfinite(contour.length) else 0.0
        return contour.point_at(half)
    if isinstance(contour, ProfileContour):
        return contour.vertex_centroid
    raise TypeError(
        f"registration of a {type(contour).__name__} is not "
        "supported: a circle, a straight edge or a profile"
    )


def moved_contour(contour: Contour, registration) -> Contour:
    """``contour`` turned by dyaw (rad, counter-clockwise) about
    :func:`pivot_of` and moved by (dx, dy) (m); a circle's radius grows by
    dradius (m), a profile's edge grows outward by it (a pocket or a boss
    larger). ValueError for a nonzero dradius on a straight edge (it has
    no size). A pose registration (POSE_REGISTRATION_SIZE numbers): the
    :class:`PosedContour`."""
    if len(registration) == POSE_REGISTRATION_SIZE:
        w, p, size = registration[:3], registration[3:6], registration[6]
        if not np.any(registration):
            return contour
        return PosedContour(contour, rotvec_matrix(w), p, float(size))
    dx, dy, dyaw, dradius = (float(v) for v in registration)
    if not any((dx, dy, dyaw, dradius)):
        return contour
    if isinstance(contour, CircularContour):
        center = contour.center + np.array([dx, dy, 0.0])
        return CircularContour(
            center,
            contour.radius + dradius,
            start_angle=contour.start_angle + dyaw,
            direction=contour.direction,
        )
    if dradius != 0.0 and isinstance(contour, StraightContour):
        raise ValueError(
            f"dradius = {dradius!r} m on a StraightContour: a straight "
            "edge has no size to register"
        )
    pivot = pivot_of(contour)
    if isinstance(contour, StraightContour):
        R = _rot(dyaw)
        start = contour.point_at(0.0)
        start[:2] = pivot[:2] + R @ (start[:2] - pivot[:2]) + [dx, dy]
        t = contour.tangent(start)
        n = contour.material_normal
        t[:2] = R @ t[:2]
        n[:2] = R @ n[:2]
        return StraightContour(start, t, n, length=contour.length)
    if isinstance(contour, ProfileContour):
        if dradius != 0.0:
            contour = _grown(contour, dradius)
        return contour.moved((dx, dy), dyaw, pivot[:2])
    raise TypeError(
        f"registration of a {type(contour).__name__} is not "
        "supported: a circle, a straight edge or a profile"
    )


class PosedContour(Contour):
    """``base`` (a 3-D edge's contour, on the believed part) on the part
    moved by x -> R x + p (``rotation`` R, ``translation`` p, m, world),
    its material ``size`` (m) further along n1 (a hole that much larger:
    the edge moves along n1 by it; exactly so where n1 is the hole wall's
    normal, and within 1 - cos of the angle between them elsewhere). Every
    point is the base's moved, every direction the base's turned; arc
    positions, curvature and the chamfer's cross-section are the base's.
    The tool's frame turns with the part: ``axis_turn(s)`` is R times the
    base's (the start's tool rotation, held on the believed part, times it
    gives the tool axis R a(s))."""

    varying_frame = True

    def __init__(self, base: Contour, rotation, translation, size=0.0):
        self._base = base
        self._R = np.asarray(rotation, float)
        self._p = np.asarray(translation, float)
        self._size = float(size)

    @property
    def base(self) -> Contour:
        return self._base

    def _back(self, p):
        """The point p (world, on the real part) on the believed part."""
        return self._R.T @ (p - self._p)

    def _out(self, q):
        return self._R @ q + self._p

    @property
    def length(self):
        return self._base.length

    @property
    def closed(self):
        return self._base.closed

    @property
    def height(self):
        return float(self.point_at(0.0)[2])

    def phi(self, p):
        return self._base.phi(self._back(p)) + self._size

    def grad_phi(self, p):
        return self._R @ self._base.grad_phi(self._back(p))

    def n1(self, p):
        return self._R @ self._base.n1(self._back(p))

    def tangent(self, p):
        return self._R @ self._base.tangent(self._back(p))

    def frame(self, p):
        n1, t, depth, s = self._base.frame(self._back(np.asarray(p, float)))
        return self._R @ n1, self._R @ t, depth - self._size, s

    def curvature(self, p):
        return self._base.curvature(self._back(p))

    def n1_rate(self, p, v):
        return self._R @ self._base.n1_rate(
            self._back(np.asarray(p, float)), self._R.T @ np.asarray(v, float)
        )

    def _grown_at(self, q):
        """The base's zero-depth point q moved along n1 by the size."""
        return q + self._size * self._base.n1(q) if self._size else q

    def project(self, p):
        return self._out(self._grown_at(self._base.project(self._back(p))))

    def arc_position(self, p):
        return self._base.arc_position(self._back(p))

    def unwrapped_arc_position(self, p, reference_s) -> float:
        # The base's own unwrapping: a job's contour unwraps each of its
        # closed edges though it is open itself.
        return self._base.unwrapped_arc_position(self._back(p), reference_s)

    def point_at(self, s):
        return self._out(self._grown_at(self._base.point_at(s)))

    def tool_axis_at(self, s):
        return self._R @ self._base.tool_axis_at(s)

    def axis_turn(self, s):
        return self._R @ self._base.axis_turn(s)

    def task_frame(self, s):
        return self._R @ self._base.task_frame(s)

    def chamfer_scale(self, s, delta, height):
        return self._base.chamfer_scale(s, delta, height)

    def edge_u(self, s):
        return self._base.edge_u(s)

    def edge_point(self, s):
        return self._out(self._base.edge_point(s))


@functools.lru_cache(maxsize=16)
def _grown(contour: ProfileContour, growth: float) -> ProfileContour:
    """``contour`` grown by ``growth`` (m), memoised: the probe's growth
    is one value for the whole pass while the online correction moves the
    grown profile every sample, and building a profile checks its whole
    path."""
    return contour.grown(growth)


def _turn_terms(contour: Contour, p, pivot) -> np.ndarray:
    """(N, 3): (n1_x, n1_y, (z x (p - pivot)) . n1) at each planar point
    of ``p`` (N, 2): the displacement along n1 of the edge at p when the
    contour moves by (dx, dy) and turns by dyaw about ``pivot``."""
    out = np.empty((len(p), 3))
    z = contour.height
    for i, (x, y) in enumerate(p):
        n1 = contour.n1(np.array([x, y, z]))
        out[i] = (
            n1[0],
            n1[1],
            -(y - pivot[1]) * n1[0] + (x - pivot[0]) * n1[1],
        )
    return out


def _phi(contour: Contour, p) -> np.ndarray:
    z = contour.height
    return np.array([float(contour.phi(np.array([x, y, z]))) for x, y in p])


def _amplification(contour: Contour, p, *, level: bool) -> float:
    """The largest standard deviation of (dx, dy, L dyaw) (and, ``level``,
    a level common to the points) per unit noise of a fit through the
    planar points ``p`` (N, 2); inf when they do not fix it."""
    if len(p) < 3 + level:
        return math.inf
    pivot = pivot_of(contour)[:2]
    J = _turn_terms(contour, p, pivot)
    L = float(np.sqrt(np.mean(np.sum((p - pivot) ** 2, axis=1))))
    J[:, 2] /= max(L, 1e-12)
    if level:
        J = np.column_stack([J, -np.ones(len(p))])
    smallest = np.linalg.svd(J, compute_uv=False)[-1]
    return math.inf if smallest <= 1e-9 else float(1.0 / smallest)


def rigid_fit_amplification(contour: Contour, points) -> float:
    """How much a rigid fit (dx, dy, dyaw) of ``contour`` through
    ``points`` ((N, 2 or 3), m, on or near the edge) amplifies touch noise:
    the largest standard deviation of (dx, dy, L dyaw) per unit noise, L
    the points' RMS distance from the pivot (inf when they do not fix the
    move: fewer than 3, or all on one straight piece)."""
    p = np.asarray(points, float)[:, :2]
    return _amplification(contour, p, level=False)


def size_amplification(contour: Contour, points) -> float:
    """How much a fit of ``contour``'s rigid move and a level common to
    every touch (its size) through ``points`` amplifies touch noise, as
    :func:`rigid_fit_amplification` with the level as a fourth unknown
    (inf when the touches cannot tell the size from the move: fewer than
    4, or none of them on sides facing apart)."""
    p = np.asarray(points, float)[:, :2]
    return _amplification(contour, p, level=True)


def _rigid_fit(
    contour: Contour,
    p,
    *,
    level: bool = False,
    iterations: int = 50,
    tolerance: float = 1e-12,
):
    """((dx, dy, dyaw), b) minimising sum (phi_moved(p_i) - b)^2 by
    Gauss-Newton from zero, b (m) a level common to every touch when
    ``level`` (else 0): moving the contour by a small (u, beta) about its
    (moved) pivot c changes phi at p by -(u + beta z x (p - c)) . grad phi
    / |grad phi| = +(...) . n1, and registrations compose by adding."""
    pivot = pivot_of(contour)[:2]
    reg, b = np.zeros(3), 0.0
    for _ in range(iterations):
        moved = moved_contour(contour, [*reg, 0.0])
        J = _turn_terms(moved, p, pivot + reg[:2])
        if level:
            J = np.column_stack([J, -np.ones(len(p))])
        step, *_ = np.linalg.lstsq(J, b * level - _phi(moved, p), rcond=None)
        reg += step[:3]
        if level:
            b += step[3]
        if np.linalg.norm(step[:2]) + abs(step[2]) * 0.1 < tolerance:
            break
    return reg, b


@dataclass
class ProbeFit:
    registration: np.ndarray  # (4,) dx, dy, dyaw, dradius
    kept: np.ndarray  # (N,) bool, the points the fit used
    residuals: (
        np.ndarray
    )  # (N,) m, phi of every point on the fit - level: > 0 early
    rms: float  # m, of the kept points' residuals
    # m, the level common to the kept touches that the registration does
    # not apply (> 0: early on average): a circle's fitted radius less the
    # drawing's, or a profile's level, when the size is held; 0 when the
    # size is registered and on a straight edge
    level: float = 0.0


def _spread_around(points, center) -> float:
    """rad, the smallest arc of directions from ``center`` holding every
    point (2 pi minus the largest gap between neighbouring directions)."""
    a = np.sort(np.arctan2(points[:, 1] - center[1], points[:, 0] - center[0]))
    if len(a) < 2:
        return 0.0
    gaps = np.diff(np.concatenate([a, [a[0] + 2 * math.pi]]))
    return float(2 * math.pi - gaps.max())


def _level_residuals(contour: Contour, move, level: float, q):
    """phi - level of planar points ``q`` on ``contour`` moved by
    ``move`` (dx, dy, dyaw)."""
    return _phi(moved_contour(contour, [*move, 0.0]), q) - level


@dataclass
class _RigidFit:
    """A rigid fit of a contour (fit_consensus's interface): the move
    (dx, dy, dyaw), the level common to the touches (m), the residuals
    phi - level of its points."""

    contour: Contour
    move: np.ndarray
    level: float
    residuals: np.ndarray

    def residuals_of(self, points) -> np.ndarray:
        return _level_residuals(
            self.contour,
            self.move,
            self.level,
            np.asarray(points, float)[:, :2],
        )

    @property
    def rms(self) -> float:
        return float(np.sqrt(np.mean(self.residuals**2)))


def _rigid(contour: Contour, *, level: bool):
    """fit(points) -> _RigidFit: Gauss-Newton from zero, the level free
    when ``level``; ValueError when the points do not fix the move."""

    def fit(points):
        q = np.asarray(points, float)[:, :2]
        if rigid_fit_amplification(contour, q) > MAX_AMPLIFICATION:
            raise ValueError("the points do not fix the move")
        move, b = _rigid_fit(contour, q, level=level)
        return _RigidFit(
            contour, move, b, _level_residuals(contour, move, b, q)
        )

    return fit


def _circle_registration(contour, p, max_residual, fit_radius):
    """(registration, kept, level) of a circle through the points ``p``
    ((N, 2), m): see :func:`registration_from_points`."""
    if len(p) < 3:
        raise ValueError(
            f"a circle's fit needs at least 3 touches, got {len(p)}"
        )
    if len(p) >= 4:
        _, kept = fit_consensus(
            fit_circle, p, minimal=3, max_residual=max_residual, minimum=3
        )
    else:
        kept = np.ones(len(p), bool)
    # Touches within a half circle know the radius poorly: the drawing's
    # is held then, and the centre fitted with it.
    free = _spread_around(p[kept], contour.center[:2]) > math.pi
    fit = fit_circle(
        p[kept],
        radius=None if free else contour.radius,
        seed=None if free else contour.center[:2],
    )
    d = fit.center - contour.center[:2]
    dradius = fit.radius - contour.radius
    sized = fit_radius and free
    reg = np.array([d[0], d[1], 0.0, dradius if sized else 0.0])
    return reg, kept, 0.0 if sized else -dradius


def _line_registration(contour, p, max_residual):
    """(registration, kept, level 0) of a straight edge through the points
    ``p`` ((N, 2), m): its offset and heading."""
    if len(p) < 2:
        raise ValueError(
            f"a straight edge's fit needs at least 2 touches, got {len(p)}"
        )
    fit, kept = fit_consensus(
        fit_line, p, minimal=2, max_residual=max_residual, minimum=2
    )
    t = contour.tangent(contour.point_at(0.0))[:2]
    direction = fit.direction if fit.direction @ t >= 0 else -fit.direction
    dyaw = math.atan2(t[0] * direction[1] - t[1] * direction[0], t @ direction)
    # Turn about the pivot, then shift along the turned normal so the
    # line passes through the fitted point.
    turned = moved_contour(contour, [0.0, 0.0, dyaw, 0.0])
    n = turned.material_normal[:2]
    q = np.array([fit.point[0], fit.point[1], turned.height])
    shift = -turned.phi(q) * n  # phi < 0 on the material side
    return np.array([shift[0], shift[1], dyaw, 0.0]), kept, 0.0


def _growth_of_level(contour: ProfileContour, level: float) -> float:
    """m, the growth (outward, :meth:`ProfileContour.grown`) that puts
    touches ``level`` early on average back on the edge: a pocket's edge
    lies along n1 from its free side, a boss's against it."""
    pocket = float(contour.phi(contour.vertex_centroid)) > 0.0
    return -level if pocket else level


def _rigid_registration(contour, p, max_residual, fit_size):
    """(registration, kept, level) of any other contour through the points
    ``p`` ((N, 2), m): its rigid move, and with 5 or more touches a common
    level; that level is the profile's growth (``fit_size``) when the kept
    touches tell it from the move (:func:`size_amplification` at most
    ``MAX_AMPLIFICATION``)."""
    pivot_of(contour)  # TypeError for a contour that cannot be moved
    gain = rigid_fit_amplification(contour, p)
    if gain > MAX_AMPLIFICATION:
        raise ValueError(
            f"the {len(p)} touches do not fix the part's position and "
            f"turn (noise amplification {gain:.3g} > "
            f"{MAX_AMPLIFICATION:g}): at least 3, spread over sides "
            "that are not parallel"
        )
    free = len(p) >= 5
    fit = _rigid(contour, level=free)
    if len(p) >= 4:
        _, kept = fit_consensus(
            fit,
            p,
            minimal=4 if free else 3,
            max_residual=max_residual,
            minimum=4 if free else 3,
        )
    else:
        kept = np.ones(len(p), bool)
    if rigid_fit_amplification(contour, p[kept]) > MAX_AMPLIFICATION:
        raise ValueError(
            "the touches kept do not fix the part's position and turn"
        )
    levelled = free and kept.sum() >= 5
    found = _rigid(contour, level=levelled)(p[kept])
    if not (
        fit_size
        and levelled
        and isinstance(contour, ProfileContour)
        and size_amplification(contour, p[kept]) <= MAX_AMPLIFICATION
    ):
        return np.array([*found.move, 0.0]), kept, found.level
    growth = _growth_of_level(contour, found.level)
    return np.array([*found.move, growth]), kept, 0.0


def registration_from_points(
    contour: Contour, points, *, max_residual: float, fit_radius: bool = False
) -> ProbeFit:
    """The registration of ``contour`` (the believed zero-depth path) that
    best puts it through ``points`` ((N, 2 or 3), m, world; the touch
    points already compensated to the zero-depth path). The touches kept
    are those the fit most of them agree on within ``max_residual`` (m)
    (:func:`~deburr_drake.math.fits.fit_consensus`: a touch on a burr
    cannot pull the first fit towards itself).

    - A circle: its centre and, ``fit_radius``, its radius, at least 3
      points (4 to find an outlier). The touches are found agreeing with
      one circle of free radius, so that a bias common to every touch
      (the detection's depth, which the stiffness of the contact sets)
      goes into the radius rather than into the residuals; and the centre
      is that circle's: with the drawing's radius held, a common bias
      moves the centre whenever the kept touches are not symmetric (one
      dropped on a burr: 0.14 mm of common bias puts the centre 50 um
      off). The drawing's radius is held only when the kept touches
      lie within a half circle (the radius is then poorly known, and
      the size is not registered). ``fit_radius``: the fitted radius is
      applied too (else the drawing's is kept); the touches must then
      be free of the probe's own detection bias (calibrated on a ring of
      known size: a probe alone cannot tell a radius error from it).
    - A straight edge: its offset and heading (total least squares), at
      least 2 points (3 to find an outlier). It has no size:
      ``fit_radius`` changes nothing.
    - Any other contour (a profile): its rigid move (dx, dy, dyaw) by
      Gauss-Newton on the signed distances phi, at least 3 points that fix
      it (:func:`rigid_fit_amplification` at most ``MAX_AMPLIFICATION``;
      4 to find an outlier). With 5 or more a level common to every touch
      is fitted too, as a circle's radius: a detection bias common to the
      touches is neither taken for burrs nor, when a burr touch leaves the
      rest unbalanced, for a move. ``fit_radius``: that level is the
      profile's growth (dradius, a uniform offset of its edge) when the
      kept touches tell it from the move (:func:`size_amplification` at
      most ``MAX_AMPLIFICATION``: touches on sides facing apart), else
      the drawing's size is kept and the level is ``ProbeFit.level``.

    Points that cannot fix the registration are a ValueError."""
    p = np.asarray(points, float)[:, :2]
    if isinstance(contour, CircularContour):
        reg, kept, level = _circle_registration(
            contour, p, max_residual, fit_radius
        )
    elif isinstance(contour, StraightContour):
        reg, kept, level = _line_registration(contour, p, max_residual)
    else:
        reg, kept, level = _rigid_registration(
            contour, p, max_residual, fit_radius
        )
    # Residuals: phi of every touch on the fitted contour less the level
    # the registration leaves out: > 0 early.
    residuals = _phi(moved_contour(contour, reg), p) - level
    rms = float(np.sqrt(np.mean(residuals[kept] ** 2)))
    return ProbeFit(reg, kept, residuals, rms, float(level))


# -- registration while cutting -------------------------------------------
#: The online model's parameters: the contact force is
#: ||f_n|| = c0 + c1 (delta_0 - d), d = w . n1 + psi (z x (p - pivot)) . n1
#: how far the real edge lies beyond the reference contour along n1 at the
#: tool point p (w: m, the move; psi: rad, the turn about the pivot,
#: counter-clockwise), delta_0 the depth on the reference; linear in
#: (c0, c1, c1 w_x, c1 w_y, c1 psi).
ONLINE_PARAMETERS = ("c0", "c1", "c1_w_x", "c1_w_y", "c1_psi")


def _offset_terms(contour: Contour, x_p) -> np.ndarray:
    """(n1_x, n1_y, (z x (x_p - pivot)) . n1): d = w . n1 + psi (...).
    On a circle the last term is zero (n1 is radial: a turn about the
    centre moves nothing); on a straight edge it is -(s - s_pivot), and
    w . n1 is a constant, told apart from c0 only by the contact onset."""
    x_p = np.asarray(x_p, float)
    return _turn_terms(contour, x_p[None, :2], pivot_of(contour)[:2])[0]


def contact_regressor(contour: Contour, x_p) -> np.ndarray:
    """phi with ||f_n|| = phi . theta (ONLINE_PARAMETERS) at the tool point
    ``x_p`` (m) on the reference ``contour``."""
    return np.concatenate(
        [[1.0, float(contour.depth(x_p))], -_offset_terms(contour, x_p)]
    )


def onset_regressor(contour: Contour, x_p, depth_at_detection=0.0):
    """phi with 0 = phi . theta where contact first comes: the real depth
    there is ``depth_at_detection`` (m, how far the tool moved in before
    the sensor showed it), so delta_0 - d = that depth, and no c0."""
    phi = contact_regressor(contour, x_p)
    phi[0] = 0.0
    phi[1] -= depth_at_detection
    return phi


def learning_curvature(contour: Contour, samples: int = 720) -> float:
    """1/m: the curvature of most of ``contour``'s length (over
    ``samples`` points evenly along it): where the online model learns.
    The contact law c0 + c1 delta holds with one c1 where the curvature
    is one: a circle and a straight edge everywhere, a profile on its
    straight sides (its fillets have their own c1: a pocket's concave
    corner stiffer, a boss's convex one softer, which the model would take
    for an offset towards or away from the corner)."""
    L = contour.length if math.isfinite(contour.length) else 0.0
    values = np.array(
        [
            contour.curvature(contour.point_at(s))
            for s in np.linspace(0.0, L, samples, endpoint=False)
        ]
    )
    kinds, counts = np.unique(np.round(values, 9), return_counts=True)
    return float(kinds[np.argmax(counts)])


def registration_of(contour: Contour, params) -> np.ndarray:
    """(dx, dy, dyaw, 0) that moves ``contour`` onto the edge of the
    online model's ``params`` (ONLINE_PARAMETERS; zero while c1 is not
    positive). A straight edge: only the move along its normal (the move
    along it changes nothing); a circle: no turn (it changes nothing)."""
    c1 = float(params[1])
    if not c1 > 0.0:
        return np.zeros(REGISTRATION_SIZE)
    wx, wy, psi = (float(v) / c1 for v in params[2:5])
    if isinstance(contour, StraightContour):
        n = contour.material_normal[:2]
        wx, wy = (wx * n[0] + wy * n[1]) * n
    if isinstance(contour, CircularContour):
        psi = 0.0
    return np.array([wx, wy, psi, 0.0])


def rls_update(theta, P, phi, y, *, noise_var: float, forgetting: float):
    """One recursive least-squares step with exponential forgetting
    (``forgetting`` in (0, 1]): (theta, P) after measuring y = phi . theta
    + noise of variance ``noise_var``."""
    theta = np.asarray(theta, float)
    P = np.asarray(P, float)
    phi = np.asarray(phi, float)
    Pphi = P @ phi
    gain = Pphi / (forgetting * noise_var + phi @ Pphi)
    theta = theta + gain * (y - phi @ theta)
    P = (P - np.outer(gain, Pphi)) / forgetting
    return theta, 0.5 * (P + P.T)
