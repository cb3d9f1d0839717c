"""The tool's path along a 3-D edge of a part (pure numpy/scipy).

An ``EdgeContour`` is the ``Contour`` of an ``EdgeCurve``: the zero-depth
path of the cutter tip's centre as the planar contours' path is, but in 3-D
with a frame that turns along it. The cutter is a cylinder that cuts with
its side, its axis a(u) (unit, from the tip towards the holder) set by a
rule on the edge's faces (``EdgeCurve.tool_axis``). Along the edge c(u):

  * n1(u): unit, perpendicular to a(u) and to the edge's tangent, into the
    material (on the side of the faces' bisector); the chamfer depth is
    measured along it;
  * n2 = the edge's tangent in the traversal direction;
  * the tool path z(u) = c(u) - r n1(u) - e a(u), r the cutter's radius and
    e its engagement (the tip that far below the edge along the axis).

For the paper's bore (the tool along the top face's normal) this is the
circle of radius R - r at height top - e. The cutter's side plane (through
the edge, containing a and the tangent) must be a supporting plane of the
part there: a plane that cuts into either face would gouge it, so such a
rule is refused with the tilt that clears it.

The contour's arc position s is the arc length of the tool path z from the
start of the pass, in the traversal direction; z, n1, n2 and a are cubic
splines in s on knots about ``spacing`` apart, and s maps back to the edge's
arc length u.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path
from typing import NamedTuple

import numpy as np
from scipy.interpolate import CubicSpline

from deburr_drake.math.geometry import (
    Contour,
    _finite_scalar,
    _vec3,
    _vec3_float,
)
from deburr_drake.math.mesh_part import (
    EdgeCurve,
    MeshPart,
    choose_edge,
    load_part,
    sharp_edges,
    shown_direction,
    spindle_hits,
    surface_points,
)

__all__ = [
    "EdgeContour",
    "Stations",
    "chamfer_area_ratio",
    "face_rule",
    "load_edge",
    "spindle_clash",
]

_RULES = ("left", "right", "axis")
# -, the least difference of the two faces' mean cosines to a direction
# that names one of them (a direction halfway between names neither)
_FACE_MARGIN = 0.05
# rad: how far the side plane may turn into a face before it is a gouge
# (a faceted mesh's smoothed normals on a 90-degree edge scatter by less)
_GOUGE_TOLERANCE = 0.02
# columns of the splines in s: tool point z, n1, n2, axis a, q (the
# edge's arc length u less its mean rate, periodic on a loop) and the two
# faces' outward normals' components along n1 and a (left, then right)
_Z, _N1, _T, _A, _Q, _F = (
    slice(0, 3),
    slice(3, 6),
    slice(6, 9),
    slice(9, 12),
    slice(12, 13),
    slice(13, 17),
)


class Stations(NamedTuple):
    """The edge sampled for the contact mesher: arc positions ``arc`` (m,
    the tool path's), the edge's points (m, world), n1 and the tool axis
    (unit) and the faces' angle through the material (rad) there."""

    arc: np.ndarray
    points: np.ndarray
    n1: np.ndarray
    axis: np.ndarray
    face_angle: np.ndarray


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _dot(a, b):
    return np.einsum("ij,ij->i", a, b)


def minimal_rotation(a, b):
    """Rot_min(a -> b) (3 x 3): the least rotation turning the unit vector
    a onto the unit vector b, about their common normal."""
    w = np.cross(a, b)
    c = float(np.dot(a, b))
    if c <= -1.0 + 1e-12:
        raise ValueError("the tool axis turns over (a(s) = -a(0))")
    K = np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0]])
    return np.eye(3) + K + (K @ K) / (1.0 + c)


