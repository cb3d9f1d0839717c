"""The report of a whole job's run: per edge, the single pass's metrics
over that edge's slice of the run; for the job, the cycle time split by
phase, the tool tip's travel, the planned and the simulated clearance of
the moves, and the share of the selected edges cut.

Per edge (``edges: [...]`` of metrics.json): the finish, force and feed
families of :mod:`deburr_drake.runs.pass_metrics` on the edge's log (a
single pass's log, time-sliced to the edge), over the bins cut when the
edge was not cut to its end. For the job (``job: {...}``): the time in
each phase from the job-level phase signal, the tool tip's path length
from the logged joint positions, and the least signed distance between
the robot and the part's convex pieces (the planning cell's query,
:func:`deburr_drake.cell.moves.clearance`) at every logged sample of
every move, with the cutter's own distance left out on the retract and
the approach as the planner leaves it out (it is in the cut at one end).

Use: ``report = job_report(job_log, plan, cell)``;
``write_job_report(report, job_log, out)`` writes metrics.json, each
edge's logs.npz and Figs. 8-12 under ``edge_<index>/``."""

from __future__ import annotations

from dataclasses import dataclass, field
import json
from pathlib import Path
from typing import Dict, List, Optional

import numpy as np

from deburr_drake.cell.moves import PlanningCell, clearance, tip_positions
from deburr_drake.math import metrics
from deburr_drake.runs.pass_metrics import (
    PassMetrics,
    feed_metrics,
    finish_metrics,
    force_metrics,
    pass_window,
)
from deburr_drake.runs.simulation import RunLog

__all__ = [
    "EDGE_FIELDS",
    "JOB_FIELDS",
    "JOB_COMPLETE",
    "EdgeReport",
    "JobReport",
    "edge_report",
    "job_report",
    "phase_times",
    "move_clearance",
]

#: The stop reason of a job that cut every edge it planned.
JOB_COMPLETE = "job_complete"

#: The metrics of the single pass each edge reports, by name.
_PASS_FIELDS = (
    "edge_coverage",
    "chamfer_depth_rms_error_mm",
    "chamfering_force_rms_error_N",
    "feed_mean_off_burrs_mm_s",
)

_TIMES = ("start_time_s", "contact_time_s", "cut_time_s")

#: What each entry of metrics.json's ``edges`` holds: name -> (unit,
#: meaning), for the generated metrics reference.
EDGE_FIELDS: Dict[str, tuple] = {
    "index": ("-", "the edge's index in ``deburr-drake edges``' listing"),
    "point": ("m", "a point on the edge, in the part's frame"),
    "length_m": ("m", "the length of the cutter's path along the edge"),
    "order": ("-", "its place in the job (0: cut first)"),
    "start_time_s": (
        "s",
        "when its cut began (the tool at the approach's end); null if the "
        "job stopped before it",
    ),
    "contact_time_s": (
        "s",
        "when the cutter first pressed on the edge (||f_n|| above the "
        "pass's ``CONTACT_FORCE``); its transient runs ``TRANSIENT`` s on",
    ),
    "cut_time_s": ("s", "how long its cut took"),
    "cut_to_end": (
        "-",
        "true if the tool cut the edge to its end (its pass completed)",
    ),
    "stop": (
        "-",
        "``pass_complete`` for an edge cut to its end; else what ended "
        "the job on it, or ``not_reached``",
    ),
    "edge_coverage": (
        "-",
        "fraction of the edge the tool cut (the pass's ``edge_coverage``)",
    ),
    "chamfer_depth_rms_error_mm": (
        "mm",
        "RMS error of the chamfer depth left on the edge, after the "
        "edge's transient (the pass's metric on the edge's slice)",
    ),
    "chamfering_force_rms_error_N": (
        "N",
        "RMS error of the chamfering force after the edge's transient",
    ),
    "chamfering_force_max_N": (
        "N",
        "the largest chamfering force ||f_t|| on the edge, its transient "
        "included",
    ),
    "feed_mean_off_burrs_mm_s": (
        "mm/s",
        "mean speed along the edge off its burrs, after the transient",
    ),
    "unavailable": ("-", "for each null value, why"),
}

