"""simulate: collects every logger of the diagram, extra_logs included."""

import numpy as np
import pytest

from deburr_drake.cell.diagram import LOGGED, make_deburring_diagram
from deburr_drake.config import load_scenario
from deburr_drake.runs.simulation import logger_names, simulate


def test_extra_logs_come_back_by_name():
    scenario = load_scenario("point_mass")
    diagram = make_deburring_diagram(
        scenario=scenario,
        extra_logs={"feed": ("command_generator", "feed"),
                    "state": ("plant", "state")})
    assert set(logger_names(diagram)) == set(LOGGED) | {"feed", "state"}
    log = simulate(diagram, scenario, duration=0.05)
    period = scenario.simulation.log_period
    assert log["feed"]["value"].shape == (len(log["feed"]["t"]), 1)
    np.testing.assert_allclose(np.diff(log["feed"]["t"]), period)
    assert log["state"]["value"].shape[1] == 6  # q, v of the Cartesian tool
    np.testing.assert_array_equal(log["feed"]["t"], log["chamfer"]["t"])


def test_an_extra_log_may_not_replace_a_standard_one():
    scenario = load_scenario("point_mass")
    with pytest.raises(ValueError, match="'chamfer' is logged already"):
        make_deburring_diagram(scenario=scenario, extra_logs={
            "chamfer": ("command_generator", "feed")})
