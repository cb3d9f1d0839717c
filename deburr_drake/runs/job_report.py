"""The report of a whole job's run (deburr_drake.runs.job_log.JobLog):
per edge, the single pass's metrics over that edge's slice of the run;
for the job, the cycle time split by phase, the tool tip's travel, the
planned and the simulated clearance of the moves, and the share of the
selected edges cut.

Per edge (``edges: [...]`` of metrics.json, one entry per planned cut in
the job's order): the finish, force and feed families of
:mod:`deburr_drake.runs.pass_metrics` on the edge's pass log, over the
bins cut when the edge was not cut to its end, and the largest f_t. For
the job (``job: {...}``): the time in each phase
(deburr_drake.control.sequencer.JOB_PHASES) from the phase signal, the
tool tip's path length from the logged joint positions, and the least
signed distance between the robot and the part's convex pieces (the
planning cell's query, :func:`deburr_drake.cell.moves.clearance`) at
every logged sample of every move, the cutter's own left out on the
retract and the approach as the planner leaves it out (it is in the cut
at one end).

Use: ``report = job_report(job_log, plan)`` (the JobPlan, whose
planning cell checks the moves); ``write_job_report(report,
job_log, out)`` writes metrics.json, and each edge's logs.npz and
Figs. 8-12 under ``edge_<index>/``."""

from __future__ import annotations

from dataclasses import dataclass, field
import json
from pathlib import Path
from typing import Dict, List, NamedTuple, Optional

import numpy as np

from deburr_drake.cell.moves import PlanningCell, clearance, tip_positions
from deburr_drake.control.mesh_probe import MESH_PROBE_STATE
from deburr_drake.control.sequencer import JOB_COMPLETE, JOB_PHASE, JOB_PHASES
from deburr_drake.math import metrics
from deburr_drake.runs.job_log import EdgeRun, JobLog, JobSignals
from deburr_drake.runs.pass_metrics import (
    PassMetrics,
    feed_metrics,
    finish_metrics,
    force_metrics,
    pass_window,
    pose_errors,
)

__all__ = [
    "EDGE_FIELDS",
    "JOB_FIELDS",
    "EdgeReport",
    "JobReport",
    "edge_report",
    "job_report",
    "move_clearance",
    "move_clearances",
    "write_job_report",
    "Check",
    "EDGE_RULES",
    "job_checks",
    "report_lines",
]

#: A cut the job never began.
NOT_REACHED = "not_reached"
#: The stop reason of a run that ended as complete with a cut short of
#: its edge's end (the job is then not complete).
EDGES_NOT_CUT = "edges_not_cut"
_MOVING = ("retract", "move", "approach")

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
        "when its cut began, in the job's time (the approach's end); "
        "null if the job stopped before it",
    ),
    "contact_time_s": (
        "s",
        "when the cutter first pressed on the edge, from its cut's start "
        "(||f_n|| above the pass's ``CONTACT_FORCE``); the edge's "
        "metrics begin ``TRANSIENT`` s later",
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
    "move_time_s": ("s", "of the moving time, the transit between the two"),
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
        "where that least distance was: the move (the edges it joins), its "
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
    "probing_time_s": (
        "s",
        "with touch probing (``localisation.probe``): the time before the "
        "first cut, from the first touch's lift to the tool in contact at "
        "the first edge's start on the registered part",
    ),
    "probe_touches": ("-", "touches that found the part"),
    "probe_touches_kept": ("-", "touches the registration kept"),
    "registration_position_error_mm": (
        "mm",
        "how far the registered pose puts the centroid of the cut edges' "
        "points from where the real part (``part_error``) has it",
    ),
    "registration_orientation_error_deg": (
        "deg",
        "the angle between the registered part's orientation and the "
        "real part's",
    ),
}

#: The job's probing fields (null without touch probing).
PROBE_FIELDS = (
    "probing_time_s",
    "probe_touches",
    "probe_touches_kept",
    "registration_position_error_mm",
    "registration_orientation_error_deg",
)


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
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        value = float(value)
        return value if np.isfinite(value) else None
    return value


