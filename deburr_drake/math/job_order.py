"""A job's edges: which of a part's edges are cut, and in what order (pure
numpy).

``select_edges`` takes the part's edge listing (``describe_edges``) and
the job's picks: none picks every convex edge the tool reaches from the
part's open side and lists the others with why; picks name edges by a
point near them or by index. ``order_edges`` orders them nearest-next:
from a start point, the edge nearest it, then the edge nearest where that
cut ends, and so on; each cut starts at its edge's point nearest where the
tool was.
"""

from typing import NamedTuple

import numpy as np

__all__ = ["Pick", "OrderedCut", "order_edges", "select_edges"]


class Pick(NamedTuple):
    """An edge picked by a point near it (m, world) or by index."""

    near: object  # np.ndarray (3,) or None
    index: int  # -1: by near


class OrderedCut(NamedTuple):
    """A cut in the job's order: the edge's index, and where the tool
    starts on it and ends (m, world)."""

    index: int
    start: np.ndarray
    end: np.ndarray


def _why_not(summary) -> str:
    if summary.convex is None:
        return "convex and concave along it"
    if not summary.convex:
        return "concave (the tool cannot chamfer into it)"
    return summary.blocked


def select_edges(summaries, chains, picks=()):
    """(selected edge indices, [(index, why not)] for the rest) of a part's
    ``summaries`` and ``chains``. No ``picks``: every convex edge reachable
    from the open side. Picks in their order, each once; ValueError
    naming the pick (``picks[i]``) for an index out of range."""
    if not picks:
        selected, skipped = [], []
        for s in summaries:
            why = _why_not(s)
            if why:
                skipped.append((s.index, why))
            else:
                selected.append(s.index)
        return selected, skipped
    selected = []
    for i, pick in enumerate(picks):
        if pick.index >= 0:
            if pick.index >= len(chains):
                raise ValueError(
                    f"picks[{i}]: edge index {pick.index}: the part has "
                    f"{len(chains)} edges (0 to {len(chains) - 1})"
                )
            index = pick.index
        else:
            index = int(np.argmin([c.distance(pick.near) for c in chains]))
        if index not in selected:
            selected.append(index)
    return selected, []


def _nearest_vertex(chain, point):
    return chain.points[
        int(np.argmin(np.linalg.norm(chain.points - point, axis=1)))
    ]


def _cut_of(chain, index, point):
    """The cut of ``chain`` for a tool at ``point``: a loop from (and back
    to) its vertex nearest it, an open edge from its nearer end."""
    if chain.closed:
        start = _nearest_vertex(chain, point)
        return OrderedCut(index, start, start)
    first, last = chain.points[0], chain.points[-1]
    if np.linalg.norm(last - point) < np.linalg.norm(first - point):
        first, last = last, first
    return OrderedCut(index, first, last)


def order_edges(chains, selected, *, start=None, order="nearest"):
    """The cuts of ``selected`` (indices into ``chains``): as listed
    (``order`` listed) or nearest-next from ``start`` (m, world; None: the
    first selected edge's first point)."""
    selected = list(selected)
    if not selected:
        return []
    point = (
        np.asarray(start, float)
        if start is not None
        else chains[selected[0]].points[0]
    )
    cuts = []
    left = selected
    while left:
        if order == "listed":
            index = left[0]
        else:
            index = min(left, key=lambda i: chains[i].distance(point))
        left = [i for i in left if i != index]
        cut = _cut_of(chains[index], index, point)
        cuts.append(cut)
        point = cut.end
    return cuts
