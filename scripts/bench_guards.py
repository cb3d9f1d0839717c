"""Cost of the runtime guards (deburr_drake.cell.guards) on the paper pass.

Runs the paper scenario for DURATION simulated seconds with the guards on
and off, alternating, REPEATS times each, and prints the process CPU time
of each run; with the guards on it also times the guard's own check (and
the drive saturation is measured with it: it is part of the 'on' runs).
The time spent inside the check against the run's time is the cost that
does not depend on what else the machine runs.

    python scripts/bench_guards.py [DURATION] [REPEATS]
"""

import sys
import time

from deburr_drake.cell import guards
from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.config import load_scenario
from deburr_drake.runs.simulation import simulate

DURATION = float(sys.argv[1]) if len(sys.argv) > 1 else 10.0
REPEATS = int(sys.argv[2]) if len(sys.argv) > 2 else 3

_inside = {"time": 0.0, "calls": 0}


def _timed(check):
    def timed(self, context, state):
        start = time.process_time()
        try:
            return check(self, context, state)
        finally:
            _inside["time"] += time.process_time() - start
            _inside["calls"] += 1

    return timed


guards.SafetyGuards._check = _timed(guards.SafetyGuards._check)
guards.SafetyGuards._check_torque = _timed(guards.SafetyGuards._check_torque)


def run(enabled: bool):
    text = (
        None if enabled else "guards: {enabled: false, saturate_effort: false}"
    )
    scenario = load_scenario("paper", text=text)
    diagram = make_deburring_diagram(scenario=scenario)
    _inside.update(time=0.0, calls=0)
    start = time.process_time()
    log = simulate(
        diagram, scenario, duration=DURATION, progress_interval=DURATION
    )
    cpu = time.process_time() - start
    return cpu, log


def main():
    results = {True: [], False: []}
    for k in range(REPEATS):
        for enabled in (True, False):
            cpu, log = run(enabled)
            results[enabled].append(cpu)
            inside = _inside["time"] if enabled else 0.0
            print(
                f"guards {'on ' if enabled else 'off'} run {k + 1}: "
                f"{cpu:6.2f} s CPU for {log.sim_time:g} s simulated "
                f"({log.steps} steps, stop {log.stop_reason})"
                + (
                    f"; inside the check {inside:.3f} s over "
                    f"{_inside['calls']} calls "
                    f"({inside / cpu * 100:.2f} %, "
                    f"{inside / max(_inside['calls'], 1) * 1e6:.1f} us "
                    "each)"
                    if enabled
                    else ""
                ),
                flush=True,
            )
    on, off = min(results[True]), min(results[False])
    print(
        f"best of {REPEATS}: on {on:.2f} s, off {off:.2f} s CPU: "
        f"{(on / off - 1) * 100:+.1f} % (the host's other load moves "
        "single runs by 10-25 %: trust the time inside the checks)"
    )


if __name__ == "__main__":
    main()
