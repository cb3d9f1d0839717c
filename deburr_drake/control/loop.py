"""The paper's two control loops, added to any ``DiagramBuilder`` around any
robot plant: :func:`add_deburring_controller`.

The outer loop is the ``CommandGenerator`` (feedrate law, T = 25 ms) and its
``FirstOrderHold`` (5); the inner loop is the ``ChamferObserver``, the
``ContactParameterEstimator`` (13)-(18) and the ``HybridController``
(36), (37). Together they need two signals from the user's side of the
diagram and give one back::

    plant state [q; v] ─────┐               ┌── actuation (nu) ──> plant
    measured force (3, N) ──┴─> the loops ──┘

``make_deburring_diagram`` builds the paper's cell with it; a user with a
plant of their own (``examples/own_plant.py``) calls it the same way::

    loops = add_deburring_controller(
        builder, scenario=scenario, plant=plant, contour=contour,
        plant_state=plant.get_state_output_port(),
        measured_force=my_force_sensor.get_output_port())
    builder.Connect(loops.actuation, plant.get_actuation_input_port())

The systems get the cell's names (``chamfer_observer``,
``command_generator``, ``first_order_hold``, ``contact_estimator``,
``controller``), so :data:`deburr_drake.cell.diagram.LOGGED` names their
outputs in a user's diagram too.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import NamedTuple, Optional

import numpy as np
from pydrake.multibody.plant import MultibodyPlant
from pydrake.systems.framework import DiagramBuilder, OutputPort
from pydrake.systems.primitives import ConstantVectorSource

from deburr_drake.config import Scenario
from deburr_drake.control.command import CommandGenerator, FirstOrderHold
from deburr_drake.control.controller import HybridController
from deburr_drake.control.estimator import ContactParameterEstimator
from deburr_drake.control.mesh_probe import MeshProbePlan, MeshProbingSequence
from deburr_drake.control.observer import ChamferObserver
from deburr_drake.control.online import OnlineRegistration
from deburr_drake.control.probe import ProbeGate, ProbingSequence, sensor_timing
from deburr_drake.math.geometry import Contour
from deburr_drake.math.registration import registration_size

__all__ = ["DeburringController", "add_deburring_controller"]


@dataclass
class DeburringController:
    """The systems :func:`add_deburring_controller` added, and the port to
    connect to the plant's actuation input."""

    observer: ChamferObserver
    command_generator: CommandGenerator
    first_order_hold: FirstOrderHold
    estimator: ContactParameterEstimator
    controller: HybridController
    #: ``localisation.probe.enabled``: the probing sequence (a mesh
    #: part's: MeshProbingSequence) and its gate.
    probe: Optional[ProbingSequence | MeshProbingSequence] = None
    gate: Optional[ProbeGate] = None
    #: ``localisation.online.enabled``: registration while cutting.
    online: Optional[OnlineRegistration] = None

    @property
    def actuation(self) -> OutputPort:
        """The controller's ``actuation`` output (nu, N or N m)."""
        return self.controller.GetOutputPort("actuation")

    @property
    def spindle(self) -> Optional[OutputPort]:
        """1 while the spindle turns, 0 while probing (None: no
        probing, the spindle always turns)."""
        return (
            None if self.probe is None else self.probe.GetOutputPort("spindle")
        )

    @property
    def chamfer(self) -> OutputPort:
        """The chamfer state the loops act on (while probing: no
        contact)."""
        if self.gate is not None:
            return self.gate.GetOutputPort("chamfer_state")
        return self.observer.GetOutputPort("chamfer_state")


def _connect(builder: DiagramBuilder, pairs):
    for output, input_port in pairs:
        builder.Connect(output, input_port)


def _constant(builder, name, value) -> OutputPort:
    return builder.AddNamedSystem(
        name, ConstantVectorSource(np.asarray(value, float))
    ).get_output_port()


