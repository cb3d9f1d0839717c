"""The ``deburr-drake`` command line. Thin: parses arguments and calls the
library."""

from __future__ import annotations

import argparse
import json
import sys

import numpy as np

__all__ = ["main"]


def _load(args):
    from deburr_drake.config import load_scenario

    return load_scenario(args.scenario, text=args.scenario_text)


def _progress(t, wall, feed):
    print(
        f"  t = {t:6.2f} s simulated, {wall:6.1f} s wall, "
        f"feed {feed * 1e3:5.2f} mm/s",
        flush=True,
    )


#: Exit codes of ``deburr-drake`` (also in docs/scenarios.md, "Stop
#: reasons", and ``--help``).
EXIT_CODES = {
    "pass_complete": 0,
    "duration": 0,  # a normal ending
    "error": 1,  # an exception during the run (outputs written)
    # 2: bad input (nothing run or written)
    "guard": 3,  # a runtime guard stopped the run (outputs written)
    "nan": 4,  # Drake detected a NaN (outputs written)
    "diverged": 5,  # the numerical sanity check ended it (outputs written)
    "interrupted": 130,  # SIGINT (Ctrl-C); SIGTERM gives 143
}
_EXIT_HELP = (
    "exit codes: 0 the pass completed or the duration was reached; "
    "1 error during the run; 2 bad input (nothing run or written); "
    "3 a guard stopped the run; 4 NaN detected; 5 the run diverged "
    "(numerical sanity, guards or not); 130 interrupted "
    "(SIGINT), 143 terminated (SIGTERM). Every ending after the "
    "start writes logs.npz and metrics.json (stop_reason: "
    "pass_complete, duration, interrupted, guard:<name>, diverged, "
    "nan, error)."
)
#: What ``simulate`` writes into its output directory.
_OUTPUTS = ("logs.npz", "metrics.json")
#: What ``analyze`` writes into its output directory (those that apply).
_ANALYSIS_OUTPUTS = (
    "analysis.json",
    "poles.png",
    "rho_along_run.png",
    "bode_nyquist.png",
    "stability_map.png",
    "lyapunov.png",
)


def _bad(message: str):
    from deburr_drake.config import ConfigError

    raise ConfigError(message)


def _check_writable_target(
    path, what: str, force: bool, *, is_dir: bool, names=()
):
    """Refuses, before anything runs, a path that cannot be written or
    would overwrite existing results without ``--force``."""
    import os
    from pathlib import Path

    path = Path(path)
    if is_dir:
        if path.exists() and not path.is_dir():
            _bad(f"{what} {path} is not a directory")
        existing = [n for n in names if (path / n).exists()]
        if existing and not force:
            _bad(
                f"{what} {path} already holds {', '.join(existing)}: "
                "choose another directory or pass --force to overwrite"
            )
    else:
        if path.is_dir():
            _bad(f"{what} {path} is a directory: allowed a file path")
        if path.exists() and not force:
            _bad(f"{what} {path} already exists: pass --force to overwrite")
    probe = path if is_dir else path.parent
    while not probe.exists():
        if probe.parent == probe:
            break
        probe = probe.parent
    if not probe.is_dir():
        _bad(f"{what} {path} cannot be created: {probe} is not a directory")
    if not os.access(probe, os.W_OK | os.X_OK):
        _bad(f"{what} {path} cannot be written: no write permission in {probe}")


def _check_duration(duration):
    if not (np.isfinite(duration) and duration > 0):
        _bad(
            f"--duration = {duration!r} is invalid: allowed a finite "
            "number > 0 (simulated seconds)"
        )


def _exit_code(log, signal_number) -> int:
    import signal

    reason = log.stop_reason
    if reason == "interrupted" and signal_number == signal.SIGTERM:
        return 143
    return EXIT_CODES.get(reason.split(":", 1)[0], 1)


def _print_metrics(values: dict):
    import math

    reasons = getattr(values, "reasons", {})
    width = max(len(k) for k in values)
    missing = {}
    for key in sorted(values):
        v = values[key]
        if isinstance(v, float) and not math.isfinite(v):
            print(f"  {key:{width}s} {'n/a':>12s}")
            missing.setdefault(reasons.get(key, "not finite"), []).append(key)
        else:
            print(f"  {key:{width}s} {v:12.5g}")
    for reason, keys in missing.items():
        print(f"  n/a: {reason}: {', '.join(keys)}")


