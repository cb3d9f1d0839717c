"""The shipped 3-D edge examples on paper_6dof's 6-joint arm: the arm
reaches each edge's start and follows the whole edge (the reach check the
run makes before it starts), with the tool axis where the example says."""

from pathlib import Path

import numpy as np
import pytest

from deburr_drake.cell.edge import make_contour
from deburr_drake.cell.reach import check_part_in_reach
from deburr_drake.config import load_scenario

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.mark.parametrize(
    "name", ["cross_hole_6dof", "inclined_hole_6dof", "wedge_6dof"]
)
def test_the_arm_follows_the_example_edge(name):
    scenario = load_scenario(str(EXAMPLES / f"{name}.yaml"))
    check_part_in_reach(scenario, make_contour(scenario))


def test_the_wedge_tool_leans_away_from_the_arm():
    """30 deg off vertical, its holder end away from the arm's base (+x):
    leaning the other way straightens the wrist into its singularity."""
    scenario = load_scenario(str(EXAMPLES / "wedge_6dof.yaml"))
    axis = make_contour(scenario).tool_axis_at(0.0)
    assert np.degrees(np.arccos(axis[2])) == pytest.approx(30.0, abs=0.5)
    assert axis[0] > 0.4
