"""Tests of deburr_drake.math.mesh_registration: the nearest triangle, the
point-to-plane registration of a mesh part (a known move recovered without
noise to 1e-9, a hole's size, a burr touch dropped, touches that pin too
little named) and its covariance against Monte Carlo fits."""

import math

import numpy as np
import pytest
from scipy import stats
import trimesh

from deburr_drake.math.mesh_registration import (
    MeshSurface,
    closest_on_mesh,
    closest_on_triangles,
    pose_amplification,
    register_mesh,
)
from deburr_drake.math.rigid import rpy_matrix

DEG = math.pi / 180.0
XYZ = [0.99, 0.0, 0.47]  # the cross-hole part's origin (conftest.py)


@pytest.fixture(scope="module")
def cross_hole(cross_hole_part):
    return cross_hole_part


def _touch_faces(part, surface, hole, n_hole, n_outer):
    """Faces to touch: ``n_hole`` on the hole's wall at angles spread
    round its axis, ``n_outer`` on the tube's outer face facing up or
    sideways, spread round and along the tube."""
    axis = part.rotation @ [1.0, 0.0, 0.0]  # the hole's, world
    centre = part.to_world([0.0, 0.0, 0.040])
    d = surface.centroid - centre
    depth = d @ axis
    picked = []
    for k in range(n_hole):
        # alternate depths down the hole, angles spread around it
        want = 2 * math.pi * k / n_hole
        radial = d - np.outer(depth, axis)
        angle = np.arctan2(radial[:, 1], radial[:, 0])
        at = 0.025 + 0.003 * (k % 2)  # m along the axis from the bore
        cost = (
            np.abs(np.angle(np.exp(1j * (angle - want))))
            + np.abs(depth - at) / 0.003
        )
        picked.append(int(np.argmin(np.where(hole, cost, np.inf))))
    r = np.linalg.norm(surface.centroid[:, 1:] - [0.0, 0.47], axis=1)
    outer = (np.abs(r - 0.030) < 2e-4) & (surface.normals[:, 2] > -0.2)
    outer &= np.abs(surface.normals[:, 0]) < 0.1
    for k in range(n_outer):
        want_angle = -math.pi / 2 + math.pi * k / max(n_outer - 1, 1)
        want_x = 0.91 + 0.06 * ((k * 3) % n_outer) / n_outer
        c = surface.centroid
        angle = np.arctan2(c[:, 2] - 0.47, c[:, 1])
        cost = np.abs(angle - want_angle) + np.abs(c[:, 0] - want_x) / 0.03
        picked.append(int(np.argmin(np.where(outer, cost, np.inf))))
    return np.array(picked)


def _moved(points, R, t):
    return points @ R.T + t


def test_nearest_point_of_a_triangle():
    """Against the triangle sampled finely: never farther, at most the
    sampling's step nearer."""
    rng = np.random.default_rng(0)
    u, v = np.meshgrid(np.linspace(0, 1, 301), np.linspace(0, 1, 301))
    inside = u + v <= 1.0
    u, v = u[inside], v[inside]
    for _ in range(30):
        a, b, c = rng.standard_normal((3, 3))
        p = 2.0 * rng.standard_normal(3)
        q = closest_on_triangles(p[None], a[None], b[None], c[None])[0, 0]
        samples = a + np.outer(u, b - a) + np.outer(v, c - a)
        sampled = np.min(np.linalg.norm(samples - p, axis=1))
        step = max(np.linalg.norm(b - a), np.linalg.norm(c - a)) / 300
        assert sampled - step <= np.linalg.norm(q - p) <= sampled + 1e-15


def test_closest_on_mesh_searches_every_face(cross_hole):
    part, surface, _ = cross_hole
    rng = np.random.default_rng(0)
    p = part.mesh.bounds[0] + rng.random((40, 3)) * np.ptp(
        part.mesh.bounds, axis=0
    )
    q, j = closest_on_mesh(surface, p)
    every = closest_on_triangles(p, *surface.corners)
    distance = np.min(np.linalg.norm(every - p[:, None, :], axis=2), axis=1)
    np.testing.assert_allclose(
        np.linalg.norm(q - p, axis=1), distance, atol=1e-15
    )
    # the point is on the face it names
    a = surface.corners[0][j]
    np.testing.assert_allclose(
        np.sum(surface.normals[j] * (q - a), axis=1), 0.0, atol=1e-15
    )


def test_a_measured_normal_picks_the_face_touched():
    box = trimesh.creation.box(extents=[0.02, 0.02, 0.02])
    surface = MeshSurface(box.vertices, box.faces)
    # just outside the top face's rim, nearer the side face
    p = np.array([[0.0101, 0.0, 0.0099]])
    _, side = closest_on_mesh(surface, p)
    _, top = closest_on_mesh(surface, p, [[0.0, 0.0, 1.0]])
    np.testing.assert_allclose(surface.normals[side[0]], [1, 0, 0])
    np.testing.assert_allclose(surface.normals[top[0]], [0, 0, 1])
    with pytest.raises(ValueError, match="agrees with no face"):
        closest_on_mesh(surface, p, [[1.0, 1.0, 1.0]])  # 55 deg off all


