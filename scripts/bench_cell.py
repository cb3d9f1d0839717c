#!/usr/bin/env python3
"""Wall time of the deburring cell after the start-up: five windows of
1.5 s simulated, best and median, as seconds per simulated second, per
integrator step and per 80 s pass (compare the last with
scripts/bench_floor.py's). The host's speed varies by tens of percent from
minute to minute; compare runs made side by side (alternate them).

``--split`` then runs one more window under cProfile and prints where a
control sample's time goes: the step and the port evaluations (the self
time of ``AdvanceTo`` and ``Eval``: the physics, the framework's dispatch
into Python, the C++ work an evaluation starts, such as the plant's forward
dynamics at the sample), the other pydrake calls the Python bodies make
(kinematics, state access), and the Python bodies by module. The first is
what the cell would cost if every Python system computed nothing (the
profiler adds its time at Python calls, not inside C++): set it against
scripts/bench_floor.py's ms per step.

    python scripts/bench_cell.py [--scenario paper] [--scenario-text YAML]
        [--split]
"""

import argparse
import collections
import cProfile
import pstats
import statistics
import time

from pydrake.common import RandomGenerator

from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.config import load_scenario
from deburr_drake.runs.simulation import make_simulator


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--scenario", default="paper")
    ap.add_argument(
        "--scenario-text", default=None, help="YAML overrides of the scenario"
    )
    ap.add_argument("--windows", type=int, default=5)
    ap.add_argument("--window", type=float, default=1.5, help="s simulated")
    ap.add_argument(
        "--split",
        action="store_true",
        help="one more window under cProfile: the C++ side "
        "against the Python bodies, per control sample",
    )
    args = ap.parse_args()
    scenario = load_scenario(args.scenario, text=args.scenario_text)
    diagram = make_deburring_diagram(scenario=scenario)
    simulator = make_simulator(diagram, scenario)
    context = simulator.get_mutable_context()
    diagram.SetRandomContext(
        context, RandomGenerator(scenario.sensor.noise_seed)
    )
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
    label = args.scenario + (
        f" + {args.scenario_text!r}" if args.scenario_text else ""
    )
    print(
        f"{label}: {rate:.0f} steps per simulated second; "
        f"{1e3 * best:.3f} ms per step at best, {1e3 * median:.3f} median"
    )
    print(
        f"s per simulated second: {min(per_second):.3f} at best, "
        f"{statistics.median(per_second):.3f} median"
    )
    print(
        f"an 80 s pass: {80 * min(per_second):.1f} s at best, "
        f"{80 * statistics.median(per_second):.1f} s median"
    )
    if args.split:
        samples = args.window / scenario.controller.control_period
        print_split(simulator, t + args.window, samples)


STEP = "the step and the port evaluations"


def _where(key) -> str:
    """The side of a cProfile entry: C++ (a pydrake built-in), numpy, a
    deburr_drake module, or other Python."""
    filename, _, name = key
    if filename == "~":
        if name.endswith((".AdvanceTo>", ".Eval>")):
            return STEP
        if "pydrake" in name:
            return "pydrake calls of the bodies"
        return "numpy" if "numpy" in name else "Python built-ins"
    if "/deburr_drake/" in filename:
        return "deburr_drake/" + filename.split("/deburr_drake/")[-1]
    return "numpy" if "/numpy/" in filename else "other Python"


def print_split(simulator, t_end, samples):
    """Advances to ``t_end`` under cProfile; prints self time per control
    sample by side (:func:`_where`)."""
    profile = cProfile.Profile()
    wall = time.perf_counter()
    profile.enable()
    simulator.AdvanceTo(t_end)
    profile.disable()
    wall = time.perf_counter() - wall
    sides = collections.Counter()
    for key, (_, _, self_time, _, _) in pstats.Stats(profile).stats.items():
        sides[_where(key)] += self_time
    bodies = wall - sides[STEP]
    print(
        f"under cProfile: {1e3 * wall / samples:.3f} ms per control "
        f"sample; {STEP} {1e3 * sides[STEP] / samples:.3f}, the Python "
        f"systems' bodies {1e3 * bodies / samples:.3f}:"
    )
    for side, seconds in sides.most_common():
        if side != STEP and seconds / samples > 2e-6:
            print(f"  {1e3 * seconds / samples:.3f} ms  {side}")


if __name__ == "__main__":
    main()
