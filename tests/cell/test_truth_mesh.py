"""The contact truth along a CAD part's edge: measured with the cutter
along the edge's own tool axis, so a tilted part reads the same law as an
upright one (a vertical cutter would not), and the tube read from its STL
reads the paper's ring's law."""

from pathlib import Path

import numpy as np
import pytest

from deburr_drake.cell.truth import (
    _normal_forces,
    contact_normal_force,
    truth_stations,
)
from deburr_drake.config import load_scenario

TUBE = Path(__file__).resolve().parents[2] / "examples" / "tube_stl.yaml"
DEPTH = 5e-4  # m, the paper's desired depth
PAPER_FORCE = 3.6946  # N, the paper's ring at DEPTH (less c0)


def test_the_stl_tube_reads_the_rings_law_at_every_station():
    scenario = load_scenario(TUBE)
    assert len(truth_stations(scenario)) == 64
    forces = contact_normal_force(
        scenario, [DEPTH], arc_fraction=np.array([0.0, 0.3, 0.7])
    )
    np.testing.assert_allclose(forces[:, 0], PAPER_FORCE, rtol=5e-3)


def test_a_tilted_edge_is_measured_along_its_tool_axis():
    tilted = load_scenario(
        TUBE, text="part: {pose: {xyz: [0.4, 0, 0], rpy: [0.35, 0, 0]}}"
    )
    fractions = np.array([0.0, 0.25, 0.5, 0.75])
    forces = contact_normal_force(tilted, [DEPTH], arc_fraction=fractions)
    np.testing.assert_allclose(forces[:, 0], PAPER_FORCE, rtol=5e-3)
    # a vertical cutter on the tilted band reads anything but the law
    vertical = _normal_forces(tilted, [DEPTH], fractions)[:, 0]
    assert np.ptp(vertical) > 1.0
    assert forces[:, 0] == pytest.approx(forces[0, 0], rel=1e-3)