class _Signals(NamedTuple):
    """What the inner loop reads from the outer loop and the observer:
    the chamfer state, the sampled command and the desired normal
    force (output ports)."""

    chamfer: OutputPort
    command: OutputPort
    desired: OutputPort

    @staticmethod
    def of(loops: DeburringController) -> _Signals:
        """The observer's (a job's: gated), the generator's and the
        estimator's (a job's: gated)."""
        desired = (loops.gate or loops.estimator).GetOutputPort(
            "desired_normal_force"
        )
        return _Signals(
            chamfer=loops.chamfer,
            command=loops.command_generator.GetOutputPort("command"),
            desired=desired,
        )


def _add_loops(
    builder, c: Scenario, *, plant, contour, x0, tool_frame, **passed
) -> DeburringController:
    """The observer, the command generator, its hold, the estimator and
    the controller (``passed``: the controller's and observer's optional
    arguments, ``sequenced``), not yet connected."""
    probing = c.localisation.probe.enabled
    sequenced = _job_loops(c, passed.pop("sequenced"))
    # The constant-feed laws run a timed path, no feedrate law.
    constant_feed = (
        c.command.constant_feed
        if c.controller.kind in c.controller.CONSTANT_FEED_KINDS
        else None
    )
    observer = builder.AddNamedSystem(
        "chamfer_observer",
        ChamferObserver(
            plant,
            tool_frame,
            contour,
            min_tangential_speed=c.command.min_tangential_speed,
            tool_point=passed["tool_point"],
            contour_step=passed["contour_step"],
            registered=c.localisation.enabled,
        ),
    )
    generator = builder.AddNamedSystem(
        "command_generator",
        CommandGenerator(
            c.command,
            c.task,
            contour,
            x0,
            constant_feed=constant_feed,
            contour_step=passed["contour_step"],
            registered=c.localisation.enabled,
            hold_input=sequenced,
        ),
    )
    # Probing starts off the part, at x0 (the probe's standoff).
    foh = builder.AddNamedSystem(
        "first_order_hold",
        FirstOrderHold(
            c.command.period, x0 if probing else contour.project(x0)
        ),
    )
    estimator = builder.AddNamedSystem(
        "contact_estimator",
        ContactParameterEstimator(
            c.estimator, c.task, sample_period=c.controller.control_period
        ),
    )
    controller = builder.AddNamedSystem(
        "controller",
        HybridController(
            plant,
            tool_frame,
            c.controller,
            passed["desired_rotation"],
            tool_point=passed["tool_point"],
            nominal_depth=c.task.desired_depth,
            true_plant=passed["true_plant"],
            posture=passed["posture"],
            fuzzy_weight_input=probing or sequenced,
            contour=contour,
            active_input=sequenced,
        ),
    )
    return DeburringController(
        observer=observer,
        command_generator=generator,
        first_order_hold=foh,
        estimator=estimator,
        controller=controller,
        gate=_job_gate(builder, observer, estimator) if sequenced else None,
    )


def _job_loops(c: Scenario, sequenced: bool) -> bool:
    """``sequenced``, checked: a job's loops run without registration
    while cutting (touch probing, before the first cut, they have)."""
    if sequenced and c.localisation.online.enabled:
        raise ValueError("a job's loops run without online registration")
    return sequenced


def _job_gate(builder, observer, estimator) -> ProbeGate:
    """A job's gate (``job_gate``): no contact seen off the part."""
    gate = builder.AddNamedSystem("job_gate", ProbeGate())
    builder.Connect(
        observer.GetOutputPort("chamfer_state"),
        gate.GetInputPort("chamfer_state"),
    )
    builder.Connect(
        estimator.GetOutputPort("desired_normal_force"),
        gate.GetInputPort("desired_normal_force"),
    )
    return gate


def _probing_sequence(c: Scenario, *, contour, x0, timing, mesh_probe):
    """The planar parts' sequence, or with ``mesh_probe`` (a
    MeshProbePlan) a mesh part's."""
    common = dict(
        sample_period=c.sensor.sample_period,
        timing=timing,
        initial_position=x0,
        start_depth=c.simulation.initial_depth,
        desired_depth=c.task.desired_depth,
    )
    if mesh_probe is None:
        return ProbingSequence(contour, c.localisation.probe, **common)
    return MeshProbingSequence(
        contour, mesh_probe, c.localisation.probe, **common
    )


