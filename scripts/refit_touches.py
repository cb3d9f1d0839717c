"""The probe's fit redone on the touches recorded by earlier runs, with
several ``max_residual`` values: the touches kept and the registration's
error against the real edge (um), per run. Each argument is a run's
output directory (``deburr-drake simulate --out DIR`` with probing on).

    python scripts/refit_touches.py out/pocket out/boss \\
        --thresholds 40e-6 50e-6 80e-6
"""

import argparse
from pathlib import Path

import numpy as np

from deburr_drake.config import load_scenario
from deburr_drake.runs.probe_study import refit_touches


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("runs", nargs="+", type=Path)
    p.add_argument(
        "--thresholds",
        type=float,
        nargs="+",
        default=[4e-5, 5e-5, 8e-5, 1e-4],
        help="max_residual values (m)",
    )
    a = p.parse_args()
    print(
        "| run | "
        + " | ".join(
            f"{t * 1e6:.0f} um: kept, error (um)" for t in a.thresholds
        )
        + " |"
    )
    print("|---" * (len(a.thresholds) + 1) + "|")
    for run in a.runs:
        scenario = load_scenario(str(run / "scenario.yaml"))
        touches = np.load(run / "logs.npz")["touch_points.value"][-1]
        rows = refit_touches(scenario, touches, a.thresholds)
        print(
            f"| {run.name} | "
            + " | ".join(
                f"{r['kept']} of {r['touches']}, {r['error'] * 1e6:.0f}"
                for r in rows
            )
            + " |",
            flush=True,
        )


if __name__ == "__main__":
    main()
