"""Runs the paper scenario's controller, untuned, on the variations users
write (tube radius, burrs, desired depth and force, the straight edge) and
prints one line of metrics each. Usage:
    python scripts/variants.py [NAME ...]   (default: all; see VARIANTS)"""

import sys

from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.cell.truth import contact_truth
from deburr_drake.config import load_scenario
from deburr_drake.runs.pass_metrics import pass_metrics
from deburr_drake.runs.simulation import simulate

BURRS_2MM = (
    "process: {burrs: ["
    "{center_fraction: 0.125, height: 0.002},"
    "{center_fraction: 0.4583333, height: 0.002},"
    "{center_fraction: 0.7916667, height: 0.002}]}"
)

#: name -> (YAML overrides of the paper scenario, simulated seconds at most)
VARIANTS = {
    "straight_edge": ("part: {edge: {kind: straight, length: 0.1}}", 60.0),
    "radius_20mm": ("part: {edge: {inner_radius: 0.02}}", 40.0),
    "radius_60mm": ("part: {edge: {inner_radius: 0.06}}", 40.0),
    "burrs_2mm": (BURRS_2MM, 40.0),
    "no_burrs": ("process: {burrs: []}", 30.0),
    "depth_0.2mm": ("task: {desired_depth: 0.0002}", 30.0),
    "depth_1.0mm": ("task: {desired_depth: 0.001}", 30.0),
    "force_5N": ("task: {desired_chamfering_force: 5.0}", 30.0),
    "force_15N": ("task: {desired_chamfering_force: 15.0}", 30.0),
}

KEYS = (
    "completed_pass",
    "chamfer_depth_rms_error_mm",
    "depth_tracking_rms_error_mm",
    "chamfering_force_rms_error_N",
    "feed_mean_off_burrs_mm_s",
    "feed_mean_on_burrs_mm_s",
    "force_prediction_error_rel",
    "nan_detected",
    "sim_time_s",
    "wall_time_s",
)


def run(name: str) -> dict:
    text, duration = VARIANTS[name]
    scenario = load_scenario("paper", text=text)
    scenario.simulation.duration = duration
    log = simulate(make_deburring_diagram(scenario=scenario), scenario)
    truth = contact_truth(scenario)
    values = pass_metrics(
        log,
        true_force_at_desired_depth=truth.force_at_desired_depth,
        only_cut=True,
    )
    return values


def main(names) -> None:
    for name in names or VARIANTS:
        values = run(name)
        cells = " ".join(f"{k}={values[k]:.4g}" for k in KEYS)
        print(f"{name}: {cells}", flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