def _preflight(args, plan, diagram=None):
    """The designed gains (controller.design auto) proven and the sampled
    loop's check at the start pose (deburr_drake.analysis.preflight), on
    ``diagram`` (the run's) if given, unless --no-preflight; ConfigError
    (exit 2) if predicted unstable. Returns what it found, or None."""
    from deburr_drake.analysis.preflight import preflight

    if getattr(args, "no_preflight", False):
        print("pre-flight skipped (--no-preflight)", flush=True)
        return None
    return preflight(
        plan, diagram=diagram, say=lambda line: print(line, flush=True)
    )


def _planned(args, scenario, diagram=None, meshcat=None):
    """(plan, diagram, found): the scenario planned (the reach checked),
    its pre-flight (None with --no-preflight) on ``diagram`` if given;
    where the pre-flight scaled the design down, the plan it checked and,
    if a diagram was given, one built from it."""
    from deburr_drake.cell.diagram import make_deburring_diagram
    from deburr_drake.cell.plan import plan_cell

    plan = plan_cell(scenario)
    if diagram is not None:
        diagram = diagram(plan)
    found = _preflight(args, plan, diagram)
    if found is not None and found.plan is not plan:
        plan = found.plan
        if diagram is not None:
            diagram = make_deburring_diagram(plan, meshcat=meshcat)
    return plan, diagram, found


def _write_resolved(out, scenario, found):
    """scenario.yaml (the scenario as run: the designed gains written) and,
    after a pre-flight, preflight.json, so the run can be repeated."""
    from pathlib import Path

    from pydrake.common.yaml import yaml_dump_typed

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "scenario.yaml").write_text(yaml_dump_typed(scenario))
    if found is not None:
        (out / "preflight.json").write_text(
            json.dumps(found.to_dict(), indent=2, sort_keys=True)
        )


def _simulate(args) -> int:
    from pathlib import Path
    import signal

    from deburr_drake.cell.diagram import make_deburring_diagram

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
    if args.record:
        _check_writable_target(
            args.record, "--record", args.force, is_dir=False
        )
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
            args, plan, diagram, meshcat, out, (received, running), found
        )
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)


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


def _run_and_write(args, plan, diagram, meshcat, out, flags, found) -> int:
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
    pngs = _figures(files["logs"], out, plan.scenario)
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


def _figures(logs_path, out, scenario):
    """The run's figures from logs.npz; none (said on stderr) when the run
    is too short to draw."""
    from deburr_drake.runs import figures

    try:
        with np.load(logs_path) as logs:
            return figures.make_figures(
                dict(logs),
                out,
                label=f"{scenario.name} (m = "
                f"{scenario.controller.fuzzy.order})",
            )
    except Exception as e:
        print(
            f"deburr-drake: no figures: {type(e).__name__}: {e}",
            file=sys.stderr,
        )
        return []


#: The demo's summary as printed: label, key, scale, unit.
_DEMO_ROWS = (
    (
        "delta_d time constant, adaptation off",
        "depth_time_constant",
        1.0,
        "s",
    ),
    (
        "  eq. (8) with the local stiffness",
        "depth_time_constant_eq8",
        1.0,
        "s",
    ),
    ("final depth (adaptive)", "depth_final", 1e3, "mm"),
    (
        "max |delta - delta*| after 2 s",
        "depth_max_error_after_settle",
        1e3,
        "mm",
    ),
    (
        "c0 + c1 delta* (estimated)",
        "predicted_force_at_desired_depth",
        1.0,
        "N",
    ),
    ("true ||f_n|| at delta*", "true_force_at_desired_depth", 1.0, "N"),
    ("  relative error", "force_prediction_error_rel", 1.0, ""),
    ("commanded feed (mean after 2 s)", "commanded_feed_mean", 1e3, "mm/s"),
    ("feedrate law on measured signals", "feedrate_law_mean", 1e3, "mm/s"),
    ("command speed along the contour", "command_speed", 1e3, "mm/s"),
    (
        "chamfering force (mean after 2 s)",
        "chamfering_force_mean",
        1.0,
        "N",
    ),
    (
        "fraction of s in the dead zone after 2 s",
        "dead_zone_fraction_after_settle",
        1.0,
        "",
    ),
    ("NaN detected", "nan_detected", 1.0, ""),
    ("wall time of the adaptive run", "wall_time_s", 1.0, "s"),
)


