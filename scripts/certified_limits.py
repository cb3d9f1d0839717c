"""The certified limits of a scenario, by bisection of `deburr-drake
certify` (:func:`deburr_drake.analysis.box_certificate.certified_limit`):
the largest sliding gain on the fuzzy axes (x1 and x2 together), the
largest orientation gain (all three) and the sensor cutoff's certified
end whose scenario is certified over the box (or the ``--box`` part of
it), printed beside analyze's simulated limits
(docs/stability-measurements.md). On this loop a higher cutoff is the
harder one (the paper scenario's note: 40 Hz diverged on its third burr
at an earlier design), so the bisection looks for the highest certified
cutoff, from a low end that must itself be certified.

    python scripts/certified_limits.py --scenario paper \\
        --limits sliding orientation cutoff --box stiffness k_c --json OUT \\
        --plot limits.png
    python scripts/certified_limits.py --scenario paper --limits orientation \\
        --scenario-text 'uncertainty: {fuzzy_slope: [0.05, 1.0]}'

Each trial is a whole certificate: the run to the operating point at the
trial's value, the maps, the program.
"""

import argparse
import json

from deburr_drake.analysis.box_certificate import certified_limit
from deburr_drake.analysis.limits_plot import (
    SIMULATED,
    plot_certified_limits,
    simulated_text,
)
from deburr_drake.config import ConfigError, load_scenario


def _limits(scenario):
    axes = scenario.controller.fuzzy.axes
    return {
        "sliding": (
            lambda v: {f"controller.sliding_gain[{a}]": v for a in axes},
            True,
            "N s/m",
        ),
        "orientation": (
            lambda v: {
                f"controller.orientation_gain[{i}]": v for i in range(3)
            },
            True,
            "N m s/rad",
        ),
        "cutoff": (
            lambda v: {"sensor.cutoff_frequency": v},
            True,
            "Hz",
        ),
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scenario", default="paper")
    parser.add_argument(
        "--scenario-text",
        default=None,
        help="YAML overrides of the scenario, e.g. its box: "
        "'uncertainty: {fuzzy_slope: [0.05, 1.0]}'",
    )
    parser.add_argument(
        "--limits",
        nargs="+",
        default=["sliding", "orientation", "cutoff"],
        choices=["sliding", "orientation", "cutoff"],
    )
    parser.add_argument(
        "--range",
        nargs=2,
        type=float,
        action="append",
        default=None,
        metavar=("LO", "HI"),
        help="the bracket of each limit, in --limits' order (default: "
        "sliding 400-8000, orientation 20-800, cutoff 2-199.9)",
    )
    parser.add_argument(
        "--box",
        nargs="*",
        default=None,
        help="certify over these box parameters only (certify --box)",
    )
    parser.add_argument(
        "--lowest",
        action="store_true",
        help="the lowest certified value instead of the highest (the "
        "bracket's high end must be certified): where a low gain's "
        "lightly damped mode is what the certificate cannot cover",
    )
    parser.add_argument("--numerics", default="shipped")
    parser.add_argument("--tolerance", type=float, default=0.02)
    parser.add_argument("--json", default=None)
    parser.add_argument(
        "--plot",
        default=None,
        help="a PNG of the trials against the simulated limits",
    )
    args = parser.parse_args()

    try:
        scenario = load_scenario(args.scenario, text=args.scenario_text)
    except ConfigError as error:
        raise SystemExit(f"certified_limits.py: {error}") from None
    defaults = {
        "sliding": (400.0, 8000.0),
        "orientation": (20.0, 800.0),
        "cutoff": (2.0, 199.9),
    }
    ranges = args.range or [defaults[name] for name in args.limits]
    out = {}
    for name, (lo, hi) in zip(args.limits, ranges):
        overrides, harder_above, unit = _limits(scenario)[name]
        harder_above = harder_above != args.lowest
        print(f"{name} ({unit}), bracket {lo:g}-{hi:g}:", flush=True)
        result = certified_limit(
            scenario,
            overrides,
            lo,
            hi,
            harder_above=harder_above,
            rel_tol=args.tolerance,
            numerics=args.numerics,
            only=args.box,
            progress=lambda m: print(f"  {m}", flush=True),
        )
        simulated = SIMULATED.get((scenario.name, name))
        print(
            f"  certified {result['certified']}, refused "
            f"{result['refused']} {unit}; simulated (refined): "
            f"{simulated_text(simulated, unit)}",
            flush=True,
        )
        out[name] = {**result, "unit": unit, "simulated": simulated}
    if args.plot:
        box = (
            "the whole box"
            if args.box is None
            else (" ".join(args.box) or "the nominal map")
        )
        if args.scenario_text:
            box += f" ({args.scenario_text})"
        plot_certified_limits(
            out, args.plot, title=f"{scenario.name}: certified over {box}"
        )
    if args.json:
        with open(args.json, "w") as f:
            json.dump(
                {
                    "scenario": scenario.name,
                    "scenario_text": args.scenario_text,
                    "box": args.box,
                    "limits": out,
                },
                f,
                indent=2,
            )


if __name__ == "__main__":
    main()
