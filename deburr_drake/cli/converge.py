"""``deburr-drake converge``: does the run's answer hold when the step is
refined?"""

from __future__ import annotations

from deburr_drake.cli.common import (
    _check_duration,
    _check_writable_target,
    _load,
    _output_arguments,
    _scenario_arguments,
)

#: What ``converge`` writes into its output directory.
_CONVERGENCE_OUTPUTS = ("convergence.json", "convergence.md")


def _converge(args) -> int:
    from pathlib import Path

    from deburr_drake.runs.convergence import converge, write_convergence

    scenario = _load(args)
    if args.duration is not None:
        _check_duration(args.duration)
    out = Path(args.out or f"out/{scenario.name}/convergence")
    _check_writable_target(
        out, "--out", args.force, is_dir=True, names=_CONVERGENCE_OUTPUTS
    )
    print(
        f"deburr-drake converge: scenario '{scenario.name}', "
        f"{args.duration or scenario.simulation.duration:g} s per run, up "
        f"to {args.steps} halving(s) of the step, output {out}/",
        flush=True,
    )
    study = converge(
        scenario,
        duration=args.duration,
        max_halvings=args.steps,
        tolerance=args.tolerance,
        progress=lambda line: print(f"  {line}", flush=True),
    )
    files = write_convergence(study, out)
    print()
    print(files["markdown"].read_text())
    print("wrote " + ", ".join(str(p) for p in files.values()))
    return 0


def _add_converge_parser(subparsers):
    p = subparsers.add_parser(
        "converge",
        help="does the run's answer hold when the step is refined? the "
        "scenario at its step and at the step halved, until the metrics "
        "stop changing",
    )
    _scenario_arguments(
        p, "paper", "simulated seconds per run (default: the scenario's)"
    )
    p.add_argument(
        "--steps",
        type=int,
        default=3,
        help="halvings of simulation.max_step at most (default 3: down "
        "to an eighth of it)",
    )
    p.add_argument(
        "--tolerance",
        type=float,
        default=0.05,
        help="relative change of every compared metric under which a "
        "halving changed nothing (default 0.05)",
    )
    _output_arguments(
        p,
        "out/<scenario>/convergence",
        "an existing convergence.json / .md in --out",
    )
    p.set_defaults(func=_converge)
