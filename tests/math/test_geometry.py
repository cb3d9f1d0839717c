"""Tests of deburr_drake.math.geometry (Sec. II eq. 2, corrections R5, R6)."""

import math

import numpy as np
import pytest

from deburr_drake.math.geometry import (
    CircularContour,
    Contour,
    StraightContour,
    removal_scale,
)

C = np.array([0.5, -0.2, 0.3])
R = 0.05


def circ(**kw):
    return CircularContour(C, R, **kw)


def line(**kw):
    # edge along +x at y = 0.1, z = 0.25; material on the +y side
    return StraightContour(
        [0.2, 0.1, 0.25], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], **kw
    )


def cross2(a, b):
    return a[0] * b[1] - a[1] * b[0]


def polar(rho, th, z=C[2]):
    return np.array([C[0] + rho * math.cos(th), C[1] + rho * math.sin(th), z])


# ----------------------------------------------------------- phi, n1, depth
def test_circle_phi_n1_depth_known_points():
    c = circ()
    p = polar(R + 0.002, 0.7, z=1.0)  # 2 mm into the material, z ignored
    assert c.phi(p) == pytest.approx(-0.002, abs=1e-12)
    assert c.depth(p) == pytest.approx(0.002, abs=1e-12)
    np.testing.assert_allclose(
        c.n1(p), [math.cos(0.7), math.sin(0.7), 0.0], atol=1e-12
    )
    q = polar(R - 0.01, -2.0)  # free side (inside the tube)
    assert c.phi(q) == pytest.approx(0.01, abs=1e-12)
    assert c.depth(q) == pytest.approx(-0.01, abs=1e-12)
    np.testing.assert_allclose(
        c.grad_phi(q), [-math.cos(-2.0), -math.sin(-2.0), 0.0], atol=1e-12
    )
    assert (
        isinstance(c, Contour) and c.closed and c.height == pytest.approx(0.3)
    )
    assert c.length == pytest.approx(2 * math.pi * R)


def test_line_phi_n1_depth_known_points():
    s = line()
    p = np.array([1.0, 0.1005, 7.0])  # 0.5 mm into the material
    assert s.phi(p) == pytest.approx(-0.0005, abs=1e-12)
    assert s.depth(p) == pytest.approx(0.0005, abs=1e-12)
    np.testing.assert_allclose(s.n1(p), [0.0, 1.0, 0.0], atol=1e-12)
    q = np.array([-3.0, 0.05, 0.0])
    assert s.phi(q) == pytest.approx(0.05, abs=1e-12)
    assert (
        not s.closed
        and s.length == math.inf
        and s.height == pytest.approx(0.25)
    )


@pytest.mark.parametrize(
    "contour,p",
    [
        (circ(), polar(R * 1.1, 2.3)),
        (circ(direction=-1), polar(R * 0.7, -0.4)),
        (
            StraightContour([0, 0, 0], [0.6, 0.8, 0], [-0.8, 0.6, 0]),
            np.array([0.3, -0.2, 0.1]),
        ),
    ],
)
def test_n1_unit_orthogonal_to_tangent(contour, p):
    n1, t = contour.n1(p), contour.tangent(p)
    assert np.linalg.norm(n1) == pytest.approx(1.0, abs=1e-12)
    assert np.linalg.norm(t) == pytest.approx(1.0, abs=1e-12)
    assert abs(np.dot(n1, t)) < 1e-12
    assert n1[2] == 0.0 and t[2] == 0.0


@pytest.mark.parametrize(
    "contour,p",
    [(circ(), polar(R + 0.001, 1.1)), (line(), np.array([0.4, 0.1003, 0.25]))],
)
def test_depth_rate_matches_finite_difference(contour, p):
    v = np.array([0.03, -0.02, 0.01])
    h = 1e-6
    fd = (contour.depth(p + h * v) - contour.depth(p - h * v)) / (2 * h)
    assert contour.depth_rate(p, v) == pytest.approx(fd, rel=1e-6, abs=1e-9)
    assert abs(contour.depth_rate(p, v)) > 1e-3  # non-trivial