def _demo(args) -> int:
    from deburr_drake.cell.truth import contact_truth
    from deburr_drake.runs import demo
    from deburr_drake.runs.passes import run

    scenario = _load(args)
    if args.duration is not None:
        _check_duration(args.duration)
        if args.duration <= demo.SETTLE_TIME:
            _bad(
                f"--duration = {args.duration!r} is too short for the demo:"
                f" allowed more than its {demo.SETTLE_TIME:g} s settling "
                "time (it measures after it)"
            )
    duration = 5.0 if args.duration is None else args.duration
    print(
        f"deburr-drake demo: point-mass testbed, scenario "
        f"'{scenario.name}', {duration:g} s"
    )
    truth = contact_truth(scenario)
    print(
        "contact truth (Drake hydroelastic + process threshold): "
        f"||f_n(delta*)|| = {truth.force_at_desired_depth:.3f} N, "
        f"local stiffness {truth.local_stiffness / 1e3:.2f} N/mm"
    )
    print("run 1/2: adaptation off, estimates at the truth (eq. 8)")
    frozen = run(
        demo.frozen_adaptation(scenario, truth),
        min(duration, 3.0),
        progress=_progress,
    )
    print("run 2/2: adaptive (estimator and fuzzy rules on)")
    log = run(scenario, duration, progress=_progress)
    summary = demo.summarize(log, truth, frozen)
    print()
    for label, key, scale, unit in _DEMO_ROWS:
        print(f"  {label:42s} {summary[key] * scale:10.4f} {unit}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(summary, f, indent=2)
    return 0


def _diagram(args) -> int:
    from pathlib import Path

    from deburr_drake.cell.diagram import make_deburring_diagram
    from deburr_drake.runs.graphs import write_graphs

    scenario = _load(args)
    diagram = make_deburring_diagram(scenario=scenario)
    out = Path(args.out or f"out/{scenario.name}/diagram.dot")
    written, message = write_graphs(
        diagram, out, fmt=args.format, max_depth=args.depth
    )
    for path in written:
        print(f"wrote {path}")
    if message:
        print(f"deburr-drake: {message}", file=sys.stderr)
    return 0


def _compare(args) -> int:
    from pathlib import Path

    from deburr_drake.runs import compare as cmp

    scenario = _load(args)
    if args.duration is not None:
        _check_duration(args.duration)
    controllers = [c.strip() for c in args.controllers.split(",") if c.strip()]
    if not controllers or len(set(controllers)) != len(controllers):
        _bad(
            f"--controllers = {args.controllers!r} is invalid: allowed "
            f"distinct names from {', '.join(cmp.CONTROLLERS)}"
        )
    for c in controllers:
        cmp.configure(scenario, c)
    if not (isinstance(args.workers, int) and args.workers >= 1):
        _bad(
            f"--workers = {args.workers!r} is invalid: allowed an integer >= 1"
        )
    out = Path(args.out or f"out/{scenario.name}_comparison")
    _check_writable_target(
        out,
        "--out",
        args.force,
        is_dir=True,
        names=("comparison.json", "comparison.md"),
    )
    plan, _, found = _planned(args, scenario)
    scenario = plan.scenario
    print(
        f"deburr-drake compare: scenario '{scenario.name}', "
        f"{', '.join(controllers)}, "
        + (f"{args.duration:g} s" if args.duration else "full run")
        + f", {args.workers} worker(s), output {out}/",
        flush=True,
    )
    rows = cmp.compare(
        scenario,
        controllers,
        duration=args.duration,
        out_dir=out,
        workers=args.workers,
    )
    _write_resolved(out, scenario, found)
    print((out / "comparison.md").read_text())
    worst = 0
    for row in rows:
        worst = max(
            worst, EXIT_CODES.get(row["stop_reason"].split(":", 1)[0], 1)
        )
    print(f"wrote {out}/comparison.json, comparison.md and the overlay figures")
    # A controller's guard or NaN is a finding, written in the table: the
    # comparison itself succeeded.
    return 0 if worst in (0, 3, 4) else worst


def _batch(args) -> int:
    from pathlib import Path

    from deburr_drake.runs.batch import batch_table, run_batch, write_batch

    scenario = _load(args)
    if args.duration is not None:
        _check_duration(args.duration)
    if not args.parts >= 1:
        _bad(f"--parts = {args.parts!r} is invalid: allowed an integer >= 1")
    out = Path(args.out or f"out/batch_{scenario.name}")
    carried = {
        "all": "c hat and theta",
        "estimates": "c hat",
        "weights": "theta",
    }[args.carry]
    mode = (
        "fresh (a cold start per part)"
        if args.fresh
        else f"carrying {carried} from part to part"
    )
    print(
        f"deburr-drake batch: {args.parts} parts of '{scenario.name}', "
        f"offsets up to {args.max_offset * 1e3:g} mm (seed {args.seed}), "
        f"{mode}, output {out}/",
        flush=True,
    )

    done = []

    def on_part(part, log):
        from deburr_drake.runs import report

        done.append(part)
        write_batch(done, out, label=f"{scenario.name}, {mode}")
        report.write_run(log, out / f"part{part.part}", part.values)
        m = part.metrics
        print(
            f"  part {part.part}: offset ({part.offset[0] * 1e3:+.3f}, "
            f"{part.offset[1] * 1e3:+.3f}) mm, {log.stop_reason} at "
            f"{log.stop_time:.2f} s, depth RMS "
            f"{m.get('chamfer_depth_rms_error_mm', float('nan')):.4f} mm, "
            f"first 10 % "
            f"{m.get('first_10pct_depth_rms_error_mm', float('nan')):.4f}"
            f" mm, {log.wall_time:.0f} s wall",
            flush=True,
        )

    parts = run_batch(
        scenario,
        count=args.parts,
        seed=args.seed,
        max_offset=args.max_offset,
        max_yaw=args.max_yaw,
        fresh=args.fresh,
        carry=args.carry,
        duration=args.duration,
        on_part=on_part,
    )
    paths = write_batch(parts, out, label=f"{scenario.name}, {mode}")
    print()
    print(batch_table(parts))
    print(f"\nwrote {', '.join(str(p) for p in paths.values())}")
    bad = [
        p.part
        for p in parts
        if p.stop_reason.split(":")[0] not in ("pass_complete", "duration")
    ]
    return 3 if bad else 0


def _sweep(args) -> int:
    import os
    from pathlib import Path
    import signal

    from deburr_drake import sweep

    study = sweep.load_study(args.study, text=args.study_text)
    if args.limit is not None and args.limit < 1:
        _bad(f"--limit = {args.limit!r} is invalid: allowed an integer >= 1")
    workers = args.workers or os.cpu_count() or 1
    if workers < 1:
        _bad(f"--workers = {workers!r} is invalid: allowed an integer >= 1")
    out = Path(args.out or f"out/{study.name}_sweep")
    _check_writable_target(out, "--out", True, is_dir=True)
    runs = sweep.expand_runs(study)  # every run validated before any starts
    runs = runs[: args.limit] if args.limit else runs
    if args.no_run:
        return _sweep_report(study, runs, out)
    pending = [r for r in runs if sweep.read_result(out, r.key) is None]
    sweep.check_reach(study, pending)
    _sweep_preflight(args, study, pending)
    print(
        f"deburr-drake sweep: study '{study.name}', {len(runs)} run(s) of "
        f"{study.duration:g} s, output {out}/",
        flush=True,
    )
    received = []

    def on_term(number, frame):
        # As Ctrl-C: cancel what is still running, keep what is finished.
        received.append(number)
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, on_term)
    try:
        outcome = sweep.run_sweep(
            study, runs, out, workers=workers, scheduler=args.scheduler
        )
    finally:
        signal.signal(signal.SIGTERM, previous)
    if outcome.ran == 0 and not outcome.interrupted:
        print(
            f"all {len(runs)} run(s) already have results in {out}/runs: "
            "nothing to run"
        )
    print(
        f"\n{outcome.ran} run(s) now, {outcome.skipped} already done, in "
        f"{outcome.wall_time_s:.1f} s"
    )
    summary = _sweep_report(study, runs, out, outcome)
    if outcome.errors:
        print(
            f"deburr-drake sweep: {len(outcome.errors)} run(s) could not "
            "run (nothing recorded for them; rerun to retry)",
            file=sys.stderr,
        )
    if outcome.interrupted:
        print(
            f"interrupted: the {summary['runs_finished']} finished run(s) "
            "are kept; the same command resumes"
        )
        return 143 if received else 130
    return 1 if outcome.errors else 0