#: What metrics.json's ``job`` holds: name -> (unit, meaning).
JOB_FIELDS: Dict[str, tuple] = {
    "stop_reason": (
        "-",
        "``job_complete`` when every planned edge was cut to its end; "
        "else the run's stop reason (``guard:<name>``, ``duration``, ...)",
    ),
    "stop_time_s": ("s", "the simulated time the job stopped at"),
    "stop_detail": ("-", "a guard's values at the trip, a message; or empty"),
    "cycle_time_s": ("s", "from the job's start to its stop"),
    "cutting_time_s": ("s", "time spent cutting (the edges' passes)"),
    "moving_time_s": (
        "s",
        "time spent on the moves between cuts: retract, transit and approach",
    ),
    "retract_time_s": ("s", "of the moving time, up the tool axis"),
    "transit_time_s": ("s", "of the moving time, between the two"),
    "approach_time_s": ("s", "of the moving time, down onto the next edge"),
    "travel_m": (
        "m",
        "the tool tip's path length over the job (from the logged joint "
        "positions)",
    ),
    "cutting_travel_m": ("m", "of it, while cutting"),
    "moving_travel_m": ("m", "of it, on the moves"),
    "planned_min_clearance_m": (
        "m",
        "least distance between the robot and the part on the planned "
        "moves (``deburr-drake job``'s check)",
    ),
    "min_clearance_m": (
        "m",
        "least distance between the robot and the part at every logged "
        "sample of every move, from the simulated joint positions (the "
        "cutter's own left out on the retract and the approach); above 0: "
        "no contact while moving",
    ),
    "min_clearance_at": (
        "-",
        "where that least distance was: the move (into which edge), its "
        "phase and time",
    ),
    "edges_selected": (
        "-",
        "edges the job selected: those planned and those refused",
    ),
    "edges_cut": ("-", "edges cut to their end"),
    "cut_share": ("-", "edges_cut / edges_selected"),
    "refused": ("-", "each selected edge not planned, with why"),
    "wall_time_s": (
        "s",
        "wall-clock time of the simulation; varies from run to run",
    ),
}


@dataclass
class EdgeReport:
    """One edge's entry of ``edges``: values by name (nan where the
    edge cannot give one) and why each nan."""

    values: dict
    reasons: Dict[str, str] = field(default_factory=dict)

    def record(self) -> dict:
        """As metrics.json holds it: nan as null, with ``unavailable``."""
        out = {k: _json(v) for k, v in self.values.items()}
        out["unavailable"] = dict(self.reasons)
        return out


def _json(value):
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (float, np.floating, int, np.integer)):
        value = float(value)
        return value if np.isfinite(value) else None
    if isinstance(value, np.ndarray):
        return [_json(v) for v in value]
    return value


def edge_report(
    *, index: int, order: int, point, length: float, log: Optional[RunLog]
) -> EdgeReport:
    """The entry of the edge at ``index`` (cut ``order``-th), from its
    slice of the run ``log`` (None: the job stopped before it): the
    finish, force and feed metrics of a pass on that slice, over the bins
    cut when the edge was not cut to its end."""
    values = {
        "index": int(index),
        "order": int(order),
        "point": [float(x) for x in point],
        "length_m": float(length),
    }
    out = EdgeReport(values)
    if log is None:
        values.update(
            start_time_s=float("nan"),
            cut_time_s=float("nan"),
            cut_to_end=False,
            stop="not_reached",
        )
        for name in _TIMES + _PASS_FIELDS + ("chamfering_force_max_N",):
            values[name] = float("nan")
            out.reasons[name] = "the job stopped before this edge"
        return out
    t0 = float(log["chamfer"]["t"][0]) if len(log["chamfer"]["t"]) else 0.0
    values.update(
        start_time_s=t0,
        cut_time_s=float(log.stop_time) - t0,
        cut_to_end=bool(log.completed_pass),
        stop=log.stop_reason,
    )
    window = pass_window(log)
    values["contact_time_s"] = window.contact
    if not np.isfinite(window.contact):
        out.reasons["contact_time_s"] = window.reason
    found = PassMetrics()
    for family in (
        finish_metrics(log, window, only_cut=not log.completed_pass),
        force_metrics(log, window),
        feed_metrics(log, window),
    ):
        found.merge(family)
    for name in _PASS_FIELDS:
        values[name] = found[name]
        if name in found.reasons:
            out.reasons[name] = found.reasons[name]
    f_t = np.abs(log["process"]["f_t"])
    if f_t.size:
        values["chamfering_force_max_N"] = float(np.max(f_t))
    else:
        values["chamfering_force_max_N"] = float("nan")
        out.reasons["chamfering_force_max_N"] = "no process sample"
    return out