def edge_report(cut, position: int, run: Optional[EdgeRun]) -> EdgeReport:
    """The entry of the plan's ``cut`` (a JobCut: index, point, contour),
    cut ``position``-th, from its ``run`` (None: the job stopped before
    it): the finish, force and feed metrics of a pass on its log, over
    the bins cut when the edge was not cut to its end."""
    values = {
        "index": int(cut.index),
        "order": int(position),
        "point": [float(x) for x in cut.point],
        "length_m": float(cut.contour.length),
    }
    out = EdgeReport(values)
    if run is None:
        values.update(cut_to_end=False, stop=NOT_REACHED)
        for name in _TIMES + _PASS_FIELDS + ("chamfering_force_max_N",):
            values[name] = float("nan")
            out.reasons[name] = "the job stopped before this edge"
        return out
    log = run.log
    window = pass_window(log)
    values.update(
        start_time_s=run.start_time,
        contact_time_s=window.contact,
        cut_time_s=run.end_time - run.start_time,
        cut_to_end=bool(log.completed_pass),
        stop=log.stop_reason,
    )
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
    values["chamfering_force_max_N"] = (
        float(np.max(f_t)) if f_t.size else float("nan")
    )
    if not f_t.size:
        out.reasons["chamfering_force_max_N"] = "no process sample"
    return out


def move_clearances(cell: PlanningCell, signals: JobSignals) -> np.ndarray:
    """m per sample of ``signals``: the least signed distance between the
    robot and the part (:func:`deburr_drake.cell.moves.clearance`) at
    every sample of the moves, the cutter's own left out on the retract
    and the approach (in the cut at one end, as the planner leaves it
    out); NaN on the cuts and once done."""
    out = np.full(signals.t.shape, np.nan)
    transit = signals.phase == JOB_PHASE["move"]
    for k in np.flatnonzero(np.isin(signals.phase, _codes(_MOVING))):
        out[k] = clearance(cell, signals.q[k], cutter=bool(transit[k]))
    return out


def move_clearance(cell: Optional[PlanningCell], job: JobLog) -> tuple:
    """(m, where): the least of :func:`move_clearances` (the run's own
    ``signals.clearance`` when it holds them, else computed in ``cell``);
    ``where`` names the move by the edges it joins, its phase and the
    time. (nan, "") without a move sample."""
    signals = job.signals
    distances = signals.clearance
    if distances is None:
        distances = move_clearances(cell, signals)
    if not np.any(np.isfinite(distances)):
        return float("nan"), ""
    at = int(np.nanargmin(distances))
    t = signals.t[at]
    after = [m.after for m in job.moves if m.start_time <= t]
    joins = (
        f"the move from edge {_index(job, after[-1])} to edge "
        f"{_index(job, after[-1] + 1)}"
        if after
        else "a move"
    )
    return float(distances[at]), (
        f"{joins}, {JOB_PHASES[signals.phase[at]]}, at t = {t:.3f} s"
    )


def _codes(names) -> list:
    return [JOB_PHASE[name] for name in names]


def _index(job: JobLog, position: int):
    for edge in job.edges:
        if edge.position == position:
            return edge.index
    return f"of order {position}"


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


def _stop_reason(job: JobLog, edges: List[EdgeReport]) -> str:
    """JOB_COMPLETE only when every planned cut reached its end."""
    if all(e.values["cut_to_end"] for e in edges):
        return JOB_COMPLETE
    if job.stop_reason in (JOB_COMPLETE, "pass_complete"):
        return EDGES_NOT_CUT
    return job.stop_reason


def job_report(
    job: JobLog, plan, cell: Optional[PlanningCell] = None
) -> JobReport:
    """The report of the run ``job`` of ``plan`` (its JobPlan: the cuts
    in order, the planned moves), its moves checked in ``cell`` (the
    planning cell of the robot, its tool and the part's convex pieces;
    the plan's by default)."""
    cell = cell if cell is not None else getattr(plan, "cell", None)
    runs = {edge.position: edge for edge in job.edges}
    edges = [
        edge_report(cut, k, runs.get(k)) for k, cut in enumerate(plan.cuts)
    ]
    reason = _stop_reason(job, edges)
    for edge in edges:  # the edge the job stopped on says why
        if edge.values["stop"] not in ("pass_complete", NOT_REACHED):
            edge.values["stop"] = reason
    # Time and the tool tip's travel, by phase.
    signals = job.signals
    held = metrics.time_by_label(signals.t, signals.phase, job.stop_time)
    tips = tip_positions(cell, signals.q)
    travel = metrics.path_length_by_label(tips, signals.phase)

    def by_phase(values, names):
        return float(sum(values.get(code, 0.0) for code in _codes(names)))

    planned = [m.min_clearance_m for m in plan.moves()]
    cut = sum(bool(e.values["cut_to_end"]) for e in edges)
    selected = len(edges) + len(job.refused)
    values = {
        "stop_reason": reason,
        "stop_time_s": float(job.stop_time),
        "stop_detail": job.stop_detail,
        "cycle_time_s": float(job.stop_time - signals.t[0])
        if len(signals.t)
        else 0.0,
        "cutting_time_s": by_phase(held, ["cut"]),
        "moving_time_s": by_phase(held, _MOVING),
        **{
            f"{name}_time_s": by_phase(held, [name])
            for name in ("retract", "move", "approach")
        },
        "travel_m": float(sum(travel.values())),
        "cutting_travel_m": by_phase(travel, ["cut"]),
        "moving_travel_m": by_phase(travel, _MOVING),
        "planned_min_clearance_m": min(planned, default=float("nan")),
        "edges_selected": selected,
        "edges_cut": cut,
        "cut_share": cut / selected if selected else float("nan"),
        "refused": [{"index": int(i), "why": why} for i, why in job.refused],
        "wall_time_s": float(job.wall_time),
    }
    out = JobReport(edges, values)
    _probe_values(out, job, plan, by_phase(held, ["probe"]))
    least, where = move_clearance(cell, job)
    values["min_clearance_m"], values["min_clearance_at"] = least, where
    if not np.isfinite(least):
        out.reasons["min_clearance_m"] = "no move was logged"
    if not planned:
        out.reasons["planned_min_clearance_m"] = "the plan has no move"
    if not selected:
        out.reasons["cut_share"] = "the job selected no edge"
    return out


