"""The operating point of the stability analysis: the full Context of a
scenario's closed loop in steady cutting, and the frozen variant of the
scenario the analysis linearizes.

What is frozen, and why:

- the outer loop (``CommandGenerator``, 25 ms, and the ``FirstOrderHold``
  ramp): the feed law acts on a time scale of seconds (it moves x_c by
  v T = 60 um per 25 ms sample); the inner loop's modes are 10-1000 times
  faster, so the analysis treats x_c*(t) as a given reference. The periods
  analysed never contain a 25 ms sample.
- the adaptation (the estimator's c-hat of (16)-(18) and the fuzzy rule
  weights theta of (35)): with ``adapt: false`` their rates are zero, so
  they stay at the operating point's learned values. Their own dynamics
  (time constants of 0.05-0.5 s, and none inside the dead zone) are much
  slower than the loop's; eq. (8) assumes fixed estimates too.
- the burr: the operating point lies off the burrs (checked), and the burr
  and surface-finish records are not perturbed.
- the sensor noise (``noise_std: 0``): it is an input, not dynamics.
- the safety guards and the drives' torque clamp are off (``guards``):
  neither is in the linear model; the clamp bounds a limit cycle, and a
  guard stops the run that should show it.

And one numerical setting: a scenario integrated with error control is analysed
with fixed steps of one control period (the paper scenarios run fixed steps of
their own ``max_step``, two per control period). An error-controlled step size
is hidden state that the one-period map cannot perturb, so error-controlled runs
do not follow the map; with fixed steps the 2.5 ms map and the runs agree.

Everything else is live: plant (hydroelastic contact), controller,
force sensor (sampled low-pass), the cutting process's sampled force law.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
from typing import Dict, Optional

import numpy as np
from pydrake.common import RandomGenerator
from pydrake.systems.framework import Context, Diagram

from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.cell.plan import CellPlan, plan_cell
from deburr_drake.cell.process import PROCESS_STATE
from deburr_drake.config import (
    ConfigError,
    Scenario,
    get_field,
    set_field,
)
from deburr_drake.control.layout import CHAMFER_STATE
from deburr_drake.runs.simulation import make_simulator

__all__ = [
    "OperatingPoint",
    "find_operating_point",
    "frozen_scenario",
    "transfer_state",
    "get_field",
    "set_field",
    "DEFAULT_TIME_AFTER_CONTACT",
]

#: Default simulated seconds of cutting (after the first contact) before the
#: operating point is taken.
DEFAULT_TIME_AFTER_CONTACT = 3.0
#: Give up looking for contact after this many simulated seconds.
MAX_TIME_TO_CONTACT = 5.0
#: Contact: depth > 0 and ||f_n|| above this (N).
CONTACT_FORCE = 0.5


@dataclass
class OperatingPoint:
    """A scenario's closed loop captured in steady cutting.

    ``context`` is a clone of the full root Context of ``diagram`` (built
    from ``scenario`` itself, adaptation running) at ``time``, taken after
    ``Simulator.AdvanceTo(time)``: the discrete updates due at ``time``
    (a sample of the 2.5 ms loop) are still pending, so the context is the
    state just before that sample."""

    scenario: Scenario
    diagram: Diagram
    context: Context
    time: float  # s
    contact_time: float  # s, first contact
    signals: Dict[str, float] = field(default_factory=dict)
    # The plan the diagram was built from: its frozen variants reuse its
    # edges, robot model and start.
    plan: Optional[CellPlan] = None

    def variant(self, scenario: Scenario) -> CellPlan:
        """The plan of ``scenario``, a variant of the operating point's
        (frozen, other gains): this plan's cell, or planned anew."""
        if self.plan is None:
            return plan_cell(scenario)
        return self.plan.varied(scenario)

    def summary(self) -> Dict[str, float]:
        """time, depth, feed, forces (SI) for reports."""
        return {
            "time": self.time,
            "contact_time": self.contact_time,
            **self.signals,
        }


