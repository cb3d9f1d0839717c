"""Where a sweep's chamfer-depth error comes from, run by run, from each
run's logs.npz (after the transient): the tool's true depth against delta*
(the cutting process's, on the real part), the depth the controller
measures on the part it believes in (the observer's) against delta*, and
their difference (the part error seen along n1). Prints one row per run
with the study's parameters and the counts of runs within BOUND.

    python scripts/depth_split.py OUT [BOUND_MM]   # OUT: a sweep's --out
"""

import csv
from pathlib import Path
import sys

import numpy as np

from deburr_drake.runs.pass_metrics import TRANSIENT


def split(logs) -> dict:
    t = logs["chamfer.t"]
    if "meta.contact_start" not in logs:
        return {}
    late = t > float(logs["meta.contact_start"]) + TRANSIENT
    if not np.any(late):
        return {}
    d_star = float(logs["meta.desired_depth"])
    true = np.interp(t[late], logs["process.t"], logs["process.delta"])
    believed = logs["chamfer.delta"][late]

    def rms(x):
        return float(np.sqrt(np.mean(np.square(x)))) * 1e3

    return {
        "true_depth_rms_error_mm": rms(true - d_star),
        "believed_depth_rms_error_mm": rms(believed - d_star),
        "part_error_along_n1_rms_mm": rms(true - believed),
    }


def main(argv):
    out = Path(argv[0])
    bound = float(argv[1]) if len(argv) > 1 else 0.05
    with open(out / "results.csv") as f:
        rows = list(csv.DictReader(f))
    names = (
        "true_depth_rms_error_mm",
        "believed_depth_rms_error_mm",
        "part_error_along_n1_rms_mm",
    )
    print(
        "key               stop                 finish  "
        + "  ".join(n.split("_rms")[0][:16] for n in names)
    )
    table = []
    for row in rows:
        path = out / "runs" / row["key"] / "logs.npz"
        values = {}
        if path.exists():
            with np.load(path) as logs:
                values = split(dict(logs))
        table.append(values)
        finish = row.get("chamfer_depth_rms_error_mm") or "nan"
        print(
            f"{row['key']}  {row['stop_reason'][:20]:20s} "
            f"{float(finish):7.4f}  "
            + "  ".join(f"{values.get(n, np.nan):16.4f}" for n in names)
        )
    for n in names:
        v = np.array([t.get(n, np.nan) for t in table])
        print(
            f"{n}: {int(np.sum(v <= bound))}/{len(v)} runs <= {bound} mm "
            f"(median {np.nanmedian(v):.4f} mm)"
        )


if __name__ == "__main__":
    main(sys.argv[1:])
