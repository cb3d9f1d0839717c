"""Touch probing before the pass: the robot's procedure, with the spindle
off, as Drake systems.

- :class:`ProbingSequence`: a state machine in the Context's discrete state
  that commands guarded moves along the believed normal n1 at N points of
  the edge, detects each contact on the force sensor, measures the
  contact's stiffness on the way to a second threshold
  (:func:`measured_stiffness`), compensates the detection bias
  (:func:`detection_depth` with it and the calibrated
  ``detection_bias``), fits the circle, straight edge or profile and,
  ``fit_radius``, its size where the touches tell it
  (deburr_drake.math.registration, touches that came early on a burr
  dropped), outputs the registration that corrects the
  believed part, and brings the tool to the pass's start on the corrected
  part; then it hands the command over to the command generator.
- :class:`ProbeGate`: while probing, the estimator, the force loop and the
  guards see no contact (the touches are not chamfering).

:func:`probe_arcs` places the touches; :func:`detection_depth` is the bias
model, :func:`measured_stiffness` the stiffness it is given.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from pydrake.systems.framework import EventStatus, LeafSystem

from deburr_drake.config import ConfigError, ProbeConfig
from deburr_drake.control.layout import CHAMFER_STATE, VectorLayout
from deburr_drake.math.geometry import CircularContour, Contour, StraightContour
from deburr_drake.math.registration import (
    MAX_AMPLIFICATION,
    REGISTRATION_SIZE,
    moved_contour,
    registration_from_points,
    rigid_fit_amplification,
)

__all__ = [
    "PROBE_MISSED",
    "ProbingSequence",
    "SequenceOutputs",
    "ProbeGate",
    "PROBE_STATE",
    "PHASES",
    "CUT_ESTABLISHED",
    "probe_arcs",
    "check_probe_layout",
    "detection_depth",
    "measured_stiffness",
    "median_stiffness",
    "fuzzy_weight",
    "filter_latency",
    "sensor_timing",
    "SensorTiming",
]

#: The stop reason of a run a touch found nothing in:
#: ``probe_missed:<touch index>``.
PROBE_MISSED = "probe_missed"

#: The phases of the sequence, in order.
PHASES = ("travel", "settle", "approach", "retract", "return", "enter", "done")
_P = {name: float(k) for k, name in enumerate(PHASES)}

#: The entry's cut counts as established (the command generator starts to
#: feed) once the depth on the registered part reaches this fraction of
#: the desired depth (or ``entry_dwell`` has passed).
CUT_ESTABLISHED = 0.9

PROBE_STATE = VectorLayout(
    "probe_state",
    [
        ("phase", 1),  # index into PHASES
        ("index", 1),  # the touch under way
        ("phase_start", 1),  # s
        ("segment_start", 3),  # m, world: the command moves from here ...
        ("segment_end", 3),  # m, ... to here
        ("segment_duration", 1),  # s
        ("linear", 1),  # 1: constant speed (guarded), 0: smooth
        # A travel along the edge at the standoff (1), from arc to arc (m;
        # the registered contour's on the way back), else a straight move.
        ("along_edge", 1),
        ("arc_from", 1),
        ("arc_to", 1),
        ("command", 3),  # m, the commanded tool point
        ("tare", 3),  # N, the force reading before the guarded move
        ("registration", REGISTRATION_SIZE),  # dx, dy, dyaw, dradius
        ("done_time", 1),  # s, -1 while probing
        ("cut_time", 1),  # s, the entry's cut established; -1 before
        ("touches", 1),  # touches made (contact detected)
        ("kept", 1),  # touches the fit used
        ("fit_rms", 1),  # m, the fit's residual RMS
        # N/m, the contact's stiffness at force_threshold the touches
        # measured (their median; contact_stiffness when none did).
        ("stiffness", 1),
    ],
)


class SensorTiming(NamedTuple):
    """How a force reading lags the truth, for a system sampled with the
    sensor (s): ``lag``, the first-order filter y += a (raw - y),
    a = 1 - exp(-2 pi f_c T), lags a ramp by T (1 - a) / a once settled;
    ``delay``, the reader sees the value before the filter's update at the
    same instant (T) and a crossing falls on average T / 2 before the
    sample that detects it (1.5 T)."""

    lag: float
    delay: float

    @property
    def latency(self) -> float:
        """s, the settled total: lag + delay."""
        return self.lag + self.delay


def sensor_timing(
    sample_period: float, cutoff_frequency: float
) -> SensorTiming:
    """The :class:`SensorTiming` of the sensor's filter and sampling."""
    a = 1.0 - math.exp(-2.0 * math.pi * cutoff_frequency * sample_period)
    return SensorTiming(
        lag=sample_period * (1.0 - a) / a, delay=1.5 * sample_period
    )