class EdgeContour(Contour):
    """The path of the tool along the edge ``curve`` (an ``EdgeCurve`` in
    the world frame, m).

    ``rule`` (left or right: the face whose outward normal the tool axis
    follows, left and right of the chain's own direction, which for a loop
    runs counter-clockwise seen from outside; ``axis``: the constant unit
    direction ``axis``, world, as a hole's), ``tilt`` (rad, about the
    chain's tangent) and ``lead`` (rad, towards the traversal direction)
    set the tool axis as ``EdgeCurve.tool_axis`` does. ``direction`` +1
    runs the chain's own way, -1 the other. The pass starts at
    ``start_fraction`` of the chain's length from the chain's start, or at
    the point of the edge nearest ``start_near`` (m); by default at the
    chain's start (an open chain run backwards: at its end) and, on an
    open chain, runs to its end.

    ValueError in one line: the bisector rule (n1 undefined: the axis lies
    in the faces' bisecting plane), a side plane that cuts into a face
    (naming the arc position and the tilt that clears it), an empty pass.
    """

    varying_frame = True

    def __init__(
        self,
        curve: EdgeCurve,
        *,
        cutter_radius: float,
        engagement: float,
        rule: str = "left",
        axis=None,
        rule_note: str = "",
        tilt: float = 0.0,
        lead: float = 0.0,
        direction: int = 1,
        start_fraction: float | None = None,
        start_near=None,
        spacing: float = 2.5e-4,
    ):
        self._check_arguments(rule, lead, direction, start_fraction)
        if (rule == "axis") != (axis is not None):
            raise ValueError("the axis rule takes an axis (and only it does)")
        self._axis = None if axis is None else _vec3_float(axis, "axis")
        self._rule_note = rule_note
        self._curve = curve
        self._r = _finite_scalar(cutter_radius, "cutter_radius")
        self._e = _finite_scalar(engagement, "engagement")
        self._rule, self._tilt, self._lead = rule, float(tilt), float(lead)
        self._d = int(direction)
        self._edge_length = curve.length
        self._closed = curve.closed
        self._tabulate_path(spacing)
        self._u0 = self._start_u(start_fraction, start_near)
        self._check_side_plane()
        self._check_cutter_fits()
        self._fit(spacing)

    # ----- construction -----
    @staticmethod
    def _check_arguments(rule, lead, direction, start_fraction):
        if rule == "bisector":
            raise ValueError(
                "the bisector rule leaves n1 undefined (the tool axis lies "
                "in the faces' bisecting plane, so the cutter's side faces "
                "neither face): use left or right, with a tilt"
            )
        if rule not in _RULES:
            raise ValueError(
                f"unknown tool rule {rule!r}: one of {', '.join(_RULES)}"
            )
        if not abs(_finite_scalar(lead, "lead")) < 0.5 * math.pi:
            raise ValueError(f"lead must be within (-pi/2, pi/2), got {lead}")
        if direction not in (1, -1):
            raise ValueError(f"direction must be +1 or -1, got {direction}")
        if start_fraction is not None and not 0.0 <= start_fraction <= 1.0:
            raise ValueError(
                f"start_fraction must be in [0, 1], got {start_fraction}"
            )

    def _geometry(self, u):
        """At edge arc lengths u (n,): the edge point, the chain's tangent,
        n1, the axis, the faces' bisector into the material, the faces'
        left and right outward normals and the faces' angle."""
        curve = self._curve
        f = curve.frame(u)
        axis = curve.tool_axis(
            u, rule=self._rule, tilt=self._tilt, axis=self._axis
        )
        axis = (
            math.cos(self._lead) * axis + math.sin(self._lead) * self._d * f.n2
        )
        side = _unit(np.cross(f.n2, axis))
        n1 = side * np.where(_dot(side, f.n1) >= 0.0, 1.0, -1.0)[:, None]
        return f, n1, axis

    def _tool_points(self, u):
        f, n1, axis = self._geometry(u)
        return f.point - self._r * n1 - self._e * axis

    def _tabulate_path(self, spacing):
        """S(u): the tool path's arc length from u = 0, on a grid of u."""
        L = self._edge_length
        n = max(64, math.ceil(L / spacing))
        u = np.linspace(0.0, L, n + 1)
        z = self._tool_points(u)
        if self._closed:
            z[-1] = z[0]
        path = CubicSpline(
            u, z, bc_type="periodic" if self._closed else "not-a-knot"
        )
        velocity = path.derivative()
        g, w = np.polynomial.legendre.leggauss(5)
        h = np.diff(u)
        nodes = u[:-1, None] + 0.5 * h[:, None] * (g[None, :] + 1.0)
        speed = np.linalg.norm(velocity(nodes.ravel()), axis=1)
        pieces = 0.5 * h * (speed.reshape(nodes.shape) @ w)
        self._grid_u = u
        self._grid_S = np.concatenate([[0.0], np.cumsum(pieces)])
        self._path_u = path
        self._S = CubicSpline(u, self._grid_S)

    def _S_of(self, u):
        """The tool path's arc length from u = 0 at unwrapped u (a loop's
        u beyond its length adds whole turns)."""
        u = np.asarray(u, float)
        L, total = self._edge_length, self._grid_S[-1]
        if not self._closed:
            return self._S(np.clip(u, 0.0, L))
        turns = np.floor(u / L)
        return self._S(u - turns * L) + turns * total

    def _u_of(self, S):
        """The inverse of ``_S_of``: unwrapped u at path arc lengths S."""
        S = np.asarray(S, float)
        L, total = self._edge_length, self._grid_S[-1]
        turns = np.floor(S / total) if self._closed else 0.0
        rest = S - turns * total
        u = np.interp(rest, self._grid_S, self._grid_u)
        velocity = self._path_u.derivative()
        for _ in range(3):  # Newton on S(u) = rest, dS/du = |z'(u)|
            speed = np.linalg.norm(velocity(u), axis=-1)
            u = np.clip(u - (self._S(u) - rest) / speed, 0.0, L)
        return u + turns * L

    def _start_u(self, fraction, near):
        if near is not None:
            if fraction is not None:
                raise ValueError(
                    "start the pass at start_fraction or start_near, not both"
                )
            return self._curve.project(_vec3_float(near, "start_near"))
        if fraction is None:
            fraction = 1.0 if (self._d < 0 and not self._closed) else 0.0
        return fraction * self._edge_length

    def _pass_length(self):
        if self._closed:
            return float(self._grid_S[-1])
        S0 = float(self._S_of(self._u0))
        return self._grid_S[-1] - S0 if self._d > 0 else S0

    def _check_side_plane(self):
        """The side plane (through the edge, containing the axis and the
        tangent, its normal n1) is a supporting plane where n1 lies within
        (pi - face angle) / 2 of the faces' bisector, turning about the
        tangent: both faces then lie on n1's side of it."""
        n = max(256, math.ceil(self._edge_length / 2.5e-4))
        u = np.linspace(0.0, self._edge_length, n, endpoint=self._closed)
        f, n1, _ = self._geometry(u)
        off = np.arctan2(
            _dot(f.n2, np.cross(f.n1, n1)), np.clip(_dot(f.n1, n1), -1, 1)
        )
        half = 0.5 * (math.pi - f.face_angle)
        bad = np.abs(off) > half + _GOUGE_TOLERANCE
        if not bad.any():
            return
        k = int(np.flatnonzero(bad)[0])
        where = self._d * (self._S_of(u[k]) - self._S_of(self._u0))
        if self._closed:
            where %= self._grid_S[-1]
        angle = math.degrees(f.face_angle[k])
        into = math.degrees(abs(off[k]) - half[k])
        lo = float(np.max(-half - off))
        hi = float(np.min(half - off))
        if lo > hi:
            cure = (
                "no tilt clears it along the whole edge (the faces' angle "
                f"goes from {math.degrees(f.face_angle.min()):.1f} to "
                f"{math.degrees(f.face_angle.max()):.1f} deg)"
            )
        else:
            turn = lo if lo > 0.0 else hi
            tilt = round(self._tilt + turn, 4) + 0.0  # no "-0.0000"
            cure = (
                f"a tilt of {tilt:.4f} rad ({math.degrees(tilt):.1f} deg) "
                "clears it"
            )
        raise ValueError(
            f"the cutter's side plane (tool rule {self._rule}, tilt "
            f"{self._tilt:g} rad) cuts {into:.1f} deg into a face at arc "
            f"position {where * 1e3:.2f} mm, where the faces meet at "
            f"{angle:.1f} deg: {cure}"
        )

    def _check_cutter_fits(self):
        """The edge, seen along the tool axis, bends towards the free side
        (a hole's rim, a pocket's rounded corner) no tighter than the
        cutter's radius: else the cutter's centre would pass the edge's
        centre of curvature and its side cut the wall across."""
        n = max(256, math.ceil(self._edge_length / 2.5e-4))
        u = np.linspace(0.0, self._edge_length, n, endpoint=self._closed)
        f, n1, axis = self._geometry(u)
        # the curvature towards the free side, over the share of the
        # tangent across the axis squared: the curvature seen along it
        bend = -_dot(self._curve.curvature_vector(u), n1) / np.maximum(
            1.0 - _dot(f.n2, axis) ** 2, 1e-12
        )
        k = int(np.argmax(bend))
        if bend[k] * self._r < 1.0:
            return
        where = self._S_of(u[k]) - self._S_of(self._u0)
        if self._closed:
            where %= self._grid_S[-1]
        raise ValueError(
            f"the edge bends tighter than the cutter at arc position "
            f"{abs(where) * 1e3:.2f} mm: its radius there, seen along the "
            f"tool axis, is {1e3 / bend[k]:.2f} mm towards the free side, "
            f"not larger than the cutter's {self._r * 1e3:.2f} mm: a "
            "smaller tool.cutter_radius fits"
        )

    def _fit(self, spacing):
        """Splines in s of z, n1, n2, a and q = u - (L_edge / L) d s."""
        L = self._pass_length()
        if L <= 1e-9:
            raise ValueError(
                "the pass is empty: an open edge run backwards from its start "
                "(or forwards from its end)"
            )
        n = max(16, math.ceil(L / spacing))
        s = np.linspace(0.0, L, n + 1)
        u = self._u_of(self._S_of(self._u0) + self._d * s)
        f, n1, axis = self._geometry(u)
        z = f.point - self._r * n1 - self._e * axis
        rate = self._d * self._edge_length / L if self._closed else 0.0
        faces = np.column_stack(
            [
                _dot(f.left_normal, n1),
                _dot(f.left_normal, axis),
                _dot(f.right_normal, n1),
                _dot(f.right_normal, axis),
            ]
        )
        data = np.column_stack(
            [z, n1, self._d * f.n2, axis, u - rate * s, faces]
        )
        if self._closed:
            data[-1] = data[0]
        spline = CubicSpline(
            s, data, bc_type="periodic" if self._closed else "not-a-knot"
        )
        self._length = float(L)
        self._rate = rate
        self._n = n
        self._h = L / n
        self._C = np.ascontiguousarray(np.moveaxis(spline.c, 1, 0))  # n,4,17
        # per piece: the cubic's coefficients of z, then of t
        self._rows = np.concatenate(
            [
                self._C[:, :, _Z].reshape(n, 12),
                self._C[:, :, _T].reshape(n, 12),
            ],
            axis=1,
        ).tolist()
        self._samples = z[:-1] if self._closed else z
        self._sample_s = s[:-1] if self._closed else s
        # within this distance of the path its nearest point is the local
        # one Newton finds from a nearby s (half the least radius)
        bend = np.linalg.norm(spline(s, 2)[:, _Z], axis=1).max()
        self._reach = 0.5 / max(bend, 1e-9)
        self._a0 = axis[0] / np.linalg.norm(axis[0])
        # world z onto the start's axis: the task frame at the start
        self._task0 = minimal_rotation(np.array([0.0, 0.0, 1.0]), self._a0)
        self._last_s = 0.0

    def describe_rule(self) -> str:
        """One line: the tool rule this path was built with (and
        ``rule_note``: why), its tilt and lead."""
        if self._rule == "axis":
            what = f"the tool axis along {shown_direction(self._axis)} (world)"
        else:
            what = f"the tool on the {self._rule} face"
        note = f" ({self._rule_note})" if self._rule_note else ""
        return (
            f"tool rule: {what}{note}, tilt {self._tilt:g} rad, lead "
            f"{self._lead:g} rad"
        )

    # ----- evaluation -----
    def _clamp(self, s):
        L = self._length
        if self._closed:
            s %= L
            return 0.0 if s >= L else s
        return min(max(s, 0.0), L)

    def _piece(self, s):
        k = int(s / self._h)
        k = min(max(k, 0), self._n - 1)
        return self._C[k], s - k * self._h

    def _values(self, s):
        """All the columns at a float s (already wrapped or clamped)."""
        c, x = self._piece(s)
        return np.dot((x * x * x, x * x, x, 1.0), c)

    def _newton(self, p, s, iterations=12):
        """s where the chamfer's cross-section plane (normal to the edge
        tangent t(s)) passes through p, by Newton from s, and the squared
        distance from p to z(s) (inf: Newton did not converge).

        The root of g(s) = (z(s) - p) . t(s), not the path's nearest point:
        where the tool axis tilts along the edge the path's tangent z' leans
        off t, and the nearest point of a tool pressed delta along n1 would
        trail or lead the cross-section by about delta (n1 . z') / |z'|.
        Plain floats: a handful of 3-vectors costs less than numpy calls."""
        px, py, pz = float(p[0]), float(p[1]), float(p[2])
        rows, h, last = self._rows, self._h, self._n - 1
        for _ in range(iterations):
            k = min(max(int(s / h), 0), last)
            x = s - k * h
            (ax, ay, az, bx, by, bz, cx, cy, cz, dx, dy, dz) = rows[k][:12]
            (Ax, Ay, Az, Bx, By, Bz, Cx, Cy, Cz, Dx, Dy, Dz) = rows[k][12:]
            rx = ((ax * x + bx) * x + cx) * x + dx - px
            ry = ((ay * x + by) * x + cy) * x + dy - py
            rz = ((az * x + bz) * x + cz) * x + dz - pz
            ux = (3.0 * ax * x + 2.0 * bx) * x + cx
            uy = (3.0 * ay * x + 2.0 * by) * x + cy
            uz = (3.0 * az * x + 2.0 * bz) * x + cz
            tx = ((Ax * x + Bx) * x + Cx) * x + Dx
            ty = ((Ay * x + By) * x + Cy) * x + Dy
            tz = ((Az * x + Bz) * x + Cz) * x + Dz
            g = rx * tx + ry * ty + rz * tz
            slope = (
                ux * tx
                + uy * ty
                + uz * tz
                + rx * ((3.0 * Ax * x + 2.0 * Bx) * x + Cx)
                + ry * ((3.0 * Ay * x + 2.0 * By) * x + Cy)
                + rz * ((3.0 * Az * x + 2.0 * Bz) * x + Cz)
            )
            if slope <= 0.0:
                return s, math.inf
            step = g / slope
            s_new = self._clamp(s - step)
            if abs(s_new - s) < 1e-10 or abs(step) < 1e-10:
                return s_new, rx * rx + ry * ry + rz * rz
            s = s_new
        return s, math.inf

    def _locate(self, p):
        """Arc position of the path's point nearest the float point p:
        Newton from the last answer when p is within reach of the path
        there, else from the nearest sample."""
        s, distance2 = self._newton(p, self._last_s, iterations=6)
        if distance2 < self._reach * self._reach:
            self._last_s = s
            return s
        d = self._samples - p
        k = int(np.argmin(np.einsum("ij,ij->i", d, d)))
        s, _ = self._newton(p, float(self._sample_s[k]))
        self._last_s = s
        return s

    def _at(self, p):
        """(s*, the columns at s*) for a point p (AutoDiff: its value)."""
        s = self._locate(_vec3_float(p, "p"))
        return s, self._values(s)

    # ----- Contour -----
    @property
    def length(self):
        return self._length

    @property
    def closed(self):
        return self._closed

    @property
    def height(self):
        """z of the pass's start (m): a 3-D path has no one height."""
        return float(self._values(0.0)[2])

    @property
    def curve(self) -> EdgeCurve:
        return self._curve

    @property
    def direction(self) -> int:
        return self._d

    def phi(self, p):
        _, v = self._at(p)
        p = _vec3(p, "p")
        z, n1 = v[_Z], v[_N1]
        return -(
            n1[0] * (p[0] - z[0])
            + n1[1] * (p[1] - z[1])
            + n1[2] * (p[2] - z[2])
        )

    def grad_phi(self, p):
        _, v = self._at(p)
        zero = 0.0 * _vec3(p, "p")[0]
        return zero - v[_N1]

    def n1(self, p):
        _, v = self._at(p)
        zero = 0.0 * _vec3(p, "p")[0]
        return zero + v[_N1]

    def tangent(self, p):
        _, v = self._at(p)
        zero = 0.0 * _vec3(p, "p")[0]
        return zero + v[_T]

    def frame(self, p):
        p = _vec3_float(p, "p")
        s = self._locate(p)
        v = self._values(s)
        n1 = v[_N1]
        return n1, v[_T], float(n1 @ (p - v[_Z])), s

    def curvature(self, p):
        """-z''(s*) . n1: > 0 where the path bends away from the material."""
        s, v = self._at(p)
        c, x = self._piece(s)
        d2 = 6.0 * c[0, _Z] * x + 2.0 * c[1, _Z]
        return float(-(d2 @ v[_N1]))

    def n1_rate(self, p, v):
        """n1'(s*) ds*/dt, with ds*/dt = t . v / (z' . t - (p - z) . t')
        from differentiating (z(s*) - p) . t(s*) = 0."""
        p = _vec3_float(p, "p")
        v = _vec3_float(v, "v")
        s = self._locate(p)
        c, x = self._piece(s)
        value = ((c[0] * x + c[1]) * x + c[2]) * x + c[3]
        d1 = (3.0 * c[0] * x + 2.0 * c[1]) * x + c[2]
        r = p - value[_Z]
        rate = (value[_T] @ v) / (d1[_Z] @ value[_T] - r @ d1[_T])
        return d1[_N1] * rate

    def project(self, p):
        return self._at(p)[1][_Z].copy()

    def arc_position(self, p):
        return self._at(p)[0]

    def point_at(self, s):
        s = self._clamp(_finite_scalar(s, "s"))
        return self._values(s)[_Z].copy()

    # ----- the turning frame -----
    def tool_axis_at(self, s):
        """a(s): the tool axis (unit, world) at arc position s."""
        a = self._values(self._clamp(_finite_scalar(s, "s")))[_A]
        return a / np.linalg.norm(a)

    def axis_turn(self, s):
        """Rot_min(a(0) -> a(s)) (3 x 3): the least rotation turning the
        start's axis onto a(s), about their common normal."""
        return minimal_rotation(self._a0, self.tool_axis_at(s))

    def task_frame(self, s):
        """The controller's task axes at arc position s (columns, world):
        Rot_min(a(0) -> a(s)) Rot_min(z -> a(0)), so x3 is the tool axis
        a(s) and the frame turns with the desired tool rotation."""
        return self.axis_turn(s) @ self._task0

    def chamfer_scale(self, s, delta, height):
        """The chamfer's cross-section at arc position s over delta *
        ``height`` (m): the part of the faces' wedge within delta of the
        cutter's side plane and above its tip (``height`` below the edge
        along the axis), in the (n1, a) plane through the edge point
        (``chamfer_area_ratio``); 1 where one face runs along -a and the
        other along n1."""
        s = self._clamp(_finite_scalar(s, "s"))
        left_n1, left_a, right_n1, right_a = self._values(s)[_F]
        return chamfer_area_ratio(
            ((left_n1, left_a), (right_n1, right_a)), delta, height
        )

    def edge_u(self, s):
        """The edge's arc length u (m, in [0, edge length)) at arc
        position s."""
        s = self._clamp(_finite_scalar(s, "s"))
        u = float(self._values(s)[_Q][0]) + self._rate * s
        return float(self._curve._u(u))

    def edge_point(self, s):
        """c(u(s)): the part's edge point (m, world) where the chamfer at
        arc position s is cut."""
        return self._curve.point(self.edge_u(s))

    def stations(self, spacing) -> Stations:
        """The pass's edge sampled about ``spacing`` (m) apart along the
        edge, in the traversal direction (a loop: its last station is not
        the first again)."""
        spacing = _finite_scalar(spacing, "spacing")
        if spacing <= 0.0:
            raise ValueError(f"spacing must be > 0, got {spacing}")
        L = self._edge_length
        S0 = float(self._S_of(self._u0))
        if self._closed:
            n = max(8, round(L / spacing))
            u = self._u0 + self._d * L * np.arange(n) / n
        else:
            end = L if self._d > 0 else 0.0
            n = max(1, math.ceil(abs(end - self._u0) / spacing))
            u = np.linspace(self._u0, end, n + 1)
        s = self._d * (self._S_of(u) - S0)
        if self._closed:
            s = np.mod(s, self._length)
            s[0] = 0.0
        f, n1, axis = self._geometry(self._curve._u(u))
        return Stations(s, f.point, n1, axis, f.face_angle)


