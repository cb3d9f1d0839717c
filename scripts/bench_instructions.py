#!/usr/bin/env python3
"""Instructions per integrator step of the deburring cell, counted by
valgrind's callgrind over the first ``--duration`` simulated seconds (inside
Simulator.AdvanceTo only: no start-up, no figures). Unlike wall time on a
shared host, the count repeats exactly for the same code and inputs, so it
compares two versions of the code even when the machine's speed drifts.
Takes about 90 s for the default 0.5 s; needs valgrind.

    python scripts/bench_instructions.py [--scenario paper] [--duration 0.5]
        [--scenario-text YAML] [--floor]

--floor counts scripts/bench_floor.py's diagram instead (the physics alone,
one 2.5 ms step per sample, from its start): the cell's count minus the
floor's is what the Python loop and the logging cost.

Per simulated second is the figure to compare when the step changes
(e.g. --scenario-text 'simulation: {max_step: 0.0025}' against the
paper's two steps per 2.5 ms sample).
"""

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile

_CHILD = """
import sys
from pydrake.common import RandomGenerator
from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.config import load_scenario
from deburr_drake.runs.simulation import make_simulator
scenario = load_scenario(sys.argv[1], text=sys.argv[3] or None)
diagram = make_deburring_diagram(scenario=scenario)
simulator = make_simulator(diagram, scenario)
diagram.SetRandomContext(simulator.get_mutable_context(),
                         RandomGenerator(scenario.sensor.noise_seed))
simulator.Initialize()
simulator.AdvanceTo(float(sys.argv[2]))
print("steps", simulator.get_num_steps_taken())
"""

_FLOOR_CHILD = """
import sys
sys.path.insert(0, sys.argv[3])
from bench_floor import make_floor_simulator
simulator, _ = make_floor_simulator()
simulator.AdvanceTo(float(sys.argv[2]))
print("steps", simulator.get_num_steps_taken())
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--scenario", default="paper")
    ap.add_argument("--duration", type=float, default=0.5, help="s simulated")
    ap.add_argument(
        "--scenario-text", default="", help="YAML overrides of the scenario"
    )
    ap.add_argument(
        "--floor",
        action="store_true",
        help="count bench_floor.py's physics-only diagram",
    )
    args = ap.parse_args()
    if shutil.which("valgrind") is None:
        sys.exit(
            "bench_instructions: valgrind is not installed "
            "(apt-get install valgrind)"
        )
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "callgrind.out")
        run = subprocess.run(
            [
                "valgrind",
                "--tool=callgrind",
                "--collect-atstart=no",
                "--toggle-collect=*Simulator*AdvanceTo*",
                f"--callgrind-out-file={out}",
                sys.executable,
                "-c",
                _FLOOR_CHILD if args.floor else _CHILD,
                args.scenario,
                str(args.duration),
                os.path.dirname(os.path.abspath(__file__))
                if args.floor
                else args.scenario_text,
            ],
            capture_output=True,
            text=True,
        )
        if run.returncode != 0:
            sys.exit(f"bench_instructions: the run failed:\n{run.stderr}")
    steps = int(re.search(r"^steps (\d+)", run.stdout, re.M).group(1))
    total = int(re.search(r"Collected : (\d+)", run.stderr).group(1))
    label = (
        "floor (bench_floor.py)"
        if args.floor
        else (
            args.scenario
            + (f" + {args.scenario_text!r}" if args.scenario_text else "")
        )
    )
    print(
        f"{label}, first {args.duration:g} s: {steps} steps, "
        f"{total / 1e6:.1f} M instructions, "
        f"{total / steps / 1e6:.3f} M per step, "
        f"{total / args.duration / 1e9:.3f} G per simulated second"
    )


if __name__ == "__main__":
    main()
