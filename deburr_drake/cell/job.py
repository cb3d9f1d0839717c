"""A whole part's job, planned before anything runs: the edges chosen and
ordered (deburr_drake.math.job_order), each cut's path and its start and
end postures, and the moves between the cuts (deburr_drake.cell.moves).

Use: ``job = plan_job(scenario)`` for a scenario with a ``job`` section.
An edge that cannot be cut (its path, or no posture at its start or end)
or reached (no move to it) is refused in one line naming the edge and
where; the job goes on from the last cut with the next edge."""

from dataclasses import dataclass, replace
from typing import List, NamedTuple, Optional

import numpy as np

from deburr_drake.cell.arm import solve_tool_pose
from deburr_drake.cell.moves import (
    Move,
    MovePlanningError,
    MoveSettings,
    PlanningCell,
    make_planning_cell,
    plan_move,
)
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


def _posture(model, robot, frame, p, axis, q_guess=None):
    return solve_tool_pose(
        model,
        p,
        q_guess=ik_seed(robot, p) if q_guess is None else q_guess,
        instance=frame.model_instance(),
        tool_frame=robot.tool_frame,
        tool_axis=axis,
    )


def _cut(scenario, model, part, chains, ordered, tilt=0.0):
    """The JobCut of ``ordered`` (no move yet); ValueError or
    RuntimeError say why not."""
    job = scenario.job
    to_part = part.rotation.T
    chain = chains[ordered.index]
    point = to_part @ (chain.points[len(chain.points) // 2] - part.translation)
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
    robot = scenario.robot
    frame = model.GetFrameByName(robot.tool_frame)
    ends = []
    for s in (0.0, contour.length):
        p, axis = contour.point_at(s), contour.tool_axis_at(s)
        q_guess = ends[0][2] if ends else None
        try:
            q = _posture(model, robot, frame, p, axis, q_guess)
        except RuntimeError as e:
            where = "start" if not ends else "end"
            raise RuntimeError(f"no posture at its {where}: {e}") from None
        ends.append((p, axis, q))
    return JobCut(ordered.index, point, edge, contour, *ends, None)


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
    # Each cut, and the move to it from the last one cut.
    cuts, refused = [], []
    for item in ordered:
        try:
            cut = _cut(
                scenario, model, part, chains, item, tilts.get(item.index, 0.0)
            )
        except (ValueError, RuntimeError) as e:
            refused.append((item.index, f"edge {item.index}: {e}"))
            continue
        if cuts:
            label = f"move from edge {cuts[-1].index} to edge {cut.index}"
            try:
                move = plan_move(
                    cell,
                    cuts[-1].end,
                    cut.start,
                    settings=settings,
                    label=label,
                )
            except MovePlanningError as e:
                refused.append((cut.index, str(e)))
                continue
            cut = cut._replace(move=move)
        cuts.append(cut)
    return JobPlan(cuts, skipped, refused, cell)