def _probe_values(out: JobReport, job: JobLog, plan, probing: float):
    """The job's probing (:data:`PROBE_FIELDS`): its time (``probing``,
    s, the probe phase's), its touches and the registration's error
    against the real part at the centroid of the cut edges' points."""
    L = MESH_PROBE_STATE
    values = out.job
    probe = job.probe
    why = None
    if probe is None or not len(probe["t"]):
        why = "the job did not probe (localisation.probe.enabled false)"
    else:
        last = probe["value"][-1]
        values["probe_touches"] = int(L.get(last, "touches"))
        values["probe_touches_kept"] = int(L.get(last, "kept"))
        if float(L.get(last, "done_time")) < 0.0:
            why = f"probing did not finish ({job.stop_reason})"
        else:
            values["probing_time_s"] = probing
    if why is not None:
        for name in PROBE_FIELDS:
            if name not in values:
                values[name] = float("nan")
                out.reasons[name] = why
        return
    points = [
        c.contour.point_at(s)
        for c in plan.cuts
        for s in np.linspace(0.0, c.contour.length, 50)
    ]
    position, turn = pose_errors(
        job.scenario, L.get(last, "registration"), np.mean(points, axis=0)
    )
    values["registration_position_error_mm"] = float(
        np.linalg.norm(position) * 1e3
    )
    values["registration_orientation_error_deg"] = float(
        np.degrees(np.linalg.norm(turn))
    )


def write_job_report(
    report: JobReport,
    job: JobLog,
    out,
    *,
    label: str = "",
    figures: bool = True,
) -> Dict[str, object]:
    """metrics.json (``scenario``, ``stop_reason``, ``edges`` and ``job``;
    strict JSON) in ``out``, and per edge cut or begun, under
    ``edge_<index>/``, its logs.npz (``runs.report.log_arrays`` of its
    pass log) and, with ``figures``, its Figs. 8-12. Returns {"metrics":
    path, "edges": {index: [paths]}, "failures": {index: one line}}: a
    figure that cannot be drawn is said, not raised."""
    from deburr_drake.runs.figure_process import draw_figures
    from deburr_drake.runs.report import log_arrays

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    record = {"scenario": job.scenario.name, **report.record()}
    metrics_path = out / "metrics.json"
    metrics_path.write_text(
        json.dumps(record, indent=2, sort_keys=True, allow_nan=False) + "\n"
    )
    entries = {e.values["order"]: e for e in report.edges}
    written, failures = {}, {}
    for run in job.edges:
        folder = out / f"edge_{run.index}"
        folder.mkdir(exist_ok=True)
        logs = folder / "logs.npz"
        values = entries[run.position].values
        np.savez_compressed(logs, **log_arrays(run.log, values))
        written[run.index] = [logs]
        if not figures:
            continue
        name = f"{label} edge {run.index}".strip()
        drawn, failure = draw_figures(logs, folder, name)
        written[run.index] += drawn
        if failure is not None:
            failures[run.index] = failure
    return {"metrics": metrics_path, "edges": written, "failures": failures}


class Check(NamedTuple):
    """One rule on the report: what, the value found, the rule, held."""

    what: str
    value: object
    rule: str
    ok: bool


