"""Registration of the believed part (pure numpy): the correction
``r = (dx, dy, dyaw, dradius)`` (m, m, rad, m) that moves the believed edge
onto the real one, the contour it gives, and ``r`` from probed points.

- :func:`moved_contour`: the believed contour moved by (dx, dy), turned by
  dyaw about its pivot (a circle: its centre, dyaw turns its start angle; a
  straight edge: its midpoint, or its start when it is endless) and, a
  circle, with a radius dradius larger.
- :func:`registration_from_points`: the circle or straight-edge fit
  (deburr_drake.math.fits) of touch points on the real edge's zero-depth
  path, with the points off by more than ``max_residual`` dropped.
- while cutting (:func:`contact_regressor`, :func:`rls_update`,
  :func:`registration_of`): the contact force against the depth on a
  reference contour, ||f_n|| = c0 + c1 (delta_0 - d), shows how far the
  real edge lies beyond it, d = w . n1 + psi (s - s_pivot), the offset
  estimated together with the contact parameters by recursive least
  squares.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from deburr_drake.math.fits import fit_circle, fit_consensus, fit_line
from deburr_drake.math.geometry import (CircularContour, Contour,
                                        StraightContour)

__all__ = ["REGISTRATION_SIZE", "moved_contour", "ProbeFit",
           "registration_from_points", "ONLINE_PARAMETERS",
           "contact_regressor", "onset_regressor", "registration_of",
           "rls_update"]

#: (dx, dy, dyaw, dradius).
REGISTRATION_SIZE = 4


def _rot(yaw):
    c, s = math.cos(yaw), math.sin(yaw)
    return np.array([[c, -s], [s, c]])


def _pivot(contour: StraightContour) -> np.ndarray:
    half = 0.5 * contour.length if math.isfinite(contour.length) else 0.0
    return contour.point_at(half)


def moved_contour(contour: Contour, registration) -> Contour:
    """``contour`` moved by ``registration`` (dx, dy, dyaw, dradius)."""
    dx, dy, dyaw, dradius = (float(v) for v in registration)
    if not any((dx, dy, dyaw, dradius)):
        return contour
    if isinstance(contour, CircularContour):
        center = contour.center + np.array([dx, dy, 0.0])
        return CircularContour(center, contour.radius + dradius,
                               start_angle=contour.start_angle + dyaw,
                               direction=contour.direction)
    if isinstance(contour, StraightContour):
        R = _rot(dyaw)
        pivot = _pivot(contour)
        start = contour.point_at(0.0)
        start[:2] = pivot[:2] + R @ (start[:2] - pivot[:2]) + [dx, dy]
        t = contour.tangent(start)
        n = contour.material_normal
        t[:2] = R @ t[:2]
        n[:2] = R @ n[:2]
        return StraightContour(start, t, n, length=contour.length)
    raise TypeError(f"registration of a {type(contour).__name__} is not "
                    "supported: a circle or a straight edge")


@dataclass
class ProbeFit:
    registration: np.ndarray  # (4,) dx, dy, dyaw, dradius
    kept: np.ndarray          # (N,) bool, the points the fit used
    residuals: np.ndarray     # (N,) m, of every point to the final fit
    rms: float                # m, of the kept points


def registration_from_points(contour: Contour, points, *,
                             max_residual: float,
                             fit_radius: bool = False) -> ProbeFit:
    """The registration of ``contour`` (the believed zero-depth path) that
    best puts it through ``points`` ((N, 2 or 3), m, world; the touch
    points already compensated to the zero-depth path). A circle: its
    centre (and, ``fit_radius``, its radius), at least 3 points (4 to
    find an outlier); a
    straight edge: its offset and heading, at least 3 points (2 are fitted
    exactly, the third shows an outlier)."""
    p = np.asarray(points, float)[:, :2]
    if isinstance(contour, CircularContour):
        # The touches are found agreeing with one circle of free radius
        # (fit_consensus), so that a bias common to every touch (the
        # detection's depth, which the stiffness of the contact sets) goes
        # into the radius rather than into the residuals; and the centre
        # is that circle's: with the drawing's radius held, a common bias
        # moves the centre whenever the kept touches are not symmetric
        # (one dropped on a burr: 0.14 mm of common bias put the centre
        # 50 um off, measured). The drawing's radius is held only when the
        # kept touches lie within a half circle (the radius is then
        # poorly known). ``fit_radius``: the fitted radius is applied too
        # (else the drawing's is kept: a probe cannot tell a radius error
        # from its own detection bias).
        if len(p) >= 4:
            _, kept = fit_consensus(fit_circle, p, minimal=3,
                                    max_residual=max_residual, minimum=3)
        else:
            kept = np.ones(len(p), bool)
        spread = _spread_around(p[kept], contour.center[:2])
        free = fit_radius or spread > math.pi
        fit = fit_circle(p[kept], radius=None if free else contour.radius,
                         seed=None if free else contour.center[:2])
        d = fit.center - contour.center[:2]
        reg = np.array([d[0], d[1], 0.0,
                        fit.radius - contour.radius if fit_radius else 0.0])
        all_res = np.linalg.norm(p - fit.center, axis=1) - fit.radius
        return ProbeFit(reg, kept, all_res, fit.rms)
    if isinstance(contour, StraightContour):
        fit, kept = fit_consensus(fit_line, p, minimal=2,
                                  max_residual=max_residual, minimum=2)
        t = contour.tangent(contour.point_at(0.0))[:2]
        direction = fit.direction if fit.direction @ t >= 0 else \
            -fit.direction
        dyaw = math.atan2(t[0] * direction[1] - t[1] * direction[0],
                          t @ direction)
        # Turn about the pivot, then shift along the turned normal so the
        # line passes through the fitted point.
        turned = moved_contour(contour, [0.0, 0.0, dyaw, 0.0])
        n = turned.material_normal[:2]
        q = np.array([fit.point[0], fit.point[1], turned.height])
        shift = -turned.phi(q) * n  # phi < 0 on the material side
        reg = np.array([shift[0], shift[1], dyaw, 0.0])
        normal = np.array([-direction[1], direction[0]])
        all_res = (p - fit.point) @ normal
        return ProbeFit(reg, kept, all_res, fit.rms)
    raise TypeError(f"registration of a {type(contour).__name__} is not "
                    "supported: a circle or a straight edge")


def _spread_around(points, center) -> float:
    """rad, the smallest arc of directions from ``center`` holding every
    point (2 pi minus the largest gap between neighbouring directions)."""
    a = np.sort(np.arctan2(points[:, 1] - center[1],
                           points[:, 0] - center[0]))
    if len(a) < 2:
        return 0.0
    gaps = np.diff(np.concatenate([a, [a[0] + 2 * math.pi]]))
    return float(2 * math.pi - gaps.max())


# -- registration while cutting -------------------------------------------
#: The online model's parameters: the contact force is
#: ||f_n|| = c0 + c1 (delta_0 - d), d = w . n1 + psi (s - s_pivot) how far
#: the real edge lies beyond the reference contour along n1 (w: m, the
#: offset; psi: rad, a straight edge's heading error), delta_0 the depth on
#: the reference; linear in (c0, c1, c1 w_x, c1 w_y, c1 psi).
ONLINE_PARAMETERS = ("c0", "c1", "c1_w_x", "c1_w_y", "c1_psi")


def _offset_terms(contour: Contour, x_p) -> np.ndarray:
    """(n1_x, n1_y, s - s_pivot): d = w . n1 + psi (s - s_pivot). A circle
    has no psi (its yaw moves nothing); on a straight edge w . n1 is a
    constant, told apart from c0 only by the contact onset."""
    n1 = contour.n1(x_p)
    if isinstance(contour, StraightContour):
        s = contour.arc_position(x_p) - contour.arc_position(_pivot(contour))
        return np.array([n1[0], n1[1], s])
    return np.array([n1[0], n1[1], 0.0])


def contact_regressor(contour: Contour, x_p) -> np.ndarray:
    """phi with ||f_n|| = phi . theta (ONLINE_PARAMETERS) at the tool point
    ``x_p`` (m) on the reference ``contour``."""
    return np.concatenate([[1.0, float(contour.depth(x_p))],
                           -_offset_terms(contour, x_p)])


def onset_regressor(contour: Contour, x_p, depth_at_detection=0.0):
    """phi with 0 = phi . theta where contact first comes: the real depth
    there is ``depth_at_detection`` (m, how far the tool moved in before
    the sensor showed it), so delta_0 - d = that depth, and no c0."""
    phi = contact_regressor(contour, x_p)
    phi[0] = 0.0
    phi[1] -= depth_at_detection
    return phi


def registration_of(contour: Contour, params) -> np.ndarray:
    """(dx, dy, dyaw, dradius) that moves ``contour`` onto the edge of the
    online model's ``params`` (ONLINE_PARAMETERS; zero while c1 is not
    positive)."""
    c1 = float(params[1])
    if not c1 > 0.0:
        return np.zeros(REGISTRATION_SIZE)
    wx, wy, psi = (float(v) / c1 for v in params[2:5])
    if isinstance(contour, StraightContour):
        n = contour.material_normal[:2]
        w = (wx * n[0] + wy * n[1]) * n
        # Turning by beta (counter-clockwise) about the pivot moves the
        # point at arc s by -beta (s - s_pivot) along n1 (material on the
        # right of the tangent): beta = -psi.
        return np.array([w[0], w[1], -psi, 0.0])
    return np.array([wx, wy, 0.0, 0.0])


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