def _sweep_preflight(args, study, runs):
    """The pre-flight of the runs about to run, once per distinct loop
    (analysis.preflight.loop_key: burrs, noise and duration aside); the
    first refused run is one line naming it."""
    from deburr_drake.analysis.preflight import loop_key, preflight
    from deburr_drake.config import ConfigError
    from deburr_drake.sweep.study import scenario_from_text

    if args.no_preflight:
        print("pre-flight skipped (--no-preflight)", flush=True)
        return
    checked = set()
    for run in runs:
        scenario = scenario_from_text(run.scenario_text)
        key = loop_key(scenario)
        if key in checked:
            continue
        try:
            found = preflight(scenario)
        except ConfigError as e:
            section = "grid" if study.grid else "sample.fields"
            shown = ", ".join(f"{n} = {v:.6g}" for n, v in run.params.items())
            raise ConfigError(
                f"study.{section}: run {run.index} ({shown}): {e}"
            ) from None
        checked.add(key)
        print(
            f"pre-flight of run {run.index}: rho = {found.rho:.5f} at the "
            "start pose",
            flush=True,
        )


def _sweep_report(study, runs, out, outcome=None):
    """Writes results.csv, summary.json and the figures from the finished
    runs among ``runs`` and prints the success rates; returns the summary
    (0 with --no-run)."""
    from deburr_drake import sweep

    results = (
        outcome.results
        if outcome is not None
        else {r.key: sweep.read_result(out, r.key) for r in runs}
    )
    files = sweep.write_results(
        study,
        runs,
        results,
        out,
        rules=sweep.rules_of(study),
        metrics=sweep.metrics_of(study),
        wall_time_s=outcome.wall_time_s if outcome is not None else None,
    )
    summary = files["summary_data"]
    print(
        f"{summary['runs_finished']}/{len(runs)} run(s) finished; stop "
        f"reasons {summary['stop_reasons']}"
    )
    for r in summary["rules"]:
        if r["runs"]:
            lo, hi = r["ci95"]
            print(
                f"  {r['rule']:45s} {r['passed']:4d}/{r['runs']:<4d} "
                f"{100 * r['success_rate']:5.1f} % "
                f"(95 % CI {100 * lo:.1f}-{100 * hi:.1f} %)"
            )
    ranked = [
        r
        for r in summary["failures_explained_by"]
        if r["association"] is not None
    ][:2]
    if ranked:
        print(
            "how badly runs did is best explained by "
            + ", ".join(
                f"{r['parameter']} ({r['association']:.2f})" for r in ranked
            )
        )
        for b in summary["success_by_parameter"].get(
            ranked[0]["parameter"], []
        ):
            print(
                f"  {b['low']:11.4g} .. {b['high']:<11.4g} {b['passed']:4d}"
                f"/{b['runs']:<4d} pass"
            )
    print(f"wrote {out}/results.csv, summary.json and the figures")
    return summary if outcome is not None else 0


