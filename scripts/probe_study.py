"""Touch probing studies: accuracy against the number of touches
and the sensor's noise, and the probe's qualification (25 repeats on the
reference ring, centre and radius fitted). Prints the tables.

    python scripts/probe_study.py accuracy --repeats 5
    python scripts/probe_study.py qualification --repeats 25
"""

import argparse

from deburr_drake.config import load_scenario
from deburr_drake.runs.probe_study import (
    probe_accuracy,
    probe_qualification,
    summarize,
)


def _row(label, s):
    print(
        f"| {label} | {s['runs']} | {s['centre_std_x_mm'] * 1e3:.1f} | "
        f"{s['centre_std_y_mm'] * 1e3:.1f} | "
        f"{s['centre_error_rms_mm'] * 1e3:.1f} | "
        f"{s['centre_error_max_mm'] * 1e3:.1f} | "
        f"{s['radius_error_mean_mm'] * 1e3:+.1f} +- "
        f"{s['radius_error_std_mm'] * 1e3:.1f} | "
        f"{s['fit_rms_mean_um']:.1f} | {s['kept_mean']:.1f} | "
        f"{s['probing_time_mean_s']:.1f} |",
        flush=True,
    )


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("study", choices=["accuracy", "qualification"])
    p.add_argument("--scenario", default="paper_localised")
    p.add_argument("--scenario-text", default=None)
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--points", type=int, nargs="+", default=[4, 6, 8, 12])
    p.add_argument(
        "--noise",
        type=float,
        nargs="+",
        default=[0.1, 0.3],
        help="sensor noise std per axis before the filter (N)",
    )
    p.add_argument("--max-offset", type=float, default=0.001)
    p.add_argument("--seed", type=int, default=0)
    a = p.parse_args()
    scenario = load_scenario(a.scenario, text=a.scenario_text)
    print(
        "| case | runs | centre std x (um) | centre std y (um) | "
        "centre error RMS (um) | max (um) | radius error (um) | "
        "fit RMS (um) | touches kept | probing (s) |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    if a.study == "qualification":
        _row(
            "reference ring, radius fitted",
            summarize(
                probe_qualification(scenario, repeats=a.repeats, seed=a.seed)
            ),
        )
        return
    for n in a.points:
        for sigma in a.noise:
            results = probe_accuracy(
                scenario,
                points=[n],
                noise=[sigma],
                repeats=a.repeats,
                max_offset=a.max_offset,
                seed=a.seed,
            )
            _row(f"N = {n}, noise {sigma:g} N", summarize(results))


if __name__ == "__main__":
    main()