def _clipped_integral(slope, offset, x0, x1):
    """The integral of max(0, slope x + offset) over [x0, x1] (x0 <= x1)."""
    if x1 <= x0:
        return 0.0
    h0, h1 = slope * x0 + offset, slope * x1 + offset
    if h0 >= 0.0 and h1 >= 0.0:
        return offset * (x1 - x0) + 0.5 * slope * (x1 * x1 - x0 * x0)
    if h0 <= 0.0 and h1 <= 0.0:
        return 0.0
    root = -offset / slope  # inside (x0, x1): h changes sign there
    return 0.5 * (h0 * (root - x0) if h0 > 0.0 else h1 * (x1 - root))


def chamfer_area_ratio(faces, delta, height):
    """The chamfer's cross-section over delta * ``height`` on a convex edge.

    In the plane through the edge point spanned by n1 (x, into the
    material) and the tool axis a (y, towards the holder), the material
    is the wedge {x n_x + y n_y <= 0 for both faces}, ``faces`` the two
    faces' outward normals as (n_x, n_y) = (n . n1, n . a). The cutter
    removes the part of it with 0 <= x <= delta (its side plane at x = 0
    supports the part) and y >= -height (its tip). A face with n_y > 0
    bounds the wedge above by y = k x, k = -n_x / n_y, one with n_y < 0
    below; with x >= 0 the lower of the upper lines (k_u) and the higher
    of the lower ones (k_l) bound it, so the section's height at x is
    k_u x - max(-height, k_l x), clipped at zero. Exactly 1 for the faces
    (0, 1) and (-1, 0) (one face along n1, the other along -a: the planar
    contours' rectangle). delta <= 0: 1 (no cut; the area is zero either
    way)."""
    if not delta > 0.0:
        return 1.0
    upper, lower = math.inf, -math.inf
    for n_x, n_y in faces:
        if n_y > 0.0:
            upper = min(upper, -n_x / n_y)
        elif n_y < 0.0:
            lower = max(lower, -n_x / n_y)
        elif n_x > 0.0:  # a face along a: no material at x > 0
            return 0.0
    if upper == math.inf:
        raise ValueError(
            "no face bounds the chamfer towards the tool's holder: the "
            "tool axis points into the part"
        )
    # below x_break the lower face bounds the section, beyond it the tip
    x_break = min(delta, height / -lower) if lower < 0.0 else delta
    area = _clipped_integral(
        upper - lower, 0.0, 0.0, x_break
    ) + _clipped_integral(upper, height, x_break, delta)
    return area / (delta * height)


