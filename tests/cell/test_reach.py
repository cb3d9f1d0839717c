"""The shipped 3-D edge examples on paper_6dof's 6-joint arm: the arm
reaches each edge's start and follows the whole edge (the reach check the
run makes before it starts), with the tool axis where the example says."""

from pathlib import Path

import numpy as np
import pytest

from deburr_drake.cell.edge import make_contour
from deburr_drake.cell.reach import check_part_in_reach
from deburr_drake.config import ConfigError, load_scenario

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.mark.parametrize(
    "name",
    [
        "cross_hole_6dof",
        "inclined_hole_6dof",
        "wedge_6dof",
        "angled_hole_6dof",
        "pipe_hole_6dof",
    ],
)
def test_the_arm_follows_the_example_edge(name):
    """From the posture nearest the seed: no other start is chosen."""
    scenario = load_scenario(str(EXAMPLES / f"{name}.yaml"))
    assert check_part_in_reach(scenario, make_contour(scenario)) is None


def test_no_rule_given_on_holes_off_the_vertical_and_in_a_pipe():
    """Only file, units, near and the pose: the hole's axis, 30 deg off
    vertical leaning towards -y, and vertical."""
    for name, axis in (
        ("angled_hole_6dof", [0.0, -0.5, np.sqrt(0.75)]),
        ("pipe_hole_6dof", [0.0, 0.0, 1.0]),
    ):
        scenario = load_scenario(str(EXAMPLES / f"{name}.yaml"))
        edge = scenario.part.edge
        assert not (edge.tool_rule or edge.tool_face or edge.tilt)
        contour = make_contour(scenario)
        for s in np.linspace(0.0, contour.length, 8, endpoint=False):
            np.testing.assert_allclose(contour.tool_axis_at(s), axis, atol=1e-3)


def test_the_spin_is_free_when_the_seed_fails(capsys):
    """A seed with A4 at 6.05 rad (its limit 6.1): the start posture
    nearest it is not found; the arm follows the cross hole from another
    start, the one with the most joint-limit margin, and says so."""
    scenario = load_scenario(
        str(EXAMPLES / "cross_hole_6dof.yaml"),
        text="robot: {ik_seed: [0.0, 0.45, 0.5, 6.05, 0.6, 0.0]}",
    )
    q0 = check_part_in_reach(scenario, make_contour(scenario))
    assert q0 is not None and abs(q0[3]) < 6.1 - 0.5
    assert "the run starts there" in capsys.readouterr().err


def test_a_singular_start_is_refused_as_singular_not_reach():
    """The angled hole turned so its axis leans towards the arm (-x):
    the wrist meets it only near its straight posture."""
    with pytest.raises(ConfigError) as refused:
        check_part_in_reach(
            load_scenario(
                str(EXAMPLES / "angled_hole_6dof.yaml"),
                text="part: {pose: {rpy: [0, 0, -1.5707963]}}",
            )
        )
    message = str(refused.value)
    assert message.startswith("part.pose = ")
    assert "singular" in message and "reach" not in message


def test_the_wedge_tool_leans_away_from_the_arm():
    """30 deg off vertical, its holder end away from the arm's base (+x):
    leaning the other way straightens the wrist into its singularity."""
    scenario = load_scenario(str(EXAMPLES / "wedge_6dof.yaml"))
    axis = make_contour(scenario).tool_axis_at(0.0)
    assert np.degrees(np.arccos(axis[2])) == pytest.approx(30.0, abs=0.5)
    assert axis[0] > 0.4
