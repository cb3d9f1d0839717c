"""Running a deburring diagram and collecting its logs as named arrays.

Use: ``log = simulate(diagram, scenario, duration=3.0)`` runs a diagram from
:func:`deburr_drake.cell.diagram.make_deburring_diagram` and returns a
:class:`RunLog`: ``log["chamfer"]["f_n"]`` is the array of one named block
of one logger (``log["chamfer"]["t"]`` its sample times; the loggers are
``deburr_drake.cell.diagram.LOGGED``, the blocks the layouts of
``deburr_drake.control.layout``), ``log.stop_reason`` says how the run ended.
:func:`make_simulator` gives the scenario's configured ``Simulator`` for a
diagram of your own."""

from __future__ import annotations

from dataclasses import dataclass, field
import re
import time
from typing import Callable, Dict, Optional

import numpy as np
from pydrake.common import RandomGenerator
from pydrake.systems.analysis import (
    ApplySimulatorConfig,
    Simulator,
    SimulatorConfig,
)
from pydrake.systems.framework import Diagram, EventStatus
from pydrake.systems.primitives import VectorLogSink

from deburr_drake.cell.gains import resolve_design, resolve_gains
from deburr_drake.cell.guards import effort_limits
from deburr_drake.cell.process import PROCESS_STATE
from deburr_drake.config import ConfigError, Scenario
from deburr_drake.control.layout import (
    CHAMFER_STATE,
    COMMAND_STATE,
    CONTROLLER_DIAGNOSTICS,
)
from deburr_drake.control.probe import PROBE_MISSED
from deburr_drake.control.sequencer import JOB_COMPLETE
from deburr_drake.math import metrics

__all__ = [
    "RunLog",
    "simulate",
    "make_simulator",
    "logger_names",
    "STOP_REASONS",
    "DIVERGED",
    "NumericalSanity",
    "PassProgress",
    "final_blocks",
]

#: Why a run ended (``RunLog.stop_reason``). ``guard:<name>`` names the
#: guard that tripped (deburr_drake.cell.guards); ``probe_missed:<i>``:
#: touch i of the touch probing found nothing within its search distance
#: (deburr_drake.control.probe); ``job_complete``: a job's last cut
#: reached its end (deburr_drake.control.sequencer); ``diverged``: the
#: numerical sanity check (:class:`NumericalSanity`) ended it.
STOP_REASONS = (
    "pass_complete",
    "job_complete",
    "duration",
    "interrupted",
    "guard:<name>",
    "probe_missed:<touch index>",
    "diverged",
    "nan",
    "error",
)
#: The stop reason of a run :class:`NumericalSanity` ended.
DIVERGED = "diverged"

_LAYOUTS = {
    "chamfer": CHAMFER_STATE,
    "controller": CONTROLLER_DIAGNOSTICS,
    "command": COMMAND_STATE,
    "process": PROCESS_STATE,
}


@dataclass
class RunLog:
    """Logged signals of one run. ``signals[logger]`` is a dict with
    ``t`` (s) and one array per named block (rows: samples)."""

    scenario: Scenario
    signals: Dict[str, Dict[str, np.ndarray]] = field(default_factory=dict)
    wall_time: float = 0.0  # s
    sim_time: float = 0.0  # s
    steps: int = 0
    completed_pass: bool = False
    stop_reason: str = "duration"  # one of STOP_REASONS
    stop_time: float = 0.0  # s, simulated time at the stop
    stop_detail: str = ""  # the guard's values, the signal, the exception

    def __getitem__(self, key: str) -> Dict[str, np.ndarray]:
        return self.signals[key]

    def flat(self) -> Dict[str, np.ndarray]:
        """Every array as ``"<logger>.<block>"`` (for np.savez)."""
        return {
            f"{k}.{b}": v
            for k, blocks in self.signals.items()
            for b, v in blocks.items()
        }