def _add_probing(
    builder,
    c: Scenario,
    loops,
    signals,
    *,
    contour,
    x0,
    timing,
    force,
    mesh_probe=None,
    sequenced=False,
):
    """The probing sequence and its gate between the observer, the
    generator and the estimator and the rest (``sequenced``: a job's,
    whose sequencer holds the generator and weighs the fuzzy rules).
    Returns the signals the loops use from then on, the sequence and the
    gate."""
    probe = builder.AddNamedSystem(
        "probing_sequence",
        _probing_sequence(
            c, contour=contour, x0=x0, timing=timing, mesh_probe=mesh_probe
        ),
    )
    held = None
    if mesh_probe is not None:  # the start's n1 and arc while probing
        held = (contour.n1(contour.point_at(0.0)), 0.0)
    gate = builder.AddNamedSystem("probe_gate", ProbeGate(held))
    _connect(
        builder,
        [
            (signals.chamfer, probe.GetInputPort("chamfer_state")),
            (force, probe.GetInputPort("measured_force")),
            (signals.command, probe.GetInputPort("command_in")),
            (probe.GetOutputPort("probing"), gate.GetInputPort("probing")),
            (signals.chamfer, gate.GetInputPort("chamfer_state")),
            (signals.desired, gate.GetInputPort("desired_normal_force")),
        ],
    )
    if not sequenced:
        _connect(
            builder,
            [
                (
                    probe.GetOutputPort("hold"),
                    loops.command_generator.GetInputPort("hold"),
                ),
                (
                    probe.GetOutputPort("fuzzy_weight"),
                    loops.controller.GetInputPort("fuzzy_weight"),
                ),
            ],
        )
    gated = _Signals(
        chamfer=gate.GetOutputPort("chamfer_state"),
        command=probe.GetOutputPort("command"),
        desired=gate.GetOutputPort("desired_normal_force"),
    )
    return gated, probe, gate


def _add_online(builder, c: Scenario, loops, base, *, contour, timing, probe):
    """Registration while cutting, on top of the ``base`` registration
    (the probe's, or zero). Returns its system."""
    online = builder.AddNamedSystem(
        "online_registration",
        OnlineRegistration(
            contour,
            c.localisation.online,
            c.estimator,
            latency=timing.latency,
            probed=probe is not None,
        ),
    )
    # It learns while the spindle turns.
    active = (
        _constant(builder, "spindle_on", [1.0])
        if probe is None
        else probe.GetOutputPort("spindle")
    )
    _connect(
        builder,
        [
            (
                loops.observer.GetOutputPort("chamfer_state"),
                online.GetInputPort("chamfer_state"),
            ),
            (base, online.GetInputPort("base_registration")),
            (active, online.GetInputPort("active")),
        ],
    )
    return online


def _add_localisation(
    builder,
    c: Scenario,
    loops,
    signals,
    *,
    contour,
    x0,
    measured_force,
    mesh_probe=None,
    sequenced=False,
):
    """``localisation.probe``: the probing sequence and its gate;
    ``localisation.online``: registration while cutting; the registration
    into the observer and the generator. Returns the loops with those
    systems and the signals the loops use from then on."""
    timing = sensor_timing(c.sensor.sample_period, c.sensor.cutoff_frequency)
    generator = loops.command_generator
    probe = gate = online = None
    # Touch probing, or neither hold nor registration from it.
    if c.localisation.probe.enabled:
        signals, probe, gate = _add_probing(
            builder,
            c,
            loops,
            signals,
            contour=contour,
            x0=x0,
            timing=timing,
            force=measured_force,
            mesh_probe=mesh_probe,
            sequenced=sequenced,
        )
        registration = probe.GetOutputPort("registration")
    else:
        builder.Connect(
            _constant(builder, "no_probing", [0.0]),
            generator.GetInputPort("hold"),
        )
        registration = _constant(
            builder,
            "no_probe_registration",
            np.zeros(registration_size(contour)),
        )
    # Registration while cutting.
    if c.localisation.online.enabled:
        online = _add_online(
            builder,
            c,
            loops,
            registration,
            contour=contour,
            timing=timing,
            probe=probe,
        )
        registration = online.GetOutputPort("registration")
    # The believed part, moved by the registration.
    for system in (loops.observer, generator):
        builder.Connect(registration, system.GetInputPort("registration"))
    return replace(loops, probe=probe, gate=gate, online=online), signals


