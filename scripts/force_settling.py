"""How a run's chamfering force settles: the first full contact and the
fraction of samples within +-1 N of the desired force from 3 s after it,
off the burrs (deburr_drake.runs.pass_metrics.force_settling_metrics),
with the run's f_t RMS error and depth RMS error.

Use: ``python scripts/force_settling.py out/ur10_cell [more run folders]``
(each a ``deburr-drake simulate --out`` folder: logs.npz, scenario.yaml,
metrics.json)."""

import argparse
import json
from pathlib import Path

import numpy as np

from deburr_drake.config import load_scenario
from deburr_drake.runs.pass_metrics import force_settling_metrics
from deburr_drake.runs.simulation import RunLog


def run_log(folder: Path) -> RunLog:
    """The run in ``folder`` as a RunLog (signals and scenario)."""
    signals = {}
    with np.load(folder / "logs.npz") as z:
        for key in z.files:
            logger, _, block = key.partition(".")
            signals.setdefault(logger, {})[block] = z[key]
    t = signals["process"]["t"]
    return RunLog(
        load_scenario(str(folder / "scenario.yaml")),
        signals,
        sim_time=float(t[-1]) if len(t) else 0.0,
    )


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("runs", nargs="+", type=Path)
    args = parser.parse_args()
    for folder in args.runs:
        settling = force_settling_metrics(run_log(folder))
        run = json.loads((folder / "metrics.json").read_text())
        print(
            f"{folder}: full contact {settling['full_contact_time_s']:.3f} s, "
            f"f_t within 1 N from 3 s on "
            f"{settling['chamfering_force_settled_fraction']:.4f}, "
            f"f_t RMS {run['chamfering_force_rms_error_N']:.3f} N, "
            f"depth RMS {run['chamfer_depth_rms_error_mm']:.4f} mm"
        )
        for name, reason in settling.reasons.items():
            print(f"  {name}: {reason}")


if __name__ == "__main__":
    main()