def _check_analyze_times(args):
    """--at, --until, --spacing, --lyapunov > 0, --after-contact >= 0 and
    --at before --until: refused before anything runs."""
    for name in ("at", "until", "spacing", "lyapunov"):
        value = getattr(args, name)
        if value is not None and not (np.isfinite(value) and value > 0):
            _bad(f"--{name} = {value!r} is invalid: allowed a time > 0 s")
    if not (np.isfinite(args.after_contact) and args.after_contact >= 0):
        _bad(
            f"--after-contact = {args.after_contact!r} is invalid: "
            "allowed a time >= 0 s"
        )
    if args.at is not None and args.until is not None and args.at >= args.until:
        _bad(
            f"--at = {args.at!r} is invalid: allowed a time before "
            f"--until ({args.until!r} s)"
        )


def _analyze(args) -> int:
    from pathlib import Path

    from deburr_drake import analysis

    # The scenario and every option, checked before anything runs.
    scenario = _load(args)
    grid = analysis.parse_map(scenario, args.map) if args.map else None
    overrides = analysis.parse_settings(scenario, args.set or [])
    _check_analyze_times(args)
    out = Path(args.out or f"out/{scenario.name}/analysis")
    _check_writable_target(
        out, "--out", args.force, is_dir=True, names=_ANALYSIS_OUTPUTS
    )
    out.mkdir(parents=True, exist_ok=True)

    def say(message):
        print(f"  {message}", flush=True)

    # The verdict on the run and, if it settles, the operating point's
    # analysis.
    result = analysis.analyze(
        scenario,
        at=args.at,
        after_contact=args.after_contact,
        overrides=overrides,
        until=args.until,
        spacing=args.spacing or analysis.DEFAULT_SPACING,
        robust=not args.no_robust,
        numerics=args.numerics,
        progress=say,
    )
    settled = result.get("eigenvalues") is not None
    # --validate: predicted against simulated boundaries at that point.
    if args.validate and settled:
        result["boundaries"] = analysis.validate_boundaries(
            result["_objects"]["op"], progress=say
        )
    # --lyapunov: a run of its own, V1 and V traced along it.
    if args.lyapunov:
        trace = analysis.lyapunov_trace(scenario, duration=args.lyapunov)
        result["lyapunov"] = trace.summary
        analysis.plot_lyapunov(trace, out / "lyapunov.png", title=scenario.name)
    # --map: rho over one or two fields at the operating point.
    if grid is not None and settled:
        result["_objects"]["map"] = analysis.stability_map(
            result["_objects"]["op"], grid
        )
        result["map"] = result["_objects"]["map"].to_dict()
    # analysis.json, the figures and the one-screen summary.
    files = analysis.write_analysis(result, out)
    print()
    print(analysis.summary_text(result))
    if (args.validate or grid is not None) and not settled:
        print(
            "no --map / --validate: they need an operating point in "
            "steady cutting"
        )
    print("\nwrote " + ", ".join(str(p) for p in files.values()))
    return 0


