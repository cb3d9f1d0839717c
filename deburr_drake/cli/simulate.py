"""``deburr-drake simulate``: one deburring pass, its logs, metrics and
figures."""

from __future__ import annotations

import sys

import numpy as np

from deburr_drake.cli.common import (
    _EXIT_HELP,
    _bad,
    _check_duration,
    _check_writable_target,
    _exit_code,
    _load,
    _planned,
    _preflight_argument,
    _print_metrics,
    _progress,
    _scenario_arguments,
    _write_resolved,
)

#: What ``simulate`` writes into its output directory.
_OUTPUTS = ("logs.npz", "metrics.json")


def _simulate(args) -> int:
    from pathlib import Path

    from deburr_drake.runs.figure_process import FigureProcess

    scenario = _load(args)
    if args.duration is not None:
        _check_duration(args.duration)
        scenario.simulation.duration = args.duration
        scenario.validate()
    if not (args.progress_interval > 0 and np.isfinite(args.progress_interval)):
        _bad(
            f"--progress-interval = {args.progress_interval!r} is "
            "invalid: allowed a finite number > 0 (simulated seconds)"
        )
    out = Path(args.out or f"out/{scenario.name}")
    _check_writable_target(
        out, "--out", args.force, is_dir=True, names=_OUTPUTS
    )
    if scenario.job.file:
        return _simulate_job(args, scenario, out)
    if args.record:
        _check_writable_target(
            args.record, "--record", args.force, is_dir=False
        )
    # Started once the input is accepted (before Meshcat's threads): it
    # imports matplotlib while this process plans and runs, and draws the
    # figures once the logs are written.
    with FigureProcess() as drawer:
        return _plan_and_run(args, scenario, out, drawer)


def _plan_and_run(args, scenario, out, drawer) -> int:
    import signal

    from deburr_drake.cell.diagram import make_deburring_diagram

    # One plan and one diagram: the pre-flight runs on the run's.
    meshcat = _meshcat(args)
    plan, diagram, found = _planned(
        args,
        scenario,
        lambda plan: make_deburring_diagram(plan, meshcat=meshcat),
        meshcat,
    )
    scenario = plan.scenario
    passes = scenario.simulation.stop_after_passes
    print(
        f"deburr-drake simulate: scenario '{scenario.name}' "
        f"({scenario.robot.model}, m = {scenario.controller.fuzzy.order}), "
        f"up to {scenario.simulation.duration:g} s"
        + (f" or {passes:g} pass(es)" if passes else "")
        + f", output {out}/",
        flush=True,
    )
    if hasattr(plan.contour, "describe_rule"):
        print(plan.contour.describe_rule(), flush=True)
    received, running = [], [True]

    def on_signal(number, frame):
        # Only a flag: the simulator's monitor stops the run after the
        # current step, and everything logged so far is written. A second
        # signal while the run still winds down stops waiting for it; once
        # the outputs are being written, signals wait for them.
        if received and running[0]:
            raise KeyboardInterrupt
        received.append(number)

    previous = {
        n: signal.signal(n, on_signal) for n in (signal.SIGINT, signal.SIGTERM)
    }
    try:
        return _run_and_write(
            args,
            plan,
            diagram,
            meshcat,
            out,
            (received, running),
            found,
            drawer,
        )
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)


def _simulate_job(args, scenario, out) -> int:
    """A scenario with a ``job:`` section: the whole job, one simulation
    (deburr_drake.runs.job_run), and its report
    (deburr_drake.runs.job_report): metrics.json, each edge's logs and
    figures in ``edge_<index>/``, the replay with --record."""
    from deburr_drake.cell.job_cell import plan_job_cell
    from deburr_drake.runs.job_report import (
        job_checks,
        job_report,
        report_lines,
        write_job_report,
    )
    from deburr_drake.runs.job_run import run_job

    if args.record:
        _check_writable_target(
            args.record, "--record", args.force, is_dir=False
        )
    plan = plan_job_cell(scenario)
    cuts = ", ".join(str(c.index) for c in plan.job.cuts)
    print(
        f"deburr-drake simulate: job '{scenario.name}', edges {cuts} "
        f"({len(plan.job.refused)} refused), up to "
        f"{scenario.simulation.duration:g} s, output {out}/",
        flush=True,
    )
    for _, why in plan.job.refused:
        print(f"  refused: {why}", flush=True)
    meshcat = _meshcat(args)
    if args.record:
        meshcat.StartRecording(frames_per_second=10.0)
    result = run_job(
        plan,
        progress=_progress,
        progress_interval=args.progress_interval,
        meshcat=meshcat,
    )
    log = result.log
    print(
        f"\nstopped at t = {log.stop_time:.3f} s: {log.stop_reason}"
        + (f" ({log.stop_detail})" if log.stop_detail else ""),
        flush=True,
    )
    if args.record:
        _write_replay(meshcat, args.record)
    report = job_report(log, plan.job)
    files = write_job_report(report, log, out, label=scenario.name)
    for index, failure in files["failures"].items():
        print(
            f"deburr-drake: edge {index}: no figures: {failure}",
            file=sys.stderr,
        )
    print("\n".join(report_lines(report, job_checks(report))))
    print(f"\nwrote {files['metrics']} and {len(log.edges)} edge folders")
    return _exit_code(log, None)


