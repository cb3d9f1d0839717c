"""Running a study on Dask: every run is one task in a worker process (a
``LocalCluster`` of processes on this machine by default, or any
scheduler by address). Drake objects never cross processes: a task gets
the scenario as YAML text and its output directory, and returns the
metrics (the worker has already written them). Each finished run leaves
``runs/<key>/result.json``, written atomically last: a rerun skips it,
and a killed sweep loses only the runs that were still going."""

from __future__ import annotations

from dataclasses import dataclass, field
import json
import math
import os
from pathlib import Path
import socket
import sys
import time
from typing import Callable, Dict, List, Optional

from deburr_drake.sweep.study import RunSpec, Study, metrics_of

__all__ = [
    "run_scenario",
    "run_sweep",
    "result_path",
    "read_result",
    "SweepOutcome",
    "NORMAL_STOPS",
]

#: Stop reasons of a run that ended as planned.
NORMAL_STOPS = ("duration", "pass_complete")
#: Metrics that need the plant's force at delta* (cell.truth.contact_truth).
_TRUTH_METRICS = ("true_force_at_desired_depth_N", "force_prediction_error_rel")


def result_path(out_dir, key: str) -> Path:
    return Path(out_dir) / "runs" / key / "result.json"


def read_result(out_dir, key: str) -> Optional[dict]:
    """The finished run's result, or None (none yet, or unreadable: a
    rerun then does the run again)."""
    path = result_path(out_dir, key)
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def _write_atomically(path: Path, data: dict):
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    with open(tmp, "w") as f:
        json.dump(data, f, indent=2, sort_keys=True, allow_nan=False)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def _sweep_fields(result: dict) -> dict:
    reason = result.get("stop_reason", "error")
    result["guard_tripped"] = float(reason.startswith("guard:"))
    result["run_failed"] = float(reason not in NORMAL_STOPS)
    return result


def failed_result(key: str, reason: str, detail: str) -> dict:
    """What a run that gave no metrics leaves: every metric null."""
    return _sweep_fields(
        {
            "key": key,
            "stop_reason": reason,
            "stop_detail": detail,
            "stop_time_s": None,
            "completed_pass": False,
            "unavailable": {"*": f"the run ended with {reason}"},
        }
    )


def run_scenario(
    scenario_text: str,
    run_dir: str,
    key: str,
    *,
    keep_logs: bool = True,
    metrics=(),
) -> dict:
    """One run, in the worker's process: builds the diagram from the
    scenario's YAML, simulates, writes ``logs.npz`` (if ``keep_logs``),
    ``metrics.json`` and, last and atomically, ``result.json`` into
    ``run_dir``, and returns the result. Never raises for a run that goes
    wrong: an exception anywhere is the result's ``stop_reason: error``."""
    import traceback

    out = Path(run_dir)
    out.mkdir(parents=True, exist_ok=True)
    t_start, cpu_start = time.perf_counter(), time.process_time()
    timing = {}
    try:
        from deburr_drake.cell.diagram import make_deburring_diagram
        from deburr_drake.cell.plan import plan_cell
        from deburr_drake.runs import report
        from deburr_drake.runs.passes import run_pass
        from deburr_drake.sweep.study import scenario_from_text

        scenario = scenario_from_text(scenario_text)
        (out / "scenario.yaml").write_text(scenario_text)
        t = time.perf_counter()
        plan = plan_cell(scenario)
        diagram = make_deburring_diagram(plan)
        timing["build_s"] = time.perf_counter() - t
        done = run_pass(
            plan,
            diagram=diagram,
            truth=any(m in _TRUTH_METRICS for m in metrics),
        )
        log, values = done.log, done.metrics
        timing["simulate_s"] = log.wall_time
        if keep_logs:
            report.write_run(log, out, values)
        result = report.run_summary(log, values)
        if not keep_logs:
            _write_atomically(out / "metrics.json", result)
        result = dict(result)
    except Exception as e:
        result = failed_result(
            key,
            "error",
            f"{type(e).__name__}: {e}\n" + traceback.format_exc(limit=5),
        )
    result = _sweep_fields(result)
    result.update(
        key=key,
        run_dir=str(out),
        host=socket.gethostname(),
        pid=os.getpid(),
        run_wall_time_s=time.perf_counter() - t_start,
        run_cpu_time_s=time.process_time() - cpu_start,
        **timing,
    )
    _write_atomically(out / "result.json", result)
    return result


@dataclass
class SweepOutcome:
    """What a sweep did: every run's result by key (None: not finished),
    how many ran now and how many were already there."""

    runs: List[RunSpec]
    results: Dict[str, Optional[dict]] = field(default_factory=dict)
    ran: int = 0
    skipped: int = 0
    interrupted: bool = False
    wall_time_s: float = 0.0
    errors: List[str] = field(default_factory=list)  # tasks that could not run


def _clock(seconds: float) -> str:
    if not math.isfinite(seconds):
        return "--:--"
    seconds = int(round(seconds))
    h, rest = divmod(seconds, 3600)
    return (f"{h}:" if h else "") + f"{rest // 60:02d}:{rest % 60:02d}"


