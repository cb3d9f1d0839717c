"""Outer loop: the feedrate-law command generator and the first-order hold
between it and the inner loop (paper Section III.A, eq. (5), R2, R5, R6).

Use: ``CommandGenerator(scenario.command, scenario.task, contour, x0)``
and ``FirstOrderHold(scenario.command.period, contour.project(x0))``,
the generator's ``command`` into the hold's ``sampled``;
:func:`feedrate_law` is the outer-loop law of a scenario
(math.feedrate.FeedrateLaw), :func:`edge_steady_feed` the feed it settles
at on the scenario's edge."""

from __future__ import annotations

import numpy as np
from pydrake.systems.framework import BasicVector, LeafSystem

from deburr_drake.config import (
    CommandConfig,
    ConfigError,
    Scenario,
    TaskConfig,
)
from deburr_drake.control.layout import CHAMFER_STATE, COMMAND_STATE
from deburr_drake.control.observer import RegisteredContour
from deburr_drake.math.feedrate import FeedrateLaw, cutting_damping
from deburr_drake.math.geometry import Contour, contour_at, removal_scale
from deburr_drake.math.registration import registration_size

__all__ = [
    "CommandGenerator",
    "FirstOrderHold",
    "edge_steady_feed",
    "feedrate_law",
]


def feedrate_law(
    config: CommandConfig, task: TaskConfig, *, varying_frame: bool = False
) -> FeedrateLaw:
    """The outer loop's feedrate law of ``config`` and ``task``: the
    integrating variant where ``config.feed_law`` asks for it, or on
    ``auto`` along an edge whose frame turns (``varying_frame``, a CAD
    part's 3-D edge; CommandConfig.feed_law says why)."""
    return FeedrateLaw(
        desired_force=task.desired_chamfering_force,
        threshold_force=config.threshold_power_force,
        force_offset=config.force_offset,
        default_feed=config.default_feed,
        max_feed=config.max_feed,
        integrating=config.feed_law == "integrating"
        or (config.feed_law == "auto" and varying_frame),
    )


def edge_steady_feed(
    scenario: Scenario, *, curvature: float = 0.0, burr_area: float = 0.0
) -> float:
    """The feed (m/s) ``scenario``'s law settles at in steady cutting at
    the desired depth where the zero-depth path has ``curvature`` (1/m) and
    the cut a burr of ``burr_area`` (m^2): FeedrateLaw.steady_feed on g =
    k_c s (delta* h + burr area), s the edge's removal_scale, the
    process's P'_th."""
    d = scenario.task.desired_depth
    g = cutting_damping(
        scenario.process.cutting_coefficient
        * removal_scale(curvature, d, scenario.tool.cutter_radius),
        d * scenario.tool.engagement,
        burr_area,
    )
    return feedrate_law(scenario.command, scenario.task).steady_feed(
        g, scenario.process.threshold_power_force
    )


def _check(config: CommandConfig, task: TaskConfig):
    config.validate()
    task.validate()
    if task.desired_chamfering_force <= config.threshold_power_force:
        raise ConfigError(
            "task.desired_chamfering_force = "
            f"{task.desired_chamfering_force!r} is invalid: allowed > "
            f"command.threshold_power_force "
            f"({config.threshold_power_force})"
        )