def _meshcat(args):
    """A Meshcat with --meshcat (its URL printed) or --record, else
    None."""
    if not (args.meshcat or args.record):
        return None
    from pydrake.geometry import Meshcat

    meshcat = Meshcat()
    if args.meshcat:
        print(f"Meshcat: {meshcat.web_url()}", flush=True)
    return meshcat


def _run_and_write(
    args, plan, diagram, meshcat, out, flags, found, drawer
) -> int:
    import signal

    from deburr_drake.runs import report
    from deburr_drake.runs.passes import run_pass

    received, running = flags
    # The run and its metrics; a signal in ``received`` stops it after the
    # current step. A run that stopped before the pass was done: the finish
    # over the bins the tool reached.
    if args.record:
        meshcat.StartRecording(frames_per_second=10.0)
    try:
        result = run_pass(
            plan,
            diagram=diagram,
            progress=_progress,
            progress_interval=args.progress_interval,
            should_stop=lambda: "interrupted" if received else None,
        )
    finally:
        running[0] = False
    log, values = result.log, result.metrics
    signal_number = received[0] if received else None
    if signal_number is not None and log.stop_reason == "interrupted":
        log.stop_detail = signal.Signals(signal_number).name
    print(
        f"\nstopped at t = {log.stop_time:.3f} s: {log.stop_reason}"
        + (f" ({log.stop_detail})" if log.stop_detail else ""),
        flush=True,
    )
    if result.no_truth:
        print(
            f"deburr-drake: no contact truth: {result.no_truth}",
            file=sys.stderr,
        )
    # The replay, however the run ended.
    if args.record:
        _write_replay(meshcat, args.record)
    # logs.npz, metrics.json, the scenario as run and the figures.
    files = report.write_run(log, out, values)
    _write_resolved(out, plan.scenario, found)
    pngs = _figures(drawer, files["logs"], out, plan.scenario)
    # The metrics and what was written.
    print()
    _print_metrics(values)
    written = "scenario.yaml" + (
        " (the designed gains)" if found is not None and found.design else ""
    )
    if found is not None:
        written += ", preflight.json"
    print(
        f"\nwrote {files['logs']}, {files['metrics']}, {written} and "
        f"{len(pngs)} figures in {out}/"
    )
    return _exit_code(log, signal_number)


def _write_replay(meshcat, path):
    """The HTML replay; a failure is said, not raised (the run's outputs
    still get written)."""
    from deburr_drake.runs.replay import write_recording

    try:
        path = write_recording(meshcat, path)
        print(f"wrote the replay {path}")
    except Exception as e:
        print(
            f"deburr-drake: could not write the replay: {e}",
            file=sys.stderr,
        )


def _figures(drawer, logs_path, out, scenario):
    """The run's figures from logs.npz; none (said on stderr) when the run
    is too short to draw."""
    label = f"{scenario.name} (m = {scenario.controller.fuzzy.order})"
    paths, failure = drawer.draw(logs_path, out, label)
    if failure is not None:
        print(f"deburr-drake: no figures: {failure}", file=sys.stderr)
    return paths


def _add_simulate_parser(subparsers):
    p = subparsers.add_parser(
        "simulate",
        help="run a deburring scenario (the paper's experiment by default)",
        epilog=_EXIT_HELP,
    )
    _scenario_arguments(
        p, "paper", "simulated seconds at most (default: the scenario's)"
    )
    p.add_argument(
        "--out", default=None, help="output directory (default out/<scenario>)"
    )
    p.add_argument(
        "--progress-interval",
        type=float,
        default=5.0,
        help="simulated seconds between progress lines",
    )
    p.add_argument(
        "--meshcat",
        action="store_true",
        help="show the run live in Meshcat (prints the URL)",
    )
    p.add_argument(
        "--record",
        default=None,
        metavar="PATH.html",
        help="write a self-contained HTML replay of the run",
    )
    p.add_argument(
        "--force",
        action="store_true",
        help="overwrite existing logs.npz / metrics.json in "
        "--out and an existing --record file",
    )
    _preflight_argument(p)
    p.set_defaults(func=_simulate)
