"""A job planned on the block in front of the 6-joint arm: picked edges
cut in the order listed, the moves between them clear of the part, the
chamfer's 120-degree edge cut by the default rule's tilt."""

import math
from pathlib import Path

import numpy as np
import pytest

from deburr_drake.cell.job import plan_job
from deburr_drake.config import load_scenario

BLOCK = Path(__file__).resolve().parents[2] / "models" / "parts" / "block.stl"

JOB = f"""
job:
  file: {BLOCK}
  units: mm
  pose: {{xyz: [0.95, 0.0, 0.50], rpy: [0.0, 0.0, 0.0]}}
  edges: [{{near: [-0.03, 0.015, 0.0]}}, {{near: [0.0, 0.032, 0.0]}},
          {{near: [0.011, 0.028, 0.0]}}, {{near: [-0.034, -0.028, 0.0]}}]
  order: listed
"""


@pytest.fixture(scope="module")
def plan():
    return plan_job(load_scenario("paper_6dof", text=JOB))


def test_the_picked_edges_are_cut_in_order_with_moves_between(plan):
    # the bore, the chamfer, the slot, the hole 15 degrees off the normal
    points = [c.point for c in plan.cuts]
    np.testing.assert_allclose(points[0][:2], [-0.04, 0.015], atol=0.011)
    np.testing.assert_allclose(points[1][1], 0.032, atol=1e-9)
    np.testing.assert_allclose(points[2][:2], [0.005, 0.022], atol=0.025)
    np.testing.assert_allclose(points[3][:2], [-0.04, -0.028], atol=0.007)
    assert plan.cuts[0].move is None
    assert len(plan.moves()) == 3
    for move in plan.moves():
        assert move.min_clearance_m > 0.0
        assert move.duration_s > 0.0 and move.travel_m > 0.04
    assert plan.skipped == [] and plan.refused == []


def test_the_chamfer_is_cut_tilted_off_the_top_by_the_least_clear_turn(plan):
    """The faces meet at 120 degrees: the tool stands on the top, turned
    30 degrees about the edge so the cutter's side lies along the chamfer
    face, leaning over the top (the side away from the chamfer)."""
    chamfer = plan.cuts[1].contour
    for s in (0.0, 0.5 * chamfer.length, chamfer.length):
        np.testing.assert_allclose(
            chamfer.tool_axis_at(s), [0.0, -0.5, math.sqrt(0.75)], atol=1e-6
        )


@pytest.mark.parametrize("angle", [120.0, 135.0])
def test_a_roof_edge_is_cut_up_to_where_the_spindle_meets_the_top(
    angle, roof_stl, tmp_path
):
    """A roof-like prism turned so the tool leans away from the arm: at
    120 degrees the default's 30-degree turn cuts the edge, the arm and
    spindle clear of the part along it; at 135 degrees the 45-degree turn
    lays arm6's spindle (30 mm round the axis from 24 mm up) into the top,
    and the refusal names the spindle, how deep, and the tilt."""
    path = roof_stl(angle, tmp_path / "roof.stl")
    job = f"""
job:
  file: {path}
  units: mm
  pose: {{xyz: [0.99, 0.03, 0.48], rpy: [0.0, 0.0, {math.pi}]}}
  edges: [{{near: [0.04, 0.03, 0.02]}}]
"""
    plan = plan_job(load_scenario("paper_6dof", text=job))
    if angle == 120.0:
        assert plan.refused == [] and len(plan.cuts) == 1
        (cut,) = plan.cuts
        np.testing.assert_allclose(
            cut.contour.tool_axis_at(0.0),
            [0.5, 0.0, math.sqrt(0.75)],
            atol=1e-6,
        )
        assert cut.min_clearance_m > 0.0
        assert len(cut.postures) == len(cut.arcs) >= 15
        np.testing.assert_array_equal(cut.end[2], cut.postures[-1])
    else:
        assert plan.cuts == []
        ((index, line),) = plan.refused
        assert line.startswith(f"edge {index}: at arc ")
        assert "the spindle stands" in line and "135.0 deg" in line
        assert "tilt 0.785398 rad" in line or "tilt -0.785398 rad" in line
