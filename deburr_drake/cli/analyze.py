"""``deburr-drake analyze``: is the run stable? the verdict on the run,
then the analysis in steady cutting."""

from __future__ import annotations

import numpy as np

from deburr_drake.cli.common import (
    _bad,
    _check_writable_target,
    _load,
    _output_arguments,
    _scenario_arguments,
)

#: What ``analyze`` writes into its output directory (those that apply).
_ANALYSIS_OUTPUTS = (
    "analysis.json",
    "poles.png",
    "rho_along_run.png",
    "bode_nyquist.png",
    "stability_map.png",
    "lyapunov.png",
)


def _check_analyze_times(args):
    """--at, --until, --spacing, --lyapunov > 0, --after-contact >= 0 and
    --at before --until: refused before anything runs."""
    for name in ("at", "until", "spacing", "lyapunov"):
        value = getattr(args, name)
        if value is not None and not (np.isfinite(value) and value > 0):
            _bad(f"--{name} = {value!r} is invalid: allowed a time > 0 s")
    if not (np.isfinite(args.after_contact) and args.after_contact >= 0):
        _bad(
            f"--after-contact = {args.after_contact!r} is invalid: "
            "allowed a time >= 0 s"
        )
    if args.at is not None and args.until is not None and args.at >= args.until:
        _bad(
            f"--at = {args.at!r} is invalid: allowed a time before "
            f"--until ({args.until!r} s)"
        )


def _analyze(args) -> int:
    from pathlib import Path

    from deburr_drake import analysis

    # The scenario and every option, checked before anything runs.
    scenario = _load(args)
    grid = analysis.parse_map(scenario, args.map) if args.map else None
    overrides = analysis.parse_settings(scenario, args.set or [])
    _check_analyze_times(args)
    out = Path(args.out or f"out/{scenario.name}/analysis")
    _check_writable_target(
        out, "--out", args.force, is_dir=True, names=_ANALYSIS_OUTPUTS
    )
    out.mkdir(parents=True, exist_ok=True)

    def say(message):
        print(f"  {message}", flush=True)

    # The verdict on the run and, if it settles, the operating point's
    # analysis.
    result = analysis.analyze(
        scenario,
        at=args.at,
        after_contact=args.after_contact,
        overrides=overrides,
        until=args.until,
        spacing=args.spacing or analysis.DEFAULT_SPACING,
        robust=not args.no_robust,
        numerics=args.numerics,
        progress=say,
    )
    settled = result.get("eigenvalues") is not None
    # --validate: predicted against simulated boundaries at that point.
    if args.validate and settled:
        result["boundaries"] = analysis.validate_boundaries(
            result["_objects"]["op"], progress=say
        )
    # --lyapunov: a run of its own, V1 and V traced along it.
    if args.lyapunov:
        trace = analysis.lyapunov_trace(scenario, duration=args.lyapunov)
        result["lyapunov"] = trace.summary
        analysis.plot_lyapunov(trace, out / "lyapunov.png", title=scenario.name)
    # --map: rho over one or two fields at the operating point.
    if grid is not None and settled:
        result["_objects"]["map"] = analysis.stability_map(
            result["_objects"]["op"], grid
        )
        result["map"] = result["_objects"]["map"].to_dict()
    # analysis.json, the figures and the one-screen summary.
    files = analysis.write_analysis(result, out)
    print()
    print(analysis.summary_text(result))
    if (args.validate or grid is not None) and not settled:
        print(
            "no --map / --validate: they need an operating point in "
            "steady cutting"
        )
    print("\nwrote " + ", ".join(str(p) for p in files.values()))
    return 0


def _add_analyze_parser(subparsers):
    p = subparsers.add_parser(
        "analyze",
        help="is the run stable? the verdict on "
        "the scenario's run, then the "
        "analysis in steady cutting",
    )
    _scenario_arguments(p, "paper", None)
    _operating_point_arguments(p)
    _analyzed_run_arguments(p)
    _output_arguments(
        p, "out/<scenario>/analysis", "an existing analysis in --out"
    )
    p.set_defaults(func=_analyze)


def _operating_point_arguments(parser):
    """analyze's options of the operating point and what is done there
    (--lyapunov runs on its own)."""
    parser.add_argument(
        "--at",
        type=float,
        default=None,
        help="simulated time (s) of the operating point "
        "(default: --after-contact s after the first "
        "contact)",
    )
    parser.add_argument(
        "--after-contact",
        type=float,
        default=3.0,
        help="seconds of cutting before the operating point (default 3)",
    )
    parser.add_argument(
        "--map",
        nargs="+",
        default=None,
        metavar="FIELD=LO:HI:N",
        help="stability map of rho over one or two scenario "
        "fields by dotted name, e.g. "
        "sensor.cutoff_frequency=5:80:16 "
        "controller.sliding_gain[0]=100:3000:16",
    )
    parser.add_argument(
        "--set",
        nargs="+",
        default=None,
        metavar="FIELD=VALUE",
        help="analyse the operating point with these scenario "
        "fields changed (the scenario as given reaches "
        "steady cutting first), e.g. "
        "controller.sliding_gain[0]=4500",
    )
    parser.add_argument(
        "--lyapunov",
        type=float,
        default=None,
        metavar="SECONDS",
        help="also run the scenario this long and trace V1 of "
        "Prop. 1 and V of (38) (lyapunov.png)",
    )
    parser.add_argument(
        "--validate",
        action="store_true",
        help="predicted against simulated stability boundaries "
        "(short runs from the operating point)",
    )


def _analyzed_run_arguments(parser):
    """analyze's options of the run and the maps along it."""
    parser.add_argument(
        "--until",
        type=float,
        default=None,
        metavar="SECONDS",
        help="end the analysed run here (default: the "
        "scenario's duration or pass)",
    )
    parser.add_argument(
        "--spacing",
        type=float,
        default=None,
        metavar="SECONDS",
        help="seconds of cutting between the maps along the run "
        "(default 5; burrs and curvature changes add "
        "their own)",
    )
    parser.add_argument(
        "--no-robust",
        action="store_true",
        help="skip the robust margin over the uncertain parameters (11 maps)",
    )
    parser.add_argument(
        "--numerics",
        choices=("refined", "shipped"),
        default="refined",
        help="how the run and its maps are integrated: refined (default: "
        "a quarter of simulation.max_step, eq. (3) between samples, "
        "where the verdict stops changing with the step) or shipped (the "
        "scenario's own step, faster)",
    )
