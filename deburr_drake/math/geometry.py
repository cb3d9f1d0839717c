"""Part-edge geometry for contour-following deburring (pure numpy, no pydrake).

A ``Contour`` is the zero-depth path of the tool reference point x_p (the
paper's x_s with phi(x_s) = 0, Sec. II, Fig. 2): a planar curve at height
``height`` in a horizontal plane.  The part wall is vertical, so phi ignores z.

Sign conventions (all in the horizontal plane, |grad phi| = 1):
  * phi > 0 on the free side, phi < 0 in the material;
  * n1 = -grad phi / |grad phi|, unit, horizontal, pointing INTO the material
    (Sec. II; the contact force on the tool is f_n = -|f_n| n1);
  * chamfer depth delta = -phi(p) (positive in the material);
  * n2 = (I - n1 n1^T) v / |(I - n1 n1^T) v| is the direction of motion (eq. 2,
    correction R5 in docs/cell-and-paper.md), with the contour tangent in the
    configured traversal direction as the start-up fallback at near-zero
    tangential speed;
  * the outer-loop command lies on the zero-depth contour: ``advance`` projects
    x_p onto phi = 0 and moves along it by the arc length ds (correction R6).

"T-generic" methods (phi, grad_phi, n1, depth, depth_rate, tangent, n2) accept
float arrays or numpy object arrays of pydrake AutoDiffXd and use only
arithmetic and np.sqrt/np.dot on them.  The path methods (project, arc_position,
unwrapped_arc_position, point_at, advance) work on floats; AutoDiffXd inputs are
reduced to their values and the results are float arrays.

New contour shapes (e.g. the closed polyline with filleted corners of
:mod:`deburr_drake.math.profile`) subclass ``Contour`` and implement only
the abstract members; the defaults for n1, depth, depth_rate, n2,
unwrapped_arc_position and advance are shared.
"""

from __future__ import annotations

import abc
import math

import numpy as np

__all__ = [
    "Contour",
    "CircularContour",
    "StraightContour",
    "contour_at",
    "direction_of_motion",
    "removal_scale",
]

_TOL = 1e-9  # validation tolerance (unit-ness, orthogonality, horizontality)
_MIN_RHO = (
    1e-9  # CircularContour: n1 undefined closer than this to the centre axis
)


def _value(y):
    """Plain float of a float or AutoDiffXd scalar (for branching only)."""
    return y.value() if hasattr(y, "value") else float(y)


def _vec3(p, name):
    """Shape-(3,) array: object dtype kept (AutoDiffXd), otherwise float."""
    a = np.asarray(p)
    if a.dtype != object:
        a = a.astype(float)
    if a.shape != (3,):
        raise ValueError(f"{name} must have shape (3,), got shape {a.shape}")
    return a


def _vec3_float(p, name):
    """Shape-(3,) finite float array; AutoDiffXd entries are reduced to
    values."""
    if (
        type(p) is np.ndarray
        and p.dtype == np.float64
        and p.shape == (3,)
        and math.isfinite(p[0] + p[1] + p[2])
    ):
        return p  # the common case, on every controller and process step
    a = np.asarray(p)
    if a.shape != (3,):
        raise ValueError(f"{name} must have shape (3,), got shape {a.shape}")
    if a.dtype == object:
        a = np.array([_value(y) for y in a], dtype=float)
    else:
        a = a.astype(float)
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite, got {a}")
    return a


def _finite_scalar(x, name):
    x = _value(x)
    if not math.isfinite(x):
        raise ValueError(f"{name} must be a finite number, got {x}")
    return x


def contour_at(contour, step, time: float):
    """``contour``, or the contour of ``step`` = (time (s), contour) once
    ``time`` has reached that step's time (``step`` None: no step)."""
    if step is not None and time >= step[0]:
        return step[1]
    return contour


