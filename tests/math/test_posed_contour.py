"""Tests of deburr_drake.math.registration.PosedContour: a 3-D edge's
contour moved by a pose registration is the edge of the part at the moved
pose (its points, n1, tool axis and depth), and a zero registration
leaves the contour as it is."""

import math
from pathlib import Path

import numpy as np
import pytest

from deburr_drake.math.edge_contour import EdgeContour, load_edge
from deburr_drake.math.registration import (
    POSE_REGISTRATION_SIZE,
    PosedContour,
    moved_contour,
    registration_size,
)
from deburr_drake.math.rigid import matrix_rotvec, matrix_rpy, rpy_matrix

PARTS = Path(__file__).resolve().parents[2] / "models" / "parts"
# examples/cross_hole_6dof.yaml's part: its pose and the rim
CROSS_HOLE_XYZ = [0.99, 0.0, 0.47]
CROSS_HOLE_RPY = [0.0, -math.pi / 2, 0.0]
NEAR = [0.030, 0.0, 0.048]


def _path(xyz, rpy):
    part, curve, _ = load_edge(
        PARTS / "cross_hole.stl",
        units="mm",
        xyz=xyz,
        rpy=rpy,
        near=NEAR,
        sharp_angle=math.radians(30.0),
    )
    return EdgeContour(
        curve,
        cutter_radius=0.003,
        engagement=0.001,
        rule="right",
        start_near=part.to_world(NEAR),
    )


@pytest.fixture(scope="module")
def believed_and_real():
    """The rim's path on the believed part and on the part moved 1 mm and
    1 degree about every axis, and the move x_real = R x + p."""
    d = math.radians(1.0)
    R_b = rpy_matrix(CROSS_HOLE_RPY)
    R_r = rpy_matrix(CROSS_HOLE_RPY) @ rpy_matrix([d, -d, d])
    p_b = np.array(CROSS_HOLE_XYZ)
    p_r = p_b + [0.001, -0.001, 0.001]
    R = R_r @ R_b.T
    p = p_r - R @ p_b
    believed = _path(CROSS_HOLE_XYZ, CROSS_HOLE_RPY)
    real = _path(list(p_r), list(matrix_rpy(R_r)))
    return believed, real, R, p


def test_the_posed_edge_is_the_edge_of_the_moved_part(believed_and_real):
    believed, real, R, p = believed_and_real
    registration = [*matrix_rotvec(R), *p, 0.0]
    posed = moved_contour(believed, registration)
    assert isinstance(posed, PosedContour)
    assert registration_size(believed) == POSE_REGISTRATION_SIZE == 7
    for s in np.linspace(0.0, believed.length, 37, endpoint=False):
        q = posed.point_at(s)
        # On the real path (within the splines' fit), with its n1 and axis.
        assert abs(real.phi(q)) < 2e-6
        s_real = real.arc_position(q)
        np.testing.assert_allclose(posed.n1(q), real.n1(q), atol=2e-3)
        np.testing.assert_allclose(
            posed.tool_axis_at(s), real.tool_axis_at(s_real), atol=2e-3
        )
        # A point 0.1 mm into the material is that deep on both.
        inside = q + 1e-4 * posed.n1(q)
        assert posed.depth(inside) == pytest.approx(1e-4, abs=1e-9)
        assert real.depth(inside) == pytest.approx(1e-4, abs=3e-6)
        n1, t, depth, arc = posed.frame(inside)
        np.testing.assert_allclose(n1, posed.n1(inside), atol=1e-12)
        assert depth == pytest.approx(1e-4, abs=1e-9) and arc == pytest.approx(
            s, abs=1e-6
        )
    # The tool frame turns with the part: R_start's axis a(0) to R a(s).
    s = 0.3 * believed.length
    a0 = believed.tool_axis_at(0.0)
    np.testing.assert_allclose(
        posed.axis_turn(s) @ a0, R @ believed.tool_axis_at(s), atol=1e-12
    )


def test_a_larger_hole_moves_the_edge_into_the_material(believed_and_real):
    believed = believed_and_real[0]
    posed = moved_contour(believed, [0.0] * 6 + [5e-5])
    for s in np.linspace(0.0, believed.length, 9, endpoint=False):
        q = believed.point_at(s)
        assert posed.depth(q) == pytest.approx(-5e-5, abs=1e-12)
        np.testing.assert_allclose(
            posed.point_at(s), q + 5e-5 * believed.n1(q), atol=1e-12
        )


def test_zero_pose_registration_is_the_same_contour(believed_and_real):
    believed = believed_and_real[0]
    assert moved_contour(believed, np.zeros(7)) is believed