#: The phases the job's time and travel are split into; the job log's
#: phase signal names each sample's by its code (``phase_names``).
CUTTING, RETRACT, TRANSIT, APPROACH = "cut", "retract", "transit", "approach"
_MOVING = (RETRACT, TRANSIT, APPROACH)


def phase_times(t, phase, stop_time: float, phase_names) -> Dict[str, float]:
    """s by phase name (every one of ``phase_names``' values, 0 when
    never entered): each sample's phase held to the next sample."""
    held = metrics.time_by_label(t, phase, stop_time)
    return {name: held.get(code, 0.0) for code, name in phase_names.items()}


def move_clearance(
    cell: PlanningCell, q, phase, cut, phase_names, times
) -> tuple:
    """(m, where): the least signed distance between the robot and the
    part (:func:`deburr_drake.cell.moves.clearance`) over the samples of
    the moves, the cutter's own left out on the retract and the approach
    (in the cut at one end, as the planner leaves it out); ``where`` names
    the move by the edge it leads to, the phase and the time. (nan, "")
    without a move sample."""
    names = np.array([phase_names.get(int(p), "") for p in phase])
    best, where = float("nan"), ""
    for k in np.flatnonzero(np.isin(names, _MOVING)):
        distance = clearance(cell, q[k], cutter=names[k] == TRANSIT)
        if not distance >= best:  # also the first (best nan)
            best = distance
            where = (
                f"{names[k]} into the cut of order {int(cut[k])} at "
                f"t = {times[k]:.3f} s"
            )
    return best, where


@dataclass
class JobReport:
    """What metrics.json holds for a job: ``edges`` (one
    :class:`EdgeReport` per planned cut, in order) and ``job`` (values by
    name, nan where the run cannot give one, with ``reasons``)."""

    edges: List[EdgeReport]
    job: dict
    reasons: Dict[str, str] = field(default_factory=dict)

    @property
    def stop_reason(self) -> str:
        return self.job["stop_reason"]

    def record(self) -> dict:
        job = {k: _json(v) for k, v in self.job.items()}
        job["unavailable"] = dict(self.reasons)
        return {
            "edges": [e.record() for e in self.edges],
            "job": job,
            "stop_reason": self.job["stop_reason"],
        }