class _Progress:
    """One line: runs done, failed (not ended as planned), time left."""

    def __init__(self, total: int, workers: int, stream):
        self.total, self.workers, self.stream = total, workers, stream
        self.done = self.failed = 0
        self.start = time.perf_counter()
        self.tty = stream.isatty()

    def update(self, result: dict):
        self.done += 1
        self.failed += int(result.get("run_failed", 1.0) > 0)
        elapsed = time.perf_counter() - self.start
        left = elapsed / self.done * (self.total - self.done)
        width = 30
        filled = int(width * self.done / max(self.total, 1))
        line = (
            f"[{'#' * filled}{'.' * (width - filled)}] "
            f"{self.done}/{self.total} done, {self.failed} failed, "
            f"{_clock(elapsed)} elapsed, ~{_clock(left)} left"
        )
        if self.tty:
            end = "\n" if self.done == self.total else ""
            print("\r" + line, end=end, file=self.stream, flush=True)
        else:
            print(
                line + f"  ({result.get('key')}: {result.get('stop_reason')})",
                file=self.stream,
                flush=True,
            )


def _client(workers: int, scheduler: Optional[str]):
    import dask
    from distributed import Client, LocalCluster

    if scheduler:
        return Client(scheduler, timeout="20s"), None
    # One task per worker process; a worker that dies (a crash inside
    # Drake) fails its run at once instead of retrying it on another, and
    # only that run: no task waits assigned to a worker (saturation 1.0;
    # Dask's 1.1 queued a second one there, and it failed too).
    dask.config.set(
        {
            "distributed.scheduler.allowed-failures": 0,
            "distributed.scheduler.worker-saturation": 1.0,
        }
    )
    cluster = LocalCluster(
        n_workers=workers,
        threads_per_worker=1,
        processes=True,
        dashboard_address=":0",
        silence_logs=40,
    )
    return Client(cluster), cluster


def run_sweep(
    study: Study,
    runs: List[RunSpec],
    out_dir,
    *,
    workers: int = 2,
    scheduler: Optional[str] = None,
    on_result: Optional[Callable[[dict], None]] = None,
    stream=None,
    priority: int = 0,
) -> SweepOutcome:
    """Runs every run of ``runs`` that has no result in ``out_dir`` yet, as
    Dask tasks, and returns all their results. A task that fails without
    a result (its worker died) is recorded with ``stop_reason: crash``.
    KeyboardInterrupt cancels what is still running and returns what is
    finished (``interrupted``). ``priority``: Dask's task priority (higher
    first), for studies that share a cluster."""
    from distributed import as_completed

    stream = stream or sys.stdout
    out = Path(out_dir).resolve()
    outcome = SweepOutcome(runs=runs)
    start = time.perf_counter()
    todo = []
    for run in runs:
        result = read_result(out, run.key)
        outcome.results[run.key] = result
        if result is None:
            todo.append(run)
    todo = list({r.key: r for r in todo}.values())  # identical runs: once
    outcome.skipped = len(runs) - len(todo)
    if not todo:
        outcome.wall_time_s = time.perf_counter() - start
        return outcome
    client, cluster = _client(workers, scheduler)
    n_workers = len(client.scheduler_info().get("workers", {})) or workers
    print(
        f"sweep {study.name}: {len(todo)} run(s) to do, "
        f"{outcome.skipped} already done; "
        + (
            f"scheduler {scheduler} ({n_workers} workers)"
            if scheduler
            else f"{n_workers} local worker process(es)"
        ),
        file=stream,
        flush=True,
    )
    futures = {}
    try:
        _submit(client, study, todo, out, priority, futures)
        progress = _Progress(len(todo), n_workers, stream)
        for future in as_completed(list(futures)):
            run = futures[future]
            result = _finished_result(future, run, out, outcome)
            if result is None:
                continue
            outcome.results[run.key] = result
            outcome.ran += 1
            progress.update(result)
            if on_result is not None:
                on_result(result)
    except KeyboardInterrupt:
        outcome.interrupted = True
        client.cancel(list(futures))
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    outcome.wall_time_s = time.perf_counter() - start
    return outcome


def _submit(client, study: Study, todo, out: Path, priority, futures: dict):
    """Submits every run of ``todo`` to ``client``, recording each in
    ``futures`` ({future: run}) as it goes (an interrupt cancels what was
    submitted)."""
    metrics = metrics_of(study)
    for run in todo:
        future = client.submit(
            run_scenario,
            run.scenario_text,
            str(out / "runs" / run.key),
            run.key,
            keep_logs=study.keep_logs,
            metrics=metrics,
            key=f"deburr-run-{run.key}",
            pure=False,
            priority=priority,
        )
        futures[future] = run


def _finished_result(future, run: RunSpec, out: Path, outcome: SweepOutcome):
    """The result of a finished task; for a task whose worker died, a
    ``crash`` result (recorded, never retried); None for an error that is
    not the run's doing (kept in ``outcome.errors``, nothing recorded)."""
    from distributed import KilledWorker

    if future.status == "finished":
        return future.result()
    error = future.exception()
    if not isinstance(error, KilledWorker):
        # Not the run's doing (e.g. the scheduler cannot unpickle the
        # task: deburr_drake not importable there): nothing is recorded,
        # a rerun tries again.
        message = f"{type(error).__name__}: {error}"
        if message not in outcome.errors:
            print(
                f"deburr-drake sweep: run {run.key} could not "
                f"run: {' '.join(message.split())}",
                file=sys.stderr,
                flush=True,
            )
        outcome.errors.append(message)
        return None
    # The worker process died running it (a crash inside Drake, out of
    # memory): recorded, never retried.
    result = failed_result(run.key, "crash", f"{type(error).__name__}: {error}")
    run_dir = out / "runs" / run.key
    run_dir.mkdir(parents=True, exist_ok=True)
    result["run_dir"] = str(run_dir)
    _write_atomically(run_dir / "result.json", result)
    return result
