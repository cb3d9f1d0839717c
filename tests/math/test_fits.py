"""Circle and line fits on synthetic points with a known answer."""

import numpy as np
import pytest

from deburr_drake.math.fits import (
    fit_circle,
    fit_circle_taubin,
    fit_line,
    fit_rejecting,
)


def _circle(center, radius, angles):
    return np.asarray(center) + radius * np.column_stack(
        [np.cos(angles), np.sin(angles)]
    )


def test_exact_circle_recovered_by_both_fits():
    pts = _circle(
        [0.4003, -0.0007], 0.027, np.linspace(0, 2 * np.pi, 7, endpoint=False)
    )
    for fit in (fit_circle_taubin(pts), fit_circle(pts)):
        np.testing.assert_allclose(fit.center, [0.4003, -0.0007], atol=1e-12)
        assert fit.radius == pytest.approx(0.027, abs=1e-12)
        assert fit.rms < 1e-12


def test_partial_arc_geometric_fit_beats_noise_bound():
    rng = np.random.default_rng(3)
    sigma, n = 10e-6, 8
    errors = []
    for _ in range(200):
        angles = np.linspace(0, 2 * np.pi, n, endpoint=False)
        pts = _circle([0.0, 0.0], 0.030, angles)
        pts += sigma * rng.standard_normal(pts.shape)
        errors.append(fit_circle(pts, radius=0.030).center)
    # sigma sqrt(2 / N) per axis (the fit's standard error) within 20 %.
    assert np.std(np.array(errors), axis=0) == pytest.approx(
        sigma * np.sqrt(2 / n), rel=0.2
    )


def test_known_radius_on_a_short_arc():
    angles = np.radians([10, 30, 50, 70])
    pts = _circle([1.0, 2.0], 0.05, angles)
    fit = fit_circle(pts, radius=0.05, seed=[1.001, 2.001])
    np.testing.assert_allclose(fit.center, [1.0, 2.0], atol=1e-10)


def test_line_offset_and_heading():
    heading = np.radians(20.0)
    d = np.array([np.cos(heading), np.sin(heading)])
    nrm = np.array([-d[1], d[0]])
    s = np.linspace(0, 0.05, 6)
    pts = np.array([0.3, 0.1]) + s[:, None] * d + 2e-4 * nrm
    fit = fit_line(pts)
    assert fit.heading == pytest.approx(heading, abs=1e-12)
    # The line passes 0.2 mm to the left of (0.3, 0.1).
    assert (np.array([0.3, 0.1]) - fit.point) @ nrm == pytest.approx(
        -2e-4, abs=1e-12
    )
    held = fit_line(pts, heading=heading)
    np.testing.assert_allclose(held.residuals, 0.0, atol=1e-12)


def test_burr_under_a_probe_point_is_rejected():
    rng = np.random.default_rng(5)
    angles = np.linspace(0, 2 * np.pi, 8, endpoint=False)
    pts = _circle([0.4, 0.0], 0.027, angles)
    pts += 5e-6 * rng.standard_normal(pts.shape)
    # A 1 mm burr: that probe touches 1 mm early (inside the circle).
    pts[3] = _circle([0.4, 0.0], 0.027 - 0.001, angles[3:4])[0]
    plain = fit_circle(pts)
    assert np.linalg.norm(plain.center - [0.4, 0.0]) > 1e-4
    fit, kept = fit_rejecting(fit_circle, pts, max_residual=1e-4, minimum=3)
    assert list(np.flatnonzero(~kept)) == [3]
    assert np.linalg.norm(fit.center - [0.4, 0.0]) < 2e-5
    assert fit.radius == pytest.approx(0.027, abs=2e-5)


def test_line_burr_rejected_and_clean_points_kept():
    pts = np.column_stack([np.linspace(0, 0.04, 6), np.zeros(6)])
    pts[2, 1] = 8e-4
    fit, kept = fit_rejecting(fit_line, pts, max_residual=1e-4, minimum=2)
    assert list(np.flatnonzero(~kept)) == [2]
    assert fit.heading == pytest.approx(0.0, abs=1e-12)
    clean, kept = fit_rejecting(
        fit_line, np.delete(pts, 2, axis=0), max_residual=1e-4, minimum=2
    )
    assert kept.all()


def test_bad_points_raise():
    with pytest.raises(ValueError, match="at least 3"):
        fit_circle([[0, 0], [1, 0]])
    with pytest.raises(ValueError, match="finite"):
        fit_line([[0, 0], [np.nan, 1]])