def filter_latency(sample_period: float, cutoff_frequency: float) -> float:
    """s: the settled latency of :func:`sensor_timing`."""
    return sensor_timing(sample_period, cutoff_frequency).latency


def detection_depth(
    speed: float, threshold: float, stiffness: float, timing: SensorTiming
) -> float:
    """m: how deep past the zero-depth path the tool is when a guarded move
    at ``speed`` (m/s) detects contact on a contact of linear
    ``stiffness`` (N/m): the filtered force of the ramp k v t,
    k v (t - lag (1 - exp(-t / lag))), reaches ``threshold`` at t, and the
    tool moves on for ``delay``: v (t + delay). At rest: threshold /
    stiffness."""
    v = max(float(speed), 0.0)
    if v == 0.0:
        return threshold / stiffness
    rate = stiffness * v  # N/s
    lag = timing.lag
    t = threshold / rate + lag  # the settled answer, an upper bound
    for _ in range(50):  # Newton on g(t) = t - lag (1 - e^(-t/lag)) - F/kv
        e = math.exp(-t / lag) if lag > 0 else 0.0
        g = t - lag * (1.0 - e) - threshold / rate
        dg = 1.0 - e
        if dg <= 0.0:
            break
        step = g / dg
        t -= step
        if abs(step) < 1e-12:
            break
    return v * (t + timing.delay)


#: Shifts (fractions of L / N) tried for a profile's even layout.
_LAYOUT_SHIFTS = 32


def probe_arcs(contour: Contour, config: ProbeConfig) -> np.ndarray:
    """Arc positions (m) of the N touches on ``contour``: ``spacing``
    apart from ``first_arc`` (a closed edge wraps), or spread evenly
    (``spacing`` 0: a circle from ``first_arc``, an open edge centred, any
    other closed edge (a profile) L / N apart from ``first_arc`` plus the
    shift, among 32 steps of L / (32 N), that best fixes its move and turn
    (the smallest :func:`rigid_fit_amplification`): touches in the middle
    of every side of a square, and in the middle of its fillets, see no
    turn)."""
    n, L = config.points, contour.length
    if contour.closed:
        step = config.spacing or L / n
        arcs = (config.first_arc + step * np.arange(n)) % L
        if config.spacing or isinstance(contour, CircularContour):
            return arcs
        gains = [
            rigid_fit_amplification(
                contour,
                np.array(
                    [
                        contour.point_at(s)
                        for s in arcs + k * step / _LAYOUT_SHIFTS
                    ]
                ),
            )
            for k in range(_LAYOUT_SHIFTS)
        ]
        best = int(np.argmin(gains))
        return (arcs + best * step / _LAYOUT_SHIFTS) % L
    if not math.isfinite(L) and not config.spacing:
        raise ConfigError(
            "localisation.probe.spacing = 0 is invalid on an edge of "
            "infinite length: allowed > 0"
        )
    step = config.spacing or L / n
    span = step * (n - 1)
    first = config.first_arc if config.spacing else 0.5 * (L - span)
    return first + step * np.arange(n)


