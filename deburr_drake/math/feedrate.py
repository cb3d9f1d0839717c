"""The outer loop's feedrate law (Hsu & Fu 2000, before eq. (5)), the feed
it settles at in steady cutting and its slope: pure numpy, on scalars or
arrays.

Use: ``law = FeedrateLaw(desired_force=..., threshold_force=...,
force_offset=..., default_feed=..., max_feed=...)``, then
``law(tangential_speed, chamfering_force, last_feed)`` per sample or on
logged arrays, ``law.steady_feed(cutting_damping(k_c, area))`` and
``law.slope``."""

from __future__ import annotations

from dataclasses import dataclass
import math

import numpy as np

__all__ = ["FeedrateLaw", "cutting_damping"]


def cutting_damping(cutting_coefficient, chamfer_area, burr_area=0.0):
    """g of eq. (3) (N s/m): ``cutting_coefficient`` k_c (N s/m^3, times
    the edge's removal scale where it curves) times the cross-section cut,
    the chamfer's (m^2, delta x cut height on a planar edge) plus the
    burr's (m^2). Scalars or arrays."""
    return cutting_coefficient * (chamfer_area + burr_area)


@dataclass(frozen=True)
class FeedrateLaw:
    """The feed speed v (m/s) of the outer-loop law before eq. (5):

        v = s (||f_td|| - P'_th) / (||f_t|| - P'_th)
            if ||f_t|| - P'_th > v_eps, else v0,

    at most ``max_feed`` (the paper is silent; CommandConfig.max_feed says
    why). The speed s it scales is the tool's tangential speed |n2^T
    xdot_p| (the paper's law) or, ``integrating``, the last commanded feed
    v_k, so the law integrates the force error (CommandConfig.feed_law)."""

    desired_force: float  # N, ||f_td||
    threshold_force: float  # N, P'_th
    force_offset: float  # N, v_eps
    default_feed: float  # m/s, v0
    max_feed: float = math.inf  # m/s
    integrating: bool = False

    def __call__(self, tangential_speed, chamfering_force, last_feed=None):
        """v (m/s) from the tangential speed n2^T xdot_p (m/s, either
        sign; read only by the paper's law), ||f_t|| (N) and the last
        commanded feed (m/s; read only when ``integrating``): floats give a
        float, numpy arrays an array."""
        speed = last_feed if self.integrating else tangential_speed
        excess = chamfering_force - self.threshold_force
        # The command generator's per-sample call: plain float arithmetic,
        # no array round trip (np.float64 is a float too).
        if isinstance(excess, float) and isinstance(speed, float):
            if excess > self.force_offset:
                v = abs(speed) * (self.desired_force - self.threshold_force)
                v /= excess
                return self.max_feed if v > self.max_feed else v
            return self.default_feed
        cutting = np.asarray(excess) > self.force_offset
        v = (
            np.abs(speed)
            * (self.desired_force - self.threshold_force)
            / np.where(cutting, excess, 1.0)
        )
        return np.where(
            cutting, np.minimum(v, self.max_feed), self.default_feed
        )

    def cutting(self, chamfering_force):
        """Whether ||f_t|| (N) takes the law's cutting branch,
        ||f_t|| - P'_th > v_eps (bool or bool array)."""
        return chamfering_force - self.threshold_force > self.force_offset

    def steady_feed(self, cutting_damping, threshold_force=None):
        """The feed (m/s) the law settles at in steady cutting on a cut of
        g = ``cutting_damping`` (N s/m, :func:`cutting_damping`), scalar
        or array; ``threshold_force`` is the process's P'_th (N), what the
        true ||f_t|| carries beyond g v (default: the law's own).

        With ||f_t|| = P'_th + g v (eq. (3) at steady feed, no plunge) the
        law's fixed point v = v (||f_td|| - P'_th) / (||f_t|| - P'_th) is
        ||f_t|| = ||f_td||, v = (||f_td|| - P'_th) / g, whichever speed it
        scales; at most ``max_feed``. Where that force is not on the law's
        cutting branch (||f_td|| minus the law's P'_th within v_eps) or
        nothing is cut (g <= 0) the law runs at v0."""
        p = self.threshold_force if threshold_force is None else threshold_force
        excess = max(self.desired_force - p, 0.0)
        g = np.asarray(cutting_damping, float)
        cutting = (g > 0.0) & self.cutting(self.desired_force)
        v = np.where(
            cutting,
            np.minimum(excess / np.where(cutting, g, 1.0), self.max_feed),
            self.default_feed,
        )
        return float(v) if v.ndim == 0 else v

    @property
    def slope(self) -> float:
        """-d ln v / d ln ||f_t|| at ||f_t|| = ||f_td||, the law's gain
        from a relative force error to a relative feed change:
        ||f_td|| / (||f_td|| - P'_th)."""
        return self.desired_force / (self.desired_force - self.threshold_force)
