"""A parameter study in a Python loop: the paper cell at several desired
chamfer depths, one row of metrics per run.

Each run loads the scenario, changes one field by its dotted name, builds
the diagram, simulates it and computes the pass metrics (after the 2 s
contact transient; a run of a few seconds gives about a second of them).

    python examples/parameter_study.py --duration 4 --values 0.3,0.5,0.7
    python examples/parameter_study.py --field controller.fuzzy.order \\
        --values 0,2
"""

import argparse
import os

import numpy as np

import deburr_drake as dd

#: Columns of the table: metric name -> header.
COLUMNS = {
    "depth_tracking_rms_error_mm": "depth err RMS (mm)",
    "normal_force_rms_error_N": "e_f RMS (N)",
    "chamfering_force_rms_error_N": "f_t err RMS (N)",
    "feed_mean_off_burrs_mm_s": "feed (mm/s)",
}


def study(scenario_name, field, values, duration, scale=1.0):
    """{value: (measured mean depth (m), metrics)} for each value of the
    field (given in the field's unit divided by ``scale``)."""
    rows = {}
    for value in values:
        scenario = dd.load_scenario(scenario_name)
        dd.set_field(scenario, field, value * scale)
        scenario.validate()
        log = dd.run(scenario, duration)
        metrics = dd.pass_metrics(log, only_cut=True)
        chamfer = log["chamfer"]
        late = chamfer["t"] >= metrics.get("contact_time_s", 0.0) + 2.0
        depth = (
            float(np.mean(chamfer["delta"][late]))
            if late.any()
            else float("nan")
        )
        rows[value] = (depth, metrics)
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="paper")
    parser.add_argument(
        "--field",
        default="task.desired_depth",
        help="scenario field by dotted name",
    )
    parser.add_argument(
        "--values",
        default="0.4,0.5,0.6",
        help="comma-separated values (mm for a depth)",
    )
    parser.add_argument(
        "--duration",
        type=float,
        default=float(os.environ.get("DEBURR_EXAMPLE_DURATION", 4.0)),
        help="simulated seconds per run (default 4; the paper's pass is "
        "about 80 s)",
    )
    args = parser.parse_args(argv)
    values = [float(v) for v in args.values.split(",")]
    # Depths are given in mm on the command line; the scenario is SI.
    scale = 1e-3 if args.field.endswith("depth") else 1.0
    if args.field.endswith("order"):
        values = [int(v) for v in values]
    rows = study(args.scenario, args.field, values, args.duration, scale)
    header = f"{args.field:>24s} | {'mean depth (mm)':>15s} | " + " | ".join(
        f"{h:>18s}" for h in COLUMNS.values()
    )
    print(header)
    print("-" * len(header))
    for value, (depth, metrics) in rows.items():
        print(
            f"{value:>24g} | {depth * 1e3:15.4f} | "
            + " | ".join(
                f"{metrics.get(k, float('nan')):18.4f}" for k in COLUMNS
            )
        )


if __name__ == "__main__":
    main()