def check_probe_layout(
    contour: Contour, config: ProbeConfig, arcs=None
) -> None:
    """One ConfigError naming ``localisation.probe.points`` (or
    ``spacing``) when touches at ``arcs`` (default :func:`probe_arcs`) on
    the believed ``contour`` cannot fix its registration: a profile needs
    touches on sides that are not parallel
    (:func:`~deburr_drake.math.registration.rigid_fit_amplification` at
    most ``MAX_AMPLIFICATION``). A circle and a straight edge are fixed by
    any 3 distinct touches."""
    if isinstance(contour, (CircularContour, StraightContour)):
        return
    arcs = probe_arcs(contour, config) if arcs is None else arcs
    points = np.array([contour.point_at(s) for s in arcs])
    gain = rigid_fit_amplification(contour, points)
    if gain > MAX_AMPLIFICATION:
        name = "spacing" if config.spacing else "points"
        raise ConfigError(
            f"localisation.probe.{name} = {getattr(config, name)!r} is "
            f"invalid: the {len(arcs)} touches at arcs "
            f"{np.round(np.asarray(arcs) * 1e3, 1).tolist()} mm do not fix "
            f"the {type(contour).__name__}'s position and turn (noise "
            f"amplification {gain:.3g} > {MAX_AMPLIFICATION:g}): spread "
            "them over sides that are not parallel"
        )


#: Per touch, the crossings of the guarded move: x, y, z (m) and the
#: speed along n1 (m/s) at the first threshold, the way (m) on to the
#: second (0: not reached).
_CROSSING = 5


def measured_stiffness(
    span: float,
    threshold: float,
    second: float,
    exponent: float,
    exponent_slope: float = 0.0,
) -> float:
    """N/m: the stiffness F / delta at ``threshold`` (N) of a contact
    F = c delta^exponent exp(-exponent_slope delta), whose local
    exponent d ln F / d ln delta = exponent - exponent_slope delta falls
    with depth (1/m), that took ``span`` (m) more depth to reach
    ``second`` (N). The depth delta at the threshold solves
    exponent ln(1 + span / delta) - exponent_slope span = ln(second /
    threshold); without the slope delta = span / ((second /
    threshold)^(1 / exponent) - 1) (linear: the slope (second -
    threshold) / span)."""
    target = math.log(second / threshold) + exponent_slope * span
    # ln(1 + span / delta) = target / exponent: one root, the left side
    # falls from infinity to 0 as delta grows.
    ratio = math.expm1(target / exponent)
    return threshold * ratio / span


def median_stiffness(spans, config: ProbeConfig) -> float:
    """N/m: the median of :func:`measured_stiffness` over the touches'
    ``spans`` (m, the way from ``force_threshold`` to
    ``stiffness_threshold``): a touch on a burr measures the burr's."""
    c = config
    return float(
        np.median(
            [
                measured_stiffness(
                    span,
                    c.force_threshold,
                    c.stiffness_threshold,
                    c.contact_exponent,
                    c.contact_exponent_slope,
                )
                for span in spans
            ]
        )
    )


def fuzzy_weight(done_time: float, t: float, ramp: float) -> float:
    """The fuzzy compensator's weight at ``t`` (s): 0 while probing
    (``done_time`` < 0), then a ramp to 1 over ``ramp`` (s)."""
    if done_time < 0:
        return 0.0
    return 1.0 if ramp <= 0 else min(1.0, (t - done_time) / ramp)


class _Step(NamedTuple):
    """One sample of the sequence: its context, the state x, the touch
    points and crossings being written, the time, the command and
    whether the move under way has finished."""

    context: object
    x: np.ndarray
    t: float
    command: np.ndarray
    finished: bool
    touches: np.ndarray
    crossings: np.ndarray


