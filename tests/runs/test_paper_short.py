"""A short run of the paper's cell (5-DOF arm, m = 2): contact is
established and the chamfer depth converges. The full pass is
``deburr-drake simulate`` (minutes), not a test."""

import numpy as np
import pytest

from deburr_drake.math import metrics

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def log(paper_log):
    # 5 s of the paper cell (tests/conftest.py), run once for the session.
    return paper_log


def test_contact_is_established(log):
    ch = log["chamfer"]
    t_contact = metrics.first_time(ch["t"], ch["f_n"] > 1.0)
    assert t_contact < 0.5
    after = metrics.window(ch["t"], t_contact + 0.5)
    assert np.all(ch["f_n"][after] > 2.0)


def test_depth_converges(log):
    ch = log["chamfer"]
    late = metrics.window(ch["t"], 3.5)
    assert np.max(np.abs(ch["delta"][late] - 5e-4)) < 2e-5


def test_the_tool_feeds_along_the_edge(log):
    cmd = log["command"]
    late = metrics.window(cmd["t"], 2.0)
    speed = metrics.mean_speed(cmd["t"][late], cmd["arc_position"][late])
    assert 1.5e-3 < speed < 3.5e-3
    assert not metrics.any_nan(
        *[v for b in log.signals.values() for v in b.values()]
    )