#: The rules each edge's cut is held to: metric -> (comparison, bound).
EDGE_RULES = {
    "edge_coverage": (">=", 0.99),
    "chamfer_depth_rms_error_mm": ("<=", 0.05),
    "chamfering_force_rms_error_N": ("<=", 1.5),
}


def _holds(value, comparison, bound) -> bool:
    if value is None or not np.isfinite(value):
        return False
    return value >= bound if comparison == ">=" else value <= bound


def job_checks(report: JobReport) -> List[Check]:
    """The report against the rules: per edge :data:`EDGE_RULES` (a
    null value fails), the job complete (no guard, no other ending),
    and the simulated least clearance of the moves above 0."""
    checks = []
    for edge in report.edges:
        v = edge.values
        for name, (comparison, bound) in EDGE_RULES.items():
            checks.append(
                Check(
                    f"edge {v['index']} {name}",
                    v[name],
                    f"{comparison} {bound:g}",
                    _holds(v[name], comparison, bound),
                )
            )
    reason = report.stop_reason
    checks.append(
        Check("job stop_reason", reason, JOB_COMPLETE, reason == JOB_COMPLETE)
    )
    least = report.job["min_clearance_m"]
    clear = least is not None and bool(np.isfinite(least)) and least > 0.0
    checks.append(Check("job min_clearance_m", least, "> 0", clear))
    return checks


def _number(value, scale=1.0, spec=".4g") -> str:
    if value is None or not np.isfinite(value):
        return "n/a"
    return f"{value * scale:{spec}}"


def report_lines(report: JobReport, checks: List[Check]) -> List[str]:
    """The report as text (mm for lengths and depths): a row per edge
    with its rules held or not, the job's ending, times, travel,
    clearance and share of edges cut, and the checks that failed."""
    failed = {c.what for c in checks if not c.ok}
    lines = [
        "edge order length_mm coverage depth_rms_mm f_t_rms_N f_t_max_N "
        "feed_mm_s stop"
    ]
    for edge in report.edges:
        v = edge.values
        held = all(
            f"edge {v['index']} {name}" not in failed for name in EDGE_RULES
        )
        lines.append(
            f"{v['index']:4d} {v['order']:5d} {v['length_m'] * 1e3:9.1f} "
            f"{_number(v['edge_coverage'], spec='.4f'):>8s} "
            f"{_number(v['chamfer_depth_rms_error_mm'], spec='.5f'):>12s} "
            f"{_number(v['chamfering_force_rms_error_N'], spec='.3f'):>9s} "
            f"{_number(v['chamfering_force_max_N'], spec='.2f'):>9s} "
            f"{_number(v['feed_mean_off_burrs_mm_s'], spec='.2f'):>9s} "
            f"{v['stop']}" + ("" if held else "  MISSES A RULE")
        )
    j = report.job
    lines += [
        f"job: {j['stop_reason']} at {j['stop_time_s']:.3f} s"
        + (f" ({j['stop_detail']})" if j["stop_detail"] else ""),
        f"cycle time {j['cycle_time_s']:.2f} s: cutting "
        f"{j['cutting_time_s']:.2f} s, moving {j['moving_time_s']:.2f} s "
        f"(retract {j['retract_time_s']:.2f} s, move "
        f"{j['move_time_s']:.2f} s, approach {j['approach_time_s']:.2f} s)",
        f"tool-tip travel {j['travel_m'] * 1e3:.0f} mm: cutting "
        f"{j['cutting_travel_m'] * 1e3:.0f} mm, moving "
        f"{j['moving_travel_m'] * 1e3:.0f} mm",
        f"least clearance on the moves: planned "
        f"{_number(j['planned_min_clearance_m'], 1e3, '.2f')} mm, simulated "
        f"{_number(j['min_clearance_m'], 1e3, '.2f')} mm"
        + (f" ({j['min_clearance_at']})" if j["min_clearance_at"] else ""),
        f"edges cut {j['edges_cut']} of {j['edges_selected']} selected "
        f"({_number(j['cut_share'], spec='.2f')})",
        f"wall time {j['wall_time_s']:.1f} s",
    ]
    for refused in j["refused"]:
        lines.append(f"refused: {refused['why']}")
    misses = [c for c in checks if not c.ok]
    lines.append(
        f"rules: {len(checks) - len(misses)} of {len(checks)} held"
        + "".join(
            f"\n  missed: {c.what} = {c.value} (rule {c.rule})" for c in misses
        )
    )
    return lines