class SequenceOutputs:
    """The outputs a probing sequence computes from its state the same way
    whatever part it touches. The sequence sets ``_state`` (its discrete
    state's index), ``_layout`` (that state's VectorLayout, with phase,
    command, cut_time, done_time and registration), ``_done_phase`` (the
    phase's code once done), ``_command_in`` and ``_config``."""

    def _x(self, context):
        return context.get_discrete_state(self._state).get_value()

    def _done(self, context) -> bool:
        return self._layout.get(self._x(context), "phase") == self._done_phase

    def _calc_command(self, context, output):
        if self._done(context):
            output.SetFromVector(self._command_in.Eval(context))
        else:
            output.SetFromVector(self._layout.get(self._x(context), "command"))

    def _calc_probing(self, context, output):
        output.SetAtIndex(0, 0.0 if self._done(context) else 1.0)

    def _calc_hold(self, context, output):
        cut = self._layout.get(self._x(context), "cut_time")
        output.SetAtIndex(0, 1.0 if cut < 0 else 0.0)

    def _calc_spindle(self, context, output):
        output.SetAtIndex(0, 1.0 if self._done(context) else 0.0)

    def _calc_fuzzy_weight(self, context, output):
        done = float(self._layout.get(self._x(context), "done_time"))
        output.SetAtIndex(
            0,
            fuzzy_weight(
                done, context.get_time(), self._config.fuzzy_ramp_time
            ),
        )

    def _calc_registration(self, context, output):
        output.SetFromVector(self._layout.get(self._x(context), "registration"))


