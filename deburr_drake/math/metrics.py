"""Metrics over logged runs: pure numpy functions of arrays (no Drake).

The building blocks of :func:`deburr_drake.runs.pass_metrics.pass_metrics`; use
them on a :class:`~deburr_drake.runs.simulation.RunLog`'s arrays for a metric of
your own, e.g. ``rms(log["chamfer"]["f_t"][window(t, 2.0)] - 10.0)``."""

from __future__ import annotations

import numpy as np

__all__ = [
    "window",
    "exponential_time_constant",
    "rms",
    "dead_zone_fraction",
    "mean_speed",
    "any_nan",
    "secant_slope",
    "high_frequency_power",
    "cell_crossings",
    "surface_roughness",
    "time_by_label",
    "path_length_by_label",
]


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
            f"{upper}: cannot fit a time constant"
        )
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


def first_time(t, condition) -> float:
    """The first time at which ``condition`` holds (nan if never)."""
    t, condition = np.asarray(t, float), np.asarray(condition, bool)
    idx = np.flatnonzero(condition)
    return float(t[idx[0]]) if idx.size else float("nan")


def arc_distance(a, b, length: float, closed: bool):
    """Signed arc distance a - b, wrapped to [-L/2, L/2) on a closed edge."""
    d = np.asarray(a, float) - b
    return (d + length / 2) % length - length / 2 if closed else d


def arc_span_mask(arc, start: float, stop: float, length: float, closed: bool):
    """Bins whose arc lies in the span travelled from ``start`` to ``stop``
    (m, unwrapped; stop >= start). On a closed edge spans of a full length
    or more cover everything."""
    arc = np.asarray(arc, float)
    if stop < start:
        raise ValueError(f"span stop {stop} < start {start}")
    if not closed:
        return (arc >= start) & (arc <= stop)
    if stop - start >= length:
        return np.ones(arc.shape, bool)
    return ((arc - start) % length) <= (stop - start)


def total_variation(x) -> float:
    """Sum over samples and channels of |x[k+1] - x[k]|."""
    x = np.asarray(x, float)
    return float(np.sum(np.abs(np.diff(x, axis=0)))) if len(x) > 1 else 0.0


def high_frequency_power(t, x, cutoff: float) -> float:
    """Mean power (sum over channels, units of x squared) of the part of
    the uniformly sampled signal ``x`` (samples along axis 0, times ``t``)
    above ``cutoff`` Hz, from its one-sided periodogram: the mean square of
    the signal high-passed at ``cutoff``. nan with fewer than 8 samples."""
    x = np.asarray(x, float)
    if x.ndim == 1:
        x = x[:, None]
    if len(x) < 8:
        return float("nan")
    dt = float(np.median(np.diff(t)))
    spectrum = np.fft.rfft(x - x.mean(axis=0), axis=0)
    freq = np.fft.rfftfreq(len(x), dt)
    # Parseval: mean square = sum |X_k|^2 / N^2 with the one-sided bins
    # (except DC and Nyquist) counted twice.
    weight = np.full(freq.shape, 2.0)
    weight[0] = 1.0
    if len(x) % 2 == 0:
        weight[-1] = 1.0
    power = weight[:, None] * np.abs(spectrum) ** 2 / len(x) ** 2
    return float(np.sum(power[freq > cutoff]))


def cell_crossings(s, delta: float) -> int:
    """How often ``s`` (samples along axis 0, one column per axis) moves
    from one zeroth-order B-spline cell [(j - 1/2) Delta, (j + 1/2) Delta)
    to another (R1's half-open indicator), summed over the columns."""
    s = np.asarray(s, float)
    if s.ndim == 1:
        s = s[:, None]
    cells = np.floor(s / delta + 0.5)
    return int(np.count_nonzero(np.diff(cells, axis=0)))


def surface_roughness(
    u, y0_range, s_range, *, n_y0: int = 8, n_s: int = 128
) -> float:
    """How far a control surface u(y0, s) (a callable, N) departs from a
    plane over the region y0_range x s_range: the RMS residual (N) of its
    least-squares fit a + b y0 + c s on an n_y0 x n_s grid. A plane scores
    0; a staircase of steps J (the m = 0 rule base) scores about
    J / sqrt(12); a smooth surface scores what its curvature bends away
    from the plane. Unlike a finite-difference curvature it does not grow
    as the grid is refined when u has jumps. nan on an empty region."""
    (y_lo, y_hi), (s_lo, s_hi) = y0_range, s_range
    if not (
        np.isfinite([y_lo, y_hi, s_lo, s_hi]).all()
        and y_hi >= y_lo
        and s_hi > s_lo
    ):
        return float("nan")
    y0 = np.linspace(y_lo, y_hi, n_y0 if y_hi > y_lo else 1)
    s = np.linspace(s_lo, s_hi, n_s)
    Y, S = np.meshgrid(y0, s, indexing="ij")
    values = np.array([float(u(a, b)) for a, b in zip(Y.ravel(), S.ravel())])
    A = np.column_stack([np.ones(values.size), Y.ravel(), S.ravel()])
    coef, *_ = np.linalg.lstsq(A, values, rcond=None)
    return rms(values - A @ coef)


def time_by_label(t, labels, stop: float) -> dict:
    """{label: s}: how long each label held, each sample's label holding
    from its time to the next sample's (the last one's to ``stop``).
    Samples after ``stop`` count for nothing."""
    t, labels = np.asarray(t, float), np.asarray(labels)
    if t.size == 0:
        return {}
    ends = np.minimum(np.append(t[1:], max(stop, t[-1])), stop)
    held = np.clip(ends - np.minimum(t, stop), 0.0, None)
    return {
        label.item(): float(np.sum(held[labels == label]))
        for label in np.unique(labels)
    }


def path_length_by_label(points, labels) -> dict:
    """{label: length}: the polyline through ``points`` (rows), each
    segment counted for the label of the point it starts at."""
    points, labels = np.asarray(points, float), np.asarray(labels)
    if len(points) < 2:
        return {label.item(): 0.0 for label in np.unique(labels)}
    steps = np.linalg.norm(np.diff(points, axis=0), axis=1)
    starts = labels[:-1]
    return {
        label.item(): float(np.sum(steps[starts == label]))
        for label in np.unique(labels)
    }