def plant_cache_refresh(diagram: Diagram, integrator: str):
    """A simulator monitor's first duty with ``cenic`` (None otherwise):
    mark the plant's continuous state changed after every step.

    Drake 1.51.1's CENIC leaves the plant's position and velocity
    kinematics cached at the step's start when it writes the step's end
    state: after AdvanceTo, body poses, contact results, reaction forces
    and accelerations evaluated on the simulator's context are one step
    old while the state output is new (runge_kutta3 does not). Every
    sample's reader of the plant's outputs (the force sensor's weld
    reaction, the cutting process's held mean) would see the state one
    step before the sample. Taking mutable access to the continuous state
    invalidates what depends on it; the kinematics are then computed once
    more per step, for the state they describe.

    Upstream, drake#24061 reports CENIC's reaction forces wrong; no
    report names the stale cache itself. When Drake's CENIC leaves the
    cache consistent, tests/runs/test_simulation.py's pin of the stale
    kinematics fails: then this refresh can go."""
    if integrator != "cenic" or not diagram.HasSubsystemNamed("plant"):
        return None
    plant = diagram.GetSubsystemByName("plant")

    def refresh(root_context):
        plant.GetMyMutableContextFromRoot(
            root_context
        ).get_mutable_continuous_state_vector()

    return refresh


def set_monitor(
    simulator: Simulator,
    diagram: Diagram,
    integrator: str,
    monitor: Optional[Callable] = None,
):
    """Installs ``monitor(root_context) -> EventStatus`` (or none) after
    :func:`plant_cache_refresh`'s refresh, which every simulator of the
    cell needs with ``cenic``."""
    refresh = plant_cache_refresh(diagram, integrator)
    if refresh is None and monitor is None:
        return

    def monitored(root_context):
        if refresh is not None:
            refresh(root_context)
        return (
            monitor(root_context)
            if monitor is not None
            else EventStatus.Succeeded()
        )

    simulator.set_monitor(monitored)


class NumericalSanity:
    """Has the integration itself diverged? ``check(root_context)`` gives
    what is beyond its bounds (a message) or None, from states alone:

    - every continuous state of the diagram finite (the plant's q and v,
      the controller's delta_d and theta, the estimator's c-hat, ...);
    - every joint speed within ``SPEED_FACTOR`` x its velocity limit from
      the robot model; a joint without one (the Cartesian tool's slides)
      within ``UNLIMITED_SPEED_FEEDS`` x ``command.default_feed``;
    - every commanded joint torque within ``TORQUE_FACTOR`` x its effort
      limit (the drives clamp at the limit: a command a thousand times
      beyond it is the controller's arithmetic running away).

    Not a guard (those are the user's limits, ``guards:``, and can be
    off): bounds no healthy run approaches, which end a run before
    Drake's contact solver fails on the state (an abort that loses the
    run): a diverging state leaps past them by orders of magnitude in one
    step, while a limit cycle, however violent, stays below them. The
    check reads states and held outputs (no computation) after every
    step: a few microseconds."""

    SPEED_FACTOR = 10.0
    UNLIMITED_SPEED_FEEDS = 1.0e4
    TORQUE_FACTOR = 1.0e3
    #: The bound on |x| that makes an infinity fail (a NaN fails any).
    _FINITE = 1e300

    def __init__(self, diagram: Diagram, scenario: Scenario):
        self._plant = self._controller = None
        self._size = diagram.num_continuous_states()
        bounds = [np.full(self._size, self._FINITE)]
        if diagram.HasSubsystemNamed("plant"):
            self._plant = diagram.GetSubsystemByName("plant")
            limits = np.abs(self._plant.GetVelocityUpperLimits())
            self._speed = np.where(
                np.isfinite(limits),
                self.SPEED_FACTOR * limits,
                self.UNLIMITED_SPEED_FEEDS * scenario.command.default_feed,
            )
            self._speed_why = [
                f"{self.SPEED_FACTOR:g} x its velocity limit"
                if np.isfinite(limit)
                else f"{self.UNLIMITED_SPEED_FEEDS:g} x the default feed"
                for limit in limits
            ]
            self._speed_names = self._plant.GetVelocityNames()
            bounds.append(self._speed)
            names, efforts = effort_limits(self._plant)
            if diagram.HasSubsystemNamed("controller"):
                controller = diagram.GetSubsystemByName("controller")
                self._actuation = controller.GetOutputPort("actuation")
                if self._actuation.size() == efforts.size:
                    self._controller = controller
                    self._torque = np.minimum(
                        self.TORQUE_FACTOR * efforts, self._FINITE
                    )
                    self._torque_names = names
                    bounds.append(self._torque)
        # One compare of every checked value with its bound.
        self._bound = np.concatenate(bounds)

    def check(self, root_context) -> Optional[str]:
        """None, or what diverged (the first of the checks that fails)."""
        values = [root_context.get_continuous_state_vector().CopyToVector()]
        if self._plant is not None:
            values.append(
                self._plant.GetVelocities(
                    self._plant.GetMyContextFromRoot(root_context)
                )
            )
        if self._controller is not None:
            values.append(
                self._actuation.Eval(
                    self._controller.GetMyContextFromRoot(root_context)
                )
            )
        if (np.abs(np.concatenate(values)) <= self._bound).all():
            return None
        return self._diagnose(*values)

    def _diagnose(self, x, v=None, tau=None) -> str:
        """What failed (the slow path)."""
        if not np.isfinite(x).all():
            bad = np.flatnonzero(~np.isfinite(x))
            return (
                f"a non-finite continuous state (elements "
                f"{bad[:8].tolist()} of {x.size})"
            )
        if v is not None and not (np.abs(v) <= self._speed).all():
            k = int(np.argmax(np.abs(v) / self._speed))
            return (
                f"{self._speed_names[k]} = {v[k]:.4g} (SI) beyond "
                f"{self._speed[k]:.4g}, {self._speed_why[k]}"
            )
        k = int(np.argmax(np.abs(tau) / self._torque))
        return (
            f"commanded {self._torque_names[k]} torque {tau[k]:.4g} "
            f"beyond {self._torque[k]:.4g} ({self.TORQUE_FACTOR:g} x its "
            "effort limit)"
        )

    def monitor_status(self, root_context, reporter):
        """``EventStatus.ReachedTermination(reporter, "diverged: ...")``
        or None."""
        found = self.check(root_context)
        if found is None:
            return None
        return EventStatus.ReachedTermination(
            reporter,
            f"{DIVERGED}: {found} at t = {root_context.get_time():.4f} s",
        )


