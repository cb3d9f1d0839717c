"""``deburr-drake demo``: the point-mass testbed and what the controller
promises there."""

from __future__ import annotations

import json

from deburr_drake.cli.common import (
    _bad,
    _check_duration,
    _load,
    _progress,
    _scenario_arguments,
)

#: The demo's summary as printed: label, key, scale, unit.
_DEMO_ROWS = (
    (
        "delta_d time constant, adaptation off",
        "depth_time_constant",
        1.0,
        "s",
    ),
    (
        "  eq. (8) with the local stiffness",
        "depth_time_constant_eq8",
        1.0,
        "s",
    ),
    ("final depth (adaptive)", "depth_final", 1e3, "mm"),
    (
        "max |delta - delta*| after 2 s",
        "depth_max_error_after_settle",
        1e3,
        "mm",
    ),
    (
        "c0 + c1 delta* (estimated)",
        "predicted_force_at_desired_depth",
        1.0,
        "N",
    ),
    ("true ||f_n|| at delta*", "true_force_at_desired_depth", 1.0, "N"),
    ("  relative error", "force_prediction_error_rel", 1.0, ""),
    ("commanded feed (mean after 2 s)", "commanded_feed_mean", 1e3, "mm/s"),
    ("feedrate law on measured signals", "feedrate_law_mean", 1e3, "mm/s"),
    ("command speed along the contour", "command_speed", 1e3, "mm/s"),
    (
        "chamfering force (mean after 2 s)",
        "chamfering_force_mean",
        1.0,
        "N",
    ),
    (
        "fraction of s in the dead zone after 2 s",
        "dead_zone_fraction_after_settle",
        1.0,
        "",
    ),
    ("NaN detected", "nan_detected", 1.0, ""),
    ("wall time of the adaptive run", "wall_time_s", 1.0, "s"),
)


def _demo(args) -> int:
    from deburr_drake.cell.truth import contact_truth
    from deburr_drake.runs import demo
    from deburr_drake.runs.passes import run

    scenario = _load(args)
    if args.duration is not None:
        _check_duration(args.duration)
        if args.duration <= demo.SETTLE_TIME:
            _bad(
                f"--duration = {args.duration!r} is too short for the demo:"
                f" allowed more than its {demo.SETTLE_TIME:g} s settling "
                "time (it measures after it)"
            )
    duration = 5.0 if args.duration is None else args.duration
    print(
        f"deburr-drake demo: point-mass testbed, scenario "
        f"'{scenario.name}', {duration:g} s"
    )
    truth = contact_truth(scenario)
    print(
        "contact truth (Drake hydroelastic + process threshold): "
        f"||f_n(delta*)|| = {truth.force_at_desired_depth:.3f} N, "
        f"local stiffness {truth.local_stiffness / 1e3:.2f} N/mm"
    )
    print("run 1/2: adaptation off, estimates at the truth (eq. 8)")
    frozen = run(
        demo.frozen_adaptation(scenario, truth),
        min(duration, 3.0),
        progress=_progress,
    )
    print("run 2/2: adaptive (estimator and fuzzy rules on)")
    log = run(scenario, duration, progress=_progress)
    summary = demo.summarize(log, truth, frozen)
    print()
    for label, key, scale, unit in _DEMO_ROWS:
        print(f"  {label:42s} {summary[key] * scale:10.4f} {unit}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(summary, f, indent=2)
    return 0


def _add_demo_parser(subparsers):
    p = subparsers.add_parser(
        "demo",
        help="run the point-mass testbed and print its convergence numbers",
    )
    _scenario_arguments(
        p, "point_mass", "simulated seconds of the adaptive run (default 5)"
    )
    p.add_argument("--json", default=None, help="also write the numbers")
    p.set_defaults(func=_demo)
