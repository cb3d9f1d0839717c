"""What a job run records: one log per cut edge, shaped as a single pass's,
and the job's own signals over the whole run.

A job (a scenario with a ``job:`` section, planned by
deburr_drake.cell.job.plan_job) is one simulation of every edge in order:
cut, retract, move, approach, the next cut (the phases are
deburr_drake.control.sequencer.JOB_PHASES). Its record is a
:class:`JobLog`:

- ``edges``: an :class:`EdgeRun` per edge the run started to cut, in the
  order cut. ``EdgeRun.log`` is a :class:`~deburr_drake.runs.simulation.RunLog`
  exactly as a single-edge run of that edge gives it: its ``scenario`` is
  the single-edge scenario of the edge (the job's scenario with
  ``part.edge`` set to the cut's ``EdgeConfig``), its ``signals`` hold the
  same loggers and blocks (``chamfer``, ``controller``, ``actuation``,
  ``estimates``, ``desired_normal_force``, ``command``, ``reference``,
  ``process``, ``tool_force``; ``finish``, ``theta`` and ``meta`` as a
  pass's final state), every time series cut to the samples of that
  edge's ``cut`` phase and counted from its start (``t = 0`` at
  ``EdgeRun.start_time`` of the job). ``process`` and ``finish`` are that
  edge's own cutting process (its bins along its own arc);
  ``theta.final`` the fuzzy weights at the cut's end. ``completed_pass``
  is True when the cut reached the edge's end; ``stop_reason`` is then
  ``pass_complete``, else the job's. So
  ``pass_metrics(edge.log)`` and the figures of a pass read it as they
  read a pass.
- ``moves``: a :class:`MoveRun` per move begun (retract, transit and
  approach between two cuts), with its planned figures and its times in
  the run.
- ``signals``: :class:`JobSignals` over the whole run: ``t``, the joint
  angles ``q``, the phase code and the cut under way per sample, and the
  tool's least distance to the part along the moves.
- ``stop_reason``: ``job_complete`` (JOB_COMPLETE) when every cut reached
  its end, else as a pass's (``guard:<name>``, ``duration``,
  ``diverged``, ...), with ``stop_time`` and ``stop_detail``. A job that
  stopped on its third edge still holds the first two, complete, and the
  third up to the stop.

Use :func:`make_job_log` to assemble a JobLog from the run's loggers (or
from synthetic arrays: it needs numpy arrays and scenarios, no Drake
system); :func:`edge_window` and :func:`slice_signals` are the two steps
it takes per edge."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, List, NamedTuple, Optional, Sequence, Tuple

import numpy as np

from deburr_drake.config import Scenario
from deburr_drake.control.sequencer import JOB_COMPLETE, JOB_PHASE, JOB_PHASES
from deburr_drake.runs.simulation import RunLog

__all__ = [
    "JobLog",
    "EdgeRun",
    "MoveRun",
    "JobSignals",
    "EdgeSource",
    "make_job_log",
    "edge_window",
    "slice_signals",
    "JOB_COMPLETE",
    "JOB_PHASES",
    "FINAL_BLOCKS",
]

#: The blocks of a pass's log that hold its final state, not samples.
FINAL_BLOCKS = ("finish", "theta", "meta")

Signals = Dict[str, Dict[str, np.ndarray]]


@dataclass
class JobSignals:
    """The job's signals over the whole run, one row per sample (at
    ``simulation.log_period``).

    ``t`` (s, (k,)); ``q`` (rad or m, (k, n)): the plant's joint
    positions; ``phase`` (int, (k,)): the code of the phase under way
    (index into JOB_PHASES); ``cut`` (int, (k,)): the position in
    ``JobLog.edges`` of the edge being cut, -1 on retract, move and
    approach (and once done); ``clearance`` (m, (k,)): the least
    distance from the robot to the part (the part's convex pieces, as
    the moves were planned against) at the samples of the moves, NaN on
    the cuts and where it was not computed, or None when not computed at
    all. On retract and approach the cutter itself is left out (one end
    of them is in the cut), as the plan leaves it out."""

    t: np.ndarray
    q: np.ndarray
    phase: np.ndarray
    cut: np.ndarray
    clearance: Optional[np.ndarray] = None

    def __post_init__(self):
        self.t = np.asarray(self.t, float)
        self.q = np.asarray(self.q, float).reshape(len(self.t), -1)
        self.phase = np.asarray(self.phase, int)
        self.cut = np.asarray(self.cut, int)
        if self.clearance is not None:
            self.clearance = np.asarray(self.clearance, float)
        for name in ("phase", "cut", "clearance"):
            value = getattr(self, name)
            if value is not None and value.shape != self.t.shape:
                raise ValueError(
                    f"JobSignals.{name}: shape {value.shape}, allowed "
                    f"{self.t.shape} (one value per sample of t)"
                )

    def in_phase(self, name: str) -> np.ndarray:
        """The samples in phase ``name`` (a mask)."""
        return self.phase == JOB_PHASE[name]


@dataclass
class EdgeRun:
    """One edge of the job as it was cut.

    ``position``: in the job's order (0: the first cut); ``index``: in
    the part's listing (``deburr-drake edges``); ``point`` (m, part
    frame): a point on the edge; ``length_m``: the edge's length;
    ``start_time`` / ``end_time`` (s, the job's time): the first and last
    sample of its cut; ``log``: its pass log (module docstring)."""

    position: int
    index: int
    point: np.ndarray
    length_m: float
    start_time: float
    end_time: float
    log: RunLog

    @property
    def completed(self) -> bool:
        """True when the cut reached the edge's end."""
        return self.log.completed_pass


@dataclass
class MoveRun:
    """One move between two cuts (retract, transit, approach).

    ``after``: the position in ``JobLog.edges`` of the cut it leaves (it
    goes to ``after + 1``); ``start_time`` / ``end_time`` (s, the job's
    time): its first and last sample (``end_time`` NaN when the run
    stopped on it); the plan's ``planned_duration_s``, ``travel_m`` (the
    tool tip's path length) and ``planned_min_clearance_m`` (the least
    distance to the part the plan checked)."""

    after: int
    start_time: float
    end_time: float
    planned_duration_s: float
    travel_m: float
    planned_min_clearance_m: float


@dataclass
class JobLog:
    """A job run's record (see the module docstring)."""

    scenario: Scenario  # the job's scenario as run
    edges: List[EdgeRun]
    moves: List[MoveRun]
    signals: JobSignals
    stop_reason: str = "duration"  # JOB_COMPLETE or as RunLog's
    stop_time: float = 0.0  # s
    stop_detail: str = ""
    wall_time: float = 0.0  # s
    sim_time: float = 0.0  # s
    steps: int = 0
    #: (part listing index, why) of the edges the plan selected but could
    #: not cut or reach, and of those the selection left out.
    refused: List[Tuple[int, str]] = field(default_factory=list)
    skipped: List[Tuple[int, str]] = field(default_factory=list)
    #: how many cuts the plan has (edges cut or not)
    planned_cuts: int = 0
    #: with touch probing, the probing sequence's log (``t`` and
    #: ``value``, MESH_PROBE_STATE), else None
    probe: Optional[dict] = None

    @property
    def completed(self) -> bool:
        """True when every planned cut reached its end."""
        return self.stop_reason == JOB_COMPLETE


class EdgeSource(NamedTuple):
    """What :func:`make_job_log` needs of one edge besides the shared
    loggers: the edge's ``index`` in the part's listing, ``point`` (m,
    part frame), ``length_m``, its single-edge ``scenario``, its own
    cutting process's logger (``process``: ``t`` and the PROCESS_STATE
    blocks), its ``final`` state blocks (``finish``, ``theta``, ``meta``
    as a pass's) and whether its cut reached the end (``completed``)."""

    index: int
    point: np.ndarray
    length_m: float
    scenario: Scenario
    process: Dict[str, np.ndarray]
    final: Signals
    completed: bool


def edge_window(signals: JobSignals, position: int) -> Optional[tuple]:
    """(start, end) s: the first and last sample of cut ``position``
    (None when it was never cut)."""
    times = signals.t[signals.cut == position]
    if not len(times):
        return None
    return float(times[0]), float(times[-1])


def slice_signals(logs: Signals, start: float, end: float) -> Signals:
    """Every logger of ``logs`` (``{name: {"t": ..., block: ...}}``) cut
    to its samples in [start, end] and counted from ``start``; blocks
    without ``t`` (a final state) are left out."""
    out = {}
    for name, blocks in logs.items():
        if "t" not in blocks:
            continue
        t = np.asarray(blocks["t"], float)
        keep = (t >= start - 1e-12) & (t <= end + 1e-12)
        out[name] = {
            block: (t[keep] - start if block == "t" else np.asarray(v)[keep])
            for block, v in blocks.items()
        }
    return out


def _moves(signals: JobSignals, planned: Sequence) -> List[MoveRun]:
    """A MoveRun per move begun: the samples between cut k's last and
    cut k + 1's first, in retract, move or approach."""
    out = []
    off = ~signals.in_phase("cut") & ~signals.in_phase("done")
    for k, move in enumerate(planned):
        cut_k = signals.t[signals.cut == k]
        if not len(cut_k):
            break
        after = off & (signals.t > cut_k[-1])
        following = signals.t[signals.cut == k + 1]
        if len(following):
            after &= signals.t < following[0]
        times = signals.t[after]
        if not len(times):
            break
        out.append(
            MoveRun(
                after=k,
                start_time=float(times[0]),
                end_time=float(times[-1]) if len(following) else np.nan,
                planned_duration_s=float(move.duration_s),
                travel_m=float(move.travel_m),
                planned_min_clearance_m=float(move.min_clearance_m),
            )
        )
    return out


def make_job_log(
    scenario: Scenario,
    edges: Sequence[EdgeSource],
    shared: Signals,
    signals: JobSignals,
    moves: Sequence = (),
    *,
    stop_reason: str,
    stop_time: float,
    stop_detail: str = "",
    wall_time: float = 0.0,
    steps: int = 0,
    refused: Sequence = (),
    skipped: Sequence = (),
    probe: Optional[dict] = None,
) -> JobLog:
    """The JobLog of a run: ``edges`` (an EdgeSource per planned cut, in
    the job's order), ``shared`` (the loggers every cut shares, over the
    whole run, as RunLog.signals: ``chamfer``, ``controller``, ...),
    ``signals`` (the job's) and ``moves`` (the plan's Move between cut k
    and k + 1, anything with ``duration_s``, ``travel_m`` and
    ``min_clearance_m``). An edge the run never cut is left out; each
    cut's pass log is ``shared`` and its own ``process`` sliced to its
    cut (:func:`edge_window`, :func:`slice_signals`) with its ``final``
    blocks."""
    runs = []
    for position, source in enumerate(edges):
        window = edge_window(signals, position)
        if window is None:
            continue
        start, end = window
        logged = slice_signals(
            {**shared, "process": source.process}, start, end
        )
        logged.update({k: dict(v) for k, v in source.final.items()})
        reason = "pass_complete" if source.completed else stop_reason
        log = RunLog(
            scenario=source.scenario,
            signals=logged,
            sim_time=end - start,
            completed_pass=bool(source.completed),
            stop_reason=reason,
            stop_time=end - start,
            stop_detail="" if source.completed else stop_detail,
        )
        runs.append(
            EdgeRun(
                position=position,
                index=int(source.index),
                point=np.asarray(source.point, float),
                length_m=float(source.length_m),
                start_time=start,
                end_time=end,
                log=log,
            )
        )
    return JobLog(
        scenario=scenario,
        edges=runs,
        moves=_moves(signals, moves),
        signals=signals,
        stop_reason=stop_reason,
        stop_time=float(stop_time),
        stop_detail=stop_detail,
        wall_time=float(wall_time),
        sim_time=float(stop_time),
        steps=int(steps),
        refused=list(refused),
        skipped=list(skipped),
        planned_cuts=len(edges),
        probe=probe,
    )
