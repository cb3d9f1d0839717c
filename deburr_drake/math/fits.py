"""Fits of probed points (pure numpy): a circle (Taubin's algebraic fit
seeding a Gauss-Newton geometric fit, the radius free or known), a straight
edge (total least squares: offset and heading), and residual-based outlier
rejection (a probe point that landed on a burr sits inside the edge by the
burr's height: its residual gives it away).

Use::

    fit = fit_circle(points_xy)                 # CircleFit: centre, radius
    fit = fit_circle(points_xy, radius=0.027)   # the centre only
    fit = fit_line(points_xy)                   # LineFit: point, direction
    fit, kept = fit_rejecting(fit_circle, points_xy, max_residual=1e-4)
    fit, kept = fit_consensus(fit_circle, points_xy, minimal=3,
                              max_residual=5e-5)

Points are (N, 2) arrays in a plane (m). With N touches spread around a
circle and probe noise sigma, the centre is known to about
sigma sqrt(2 / N) per axis.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import combinations
from math import comb
from typing import Callable, Optional

import numpy as np

__all__ = [
    "CircleFit",
    "LineFit",
    "fit_circle",
    "fit_circle_taubin",
    "fit_line",
    "fit_rejecting",
    "fit_consensus",
]


@dataclass
class CircleFit:
    center: np.ndarray  # (2,) m
    radius: float  # m
    residuals: np.ndarray  # (N,) m, |p - c| - R: > 0 outside the circle
    iterations: int = 0

    @property
    def rms(self) -> float:
        return float(np.sqrt(np.mean(self.residuals**2)))

    def residuals_of(self, points) -> np.ndarray:
        """|p - c| - R of any (N, 2) points (m)."""
        return (
            np.linalg.norm(np.asarray(points, float) - self.center, axis=1)
            - self.radius
        )


@dataclass
class LineFit:
    point: np.ndarray  # (2,) m, the centroid of the points
    direction: np.ndarray  # (2,) unit, the sense of the points' order
    residuals: np.ndarray  # (N,) m, signed distance, left of direction > 0

    @property
    def heading(self) -> float:
        """rad, of ``direction`` from the x axis."""
        return float(np.arctan2(self.direction[1], self.direction[0]))

    @property
    def rms(self) -> float:
        return float(np.sqrt(np.mean(self.residuals**2)))

    def residuals_of(self, points) -> np.ndarray:
        """Signed distances of any (N, 2) points (m), left > 0."""
        normal = np.array([-self.direction[1], self.direction[0]])
        return (np.asarray(points, float) - self.point) @ normal


def _points(points, minimum: int) -> np.ndarray:
    p = np.asarray(points, float)
    if p.ndim != 2 or p.shape[1] != 2 or not np.all(np.isfinite(p)):
        raise ValueError(
            f"points must be a finite (N, 2) array, got shape {p.shape}"
        )
    if len(p) < minimum:
        raise ValueError(f"need at least {minimum} points, got {len(p)}")
    return p


def fit_circle_taubin(points) -> CircleFit:
    """Taubin's algebraic circle fit (Chernov's Newton form): unbiased to
    first order, the usual seed of a geometric fit. At least 3 points."""
    p = _points(points, 3)
    mean = p.mean(axis=0)
    x, y = (p - mean).T
    z = x * x + y * y
    zm = z.mean()
    z0 = (z - zm) / (2.0 * np.sqrt(zm))
    # SVD of [z0, x, y]: the smallest singular vector of the centred,
    # normalized system (Taubin's constraint), as in Chernov (2010).
    _, _, vt = np.linalg.svd(np.column_stack([z0, x, y]), full_matrices=False)
    a = vt[-1]
    a0 = a[0] / (2.0 * np.sqrt(zm))
    a3 = -zm * a0
    # A (x^2 + y^2) + B x + C y + D = 0.
    center = -np.array([a[1], a[2]]) / (2.0 * a0) + mean
    radius = float(
        np.sqrt(a[1] ** 2 + a[2] ** 2 - 4 * a0 * a3) / (2.0 * abs(a0))
    )
    residuals = np.linalg.norm(p - center, axis=1) - radius
    return CircleFit(center=center, radius=radius, residuals=residuals)


def fit_circle(
    points,
    *,
    radius: Optional[float] = None,
    seed: Optional[np.ndarray] = None,
    iterations: int = 50,
    tolerance: float = 1e-12,
) -> CircleFit:
    """Geometric circle fit: min sum (|p_i - c| - R)^2 by Gauss-Newton,
    seeded by :func:`fit_circle_taubin` (or ``seed``, a centre). With
    ``radius`` given the radius is held and only the centre is fitted
    (at least 2 points; 3 without it)."""
    p = _points(points, 3 if radius is None else 2)
    if seed is not None:
        c = np.asarray(seed, float).copy()
        r = (
            float(np.mean(np.linalg.norm(p - c, axis=1)))
            if radius is None
            else float(radius)
        )
    elif len(p) >= 3:
        start = fit_circle_taubin(p)
        c, r = start.center.copy(), start.radius
    else:
        c = p.mean(axis=0)
        r = float(radius)
    if radius is not None:
        r = float(radius)
    k = 0
    for k in range(1, iterations + 1):
        d = p - c
        rho = np.linalg.norm(d, axis=1)
        if np.any(rho == 0.0):
            raise ValueError("a point lies on the circle's centre")
        u = d / rho[:, None]
        res = rho - r
        # d res / d c = -u; d res / d R = -1.
        J = (
            -u
            if radius is not None
            else np.column_stack([-u, -np.ones(len(p))])
        )
        step, *_ = np.linalg.lstsq(J, -res, rcond=None)
        c = c + step[:2]
        if radius is None:
            r = r + step[2]
        if np.linalg.norm(step) < tolerance:
            break
    residuals = np.linalg.norm(p - c, axis=1) - r
    return CircleFit(
        center=c, radius=float(r), residuals=residuals, iterations=k
    )


def fit_line(points, *, heading: Optional[float] = None) -> LineFit:
    """Total-least-squares line (at least 2 points; 1 with ``heading``
    given, rad, then only the offset is fitted). The direction points from
    the first point towards the last."""
    p = _points(points, 2 if heading is None else 1)
    mean = p.mean(axis=0)
    if heading is None:
        _, _, vt = np.linalg.svd(p - mean, full_matrices=False)
        direction = vt[0]
        if direction @ (p[-1] - p[0]) < 0:
            direction = -direction
    else:
        direction = np.array([np.cos(heading), np.sin(heading)])
    normal = np.array([-direction[1], direction[0]])
    residuals = (p - mean) @ normal
    return LineFit(point=mean, direction=direction, residuals=residuals)


def fit_rejecting(
    fit: Callable, points, *, max_residual: float, minimum: int, **kwargs
):
    """(fit, kept) of ``fit(points[kept], **kwargs)`` after dropping, one
    at a time, the point of largest |residual| while it exceeds
    ``max_residual`` (m) and more than ``minimum`` points remain. ``kept``
    is a boolean mask over ``points``."""
    p = np.asarray(points, float)
    kept = np.ones(len(p), bool)
    result = fit(p[kept], **kwargs)
    while kept.sum() > minimum:
        worst = int(np.argmax(np.abs(result.residuals)))
        if abs(result.residuals[worst]) <= max_residual:
            break
        kept[np.flatnonzero(kept)[worst]] = False
        result = fit(p[kept], **kwargs)
    return result, kept


#: Subsets tried by :func:`fit_consensus` at most (all of them when there
#: are no more; else this many, drawn with a fixed seed).
CONSENSUS_SUBSETS = 2000


def fit_consensus(
    fit: Callable,
    points,
    *,
    minimal: int,
    max_residual: float,
    minimum: Optional[int] = None,
    **kwargs,
):
    """(fit, kept): the fit of the largest set of points that agree with
    one another within ``max_residual`` (m), found from the exact fits of
    every ``minimal``-point subset (random sample consensus, exhaustive
    for the few points of a probe: 56 subsets for 8 points and a circle),
    then refitted to its inliers until the set settles. Unlike
    :func:`fit_rejecting`, an outlier cannot pull the first fit towards
    itself: two burr touches 0.15 mm early among eight left the
    one-at-a-time rejection 30 um off the centre, this exactly on it.
    Ties go to the smaller inlier RMS. With fewer than ``minimum``
    (default ``minimal + 1``) agreeing points, :func:`fit_rejecting`
    decides."""
    p = np.asarray(points, float)
    minimum = minimal + 1 if minimum is None else minimum
    if len(p) <= minimal:
        return fit(p, **kwargs), np.ones(len(p), bool)
    if comb(len(p), minimal) <= CONSENSUS_SUBSETS:
        subsets = combinations(range(len(p)), minimal)
    else:
        rng = np.random.default_rng(0)
        subsets = (
            rng.choice(len(p), minimal, replace=False)
            for _ in range(CONSENSUS_SUBSETS)
        )
    best, best_key = None, None
    for subset in subsets:
        try:
            trial = fit(p[list(subset)], **kwargs)
        except (ValueError, np.linalg.LinAlgError):
            continue  # e.g. collinear points: no circle
        res = np.abs(trial.residuals_of(p))
        if not np.all(np.isfinite(res)):
            continue
        inliers = res <= max_residual
        key = (
            int(inliers.sum()),
            -float(np.sqrt(np.mean(res[inliers] ** 2)))
            if inliers.any()
            else 0.0,
        )
        if best_key is None or key > best_key:
            best, best_key = inliers, key
    if best is None or best.sum() < minimum:
        return fit_rejecting(
            fit, p, max_residual=max_residual, minimum=minimum, **kwargs
        )
    kept = best
    result = fit(p[kept], **kwargs)
    for _ in range(10):
        now = np.abs(result.residuals_of(p)) <= max_residual
        if now.sum() < minimum or np.array_equal(now, kept):
            break
        kept = now
        result = fit(p[kept], **kwargs)
    return result, kept
