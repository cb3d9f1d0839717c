"""plan_cell: a scenario resolved once (gains, edges, model, start, the
contact truth on first use), the diagram built from it, and one Diagram
per ``simulate`` run, its pre-flight included."""

from pathlib import Path

import numpy as np
import pytest

from deburr_drake.cell.counts import DIAGRAMS, counts
from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.cell.gains import design_gains
from deburr_drake.cell.plan import CellPlan, plan_cell
from deburr_drake.cli import main
from deburr_drake.config import load_scenario

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


@pytest.fixture(scope="module")
def paper():
    return load_scenario("paper")


@pytest.fixture(scope="module")
def plan(paper):
    return plan_cell(paper)


def test_the_plan_holds_what_the_diagram_is_built_from(paper, plan):
    assert isinstance(plan, CellPlan)
    assert plan.source is paper and plan.design is None
    assert plan.scenario.controller.fuzzy.max_slope > 0  # resolved
    assert paper.controller.fuzzy.max_slope == 0  # the caller's as it was
    plant_q = plan.start.q
    assert plant_q.shape == (plan.model.num_positions(),)
    np.testing.assert_allclose(
        plan.belief.point_at(0.0)
        + paper.simulation.initial_depth
        * plan.belief.n1(plan.belief.point_at(0.0)),
        plan.start.position,
    )
    # The contact truth: computed once, kept.
    assert plan.contact_truth() is plan.contact_truth()


def test_one_build_per_call_and_the_plan_is_required(paper, plan):
    n = counts()[DIAGRAMS]
    diagram = make_deburring_diagram(plan)
    assert counts()[DIAGRAMS] == n + 1
    plant = diagram.GetSubsystemByName("plant")
    np.testing.assert_array_equal(plant.GetDefaultPositions(), plan.start.q)
    with pytest.raises(TypeError, match="plan_cell"):
        make_deburring_diagram(paper)
    with pytest.raises(TypeError, match="not both"):
        make_deburring_diagram(plan, scenario=paper)


def test_designed_gains_are_the_start_pose_s():
    """controller.design auto: the gains designed at the pose the run
    starts from (a 3-D edge: the tool along its axis there)."""
    scenario = load_scenario(EXAMPLES / "cross_hole_6dof.yaml")
    plan = plan_cell(scenario)
    assert plan.design is not None
    expected = design_gains(scenario, plan.start.q)
    assert plan.design.as_fields() == expected.as_fields()
    assert plan.scenario.controller.design == "written"


def test_simulate_builds_one_diagram(tmp_path):
    n = counts()[DIAGRAMS]
    out = tmp_path / "out"
    args = ["simulate", "--duration", "0.01", "--out", str(out)]
    assert main(args) == 0
    assert counts()[DIAGRAMS] == n + 1
    assert (out / "preflight.json").exists()