def face_rule(curve: EdgeCurve, direction) -> str:
    """``left`` or ``right``: the face of ``curve`` whose outward normal
    is nearest the (world) ``direction`` on average along the edge, so a
    tool rule reads as "stand on the face facing up" whichever way the
    chain runs. ValueError in one line when the direction is about as
    near both faces."""
    d = _vec3_float(direction, "direction")
    norm = float(np.linalg.norm(d))
    if not norm > 0.0:
        raise ValueError("the tool face's direction must not be zero")
    n = max(64, math.ceil(curve.length / 1e-3))
    u = np.linspace(0.0, curve.length, n, endpoint=not curve.closed)
    left, right = curve.face_normals(u)
    near_left = float(np.mean(left @ d)) / norm
    near_right = float(np.mean(right @ d)) / norm
    if abs(near_left - near_right) < _FACE_MARGIN:
        raise ValueError(
            "the direction is about as near both faces' outward normals "
            f"(mean cosines {near_left:.2f} and {near_right:.2f}): name "
            "the face the tool stands on more nearly"
        )
    return "left" if near_left > near_right else "right"


def spindle_clash(
    part: MeshPart, path: EdgeContour, cutter_radius, cutter_length
) -> str:
    """'' when along ``path`` (48 stations) the spindle beyond the
    cutter stands clear of ``part`` (``spindle_hits``), else where it
    does not, in a phrase."""
    stations = path.stations(path.length / 48)
    hits = spindle_hits(
        surface_points(part),
        stations.points,
        stations.n1,
        stations.axis,
        cutter_radius=cutter_radius,
        cutter_length=cutter_length,
    )
    if not np.any(hits):
        return ""
    k = int(np.flatnonzero(hits)[0])
    return (
        f"the spindle stands in the part at {np.mean(hits):.0%} of the edge "
        f"(first at arc position {stations.arc[k] * 1e3:.1f} mm, the tool "
        f"axis along {shown_direction(stations.axis[k])})"
    )