@pytest.mark.parametrize(
    "contour,p",
    [
        (circ(), polar(R + 0.0005, 1.1)),
        (circ(direction=-1), polar(R * 0.9, -2.5)),
        (line(), np.array([0.4, 0.1003, 0.25])),
    ],
)
def test_n1_rate_matches_finite_difference(contour, p):
    v = np.array([0.03, -0.02, 0.01])
    h = 1e-6
    fd = (contour.n1(p + h * v) - contour.n1(p - h * v)) / (2 * h)
    np.testing.assert_allclose(contour.n1_rate(p, v), fd, atol=1e-8)


def test_n1_rate_on_a_circle_is_speed_over_radius_along_the_tangent():
    # The tool at depth delta moves along the edge at V: n1 turns at V / rho
    # (the reference x* + delta n1 moves (rho / R) V, not V).
    c = circ()
    rho = R + 0.0005
    p = polar(rho, 0.4)
    t = c.tangent(p)
    np.testing.assert_allclose(
        c.n1_rate(p, 0.002 * t), 0.002 / rho * t, atol=1e-15
    )
    np.testing.assert_allclose(c.n1_rate(p, 0.002 * c.n1(p)), 0.0, atol=1e-15)


# ---------------------------------------------------------------- n2 (R5)
def test_n2_is_direction_of_motion_and_falls_back_to_tangent():
    c = circ()
    p = polar(R + 0.0005, 0.0)  # n1 = +x, CCW tangent = +y
    v = np.array([0.004, 0.02, 0.0])  # moving CCW with a small normal part
    np.testing.assert_allclose(c.n2(p, v, 1e-6), [0.0, 1.0, 0.0], atol=1e-12)
    assert (
        np.dot(c.n2(p, v, 1e-6), v) > 0
    )  # same direction as motion, not opposite
    # moving backwards: n2 follows the motion, not the tangent
    np.testing.assert_allclose(c.n2(p, -v, 1e-6), [0.0, -1.0, 0.0], atol=1e-12)
    # 3-D motion: the vertical part (along the wall) does not tip n2 out of
    # the contour's plane; n2 is the edge tangent in the sense of motion
    v3 = np.array([0.01, 0.02, -0.01])
    np.testing.assert_allclose(c.n2(p, v3, 1e-6), [0.0, 1.0, 0.0], atol=1e-12)
    assert c.edge_speed(p, v3) == pytest.approx(0.02)
    # start-up: tangential speed below min_speed -> tangent in traversal
    # direction
    tiny = np.array([0.5, 1e-8, 0.0])  # large normal, tiny tangential part
    np.testing.assert_allclose(c.n2(p, tiny, 1e-6), [0.0, 1.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(
        circ(direction=-1).n2(p, np.zeros(3), 1e-6),
        [0.0, -1.0, 0.0],
        atol=1e-12,
    )
    with pytest.raises(ValueError, match="min_speed"):
        c.n2(p, v, 0.0)


# ---------------------------------------------------------- projection, arc
@pytest.mark.parametrize(
    "contour,p",
    [
        (circ(), polar(R * 1.3, 2.0, z=0.9)),
        (line(), np.array([0.7, 0.13, -1.0])),
    ],
)
def test_project_lands_on_zero_depth_at_height(contour, p):
    q = contour.project(p)
    assert contour.phi(q) == pytest.approx(0.0, abs=1e-12)
    assert q[2] == pytest.approx(contour.height, abs=1e-15)
    # closest point: p - q is along n1 in the plane
    d = (p - q)[:2]
    assert abs(cross2(d, contour.n1(p)[:2])) < 1e-12


def test_circle_project_exact():
    np.testing.assert_allclose(
        circ().project(polar(0.2, math.pi / 3, z=5.0)),
        polar(R, math.pi / 3),
        atol=1e-12,
    )


@pytest.mark.parametrize(
    "contour",
    [
        circ(start_angle=0.4),
        circ(start_angle=-1.0, direction=-1),
        line(),
        StraightContour([1, 2, 3], [0, -1, 0], [1, 0, 0], length=0.5),
    ],
)
def test_arc_position_point_at_round_trip(contour):
    L = contour.length if contour.closed else 0.5
    for s in np.linspace(0.0, 0.999 * L, 7):
        p = contour.point_at(s)
        assert contour.phi(p) == pytest.approx(0.0, abs=1e-12)
        assert contour.arc_position(p) == pytest.approx(s, abs=1e-12)
        # off-contour points at the same arc position
        assert contour.arc_position(p + 0.003 * contour.n1(p)) == pytest.approx(
            s, abs=1e-12
        )


def test_circle_start_point_and_quarter():
    c = circ(start_angle=math.pi / 2)
    np.testing.assert_allclose(
        c.point_at(0.0), polar(R, math.pi / 2), atol=1e-12
    )
    np.testing.assert_allclose(
        c.point_at(c.length / 4), polar(R, math.pi), atol=1e-12
    )  # CCW


def test_line_signed_arc_position_before_start_and_beyond_length():
    s = line(length=0.3)
    assert s.arc_position([0.1, 0.5, 0.0]) == pytest.approx(-0.1, abs=1e-12)
    assert s.arc_position([0.7, 0.5, 0.0]) == pytest.approx(0.5, abs=1e-12)
    np.testing.assert_allclose(s.point_at(0.5), [0.7, 0.1, 0.25], atol=1e-12)


# ---------------------------------------------------------------- advance (R6)
@pytest.mark.parametrize(
    "contour", [circ(start_angle=0.3), circ(direction=-1), line()]
)
def test_advance_moves_exact_arc_and_removes_depth(contour):
    p0 = contour.point_at(0.01)
    p = (
        p0 + 0.0005 * contour.n1(p0) + np.array([0, 0, 0.02])
    )  # 0.5 mm into material, off height
    assert contour.depth(p) == pytest.approx(0.0005, abs=1e-9)
    ds = 0.002
    q = contour.advance(p, ds)
    assert contour.depth(q) == pytest.approx(0.0, abs=1e-12)
    assert q[2] == pytest.approx(contour.height, abs=1e-15)
    assert contour.arc_position(q) - contour.arc_position(p) == pytest.approx(
        ds, abs=1e-12
    )
    if contour.closed:  # chord of an arc of length ds
        assert np.linalg.norm(q - contour.project(p)) == pytest.approx(
            2 * R * math.sin(ds / (2 * R)), abs=1e-12
        )
    else:
        assert np.linalg.norm(q - contour.project(p)) == pytest.approx(
            ds, abs=1e-12
        )
    # repeated advances from depth-carrying points do not accumulate depth
    x = p
    for k in range(20):
        x = contour.advance(x + 0.0005 * contour.n1(x), ds)
        assert contour.depth(x) == pytest.approx(0.0, abs=1e-12)
    assert contour.unwrapped_arc_position(x, 0.01 + 20 * ds) == pytest.approx(
        0.01 + 20 * ds, abs=1e-10
    )
    assert np.allclose(contour.advance(p, 0.0), contour.project(p), atol=1e-12)
    with pytest.raises(ValueError, match="ds"):
        contour.advance(p, -1e-6)


def test_direction_minus_one_runs_clockwise():
    c = circ(direction=-1)
    a, b = c.point_at(0.0), c.point_at(0.01)
    # signed z of (a - C) x (b - C) < 0  <=> clockwise seen from +z
    assert cross2((a - C)[:2], (b - C)[:2]) < 0
    np.testing.assert_allclose(
        c.point_at(c.length / 4), polar(R, -math.pi / 2), atol=1e-12
    )
    np.testing.assert_allclose(
        c.tangent(polar(R, 0.0)), [0.0, -1.0, 0.0], atol=1e-12
    )
    ccw = circ()
    a, b = ccw.point_at(0.0), ccw.point_at(0.01)
    assert cross2((a - C)[:2], (b - C)[:2]) > 0


# ---------------------------------------------------------------- wrap-around
@pytest.mark.parametrize("direction", [1, -1])
def test_closed_wrap_around_and_unwrapped_across_seam(direction):
    c = circ(start_angle=1.0, direction=direction)
    L = c.length
    p = c.point_at(L - 0.001)
    assert c.arc_position(p) == pytest.approx(L - 0.001, abs=1e-12)
    q = c.advance(p, 0.003)  # crosses the seam
    assert c.arc_position(q) == pytest.approx(0.002, abs=1e-12)
    assert 0.0 <= c.arc_position(c.point_at(-1e-17)) < L
    np.testing.assert_allclose(
        c.point_at(L + 0.002), c.point_at(0.002), atol=1e-12
    )
    np.testing.assert_allclose(c.point_at(-0.001), p, atol=1e-12)
    # progress counting: reference just before the seam -> value just past L
    assert c.unwrapped_arc_position(q, L - 0.001) == pytest.approx(
        L + 0.002, abs=1e-12
    )
    assert c.unwrapped_arc_position(q, 5 * L) == pytest.approx(
        5 * L + 0.002, abs=1e-12
    )
    assert c.unwrapped_arc_position(p, 0.0) == pytest.approx(-0.001, abs=1e-12)
    # open contour: unwrapped equals arc_position
    s = line()
    assert s.unwrapped_arc_position([0.5, 0.0, 0.0], 100.0) == pytest.approx(
        0.3, abs=1e-12
    )


# ---------------------------------------------------------------- AutoDiffXd
@pytest.mark.parametrize(
    "contour,p0",
    [
        (circ(direction=-1), polar(R + 0.001, 0.8)),
        (
            StraightContour([0, 0, 0], [0.6, 0.8, 0], [-0.8, 0.6, 0]),
            np.array([0.3, -0.2, 0.1]),
        ),
    ],
)
def test_autodiff_depth_and_n1_derivatives(contour, p0):
    ad = pytest.importorskip("pydrake.autodiffutils")
    p = ad.InitializeAutoDiff(p0).reshape(-1)
    assert p.dtype == object
    d = contour.depth(p)
    np.testing.assert_allclose(d.value(), contour.depth(p0), atol=1e-15)
    # analytic d(depth)/dp = n1 (|grad phi| = 1)
    np.testing.assert_allclose(d.derivatives(), contour.n1(p0), atol=1e-12)
    n1 = contour.n1(p)
    J = ad.ExtractGradient(n1)
    np.testing.assert_allclose(
        ad.ExtractValue(n1).reshape(-1), contour.n1(p0), atol=1e-15
    )
    if isinstance(contour, CircularContour):
        u = contour.n1(p0)
        rho = R + 0.001
        Jx = np.zeros((3, 3))
        Jx[:2, :2] = (np.eye(2) - np.outer(u[:2], u[:2])) / rho  # d(r_hat)/dp
        np.testing.assert_allclose(J, Jx, atol=1e-10)
    else:
        np.testing.assert_allclose(J, np.zeros((3, 3)), atol=1e-15)
    # the other T-generic methods accept AutoDiffXd and agree in value
    v = np.array([0.01, 0.02, 0.0])
    vad = np.array([ad.AutoDiffXd(x) for x in v])
    np.testing.assert_allclose(
        contour.depth_rate(p, vad).value(),
        contour.depth_rate(p0, v),
        atol=1e-15,
    )
    np.testing.assert_allclose(
        ad.ExtractValue(contour.n2(p, vad, 1e-6)).reshape(-1),
        contour.n2(p0, v, 1e-6),
        atol=1e-12,
    )
    np.testing.assert_allclose(
        ad.ExtractValue(contour.tangent(p)).reshape(-1),
        contour.tangent(p0),
        atol=1e-15,
    )
    np.testing.assert_allclose(
        ad.ExtractValue(contour.n2(p, 0 * vad, 1e-6)).reshape(-1),
        contour.tangent(p0),
        atol=1e-15,
    )
    # float-only path methods reduce AutoDiffXd inputs to values
    np.testing.assert_allclose(
        contour.project(p), contour.project(p0), atol=1e-15
    )


# ---------------------------------------------------------------- validation
def test_validation_errors():
    with pytest.raises(ValueError, match="radius"):
        CircularContour(C, 0.0)
    with pytest.raises(ValueError, match="radius"):
        CircularContour(C, -0.1)
    with pytest.raises(ValueError, match="direction"):
        CircularContour(C, R, direction=0)
    with pytest.raises(ValueError, match="center"):
        CircularContour([0.0, 0.0], R)
    with pytest.raises(ValueError, match="centre"):
        circ().n1(np.array([C[0], C[1], 2.0]))
    with pytest.raises(ValueError, match="centre"):
        circ().project(C)
    with pytest.raises(ValueError, match="p must have shape"):
        circ().phi([1.0, 2.0])
    o = [0.0, 0.0, 0.0]
    with pytest.raises(ValueError, match="tangent"):
        StraightContour(o, [1.0 + 1e-6, 0, 0], [0, 1, 0])
    with pytest.raises(ValueError, match="tangent"):
        StraightContour(o, [0.6, 0, 0.8], [0, 1, 0])
    with pytest.raises(ValueError, match="material_normal"):
        StraightContour(o, [1, 0, 0], [0, 0.9, 0])
    with pytest.raises(ValueError, match="material_normal"):
        StraightContour(o, [1, 0, 0], [0, 0, 1])
    with pytest.raises(ValueError, match="orthogonal"):
        StraightContour(o, [1, 0, 0], [0.6, 0.8, 0])
    with pytest.raises(ValueError, match="length"):
        StraightContour(o, [1, 0, 0], [0, 1, 0], length=0.0)
    # within tolerance is accepted
    StraightContour(o, [1.0 + 5e-10, 0, 0], [0, 1, 0])
    with pytest.raises(TypeError):
        Contour()


@pytest.mark.parametrize(
    "contour,p",
    [
        (circ(), polar(R + 0.0004, 2.5, z=0.3)),
        (circ(direction=-1, start_angle=1.0), polar(R - 0.001, -0.7)),
        (line(), np.array([0.7, 0.13, -1.0])),
    ],
)
def test_frame_equals_the_separate_methods(contour, p):
    n1, tangent, depth, arc = contour.frame(p)
    np.testing.assert_allclose(n1, contour.n1(p), atol=1e-15)
    np.testing.assert_allclose(tangent, contour.tangent(p), atol=1e-15)
    assert depth == pytest.approx(contour.depth(p), abs=1e-15)
    assert arc == pytest.approx(contour.arc_position(p), abs=1e-12)


def test_removal_scale_is_the_swept_band_per_metre_of_centre_travel():
    r, d = 0.003, 5e-4
    assert removal_scale(0.0, d, r) == 1.0
    rho = 0.005  # concave: path radius
    band = ((rho + r + d) ** 2 - (rho + r) ** 2) / 2  # per radian
    assert removal_scale(1 / rho, d, r) * d == pytest.approx(band / (rho + d))
    rho = 0.011  # convex (boss corner)
    band = ((rho - r) ** 2 - (rho - r - d) ** 2) / 2
    assert removal_scale(-1 / rho, d, r) * d == pytest.approx(band / (rho - d))
    assert removal_scale(-1 / rho, d, r) < 1 < removal_scale(1 / 0.005, d, r)
