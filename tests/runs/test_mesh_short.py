"""A short run of the paper's cell on its tube read from an STL file
(examples/tube_stl.yaml: a mesh edge, its contact band, the tool axis
from the top face): contact is established and the chamfer depth and
normal force converge as on the paper's ring (test_paper_short.py). The
full pass is ``deburr-drake simulate`` (minutes), not a test."""

from pathlib import Path

import numpy as np
import pytest

from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.config import load_scenario
from deburr_drake.math import metrics
from deburr_drake.runs.simulation import simulate

pytestmark = pytest.mark.slow

TUBE = Path(__file__).resolve().parents[2] / "examples" / "tube_stl.yaml"


@pytest.fixture(scope="module")
def log():
    scenario = load_scenario(TUBE)
    assert scenario.part.edge.kind == "mesh"
    return simulate(
        make_deburring_diagram(scenario=scenario), scenario, duration=4.0
    )


def test_contact_is_established(log):
    ch = log["chamfer"]
    t_contact = metrics.first_time(ch["t"], ch["f_n"] > 1.0)
    assert t_contact < 0.5
    after = metrics.window(ch["t"], t_contact + 0.5)
    assert np.all(ch["f_n"][after] > 2.0)


def test_depth_and_force_converge(log):
    ch = log["chamfer"]
    late = metrics.window(ch["t"], 3.0)
    assert np.max(np.abs(ch["delta"][late] - 5e-4)) < 2e-5
    # the paper's ring reads 5.371 N over the same second
    assert np.mean(ch["f_n"][late]) == pytest.approx(5.371, rel=0.01)


def test_the_tool_feeds_along_the_edge(log):
    cmd = log["command"]
    late = metrics.window(cmd["t"], 2.0)
    speed = metrics.mean_speed(cmd["t"][late], cmd["arc_position"][late])
    assert 1.5e-3 < speed < 3.5e-3
    assert not metrics.any_nan(
        *[v for b in log.signals.values() for v in b.values()]
    )