class ProbingSequence(SequenceOutputs, LeafSystem):
    """Guarded moves at N points of the believed edge, the fit, and the way
    to the pass's start on the corrected part.

    .. pydrake_system::

        name: ProbingSequence
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
        - probe_state
        - touch_points

    - ``chamfer_state`` (CHAMFER_STATE): x_p (m) and xdot_p (m/s) are read.
    - ``measured_force`` (3, N, world): the force sensor's reading.
    - ``command_in`` (3, m): the command generator's x_c, passed through to
      ``command`` once probing is done.
    - ``command`` (3, m): the commanded tool point (to the first-order hold).
    - ``probing`` (1): 1 while probing, then 0. ``spindle`` (1): 1 - probing.
    - ``hold`` (1): 1 while probing and on the entry's dwell, then 0 (the
      command generator's ``hold``: no feed). The dwell lasts until the
      depth on the registered part reaches CUT_ESTABLISHED of
      ``desired_depth`` (at once with 0), or ``entry_dwell``: the feed
      starts on a cut at its depth, not on the way down to it.
    - ``fuzzy_weight`` (1): 0 while probing, then ramps to 1 over
      ``fuzzy_ramp_time`` (the weight of the controller's fuzzy
      compensator: rules learned on earlier parts come in as the cut is
      established).
    - ``registration`` (4): dx, dy (m), dyaw (rad), dradius (m): the
      correction of the believed part, zero until the fit.
    - ``probe_state`` (PROBE_STATE layout), ``touch_points`` (N x 4: x, y,
      z of each compensated touch (m), 1 if contact was detected).
    - Discrete state: the two outputs above and each touch's crossings
      (N x 5: x, y, z (m) and speed along n1 (m/s) at ``force_threshold``,
      the way on to ``stiffness_threshold`` (m, 0: not reached)), updated
      every ``sample_period`` (the sensor's).

    Each touch: travel (smooth, along the believed edge at the standoff: a
    straight move would cut a convex corner) to the standoff point
    ``standoff`` before the believed zero-depth path along -n1, settle, tare
    the force, move along n1 at ``approach_speed`` until -(f - tare).n1
    exceeds ``force_threshold`` (nothing within ``search_distance``: a miss,
    which ends the run with the stop reason ``probe_missed:<touch index>``),
    record x_p, go on until it exceeds ``stiffness_threshold`` (the way
    between the two crossings gives the contact's stiffness), retract by
    ``retract``. Then every touch less the :func:`detection_depth` on the
    touches' median stiffness and the calibrated ``detection_bias`` along
    n1, the fit, a travel (along the corrected edge) to the corrected
    start's standoff and an entry at the approach speed to ``start`` on the
    corrected part (the tool point the pass starts from); the command
    generator takes over from there.
    """

    def __init__(
        self,
        contour: Contour,
        config: ProbeConfig,
        *,
        sample_period: float,
        timing: SensorTiming,
        initial_position,
        start_depth: float = 0.0,
        desired_depth: float = 0.0,
    ):
        super().__init__()
        config.validate()
        self.set_name("probing_sequence")
        self._layout, self._done_phase = PROBE_STATE, _P["done"]
        self._contour = contour
        self._config = config
        self._timing = timing
        self._start_depth = start_depth
        self._established_depth = CUT_ESTABLISHED * desired_depth
        # The touches, checked to fix the part.
        self._arcs = probe_arcs(contour, config)
        self._n = len(self._arcs)
        check_probe_layout(contour, config, self._arcs)
        # State: the sequence (PROBE_STATE) and the touch points.
        self._state = self.DeclareDiscreteState(
            self._initial_state(np.asarray(initial_position, float), config)
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
        self._declare_outputs()

    def _initial_state(self, x0, config):
        """PROBE_STATE at the start: travelling from x0 to the first
        touch's standoff."""
        initial = PROBE_STATE.pack(
            phase=_P["travel"],
            index=0,
            phase_start=0.0,
            segment_start=x0,
            segment_end=x0,
            segment_duration=1.0,
            linear=0.0,
            along_edge=0.0,
            arc_from=0.0,
            arc_to=0.0,
            command=x0,
            tare=np.zeros(3),
            registration=np.zeros(REGISTRATION_SIZE),
            done_time=-1.0,
            cut_time=-1.0,
            touches=0.0,
            kept=0.0,
            fit_rms=0.0,
            stiffness=config.contact_stiffness,
        )
        self._edge_segment(
            initial, 0.0, "travel", x0, self._contour, self._arcs[0]
        )
        return initial

    def _declare_outputs(self):
        state = {self.xd_ticket()}
        self.DeclareVectorOutputPort(
            "command",
            3,
            self._calc_command,
            prerequisites_of_calc={self.xd_ticket(), self._command_in.ticket()},
        )
        for name, calc in (
            ("probing", self._calc_probing),
            ("hold", self._calc_hold),
            ("spindle", self._calc_spindle),
        ):
            self.DeclareVectorOutputPort(
                name, 1, calc, prerequisites_of_calc=state
            )
        self.DeclareVectorOutputPort(
            "fuzzy_weight",
            1,
            self._calc_fuzzy_weight,
            prerequisites_of_calc={self.xd_ticket(), self.time_ticket()},
        )
        self.DeclareVectorOutputPort(
            "registration",
            REGISTRATION_SIZE,
            self._calc_registration,
            prerequisites_of_calc=state,
        )
        self.DeclareStateOutputPort("probe_state", self._state)
        self.DeclareStateOutputPort("touch_points", self._touch_state)

    # -- geometry of the moves -------------------------------------------
    @property
    def arcs(self) -> np.ndarray:
        return self._arcs.copy()

    def standoff_point(self, contour: Contour, s: float) -> np.ndarray:
        p = contour.point_at(s)
        return p - self._config.standoff * contour.n1(p)

    def _travel_time(self, a, b) -> float:
        # A smooth (3u^2 - 2u^3) move peaks at 1.5 x the mean speed.
        return max(
            float(np.linalg.norm(np.asarray(b) - a))
            / self._config.travel_speed,
            0.05,
        )

    def _segment(self, x, t, phase, start, end, duration, linear):
        x[PROBE_STATE.slice("phase")] = _P[phase]
        x[PROBE_STATE.slice("phase_start")] = t
        x[PROBE_STATE.slice("segment_start")] = start
        x[PROBE_STATE.slice("segment_end")] = end
        x[PROBE_STATE.slice("segment_duration")] = max(duration, 1e-9)
        x[PROBE_STATE.slice("linear")] = 1.0 if linear else 0.0
        x[PROBE_STATE.slice("along_edge")] = 0.0

    def _edge_point(self, contour, x, w):
        """The travel along the edge at weight w in [0, 1]: the standoff
        point at the arc w of the way, plus what is left of the start's
        offset from it (the move starts where the tool is)."""
        s0 = float(PROBE_STATE.get(x, "arc_from"))
        s1 = float(PROBE_STATE.get(x, "arc_to"))
        off = PROBE_STATE.get(x, "segment_start") - self.standoff_point(
            contour, s0
        )
        return (
            self.standoff_point(contour, s0 + w * (s1 - s0)) + (1.0 - w) * off
        )

    def _edge_segment(self, x, t, phase, start, contour, s_to):
        """A smooth travel from ``start`` to the standoff point at arc
        ``s_to`` along ``contour`` at the standoff (the shorter way round
        a closed edge): a straight move between two touches would cut the
        corner of a boss, or any convex edge, through the material."""
        s_from = float(contour.arc_position(start))
        if contour.closed:
            L = contour.length
            s_to = s_from + ((s_to - s_from + 0.5 * L) % L - 0.5 * L)
        end = self.standoff_point(contour, s_to)
        self._segment(x, t, phase, start, end, 1.0, False)
        x[PROBE_STATE.slice("along_edge")] = 1.0
        x[PROBE_STATE.slice("arc_from")] = s_from
        x[PROBE_STATE.slice("arc_to")] = s_to
        path = np.array(
            [self._edge_point(contour, x, w) for w in np.linspace(0.0, 1.0, 17)]
        )
        length = float(np.sum(np.linalg.norm(np.diff(path, axis=0), axis=1)))
        x[PROBE_STATE.slice("segment_duration")] = max(
            length / self._config.travel_speed, 0.05
        )

    def _along(self, x, t):
        u = (t - PROBE_STATE.get(x, "phase_start")) / PROBE_STATE.get(
            x, "segment_duration"
        )
        u = min(max(u, 0.0), 1.0)
        w = u if PROBE_STATE.get(x, "linear") > 0.5 else u * u * (3 - 2 * u)
        if PROBE_STATE.get(x, "along_edge") > 0.5:
            phase = PHASES[int(round(float(PROBE_STATE.get(x, "phase"))))]
            contour = (
                self._registered(x) if phase == "return" else self._contour
            )
            return self._edge_point(contour, x, w), u >= 1.0
        a = PROBE_STATE.get(x, "segment_start")
        b = PROBE_STATE.get(x, "segment_end")
        return a + w * (b - a), u >= 1.0

    # -- the state machine -----------------------------------------------
    def _update(self, context, discrete_state):
        x = context.get_discrete_state(self._state).get_value()
        phase = PHASES[int(round(float(PROBE_STATE.get(x, "phase"))))]
        t = context.get_time()
        if phase == "done":
            self._watch_entry(context, x, t, discrete_state)
            return
        x = x.copy()
        command, finished = self._along(x, t)
        x[PROBE_STATE.slice("command")] = command
        touches, crossings = (
            context.get_discrete_state(k).get_value().copy()
            for k in (self._touch_state, self._crossing_state)
        )
        step = _Step(context, x, t, command, finished, touches, crossings)
        status = self._PHASE_STEPS[phase](self, step)
        discrete_state.set_value(self._state, x)
        discrete_state.set_value(self._touch_state, touches)
        discrete_state.set_value(self._crossing_state, crossings)
        return status  # None but for a missed touch

    def _watch_entry(self, context, x, t, discrete_state):
        """Every sample of the pass: the time the entry's cut is
        established, written once (a copy of the state only then)."""
        if PROBE_STATE.get(x, "cut_time") < 0 and (
            CHAMFER_STATE.get(self._chamfer_port.Eval(context), "delta")
            >= self._established_depth
            or t - PROBE_STATE.get(x, "done_time") >= self._config.entry_dwell
        ):
            x = x.copy()
            x[PROBE_STATE.slice("cut_time")] = t
            discrete_state.set_value(self._state, x)

    # One method per phase: what a sample does in it (it writes ``step.x``
    # and ``step.touches``).
    def _travel(self, step):
        if step.finished:
            self._segment(
                step.x,
                step.t,
                "settle",
                step.command,
                step.command,
                self._config.settle_time,
                False,
            )

    def _settle(self, step):
        if not step.finished:
            return
        c, x = self._config, step.x
        i = int(round(float(PROBE_STATE.get(x, "index"))))
        x[PROBE_STATE.slice("tare")] = self._force_port.Eval(step.context)
        n = self._contour.n1(self._contour.point_at(self._arcs[i]))
        self._segment(
            x,
            step.t,
            "approach",
            step.command,
            step.command + c.search_distance * n,
            c.search_distance / c.approach_speed,
            True,
        )

    def _approach(self, step):
        c, x = self._config, step.x
        a = PROBE_STATE.get(x, "segment_start")
        n = PROBE_STATE.get(x, "segment_end") - a
        n /= np.linalg.norm(n)
        f = self._force_port.Eval(step.context) - PROBE_STATE.get(x, "tare")
        pushed = -float(f @ n)
        chamfer = self._chamfer_port.Eval(step.context)
        x_p = CHAMFER_STATE.get(chamfer, "x_p")
        i = int(round(float(PROBE_STATE.get(x, "index"))))
        row = slice(_CROSSING * i, _CROSSING * i + _CROSSING)
        touched = step.touches[4 * i + 3] > 0.5
        if not touched and pushed >= c.force_threshold:
            # The touch, compensated with the configured stiffness until
            # the fit has the measured one.
            speed = float(CHAMFER_STATE.get(chamfer, "xdot_p") @ n)
            step.crossings[row] = [*x_p, speed, 0.0]
            step.touches[4 * i : 4 * i + 4] = [
                *self._touch(x_p, n, speed, c.contact_stiffness),
                1.0,
            ]
            x[PROBE_STATE.slice("touches")] += 1.0
            if c.stiffness_threshold > 0:
                return  # on to the second threshold
        elif touched and pushed >= c.stiffness_threshold:
            # The way between the two thresholds: the filter delays both
            # crossings alike, so it is the contact's.
            step.crossings[row.stop - 1] = float(
                (x_p - step.crossings[row][:3]) @ n
            )
        elif not step.finished:
            return
        elif not touched:
            # Nothing within the search distance: the part is not where
            # the cell believes, by more than the probe looks; the run
            # ends rather than cut a part it could not find.
            return EventStatus.ReachedTermination(
                self,
                f"{PROBE_MISSED}:{i}: no contact within search_distance "
                f"{c.search_distance:g} m along n1 {np.round(n, 6).tolist()} "
                f"from {np.round(a, 6).tolist()} m (touch {i} of {self._n}, "
                f"arc {self._arcs[i]:.6g} m)",
            )
        # Back from the touch.
        back = x_p - c.retract * n
        self._segment(
            x,
            step.t,
            "retract",
            step.command,
            back,
            self._travel_time(step.command, back),
            False,
        )

    def _touch(self, x_p, n, speed, stiffness):
        """The touch on the zero-depth path: the crossing at ``x_p`` (m)
        moving at ``speed`` (m/s) along ``n`` less the modelled depth at
        detection on a contact of ``stiffness`` (N/m) and the depth the
        probe's qualification found the model leaves."""
        c = self._config
        return x_p - n * (
            detection_depth(speed, c.force_threshold, stiffness, self._timing)
            + c.detection_bias
        )

    def _retract(self, step):
        if not step.finished:
            return
        x = step.x
        i = int(round(float(PROBE_STATE.get(x, "index")))) + 1
        x[PROBE_STATE.slice("index")] = i
        if i < self._n:
            self._edge_segment(
                x, step.t, "travel", step.command, self._contour, self._arcs[i]
            )
        else:
            self._compensate(x, step.touches, step.crossings)
            self._fit(x, step.touches)
            self._edge_segment(
                x, step.t, "return", step.command, self._registered(x), 0.0
            )

    def _return(self, step):
        if not step.finished:
            return
        contour = self._registered(step.x)
        p = contour.point_at(0.0)
        start = p + self._start_depth * contour.n1(p)
        self._segment(
            step.x,
            step.t,
            "enter",
            step.command,
            start,
            float(np.linalg.norm(start - step.command))
            / self._config.approach_speed,
            True,
        )

    def _enter(self, step):
        if step.finished:
            step.x[PROBE_STATE.slice("phase")] = _P["done"]
            step.x[PROBE_STATE.slice("done_time")] = step.t

    #: phase -> what a sample does in it
    _PHASE_STEPS = {
        "travel": _travel,
        "settle": _settle,
        "approach": _approach,
        "retract": _retract,
        "return": _return,
        "enter": _enter,
    }

    def _registered(self, x) -> Contour:
        return moved_contour(self._contour, PROBE_STATE.get(x, "registration"))

    def _compensate(self, x, touches, crossings):
        """Every touch compensated with the stiffness the touches measured
        (their median: a touch on a burr measures the burr's)."""
        c = self._config
        rows = crossings.reshape(self._n, _CROSSING)
        spans = rows[:, 4][(touches[3::4] > 0.5) & (rows[:, 4] > 0)]
        if not len(spans):
            return  # the configured stiffness stays
        k = median_stiffness(spans, c)
        x[PROBE_STATE.slice("stiffness")] = k
        for i in np.flatnonzero(touches[3::4] > 0.5):
            n = self._contour.n1(self._contour.point_at(self._arcs[i]))
            touches[4 * i : 4 * i + 3] = self._touch(
                rows[i, :3], n, rows[i, 3], k
            )

    def _fit(self, x, touches):
        t = touches.reshape(self._n, 4)
        hit = t[:, 3] > 0.5
        minimum = 3
        if hit.sum() < minimum:
            return  # too few touches: the believed part stays as it is
        try:
            fit = registration_from_points(
                self._contour,
                t[hit, :3],
                max_residual=self._config.max_residual,
                fit_radius=self._config.fit_radius,
            )
        except ValueError:
            # The touches do not fix the part (too many dropped): the
            # believed part stays as it is (probe_state: kept 0).
            return
        x[PROBE_STATE.slice("registration")] = fit.registration
        x[PROBE_STATE.slice("kept")] = float(fit.kept.sum())
        x[PROBE_STATE.slice("fit_rms")] = fit.rms
        # Flag the dropped touches (2: touched, dropped by the fit).
        rows = np.flatnonzero(hit)[~fit.kept]
        t[rows, 3] = 2.0
        touches[:] = t.ravel()


_GATED = [
    CHAMFER_STATE.slice(name).start
    for name in ("f_n", "f_t", "delta", "delta_dot")
]


class ProbeGate(LeafSystem):
    """What the force loop, the estimator and the guards see while the
    sequence probes: no contact (||f_n||, ||f_t||, delta and delta_dot 0,
    the desired normal force 0, so delta_d' = 0 in (7) and the estimator
    does not adapt); afterwards its inputs unchanged. ``held`` (n1,
    arc position): while probing, n1 and the arc position are those (and
    n1's rate 0).

    .. pydrake_system::

        name: ProbeGate
        input_ports:
        - probing
        - chamfer_state
        - desired_normal_force
        output_ports:
        - chamfer_state
        - desired_normal_force
    """

    def __init__(self, held=None):
        super().__init__()
        self.set_name("probe_gate")
        # A mesh part's probe goes far from the edge: the loops see the
        # start's n1 and arc position while it probes (``held``: (n1,
        # arc)), so the tool's orientation and the desired point's offset
        # along n1 hold still instead of following the nearest point of
        # the edge across the part.
        self._held = held
        self._probing = self.DeclareVectorInputPort("probing", 1)
        self._chamfer = self.DeclareVectorInputPort(
            "chamfer_state", CHAMFER_STATE.size
        )
        self._desired = self.DeclareVectorInputPort("desired_normal_force", 1)
        self.DeclareVectorOutputPort(
            "chamfer_state", CHAMFER_STATE.size, self._calc_chamfer
        )
        self.DeclareVectorOutputPort(
            "desired_normal_force", 1, self._calc_desired
        )

    def _on(self, context) -> bool:
        return self._probing.Eval(context)[0] > 0.5

    def _calc_chamfer(self, context, output):
        chamfer = self._chamfer.Eval(context).copy()
        if self._on(context):
            chamfer[_GATED] = 0.0
            if self._held is not None:
                n1, arc = self._held
                chamfer[CHAMFER_STATE.slice("n1")] = n1
                chamfer[CHAMFER_STATE.slice("arc_position")] = arc
                chamfer[CHAMFER_STATE.slice("n1_rate")] = 0.0
        output.SetFromVector(chamfer)

    def _calc_desired(self, context, output):
        output.SetAtIndex(
            0, 0.0 if self._on(context) else self._desired.Eval(context)[0]
        )