def direction_of_motion(tangent, v, min_speed):
    """n2 of :meth:`Contour.n2` from the edge tangent at the point: +-tangent
    by the sign of the speed along it, ``tangent`` below ``min_speed``."""
    min_speed = _finite_scalar(min_speed, "min_speed")
    if min_speed <= 0.0:
        raise ValueError(f"min_speed must be > 0, got {min_speed}")
    speed = _value(np.dot(tangent, _vec3(v, "v")))
    if abs(speed) < min_speed or speed > 0:
        return tangent
    return -tangent


class Contour(abc.ABC):
    """Zero-depth contour phi(p) = 0 in the horizontal plane z = ``height``.

    Subclasses implement: ``length``, ``closed``, ``height``, ``phi``,
    ``grad_phi``, ``tangent``, ``project``, ``arc_position``, ``point_at``.
    """

    # ----- abstract geometry -------------------------------------------------
    @property
    @abc.abstractmethod
    def length(self) -> float:
        """Arc length of the contour [m]; math.inf for an open, unbounded
        one."""

    @property
    @abc.abstractmethod
    def closed(self) -> bool:
        """True if arc positions wrap modulo ``length``."""

    @property
    @abc.abstractmethod
    def height(self) -> float:
        """z of the contour plane [m]."""

    varying_frame = False
    """True when the tool axis turns along the contour (a 3-D edge)."""

    def tool_axis_at(self, s):
        """The tool axis a(s) (unit, world) at arc position s: vertical."""
        return np.array([0.0, 0.0, 1.0])

    def axis_turn(self, s):
        """Rot_min(a(0) -> a(s)), the tool axis's turn (3 x 3): none."""
        return np.eye(3)

    def task_frame(self, s):
        """The controller's task axes x1, x2, x3 (columns, world) at arc
        position s: x3 along the tool axis, x1 and x2 across it. The
        world's axes here (the tool vertical)."""
        return np.eye(3)

    def chamfer_scale(self, s, delta, height):
        """The chamfer's cross-section at arc position s over delta *
        ``height`` (the cut's depth and height, m): 1, a vertical tool
        cutting a vertical wall under a horizontal top face."""
        return 1.0

    @abc.abstractmethod
    def phi(self, p):
        """Signed planar distance: > 0 free side, < 0 material (T-generic)."""

    @abc.abstractmethod
    def grad_phi(self, p):
        """Gradient of phi, shape (3,), z component 0 (T-generic)."""

    @abc.abstractmethod
    def tangent(self, p):
        """Unit tangent (3,) at the projection of p, in the traversal direction,
        orthogonal to n1(p) (T-generic)."""

    @abc.abstractmethod
    def project(self, p) -> np.ndarray:
        """Closest point on phi = 0 at z = height (float)."""

    @abc.abstractmethod
    def arc_position(self, p) -> float:
        """Arc position s of project(p) from the start point along the traversal
        direction; closed contours wrap into [0, length) (float)."""

    @abc.abstractmethod
    def point_at(self, s) -> np.ndarray:
        """3-D point at arc position s (closed: s modulo length) (float)."""

    # ----- shared defaults ---------------------------------------------------
    def n1(self, p):
        """n1 = -grad phi / |grad phi| (Sec. II), unit, into the material
        (T-generic)."""
        g = self.grad_phi(p)
        return -g / np.sqrt(np.dot(g, g))

    def depth(self, p):
        """Chamfer depth delta = -phi(p), positive in the material
        (T-generic)."""
        return -self.phi(p)

    def depth_rate(self, p, v):
        """d(delta)/dt = n1(p) . v for tool velocity v (T-generic)."""
        v = _vec3(v, "v")
        return np.dot(self.n1(p), v)

    @abc.abstractmethod
    def curvature(self, p) -> float:
        """Signed curvature (1/m) of the contour at the projection of p
        (float): 1/rho where the centre of curvature lies on the free side
        (a concave edge: the tube's bore, a pocket's corner), -1/rho where
        it lies in the material (a convex edge: a boss's corner), 0 on a
        straight piece."""

    @abc.abstractmethod
    def n1_rate(self, p, v) -> np.ndarray:
        """dn1/dt = (dn1/dp) v for a point p moving at v (1/s, float): the
        rate at which the depth direction turns, from the edge's
        curvature. x_pd = x* + delta_d n1(x_p) moves at
        xdot* + delta_d' n1 + delta_d n1_rate."""

    def n2(self, p, v, min_speed):
        """Direction of motion along the edge (eq. 2, R5): +-tangent(p), the
        sign of the velocity's component along the edge, i.e.
        (I - n1 n1^T) v normalized after also dropping the component along
        the wall's vertical (parallel to the cutter axis), which cuts no
        chamfer and would otherwise tip n2 out of the contour's plane.

        Returns ``tangent(p)`` when the speed along the edge is below
        ``min_speed`` (start-up). T-generic; min_speed is a float > 0 [m/s].
        """
        return direction_of_motion(self.tangent(p), v, min_speed)

    def frame(self, p):
        """(n1, tangent, depth, arc_position) at a float point p in one
        call: what the observer and the cutting process need per
        evaluation. Subclasses may compute it faster; the values equal the
        separate methods'."""
        return (
            self.n1(p),
            self.tangent(p),
            float(self.depth(p)),
            self.arc_position(p),
        )

    def edge_speed(self, p, v):
        """Signed speed along the edge, tangent(p) . v (m/s). T-generic."""
        return np.dot(self.tangent(p), _vec3(v, "v"))

    def unwrapped_arc_position(self, p, reference_s) -> float:
        """The s congruent to arc_position(p) modulo length that is closest to
        reference_s (closed contours; counts progress past one revolution).
        Open contours return arc_position(p)."""
        s = self.arc_position(p)
        if not self.closed:
            return s
        reference_s = _finite_scalar(reference_s, "reference_s")
        L = self.length
        return s + L * round((reference_s - s) / L)

    def advance(self, p, ds) -> np.ndarray:
        """R6: project p onto phi = 0 and move along the contour by arc length
        ds >= 0; returns point_at(arc_position(p) + ds)."""
        ds = _finite_scalar(ds, "ds")
        if ds < 0.0:
            raise ValueError(
                "ds must be >= 0 (arc length along the traversal "
                f"direction), got {ds}"
            )
        return self.point_at(self.arc_position(p) + ds)

    # ----- helpers for subclasses -------------------------------------------
    def _wrap(self, s: float) -> float:
        """Wrap s into [0, length) for closed contours."""
        L = self.length
        s = s % L
        if s >= L:  # float rounding of tiny negative s
            s = 0.0
        return s


