"""The part's edges drawn with their indices (pure matplotlib, explicit Agg
canvas): what ``deburr-drake edges`` lists, in a 3-D view and seen from
above, coloured by whether the tool can cut them."""

from __future__ import annotations

from pathlib import Path

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
import numpy as np

__all__ = ["edge_figure"]

_COLOURS = {
    "reachable": "tab:blue",
    "concave": "tab:orange",
    "blocked": "0.6",
}


def _colour(summary):
    if not summary.reachable:
        return _COLOURS["blocked"]
    if summary.convex is False:
        return _COLOURS["concave"]
    return _COLOURS["reachable"]


def edge_figure(part, chains, summaries, path, *, title="", chosen=None):
    """Writes a PNG to ``path`` of the ``chains`` of ``part`` (m, drawn in
    mm in the part frame) with their ``summaries``' indices; ``chosen``
    (an index) is drawn thicker. Returns the path."""
    fig = Figure(figsize=(12.0, 6.0))
    space = fig.add_subplot(1, 2, 1, projection="3d")
    plan = fig.add_subplot(1, 2, 2)
    rotation, translation = part.rotation, part.translation
    corners = (part.mesh.bounds - translation) @ rotation
    for chain, summary in zip(chains, summaries):
        points = (chain.points - translation) @ rotation * 1e3
        if chain.closed:
            points = np.vstack([points, points[:1]])
        width = 3.0 if summary.index == chosen else 1.4
        colour = _colour(summary)
        # the edges the tool can cut drawn over those it cannot
        order = 3 if summary.reachable else 2
        space.plot(*points.T, color=colour, lw=width, zorder=order)
        plan.plot(
            points[:, 0], points[:, 1], color=colour, lw=width, zorder=order
        )
        label = (summary.point - translation) @ rotation * 1e3
        space.text(*label, str(summary.index), fontsize=8)
        plan.annotate(str(summary.index), label[:2], fontsize=8)
    span = np.ptp(corners, axis=0).max() * 1e3
    middle = corners.mean(axis=0) * 1e3
    for set_limits, k in zip(
        (space.set_xlim, space.set_ylim, space.set_zlim), range(3)
    ):
        set_limits(middle[k] - 0.55 * span, middle[k] + 0.55 * span)
    space.set_box_aspect((1.0, 1.0, 1.0))  # millimetres alike on the axes
    space.set_xlabel("x (mm)")
    space.set_ylabel("y (mm)")
    space.set_zlabel("z (mm)")
    plan.set_aspect("equal")
    plan.set_xlabel("x (mm)")
    plan.set_ylabel("y (mm)")
    plan.set_title("seen from +z (part frame)")
    for name, colour in _COLOURS.items():
        plan.plot([], [], color=colour, label=name)
    plan.legend(loc="best", fontsize=8)
    fig.suptitle(title or "sharp edges")
    fig.subplots_adjust(wspace=0.35)
    FigureCanvasAgg(fig)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    return path
