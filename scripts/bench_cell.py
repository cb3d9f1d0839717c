#!/usr/bin/env python3
"""Wall time per integrator step of the deburring cell, after the start-up:
five windows of 1.5 s simulated, best and median, and what that makes for
an 80 s pass. The host's speed varies by tens of percent from minute to
minute; compare runs made side by side.

    python scripts/bench_cell.py [--scenario paper]
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
    ap.add_argument("--windows", type=int, default=5)
    ap.add_argument("--window", type=float, default=1.5, help="s simulated")
    args = ap.parse_args()
    scenario = load_scenario(args.scenario)
    diagram = make_deburring_diagram(scenario=scenario)
    simulator = make_simulator(diagram, scenario)
    context = simulator.get_mutable_context()
    diagram.SetRandomContext(context,
                             RandomGenerator(scenario.sensor.noise_seed))
    simulator.Initialize()
    t = 2.0
    simulator.AdvanceTo(t)
    per_step, steps_per_s = [], []
    for _ in range(args.windows):
        steps = simulator.get_num_steps_taken()
        wall = time.perf_counter()
        t += args.window
        simulator.AdvanceTo(t)
        wall = time.perf_counter() - wall
        steps = simulator.get_num_steps_taken() - steps
        per_step.append(wall / steps)
        steps_per_s.append(steps / args.window)
    best, median = min(per_step), statistics.median(per_step)
    rate = statistics.median(steps_per_s)
    print(f"{args.scenario}: {rate:.0f} steps per simulated second; "
          f"{1e3 * best:.3f} ms per step at best, {1e3 * median:.3f} median")
    print(f"an 80 s pass at that rate: {80 * rate * best:.1f} s at best, "
          f"{80 * rate * median:.1f} s median")


if __name__ == "__main__":
    main()
