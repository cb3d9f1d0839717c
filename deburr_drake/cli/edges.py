"""``deburr-drake edges``: every sharp edge of a part, listed and drawn."""

from __future__ import annotations

import math

from deburr_drake.cli.common import _bad

_OPEN_SIDE = (
    "reach: yes when the part does not stand on the edge (its lowest "
    "points along up are its base) and at 48 stations along it, the tool "
    "axis set by the rule, the spindle (beyond the cutter's 20 mm, within "
    "20 mm of the axis) holds none of the part's surface"
)


def _part_source(args):
    """(file, units, xyz, rpy, sharp angle in rad, the scenario's edge
    near point in the part frame or None) from PART or --scenario."""
    from deburr_drake.config import EdgeConfig, load_scenario

    if args.scenario:
        if args.part or args.pose:
            _bad("give PART (with --pose) or --scenario, not both")
        scenario = load_scenario(args.scenario)
        edge = scenario.part.edge
        if edge.kind != "mesh":
            _bad(
                f"--scenario {args.scenario}: part.edge.kind is "
                f"{edge.kind!r}: edges lists a mesh part's"
            )
        pose = scenario.part.pose
        angle = (
            math.radians(args.sharp_angle)
            if args.sharp_angle is not None
            else edge.sharp_angle
        )
        return (
            edge.mesh_file(),
            edge.units,
            pose.xyz,
            pose.rpy,
            angle,
            edge.near,
        )
    if not args.part:
        _bad("give a part's file (PART) or --scenario")
    pose = args.pose or [0.0] * 6
    angle = math.radians(30.0 if args.sharp_angle is None else args.sharp_angle)
    if not 0.0 < angle < math.pi:
        _bad(f"--sharp-angle {args.sharp_angle} is invalid: in (0, 180) deg")
    file = EdgeConfig(kind="mesh", file=args.part).mesh_file()
    return file, args.units, pose[:3], pose[3:], angle, None


def _row(summary, part, marker):
    p = part.rotation.T @ (summary.point - part.translation)
    low, high = (math.degrees(a) for a in summary.dihedral)
    kind = {True: "convex", False: "concave", None: "mixed"}[summary.convex]
    reach = "yes" if summary.reachable else f"no: {summary.blocked}"
    point = "[" + ", ".join(f"{x:8.4f}" for x in p) + "]"
    return (
        f"{summary.index:4d}  {'loop' if summary.closed else 'open':4s}  "
        f"{summary.length * 1e3:9.1f}  {low:6.1f}-{high:5.1f}  {kind:7s}  "
        f"{point}  {reach}{marker}\n"
        f"{'':6s}{summary.rule.describe()}"
    )


def _edges(args) -> int:
    from pathlib import Path

    from deburr_drake.math.mesh_part import (
        choose_edge,
        describe_edges,
        load_part,
        sharp_edges,
    )
    from deburr_drake.runs.edge_figure import edge_figure

    file, units, xyz, rpy, angle, near = _part_source(args)
    try:
        part = load_part(file, units=units, xyz=xyz, rpy=rpy)
    except ValueError as e:
        _bad(f"PART {file} is invalid: {e}")
    chains = sharp_edges(part, min_angle=angle)
    summaries = describe_edges(part, chains)
    chosen = None
    if near is not None and chains:
        nearest = choose_edge(chains, near=part.to_world(near))
        chosen = next(i for i, c in enumerate(chains) if c is nearest)
    print(
        f"{file}: {len(chains)} sharp edges (faces' normals over "
        f"{math.degrees(angle):.1f} deg apart; up is the world's +z)"
    )
    print(
        "   # shape  length_mm  dihedral_deg  kind     "
        "point (m, part frame)             reach"
    )
    for summary in summaries:
        marker = "  <- the scenario's edge" if summary.index == chosen else ""
        print(_row(summary, part, marker))
    print(_OPEN_SIDE)
    out = Path(args.out or f"out/edges/{Path(file).stem}.png")
    edge_figure(
        part,
        chains,
        summaries,
        out,
        title=f"{Path(file).name}: sharp edges",
        chosen=chosen,
    )
    print(f"wrote {out}")
    return 0


def _add_edges_parser(subparsers):
    p = subparsers.add_parser(
        "edges",
        help="list and draw a CAD part's sharp edges: index, loop or "
        "open, length, dihedral, convex or concave, a point, reach",
    )
    p.add_argument(
        "part",
        nargs="?",
        default=None,
        help="the part's STL, OBJ or STEP file (or a name in models/parts)",
    )
    p.add_argument(
        "--units",
        default="m",
        help="the file's length unit: m, mm, cm or in (default m)",
    )
    p.add_argument(
        "--sharp-angle",
        type=float,
        default=None,
        help="deg: an edge where the faces' normals differ by more "
        "(default 30, or the scenario's part.edge.sharp_angle)",
    )
    p.add_argument(
        "--pose",
        type=float,
        nargs=6,
        default=None,
        metavar=("X", "Y", "Z", "ROLL", "PITCH", "YAW"),
        help="the part placed at xyz (m) and roll-pitch-yaw (rad), as "
        "part.pose (default at the origin)",
    )
    p.add_argument(
        "--scenario",
        default=None,
        help="take the part (file, units, pose, sharp angle) from a "
        "scenario with a mesh edge, and mark its edge",
    )
    p.add_argument(
        "--out",
        default=None,
        help="the figure (PNG; default out/edges/<part>.png)",
    )
    p.set_defaults(func=_edges)
