"""A short run on a mesh part that is not where the controller believes
it (examples/tube_stl.yaml, part_error.offset): the plant's part (its
contact band and the cutting process) is moved, the controller follows
the file at part.pose, so the true depth and the depth the controller
sees (and holds) differ by the error along the edge's normal."""

from pathlib import Path

import numpy as np
import pytest

from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.cell.plan import plan_cell
from deburr_drake.config import load_scenario
from deburr_drake.math import metrics
from deburr_drake.runs.simulation import simulate

pytestmark = pytest.mark.slow

TUBE = Path(__file__).resolve().parents[2] / "examples" / "tube_stl.yaml"
OFFSET = [0.0003, 0.0001, 0.0]  # m, believed - real


def test_true_depth_is_the_believed_one_plus_the_error_along_n1():
    scenario = load_scenario(TUBE, text=f"part_error: {{offset: {OFFSET}}}")
    plan = plan_cell(scenario)
    log = simulate(make_deburring_diagram(plan), plan.scenario, duration=3.0)
    ch, pr = log["chamfer"], log["process"]
    assert metrics.first_time(ch["t"], ch["f_n"] > 1.0) < 0.5
    late = metrics.window(ch["t"], 2.0)
    # the real edge is the believed one moved by -offset: its depth at a
    # tool point is the believed depth plus offset . n1
    n1 = plan.belief.n1(plan.start.position)
    gap = pr["delta"][late].ravel() - ch["delta"][late].ravel()
    assert np.mean(gap) == pytest.approx(float(n1 @ OFFSET), abs=2e-5)
    # the controller holds the depth it sees at the desired one, so the
    # cut is off by the error: what localisation has to find
    assert np.mean(ch["delta"][late]) == pytest.approx(
        plan.scenario.task.desired_depth, abs=2e-5
    )
    assert np.mean(pr["delta"][late]) == pytest.approx(
        plan.scenario.task.desired_depth + float(n1 @ OFFSET), abs=2e-5
    )
