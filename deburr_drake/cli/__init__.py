"""The ``deburr-drake`` command line. Thin: parses arguments and calls the
library. One module per command (its handler and its parser), what they
share in :mod:`deburr_drake.cli.common`."""

from __future__ import annotations

import argparse
import sys

from deburr_drake.cli.analyze import _add_analyze_parser
from deburr_drake.cli.batch import _add_batch_parser
from deburr_drake.cli.certify import _add_certify_parser
from deburr_drake.cli.common import _EXIT_HELP
from deburr_drake.cli.compare import _add_compare_parser
from deburr_drake.cli.converge import _add_converge_parser
from deburr_drake.cli.demo import _add_demo_parser
from deburr_drake.cli.diagram import _add_diagram_parser
from deburr_drake.cli.edges import _add_edges_parser
from deburr_drake.cli.job import _add_job_parser
from deburr_drake.cli.simulate import _add_simulate_parser
from deburr_drake.cli.sweep import _add_sweep_parser

__all__ = ["main"]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        prog="deburr-drake",
        description="Adaptive fuzzy hybrid position/force deburring on "
        "Drake (Hsu & Fu, 2000).",
        epilog=_EXIT_HELP,
    )
    subparsers = parser.add_subparsers(dest="command", required=True)
    _add_demo_parser(subparsers)
    _add_simulate_parser(subparsers)
    _add_batch_parser(subparsers)
    _add_compare_parser(subparsers)
    _add_diagram_parser(subparsers)
    _add_sweep_parser(subparsers)
    _add_analyze_parser(subparsers)
    _add_converge_parser(subparsers)
    _add_edges_parser(subparsers)
    _add_job_parser(subparsers)
    _add_certify_parser(subparsers)
    args = parser.parse_args(argv)
    from deburr_drake.config import ConfigError

    try:
        return args.func(args)
    except ConfigError as e:
        print(f"deburr-drake: error: {e}", file=sys.stderr)
        return 2
