"""Predicted (rho of the one-period map = 1) against simulated (short runs
from the operating point) stability boundaries for the sensor's cutoff
frequency, the sliding gain on the fuzzy axes and the fuzzy surface's
slope, on the point-mass testbed and the paper arm.

    python scripts/validate_stability.py [--scenario point_mass paper]
        [--duration 1.0] [--tolerance 0.02] [--json OUT.json]
"""

import argparse
import json
import sys
import time

from deburr_drake.analysis import find_operating_point, validate_boundaries
from deburr_drake.config import ConfigError, load_scenario


def _fmt(x):
    if x is None:
        return "none in range"
    return f"{x:.4g}"


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", nargs="+",
                        default=["point_mass", "paper"])
    parser.add_argument("--duration", type=float, default=1.0,
                        help="simulated seconds per stability run")
    parser.add_argument("--tolerance", type=float, default=0.02,
                        help="relative bisection tolerance")
    parser.add_argument("--json", default=None)
    args = parser.parse_args(argv)
    table = {}
    try:
        for name in args.scenario:
            start = time.perf_counter()
            op = find_operating_point(load_scenario(name))
            rows = validate_boundaries(
                op, duration=args.duration, rel_tol=args.tolerance,
                progress=lambda m: print(f"  [{name}] {m}", flush=True))
            table[name] = rows
            print(f"\n{name} (operating point t = {op.time:.3f} s, "
                  f"{time.perf_counter() - start:.0f} s wall)")
            print(f"  {'parameter':52s} {'range':>15s} {'predicted':>13s} "
                  f"{'simulated':>13s} {'apart':>7s}")
            for r in rows:
                apart = (f"{100 * r['error_rel']:.1f} %"
                         if r["error_rel"] is not None else "-")
                rng = f"{r['range'][0]:g}-{r['range'][1]:g}"
                print(f"  {r['parameter'] + ' (' + r['unit'] + ')':52s} "
                      f"{rng:>15s} {_fmt(r['predicted']):>13s} "
                      f"{_fmt(r['simulated']):>13s} {apart:>7s}",
                      flush=True)
    except ConfigError as e:
        print(f"validate_stability: error: {e}", file=sys.stderr)
        return 2
    if args.json:
        with open(args.json, "w") as f:
            json.dump(table, f, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