class PassProgress:
    """Has the run done its ``simulation.stop_after_passes`` edge
    lengths? The command generator's arc progress has gone that far
    *and* the tool has cut at least ``COVERAGE`` of the edge's finish
    bins over that span. The arc progress alone is the projection of
    the tool on the edge: a runaway tool, thrown across the part, moves
    it half an edge length in one period; a pass the tool cut leaves
    only the few millimetres it lags behind its command uncut (the paper
    pass: all bins)."""

    COVERAGE = 0.5

    def __init__(self, diagram: Diagram, passes: float):
        self.passes = passes
        self._generator = diagram.GetSubsystemByName("command_generator")
        contour = self._generator.contour
        start = self._generator.start_arc_position
        self.end = start + passes * contour.length
        self._process = (
            diagram.GetSubsystemByName("cutting_process")
            if diagram.HasSubsystemNamed("cutting_process")
            else None
        )
        if self._process is not None:
            self._span = metrics.arc_span_mask(
                self._process.bins.centers,
                start,
                max(self.end, start),
                contour.length,
                contour.closed,
            )

    def done(self, root_context) -> bool:
        if not self.passes > 0:
            return False
        context = self._generator.GetMyContextFromRoot(root_context)
        if self._generator.arc_progress(context) < self.end:
            return False
        return self.coverage(root_context) >= self.COVERAGE

    def coverage(self, root_context) -> float:
        """The fraction of the span's finish bins cut (1 without a
        cutting process)."""
        if self._process is None or not self._span.any():
            return 1.0
        depth = self._process.GetOutputPort("finish_depth").Eval(
            self._process.GetMyContextFromRoot(root_context)
        )
        return float(np.mean(depth[self._span] > 0.0))


def make_simulator(
    diagram: Diagram, scenario: Scenario, *, monitor: Optional[Callable] = None
) -> Simulator:
    """The scenario's integrator on ``diagram``, with :func:`set_monitor`'s
    cache refresh and ``monitor``. A designed step (``controller.design``
    auto) is taken from the design, as the builder takes its gains."""
    sim = resolve_gains(scenario).simulation
    simulator = Simulator(diagram)
    ApplySimulatorConfig(
        SimulatorConfig(
            integration_scheme=sim.integrator,
            max_step_size=sim.max_step,
            accuracy=sim.accuracy,
            use_error_control=sim.error_control,
        ),
        simulator,
    )
    if sim.error_control:
        simulator.get_mutable_integrator().set_target_accuracy(sim.accuracy)
    set_monitor(simulator, diagram, sim.integrator, monitor)
    return simulator


