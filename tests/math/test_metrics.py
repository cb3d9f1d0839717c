"""Pure metric functions."""

import numpy as np
import pytest

from deburr_drake.math import metrics


def test_time_constant_of_an_exponential():
    t = np.linspace(0, 2, 2001)
    y = 5e-4 * (1 - np.exp(-t / 0.25))
    tau = metrics.exponential_time_constant(
        t, y, 5e-4, lower=1e-5, upper=1.5e-4
    )
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
        [False, True, True, False],
    )


def test_total_variation_rms_and_speed():
    x = np.array([[0.0, 1.0], [1.0, 1.0], [0.0, 3.0]])
    assert metrics.total_variation(x) == pytest.approx(1 + 1 + 2)
    assert metrics.rms([3.0, -4.0]) == pytest.approx(np.sqrt(12.5))
    assert metrics.mean_speed([0, 2], [1.0, 5.0]) == pytest.approx(2.0)
    assert metrics.arc_distance(0.95, 0.05, 1.0, True) == pytest.approx(-0.1)
    assert metrics.first_time([0, 1, 2], [False, True, True]) == 1
    assert metrics.any_nan([1.0, np.nan]) and not metrics.any_nan([1.0])


def test_surface_roughness_of_a_plane_a_staircase_and_a_parabola():
    from deburr_drake.math.metrics import surface_roughness

    plane = surface_roughness(
        lambda y, s: 2.0 + 3.0 * y - 5.0 * s, (0.3, 0.5), (-1.0, 1.0)
    )
    assert plane == pytest.approx(0.0, abs=1e-12)
    # Steps of 1 every 0.1 over [-1, 1): about 1 / sqrt(12).
    stairs = surface_roughness(
        lambda y, s: np.floor(s / 0.1), (0.3, 0.5), (-1.0, 1.0), n_s=2000
    )
    assert stairs == pytest.approx(1 / np.sqrt(12), rel=0.02)
    # s^2 on [-1, 1]: residual s^2 - 1/3, RMS sqrt(1/5 - 1/9).
    parabola = surface_roughness(
        lambda y, s: s * s, (0.4, 0.4), (-1.0, 1.0), n_s=4001
    )
    assert parabola == pytest.approx(np.sqrt(1 / 5 - 1 / 9), rel=1e-3)
    assert np.isnan(surface_roughness(lambda y, s: s, (0.4, 0.4), (0.1, 0.1)))


def test_the_second_order_surface_is_smoother_than_the_zeroth():
    """The same rule weights (a ramp in s) under m = 0 and m = 2: the
    zeroth-order surface is a staircase, the second-order one nearly the
    plane through it."""
    from deburr_drake.math.fuzzy import RuleBase
    from deburr_drake.math.metrics import surface_roughness

    rough = {}
    for m in (0, 2):
        rb = RuleBase(m=m, upsilon=5, delta0=0.2, deltak=0.004)
        theta = np.tile(np.arange(-5, 6, dtype=float), 11)  # theta_ij = j
        rough[m] = surface_roughness(
            lambda y, s: rb.evaluate(theta, y, s), (0.4, 0.45), (-0.012, 0.012)
        )
    assert rough[0] == pytest.approx(1 / np.sqrt(12), rel=0.1)
    assert rough[2] < 0.2 * rough[0]


def test_time_by_label_holds_each_sample_to_the_next():
    t = np.array([0.0, 1.0, 1.5, 4.0, 6.0])
    labels = np.array([2, 2, 0, 1, 0])
    # 0: 1.5 -> 4.0 and 6.0 -> 7.0; the sample at 8.0 lies past the stop
    held = metrics.time_by_label(np.r_[t, 8.0], np.r_[labels, 1], 7.0)
    assert held == pytest.approx({0: 3.5, 1: 2.0, 2: 1.5})
    assert sum(held.values()) == pytest.approx(7.0)
    assert metrics.time_by_label([], [], 1.0) == {}


def test_path_length_by_label_counts_a_segment_for_its_start():
    points = np.array([[0, 0, 0], [3, 4, 0], [3, 4, 1], [3, 4, 3.0]])
    lengths = metrics.path_length_by_label(points, ["a", "b", "a", "b"])
    assert lengths == pytest.approx({"a": 5.0 + 2.0, "b": 1.0})
    assert metrics.path_length_by_label(points[:1], ["a"]) == {"a": 0.0}