def _true_move(pivot):
    """1 mm and 1 degree about every axis (about ``pivot``)."""
    R = rpy_matrix([DEG, -DEG, DEG])
    return R, pivot - R @ pivot + np.array([0.001, -0.001, 0.001])


@pytest.mark.parametrize("grown", [0.0, 1e-4])
def test_known_move_and_size_recovered_without_noise(cross_hole, grown):
    part, surface, hole = cross_hole
    faces = _touch_faces(part, surface, hole, 8, 10)
    x = surface.centroid[faces]
    # a hole ``grown`` larger: its wall's faces that much into the material
    x = x - grown * surface.normals[faces] * hole[faces][:, None]
    R, t = _true_move(np.array(XYZ))
    fit = register_mesh(
        surface,
        _moved(x, R, t),
        normals=surface.normals[faces] @ R.T,
        max_residual=5e-5,
        sized_faces=hole,
    )
    assert fit.kept.all()
    np.testing.assert_allclose(fit.rotation, R, atol=1e-9)
    np.testing.assert_allclose(fit.translation, t, atol=1e-9)
    assert fit.size == pytest.approx(grown, abs=1e-9)
    assert fit.rms < 1e-9


def test_a_touch_on_a_burr_is_dropped(cross_hole):
    part, surface, hole = cross_hole
    faces = _touch_faces(part, surface, hole, 5, 7)
    x = surface.centroid[faces]
    x[3] += 2e-4 * surface.normals[faces[3]]  # 0.2 mm early
    R, t = _true_move(np.array(XYZ))
    fit = register_mesh(surface, _moved(x, R, t), max_residual=5e-5)
    assert fit.kept.sum() == len(x) - 1 and not fit.kept[3]
    assert fit.residuals[3] == pytest.approx(2e-4, abs=1e-9)
    np.testing.assert_allclose(fit.rotation, R, atol=1e-9)
    np.testing.assert_allclose(fit.translation, t, atol=1e-9)
    assert fit.size is None


def test_touches_that_pin_too_little_are_named(cross_hole):
    part, surface, hole = cross_hole
    faces = _touch_faces(part, surface, hole, 0, 12)  # the tube's face
    assert (
        pose_amplification(surface.centroid[faces], surface.normals[faces])
        > 1e6
    )
    with pytest.raises(ValueError) as e:
        register_mesh(surface, surface.centroid[faces], max_residual=5e-5)
    message = str(e.value)
    assert "\n" not in message
    # a tube turns about and slides along its axis (world x) unseen
    assert message.endswith(
        ("rotation about x is not pinned", "translation along x is not pinned")
    )


def _noisy_distances(cross_hole, touches, sigma, seed, count, **options):
    """The Mahalanobis distances of ``count`` fits' errors under their
    reported covariance: ``touches`` (on the hole, on the outer face) on
    the cross-hole part moved by 1 mm and 1 degree, noise ``sigma`` (m)
    along their normals; ``options`` to register_mesh."""
    part, surface, hole = cross_hole
    faces = _touch_faces(part, surface, hole, *touches)
    x0 = surface.centroid[faces]
    n0 = surface.normals[faces]
    R, t = _true_move(np.array(XYZ))
    rng = np.random.default_rng(seed)
    d2 = []
    for _ in range(count):
        noisy = x0 + sigma * rng.standard_normal(len(x0))[:, None] * n0
        fit = register_mesh(
            surface, _moved(noisy, R, t), max_residual=10 * sigma, **options
        )
        e = fit.error_of(R, t)
        d2.append(e @ np.linalg.solve(fit.covariance, e))
    return np.array(d2)


@pytest.mark.slow  # 200 fits, about a minute
def test_covariance_matches_monte_carlo(cross_hole):
    """200 fits with the probe's noise along the normal: the Mahalanobis
    distances of their errors under the reported covariance are
    chi-square with 6 degrees of freedom."""
    sigma = 5e-6  # m
    d2 = _noisy_distances(cross_hole, (4, 7), sigma, 7, 200, touch_noise=sigma)
    assert abs(d2.mean() - 6.0) < 1.0  # the mean's sd: sqrt(12 / 200)
    assert stats.kstest(d2, stats.chi2(6).cdf).pvalue > 0.01


@pytest.mark.slow  # 2 x 150 fits, about a minute
def test_a_floor_on_the_touch_error_keeps_the_covariance_honest(cross_hole):
    """Seven touches for six unknowns, the touches' noise estimated from
    the residuals: one degree of freedom, so a small residual by chance
    reports a covariance far too small, and the Mahalanobis distances of
    the errors have a long tail (the probe's 37-38 on the inclined hole).
    With the per-touch error as a floor (``touch_error``, here the
    noise's own size) they are within chi-square with 6 degrees of
    freedom: no more of them past its 99th percentile than it allows."""
    sigma = 2e-5  # m
    far = stats.chi2(6).ppf(0.99)
    bare, floored = (
        _noisy_distances(cross_hole, (3, 4), sigma, 11, 150, touch_error=e)
        for e in (0.0, sigma)
    )
    assert np.mean(bare > far) > 0.1  # the residuals alone: dishonest
    assert np.mean(floored > far) <= 0.03
    assert 3.0 < floored.mean() < 6.5  # at most chi-square's 6