def _final_state(diagram, context) -> Dict[str, Dict[str, np.ndarray]]:
    """What the run leaves behind: the surface finish and burrs along the
    edge, the final fuzzy rule weights and the rule-base geometry."""
    process = diagram.GetSubsystemByName("cutting_process")
    controller = diagram.GetSubsystemByName("controller")
    theta = controller.theta(controller.GetMyContextFromRoot(context))
    return final_blocks(
        process, process.GetMyContextFromRoot(context), controller, theta
    )


def final_blocks(
    process, process_context, controller, theta
) -> Dict[str, Dict[str, np.ndarray]]:
    """A pass's final-state blocks: ``finish`` (``process``'s bins, the
    depth cut and the burrs), ``theta`` (``theta``, the rule weights) and
    ``meta`` (``controller``'s rule-base geometry)."""
    pc = process_context
    f = controller.config.fuzzy
    delta0, deltak = f.deltas()
    return {
        "finish": {
            "arc": process.bins.centers.copy(),
            "depth": process.GetOutputPort("finish_depth").Eval(pc).copy(),
            "burr_initial": process.initial_burr_height(),
            "burr_remaining": process.GetOutputPort("burr_height")
            .Eval(pc)
            .copy(),
        },
        "theta": {"final": np.array(theta, copy=True)},
        "meta": {
            "fuzzy_order": np.array(f.order),
            "upsilon": np.array(f.upsilon),
            "delta0": np.array(delta0),
            "deltak": np.array(deltak),
            "dead_zone": np.array(
                [
                    rb.resolved_dead_zone_half_width
                    for rb in controller.rule_bases
                ]
            ),
            "fuzzy_axes": np.array(f.axes),
        },
    }


def logger_names(diagram: Diagram):
    """The names ``<name>`` of the diagram's loggers ``log_<name>``: those of
    ``deburr_drake.cell.diagram.LOGGED`` and any ``extra_logs``."""
    return [
        s.get_name()[len("log_") :]
        for s in diagram.GetSystems()
        if s.get_name().startswith("log_") and isinstance(s, VectorLogSink)
    ]


def _collect(diagram, context, loggers) -> Dict[str, Dict[str, np.ndarray]]:
    out = {}
    for name in loggers:
        sink = diagram.GetSubsystemByName(f"log_{name}")
        log = sink.FindLog(context)
        data = log.data().T
        layout = _LAYOUTS.get(name)
        blocks = layout.split(data) if layout else {"value": data}
        out[name] = {"t": log.sample_times().copy(), **blocks}
    return out


def _stop_of(status, diagram) -> tuple:
    """(stop_reason, detail) of a simulator status that reached a
    termination condition requested by a system's event or the monitor."""
    from deburr_drake.cell.guards import GUARDS_SYSTEM

    system = status.system()
    name = system.get_name() if system is not None else ""
    message = status.message()
    if name == GUARDS_SYSTEM:
        return f"guard:{message.split(':', 1)[0]}", message
    if name == "command_generator":
        return "pass_complete", message
    if message.startswith(f"{JOB_COMPLETE}:"):
        return JOB_COMPLETE, message.split(":", 1)[1].strip()
    if message.startswith(f"{PROBE_MISSED}:"):
        reason, _, detail = message.partition(": ")
        return reason, detail
    if message.startswith(f"{DIVERGED}:"):
        return DIVERGED, message.split(":", 1)[1].strip()
    return message or "interrupted", ""


def _is_nan_error(error: BaseException) -> bool:
    return re.search(r"\bNaN\b", str(error)) is not None


def _stop_monitor(diagram, scenario, passes, should_stop):
    """The monitor that ends the run when :class:`NumericalSanity` finds
    it diverged, once ``passes`` edge lengths are done
    (:class:`PassProgress`) or when ``should_stop()`` gives a reason."""
    sanity = NumericalSanity(diagram, scenario)
    progress = PassProgress(diagram, passes)
    generator = diagram.GetSubsystemByName("command_generator")

    def monitor(root_context):
        diverged = sanity.monitor_status(root_context, diagram)
        if diverged is not None:
            return diverged
        if progress.done(root_context):
            return EventStatus.ReachedTermination(
                generator, "completed the pass"
            )
        if should_stop is not None:
            reason = should_stop()
            if reason:
                return EventStatus.ReachedTermination(diagram, reason)
        return EventStatus.Succeeded()

    return monitor