def job_report(
    *,
    cuts,
    edge_logs: List[Optional[RunLog]],
    refused=(),
    planned_clearance: float,
    t,
    q,
    phase,
    cut,
    phase_names: Dict[int, str],
    stop_reason: str,
    stop_time: float,
    stop_detail: str = "",
    wall_time: float = float("nan"),
    cell: PlanningCell,
) -> JobReport:
    """The report of a job's run.

    ``cuts``: the plan's cuts in order (``deburr_drake.cell.job.JobCut``:
    index, point, contour); ``edge_logs``: each one's slice of the run
    (None for a cut the job never began); ``refused``: (index, why) of
    the edges selected but not planned; ``planned_clearance``: m, the
    least clearance of the planned moves. The job-level signals, one row
    per logged sample: ``t`` (s), ``q`` (rad), ``phase`` (codes named by
    ``phase_names``), ``cut`` (the order of the cut being made or moved
    to). ``stop_reason`` is the run's; the job's is :data:`JOB_COMPLETE`
    only when every planned cut was cut to its end."""
    edges = [
        edge_report(
            index=c.index,
            order=k,
            point=c.point,
            length=c.contour.length,
            log=log,
        )
        for k, (c, log) in enumerate(zip(cuts, edge_logs))
    ]
    cut_count = sum(bool(e.values["cut_to_end"]) for e in edges)
    complete = cut_count == len(edges)
    if complete:
        reason = JOB_COMPLETE
    elif stop_reason in (JOB_COMPLETE, "pass_complete"):
        reason = "edges_not_cut"
    else:
        reason = stop_reason
    # The edge the job stopped on says why.
    for edge in edges:
        values = edge.values
        if not values["cut_to_end"] and values["stop"] != "not_reached":
            values["stop"] = reason
    # Time and the tool tip's travel by phase.
    t, q, phase = np.asarray(t, float), np.asarray(q, float), np.asarray(phase)
    held = phase_times(t, phase, stop_time, phase_names)
    names = np.array([phase_names.get(int(p), "") for p in phase])
    tips = tip_positions(cell, q) if len(q) else np.zeros((0, 3))
    travel = metrics.path_length_by_label(tips, names)
    job = {
        "stop_reason": reason,
        "stop_time_s": float(stop_time),
        "stop_detail": stop_detail,
        "cycle_time_s": float(stop_time - t[0]) if len(t) else 0.0,
        "cutting_time_s": held.get(CUTTING, 0.0),
        "moving_time_s": sum(held.get(n, 0.0) for n in _MOVING),
        "retract_time_s": held.get(RETRACT, 0.0),
        "transit_time_s": held.get(TRANSIT, 0.0),
        "approach_time_s": held.get(APPROACH, 0.0),
        "travel_m": float(sum(travel.values())),
        "cutting_travel_m": travel.get(CUTTING, 0.0),
        "moving_travel_m": sum(travel.get(n, 0.0) for n in _MOVING),
        "planned_min_clearance_m": float(planned_clearance),
        "edges_selected": len(edges) + len(refused),
        "edges_cut": cut_count,
        "cut_share": cut_count / max(1, len(edges) + len(refused)),
        "refused": [{"index": int(i), "why": why} for i, why in refused],
        "wall_time_s": float(wall_time),
    }
    out = JobReport(edges, job)
    least, where = move_clearance(cell, q, phase, cut, phase_names, t)
    job["min_clearance_m"], job["min_clearance_at"] = least, where
    if not np.isfinite(least):
        out.reasons["min_clearance_m"] = "no move was logged"
    if not np.isfinite(planned_clearance):
        out.reasons["planned_min_clearance_m"] = "the plan has no move"
    return out


def write_job_report(
    report: JobReport,
    edge_logs: List[Optional[RunLog]],
    out,
    *,
    scenario_name: str,
    label: str = "",
    figures: bool = True,
) -> Dict[str, object]:
    """metrics.json (``scenario``, ``stop_reason``, ``edges`` and ``job``;
    strict JSON) in ``out``, and per edge cut or begun, under
    ``edge_<index>/``, its logs.npz (:func:`deburr_drake.runs.report.
    log_arrays` of its slice) and, with ``figures``, its Figs. 8-12.
    Returns {"metrics": path, "edges": {index: [paths]}, "failures":
    {index: one line}}: a figure that cannot be drawn is said, not
    raised."""
    from deburr_drake.runs.figure_process import draw_figures
    from deburr_drake.runs.report import log_arrays

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    record = {"scenario": scenario_name, **report.record()}
    metrics_path = out / "metrics.json"
    metrics_path.write_text(
        json.dumps(record, indent=2, sort_keys=True, allow_nan=False) + "\n"
    )
    written, failures = {}, {}
    for edge, log in zip(report.edges, edge_logs):
        if log is None:
            continue
        index = edge.values["index"]
        folder = out / f"edge_{index}"
        folder.mkdir(exist_ok=True)
        arrays = log_arrays(log, edge.values)
        np.savez_compressed(folder / "logs.npz", **arrays)
        paths = [folder / "logs.npz"]
        if figures:
            drawn, failure = draw_figures(
                folder / "logs.npz", folder, f"{label} edge {index}".strip()
            )
            paths += drawn
            if failure is not None:
                failures[index] = failure
        written[index] = paths
    return {"metrics": metrics_path, "edges": written, "failures": failures}
