#!/usr/bin/env python3
"""The region of attraction of the normal-force axis by sums of squares on
a reduced polynomial model (deburr_drake.analysis.region), at the operating
point `analyze` and `certify` use; prints it and writes region.json.

    python scripts/region_of_attraction.py --scenario paper --out /tmp/region
"""

import argparse
import json
from pathlib import Path

from deburr_drake.analysis.operating_point import find_operating_point
from deburr_drake.analysis.region import SOLVERS, normal_axis_region
from deburr_drake.config import load_scenario


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--scenario", default="paper")
    ap.add_argument("--out", type=Path, default=None)
    ap.add_argument("--solver", choices=sorted(SOLVERS), default="Clarabel")
    ap.add_argument("--eps", type=float, default=0.01)
    ap.add_argument("--bisections", type=int, default=8)
    ap.add_argument("--degree", type=int, default=2, help="contact fit")
    ap.add_argument(
        "--iterations", type=int, default=3, help="V-s iterations on P"
    )
    ap.add_argument(
        "--validate",
        type=float,
        nargs="*",
        default=[],
        help="depth-reference steps (mm) to run on the full Diagram",
    )
    ap.add_argument("--duration", type=float, default=1.0, help="s")
    ap.add_argument(
        "--max-step",
        type=float,
        default=None,
        help="s, the validation runs' integration step (default: the "
        "scenario's)",
    )
    args = ap.parse_args()
    op = find_operating_point(load_scenario(args.scenario))
    region = normal_axis_region(
        op,
        eps=args.eps,
        bisections=args.bisections,
        solver=args.solver,
        degree=args.degree,
        iterations=args.iterations,
        validation_steps=[d * 1e-3 for d in args.validate],
        validation_duration=args.duration,
        validation_max_step=args.max_step,
    )
    print(f"status {region['status']}  rho {region['rho']:.4g}")
    print(
        f"regions {region['regions']} ({region['regions_meeting_the_set']} "
        f"meet the set), largest Gram {region['largest_gram']}, solves "
        f"{region['solve_time_all_iterations_s']:.1f} s (the last P's "
        f"{region['solve_time_s']:.1f} s), total {region['time_s']:.1f} s"
    )
    for name, value in region["single_state_error"].items():
        extent = region["extent"][name]
        print(f"  {name:16s} alone +-{value:.4g}  extent +-{extent:.4g}")
    print(f"  contact loss inside: {region['contact_loss_inside']}")
    print(f"  ball radius by iteration: {region['ball_radius_history']}")
    print(f"  check: {region['check']}")
    for v in region["validation"]:
        print(
            f"  step {v['reference_step_m'] * 1e3:+.3f} mm "
            f"(inside: {v['inside_proven_region']}): depth diff "
            f"{v['depth_difference_max_m'] * 1e3:.4f} mm, force diff "
            f"{v['force_difference_max_n']:.3f} N, least depth "
            f"{v['least_depth_full_m'] * 1e3:.3f} / "
            f"{v['least_depth_reduced_m'] * 1e3:.3f} mm (full / reduced), "
            f"recovered {v['recovered_full']} / {v['recovered_reduced']}"
        )
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "region.json").write_text(json.dumps(region, indent=1))
        print(f"wrote {args.out / 'region.json'}")


if __name__ == "__main__":
    main()
