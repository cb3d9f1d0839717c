"""Touch probing of a mesh part before the pass: the touches planned on its
faces, each approached along its face's normal, and the part's pose (and
a hole's size) registered from them, as a Drake system.

- :class:`MeshProbePlan`: the believed part's surface, the hole's faces,
  the planned touches (deburr_drake.math.touch_plan) and the height the
  probe travels at; made once per run (deburr_drake.cell.touches).
- :class:`MeshProbingSequence`: the planar
  :class:`~deburr_drake.control.probe.ProbingSequence`'s guarded moves,
  detection, stiffness measurement and detection-bias compensation, on
  the planned faces; the moves between touches leave the part along the
  face's normal, travel above the part and come down to the next
  touch's standoff. Then the registration
  (deburr_drake.math.mesh_registration.register_mesh), and the way to
  the pass's start on the registered part. Its ``registration`` is a
  pose and a size (deburr_drake.math.registration.POSE_REGISTRATION_SIZE),
  which moves the believed 3-D edge (its points, frames and tool axis).

The probe is a ball of the cutter's radius about the tool point (a
stylus, as the touch plan plans it): the touch on a face lies that radius
along the face's normal from the tool point's crossing.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np
from pydrake.systems.framework import EventStatus, LeafSystem

from deburr_drake.config import ProbeConfig
from deburr_drake.control.layout import CHAMFER_STATE, VectorLayout
from deburr_drake.control.probe import (
    CUT_ESTABLISHED,
    PROBE_MISSED,
    SensorTiming,
    SequenceOutputs,
    detection_depth,
    median_stiffness,
)
from deburr_drake.math.geometry import Contour
from deburr_drake.math.mesh_registration import MeshSurface, register_mesh
from deburr_drake.math.registration import (
    POSE_REGISTRATION_SIZE,
    moved_contour,
)
from deburr_drake.math.rigid import matrix_rotvec
from deburr_drake.math.touch_plan import TouchPlan

__all__ = [
    "MeshProbePlan",
    "MeshProbingSequence",
    "MESH_PROBE_STATE",
    "MESH_PHASES",
    "COVARIANCE_SIZE",
    "covariance_of",
    "register_part",
    "registered_contours",
]

#: The phases of the sequence, in order: for each touch lift (along the
#: last touch's normal, then up), over (at the safe height), down (to the
#: touch's standoff), settle, find (the fast first touch), back_off (off
#: the surface it found), steady, approach (the measuring touch),
#: retract; at the end the same way to the pass's start's standoff, and
#: the entry. Without a find speed settle goes on to approach.
MESH_PHASES = (
    "lift",
    "over",
    "down",
    "settle",
    "find",
    "back_off",
    "steady",
    "approach",
    "retract",
    "enter",
    "done",
)
_P = {name: float(k) for k, name in enumerate(MESH_PHASES)}

#: (omega (3), v (3), size): the registration's covariance is 7 x 7
#: (the size's row and column zero when it was not fitted).
COVARIANCE_SIZE = 7

MESH_PROBE_STATE = VectorLayout(
    "mesh_probe_state",
    [
        ("phase", 1),  # index into MESH_PHASES
        ("index", 1),  # the touch under way (N: on the way to the start)
        ("phase_start", 1),  # s
        ("segment_start", 3),  # m, world
        ("segment_end", 3),  # m
        ("segment_duration", 1),  # s
        ("linear", 1),  # 1: constant speed (guarded), 0: smooth
        ("command", 3),  # m, the commanded tool point
        ("tare", 3),  # N
        # w (rad), p (m) of x_real = Rot(w) x + p, the hole's size (m)
        ("registration", POSE_REGISTRATION_SIZE),
        # of (omega, v, size) about the fit's pivot (rad, m), row-major
        ("covariance", COVARIANCE_SIZE * COVARIANCE_SIZE),
        ("pivot", 3),  # m, world: the point the covariance's turn is about
        ("size_fitted", 1),  # 1 when the touches told the hole's size
        ("amplification", 1),  # the kept touches' noise amplification
        ("done_time", 1),  # s, -1 while probing
        ("cut_time", 1),  # s, -1 before the entry's cut is established
        ("touching", 1),  # 1 until the entry: the probe's contact model
        ("touches", 1),
        ("kept", 1),
        ("fit_rms", 1),  # m
        ("stiffness", 1),  # N/m, the touches' median, as the planar probe
        # m, world: the surface the touch under way's find touch found
        # (its crossing less the modelled detection depth)
        ("found", 3),
        # m, the command less the tool point at rest before the find
        ("rest_error", 3),
    ],
)

#: Per touch, the crossings of the guarded move: x, y, z (m), the speed
#: along the approach (m/s) at the first threshold, the way (m) on to the
#: second (0: not reached), and the direction of the tared force at the
#: deeper of the two (3): the part pushes the ball along the normal of
#: the face it touches, which on a hole's wall (a concave face, its
#: facets turned with the part) lies up to 20 degrees off the planned
#: face's normal.
_CROSSING = 8


@dataclass(frozen=True)
class MeshProbePlan:
    """What the sequence probes: ``surface`` the believed part (m,
    world), ``sized`` (F,) bool its hole's faces (None: no hole whose
    size is fitted), ``touches`` the planned touches on it, the tool
    point's ``safe_height`` (m, world z) for the travels above the part
    and the probe's ``radius`` (m, the ball about the tool point);
    ``allowance`` (N,) m: how far each touch's face may lie off the
    believed one along its normal (the part's pose allowance), which its
    standoff and its search add."""

    surface: MeshSurface
    sized: Optional[np.ndarray]
    touches: TouchPlan
    safe_height: float
    radius: float
    allowance: np.ndarray

    @property
    def count(self) -> int:
        return len(self.touches.points)

    def route(self, standoff: float) -> np.ndarray:
        """(2 N, 3) m: every touch's standoff point and the point above
        it at the safe height (where the probe goes, on the believed
        part)."""
        low = np.array(
            [self.standoff_point(i, standoff) for i in range(self.count)]
        )
        high = low.copy()
        high[:, 2] = self.safe_height
        return np.vstack([low, high])

    def standoff_point(self, i: int, standoff: float) -> np.ndarray:
        """The tool point ``standoff`` (m) and the touch's allowance off
        the believed face of touch ``i``, along its normal."""
        t = self.touches
        clear = self.radius + standoff + self.allowance[i]
        return t.points[i] + clear * t.normals[i]


class MeshProbingSequence(SequenceOutputs, LeafSystem):
    """Guarded moves at the planned touches of a mesh part, its
    registration, and the way to the pass's start on the registered part.

    .. pydrake_system::

        name: MeshProbingSequence
        input_ports:
        - chamfer_state
        - measured_force
        - command_in
        output_ports:
        - command
        - probing
        - hold
        - spindle
        - fuzzy_weight
        - registration
        - touching
        - probe_state
        - touch_points

    The ports are :class:`~deburr_drake.control.probe.ProbingSequence`'s
    but ``registration`` (POSE_REGISTRATION_SIZE: w, p, size; zero until
    the fit), ``touching`` (1, the plant's probe contact: 1 until the
    entry, when the tool is at the start's standoff off the registered
    part) and ``probe_state`` (MESH_PROBE_STATE). ``touch_points`` (N x
    4): x, y, z (m) of each compensated touch on the part's surface
    (the ball's radius taken off along the face's normal), 1 if contact
    was detected (2: dropped by the fit).

    Each touch: lift (back along the last touch's normal by ``retract``
    and up) to ``safe_height``, over to above the touch's standoff point
    (``standoff`` off the believed face along its normal), down to it
    (these at ``clear_travel_speed``), settle (``clear_settle_time``),
    tare. Then the find touch: a smooth move along minus the normal at a
    mean ``find_speed`` until the force against it exceeds
    ``force_threshold``; the face it found is its crossing less the
    modelled detection depth at its speed. Back off (at
    ``travel_speed``) to where the tool comes to rest ``find_backoff``
    off that face (the command less the arm's error at rest before the
    find), settle (``find_settle_time``), tare. Then the measuring touch:
    along minus the normal at ``approach_speed`` until the force exceeds
    ``force_threshold``, on to ``stiffness_threshold``, back by
    ``retract``. A find or measuring touch that finds nothing within its
    search (``search_distance`` and twice the touch's allowance, or
    ``search_distance`` and ``find_backoff``) ends the run,
    ``probe_missed:<touch index>``. With ``find_speed`` 0 the measuring
    touch starts from the standoff point. Then each touch
    compensated as the planar probe's (:func:`detection_depth` on the
    touches' median stiffness, ``detection_bias``) but along the force
    the ball felt (the touched face's normal), the registration
    (``max_residual``, the hole's size with ``fit_radius``), up, over and
    down (at ``entry_travel_speed``) to the standoff of the pass's start
    on the registered part, settle, and the entry along its n1 at the
    approach speed.
    """

    def __init__(
        self,
        contour: Contour,
        plan: MeshProbePlan,
        config: ProbeConfig,
        *,
        sample_period: float,
        timing: SensorTiming,
        initial_position,
        start_depth: float = 0.0,
        desired_depth: float = 0.0,
        touch_noise: Optional[float] = None,
    ):
        super().__init__()
        config.validate()
        self.set_name("probing_sequence")
        self._layout, self._done_phase = MESH_PROBE_STATE, _P["done"]
        self._contour = contour
        self._plan = plan
        self._config = config
        self._timing = timing
        self._start_depth = start_depth
        self._established_depth = CUT_ESTABLISHED * desired_depth
        self._touch_noise = touch_noise
        self._n = plan.count
        # State: the sequence, the touches and their crossings.
        self._state = self.DeclareDiscreteState(
            self._initial_state(np.asarray(initial_position, float))
        )
        self._touch_state = self.DeclareDiscreteState(np.zeros(4 * self._n))
        self._crossing_state = self.DeclareDiscreteState(
            np.zeros(_CROSSING * self._n)
        )
        # Inputs, and the sequence stepped at the sensor's samples.
        self._chamfer_port = self.DeclareVectorInputPort(
            "chamfer_state", CHAMFER_STATE.size
        )
        self._force_port = self.DeclareVectorInputPort("measured_force", 3)
        self._command_in = self.DeclareVectorInputPort("command_in", 3)
        self.DeclarePeriodicDiscreteUpdateEvent(
            sample_period, 0.0, self._update
        )
        # Outputs: all functions of the state (and command_in once done).
        state = {self.discrete_state_ticket(self._state)}
        self.DeclareVectorOutputPort(
            "command",
            3,
            self._calc_command,
            prerequisites_of_calc=state | {self._command_in.ticket()},
        )
        for name, calc in (
            ("probing", self._calc_probing),
            ("hold", self._calc_hold),
            ("spindle", self._calc_spindle),
            ("touching", self._calc_touching),
        ):
            self.DeclareVectorOutputPort(
                name, 1, calc, prerequisites_of_calc=state
            )
        self.DeclareVectorOutputPort(
            "fuzzy_weight",
            1,
            self._calc_fuzzy_weight,
            prerequisites_of_calc=state | {self.time_ticket()},
        )
        self.DeclareVectorOutputPort(
            "registration",
            POSE_REGISTRATION_SIZE,
            self._calc_registration,
            prerequisites_of_calc=state,
        )
        self.DeclareStateOutputPort("probe_state", self._state)
        self.DeclareStateOutputPort("touch_points", self._touch_state)

    # -- set-up ----------------------------------------------------------
    def _initial_state(self, x0):
        L = MESH_PROBE_STATE
        x = np.zeros(L.size)
        x[L.slice("command")] = x0
        for name in ("done_time", "cut_time"):
            x[L.slice(name)] = -1.0
        x[L.slice("touching")] = 1.0
        x[L.slice("stiffness")] = self._config.contact_stiffness
        self._lift(x, 0.0, x0)
        return x

    @property
    def plan(self) -> MeshProbePlan:
        return self._plan

    # -- moves -------------------------------------------------------------
    def _segment(self, x, t, phase, start, end, duration, linear):
        L = MESH_PROBE_STATE
        x[L.slice("phase")] = _P[phase]
        x[L.slice("phase_start")] = t
        x[L.slice("segment_start")] = start
        x[L.slice("segment_end")] = end
        x[L.slice("segment_duration")] = max(duration, 1e-9)
        x[L.slice("linear")] = 1.0 if linear else 0.0

    def _smooth(self, x, t, phase, start, end):
        """A smooth move at about ``clear_travel_speed`` (its mean), on
        the way to the pass's start at ``entry_travel_speed``."""
        c = self._config
        last = MESH_PROBE_STATE.get(x, "index") >= self._n
        speed = c.entry_travel_speed if last else c.clear_travel_speed
        length = float(np.linalg.norm(np.asarray(end) - start))
        self._segment(x, t, phase, start, end, max(length / speed, 0.05), False)

    def _lift(self, x, t, start):
        """Straight up to the safe height (from a touch's retract point,
        or from the start: its standoff, clear of the part)."""
        up = np.array([start[0], start[1], self._plan.safe_height])
        self._smooth(x, t, "lift", start, up)

    def _target(self, x) -> np.ndarray:
        """Where the next descent ends: the next touch's standoff point,
        or after the last touch the pass's start's standoff on the
        registered part."""
        i = int(round(float(MESH_PROBE_STATE.get(x, "index"))))
        if i < self._n:
            return self._plan.standoff_point(i, self._config.standoff)
        contour = self._registered(x)
        p = contour.point_at(0.0)
        return p - self._config.standoff * contour.n1(p)

    def _along(self, x, t):
        L = MESH_PROBE_STATE
        u = (t - L.get(x, "phase_start")) / L.get(x, "segment_duration")
        u = min(max(u, 0.0), 1.0)
        w = u if L.get(x, "linear") > 0.5 else u * u * (3 - 2 * u)
        a = L.get(x, "segment_start")
        b = L.get(x, "segment_end")
        return a + w * (b - a), u >= 1.0

    # -- the state machine -----------------------------------------------
    def _update(self, context, discrete_state):
        x = context.get_discrete_state(self._state).get_value()
        phase = MESH_PHASES[int(round(float(MESH_PROBE_STATE.get(x, "phase"))))]
        t = context.get_time()
        if phase == "done":
            self._watch_entry(context, x, t, discrete_state)
            return None
        x = x.copy()
        command, finished = self._along(x, t)
        x[MESH_PROBE_STATE.slice("command")] = command
        touches, crossings = (
            context.get_discrete_state(k).get_value().copy()
            for k in (self._touch_state, self._crossing_state)
        )
        status = self._step(
            phase, context, x, t, command, finished, touches, crossings
        )
        discrete_state.set_value(self._state, x)
        discrete_state.set_value(self._touch_state, touches)
        discrete_state.set_value(self._crossing_state, crossings)
        return status

    def _step(
        self, phase, context, x, t, command, finished, touches, crossings
    ):
        """What a sample does in ``phase`` (it writes ``x``, ``touches``
        and ``crossings``); an EventStatus for a missed touch."""
        L, c = MESH_PROBE_STATE, self._config
        i = int(round(float(L.get(x, "index"))))
        if phase == "approach":
            return self._approach(
                context, x, t, command, finished, touches, crossings, i
            )
        if phase == "find":
            return self._find(context, x, t, command, finished, i)
        if not finished:
            return None
        if phase == "lift":
            target = self._target(x)
            over = np.array([target[0], target[1], self._plan.safe_height])
            self._smooth(x, t, "over", command, over)
        elif phase == "over":
            self._smooth(x, t, "down", command, self._target(x))
        elif phase == "down":
            # Held until the arm's ringing after the move has died down:
            # before a touch for its tare, before the entry so that the
            # entry does not start with the tool still moving (the arm
            # overshoots the command then and cuts in too deep).
            self._segment(
                x, t, "settle", command, command, c.clear_settle_time, False
            )
        elif phase == "settle" and i == self._n:
            self._enter(x, t, command)
        elif phase == "settle":
            self._start_touch(context, x, t, command, i)
        elif phase == "back_off":
            self._segment(
                x, t, "steady", command, command, c.find_settle_time, False
            )
        elif phase == "steady":
            self._steady(context, x, t, command, i)
        elif phase == "retract":
            x[L.slice("index")] = i + 1
            if i + 1 == self._n:
                self._compensate(x, touches, crossings)
                self._fit(x, touches)
            self._lift(x, t, command)
        elif phase == "enter":
            x[L.slice("phase")] = _P["done"]
            x[L.slice("done_time")] = t
        return None

    def _enter(self, x, t, command):
        """On to the start on the registered part, along its n1."""
        contour = self._registered(x)
        p = contour.point_at(0.0)
        start = p + self._start_depth * contour.n1(p)
        self._segment(
            x,
            t,
            "enter",
            command,
            start,
            float(np.linalg.norm(start - command))
            / self._config.approach_speed,
            True,
        )
        x[MESH_PROBE_STATE.slice("touching")] = 0.0

    def _start_touch(self, context, x, t, command, i):
        """Touch ``i`` from its standoff, settled: the tare, then the
        find touch (or, without a find speed, the measuring touch)."""
        L, c = MESH_PROBE_STATE, self._config
        x[L.slice("tare")] = self._force_port.Eval(context)
        x_p = CHAMFER_STATE.get(self._chamfer_port.Eval(context), "x_p")
        x[L.slice("rest_error")] = command - x_p
        n = self._plan.touches.normals[i]
        search = self._search(i)
        if c.find_speed > 0:
            # The find touch: smooth, so it starts without a jerk the
            # sensor reads as a push (the tool's inertia), fastest
            # about the middle of its search, where the face is.
            self._segment(
                x,
                t,
                "find",
                command,
                command - search * n,
                search / c.find_speed,
                False,
            )
        else:
            self._guarded(x, t, command, n, search)

    def _steady(self, context, x, t, command, i):
        """After the find's back-off and settle: the measuring touch, or
        a further back-off if the tool rests too near the face."""
        L, c = MESH_PROBE_STATE, self._config
        m = self._plan.touches.normals[i]
        x_p = CHAMFER_STATE.get(self._chamfer_port.Eval(context), "x_p")
        off = float((x_p - L.get(x, "found")) @ m)
        if off < 0.5 * c.find_backoff:
            # The arm's friction held the tool nearer the face than
            # the back-off meant (or on it): back off by what is
            # missing before the tare.
            self._back_off(x, t, command, command + (c.find_backoff - off) * m)
            return
        x[L.slice("tare")] = self._force_port.Eval(context)
        # On to the find's own end at least: a find set off by the
        # reading (the arm still ringing at its tare) stopped short of
        # the face. The find starts at the touch's standoff point, where
        # the descent ends.
        find_end = self._target(x) - self._search(i) * m
        rest_of_find = float((command - find_end) @ m)
        self._guarded(
            x,
            t,
            command,
            m,
            max(c.find_backoff + c.search_distance, rest_of_find),
        )

    def _search(self, i) -> float:
        """m: touch ``i``'s search from its standoff, widened by what the
        allowed pose error can move its face."""
        c = self._config
        return c.search_distance + 2.0 * self._plan.allowance[i]

    def _guarded(self, x, t, command, m, search):
        """The measuring touch: along -``m`` (the face's normal) at the
        approach speed, ``search`` (m) at most."""
        speed = self._config.approach_speed
        end = command - search * m
        self._segment(x, t, "approach", command, end, search / speed, True)

    def _tared(self, context, x) -> np.ndarray:
        """N: the force reading less the tare."""
        return self._force_port.Eval(context) - MESH_PROBE_STATE.get(x, "tare")

    def _pushed(self, context, x, n) -> float:
        """N: the tared force against the approach's direction ``n``."""
        return -float(self._tared(context, x) @ n)

    def _find(self, context, x, t, command, finished, i):
        """The find touch: on contact the surface it found (the crossing
        less the modelled depth at its speed), then back off it."""
        c, L = self._config, MESH_PROBE_STATE
        n = -self._plan.touches.normals[i]
        if self._pushed(context, x, n) >= c.force_threshold:
            chamfer = self._chamfer_port.Eval(context)
            x_p = CHAMFER_STATE.get(chamfer, "x_p")
            speed = float(CHAMFER_STATE.get(chamfer, "xdot_p") @ n)
            depth = detection_depth(
                speed, c.force_threshold, c.contact_stiffness, self._timing
            )
            found = x_p - depth * n
            x[L.slice("found")] = found
            # Back along the normal, on the find's line, to where the
            # tool comes to rest find_backoff off that face: the arm's
            # error at rest before the find (the tool held off the
            # command) along the normal added.
            lead = float((command - found) @ n)
            rest = float(L.get(x, "rest_error") @ n)
            way = lead + c.find_backoff - rest
            self._back_off(x, t, command, command - way * n)
            return None
        if finished:
            return self._missed(x, i, n, "find touch")
        return None

    def _back_off(self, x, t, command, end):
        """A smooth move off the face to ``end`` (m) at about
        ``travel_speed``."""
        length = float(np.linalg.norm(end - command))
        self._segment(
            x,
            t,
            "back_off",
            command,
            end,
            max(length / self._config.travel_speed, 0.05),
            False,
        )

    def _missed(self, x, i, n, what):
        """The run's end at touch ``i``: its ``what`` (a guarded move
        along ``n``) found nothing within its search."""
        L, c = MESH_PROBE_STATE, self._config
        a = L.get(x, "segment_start")
        search = float(np.linalg.norm(L.get(x, "segment_end") - a))
        if what == "measuring touch" and c.find_speed > 0:
            within = (
                f"find_backoff {c.find_backoff:g} m, or on to the find "
                "touch's end"
            )
        else:
            within = f"twice the allowance {self._plan.allowance[i]:.3g} m"
        return EventStatus.ReachedTermination(
            self,
            f"{PROBE_MISSED}:{i}: no contact within {search:.3g} m "
            f"(search_distance {c.search_distance:g} m and {within}) "
            f"along {np.round(n, 6).tolist()} from "
            f"{np.round(a, 6).tolist()} m (the {what} of touch {i} of "
            f"{self._n} on the part's faces)",
        )

    def _approach(
        self, context, x, t, command, finished, touches, crossings, i
    ):
        c, L = self._config, MESH_PROBE_STATE
        n = -self._plan.touches.normals[i]  # the approach's direction
        f = self._tared(context, x)
        pushed = -float(f @ n)
        chamfer = self._chamfer_port.Eval(context)
        x_p = CHAMFER_STATE.get(chamfer, "x_p")
        row = slice(_CROSSING * i, _CROSSING * i + _CROSSING)
        touched = touches[4 * i + 3] > 0.5
        if not touched and pushed >= c.force_threshold:
            speed = float(CHAMFER_STATE.get(chamfer, "xdot_p") @ n)
            out = f / np.linalg.norm(f)
            crossings[row] = [*x_p, speed, 0.0, *out]
            touches[4 * i : 4 * i + 4] = [
                *self._touch(x_p, -out, speed, c.contact_stiffness),
                1.0,
            ]
            x[L.slice("touches")] += 1.0
            if c.stiffness_threshold > 0:
                return None
        elif touched and pushed >= c.stiffness_threshold:
            crossings[row.start + 4] = float((x_p - crossings[row][:3]) @ n)
            crossings[row.start + 5 : row.stop] = f / np.linalg.norm(f)
        elif not finished:
            return None
        elif not touched:
            return self._missed(x, i, n, "measuring touch")
        # Back from the touch along the face's normal.
        back = x_p - c.retract * n
        length = float(np.linalg.norm(back - command))
        self._segment(
            x,
            t,
            "retract",
            command,
            back,
            max(length / c.travel_speed, 0.05),
            False,
        )
        return None

    def _touch(self, x_p, n, speed, stiffness):
        """The touch on the part's surface: the ball's centre at the
        crossing ``x_p`` moving at ``speed`` along the approach, less the
        modelled depth at detection and the probe's qualified bias, plus
        the ball's radius, along ``n``: into the face the ball touched
        (against the force it felt)."""
        c = self._config
        depth = (
            detection_depth(speed, c.force_threshold, stiffness, self._timing)
            + c.detection_bias
        )
        return x_p + n * (self._plan.radius - depth)

    def _watch_entry(self, context, x, t, discrete_state):
        if MESH_PROBE_STATE.get(x, "cut_time") < 0 and (
            CHAMFER_STATE.get(self._chamfer_port.Eval(context), "delta")
            >= self._established_depth
            or t - MESH_PROBE_STATE.get(x, "done_time")
            >= self._config.entry_dwell
        ):
            x = x.copy()
            x[MESH_PROBE_STATE.slice("cut_time")] = t
            discrete_state.set_value(self._state, x)

    def _compensate(self, x, touches, crossings):
        """Every touch compensated with the stiffness the touches measured
        (their median), as the planar probe's."""
        c = self._config
        rows = crossings.reshape(self._n, _CROSSING)
        hit = touches[3::4] > 0.5
        spans = rows[:, 4][hit & (rows[:, 4] > 0)]
        if not len(spans):
            return
        k = median_stiffness(spans, c)
        x[MESH_PROBE_STATE.slice("stiffness")] = k
        for i in np.flatnonzero(hit):
            touches[4 * i : 4 * i + 3] = self._touch(
                rows[i, :3], -rows[i, 5:8], rows[i, 3], k
            )

    def _fit(self, x, touches):
        L = MESH_PROBE_STATE
        t = touches.reshape(self._n, 4)
        hit = t[:, 3] > 0.5
        try:
            registration, fit = register_part(
                self._plan, t[hit, :3], self._config, self._touch_noise
            )
        except ValueError:
            # The touches do not fix the part: the believed part stays
            # (probe_state: kept 0).
            return
        x[L.slice("registration")] = registration
        cov = np.zeros((COVARIANCE_SIZE, COVARIANCE_SIZE))
        k = fit.covariance.shape[0]
        cov[:k, :k] = fit.covariance
        x[L.slice("covariance")] = cov.ravel()
        x[L.slice("pivot")] = fit.pivot
        x[L.slice("size_fitted")] = 0.0 if fit.size is None else 1.0
        x[L.slice("amplification")] = fit.amplification
        x[L.slice("kept")] = float(fit.kept.sum())
        x[L.slice("fit_rms")] = fit.rms
        rows = np.flatnonzero(hit)[~fit.kept]
        t[rows, 3] = 2.0
        touches[:] = t.ravel()

    def _registered(self, x) -> Contour:
        return moved_contour(
            self._contour, MESH_PROBE_STATE.get(x, "registration")
        )

    # -- outputs ---------------------------------------------------------
    def _calc_touching(self, context, output):
        output.SetAtIndex(
            0, float(MESH_PROBE_STATE.get(self._x(context), "touching"))
        )


def register_part(
    plan: MeshProbePlan, points, config: ProbeConfig, touch_noise=None
):
    """(registration, fit): the part's pose and the hole's size from
    compensated touches ``points`` ((N, 3), m, on the real part's
    surface) on the believed part of ``plan`` (deburr_drake.math.
    mesh_registration.register_mesh with ``max_residual``, the size with
    ``fit_radius``, the per-touch error no smaller than ``touch_error``),
    as a POSE_REGISTRATION_SIZE vector (w, p, size) that
    :func:`registered_contours` moves edges by, and the MeshFit.
    ValueError: touches that do not fix the pose."""
    fit = register_mesh(
        plan.surface,
        points,
        max_residual=config.max_residual,
        touch_noise=touch_noise,
        touch_error=config.touch_error,
        sized_faces=plan.sized if config.fit_radius else None,
    )
    size = 0.0 if fit.size is None else fit.size
    registration = np.array(
        [*matrix_rotvec(fit.rotation), *fit.translation, size]
    )
    return registration, fit


def registered_contours(contours, registration) -> list:
    """Every edge of a part (``contours``, believed) moved by the part's
    one ``registration`` (:func:`register_part`): a whole-part job
    registers the part once and cuts each edge on the part it found."""
    return [moved_contour(c, registration) for c in contours]


def covariance_of(state) -> np.ndarray:
    """The registration's covariance (7 x 7) in a MESH_PROBE_STATE
    vector."""
    return np.asarray(MESH_PROBE_STATE.get(state, "covariance")).reshape(
        COVARIANCE_SIZE, COVARIANCE_SIZE
    )
