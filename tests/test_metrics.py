"""Pure metric functions."""

import numpy as np
import pytest

from deburr_drake import metrics


def test_time_constant_of_an_exponential():
    t = np.linspace(0, 2, 2001)
    y = 5e-4 * (1 - np.exp(-t / 0.25))
    tau = metrics.exponential_time_constant(t, y, 5e-4, lower=1e-5,
                                            upper=1.5e-4)
    assert tau == pytest.approx(0.25, rel=1e-6)
    with pytest.raises(ValueError):
        metrics.exponential_time_constant(t, y, 5e-4, lower=1.0, upper=2.0)


def test_arc_span_mask_wraps_on_a_closed_edge():
    arc = np.array([0.0, 0.5, 0.9, 0.95])
    mask = metrics.arc_span_mask(arc, 0.9, 1.05, 1.0, closed=True)
    np.testing.assert_array_equal(mask, [True, False, True, True])
    assert metrics.arc_span_mask(arc, 0.0, 2.0, 1.0, True).all()
    np.testing.assert_array_equal(
        metrics.arc_span_mask(arc, 0.4, 0.92, 1.0, closed=False),
        [False, True, True, False])


def test_total_variation_rms_and_speed():
    x = np.array([[0.0, 1.0], [1.0, 1.0], [0.0, 3.0]])
    assert metrics.total_variation(x) == pytest.approx(1 + 1 + 2)
    assert metrics.rms([3.0, -4.0]) == pytest.approx(np.sqrt(12.5))
    assert metrics.mean_speed([0, 2], [1.0, 5.0]) == pytest.approx(2.0)
    assert metrics.arc_distance(0.95, 0.05, 1.0, True) == pytest.approx(-0.1)
    assert metrics.first_time([0, 1, 2], [False, True, True]) == 1
    assert metrics.any_nan([1.0, np.nan]) and not metrics.any_nan([1.0])