def _advance(
    simulator, diagram, duration, progress, progress_interval, generator
) -> tuple:
    """Advances ``simulator`` to ``duration`` in ``progress_interval``
    slices; (stop_reason, detail) of how it ended."""
    context = simulator.get_context()
    generator_context = generator.GetMyContextFromRoot(context)
    wall_start = time.perf_counter()
    t = 0.0
    try:
        simulator.Initialize()
        while t < duration - 1e-12:
            status = simulator.AdvanceTo(min(duration, t + progress_interval))
            t = context.get_time()
            if (
                status.reason()
                == status.ReturnReason.kReachedTerminationCondition
            ):
                return _stop_of(status, diagram)
            if progress is not None:
                feed = generator.GetOutputPort("feed").Eval(generator_context)
                progress(t, time.perf_counter() - wall_start, feed[0])
    except KeyboardInterrupt:
        return "interrupted", "KeyboardInterrupt"
    except Exception as e:  # Drake's NaN checks and failures end up here
        reason = "nan" if _is_nan_error(e) else "error"
        return reason, f"{type(e).__name__}: {e}"
    return "duration", ""


def simulate(
    diagram: Diagram,
    scenario: Scenario,
    *,
    duration: Optional[float] = None,
    progress: Optional[Callable[[float, float, float], None]] = None,
    progress_interval: float = 1.0,
    loggers=None,
    should_stop: Optional[Callable[[], Optional[str]]] = None,
    initial_state: Optional[Callable] = None,
) -> RunLog:
    """Simulates from the diagram's default context for ``duration`` (the
    scenario's by default, or until ``stop_after_passes`` edge lengths are
    done) and returns the logs. ``progress(t, wall, feed)`` (s, s, m/s of
    commanded feed) is called every ``progress_interval`` simulated
    seconds. ``loggers`` (names) limits the logs collected; by default
    every ``log_<name>`` of the diagram (:func:`logger_names`).

    ``scenario``: the one the diagram was built from, its designed values
    resolved as the builder resolves them (cell.gains.resolve_design, on
    a copy), so the run's step and ``RunLog.scenario`` are those built.

    Every ending returns what was logged so far, with ``stop_reason`` (one
    of :data:`STOP_REASONS`), ``stop_time`` and ``stop_detail``: the pass
    completed (:class:`PassProgress`), the duration reached, a guard of
    the diagram tripped (its event requested termination), the run
    diverged (:class:`NumericalSanity`, guards or not: "diverged"),
    ``should_stop()`` returned a reason (both checked after every step,
    e.g. a signal handler's flag: "interrupted"), Drake detected a NaN
    ("nan"), or another exception ("error"; the detail holds its message).

    ``initial_state(diagram, context)``, if given, sets states of the root
    context before the run starts (after the random context: e.g. the
    learned fuzzy weights a batch carries from the part before)."""
    duration = scenario.simulation.duration if duration is None else duration
    if not (progress_interval > 0 and np.isfinite(progress_interval)):
        raise ConfigError(
            f"progress_interval = {progress_interval!r} is "
            "invalid: allowed a finite number > 0"
        )
    scenario = resolve_design(scenario)
    simulator = make_simulator(
        diagram,
        scenario,
        monitor=_stop_monitor(
            diagram,
            scenario,
            scenario.simulation.stop_after_passes,
            should_stop,
        ),
    )
    context = simulator.get_mutable_context()
    generator = diagram.GetSubsystemByName("command_generator")
    diagram.SetRandomContext(
        context, RandomGenerator(scenario.sensor.noise_seed)
    )
    if initial_state is not None:
        initial_state(diagram, context)
    wall_start = time.perf_counter()
    reason, detail = _advance(
        simulator, diagram, duration, progress, progress_interval, generator
    )
    t = context.get_time()
    wall = time.perf_counter() - wall_start
    signals = _collect(diagram, context, loggers or logger_names(diagram))
    try:
        signals.update(_final_state(diagram, context))
    except Exception as e:  # e.g. a NaN state; the logs are still there
        detail += f" (final state unavailable: {type(e).__name__}: {e})"
    return RunLog(
        scenario=scenario,
        signals=signals,
        wall_time=wall,
        sim_time=t,
        steps=simulator.get_num_steps_taken(),
        completed_pass=reason == "pass_complete",
        stop_reason=reason,
        stop_time=t,
        stop_detail=detail,
    )
