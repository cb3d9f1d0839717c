"""The job's sequencer: what a whole part's run does at each moment, as a
Drake system, the phases it goes through and the layout of its state.

A job cuts its edges in order. Each cut runs the paper's force loop on
its edge; between two cuts the tool retracts up the cut's tool axis,
moves in free space along the planned joint path and comes down the next
cut's tool axis onto its start (deburr_drake.cell.moves plans the three
as one joint path). The run ends in ``done`` when the last cut has
reached its end. With touch probing the job begins in ``probe``: the
part's touches and its registration (deburr_drake.control.mesh_probe),
then every cut on the registered part and every move moved with it.
:class:`JobSequencer` is modelled on the touch probing's
ProbingSequence (deburr_drake.control.probe): it holds the command
generator and gates the force loop the same way."""

from __future__ import annotations

from typing import Callable, NamedTuple, Optional, Sequence

import numpy as np
from pydrake.systems.framework import EventStatus, LeafSystem

from deburr_drake.control.layout import (
    CHAMFER_STATE,
    COMMAND_STATE,
    VectorLayout,
)
from deburr_drake.control.probe import CUT_ESTABLISHED

__all__ = [
    "JOB_PHASES",
    "JOB_PHASE",
    "JOB_STATE",
    "JOB_COMPLETE",
    "CutPlan",
    "MovePlan",
    "JobProbe",
    "JobSequencer",
    "ActuationSwitch",
]

#: The phases of a job, in the order each cut goes through them, and
#: ``probe`` (touch probing, once, before the first cut); a phase's code
#: in the logs is its index here.
JOB_PHASES = ("cut", "retract", "move", "approach", "done", "probe")
#: phase name -> code.
JOB_PHASE = {name: k for k, name in enumerate(JOB_PHASES)}

#: The stop reason of a job whose every cut reached its end.
JOB_COMPLETE = "job_complete"

#: The sequencer's discrete state.
JOB_STATE = VectorLayout(
    "job_state",
    [
        ("phase", 1),  # code, index into JOB_PHASES
        ("cut", 1),  # position in the job's order of the cut under way
        # (or, on retract, move and approach, of the cut just left)
        ("phase_start", 1),  # s, when the phase began
        ("established", 1),  # s, the cut's entry established; -1 before
        ("move_start", 1),  # s, the move's (its retract's) start; -1 on cuts
    ],
)


class MovePlan(NamedTuple):
    """A planned move in joint space: ``times`` (s, (k,), from 0) and
    ``path`` (rad or m, (k, n)); the retract ends at ``retract_end`` (s)
    and the approach begins at ``approach_start`` (s)."""

    times: np.ndarray
    path: np.ndarray
    retract_end: float
    approach_start: float

    @property
    def duration(self) -> float:
        return float(self.times[-1])

    def reference(self, t: float, path=None) -> np.ndarray:
        """[q; v] at ``t`` s into the move: the path's (or ``path``'s, the
        same shape: the path moved with a registered part)
        piecewise-linear interpolation and its slope (at rest before and
        after)."""
        times = self.times
        path = self.path if path is None else path
        if t <= times[0] or t >= times[-1]:
            q = path[0] if t <= times[0] else path[-1]
            return np.concatenate([q, np.zeros(path.shape[1])])
        k = int(np.searchsorted(times, t, side="right")) - 1
        k = min(max(k, 0), len(times) - 2)
        span = times[k + 1] - times[k]
        w = (t - times[k]) / span
        q = (1.0 - w) * path[k] + w * path[k + 1]
        return np.concatenate([q, (path[k + 1] - path[k]) / span])


class CutPlan(NamedTuple):
    """What the sequencer needs of one cut: the arc (m, on the contour
    the command generator runs on) its command must reach for the cut to
    end, and the move that follows it (None after the last)."""

    end_arc: float
    move: Optional[MovePlan]


class JobProbe(NamedTuple):
    """A job's touch probing, as the sequencer sees it: ``registration``
    (the size of the probe's registration output) and ``move`` (a
    planned joint path (k, n) and a registration -> the path with the
    tool's every pose moved as the registration moves the part)."""

    registration: int
    move: Callable[[np.ndarray, np.ndarray], np.ndarray]


