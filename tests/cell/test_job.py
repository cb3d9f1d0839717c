"""A job planned on the block in front of the 6-joint arm: picked edges
cut in the order listed, the moves between them clear of the part, an
edge that cannot be cut refused in one line naming it."""

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
  edges: [{{near: [-0.03, 0.015, 0.0]}}, {{near: [0.045, 0.0, 0.0]}},
          {{near: [0.011, 0.028, 0.0]}}, {{near: [-0.034, -0.028, 0.0]}}]
  order: listed
"""


@pytest.fixture(scope="module")
def plan():
    return plan_job(load_scenario("paper_6dof", text=JOB))


def test_the_picked_edges_are_cut_in_order_with_moves_between(plan):
    # the bore, the slot, the hole 15 degrees off the top's normal
    points = [c.point for c in plan.cuts]
    np.testing.assert_allclose(points[0][:2], [-0.04, 0.015], atol=0.011)
    np.testing.assert_allclose(points[1][:2], [0.005, 0.022], atol=0.025)
    np.testing.assert_allclose(points[2][:2], [-0.04, -0.028], atol=0.007)
    assert plan.cuts[0].move is None
    assert len(plan.moves()) == 2
    for move in plan.moves():
        assert move.min_clearance_m > 0.0
        assert move.duration_s > 0.0 and move.travel_m > 0.04
    assert plan.skipped == []


def test_the_chamfer_is_refused_naming_the_edge_and_the_tilt(plan):
    (index, line) = plan.refused[0]
    assert len(plan.refused) == 1
    assert line.startswith(f"edge {index}: ")
    assert "tilt" in line and "\n" not in line


def test_tilted_as_told_the_chamfers_approach_meets_the_spindle():
    """The tilt the refusal names, given to the chamfer's pick: the cut's
    path is made, and the move down to it is refused naming the spindle."""
    text = JOB.replace(
        "{near: [0.045, 0.0, 0.0]}", "{near: [0.045, 0.0, 0.0], tilt: -0.7854}"
    )
    plan = plan_job(load_scenario("paper_6dof", text=text))
    (index, line) = plan.refused[0]
    assert len(plan.refused) == 1 and len(plan.cuts) == 3
    assert line.startswith(f"move from edge {plan.cuts[0].index} to edge ")
    assert "approach: the spindle enters the part" in line