class CommandGenerator(LeafSystem):
    """Discrete outer-loop command generator, period T.

    At t = kT it reads the chamfer state, computes the feed speed v with
    the law of :func:`feedrate_law` and outputs the point x_c(kT) that lies
    on the zero-depth contour a distance v T ahead of the projection of x_p
    (R6: the command is the paper's x_s, so (9) adds the depth only once).

    .. pydrake_system::

        name: CommandGenerator
        input_ports:
        - chamfer_state
        - registration (optional)
        - hold (optional)
        output_ports:
        - command_state
        - command
        - feed

    - ``chamfer_state`` (CHAMFER_STATE layout): x_p (m), xdot_p (m/s), n2
      and ||f_t|| (N) are read.
    - ``command_state`` (COMMAND_STATE layout): the discrete state below.
    - ``command`` (3, m): x_c(kT), world frame.
    - ``feed`` (1, m/s): the commanded feed speed v.
    - ``registration`` (the observer's size) and ``hold`` (1), only with
      ``registered=True`` (``hold`` alone with ``hold_input=True``: a job's
      sequencer holds the feed off the part): the contour moved by the
      registration (as the observer's); while ``hold`` > 0.5 (touch
      probing and the entry's dwell) no feed: x_c is the pass's start on
      the registered contour (the point at the start's arc position, the
      probe's entry target): the position loop keeps the tool there
      while the entry's cut builds. A job's sequencer's hold
      (``hold_input=True``, probed or not): x_c is the projection of x_p
      and the arc position the one nearest the start.
    - Discrete state (COMMAND_STATE layout): x_c (m), feed (m/s), arc
      position of x_c (m, unwrapped, counts progress past one revolution).

    With ``config.feed_law`` integrating the law scales the last commanded
    feed while cutting, and below the cutting threshold x_c advances from
    the last command (CommandConfig.feed_law says why).

    With ``constant_feed`` v (m/s) there is no feedrate law and no
    feedback: x_c((k+1)T) lies v T of arc ahead of x_c(kT) whatever the
    tool does (a timed path, what the constant-feed baselines of
    ``controller.kind`` impedance and position run).
    """

    def __init__(
        self,
        config: CommandConfig,
        task: TaskConfig,
        contour: Contour,
        initial_position,
        *,
        constant_feed=None,
        contour_step=None,
        registered: bool = False,
        hold_input: bool = False,
    ):
        super().__init__()
        _check(config, task)
        self.set_name("command_generator")
        self._config = config
        self._contour = contour
        # (time, contour): the part as the controller sees it from then on.
        self._contour_step = contour_step
        self._period = config.period
        if constant_feed is not None and not constant_feed > 0:
            raise ConfigError(
                f"command.constant_feed = {constant_feed!r} "
                "is invalid: allowed a finite number > 0"
            )
        self._constant_feed = constant_feed
        # The feed law, chosen once (CommandConfig.feed_law).
        self._law = feedrate_law(
            config, task, varying_frame=contour.varying_frame
        )
        start = contour.project(np.asarray(initial_position, float))
        s0 = contour.arc_position(start)
        self._state_index = self.DeclareDiscreteState(
            COMMAND_STATE.pack(
                x_c=start,
                feed=(
                    config.default_feed
                    if constant_feed is None
                    else constant_feed
                ),
                arc_position=s0,
            )
        )
        self._chamfer_port = self.DeclareVectorInputPort(
            "chamfer_state", CHAMFER_STATE.size
        )
        self._registration = RegisteredContour(
            self.DeclareVectorInputPort(
                "registration", registration_size(contour)
            )
            if registered
            else None
        )
        self._hold = (
            self.DeclareVectorInputPort("hold", 1)
            if registered or hold_input
            else None
        )
        self._start_arc = s0
        # (a job's cuts each start elsewhere: its hold follows the tool)
        self._hold_at_start = registered and not hold_input
        self.DeclarePeriodicDiscreteUpdateEvent(
            config.period, 0.0, self._update
        )
        self.DeclareStateOutputPort("command_state", self._state_index)
        self.DeclareVectorOutputPort(
            "command",
            3,
            self._calc_command,
            prerequisites_of_calc={self.xd_ticket()},
        )
        self.DeclareVectorOutputPort(
            "feed", 1, self._calc_feed, prerequisites_of_calc={self.xd_ticket()}
        )

    @property
    def period(self) -> float:
        return self._period

    @property
    def contour(self) -> Contour:
        return self._contour

    @property
    def start_arc_position(self) -> float:
        """Arc position (m) of x_c(0)."""
        return float(
            COMMAND_STATE.get(
                self.CreateDefaultContext()
                .get_discrete_state(self._state_index)
                .get_value(),
                "arc_position",
            )
        )

    def arc_progress(self, context) -> float:
        """Unwrapped arc position (m) of the current command."""
        return float(
            COMMAND_STATE.get(
                context.get_discrete_state(self._state_index).get_value(),
                "arc_position",
            )
        )

    def _update(self, context, discrete_state):
        if self._hold is not None and self._hold.Eval(context)[0] > 0.5:
            self._held(context, discrete_state)
            return
        if self._constant_feed is not None:
            self._advance_timed(context, discrete_state)
            return
        chamfer = self._chamfer_port.Eval(context)
        x_p = CHAMFER_STATE.get(chamfer, "x_p")
        xdot_p = CHAMFER_STATE.get(chamfer, "xdot_p")
        n2 = CHAMFER_STATE.get(chamfer, "n2")
        # Floats keep the law on its scalar path (a layout's scalar block
        # is a 0-d array); only what the law's variant reads.
        f_t = float(CHAMFER_STATE.get(chamfer, "f_t"))
        previous = context.get_discrete_state(self._state_index).get_value()
        law = self._law
        integrating = law.integrating
        v = law(
            None if integrating else float(n2 @ xdot_p),
            f_t,
            float(COMMAND_STATE.get(previous, "feed")) if integrating else None,
        )
        ds = v * self._period
        contour = self._contour_now(context)
        s_previous = COMMAND_STATE.get(previous, "arc_position")
        if integrating and not law.cutting(f_t):
            x_c = contour.advance(COMMAND_STATE.get(previous, "x_c"), ds)
            discrete_state.set_value(
                self._state_index,
                COMMAND_STATE.pack(
                    x_c=x_c, feed=v, arc_position=s_previous + ds
                ),
            )
            return
        x_c = contour.advance(x_p, ds)
        s_p = contour.unwrapped_arc_position(x_p, s_previous)
        discrete_state.set_value(
            self._state_index,
            COMMAND_STATE.pack(x_c=x_c, feed=v, arc_position=s_p + ds),
        )

    def _advance_timed(self, context, discrete_state):
        xd = context.get_discrete_state(self._state_index).get_value()
        v = self._constant_feed
        ds = v * self._period
        x_c = self._contour_now(context).advance(
            COMMAND_STATE.get(xd, "x_c"), ds
        )
        discrete_state.set_value(
            self._state_index,
            COMMAND_STATE.pack(
                x_c=x_c,
                feed=v,
                arc_position=COMMAND_STATE.get(xd, "arc_position") + ds,
            ),
        )

    def _held(self, context, discrete_state):
        contour = self._contour_now(context)
        if self._hold_at_start:
            # The probe's hold: while probing its own command drives the
            # tool (x_c is not passed on), and on the entry's dwell the
            # tool is at the pass's start. A command on the tool's
            # projection would follow the tool wherever it drifts and the
            # cut's tangential force pushes it; held at the start, the
            # position loop keeps the tool there.
            s = self._start_arc
            x_c = contour.point_at(s)
        else:
            x_p = CHAMFER_STATE.get(self._chamfer_port.Eval(context), "x_p")
            s = contour.unwrapped_arc_position(x_p, self._start_arc)
            x_c = contour.project(x_p)
        discrete_state.set_value(
            self._state_index,
            COMMAND_STATE.pack(
                x_c=x_c,
                feed=(
                    self._config.default_feed
                    if self._constant_feed is None
                    else self._constant_feed
                ),
                arc_position=s,
            ),
        )

    def _contour_now(self, context) -> Contour:
        return self._registration(
            context,
            contour_at(self._contour, self._contour_step, context.get_time()),
        )[0]

    def _calc_command(self, context, output):
        xd = context.get_discrete_state(self._state_index).get_value()
        output.SetFromVector(COMMAND_STATE.get(xd, "x_c"))

    def _calc_feed(self, context, output):
        xd = context.get_discrete_state(self._state_index).get_value()
        output.SetAtIndex(0, COMMAND_STATE.get(xd, "feed"))


