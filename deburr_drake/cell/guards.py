"""Runtime safety guards of the deburring cell: a Drake system that checks
the run at every inner-loop sample and stops the simulation, through
Drake's event status (``EventStatus.ReachedTermination`` from its periodic
update, which ``Simulator.AdvanceTo`` returns as its termination
condition), when one trips. The message names the guard and its values at
the trip; :func:`deburr_drake.runs.simulation.simulate` turns it into the stop
reason ``guard:<name>``.

Guards (``GuardsConfig``, scenario section ``guards:``):

- ``joint_torque``: a commanded joint torque above ``joint_torque_fraction``
  of the joint's effort limit (the model's ``<effort>``); the plant never
  takes more than the limit (``add_effort_saturation``: the drives clamp,
  and the guard sees a command one sample after the plant does);
- ``tool_force``: the measured tool force above a limit;
- ``depth``: the measured or the true chamfer depth beyond a limit;
- ``workspace``: the tool tip outside the edge's bounding box plus a margin;
- ``contact_lost``: ||f_n|| below the contact force for longer than a time,
  once contact was made;
- ``nan``: a NaN or infinity in any logged signal.

The guard only reads signals; it adds one discrete update at the sample
times the controller already has, so the physics and the steps are those of
the run without it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Dict, Sequence

import numpy as np
from pydrake.systems.framework import BasicVector, EventStatus, LeafSystem
from pydrake.systems.primitives import Saturation

from deburr_drake.cell.process import PROCESS_STATE
from deburr_drake.config import ConfigError, GuardsConfig, Scenario
from deburr_drake.control.layout import CHAMFER_STATE

__all__ = [
    "GUARDS_SYSTEM",
    "GUARD_NAMES",
    "GuardLimits",
    "SafetyGuards",
    "guard_limits",
    "add_guards",
    "effort_limits",
    "add_effort_saturation",
]

#: The guard system's name in the diagram.
GUARDS_SYSTEM = "guards"
GUARD_NAMES = (
    "nan",
    "joint_torque",
    "tool_force",
    "depth",
    "workspace",
    "contact_lost",
)


@dataclass
class GuardLimits:
    """The resolved limits (SI units) the guards check against."""

    joint_names: Sequence[str]
    effort_limits: np.ndarray  # N m or N per actuator; inf: not checked
    joint_torque_fraction: float
    tool_force: float  # N
    depth: float  # m
    workspace_low: np.ndarray  # m, world
    workspace_high: np.ndarray  # m, world
    contact_lost_time: float  # s
    contact_force: float  # N
    nan: bool
    check_period: float  # s, all guards
    torque_period: float  # s, the joint torque alone (0: with the others)


def effort_limits(plant):
    """(joint names, effort limits (N m or N; inf where none)) of the
    plant's actuators, in actuation order."""
    names, limits = [], []
    for index in plant.GetJointActuatorIndices():
        actuator = plant.get_joint_actuator(index)
        names.append(actuator.joint().name())
        limit = actuator.effort_limit()
        limits.append(limit if limit > 0 else np.inf)
    return names, np.array(limits, float)


def add_effort_saturation(builder, scenario: Scenario, plant, actuation):
    """The port that drives the plant: ``actuation`` clamped at the effort
    limits by a Drake ``Saturation`` named ``drive_saturation``
    (``guards.saturate_effort``), or ``actuation`` itself. Below the limits
    the output is the input, bit for bit."""
    _, limits = effort_limits(plant)
    if not scenario.guards.saturate_effort or not np.any(np.isfinite(limits)):
        return actuation
    big = np.where(np.isfinite(limits), limits, 1e300)
    saturation = builder.AddNamedSystem(
        "drive_saturation", Saturation(-big, big)
    )
    builder.Connect(actuation, saturation.get_input_port())
    return saturation.get_output_port()


def guard_limits(scenario: Scenario, plant, contour, route=None) -> GuardLimits:
    """The scenario's ``guards`` with every 0 replaced by its default from
    the models: effort limits from the plant's actuators, the tool force
    from the task, the depth from the task and the cutter, the workspace
    from the contour (and the points of a probe's ``route``, (N, 3) m,
    where it leaves the edge)."""
    g: GuardsConfig = scenario.guards
    names, limits = effort_limits(plant)
    samples = np.array(
        [contour.point_at(s) for s in np.linspace(0.0, contour.length, 97)]
    )
    if route is not None:
        samples = np.vstack([samples, route])
    return GuardLimits(
        joint_names=names,
        effort_limits=limits,
        joint_torque_fraction=g.joint_torque_fraction,
        tool_force=g.tool_force
        or 10.0 * scenario.task.desired_chamfering_force,
        depth=g.depth
        or min(4.0 * scenario.task.desired_depth, scenario.tool.cutter_radius),
        workspace_low=samples.min(axis=0) - g.workspace_margin,
        workspace_high=samples.max(axis=0) + g.workspace_margin,
        contact_lost_time=g.contact_lost_time,
        contact_force=g.contact_force,
        nan=g.nan,
        check_period=g.check_period,
        torque_period=scenario.controller.control_period,
    )