class _ClosedAboutCenter(Contour):
    """A closed contour about ``center`` (x, y, z; z its height), its
    start at polar angle ``start_angle`` (rad), run in ``direction`` (+1
    counter-clockwise seen from +z, -1 clockwise)."""

    def _set_frame(self, center, start_angle, direction):
        self._center = _vec3_float(center, "center")
        self._start_angle = _finite_scalar(start_angle, "start_angle")
        if direction not in (1, -1):
            raise ValueError(
                "direction must be +1 (counter-clockwise) or -1 "
                f"(clockwise), got {direction}"
            )
        self._direction = int(direction)

    @property
    def center(self):
        return self._center.copy()

    @property
    def start_angle(self):
        return self._start_angle

    @property
    def direction(self):
        return self._direction

    @property
    def closed(self):
        return True

    @property
    def height(self):
        return float(self._center[2])


class CircularContour(_ClosedAboutCenter):
    """Circle of ``radius`` around ``center`` = (x, y, z); z is the contour
    height.

    Material lies OUTSIDE the circle (inner edge of a tube, tool inside): phi =
    radius - rho, n1 = radial outward (rho = planar distance to the centre).
    ``direction`` +1 = counter-clockwise seen from +z, -1 = clockwise; arc
    position 0 at polar angle ``start_angle`` [rad].  Points closer than 1e-9 m
    to the centre axis raise ValueError (n1 undefined).
    """

    def __init__(self, center, radius, start_angle=0.0, direction=1):
        self._set_frame(center, start_angle, direction)
        radius = _finite_scalar(radius, "radius")
        if radius <= 0.0:
            raise ValueError(f"radius must be > 0, got {radius}")
        self._radius = radius

    @property
    def radius(self):
        return self._radius

    @property
    def length(self):
        return 2.0 * math.pi * self._radius

    def _planar(self, p):
        """(dx, dy, rho) of p relative to the centre axis (T-generic)."""
        p = _vec3(p, "p")
        dx = p[0] - self._center[0]
        dy = p[1] - self._center[1]
        rho2 = dx * dx + dy * dy
        if _value(rho2) < _MIN_RHO * _MIN_RHO:
            raise ValueError(
                f"p must be at least {_MIN_RHO} m from the circle's "
                "centre axis (n1 undefined)"
            )
        return dx, dy, np.sqrt(rho2)

    def phi(self, p):
        _, _, rho = self._planar(p)
        return self._radius - rho

    def grad_phi(self, p):
        dx, dy, rho = self._planar(p)
        return np.array([-dx / rho, -dy / rho, 0.0 * rho])

    def tangent(self, p):
        dx, dy, rho = self._planar(p)
        d = self._direction
        return np.array([-d * dy / rho, d * dx / rho, 0.0 * rho])

    def frame(self, p):
        p = _vec3_float(p, "p")
        dx, dy = p[0] - self._center[0], p[1] - self._center[1]
        rho = math.hypot(dx, dy)
        if rho < _MIN_RHO:
            return super().frame(p)  # raises with the usual message
        n1 = np.array([dx / rho, dy / rho, 0.0])
        d = self._direction
        tangent = np.array([-d * dy / rho, d * dx / rho, 0.0])
        arc = self._wrap(
            d * (math.atan2(dy, dx) - self._start_angle) * self._radius
        )
        return n1, tangent, rho - self._radius, arc

    def curvature(self, p):
        """+1/radius: the material is outside the circle (concave edge)."""
        _vec3_float(p, "p")
        return 1.0 / self._radius

    def n1_rate(self, p, v):
        """(I - n1 n1^T) v_xy / rho: n1 is the planar radial direction."""
        p = _vec3_float(p, "p")
        v = _vec3_float(v, "v")
        dx, dy, rho = self._planar(p)
        n1 = np.array([dx / rho, dy / rho, 0.0])
        v_xy = np.array([v[0], v[1], 0.0])
        return (v_xy - (n1 @ v_xy) * n1) / rho

    def _angle(self, p):
        p = _vec3_float(p, "p")
        dx, dy, _ = self._planar(p)
        return math.atan2(dy, dx)

    def project(self, p):
        th = self._angle(p)
        c = self._center
        return np.array(
            [
                c[0] + self._radius * math.cos(th),
                c[1] + self._radius * math.sin(th),
                c[2],
            ]
        )

    def arc_position(self, p):
        th = self._angle(p)
        return self._wrap(
            self._direction * (th - self._start_angle) * self._radius
        )

    def point_at(self, s):
        s = self._wrap(_finite_scalar(s, "s"))
        th = self._start_angle + self._direction * s / self._radius
        c = self._center
        return np.array(
            [
                c[0] + self._radius * math.cos(th),
                c[1] + self._radius * math.sin(th),
                c[2],
            ]
        )


