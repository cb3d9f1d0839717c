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
from deburr_drake.cell.moves import clearance, make_planning_cell
from deburr_drake.cell.process import PROCESS_STATE
from deburr_drake.cell.truth import contact_truth
from deburr_drake.control.sequencer import JOB_COMPLETE, JOB_PHASE, JOB_STATE
from deburr_drake.math.convex_pieces import convex_pieces, placed_pieces
from deburr_drake.math.mesh_part import load_part
from deburr_drake.runs.job_log import (
    EdgeSource,
    JobLog,
    JobSignals,
    make_job_log,
)
from deburr_drake.runs.pass_metrics import PassMetrics, pass_metrics
from deburr_drake.runs.simulation import (
    _advance,
    _collect,
    _stop_monitor,
    final_blocks,
    logger_names,
    make_simulator,
)

__all__ = ["JobResult", "run_job", "job_summary", "write_job"]


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


#: s, between the samples whose clearance is computed on a move: the
#: moves' joints turn at most 0.5 rad/s, so about the plan's 5 mrad check
CLEARANCE_STEP = 0.01


def _clearance(plan: JobCellPlan, signals: JobSignals) -> np.ndarray:
    """m, the robot's least distance to the part's convex pieces at the
    samples off the part ``CLEARANCE_STEP`` apart (the cutter left out on
    the retract and the approach, as the plan leaves it out); NaN on the
    cuts and between those samples."""
    c, job = plan.scenario, plan.section
    part = load_part(
        job.part_file(), units=job.units, xyz=job.pose.xyz, rpy=job.pose.rpy
    )
    pieces = placed_pieces(convex_pieces(job.part_file()), part, job.units)
    cell = make_planning_cell(c.robot, c.tool, pieces)
    out = np.full(signals.t.shape, np.nan)
    transit = signals.in_phase("move")
    for i in np.flatnonzero(
        ~signals.in_phase("cut") & ~signals.in_phase("done")
    ):
        out[i] = clearance(cell, signals.q[i], cutter=bool(transit[i]))
    return out


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
) -> JobResult:
    """Builds the job's Diagram once (cell.job_cell.make_job_diagram),
    simulates it until the job completes (``job_complete``), a guard
    trips, the run diverges or ``duration`` (the scenario's by default)
    ends, and returns its JobLog and each cut edge's pass metrics
    (``truth``: against the contact truth of the part's material)."""
    scenario = plan.scenario
    duration = scenario.simulation.duration if duration is None else duration
    diagram = make_job_diagram(plan)
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
    signals.clearance = _clearance(plan, signals)
    shared = {
        name: logs[name]
        for name in logs
        if name not in ("job", "plant_state")
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


def job_summary(result: JobResult) -> dict:
    """What a job's metrics.json holds: how it ended, its wall time, per
    edge cut its place in the part, whether its cut reached the end and
    its pass metrics (null where a metric is not available), and per move
    its planned figures and the least clearance simulated on it
    (``min_clearance_m``, m; null where none was computed)."""
    from deburr_drake.runs.report import run_summary

    log = result.log
    edges = []
    for edge, values in zip(log.edges, result.metrics):
        summary = run_summary(edge.log, values)
        summary.update(
            index=edge.index,
            point=[float(v) for v in edge.point],
            length_m=float(edge.length_m),
            start_time_s=float(edge.start_time),
            end_time_s=float(edge.end_time),
        )
        edges.append(summary)
    clear = log.signals.clearance
    moves = []
    for move in log.moves:
        on = (log.signals.t >= move.start_time) & (
            log.signals.t <= np.nan_to_num(move.end_time, nan=np.inf)
        )
        least = np.nanmin(clear[on]) if np.any(np.isfinite(clear[on])) else None
        moves.append(
            {
                **{
                    k: float(v) if np.isfinite(v) else None
                    for k, v in vars(move).items()
                },
                "min_clearance_m": None if least is None else float(least),
            }
        )
    return {
        "moves": moves,
        "scenario": log.scenario.name,
        "stop_reason": log.stop_reason,
        "stop_time_s": float(log.stop_time),
        "stop_detail": log.stop_detail,
        "wall_time_s": float(log.wall_time),
        "planned_cuts": log.planned_cuts,
        "refused": [list(r) for r in log.refused],
        "edges": edges,
    }


def write_job(result: JobResult, out_dir) -> Dict[str, str]:
    """metrics.json (:func:`job_summary`) in ``out_dir`` and each edge's
    logs.npz and metrics.json, as a pass's, in ``edge_<index>/``."""
    import json
    from pathlib import Path

    from deburr_drake.runs.report import write_run

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    files = {"metrics": str(out / "metrics.json")}
    for edge, values in zip(result.log.edges, result.metrics):
        written = write_run(edge.log, out / f"edge_{edge.index}", values)
        files[f"edge_{edge.index}"] = str(written["logs"].parent)
    with open(files["metrics"], "w") as f:
        json.dump(
            job_summary(result), f, indent=2, sort_keys=True, allow_nan=False
        )
    result.files = files
    return files