#: What ``converge`` writes into its output directory.
_CONVERGENCE_OUTPUTS = ("convergence.json", "convergence.md")


def _converge(args) -> int:
    from pathlib import Path

    from deburr_drake.runs.convergence import converge, write_convergence

    scenario = _load(args)
    if args.duration is not None:
        _check_duration(args.duration)
    out = Path(args.out or f"out/{scenario.name}/convergence")
    _check_writable_target(
        out, "--out", args.force, is_dir=True, names=_CONVERGENCE_OUTPUTS
    )
    print(
        f"deburr-drake converge: scenario '{scenario.name}', "
        f"{args.duration or scenario.simulation.duration:g} s per run, up "
        f"to {args.steps} halving(s) of the step, output {out}/",
        flush=True,
    )
    study = converge(
        scenario,
        duration=args.duration,
        max_halvings=args.steps,
        tolerance=args.tolerance,
        progress=lambda line: print(f"  {line}", flush=True),
    )
    files = write_convergence(study, out)
    print()
    print(files["markdown"].read_text())
    print("wrote " + ", ".join(str(p) for p in files.values()))
    return 0


def _scenario_arguments(parser, default: str, duration_help: str):
    parser.add_argument(
        "--scenario",
        default=default,
        help=f"scenario name or YAML file (default {default})",
    )
    parser.add_argument(
        "--scenario-text",
        default=None,
        help="YAML overrides applied on top of the scenario",
    )
    if duration_help:
        parser.add_argument(
            "--duration", type=float, default=None, help=duration_help
        )


def _preflight_argument(parser):
    parser.add_argument(
        "--no-preflight",
        action="store_true",
        help="run even if the sampled loop at the start pose is predicted "
        "unstable (the gains of controller.design: auto are still "
        "designed, not proven)",
    )


def _add_demo_parser(subparsers):
    p = subparsers.add_parser(
        "demo",
        help="run the point-mass testbed and print its convergence numbers",
    )
    _scenario_arguments(
        p, "point_mass", "simulated seconds of the adaptive run (default 5)"
    )
    p.add_argument("--json", default=None, help="also write the numbers")
    p.set_defaults(func=_demo)


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


