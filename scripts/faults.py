"""The paper scenario under each fault the cell injects, DURATION simulated
seconds each (default 20), one row per fault: NaN seen, the largest true
normal force (the force sensor's own reading, before the injected faults,
along n1), the chamfer depth error on the real part (the cutting process's
surface-finish record over the bins cut after the transient), and why the
run stopped.

    python scripts/faults.py [DURATION] [NAME ...]
"""

import sys

import numpy as np

from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.config import load_scenario
from deburr_drake.math import metrics
from deburr_drake.runs.pass_metrics import pass_metrics
from deburr_drake.runs.simulation import simulate

FAULTS = {
    "none": "",
    "sensor bias +2 N along n1": "faults: {sensor_bias: [2.0, 0.0, 0.0]}",
    "sensor noise x10 (1 N)": "faults: {noise_scale: 10.0}",
    "dropout 1 s, hold": "faults: {dropouts: [{start: 5.0, duration: 1.0, "
    "mode: hold}]}",
    "dropout 0.5 s, zero": "faults: {dropouts: [{start: 5.0, duration: 0.5, "
    "mode: zero}]}",
    "believed radius +0.3 mm": "part_error: {radius: 0.0003}",
    "believed part 1 mm off in x": "part_error: {offset: [0.001, 0.0, 0.0]}",
    "believed part turned 0.2 rad": "part_error: {yaw: 0.2}",
    "part moves 0.3 mm along x at 10 s": "faults: {part_step: {time: 10.0, "
    "offset: [0.0003, 0.0, 0.0]}}",
    "sliding gain 2e4 (runaway)": "controller: {sliding_gain: "
    "[20000.0, 20000.0, 1500.0]}",
    # Taller than the cutter's 2 mm engagement below the edge (g = 23,100
    # N s/m on it, beyond the envelope's 2 mm: scripts/envelope.py).
    "burr 3 mm x 8 mm (> engagement)": "process: {burrs: [{center_fraction: "
    "0.1, length: 0.008, height: 0.003, thickness: 0.002}]}",
    "straight 10 mm edge, run off": "{part: {edge: {kind: straight, "
    "length: 0.01}}, process: {burrs: []}, "
    "simulation: {stop_after_passes: 0}}",
}


def run(name: str, duration: float) -> dict:
    scenario = load_scenario("paper", text=FAULTS[name] or None)
    log = simulate(
        make_deburring_diagram(scenario=scenario),
        scenario,
        duration=duration,
        progress_interval=duration,
    )
    ch = log["chamfer"]
    true_f_n = -np.einsum("ij,ij->i", log["tool_force"]["value"], ch["n1"])
    values = pass_metrics(log, only_cut=not log.completed_pass)
    return {
        "nan": log.stop_reason == "nan"
        or metrics.any_nan(
            *[v for b in log.signals.values() for v in b.values()]
        ),
        "max_f_n": float(np.max(true_f_n)) if true_f_n.size else np.nan,
        "depth_mean": values["chamfer_depth_mean_error_mm"],
        "depth_rms": values["chamfer_depth_rms_error_mm"],
        "stop": f"{log.stop_reason} at {log.stop_time:.2f} s",
    }


def main(argv):
    duration = float(argv[0]) if argv else 20.0
    names = argv[1:] or list(FAULTS)
    print(f"paper scenario, {duration:g} s each")
    print(
        f"| {'fault':30s} | NaN | max f_n (N) | depth error mean / RMS "
        f"(mm) | stop |"
    )
    print(f"|{'-' * 32}|-----|-------------|{'-' * 29}|------|")
    for name in names:
        r = run(name, duration)
        print(
            f"| {name:30s} | {'yes' if r['nan'] else 'no ':3s} | "
            f"{r['max_f_n']:11.2f} | {r['depth_mean']:+8.4f} / "
            f"{r['depth_rms']:7.4f}{' ' * 9}| {r['stop']} |",
            flush=True,
        )


if __name__ == "__main__":
    main(sys.argv[1:])