def frozen_scenario(
    scenario: Scenario, *, continuous: bool = False, **overrides
) -> Scenario:
    """A copy of ``scenario`` with the adaptation frozen, the noise off and
    fixed integration steps of one control period (see the module
    docstring); with ``continuous`` the controller and
    estimator run in continuous time (``control_period: 0``), the mode
    :func:`deburr_drake.analysis.linearize_closed_loop` differentiates."""
    frozen = copy.deepcopy(scenario)
    frozen.estimator.adapt = False
    frozen.controller.fuzzy.adapt = False
    frozen.sensor.noise_std = 0.0
    # Neither the drives' torque clamp nor the safety guards are in the
    # linear model: the clamp bounds a limit cycle, a guard stops the run.
    frozen.guards.enabled = False
    frozen.guards.saturate_effort = False
    if frozen.simulation.error_control and frozen.controller.control_period > 0:
        frozen.simulation.error_control = False
        frozen.simulation.max_step = frozen.controller.control_period
    if continuous:
        frozen.controller.control_period = 0.0
        # The law's implicit-damping term is cenic's discretization device,
        # and its held mean over a sample a sampled-data one: continuous
        # time takes eq. (3) as it follows the velocities.
        frozen.process.implicit_damping = False
        frozen.process.sample_mean = False
    for path, value in overrides.items():
        set_field(frozen, path, value)
    return frozen.validate()


def transfer_state(
    source: Diagram,
    source_context: Context,
    target: Diagram,
    target_context: Context,
):
    """Copies time and, subsystem by subsystem (matched by name), the
    continuous state and every discrete-state group whose count and sizes
    agree, from one diagram's context to another's (e.g. from the sampled
    cell to its continuous-time variant, whose controller holds nothing)."""
    target_context.SetTime(source_context.get_time())
    for system in target.GetSystems():
        name = system.get_name()
        if not source.HasSubsystemNamed(name):
            continue
        src_sys = source.GetSubsystemByName(name)
        src = src_sys.GetMyContextFromRoot(source_context)
        dst = system.GetMyMutableContextFromRoot(target_context)
        if src.num_continuous_states() == dst.num_continuous_states() > 0:
            dst.SetContinuousState(
                src.get_continuous_state_vector().CopyToVector()
            )
        if (
            src.num_discrete_state_groups()
            == dst.num_discrete_state_groups()
            > 0
        ):
            sizes = [
                (
                    src.get_discrete_state(i).size(),
                    dst.get_discrete_state(i).size(),
                )
                for i in range(src.num_discrete_state_groups())
            ]
            if all(a == b for a, b in sizes):
                for i in range(src.num_discrete_state_groups()):
                    dst.SetDiscreteState(
                        i, src.get_discrete_state(i).get_value()
                    )


def _signals(diagram: Diagram, context: Context) -> Dict[str, float]:
    observer = diagram.GetSubsystemByName("chamfer_observer")
    chamfer = observer.GetOutputPort("chamfer_state").Eval(
        observer.GetMyContextFromRoot(context)
    )
    process = diagram.GetSubsystemByName("cutting_process")
    state = process.GetOutputPort("process_state").Eval(
        process.GetMyContextFromRoot(context)
    )
    generator = diagram.GetSubsystemByName("command_generator")
    feed = generator.GetOutputPort("feed").Eval(
        generator.GetMyContextFromRoot(context)
    )[0]
    n2 = CHAMFER_STATE.get(chamfer, "n2")
    return {
        "depth": float(CHAMFER_STATE.get(chamfer, "delta")),
        "feed": float(feed),
        "tangential_speed": float(n2 @ CHAMFER_STATE.get(chamfer, "xdot_p")),
        "normal_force": float(CHAMFER_STATE.get(chamfer, "f_n")),
        "chamfering_force": float(CHAMFER_STATE.get(chamfer, "f_t")),
        "true_chamfering_force": float(PROCESS_STATE.get(state, "f_t")),
        "burr_area": float(PROCESS_STATE.get(state, "burr_area")),
        "arc_position": float(CHAMFER_STATE.get(chamfer, "arc_position")),
    }


