"""``deburr-drake compare``: one scenario with several controllers, side
by side."""

from __future__ import annotations

from deburr_drake.cli.common import (
    EXIT_CODES,
    _bad,
    _check_duration,
    _check_writable_target,
    _load,
    _output_arguments,
    _planned,
    _preflight_argument,
    _scenario_arguments,
    _write_resolved,
)


def _compare(args) -> int:
    from pathlib import Path

    from deburr_drake.runs import compare as cmp

    scenario = _load(args)
    if args.duration is not None:
        _check_duration(args.duration)
    controllers = [c.strip() for c in args.controllers.split(",") if c.strip()]
    if not controllers or len(set(controllers)) != len(controllers):
        _bad(
            f"--controllers = {args.controllers!r} is invalid: allowed "
            f"distinct names from {', '.join(cmp.CONTROLLERS)}"
        )
    for c in controllers:
        cmp.configure(scenario, c)
    if not (isinstance(args.workers, int) and args.workers >= 1):
        _bad(
            f"--workers = {args.workers!r} is invalid: allowed an integer >= 1"
        )
    out = Path(args.out or f"out/{scenario.name}_comparison")
    _check_writable_target(
        out,
        "--out",
        args.force,
        is_dir=True,
        names=("comparison.json", "comparison.md"),
    )
    plan, _, found = _planned(args, scenario)
    scenario = plan.scenario
    print(
        f"deburr-drake compare: scenario '{scenario.name}', "
        f"{', '.join(controllers)}, "
        + (f"{args.duration:g} s" if args.duration else "full run")
        + f", {args.workers} worker(s), output {out}/",
        flush=True,
    )
    rows = cmp.compare(
        scenario,
        controllers,
        duration=args.duration,
        out_dir=out,
        workers=args.workers,
    )
    _write_resolved(out, scenario, found)
    print((out / "comparison.md").read_text())
    worst = 0
    for row in rows:
        worst = max(
            worst, EXIT_CODES.get(row["stop_reason"].split(":", 1)[0], 1)
        )
    print(f"wrote {out}/comparison.json, comparison.md and the overlay figures")
    # A controller's guard or NaN is a finding, written in the table: the
    # comparison itself succeeded.
    return 0 if worst in (0, 3, 4) else worst


def _add_compare_parser(subparsers):
    p = subparsers.add_parser(
        "compare",
        help="run several controllers on one scenario and compare them",
    )
    _scenario_arguments(
        p,
        "paper",
        "simulated seconds of each run (default: the scenario's, a full pass)",
    )
    p.add_argument(
        "--controllers",
        default="fuzzy,fuzzy_m0,impedance,robust,ideal,position",
        help="comma-separated: fuzzy (the scenario's order), "
        "fuzzy_m0, fuzzy_m2, robust, ideal, impedance, "
        "position",
    )
    p.add_argument(
        "--workers", type=int, default=1, help="parallel processes (default 1)"
    )
    _output_arguments(
        p, "out/<scenario>_comparison", "an existing comparison in --out"
    )
    _preflight_argument(p)
    p.set_defaults(func=_compare)
