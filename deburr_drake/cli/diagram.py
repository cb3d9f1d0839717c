"""``deburr-drake diagram``: the cell's Diagram drawn as a graph."""

from __future__ import annotations

import sys

from deburr_drake.cli.common import _load, _scenario_arguments


def _diagram(args) -> int:
    from pathlib import Path

    from deburr_drake.cell.diagram import make_deburring_diagram
    from deburr_drake.runs.graphs import write_graphs

    scenario = _load(args)
    diagram = make_deburring_diagram(scenario=scenario)
    out = Path(args.out or f"out/{scenario.name}/diagram.dot")
    written, message = write_graphs(
        diagram, out, fmt=args.format, max_depth=args.depth
    )
    for path in written:
        print(f"wrote {path}")
    if message:
        print(f"deburr-drake: {message}", file=sys.stderr)
    return 0


def _add_diagram_parser(subparsers):
    p = subparsers.add_parser(
        "diagram",
        help="export the diagram and the controller as GraphViz graphs",
    )
    _scenario_arguments(p, "paper", None)
    p.add_argument(
        "--depth",
        type=int,
        default=None,
        help="levels of nesting to expand (default: all)",
    )
    p.add_argument(
        "--format",
        choices=("dot", "svg", "png"),
        default="dot",
        help="also render with GraphViz's dot (default: .dot only)",
    )
    p.add_argument(
        "--out",
        default=None,
        help="output path (default out/<scenario>/diagram.dot)",
    )
    p.set_defaults(func=_diagram)
