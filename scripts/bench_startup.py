"""What a sweep run costs before and after its simulation, against the
simulation itself: imports (once per worker process), loading the scenario
from its text, the reach check (inverse kinematics along the edge; the
sweep does it once per run before any starts), the diagram build (with a
tube radius whose ring mesh is not cached yet, then the same again),
Simulator initialization with the first 2.5 ms, the rest of the run, the
metrics and the files.

    python scripts/bench_startup.py [DURATION]   # default 10 s
"""

import random
import sys
import tempfile
import time

T0 = time.perf_counter()
from pydrake.common.yaml import yaml_dump_typed  # noqa: E402

from deburr_drake.cell.diagram import make_deburring_diagram  # noqa: E402
from deburr_drake.cell.reach import check_part_in_reach  # noqa: E402
from deburr_drake.config import load_scenario  # noqa: E402  # noqa: E402
from deburr_drake.runs import report  # noqa: E402
from deburr_drake.runs.pass_metrics import pass_metrics  # noqa: E402
from deburr_drake.runs.simulation import simulate  # noqa: E402
from deburr_drake.sweep import scenario_from_text  # noqa: E402


def main(argv):
    duration = float(argv[0]) if argv else 10.0
    times = {"imports (once per worker)": time.perf_counter() - T0}

    def lap(name, start):
        times[name] = time.perf_counter() - start
        return time.perf_counter()

    # A radius no run has used: its ring mesh is generated and cached.
    radius = 0.030 + random.randint(1, 10**6) * 1e-12
    base = load_scenario(
        "paper", text=f"part: {{edge: {{inner_radius: {radius!r}}}}}"
    )
    base.simulation.duration = duration
    text = yaml_dump_typed(base)
    t = time.perf_counter()
    scenario = scenario_from_text(text)
    t = lap("scenario from its YAML text", t)
    check_part_in_reach(scenario)
    t = lap("reach check (IK, 25 points; before the sweep)", t)
    diagram = make_deburring_diagram(scenario=scenario)
    t = lap("diagram build, new ring mesh", t)
    diagram = make_deburring_diagram(scenario=scenario)
    t = lap("diagram build, mesh cached", t)
    first = simulate(
        make_deburring_diagram(scenario=scenario), scenario, duration=0.0025
    )
    times["initialize + first 2.5 ms"] = first.wall_time
    t = time.perf_counter()
    log = simulate(diagram, scenario)
    t = lap(f"simulate {duration:g} s", t)
    values = pass_metrics(log, only_cut=True)
    t = lap("metrics", t)
    with tempfile.TemporaryDirectory() as tmp:
        report.write_run(log, tmp, values)
    lap("logs.npz + metrics.json", t)
    run = sum(
        v
        for k, v in times.items()
        if not k.startswith(
            ("imports", "reach", "diagram build, new", "initialize")
        )
    )
    print(f"{'step':48s} {'s':>7s} {'% of a run':>10s}")
    for name, value in times.items():
        print(f"{name:48s} {value:7.3f} {100 * value / run:9.1f} %")
    print(f"{'a run in a warm worker (cached mesh)':48s} {run:7.3f}")


if __name__ == "__main__":
    main(sys.argv[1:])
