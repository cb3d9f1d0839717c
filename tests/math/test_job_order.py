"""A job's edges on the block: all reachable convex edges picked with the
others listed and why, picks by point and index, nearest-next order."""

from pathlib import Path

import numpy as np
import pytest

from deburr_drake.math.job_order import Pick, order_edges, select_edges
from deburr_drake.math.mesh_part import describe_edges, load_part, sharp_edges

BLOCK = Path(__file__).resolve().parents[2] / "models" / "parts" / "block.stl"


def _nearest(chains, point):
    return int(np.argmin([c.distance(point) for c in chains]))


@pytest.fixture(scope="module")
def block():
    part = load_part(BLOCK, units="mm")
    chains = sharp_edges(part)
    return part, chains, describe_edges(part, chains)


def test_all_means_the_convex_edges_reachable_from_the_open_side(block):
    _, chains, summaries = block
    selected, skipped = select_edges(summaries, chains)
    assert sorted(selected + [i for i, _ in skipped]) == list(range(14))
    for i in selected:
        assert summaries[i].convex is True and summaries[i].reachable
    why = dict(skipped)
    # the slot's floor is concave; the base's edges stand on the table
    assert "concave" in why[_nearest(chains, [0.005, 0.028, -0.01])]
    assert "base" in why[_nearest(chains, [-0.07, 0.0, -0.03])]
    # every top-side edge is selected: bore, two holes, slot, rim, chamfer
    for point in (
        [-0.03, 0.015, 0.0],
        [-0.034, -0.028, 0.0],
        [0.007, -0.025, 0.0],
        [0.011, 0.028, 0.0],
        [-0.07, 0.0, 0.0],
        [0.0, 0.032, 0.0],
    ):
        assert _nearest(chains, point) in selected


def test_picks_by_point_and_index_in_their_order(block):
    _, chains, summaries = block
    picks = [Pick(np.array([-0.03, 0.015, 0.0]), -1), Pick(None, 3)]
    picks.append(Pick(None, 3))
    selected, skipped = select_edges(summaries, chains, picks)
    bore = _nearest(chains, [-0.03, 0.015, 0.0])
    assert selected == [bore, 3] and skipped == []
    with pytest.raises(ValueError, match=r"^picks\[0\]: edge index 14"):
        select_edges(summaries, chains, [Pick(None, 14)])


def test_nearest_next_from_a_start_point(block):
    _, chains, summaries = block
    selected, _ = select_edges(summaries, chains)
    start = np.array([-0.1, 0.0, 0.1])
    cuts = order_edges(chains, selected, start=start)
    assert sorted(c.index for c in cuts) == sorted(selected)
    # greedy: each next edge is the nearest of those left to the last end
    point = start
    left = set(selected)
    for cut in cuts:
        best = min(chains[i].distance(point) for i in left)
        assert chains[cut.index].distance(point) == pytest.approx(best)
        left.remove(cut.index)
        if chains[cut.index].closed:
            np.testing.assert_array_equal(cut.start, cut.end)
        point = cut.end
    listed = order_edges(chains, selected, order="listed")
    assert [c.index for c in listed] == selected
