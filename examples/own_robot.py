"""Your own robot: the paper's cell with the arm read from a model file of
yours (URDF or SDF), set by the scenario field ``robot.model: <path>``.

Without ``--model`` this copies the shipped models/arm5.sdf to a temporary
directory and uses the copy, as a user's file would be used. The file needs
what the cell reads on the arm: a frame at the tool tip (``tool_tip``) on
the body that holds the tool, whose parent joint is a weld named
``ft_sensor`` (the force/torque sensor), and actuated joints (see
models/arm5.sdf, docs/own-robot.md and docs/python-api.md).

    python examples/own_robot.py --duration 3
    python examples/own_robot.py --model my_arm.sdf --duration 3
"""

import argparse
import os
from pathlib import Path
import shutil
import tempfile

import deburr_drake as dd
from deburr_drake.cell.models import models_dir

SHIPPED_ARM = models_dir() / "arm5.sdf"


def run(model_path, duration):
    # The YAML override, as in a scenario file or --scenario-text.
    scenario = dd.load_scenario(
        "paper", text=f"robot: {{model: '{Path(model_path).as_posix()}'}}"
    )
    log = dd.run(scenario, duration)
    return scenario, log, dd.pass_metrics(log, only_cut=True)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--model",
        default=None,
        help="your robot's .urdf or .sdf (default: a copy of models/arm5.sdf)",
    )
    parser.add_argument(
        "--duration",
        type=float,
        default=float(os.environ.get("DEBURR_EXAMPLE_DURATION", 3.0)),
        help="simulated seconds (default 3)",
    )
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        model = args.model
        if model is None:
            model = shutil.copy(SHIPPED_ARM, Path(tmp) / "my_arm.sdf")
        scenario, log, metrics = run(model, args.duration)
        print(f"robot.model = {scenario.robot.model}")
        print(
            f"stop: {log.stop_reason} at {log.stop_time:.2f} s; "
            f"{len(log['actuation']['value'][0])} actuated joints"
        )
        for key in (
            "contact_time_s",
            "normal_force_rms_error_N",
            "chamfering_force_rms_error_N",
            "depth_tracking_rms_error_mm",
        ):
            print(f"  {key:32s} {metrics[key]:10.4f}")


if __name__ == "__main__":
    main()
