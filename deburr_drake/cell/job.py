"""A whole part's job, planned before anything runs: the edges chosen and
ordered (deburr_drake.math.job_order), each cut's path and its start and
end postures, and the moves between the cuts (deburr_drake.cell.moves).

Each cut is followed by the arm as the run would: postures station by
station along the cutter's path, each from the one before
(deburr_drake.cell.joint_path: reach, joint limits, wrist flips and
conditioning), the tool spun about its axis or another posture taken at
the start when the seed's does not follow; at every station the arm and
its spindle (not the cutter, which is in the cut) must stand clear of
the part's convex pieces.

Use: ``job = plan_job(scenario)`` for a scenario with a ``job`` section.
An edge that cannot be cut (its path, a station the arm does not follow,
the spindle or the arm in the part) is refused in one line naming the
edge and where; the job goes on from the last cut with the next edge. An
edge no move reaches from the last cut is tried again from each of the
next ``RETRIES`` cuts (a move between cuts whose tools stand far apart,
vertical and horizontal, may not be found where a move from another cut
is), and refused naming the last move tried if none reaches it."""

from dataclasses import dataclass, replace
import math
from typing import List, NamedTuple, Optional

import numpy as np

from deburr_drake.cell.joint_path import PathBreak
from deburr_drake.cell.moves import (
    Move,
    MovePlanningError,
    MoveSettings,
    PlanningCell,
    least_clearance,
    make_planning_cell,
    plan_move,
)
from deburr_drake.cell.reach import _follow, _free_spin
from deburr_drake.cell.robot import check_robot, ik_seed
from deburr_drake.config import EdgeConfig, Scenario
from deburr_drake.math.convex_pieces import convex_pieces, placed_pieces
from deburr_drake.math.job_order import Pick, order_edges, select_edges
from deburr_drake.math.mesh_part import describe_edges, load_part, sharp_edges

__all__ = ["JobCut", "JobPlan", "plan_job"]


class JobCut(NamedTuple):
    """One edge of the job, ready to cut."""

    index: int  # in the part's listing
    point: np.ndarray  # m, part frame: a point on the edge
    edge: EdgeConfig  # the edge as a single-edge scenario cuts it
    contour: object  # EdgeContour, world
    start: tuple  # (tip m, tool axis, q rad) at the cut's start
    end: tuple  # the same at its end
    move: Optional[Move]  # the move to this cut (None for the first)
    # m, the stations' arc positions along the cutter's path (contour)
    arcs: Optional[np.ndarray] = None
    # rad, (stations, joints): the arm's postures there, followed in order
    postures: Optional[np.ndarray] = None
    # m, the least distance of the arm and spindle (not the cutter) to the
    # part along the cut
    min_clearance_m: float = math.nan


@dataclass(frozen=True)
class JobPlan:
    """The job planned: ``cuts`` in order, ``skipped`` (index, why: not
    selected by ``edges: []``), ``refused`` (index, one line: selected
    but not cut), and the ``cell`` the moves were planned and checked in
    (the robot, its tool and the part's convex pieces), which checks the
    run's moves too."""

    cuts: List[JobCut]
    skipped: list
    refused: list
    cell: Optional[PlanningCell] = None

    def moves(self) -> List[Move]:
        return [c.move for c in self.cuts if c.move is not None]


#: m, between the stations the arm is followed at along a cut
STATION_SPACING = 0.004


def _stations(contour):
    """(the start point, the stations' points, tool axes and arc
    positions) along ``contour``, as deburr_drake.cell.reach follows an
    edge: about ``STATION_SPACING`` apart, from its start to its end (a
    loop: back to its start)."""
    count = max(8, math.ceil(contour.length / STATION_SPACING))
    arcs = np.linspace(0.0, contour.length, count + 1)
    points = [contour.point_at(s) for s in arcs]
    axes = [contour.tool_axis_at(s) for s in arcs]
    return points[0], points, axes, arcs


def _follow_cut(model, robot, contour):
    """(arcs, postures) of the arm following ``contour`` from the start
    posture nearest the seed's, else from the one the tool's free spin or
    another posture gives (deburr_drake.cell.reach); RuntimeError naming
    the station and the joint where it does not."""
    instance = model.GetFrameByName(robot.tool_frame).model_instance()
    stations = _stations(contour)
    try:
        _, path = _follow(
            model, robot, instance, stations, ik_seed(robot, stations[0])
        )
    except (PathBreak, RuntimeError) as e:
        q0 = _free_spin(model, robot, instance, stations)
        if q0 is None:
            raise RuntimeError(
                f"the arm does not follow it (from the seed, with the tool "
                f"spun about its axis, nor from other postures): {e}"
            ) from None
        _, path = _follow(model, robot, instance, stations, q0)
    return stations[3], path


