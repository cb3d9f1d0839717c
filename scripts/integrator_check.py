#!/usr/bin/env python3
"""Does the integrator setting change the result? Runs one scenario for the
same simulated time with cenic in fixed 2.5 ms steps (the paper scenarios'
default) and with cenic's error control at a target accuracy, and prints,
for each, the means the metrics are built from and the cost.

    python scripts/integrator_check.py [--scenario paper] [--duration 12]
"""

import argparse
import copy

import numpy as np

from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.config import load_scenario
from deburr_drake.math import metrics
from deburr_drake.runs.simulation import simulate


def summarize(log, start):
    chamfer, process = log["chamfer"], log["process"]
    late = metrics.window(chamfer["t"], start)
    late_p = metrics.window(process["t"], start)
    command = log["command"]
    late_c = metrics.window(command["t"], start)
    return {
        "depth mean (mm)": 1e3 * np.mean(chamfer["delta"][late]),
        "normal force mean (N)": np.mean(chamfer["f_n"][late]),
        "chamfering force mean (N)": np.mean(process["f_t"][late_p]),
        "feed mean (mm/s)": 1e3
        * metrics.mean_speed(
            command["t"][late_c], command["arc_position"][late_c]
        ),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--scenario", default="paper")
    ap.add_argument("--duration", type=float, default=12.0, help="s")
    ap.add_argument(
        "--start", type=float, default=2.0, help="s, averages from here on"
    )
    ap.add_argument("--accuracy", type=float, default=1e-4)
    args = ap.parse_args()
    base = load_scenario(args.scenario)
    variants = {}
    fixed = copy.deepcopy(base)
    fixed.simulation.error_control = False
    fixed.simulation.max_step = 0.0025
    variants["cenic, fixed 2.5 ms steps"] = fixed
    controlled = copy.deepcopy(base)
    controlled.simulation.error_control = True
    controlled.simulation.accuracy = args.accuracy
    controlled.simulation.max_step = 0.0025
    variants[f"cenic, error control at {args.accuracy:g}"] = controlled
    results = {}
    for name, scenario in variants.items():
        log = simulate(
            make_deburring_diagram(scenario=scenario),
            scenario,
            duration=args.duration,
        )
        results[name] = summarize(log, args.start)
        print(
            f"{name}: {log.sim_time:.1f} s simulated in "
            f"{log.wall_time:.1f} s wall, {log.steps} steps"
        )
        for key, value in results[name].items():
            print(f"  {key:28s} {value:10.4f}")
    a, b = results.values()
    print("relative difference (second - first) / first:")
    for key in a:
        print(f"  {key:28s} {(b[key] - a[key]) / a[key]:+10.2e}")


if __name__ == "__main__":
    main()
