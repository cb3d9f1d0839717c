"""The job's edges as one contour: the nearest edge answers, arcs are
each edge's own shifted by SPACING, the desired rotation turns from each
edge's start rotation."""

import numpy as np
import pytest

from deburr_drake.math.geometry import CircularContour, StraightContour
from deburr_drake.math.job_contour import SPACING, JobContour


def _rz(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


@pytest.fixture
def job():
    circle = CircularContour([0.0, 0.0, 0.0], 0.01)
    line = StraightContour([0.1, 0.0, 0.0], [0, 1, 0], [1, 0, 0], length=0.05)
    return JobContour([circle, line], [np.eye(3), _rz(0.3)]), circle, line


def test_the_nearest_edge_answers(job):
    contour, circle, line = job
    near_circle = np.array([0.0105, 0.0, 0.0])
    near_line = np.array([0.1002, 0.02, 0.0])
    assert contour.nearest(near_circle) == 0
    assert contour.nearest(near_line) == 1
    np.testing.assert_allclose(
        contour.project(near_line), line.project(near_line)
    )
    assert contour.arc_position(near_line) == pytest.approx(
        SPACING + line.arc_position(near_line)
    )
    n1, tangent, depth, arc = contour.frame(near_circle)
    assert depth == pytest.approx(circle.depth(near_circle))
    assert arc == pytest.approx(circle.arc_position(near_circle))
    np.testing.assert_allclose(contour.n1(near_line), line.n1(near_line))


def test_arcs_name_their_edge(job):
    contour, circle, line = job
    assert contour.edge_of_arc(0.03) == 0
    assert contour.edge_of_arc(SPACING + 0.01) == 1
    np.testing.assert_allclose(
        contour.point_at(SPACING + 0.02), line.point_at(0.02)
    )
    # advancing on the edge the point is on
    p = circle.point_at(0.01)
    np.testing.assert_allclose(
        contour.advance(p, 0.005), circle.point_at(0.015)
    )


def test_unwrapping_counts_laps_on_its_own_edge_only(job):
    contour, circle, _ = job
    p = circle.point_at(0.01)
    lap = circle.length
    assert contour.unwrapped_arc_position(p, lap + 0.009) == pytest.approx(
        lap + 0.01
    )
    # a reference on another edge: from this edge's start
    assert contour.unwrapped_arc_position(p, SPACING) == pytest.approx(0.01)


def test_the_rotation_turns_from_each_edges_start(job):
    contour, _, _ = job
    np.testing.assert_allclose(contour.axis_turn(0.01), np.eye(3), atol=1e-12)
    # R_d = axis_turn(s) R_0 is edge 1's start rotation along edge 1
    np.testing.assert_allclose(
        contour.axis_turn(SPACING + 0.01) @ np.eye(3), _rz(0.3), atol=1e-12
    )
    assert contour.varying_frame and not contour.closed


def test_bad_job_contours_are_refused():
    circle = CircularContour([0.0, 0.0, 0.0], 0.01)
    with pytest.raises(ValueError, match="one edge"):
        JobContour([], [])
    with pytest.raises(ValueError, match="2 start rotations for 1 edges"):
        JobContour([circle], [np.eye(3)] * 2)
    with pytest.raises(ValueError, match="longer than"):
        JobContour([CircularContour([0, 0, 0], 1.0)], [np.eye(3)])