def _add_batch_parser(subparsers):
    p = subparsers.add_parser(
        "batch",
        help="K parts in sequence through one cell "
        "(probe, cut, next), the learning "
        "carried from part to part",
        epilog=_EXIT_HELP,
    )
    _scenario_arguments(
        p,
        "paper_localised",
        "simulated seconds at most per part (default: the "
        "scenario's, a full pass)",
    )
    p.add_argument("--parts", type=int, default=10, help="K (default 10)")
    p.add_argument(
        "--seed", type=int, default=1, help="seeds the part errors (default 1)"
    )
    p.add_argument(
        "--max-offset",
        type=float,
        default=0.001,
        help="m: part offsets uniform over a disc of this "
        "radius (default 0.001)",
    )
    p.add_argument(
        "--max-yaw",
        type=float,
        default=0.0,
        help="rad: part yaw uniform within +- this (default 0)",
    )
    p.add_argument(
        "--fresh",
        action="store_true",
        help="a cold start per part (nothing carried over)",
    )
    p.add_argument(
        "--carry",
        choices=["all", "estimates", "weights"],
        default="all",
        help="what passes from part to part: the contact "
        "estimates c hat and the fuzzy weights theta (all, "
        "default), or one of them",
    )
    p.add_argument(
        "--out",
        default=None,
        help="output directory (default out/batch_<scenario>)",
    )
    p.set_defaults(func=_batch)


def _add_compare_parser(subparsers):
    p = subparsers.add_parser(
        "compare",
        help="run several controllers on one scenario and compare them",
    )
    _scenario_arguments(
        p,
        "paper",
        "simulated seconds of each run (default: the scenario's, a full pass)",
    )
    p.add_argument(
        "--controllers",
        default="fuzzy,fuzzy_m0,impedance,robust,ideal,position",
        help="comma-separated: fuzzy (the scenario's order), "
        "fuzzy_m0, fuzzy_m2, robust, ideal, impedance, "
        "position",
    )
    p.add_argument(
        "--workers", type=int, default=1, help="parallel processes (default 1)"
    )
    _output_arguments(
        p, "out/<scenario>_comparison", "an existing comparison in --out"
    )
    _preflight_argument(p)
    p.set_defaults(func=_compare)


def _add_diagram_parser(subparsers):
    p = subparsers.add_parser(
        "diagram",
        help="export the diagram and the controller as GraphViz graphs",
    )
    _scenario_arguments(p, "paper", None)
    p.add_argument(
        "--depth",
        type=int,
        default=None,
        help="levels of nesting to expand (default: all)",
    )
    p.add_argument(
        "--format",
        choices=("dot", "svg", "png"),
        default="dot",
        help="also render with GraphViz's dot (default: .dot only)",
    )
    p.add_argument(
        "--out",
        default=None,
        help="output path (default out/<scenario>/diagram.dot)",
    )
    p.set_defaults(func=_diagram)


def _add_sweep_parser(subparsers):
    p = subparsers.add_parser(
        "sweep",
        help="run a study (a grid or Monte Carlo "
        "samples of scenario fields) on Dask, "
        "resumable",
    )
    p.add_argument(
        "study", help="study YAML file (e.g. studies/robustness.yaml)"
    )
    p.add_argument(
        "--workers",
        type=int,
        default=None,
        help="local worker processes (default: the CPU count)",
    )
    p.add_argument(
        "--scheduler",
        default=None,
        metavar="ADDR",
        help="an existing Dask scheduler, e.g. "
        "tcp://127.0.0.1:8786, instead of local workers",
    )
    p.add_argument(
        "--out",
        default=None,
        help="output directory (default out/<study>_sweep); a "
        "rerun skips the runs it already holds",
    )
    p.add_argument(
        "--limit", type=int, default=None, help="only the study's first N runs"
    )
    p.add_argument(
        "--study-text",
        default=None,
        help="YAML overrides of the study's own fields, e.g. "
        "'{name: robustness_localised, base: "
        "paper_localised, duration: 50.0}'",
    )
    p.add_argument(
        "--no-run",
        action="store_true",
        help="run nothing: write the table, summary and figures "
        "from the runs finished so far (e.g. while a sweep "
        "is going)",
    )
    _preflight_argument(p)
    p.set_defaults(func=_sweep)


def _add_analyze_parser(subparsers):
    p = subparsers.add_parser(
        "analyze",
        help="is the run stable? the verdict on "
        "the scenario's run, then the "
        "analysis in steady cutting",
    )
    _scenario_arguments(p, "paper", None)
    _operating_point_arguments(p)
    _analyzed_run_arguments(p)
    _output_arguments(
        p, "out/<scenario>/analysis", "an existing analysis in --out"
    )
    p.set_defaults(func=_analyze)