class StraightContour(Contour):
    """Horizontal straight edge through ``start`` with traversal direction
    ``tangent``.

    ``tangent`` and ``material_normal`` are unit, horizontal and mutually
    orthogonal (within 1e-9, else ValueError); ``material_normal`` points into
    the material, so phi = -(p - start) . material_normal and n1 =
    material_normal. Arc position is the signed (p - start) . tangent: negative
    before the start, and NOT limited to ``length``.  ``length`` (> 0, default
    math.inf) is informational for callers (end of the edge); phi, project,
    point_at and advance extend the line beyond both ends without raising.
    """

    def __init__(self, start, tangent, material_normal, length=math.inf):
        self._start = _vec3_float(start, "start")
        t = _vec3_float(tangent, "tangent")
        n = _vec3_float(material_normal, "material_normal")
        for name, u in (("tangent", t), ("material_normal", n)):
            if abs(np.linalg.norm(u) - 1.0) > _TOL:
                raise ValueError(
                    f"{name} must be a unit vector (|norm - 1| <= {_TOL}), "
                    f"got norm {np.linalg.norm(u)}"
                )
            if abs(u[2]) > _TOL:
                raise ValueError(
                    f"{name} must be horizontal (|z| <= {_TOL}), got z = {u[2]}"
                )
        if abs(float(np.dot(t, n))) > _TOL:
            raise ValueError(
                "material_normal must be orthogonal to tangent "
                f"(|dot| <= {_TOL}), got {np.dot(t, n)}"
            )
        length = float(length)
        if math.isnan(length) or length <= 0.0:
            raise ValueError(
                f"length must be > 0 (math.inf allowed), got {length}"
            )
        self._t = t
        self._n = n
        self._length = length

    @property
    def start(self):
        return self._start.copy()

    @property
    def material_normal(self):
        return self._n.copy()

    @property
    def length(self):
        return self._length

    @property
    def closed(self):
        return False

    @property
    def height(self):
        return float(self._start[2])

    def phi(self, p):
        p = _vec3(p, "p")
        return -(
            (p[0] - self._start[0]) * self._n[0]
            + (p[1] - self._start[1]) * self._n[1]
        )

    def grad_phi(self, p):
        p = _vec3(p, "p")
        z = 0.0 * p[0]
        return np.array([z - self._n[0], z - self._n[1], z])

    def tangent(self, p):
        p = _vec3(p, "p")
        z = 0.0 * p[0]
        return np.array([z + self._t[0], z + self._t[1], z])

    def curvature(self, p):
        """Zero: a straight edge."""
        _vec3_float(p, "p")
        return 0.0

    def n1_rate(self, p, v):
        """Zero: a straight edge's n1 does not turn."""
        _vec3_float(p, "p")
        _vec3_float(v, "v")
        return np.zeros(3)

    def arc_position(self, p):
        p = _vec3_float(p, "p")
        return float(
            (p[0] - self._start[0]) * self._t[0]
            + (p[1] - self._start[1]) * self._t[1]
        )

    def point_at(self, s):
        s = _finite_scalar(s, "s")
        return np.array(
            [
                self._start[0] + s * self._t[0],
                self._start[1] + s * self._t[1],
                self._start[2],
            ]
        )

    def project(self, p):
        return self.point_at(self.arc_position(p))


def removal_scale(curvature, delta, cutter_radius):
    """Material the cutter removes per metre of its centre's travel on an
    arc, relative to a straight edge at the same depth:
    (1 + kappa (r + delta / 2)) / (1 + kappa delta).

    ``curvature`` kappa (1/m) is the zero-depth path's
    (:meth:`Contour.curvature`: > 0 concave, the centre of the arc on the
    free side), r the cutter radius, delta the depth (m). On a concave
    arc the edge has radius rho_e = rho + r (rho = 1 / kappa, the path's);
    at depth delta the cutter centre runs on rho + delta and removes the
    band rho_e .. rho_e + delta, delta (rho_e + delta / 2) per radian: more
    per metre of centre travel than on a line. On a convex arc (kappa < 0)
    the band is rho_e - delta .. rho_e = rho - r and less is removed."""
    k = float(curvature)
    return (1.0 + k * (cutter_radius + 0.5 * delta)) / (1.0 + k * delta)
