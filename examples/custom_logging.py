"""Custom logging: record signals the cell does not log by default and
plot them.

``make_deburring_diagram(extra_logs=...)`` adds a VectorLogSink on any
output port, named by system and port; ``simulate`` returns it as
``log[name]`` (``t`` and ``value``). Here: the commanded feed of the outer
loop (``command_generator.feed``) and the arm's joint state
(``plant.state``), against the tool's measured speed along the edge.

    python examples/custom_logging.py --duration 4 --out out/custom_logging.png
"""

import argparse
import os

from matplotlib.figure import Figure
import numpy as np

import deburr_drake as dd

EXTRA_LOGS = {
    "feed": ("command_generator", "feed"),
    "joints": ("plant", "state"),
}


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenario", default="paper")
    parser.add_argument(
        "--duration",
        type=float,
        default=float(os.environ.get("DEBURR_EXAMPLE_DURATION", 4.0)),
        help="simulated seconds (default 4)",
    )
    parser.add_argument(
        "--out",
        default="out/custom_logging.png",
        help="where to write the plot",
    )
    args = parser.parse_args(argv)
    scenario = dd.load_scenario(args.scenario)
    diagram = dd.make_deburring_diagram(
        scenario=scenario, extra_logs=EXTRA_LOGS
    )
    log = dd.simulate(diagram, scenario, duration=args.duration)

    feed, joints, chamfer = log["feed"], log["joints"], log["chamfer"]
    # The tool's speed along the edge: xdot_p along n2 (the direction of
    # motion), from the standard chamfer log.
    speed = np.einsum("ij,ij->i", chamfer["xdot_p"], chamfer["n2"])
    nq = joints["value"].shape[1] // 2
    late = feed["t"] >= 0.5 * args.duration
    print(
        f"logged {len(feed['t'])} samples of 'feed' and "
        f"{joints['value'].shape} of 'joints' (q and v of {nq} joints)"
    )
    print(
        f"mean commanded feed over the second half: "
        f"{np.mean(feed['value'][late, 0]) * 1e3:.3f} mm/s; "
        f"tool speed along the edge "
        f"{np.mean(speed[chamfer['t'] >= 0.5 * args.duration]) * 1e3:.3f}"
        " mm/s"
    )
    print(
        "joint travel (rad): "
        + ", ".join(f"{np.ptp(joints['value'][:, i]):.4f}" for i in range(nq))
    )

    fig = Figure(figsize=(8, 5))
    ax0, ax1 = fig.subplots(2, 1, sharex=True)
    ax0.plot(feed["t"], feed["value"][:, 0] * 1e3, label="commanded feed v")
    ax0.plot(chamfer["t"], speed * 1e3, lw=0.8, label="tool speed along n2")
    ax0.set_ylabel("mm/s")
    ax0.legend()
    ax1.plot(joints["t"], joints["value"][:, :nq] - joints["value"][0, :nq])
    ax1.set_ylabel("q - q(0) (rad)")
    ax1.set_xlabel("t (s)")
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    fig.savefig(args.out)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