def _add_converge_parser(subparsers):
    p = subparsers.add_parser(
        "converge",
        help="does the run's answer hold when the step is refined? the "
        "scenario at its step and at the step halved, until the metrics "
        "stop changing",
    )
    _scenario_arguments(
        p, "paper", "simulated seconds per run (default: the scenario's)"
    )
    p.add_argument(
        "--steps",
        type=int,
        default=3,
        help="halvings of simulation.max_step at most (default 3: down "
        "to an eighth of it)",
    )
    p.add_argument(
        "--tolerance",
        type=float,
        default=0.05,
        help="relative change of every compared metric under which a "
        "halving changed nothing (default 0.05)",
    )
    _output_arguments(
        p,
        "out/<scenario>/convergence",
        "an existing convergence.json / .md in --out",
    )
    p.set_defaults(func=_converge)


def _output_arguments(parser, default, overwritten):
    """--out (``default`` when not given) and --force, which overwrites
    ``overwritten``: every command refuses its own outputs in --out
    without it."""
    parser.add_argument(
        "--out", default=None, help=f"output directory (default {default})"
    )
    parser.add_argument(
        "--force", action="store_true", help=f"overwrite {overwritten}"
    )


def _operating_point_arguments(parser):
    """analyze's options of the operating point and what is done there
    (--lyapunov runs on its own)."""
    parser.add_argument(
        "--at",
        type=float,
        default=None,
        help="simulated time (s) of the operating point "
        "(default: --after-contact s after the first "
        "contact)",
    )
    parser.add_argument(
        "--after-contact",
        type=float,
        default=3.0,
        help="seconds of cutting before the operating point (default 3)",
    )
    parser.add_argument(
        "--map",
        nargs="+",
        default=None,
        metavar="FIELD=LO:HI:N",
        help="stability map of rho over one or two scenario "
        "fields by dotted name, e.g. "
        "sensor.cutoff_frequency=5:80:16 "
        "controller.sliding_gain[0]=100:3000:16",
    )
    parser.add_argument(
        "--set",
        nargs="+",
        default=None,
        metavar="FIELD=VALUE",
        help="analyse the operating point with these scenario "
        "fields changed (the scenario as given reaches "
        "steady cutting first), e.g. "
        "controller.sliding_gain[0]=4500",
    )
    parser.add_argument(
        "--lyapunov",
        type=float,
        default=None,
        metavar="SECONDS",
        help="also run the scenario this long and trace V1 of "
        "Prop. 1 and V of (38) (lyapunov.png)",
    )
    parser.add_argument(
        "--validate",
        action="store_true",
        help="predicted against simulated stability boundaries "
        "(short runs from the operating point)",
    )


def _analyzed_run_arguments(parser):
    """analyze's options of the run and the maps along it."""
    parser.add_argument(
        "--until",
        type=float,
        default=None,
        metavar="SECONDS",
        help="end the analysed run here (default: the "
        "scenario's duration or pass)",
    )
    parser.add_argument(
        "--spacing",
        type=float,
        default=None,
        metavar="SECONDS",
        help="seconds of cutting between the maps along the run "
        "(default 5; burrs and curvature changes add "
        "their own)",
    )
    parser.add_argument(
        "--no-robust",
        action="store_true",
        help="skip the robust margin over the uncertain parameters (11 maps)",
    )
    parser.add_argument(
        "--numerics",
        choices=("refined", "shipped"),
        default="refined",
        help="how the run and its maps are integrated: refined (default: "
        "a quarter of simulation.max_step, eq. (3) between samples, "
        "where the verdict stops changing with the step) or shipped (the "
        "scenario's own step, faster)",
    )


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(
        prog="deburr-drake",
        description="Adaptive fuzzy hybrid position/force deburring on "
        "Drake (Hsu & Fu, 2000).",
        epilog=_EXIT_HELP,
    )
    subparsers = parser.add_subparsers(dest="command", required=True)
    _add_demo_parser(subparsers)
    _add_simulate_parser(subparsers)
    _add_batch_parser(subparsers)
    _add_compare_parser(subparsers)
    _add_diagram_parser(subparsers)
    _add_sweep_parser(subparsers)
    _add_analyze_parser(subparsers)
    _add_converge_parser(subparsers)
    args = parser.parse_args(argv)
    from deburr_drake.config import ConfigError

    try:
        return args.func(args)
    except ConfigError as e:
        print(f"deburr-drake: error: {e}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
