"""Metrics over logged runs: pure numpy functions of arrays (no Drake)."""

from __future__ import annotations

import numpy as np

__all__ = ["window", "exponential_time_constant", "rms", "dead_zone_fraction",
           "mean_speed", "any_nan", "secant_slope"]


def window(t, start=-np.inf, stop=np.inf):
    """Boolean mask of samples with start <= t <= stop."""
    t = np.asarray(t)
    return (t >= start) & (t <= stop)


def rms(x) -> float:
    x = np.asarray(x, float)
    return float(np.sqrt(np.mean(x * x))) if x.size else float("nan")


def exponential_time_constant(t, y, final, *, lower, upper) -> float:
    """Time constant tau of an exponential approach y -> final, from a
    least-squares fit of log|final - y| against t over the samples where
    lower <= |final - y| <= upper (the linear regime near the end)."""
    t, y = np.asarray(t, float), np.asarray(y, float)
    gap = np.abs(final - y)
    use = (gap >= lower) & (gap <= upper)
    if use.sum() < 3:
        raise ValueError(
            f"only {int(use.sum())} samples with {lower} <= |final - y| <= "
            f"{upper}: cannot fit a time constant")
    slope = np.polyfit(t[use], np.log(gap[use]), 1)[0]
    if slope >= 0:
        raise ValueError("the signal does not approach its final value")
    return float(-1.0 / slope)


def secant_slope(x, y, *, lower, upper) -> float:
    """Least-squares slope dy/dx over the samples with lower <= x <= upper."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    use = (x >= lower) & (x <= upper)
    if use.sum() < 3:
        raise ValueError(f"only {int(use.sum())} samples in [{lower}, {upper}]")
    return float(np.polyfit(x[use], y[use], 1)[0])


def dead_zone_fraction(s, half_width) -> float:
    """Fraction of samples with |s| <= half_width."""
    s = np.asarray(s, float)
    return float(np.mean(np.abs(s) <= half_width)) if s.size else float("nan")


def mean_speed(t, position) -> float:
    """Average of d(position)/dt over the samples (end-point difference)."""
    t, position = np.asarray(t, float), np.asarray(position, float)
    if t.size < 2 or t[-1] <= t[0]:
        raise ValueError("need at least two samples spanning time")
    return float((position[-1] - position[0]) / (t[-1] - t[0]))


def any_nan(*arrays) -> bool:
    return any(not np.all(np.isfinite(np.asarray(a, float))) for a in arrays)