def first_contact(
    diagram: Diagram,
    context: Context,
    advance_to,
    *,
    limit: float,
    name: str,
    step: float = 0.01,
) -> float:
    """Advances the run (``advance_to(t)``) in ``step`` s until the first
    contact (depth > 0, ||f_n|| > CONTACT_FORCE) and returns its time;
    ConfigError when there is none within ``limit`` s."""
    t = context.get_time()
    while True:
        s = _signals(diagram, context)
        if s["depth"] > 0 and s["normal_force"] > CONTACT_FORCE:
            return t
        if t >= limit - 1e-12:
            raise ConfigError(
                f"scenario '{name}': the tool never reached contact (depth "
                f"> 0, ||f_n|| > {CONTACT_FORCE} N) within {limit:g} s: no "
                "operating point"
            )
        t += step
        advance_to(t)


def _next_analysis_time(t: float, inner: float, outer: float) -> float:
    """The first inner-loop sample time >= t that is not an outer-loop
    sample time (so the analysed period starts with no 25 ms update)."""
    k = np.ceil(t / inner - 1e-9)
    while True:
        tk = k * inner
        ratio = tk / outer
        if abs(ratio - round(ratio)) > 1e-6:
            return float(tk)
        k += 1


def find_operating_point(
    scenario: Scenario,
    *,
    after_contact: float = DEFAULT_TIME_AFTER_CONTACT,
    at: float | None = None,
    max_time_to_contact: float = MAX_TIME_TO_CONTACT,
    max_burr_delay: float = 5.0,
) -> OperatingPoint:
    """Simulates ``scenario`` (as given: adaptation on, noise on) from its
    default context until ``after_contact`` seconds after the first contact
    (or to the absolute time ``at``), moved on to the next inner-loop sample
    that is not an outer-loop sample, and further while the tool is on a
    burr. Raises ConfigError when the tool never reaches contact within
    ``max_time_to_contact`` or the chosen time is not positive."""
    scenario.validate()
    period = scenario.controller.control_period or scenario.sensor.sample_period
    if at is not None and not (np.isfinite(at) and at > 0):
        raise ConfigError(f"--at = {at!r} is invalid: allowed a time > 0 s")
    if not after_contact >= 0:
        raise ConfigError(
            f"after_contact = {after_contact!r} is invalid: allowed >= 0 s"
        )
    # Planned once: the operating point's scenario (its designed values
    # resolved) and cell are what its maps and frozen variants are built
    # from.
    plan = plan_cell(scenario)
    scenario = plan.scenario
    diagram = make_deburring_diagram(plan)
    simulator = make_simulator(diagram, scenario)
    context = simulator.get_mutable_context()
    diagram.SetRandomContext(
        context, RandomGenerator(scenario.sensor.noise_seed)
    )
    simulator.Initialize()
    contact = first_contact(
        diagram,
        context,
        simulator.AdvanceTo,
        limit=max_time_to_contact,
        name=scenario.name,
    )
    target = at if at is not None else contact + after_contact
    target = _next_analysis_time(target, period, scenario.command.period)
    simulator.AdvanceTo(target)
    limit = target + max_burr_delay
    while _signals(diagram, context)["burr_area"] > 0 and target < limit:
        target = _next_analysis_time(
            target + 0.1, period, scenario.command.period
        )
        simulator.AdvanceTo(target)
    signals = _signals(diagram, context)
    if signals["depth"] <= 0 or signals["normal_force"] <= CONTACT_FORCE:
        raise ConfigError(
            f"scenario '{scenario.name}': out of contact at t = "
            f"{target:g} s (depth {signals['depth']:.3g} m, ||f_n|| "
            f"{signals['normal_force']:.3g} N): no operating point"
        )
    return OperatingPoint(
        scenario=scenario,
        diagram=diagram,
        context=context.Clone(),
        time=target,
        contact_time=contact,
        signals=signals,
        plan=plan,
    )
