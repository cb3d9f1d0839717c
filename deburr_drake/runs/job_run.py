"""A whole part's job run: the Diagram of its plan simulated once, its
record (deburr_drake.runs.job_log.JobLog) and each edge's pass metrics.

Use: ``result = run_job(plan_job_cell(scenario))``; ``result.log`` is the
JobLog, ``result.metrics[k]`` the pass metrics of ``result.log.edges[k]``
(deburr_drake.runs.pass_metrics, over the bins cut when that cut did not
reach its end)."""

from __future__ import annotations

from dataclasses import dataclass, field
import time
from typing import Callable, Dict, List, Optional

import numpy as np
from pydrake.common import RandomGenerator

from deburr_drake.cell.job_cell import JobCellPlan, make_job_diagram
from deburr_drake.cell.process import PROCESS_STATE
from deburr_drake.cell.truth import contact_truth
from deburr_drake.control.sequencer import JOB_COMPLETE, JOB_PHASE, JOB_STATE
from deburr_drake.runs.job_log import (
    EdgeSource,
    JobLog,
    JobSignals,
    make_job_log,
)
from deburr_drake.runs.job_report import move_clearances
from deburr_drake.runs.pass_metrics import PassMetrics, pass_metrics
from deburr_drake.runs.simulation import (
    _advance,
    _collect,
    _stop_monitor,
    final_blocks,
    logger_names,
    make_simulator,
)

__all__ = ["JobResult", "run_job"]


@dataclass
class JobResult:
    """What :func:`run_job` gives: the job's log, each cut edge's pass
    metrics (in ``log.edges``' order) and the diagram run."""

    log: JobLog
    metrics: List[PassMetrics]
    diagram: object
    files: Dict[str, str] = field(default_factory=dict)


class _CutEnds:
    """A monitor's duty: the fuzzy weights at the end of each cut (read
    when the sequencer leaves the cut phase; the weights are held off the
    part, so the next cut starts from them)."""

    def __init__(self, diagram):
        self._sequencer = diagram.GetSubsystemByName("job_sequencer")
        self._controller = diagram.GetSubsystemByName("controller")
        self.theta: Dict[int, np.ndarray] = {}

    def __call__(self, root_context):
        context = self._sequencer.GetMyContextFromRoot(root_context)
        k = self._sequencer.cut(context)
        if self._sequencer.phase(context) != "cut" and k not in self.theta:
            self.theta[k] = self._controller.theta(
                self._controller.GetMyContextFromRoot(root_context)
            ).copy()


def _final(diagram, context, k, theta):
    """Edge k's final-state blocks, as a pass's."""
    process = diagram.GetSubsystemByName(f"cutting_process_{k}")
    return final_blocks(
        process,
        process.GetMyContextFromRoot(context),
        diagram.GetSubsystemByName("controller"),
        theta,
    )


def _job_signals(logs, nq) -> JobSignals:
    job = logs["job"]
    phase = JOB_STATE.get(job["value"], "phase").astype(int)
    cut = JOB_STATE.get(job["value"], "cut").astype(int)
    return JobSignals(
        t=job["t"],
        q=logs["plant_state"]["value"][:, :nq],
        phase=phase,
        cut=np.where(phase == JOB_PHASE["cut"], cut, -1),
    )


def _truth(plan: JobCellPlan):
    try:
        return contact_truth(plan.edges[0]).force_at_desired_depth
    except Exception:  # the metrics that need it are then null
        return None


def _reached_its_end(signals: JobSignals, k: int) -> bool:
    """Did cut k reach its end? The sample after its last is the retract
    that follows a cut's end."""
    times = signals.t[signals.cut == k]
    after = np.flatnonzero(signals.t > times[-1]) if len(times) else []
    return bool(len(after)) and signals.phase[after[0]] == JOB_PHASE["retract"]


def _edge_sources(plan, diagram, context, logs, signals, theta, reason):
    """An EdgeSource per planned cut: its process's log, its final state
    (the fuzzy weights at its cut's end, ``theta`` by cut, or the run's
    last), and whether it reached its end (the retract followed it, or
    the job completed on it)."""
    controller = diagram.GetSubsystemByName("controller")
    last = controller.theta(controller.GetMyContextFromRoot(context)).copy()
    sources = []
    for k, (cut, edge) in enumerate(zip(plan.job.cuts, plan.edges)):
        completed = _reached_its_end(signals, k) or (
            reason == JOB_COMPLETE and k == len(plan.edges) - 1
        )
        raw = logs[f"process_{k}"]
        sources.append(
            EdgeSource(
                index=cut.index,
                point=cut.point,
                length_m=plan.contour.edges[k].length,
                scenario=edge,
                process={"t": raw["t"], **PROCESS_STATE.split(raw["value"])},
                final=_final(diagram, context, k, theta.get(k, last)),
                completed=bool(completed),
            )
        )
    return sources


def run_job(
    plan: JobCellPlan,
    *,
    duration: Optional[float] = None,
    progress: Optional[Callable[[float, float, float], None]] = None,
    progress_interval: float = 1.0,
    should_stop: Optional[Callable[[], Optional[str]]] = None,
    truth: bool = True,
    meshcat=None,
) -> JobResult:
    """Builds the job's Diagram once (cell.job_cell.make_job_diagram),
    simulates it until the job completes (``job_complete``), a guard
    trips, the run diverges or ``duration`` (the scenario's by default)
    ends, and returns its JobLog and each cut edge's pass metrics
    (``truth``: against the contact truth of the part's material). With
    a ``meshcat``, the job is drawn there as it runs (record it for the
    replay: deburr_drake.runs.replay)."""
    scenario = plan.scenario
    duration = scenario.simulation.duration if duration is None else duration
    diagram = make_job_diagram(plan, meshcat=meshcat)
    ends = _CutEnds(diagram)
    stop = _stop_monitor(diagram, scenario, 0.0, should_stop)

    def monitor(root_context):
        ends(root_context)
        return stop(root_context)

    simulator = make_simulator(diagram, scenario, monitor=monitor)
    context = simulator.get_mutable_context()
    diagram.SetRandomContext(
        context, RandomGenerator(scenario.sensor.noise_seed)
    )
    generator = diagram.GetSubsystemByName("command_generator")
    wall_start = time.perf_counter()
    reason, detail = _advance(
        simulator, diagram, duration, progress, progress_interval, generator
    )
    wall = time.perf_counter() - wall_start
    t = context.get_time()
    logs = _collect(diagram, context, logger_names(diagram))
    signals = _job_signals(logs, plan.cell.model.num_positions())
    signals.clearance = move_clearances(plan.job.cell, signals)
    # The job's own and the probing's loggers are the job's, not the
    # edges'.
    shared = {
        name: logs[name]
        for name in logs
        if name not in ("job", "plant_state", "probe", "touch_points")
        and not name.startswith("process_")
    }
    sources = _edge_sources(
        plan, diagram, context, logs, signals, ends.theta, reason
    )
    log = make_job_log(
        scenario,
        sources,
        shared,
        signals,
        [c.move for c in plan.job.cuts[1:]],
        stop_reason=reason,
        stop_time=t,
        stop_detail=detail,
        wall_time=wall,
        steps=simulator.get_num_steps_taken(),
        refused=plan.job.refused,
        skipped=plan.job.skipped,
        probe=logs.get("probe"),
    )
    force = _truth(plan) if truth else None
    metrics = [
        pass_metrics(
            edge.log,
            true_force_at_desired_depth=force,
            only_cut=not edge.completed,
        )
        for edge in log.edges
    ]
    return JobResult(log, metrics, diagram)