class JobSequencer(LeafSystem):
    """The job's phases in the Diagram: each cut with the paper's force
    loop, then retract, move and approach under position control along
    the planned joint path, then the next cut; the run ends with
    ``job_complete`` when the last cut's command reaches its end.

    .. pydrake_system::

        name: JobSequencer
        input_ports:
        - command_state
        - chamfer_state
        - probing (optional)
        - registration (optional)
        output_ports:
        - job_state
        - cutting
        - force_loop
        - off_part
        - hold
        - fuzzy_weight
        - joint_reference
        - spindles

    - ``command_state`` (COMMAND_STATE): the command generator's state;
      its arc position says how far the cut has gone.
    - ``chamfer_state`` (CHAMFER_STATE, the observer's, not gated): its
      depth delta says when the cut's entry is established.
    - ``probing`` (1) and ``registration`` (``probe.registration``),
      only with a ``probe`` (JobProbe): the probing sequence's, 1 until
      it is done, and the part's pose it registered.
    - ``job_state`` (JOB_STATE): the discrete state below.
    - ``cutting`` (1): 1 in the cut phase (the force loop cuts, the
      estimator and the controller adapt), else 0; ``off_part`` (1): 1 -
      ``cutting`` (the gate's: no contact seen off the part).
    - ``force_loop`` (1): 1 where the force loop drives the arm: the cuts
      and the probing (its touches are the loop's guarded moves), else 0
      (the position loop's moves).
    - ``hold`` (1): 1 but in a cut once its entry is established (the
      command generator's hold: no feed on the way in, nor off the part).
    - ``fuzzy_weight`` (1): the fuzzy compensator's weight: 1 in a cut
      from its entry on (the rules learned on the edges before carry
      over), 0 off the part (no adaptation: a move is not cutting).
    - ``joint_reference`` (2 n): [q; v] (rad, rad/s) along the move under
      way, the planned path's; in a cut the next move's start at rest
      (not used there).
    - ``spindles`` (one per cut): 1 for the cut the tool is at (its cut
      and retract, and the approach to it), else 0: each edge's cutting
      process runs only there.
    - Discrete state (JOB_STATE), updated every ``period`` s; with a
      ``probe`` also every move's path (rad, flattened, in the cuts'
      order), the planned ones until probing ends, then moved by the
      registration (``probe.move``), once.

    A cut's entry is established once delta reaches ``CUT_ESTABLISHED``
    of ``desired_depth`` or ``entry_dwell`` s have passed; the first cut
    starts in contact, as a single pass does, established at once. With
    a ``probe`` the job starts in ``probe`` and the first cut begins when
    the probing sequence is done (it brings the tool into contact at the
    first cut's start on the registered part), established as the
    others are."""

    def __init__(
        self,
        cuts: Sequence[CutPlan],
        *,
        period: float,
        desired_depth: float,
        entry_dwell: float,
        num_positions: int,
        probe: Optional[JobProbe] = None,
    ):
        super().__init__()
        if not cuts:
            raise ValueError("a job needs one cut at least")
        for k, cut in enumerate(cuts[:-1]):
            if cut.move is None:
                raise ValueError(f"cut {k}: no move to cut {k + 1}")
        self.set_name("job_sequencer")
        self._cuts = list(cuts)
        self._established_depth = CUT_ESTABLISHED * desired_depth
        self._entry_dwell = entry_dwell
        self._n = num_positions
        self._probe = probe
        self._state = self.DeclareDiscreteState(
            JOB_STATE.pack(
                phase=JOB_PHASE["cut" if probe is None else "probe"],
                cut=0,
                phase_start=0.0,
                established=0.0 if probe is None else -1.0,
                move_start=-1.0,
            )
        )
        self._command = self.DeclareVectorInputPort(
            "command_state", COMMAND_STATE.size
        )
        self._chamfer = self.DeclareVectorInputPort(
            "chamfer_state", CHAMFER_STATE.size
        )
        self._paths = self._probing = self._registration = None
        if probe is not None:
            self._probing = self.DeclareVectorInputPort("probing", 1)
            self._registration = self.DeclareVectorInputPort(
                "registration", probe.registration
            )
        if probe is not None and len(self._cuts) > 1:
            self._paths = self.DeclareDiscreteState(
                np.concatenate([c.move.path.ravel() for c in self._cuts[:-1]])
            )
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._update)
        self.DeclareStateOutputPort("job_state", self._state)
        state = {self.xd_ticket()}
        for name, calc in (
            ("cutting", self._calc_cutting),
            ("force_loop", self._calc_force_loop),
            ("off_part", self._calc_off_part),
            ("hold", self._calc_hold),
            ("fuzzy_weight", self._calc_fuzzy_weight),
        ):
            self.DeclareVectorOutputPort(
                name, 1, calc, prerequisites_of_calc=state
            )
        self.DeclareVectorOutputPort(
            "joint_reference",
            2 * num_positions,
            self._calc_reference,
            prerequisites_of_calc={self.xd_ticket(), self.time_ticket()},
        )
        self.DeclareVectorOutputPort(
            "spindles",
            len(self._cuts),
            self._calc_spindles,
            prerequisites_of_calc=state,
        )

    @property
    def cuts(self):
        return tuple(self._cuts)

    def _x(self, context):
        return context.get_discrete_state(self._state).get_value()

    def phase(self, context) -> str:
        """The phase under way (a name of JOB_PHASES)."""
        return JOB_PHASES[int(JOB_STATE.get(self._x(context), "phase"))]

    def cut(self, context) -> int:
        """The cut under way, or just left on a move."""
        return int(JOB_STATE.get(self._x(context), "cut"))

    # -- the phases ------------------------------------------------------
    def _update(self, context, discrete_state):
        x = self._x(context)
        t = context.get_time()
        phase = JOB_PHASES[int(JOB_STATE.get(x, "phase"))]
        k = int(JOB_STATE.get(x, "cut"))
        if phase == "done":
            return EventStatus.Succeeded()
        if phase == "probe":
            return self._probed(context, discrete_state, t)
        if phase == "cut":
            return self._cutting(context, discrete_state, x, t, k)
        move = self._cuts[k].move
        into = t - float(JOB_STATE.get(x, "move_start"))
        ends = {
            "retract": (move.retract_end, "move", k),
            "move": (move.approach_start, "approach", k),
            "approach": (move.duration, "cut", k + 1),
        }
        end, following, cut = ends[phase]
        if into >= end:
            moving = following != "cut"
            self._enter(
                discrete_state,
                following,
                cut,
                t,
                move_start=float(JOB_STATE.get(x, "move_start"))
                if moving
                else -1.0,
            )
        return EventStatus.Succeeded()

    def _enter(self, discrete_state, phase, cut, t, *, move_start=-1.0):
        discrete_state.set_value(
            self._state,
            JOB_STATE.pack(
                phase=JOB_PHASE[phase],
                cut=cut,
                phase_start=t,
                established=-1.0,
                move_start=move_start,
            ),
        )

    def _probed(self, context, discrete_state, t):
        """Probing: once the sequence is done, every move's path moved
        by the registration, and the first cut."""
        if self._probing.Eval(context)[0] > 0.5:
            return EventStatus.Succeeded()
        registration = self._registration.Eval(context)
        paths = [
            self._probe.move(c.move.path, registration).ravel()
            for c in self._cuts[:-1]
        ]
        if paths:
            discrete_state.set_value(self._paths, np.concatenate(paths))
        self._enter(discrete_state, "cut", 0, t)
        return EventStatus.Succeeded()

    def _path(self, context, k) -> Optional[np.ndarray]:
        """Cut k's move's path as the arm follows it: the planned one, or
        with probing the one moved with the registered part."""
        if self._paths is None:
            return None
        n = self._n
        start = sum(c.move.path.size for c in self._cuts[:k])
        size = self._cuts[k].move.path.size
        flat = context.get_discrete_state(self._paths).get_value()
        return np.asarray(flat[start : start + size]).reshape(-1, n)

    def _cutting(self, context, discrete_state, x, t, k):
        if JOB_STATE.get(x, "established") < 0:
            depth = CHAMFER_STATE.get(self._chamfer.Eval(context), "delta")
            waited = t - float(JOB_STATE.get(x, "phase_start"))
            if depth >= self._established_depth or waited >= self._entry_dwell:
                established = x.copy()
                established[JOB_STATE.slice("established")] = t
                discrete_state.set_value(self._state, established)
            return EventStatus.Succeeded()
        arc = COMMAND_STATE.get(self._command.Eval(context), "arc_position")
        if arc < self._cuts[k].end_arc:
            return EventStatus.Succeeded()
        if k == len(self._cuts) - 1:
            self._enter(discrete_state, "done", k, t)
            return EventStatus.ReachedTermination(
                self,
                f"{JOB_COMPLETE}: cut {k} reached its end at t = {t:.4f} s",
            )
        self._enter(discrete_state, "retract", k, t, move_start=t)
        return EventStatus.Succeeded()

    # -- outputs ---------------------------------------------------------
    def _phase_code(self, context) -> int:
        return int(JOB_STATE.get(self._x(context), "phase"))

    def _calc_cutting(self, context, output):
        output.SetAtIndex(
            0, 1.0 if self._phase_code(context) == JOB_PHASE["cut"] else 0.0
        )

    def _calc_force_loop(self, context, output):
        driving = (JOB_PHASE["cut"], JOB_PHASE["probe"])
        output.SetAtIndex(
            0, 1.0 if self._phase_code(context) in driving else 0.0
        )

    def _calc_off_part(self, context, output):
        output.SetAtIndex(
            0, 0.0 if self._phase_code(context) == JOB_PHASE["cut"] else 1.0
        )

    def _established(self, context) -> bool:
        x = self._x(context)
        return (
            int(JOB_STATE.get(x, "phase")) == JOB_PHASE["cut"]
            and JOB_STATE.get(x, "established") >= 0
        )

    def _calc_hold(self, context, output):
        output.SetAtIndex(0, 0.0 if self._established(context) else 1.0)

    def _calc_fuzzy_weight(self, context, output):
        output.SetAtIndex(0, 1.0 if self._established(context) else 0.0)

    def _calc_reference(self, context, output):
        x = self._x(context)
        k = int(JOB_STATE.get(x, "cut"))
        phase = int(JOB_STATE.get(x, "phase"))
        j = k if self._cuts[k].move is not None else k - 1
        if j < 0:  # one cut: nowhere to go
            output.SetFromVector(np.zeros(2 * self._n))
            return
        move = self._cuts[j].move
        at_rest = (JOB_PHASE["cut"], JOB_PHASE["done"], JOB_PHASE["probe"])
        if phase in at_rest:
            into = 0.0 if j == k else move.duration
        else:
            into = context.get_time() - float(JOB_STATE.get(x, "move_start"))
        output.SetFromVector(move.reference(into, self._path(context, j)))

    def _calc_spindles(self, context, output):
        x = self._x(context)
        k = int(JOB_STATE.get(x, "cut"))
        phase = int(JOB_STATE.get(x, "phase"))
        on = np.zeros(len(self._cuts))
        if phase in (JOB_PHASE["cut"], JOB_PHASE["retract"]):
            on[k] = 1.0
        elif phase == JOB_PHASE["approach"]:
            on[k + 1] = 1.0
        output.SetFromVector(on)


class ActuationSwitch(LeafSystem):
    """The drives' command: the force loop's in a job's cuts, the
    position loop's on its moves.

    .. pydrake_system::

        name: ActuationSwitch
        input_ports:
        - cutting
        - force_loop
        - position_loop
        output_ports:
        - actuation

    ``cutting`` (1) from the JobSequencer; ``force_loop`` and
    ``position_loop`` (nu, N m): the two loops' actuation. Only the one
    in use is evaluated."""

    def __init__(self, size: int):
        super().__init__()
        self.set_name("actuation_switch")
        self._cutting = self.DeclareVectorInputPort("cutting", 1)
        self._force = self.DeclareVectorInputPort("force_loop", size)
        self._position = self.DeclareVectorInputPort("position_loop", size)
        self.DeclareVectorOutputPort("actuation", size, self._calc)

    def _calc(self, context, output):
        cutting = self._cutting.Eval(context)[0] > 0.5
        port = self._force if cutting else self._position
        output.SetFromVector(port.Eval(context))