def _fmt(v) -> str:
    return np.array2string(
        np.asarray(v, float), precision=4, separator=", ", suppress_small=False
    )


class SafetyGuards(LeafSystem):
    """Checks the logged signals every ``limits.check_period`` and requests
    termination naming the guard that tripped.

    .. pydrake_system::

        name: SafetyGuards
        input_ports:
        - chamfer
        - actuation
        - tool_force
        - controller (optional)
        - estimates (optional)
        - desired_normal_force (optional)
        - command (optional)
        - reference (optional)
        - process (optional)
        - probe (optional)
        - touch_points (optional)
        - registration (optional)

    One input port per logged signal, named as its logger
    (``signal_sizes``; the names above are the cell's, see
    deburr_drake.cell.diagram.LOGGED). The checks read ``actuation``
    (N m), ``tool_force`` (N, world: the force sensor's reading),
    ``chamfer`` (the observer's CHAMFER_STATE) and, where it is logged,
    ``process`` (the true depth); every input is checked for NaN.
    Discrete state ``contact``: [contact made (0/1), time contact was lost
    (s, -1 while in contact)], written only when it changes. Every guard
    is checked each ``check_period``; the joint torque also each
    ``torque_period`` (the inner loop's sample).

    The check costs a few microseconds: every signal is stacked into one
    vector and compared at once with per-element bounds (a NaN fails every
    comparison, an infinity exceeds the finite bounds of unchecked
    elements); only a failing check is looked at element by element."""

    def __init__(self, limits: GuardLimits, signal_sizes: Dict[str, int]):
        super().__init__()
        self.limits = limits
        self._inputs = {
            name: self.DeclareVectorInputPort(name, size)
            for name, size in signal_sizes.items()
        }
        for name in ("actuation", "tool_force", "chamfer"):
            if name not in self._inputs:
                raise ConfigError(f"SafetyGuards needs the {name!r} signal")
        self._ports = list(self._inputs.values())
        self._slices, start = {}, 0
        for name, size in signal_sizes.items():
            self._slices[name] = slice(start, start + size)
            start += size
        big = 1e300  # unchecked elements: finite, so inf trips too
        low, high = np.full(start, -big), np.full(start, big)
        if not limits.nan:
            low[:], high[:] = -np.inf, np.inf
        act = self._slices["actuation"]
        bound = np.where(
            np.isfinite(limits.effort_limits),
            limits.joint_torque_fraction * limits.effort_limits,
            high[act],
        )
        low[act], high[act] = -bound, bound
        chamfer = self._slices["chamfer"]
        base = chamfer.start
        high[base + CHAMFER_STATE.slice("delta").start] = limits.depth
        if "process" in self._slices:  # the true depth (part_error)
            high[
                self._slices["process"].start
                + PROCESS_STATE.slice("delta").start
            ] = limits.depth
        x_p = CHAMFER_STATE.slice("x_p")
        low[base + x_p.start : base + x_p.stop] = limits.workspace_low
        high[base + x_p.start : base + x_p.stop] = limits.workspace_high
        self._low, self._high = low, high
        self._force = self._slices["tool_force"]
        self._f_n = base + CHAMFER_STATE.slice("f_n").start
        self._tool_force_squared = limits.tool_force**2
        self._contact = self.DeclareDiscreteState(BasicVector([0.0, -1.0]))
        self.DeclarePeriodicDiscreteUpdateEvent(
            limits.check_period, 0.0, self._check
        )
        self._actuation = self._inputs["actuation"]
        self._torque_bound = high[act]
        if 0 < limits.torque_period < limits.check_period and np.any(
            np.isfinite(limits.effort_limits)
        ):
            # The torque at every inner-loop sample: one port, one compare.
            self.DeclarePeriodicDiscreteUpdateEvent(
                limits.torque_period, 0.0, self._check_torque
            )

    def _trip(self, t, name, values):
        return EventStatus.ReachedTermination(
            self, f"{name}: {values} at t = {t:.4f} s"
        )

    def _check_torque(self, context, discrete_state):
        tau = self._actuation.Eval(context)
        if (np.abs(tau) > self._torque_bound).any():
            return self._diagnose(
                context.get_time(),
                np.concatenate([port.Eval(context) for port in self._ports]),
            )
        return EventStatus.Succeeded()

    def _check(self, context, discrete_state):
        x = np.concatenate([port.Eval(context) for port in self._ports])
        if not ((x >= self._low) & (x <= self._high)).all():
            return self._diagnose(context.get_time(), x)
        f = x[self._force]
        if f @ f > self._tool_force_squared:
            return self._diagnose(context.get_time(), x)
        made, lost_since = context.get_discrete_state(self._contact).value()
        in_contact = x[self._f_n] > self.limits.contact_force
        if in_contact:
            if not made or lost_since >= 0:
                discrete_state.get_mutable_vector(self._contact).SetFromVector(
                    [1.0, -1.0]
                )
        elif made:
            t = context.get_time()
            if lost_since < 0:
                discrete_state.get_mutable_vector(self._contact).SetFromVector(
                    [1.0, t]
                )
            elif t - lost_since > self.limits.contact_lost_time:
                return self._trip(
                    t,
                    "contact_lost",
                    f"||f_n|| = {x[self._f_n]:.4g} N <= "
                    f"{self.limits.contact_force:g} N for "
                    f"{t - lost_since:.4g} s > "
                    f"{self.limits.contact_lost_time:g} s (since "
                    f"{lost_since:.4f} s)",
                )
        return EventStatus.Succeeded()

    def _diagnose(self, t, x):
        """The failing check's name and values (the slow path)."""
        lim = self.limits
        if lim.nan and not np.all(np.isfinite(x)):
            for name, s in self._slices.items():
                bad = np.flatnonzero(~np.isfinite(x[s]))
                if bad.size:
                    return self._trip(
                        t,
                        "nan",
                        f"signal {name} has non-finite elements {bad.tolist()}",
                    )
        tau = x[self._slices["actuation"]]
        ratio = np.abs(tau) / lim.effort_limits
        k = int(np.argmax(ratio))
        if ratio[k] > lim.joint_torque_fraction:
            return self._trip(
                t,
                "joint_torque",
                f"{lim.joint_names[k]} |tau| = {abs(tau[k]):.4g} > "
                f"{lim.joint_torque_fraction:g} x effort limit "
                f"{lim.effort_limits[k]:.4g} (all tau {_fmt(tau)})",
            )
        force = x[self._force]
        magnitude = float(np.linalg.norm(force))
        if magnitude > lim.tool_force:
            return self._trip(
                t,
                "tool_force",
                f"|f| = {magnitude:.4g} N > "
                f"{lim.tool_force:.4g} N (f = {_fmt(force)} N)",
            )
        chamfer = x[self._slices["chamfer"]]
        delta = float(CHAMFER_STATE.get(chamfer, "delta"))
        true = (
            float(PROCESS_STATE.get(x[self._slices["process"]], "delta"))
            if "process" in self._slices
            else delta
        )
        if max(delta, true) > lim.depth:
            return self._trip(
                t,
                "depth",
                f"delta = {delta * 1e3:.4g} mm "
                f"measured, {true * 1e3:.4g} mm true > "
                f"{lim.depth * 1e3:.4g} mm",
            )
        x_p = CHAMFER_STATE.get(chamfer, "x_p")
        if np.any(x_p < lim.workspace_low) or np.any(x_p > lim.workspace_high):
            return self._trip(
                t,
                "workspace",
                f"tool tip {_fmt(x_p)} m outside the box "
                f"{_fmt(lim.workspace_low)}..{_fmt(lim.workspace_high)} m",
            )
        bad = np.flatnonzero(~((x >= self._low) & (x <= self._high)))
        return self._trip(t, "nan", f"elements {bad.tolist()} beyond 1e300")


def add_guards(builder, scenario: Scenario, plant, contour, logged, route=None):
    """Adds :class:`SafetyGuards` named :data:`GUARDS_SYSTEM` to the
    builder, reading every ``logged`` signal (logger name -> output port),
    unless ``scenario.guards.enabled`` is false. Returns it (or None)."""
    if not scenario.guards.enabled:
        return None
    guards = builder.AddNamedSystem(
        GUARDS_SYSTEM,
        SafetyGuards(
            guard_limits(scenario, plant, contour, route),
            {name: port.size() for name, port in logged.items()},
        ),
    )
    for name, port in logged.items():
        builder.Connect(port, guards.GetInputPort(name))
    return guards