@functools.lru_cache(maxsize=8)
def _part(path, mtime, units, xyz, rpy):
    return load_part(path, units=units, xyz=xyz, rpy=rpy)


@functools.lru_cache(maxsize=16)
def _edge(path, mtime, units, xyz, rpy, sharp_angle, near):
    part = _part(path, mtime, units, xyz, rpy)
    chains = sharp_edges(part, min_angle=sharp_angle)
    if not chains:
        raise ValueError(
            f"{path}: no edge sharper than {sharp_angle:g} rad on the part"
        )
    world = part.to_world(near)
    chain = choose_edge(chains, near=world)
    return part, EdgeCurve(chain), chain.distance(world)


def load_edge(
    path, *, units="m", xyz=(0, 0, 0), rpy=(0, 0, 0), sharp_angle, near
) -> tuple[MeshPart, EdgeCurve, float]:
    """The part in ``path`` placed by ``xyz`` (m) and ``rpy`` (rad) as
    ``load_part`` places it, the ``EdgeCurve`` of its edge (dihedral over
    ``sharp_angle``, rad) nearest the point ``near`` (m, in the part
    frame), and that edge's distance from ``near`` (m). Each part and edge
    is read once per file version (the file's modification time)."""
    path = Path(path)
    mtime = path.stat().st_mtime_ns if path.is_file() else 0
    return _edge(
        str(path),
        mtime,
        units,
        tuple(float(x) for x in xyz),
        tuple(float(x) for x in rpy),
        float(sharp_angle),
        tuple(float(x) for x in near),
    )
