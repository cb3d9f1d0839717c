#!/usr/bin/env python3
"""Wall time of the deburring cell after the start-up: five windows of
1.5 s simulated, best and median, as seconds per simulated second, per
integrator step and per 80 s pass (compare the last with
scripts/bench_floor.py's). The host's speed varies by tens of percent from
minute to minute; compare runs made side by side (alternate them).

    python scripts/bench_cell.py [--scenario paper] [--scenario-text YAML]
"""

import argparse
import statistics
import time

from pydrake.common import RandomGenerator

from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.config import load_scenario
from deburr_drake.runs.simulation import make_simulator


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--scenario", default="paper")
    ap.add_argument("--scenario-text", default=None,
                    help="YAML overrides of the scenario")
    ap.add_argument("--windows", type=int, default=5)
    ap.add_argument("--window", type=float, default=1.5, help="s simulated")
    args = ap.parse_args()
    scenario = load_scenario(args.scenario, text=args.scenario_text)
    diagram = make_deburring_diagram(scenario=scenario)
    simulator = make_simulator(diagram, scenario)
    context = simulator.get_mutable_context()
    diagram.SetRandomContext(context,
                             RandomGenerator(scenario.sensor.noise_seed))
    simulator.Initialize()
    t = 2.0
    simulator.AdvanceTo(t)
    per_step, steps_per_s, per_second = [], [], []
    for _ in range(args.windows):
        steps = simulator.get_num_steps_taken()
        wall = time.perf_counter()
        t += args.window
        simulator.AdvanceTo(t)
        wall = time.perf_counter() - wall
        steps = simulator.get_num_steps_taken() - steps
        per_step.append(wall / steps)
        per_second.append(wall / args.window)
        steps_per_s.append(steps / args.window)
    best, median = min(per_step), statistics.median(per_step)
    rate = statistics.median(steps_per_s)
    label = args.scenario + (f" + {args.scenario_text!r}"
                             if args.scenario_text else "")
    print(f"{label}: {rate:.0f} steps per simulated second; "
          f"{1e3 * best:.3f} ms per step at best, {1e3 * median:.3f} median")
    print(f"s per simulated second: {min(per_second):.3f} at best, "
          f"{statistics.median(per_second):.3f} median")
    print(f"an 80 s pass: {80 * min(per_second):.1f} s at best, "
          f"{80 * statistics.median(per_second):.1f} s median")


if __name__ == "__main__":
    main()
