"""The paper's tube read from a CAD file against the paper's ring: one
full pass of `paper` and one of `examples/tube_stl.yaml` (the same tube as
models/parts/tube.stl, its top inner edge picked by a point, the pass
started where paper's starts), each metric of the finish, the forces, the
feed and the force model within 5 % of paper's (those that are zero on
paper: equal to within 1e-9). Prints the table and exits 1 on a miss.

    python scripts/tube_stl_check.py
"""

import math
from pathlib import Path
import sys

from check_table import report  # scripts/check_table.py

from deburr_drake.cell.plan import plan_cell
from deburr_drake.config import load_scenario
from deburr_drake.runs.passes import run_pass

TUBE_STL = Path(__file__).resolve().parents[1] / "examples" / "tube_stl.yaml"
# -, the share of paper's value the mesh part's may differ by
SHARE = 0.05
METRICS = (
    "chamfer_depth_rms_error_mm",
    "chamfer_depth_mean_error_mm",
    "chamfer_depth_max_error_mm",
    "depth_tracking_rms_error_mm",
    "chamfering_force_rms_error_N",
    "normal_force_rms_error_N",
    "feed_mean_off_burrs_mm_s",
    "feed_mean_on_burrs_mm_s",
    "force_prediction_error_rel",
    "predicted_force_at_desired_depth_N",
    "true_force_at_desired_depth_N",
    "edge_coverage",
    "burr_remaining_max_mm",
    "sim_time_s",
)


def _row(name, paper, tube):
    if paper == 0.0:
        return (f"{name} (paper 0)", tube, "== 0", abs(tube) <= 1e-9)
    ratio = tube / paper
    ok = math.isfinite(ratio) and abs(ratio - 1.0) <= SHARE
    return (
        f"{name} (paper {paper:.5g})",
        ratio,
        f"1 +- {SHARE:g}",
        ok,
    )


def main() -> int:
    runs = {}
    for key, scenario in (
        ("paper", load_scenario("paper")),
        ("tube_stl", load_scenario(str(TUBE_STL))),
    ):
        result = run_pass(plan_cell(scenario))
        metrics = dict(result.metrics)
        metrics["sim_time_s"] = result.log.sim_time
        runs[key] = (metrics, result.log.stop_reason)
    paper, tube = runs["paper"][0], runs["tube_stl"][0]
    rows = [_row(name, paper[name], tube[name]) for name in METRICS]
    stops = [runs[k][1] for k in ("paper", "tube_stl")]
    rows.append(
        (
            f"stop reasons equal ({stops[0]}, {stops[1]})",
            float(stops[0] == stops[1]),
            "== 1",
            stops[0] == stops[1] == "pass_complete",
        )
    )
    return report([("tube_stl / paper, one full pass each on arm5", rows)])


if __name__ == "__main__":
    sys.exit(main())
