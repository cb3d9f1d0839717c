"""``deburr-drake job``: a scenario's whole-part job planned: the edges
cut in order, those left out and why, the moves between the cuts with
their clearance, time and travel; written to ``job_plan.json``."""

from __future__ import annotations

import json
from pathlib import Path

from deburr_drake.cli.common import _bad


def _job_plan_record(plan) -> dict:
    """The plan as plain numbers (SI units)."""
    cuts = []
    for cut in plan.cuts:
        move = cut.move
        cuts.append(
            {
                "index": cut.index,
                "point": [float(x) for x in cut.point],
                "length_m": float(cut.contour.length),
                "tool_rule": cut.contour.describe_rule(),
                # the arm and spindle along the cut (the cutter is in it)
                "min_clearance_m": float(cut.min_clearance_m),
                "move_before": None
                if move is None
                else {
                    "duration_s": move.duration_s,
                    "travel_m": move.travel_m,
                    "min_clearance_m": move.min_clearance_m,
                    "planning_time_s": move.planning_time_s,
                },
            }
        )
    moves = plan.moves()
    return {
        "edges": cuts,
        "skipped": [{"index": i, "why": why} for i, why in plan.skipped],
        "refused": [{"index": i, "why": why} for i, why in plan.refused],
        "moves": {
            "count": len(moves),
            "duration_s": sum(m.duration_s for m in moves),
            "travel_m": sum(m.travel_m for m in moves),
            "min_clearance_m": min(
                (m.min_clearance_m for m in moves), default=None
            ),
        },
    }


def _job(args) -> int:
    from deburr_drake.cell.job import plan_job
    from deburr_drake.config import load_scenario

    scenario = load_scenario(args.scenario)
    if not scenario.job.file:
        _bad(f"--scenario {args.scenario}: it has no job (job.file)")
    plan = plan_job(scenario)
    record = _job_plan_record(plan)
    print(f"{scenario.job.part_file()}: {len(plan.cuts)} edges cut, in order")
    for cut in record["edges"]:
        move = cut["move_before"]
        how = (
            "first"
            if move is None
            else f"move {move['duration_s']:.2f} s, "
            f"{move['travel_m'] * 1e3:.0f} mm, clearance "
            f"{move['min_clearance_m'] * 1e3:.1f} mm"
        )
        print(
            f"  edge {cut['index']:3d}  {cut['length_m'] * 1e3:7.1f} mm  "
            f"(clearance along it {cut['min_clearance_m'] * 1e3:.1f} mm)  "
            f"{how}"
        )
    for index, why in plan.skipped:
        print(f"  edge {index:3d}  not selected: {why}")
    for _, why in plan.refused:
        print(f"  refused: {why}")
    out = Path(args.out or f"out/{scenario.name}")
    out.mkdir(parents=True, exist_ok=True)
    (out / "job_plan.json").write_text(json.dumps(record, indent=2) + "\n")
    print(f"wrote {out / 'job_plan.json'}")
    return 0


def _add_job_parser(subparsers):
    p = subparsers.add_parser(
        "job",
        help="plan a scenario's whole-part job: the edges in order, the "
        "moves between them (clearance, time, travel)",
    )
    p.add_argument(
        "--scenario", required=True, help="a scenario with a job section"
    )
    p.add_argument(
        "--out", default=None, help="folder (default out/<scenario name>)"
    )
    p.set_defaults(func=_job)
