"""``deburr-drake sweep``: a study of many runs over a grid or a sample."""

from __future__ import annotations

import sys

from deburr_drake.cli.common import (
    _bad,
    _check_writable_target,
    _interrupted_exit_code,
    _preflight_argument,
    _sigterm_as_interrupt,
)


def _sweep(args) -> int:
    import os
    from pathlib import Path

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
    # As Ctrl-C: cancel what is still running, keep what is finished.
    with _sigterm_as_interrupt() as received:
        outcome = sweep.run_sweep(
            study, runs, out, workers=workers, scheduler=args.scheduler
        )
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
        return _interrupted_exit_code(received)
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
