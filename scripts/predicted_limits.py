"""The predicted stability limits of a scenario's operating point: where
rho of the one-period map crosses 1 (bisection,
:func:`deburr_drake.analysis.validation.predicted_boundary`) for the
sliding gain on the fuzzy axes, the orientation gain (all three) and the
sensor cutoff, the operating point found by ``analyze`` at the given
numerics (its maps integrate the period at them).

    python scripts/predicted_limits.py --scenario paper --numerics refined
"""

import argparse
import json
import time

from deburr_drake.analysis.analyze_run import analyze
from deburr_drake.analysis.validation import (
    PARAMETERS,
    Parameter,
    predicted_boundary,
    simulated_boundary,
)
from deburr_drake.config import load_scenario


def orientation_gain() -> Parameter:
    return Parameter(
        "controller.orientation_gain[all]",
        "N m s/rad",
        lambda v: {f"controller.orientation_gain[{i}]": v for i in range(3)},
        ranges={"arm5": (10.0, 20000.0)},
    )


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scenario", default="paper")
    p.add_argument("--text", default=None)
    p.add_argument(
        "--numerics", choices=("refined", "shipped"), default="refined"
    )
    p.add_argument("--until", type=float, default=6.0)
    p.add_argument(
        "--at", type=float, default=None, help="operating point time (s)"
    )
    p.add_argument(
        "--frozen-runs",
        action="store_true",
        help="also the limit of 1 s kicked runs from the operating point "
        "(adaptation frozen, outer loop live: simulated_boundary)",
    )
    p.add_argument("--tolerance", type=float, default=0.01)
    p.add_argument(
        "--only", nargs="+", default=None, help="sliding orientation cutoff"
    )
    p.add_argument("--json", default=None)
    args = p.parse_args(argv)
    scenario = load_scenario(args.scenario, text=args.text)
    t0 = time.perf_counter()
    result = analyze(
        scenario,
        at=args.at,
        until=args.until,
        robust=False,
        numerics=args.numerics,
    )
    op = result["_objects"]["op"]
    print(
        f"operating point at t = {op.context.get_time():.2f} s, "
        f"max_step {op.scenario.simulation.max_step:g} s, sample_mean "
        f"{op.scenario.process.sample_mean} ({time.perf_counter() - t0:.0f}"
        " s)",
        flush=True,
    )
    cutoff, sliding, _ = PARAMETERS(scenario)
    named = {
        "sliding": sliding,
        "orientation": orientation_gain(),
        "cutoff": cutoff,
    }
    rows = {}
    for key in args.only or list(named):
        par = named[key]
        lo, hi = par.ranges.get(scenario.robot.model, par.ranges["arm5"])
        t1 = time.perf_counter()
        limit = predicted_boundary(
            op, par, lo=lo, hi=hi, rel_tol=args.tolerance
        )
        rows[key] = {"parameter": par.name, "range": [lo, hi], "limit": limit}
        print(
            f"{par.name}: predicted limit {limit} {par.unit} in [{lo:g}, "
            f"{hi:g}] ({time.perf_counter() - t1:.0f} s)",
            flush=True,
        )
        if args.frozen_runs:
            t1 = time.perf_counter()
            frozen = simulated_boundary(
                op, par, lo=lo, hi=hi, rel_tol=args.tolerance
            )
            rows[key]["frozen_runs_limit"] = frozen
            print(
                f"{par.name}: frozen runs' limit {frozen} {par.unit} "
                f"({time.perf_counter() - t1:.0f} s)",
                flush=True,
            )
    if args.json:
        with open(args.json, "w") as f:
            json.dump(rows, f, indent=2)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