def _connect_loops(builder, loops: DeburringController, signals: _Signals):
    """The loops to each other: the chamfer state to the generator, the
    estimator and the controller; the command through the hold."""
    foh, controller = loops.first_order_hold, loops.controller
    for system in (loops.command_generator, loops.estimator, controller):
        builder.Connect(signals.chamfer, system.GetInputPort("chamfer_state"))
    _connect(
        builder,
        [
            (signals.command, foh.GetInputPort("sampled")),
            (
                foh.GetOutputPort("position"),
                controller.GetInputPort("commanded_position"),
            ),
            (
                foh.GetOutputPort("velocity"),
                controller.GetInputPort("commanded_velocity"),
            ),
            (
                signals.desired,
                controller.GetInputPort("desired_normal_force"),
            ),
        ],
    )


def add_deburring_controller(
    builder: DiagramBuilder,
    *,
    scenario: Scenario,
    plant: MultibodyPlant,
    contour: Contour,
    plant_state: OutputPort,
    measured_force: OutputPort,
    tool_frame: str = "tool_tip",
    start=None,
    desired_rotation=None,
    tool_point=None,
    contour_step=None,
    true_plant=None,
    posture=None,
    sequenced: bool = False,
    mesh_probe: Optional[MeshProbePlan] = None,
) -> DeburringController:
    """Adds the command generator, first-order hold, chamfer observer,
    contact estimator and hybrid controller to ``builder``, configured by
    ``scenario`` (its ``command``, ``task``, ``estimator`` and ``controller``
    sections), and connects them to each other and to the two signals:

    - ``plant_state``: [q; v] of ``plant`` (m or rad, m/s or rad/s), e.g.
      ``plant.get_state_output_port()``;
    - ``measured_force`` (3, N, world): the part's force on the tool.

    ``plant`` (finalized): the controller's robot model (masses scaled by
    ``controller.model_mass_scale``), the simulated plant or a copy;
    ``tool_frame``: its origin is x_p; ``contour``: x_p's zero-depth
    path along the believed edge; ``start`` (m, world; default: the
    contour's start); ``desired_rotation`` (default identity), turned by
    ``contour.axis_turn(s)`` when ``contour.varying_frame``;
    ``tool_point``, ``contour_step``, ``true_plant``, ``posture``: passed
    to the systems. ``sequenced``: a job's loops (control.sequencer): a
    gate ``job_gate`` after the observer, its ``probing``, the generator's
    ``hold`` and the controller's ``fuzzy_weight`` and ``active`` left
    open (probed: the sequencer reads the probe's ``probing`` and
    ``registration``). ``mesh_probe`` (control.mesh_probe.MeshProbePlan):
    a mesh part's touches and its six-degree registration (and a hole's
    size) instead of the planar probe.

    Returns the systems; connect ``.actuation`` to the plant's actuation
    input (directly, or through your own saturation or fault systems)."""
    c = scenario
    x0 = contour.point_at(0.0) if start is None else np.asarray(start, float)
    loops = _add_loops(
        builder,
        c,
        plant=plant,
        contour=contour,
        x0=x0,
        tool_frame=tool_frame,
        desired_rotation=desired_rotation,
        tool_point=tool_point,
        contour_step=contour_step,
        true_plant=true_plant,
        posture=posture,
        sequenced=sequenced,
    )
    # The two signals from the user's side of the diagram.
    for system in (loops.observer, loops.controller):
        builder.Connect(plant_state, system.GetInputPort("plant_state"))
        builder.Connect(measured_force, system.GetInputPort("measured_force"))
    signals = _Signals.of(loops)
    if c.localisation.enabled:  # between the loops
        loops, signals = _add_localisation(
            builder,
            c,
            loops,
            signals,
            contour=contour,
            x0=x0,
            measured_force=measured_force,
            mesh_probe=mesh_probe,
            sequenced=sequenced,
        )
    # The loops to each other.
    _connect_loops(builder, loops, signals)
    return loops
