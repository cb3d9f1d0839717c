"""The example job run end to end and held to its rules (a check, exit 1
on a miss).

Plans the job of ``--scenario`` (examples/block_job.yaml: the machined
block on the 6-joint arm), simulates it once (every edge cut, the moves
between them), and writes its report to ``--out``: metrics.json
(``edges`` and ``job``), each edge's logs.npz and Figs. 8-12 under
``edge_<index>/``, and the replay of the whole job (``--record``). It
prints per edge its coverage, depth and force RMS, largest f_t, feed and
how its cut ended; the job's ending, cycle time (cutting and moving),
tool-tip travel, the planned and the simulated least clearance of the
moves, and the wall time. The rules: every edge's coverage >= 0.99,
depth RMS <= 0.05 mm and f_t RMS <= 1.5 N; the job complete (no guard);
the simulated least clearance on the moves above 0.

    python scripts/job_report.py [--scenario S] [--out DIR] [--record
        PATH.html | --no-record] [--no-figures] [--duration S]
"""

import argparse
from pathlib import Path
import sys
import time

ROOT = Path(__file__).resolve().parents[1]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--scenario", default=str(ROOT / "examples" / "block_job.yaml")
    )
    parser.add_argument("--out", default="out/block_job")
    parser.add_argument(
        "--record",
        default=None,
        help="the replay's HTML file (default OUT/replay.html)",
    )
    parser.add_argument("--no-record", action="store_true")
    parser.add_argument("--no-figures", action="store_true")
    parser.add_argument(
        "--duration", type=float, default=None, help="s, at most"
    )
    args = parser.parse_args(argv)
    started = time.perf_counter()

    from deburr_drake.cell.job_cell import plan_job_cell
    from deburr_drake.config import load_scenario
    from deburr_drake.runs.job_report import (
        job_checks,
        job_report,
        report_lines,
        write_job_report,
    )
    from deburr_drake.runs.job_run import run_job
    from deburr_drake.runs.replay import write_recording

    scenario = load_scenario(args.scenario)
    plan = plan_job_cell(scenario)
    planned = time.perf_counter() - started
    print(
        f"{scenario.name}: {len(plan.job.cuts)} edges planned in "
        f"{planned:.1f} s",
        flush=True,
    )
    meshcat = None
    if not args.no_record:
        from pydrake.geometry import Meshcat

        meshcat = Meshcat()
        meshcat.StartRecording(frames_per_second=10.0)
    result = run_job(
        plan,
        duration=args.duration,
        **({} if meshcat is None else {"meshcat": meshcat}),
        progress=lambda t, wall, feed: print(
            f"  t = {t:7.2f} s simulated, {wall:7.1f} s wall", flush=True
        ),
        progress_interval=10.0,
    )
    report = job_report(result.log, plan.job)
    out = Path(args.out)
    files = write_job_report(
        report,
        result.log,
        out,
        label=scenario.name,
        figures=not args.no_figures,
    )
    if meshcat is not None:
        replay = write_recording(meshcat, args.record or out / "replay.html")
        print(f"wrote the replay {replay}")
    for index, failure in files["failures"].items():
        print(f"edge {index}: no figures: {failure}", file=sys.stderr)
    checks = job_checks(report)
    print("\n".join(report_lines(report, checks)))
    print(
        f"whole script {time.perf_counter() - started:.1f} s wall "
        f"(plan {planned:.1f} s); wrote {files['metrics']}"
    )
    return 0 if all(c.ok for c in checks) else 1


if __name__ == "__main__":
    sys.exit(main())
