"""Tests of deburr_drake.runs.profile_envelope: each cell's run starts
LEAD before its first fillet (or mid-side) and stops TAIL past it; the
feed law's values on the line and in the fillet."""

import math

import pytest

from deburr_drake.cell.edge import make_contour
from deburr_drake.config import load_scenario
from deburr_drake.runs import profile_envelope as pe


@pytest.fixture(scope="module")
def paper():
    return load_scenario("paper")


@pytest.mark.parametrize(
    "fillet, side", [(0.004, "inner"), (0.015, "outer"), (0.030, "inner")]
)
def test_a_cell_runs_through_its_first_fillet(paper, fillet, side):
    sc = pe.fillet_scenario(paper, pe.FilletCell(fillet, side, 10.0))
    contour = make_contour(sc)
    start, end = pe.first_fillet(contour)
    r = sc.tool.cutter_radius
    radius = fillet - r if side == "inner" else fillet + r
    assert end - start == pytest.approx(0.5 * math.pi * radius)
    assert start == pytest.approx(min(pe.LEAD, pe.HALF_SIDE - fillet), abs=1e-9)
    assert contour.curvature(
        contour.point_at(0.5 * (start + end))
    ) == pytest.approx((1 if side == "inner" else -1) / radius)
    assert sc.simulation.stop_after_passes * contour.length == pytest.approx(
        end + pe.TAIL
    )
    assert sc.process.burrs == []


def test_the_feed_law_slows_in_a_pocket_corner(paper):
    sc = pe.fillet_scenario(paper, pe.FilletCell(0.008, "inner", 10.0))
    # path radius 5 mm: (1 + (3.25 mm) / 5 mm) / (1 + 0.5 / 5) = 1.5
    line, fillet = pe.law_feeds(sc, 1.0 / 0.005)
    assert line == pytest.approx(8.0 / (3.0e9 * 5e-4 * 0.002))
    assert fillet == pytest.approx(line / 1.5)