def _cut(scenario, model, cell, part, chains, summary, ordered, tilt=0.0):
    """The JobCut of ``ordered`` (no move yet; ``summary`` its edge's
    EdgeSummary); ValueError or RuntimeError say why not."""
    job = scenario.job
    to_part = part.rotation.T
    chain = chains[ordered.index]
    # the edge's middle by length: a vertex may be the corner where
    # another edge ends, and ``near`` would pick either
    point = to_part @ (summary.point - part.translation)
    edge = EdgeConfig(
        kind="mesh",
        file=str(job.part_file()),
        units=job.units,
        near=point.tolist(),
        sharp_angle=job.sharp_angle,
        tilt=tilt,
        # an open edge cut from its last point runs backwards
        direction=-1
        if not chain.closed and np.allclose(ordered.start, chain.points[-1])
        else 1,
        start_near=(to_part @ (ordered.start - part.translation)).tolist(),
    )
    contour = edge.mesh_path(scenario.tool, job.pose)
    arcs, path = _follow_cut(model, scenario.robot, contour)
    # The arm and the spindle along the cut, clear of the part.
    least, i, shape = least_clearance(cell, path, cutter=False)
    if i is not None:
        raise RuntimeError(
            f"at arc {arcs[i] * 1e3:.1f} mm the {shape} stands "
            f"{-least * 1e3:.2g} mm in the part ({contour.describe_rule()})"
        )
    ends = [
        (contour.point_at(s), contour.tool_axis_at(s), q)
        for s, q in ((arcs[0], path[0]), (arcs[-1], path[-1]))
    ]
    return JobCut(
        ordered.index, point, edge, contour, *ends, None, arcs, path, least
    )


def plan_job(
    scenario: Scenario, *, settings: Optional[MoveSettings] = None
) -> JobPlan:
    """The job of ``scenario.job`` (see the module docstring)."""
    job = scenario.job
    if not job.file:
        raise ValueError("the scenario has no job (job.file is empty)")
    settings = settings or MoveSettings()
    settings = replace(
        settings,
        approach=job.approach,
        retract=job.retract,
        clearance=job.clearance,
    )
    # The part, its edges, the job's selection and order.
    path = job.part_file()
    part = load_part(path, units=job.units, xyz=job.pose.xyz, rpy=job.pose.rpy)
    chains = sharp_edges(part, min_angle=job.sharp_angle)
    picks = [
        Pick(part.to_world(e.near) if e.near else None, e.index)
        for e in job.edges
    ]
    summaries = describe_edges(part, chains)
    selected, skipped = select_edges(summaries, chains, picks)
    # each picked edge's tilt (the first pick of an edge picked twice)
    tilts = {}
    for pick, edge in zip(picks, job.edges):
        (index,), _ = select_edges(summaries, chains, [pick])
        tilts.setdefault(index, edge.tilt)
    start = part.to_world(job.start) if job.start else None
    ordered = order_edges(chains, selected, start=start, order=job.order)
    # The robot, and the planning cell of it and the part's convex pieces.
    model = check_robot(scenario.robot)
    pieces = placed_pieces(convex_pieces(path), part, job.units)
    cell = make_planning_cell(
        scenario.robot, scenario.tool, pieces, settings=settings
    )
    # Each cut, and the move to it from the last one cut; an edge no move
    # reaches from there is tried again from the next cuts.
    cuts, refused, waiting = [], [], []
    for item in ordered:
        try:
            cut = _cut(
                scenario,
                model,
                cell,
                part,
                chains,
                summaries[item.index],
                item,
                tilts.get(item.index, 0.0),
            )
        except (ValueError, RuntimeError) as e:
            refused.append((item.index, f"edge {item.index}: {e}"))
            continue
        waiting.append([cut, "", RETRIES + 1, None])
        while waiting and _join(cell, cuts, waiting, settings):
            pass
    refused += [(cut.index, why) for cut, why, _, _ in waiting]
    return JobPlan(cuts, skipped, refused, cell)


#: -, how many later cuts an edge no move reached is tried again from
RETRIES = 2


def _join(cell, cuts, waiting, settings) -> bool:
    """Appends to ``cuts`` the first of ``waiting`` ([cut, why not yet,
    tries left, the index of the cut last tried from]) a move from the
    last cut reaches (or the first, when nothing is cut yet); True if one
    was. Each try from a cut not tried from before spends one of its
    tries; one with none left stays, with why, for the refusals."""
    for entry in waiting:
        cut, _, left, tried = entry
        if not cuts:
            cuts.append(cut)
            waiting.remove(entry)
            return True
        if left <= 0 or tried == cuts[-1].index:
            continue
        entry[2:] = [left - 1, cuts[-1].index]
        label = f"move from edge {cuts[-1].index} to edge {cut.index}"
        try:
            move = plan_move(
                cell, cuts[-1].end, cut.start, settings=settings, label=label
            )
        except MovePlanningError as e:
            entry[1] = str(e)
            continue
        cuts.append(cut._replace(move=move))
        waiting.remove(entry)
        return True
    return False
