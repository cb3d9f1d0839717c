"""Tests of deburr_drake.cell.edge on profile edges: the cutter's path at
the cutter tip's height, and the part the controller believes in
(part_error moves, turns and grows the profile)."""

import math

import numpy as np
import pytest

from deburr_drake.cell.edge import (
    believed_contour,
    edge_points,
    make_contour,
    start_position,
)
from deburr_drake.config import load_scenario


def test_pocket_path_is_the_profile_offset_by_the_cutter():
    sc = load_scenario("pocket")
    c = make_contour(sc)
    assert c.height == pytest.approx(0.050 - 0.002)
    # starts mid right side: x = 0.4 + 0.03 - 0.003
    np.testing.assert_allclose(c.point_at(0.0), [0.427, 0.0, 0.048], atol=1e-12)
    # the edge drawn where the chamfer is cut: the wall's face at the top
    np.testing.assert_allclose(
        edge_points(sc, [0.0])[0], [0.43, 0.0, 0.05], atol=1e-12
    )
    assert start_position(sc)[0] == pytest.approx(
        0.427 + sc.simulation.initial_depth
    )


def test_believed_profile_moved_turned_and_grown():
    sc = load_scenario(
        "pocket",
        text="part_error: {offset: [0.001, 0.0, "
        "0.0], yaw: 0.1, radius: 0.0005}",
    )
    real, belief = make_contour(sc), believed_contour(sc)
    # grown by 0.5 mm: 4 lines keep their lengths, the fillets' path radius
    # 5.5 instead of 5 mm
    assert belief.length - real.length == pytest.approx(2 * math.pi * 0.0005)
    # the start turned with the part: at polar angle 0.1 about the moved
    # centre, 27.5 mm out (the right side moved 0.5 mm into the material)
    p = belief.point_at(0.0)
    q = p[:2] - [0.401, 0.0]
    assert math.atan2(q[1], q[0]) == pytest.approx(0.1)
    assert q[0] * math.cos(0.1) + q[1] * math.sin(0.1) == pytest.approx(0.0275)
    boss = load_scenario("boss", text="part_error: {radius: 0.0005}")
    assert believed_contour(boss).length - make_contour(
        boss
    ).length == pytest.approx(2 * math.pi * 0.0005)


def test_the_papers_tube_as_a_mesh_edge_is_the_papers_circle():
    """tube.stl (the paper's bore, mm) at the paper's part.pose.xyz, the
    tool along the top face's normal, the pass started half its loop on
    (the loop starts at polar angle pi): the paper's contour."""
    paper = load_scenario("paper")
    sc = load_scenario(
        "paper",
        text="part: {edge: {kind: mesh, file: tube.stl, units: mm, "
        "near: [0.03, 0.0, 0.05], tool_rule: right, start_fraction: 0.5}, "
        "pose: {xyz: [0.4, 0.0, 0.0]}}",
    )
    mesh, circle = make_contour(sc), make_contour(paper)
    assert mesh.varying_frame and not circle.varying_frame
    assert mesh.length == pytest.approx(circle.length, rel=1e-6)
    arc = np.linspace(0.0, circle.length, 24, endpoint=False)
    for s in arc:
        np.testing.assert_allclose(
            mesh.point_at(s), circle.point_at(s), atol=2e-6
        )
    np.testing.assert_allclose(
        start_position(sc), start_position(paper), atol=2e-6
    )
    np.testing.assert_allclose(
        edge_points(sc, arc), edge_points(paper, arc), atol=2e-6
    )
    believed = believed_contour(sc)
    np.testing.assert_allclose(
        believed.point_at(0.3), mesh.point_at(0.3), atol=0
    )