class FirstOrderHold(LeafSystem):
    """Continuous ramp between the samples of a discrete command (eq. (5)).

    ``variant="delayed_ramp"`` (default, R2): on [kT, (k+1)T)

        x*(t) = x*(kT) + (x_c(kT) - x*(kT)) (t - kT) / T,

    so x*((k+1)T) = x_c(kT): continuous, one period behind, settles on a
    constant command. ``variant="paper_eq5"`` is (5) as printed,

        x*(t) = x*(kT) + (x_c(kT) - x*(kT - T)) (t - kT) / T,

    which does not settle (a unit step gives 0, 1, 2, 2, 1, 0, ...); it is
    kept only to show that.

    x*(t) is a continuous state whose derivative, the ramp's slope, is
    piecewise constant, so every integrator reproduces the ramp exactly and
    an integrator that treats the plant implicitly sees x* move within its
    step. The input is the discrete output of a system updated at the same
    instants (the command generator); the slope reads it through direct
    feedthrough, so the ramp toward x_c(kT) starts at kT without an extra
    period of delay.

    .. pydrake_system::

        name: FirstOrderHold
        input_ports:
        - sampled
        output_ports:
        - position
        - velocity

    - ``sampled`` (n): x_c(kT), piecewise constant.
    - ``position`` (n): x*(t). ``velocity`` (n): dx*/dt, piecewise constant.
    - Continuous state (n): x*(t). Discrete state (2n): the slope's origin,
      x*(kT) (``delayed_ramp``) or x*(kT - T) (``paper_eq5``), and x* at
      the last knot.
    """

    VARIANTS = ("delayed_ramp", "paper_eq5")

    def __init__(
        self, period: float, initial_value, *, variant: str = "delayed_ramp"
    ):
        super().__init__()
        if not (np.isfinite(period) and period > 0):
            raise ConfigError(
                f"period = {period!r} is invalid: allowed a finite number > 0"
            )
        if variant not in self.VARIANTS:
            raise ConfigError(
                f"variant = {variant!r} is invalid: allowed "
                f"one of {self.VARIANTS}"
            )
        self.set_name("first_order_hold")
        x0 = np.asarray(initial_value, float).ravel()
        n = x0.size
        self._period = period
        self._paper = variant == "paper_eq5"
        self._n = n
        xc = self.DeclareContinuousState(BasicVector(x0))
        self._knots_index = self.DeclareDiscreteState(np.concatenate([x0, x0]))
        self._input = self.DeclareVectorInputPort("sampled", n)
        self.DeclarePeriodicDiscreteUpdateEvent(period, 0.0, self._update)
        self.DeclareStateOutputPort("position", xc)
        self.DeclareVectorOutputPort(
            "velocity",
            n,
            self._calc_velocity,
            prerequisites_of_calc={self.xd_ticket(), self._input.ticket()},
        )

    def _knots(self, context):
        """(origin of the current slope, x* at the last knot)."""
        xd = context.get_discrete_state(self._knots_index).get_value()
        return xd[: self._n], xd[self._n :]

    def _slope(self, context):
        origin, _ = self._knots(context)
        return (self._input.Eval(context) - origin) / self._period

    def _update(self, context, discrete_state):
        x = context.get_continuous_state_vector().CopyToVector()
        _, last_knot = self._knots(context)
        # R2 ramps from x*(kT); (5) as printed from x*(kT - T).
        origin = last_knot if self._paper else x
        discrete_state.set_value(self._knots_index, np.concatenate([origin, x]))

    def DoCalcTimeDerivatives(self, context, derivatives):
        derivatives.get_mutable_vector().SetFromVector(self._slope(context))

    def _calc_velocity(self, context, output):
        output.SetFromVector(self._slope(context))
