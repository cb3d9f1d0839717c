"""The deburring cell as a named Drake Diagram: a robot (the 5-DOF arm of
Section IV, the 6-DOF arm6, any arm from a model file (deburr_drake.cell.robot),
or a Cartesian point-mass tool) whose cylindrical cutter chamfers
a tube's inner edge through hydroelastic contact, closed by the paper's
command generator, first-order hold, contact estimator and hybrid
controller, with the plant-side cutting process, joint friction and force
sensor.

Use: ``diagram = make_deburring_diagram(plan_cell(load_scenario("paper")))``,
then :func:`deburr_drake.runs.simulation.simulate`. Every system is named
(:data:`SYSTEM_NAMES`), every logged output is in :data:`LOGGED` (logger
``log_<name>``); pass ``meshcat=`` to draw the cell (deburr_drake.cell.meshcat).
The controller side alone, around a plant of your own, is
:func:`deburr_drake.control.loop.add_deburring_controller`."""

from __future__ import annotations

from typing import Mapping, NamedTuple, Optional, Tuple

import numpy as np
from pydrake.common import RandomDistribution
from pydrake.systems.framework import Diagram, DiagramBuilder, OutputPort
from pydrake.systems.primitives import LogVectorOutput, RandomSource

from deburr_drake.cell.counts import DIAGRAMS, count
from deburr_drake.cell.edge import edge_points
from deburr_drake.cell.faults import add_noise_scale, add_sensor_faults
from deburr_drake.cell.guards import add_effort_saturation, add_guards
from deburr_drake.cell.plan import CellPlan, plan_cell
from deburr_drake.cell.plant import add_cell_plant
from deburr_drake.cell.process import CuttingProcess
from deburr_drake.cell.sensor import ForceSensor
from deburr_drake.config import ConfigError, RobotConfig, Scenario
from deburr_drake.control.kinematics import ToolPoint
from deburr_drake.control.loop import add_deburring_controller

__all__ = [
    "make_deburring_diagram",
    "add_cutting_process",
    "add_force_sensor",
    "add_force_law",
    "add_touch_contact",
    "sensor_reading",
    "TOOL_FRAME",
    "SENSOR_JOINT",
    "LOGGED",
    "LOCALISATION_LOGGED",
    "SYSTEM_NAMES",
]

#: The default names of the tool frame and the sensor joint
#: (``robot.tool_frame``, ``robot.sensor_joint`` name them per robot).
TOOL_FRAME = RobotConfig.tool_frame
SENSOR_JOINT = RobotConfig.sensor_joint

#: Logged signals: logger name -> (system name, output port name).
LOGGED = {
    "chamfer": ("chamfer_observer", "chamfer_state"),
    "controller": ("controller", "diagnostics"),
    "actuation": ("controller", "actuation"),
    "estimates": ("contact_estimator", "estimates"),
    "desired_normal_force": ("contact_estimator", "desired_normal_force"),
    "command": ("command_generator", "command_state"),
    "reference": ("first_order_hold", "position"),
    "process": ("cutting_process", "process_state"),
    "tool_force": ("force_sensor", "measured_force"),
}

#: Logged when the controller side has localisation's systems (touch
#: probing and online registration, ``localisation``).
LOCALISATION_LOGGED = {
    "probe": ("probing_sequence", "probe_state"),
    "touch_points": ("probing_sequence", "touch_points"),
    "registration": ("online_registration", "registration_state"),
}

#: Every system the builder adds (besides the loggers ``log_<name>``).
SYSTEM_NAMES = (
    "plant",
    "scene_graph",
    "cutting_process",
    "cutting_force",
    "force_sensor",
    "sensor_noise",
    "chamfer_observer",
    "command_generator",
    "first_order_hold",
    "contact_estimator",
    "controller",
)


class _PlantSide(NamedTuple):
    """The systems between the plant and the controller side."""

    process: CuttingProcess
    force_law: Diagram
    sensor: ForceSensor
    reading: OutputPort  # what the controller side reads (after faults)


def add_cutting_process(
    builder,
    scenario: Scenario,
    plant,
    contour,
    tool_point,
    *,
    name: str = "cutting_process",
    spindle_input: bool = False,
) -> CuttingProcess:
    """The cutting process on the real edge ``contour``, reading the
    plant's state (``spindle_input``: its spindle switched by a port)."""
    c = scenario
    process = builder.AddNamedSystem(
        name,
        CuttingProcess(
            plant,
            c.robot.tool_frame,
            contour,
            c.process,
            cut_height=c.tool.engagement,
            cutter_radius=c.tool.cutter_radius,
            tool_point=tool_point,
            spindle_input=spindle_input,
        ),
    )
    builder.Connect(
        plant.get_state_output_port(), process.GetInputPort("plant_state")
    )
    return process


def add_force_sensor(builder, scenario: Scenario, plant, tool_point):
    """(the force sensor, its noise source), reading the plant's state and
    reaction forces; its ``applied_force`` and ``noise`` are left to
    connect (:func:`add_force_law`, :func:`sensor_reading`)."""
    c = scenario
    sensor = builder.AddNamedSystem(
        "force_sensor",
        ForceSensor(
            plant, c.robot.sensor_joint, c.sensor, tool_point=tool_point
        ),
    )
    noise = builder.AddNamedSystem(
        "sensor_noise",
        RandomSource(RandomDistribution.kGaussian, 3, c.sensor.sample_period),
    )
    builder.Connect(
        plant.get_state_output_port(), sensor.GetInputPort("plant_state")
    )
    builder.Connect(
        plant.get_reaction_forces_output_port(),
        sensor.GetInputPort("reaction_forces"),
    )
    return sensor, noise


def add_force_law(builder, plant, process, name=None) -> Diagram:
    """``process``'s force law (its ``applied_force`` and
    ``generalized_force`` left to connect), reading the plant's state and
    the process's terms."""
    law = process.force_law()
    law = (
        builder.AddSystem(law)
        if name is None
        else builder.AddNamedSystem(name, law)
    )
    builder.Connect(
        plant.get_state_output_port(), law.GetInputPort("plant_state")
    )
    builder.Connect(
        process.GetOutputPort("force_law_terms"),
        law.GetInputPort("force_law_terms"),
    )
    return law


def sensor_reading(builder, scenario: Scenario, sensor, noise) -> OutputPort:
    """The sensor's noise (scaled by the faults) connected, and what the
    observer and the controller read: its output after the faults (bias,
    dropouts)."""
    builder.Connect(
        add_noise_scale(builder, scenario.faults, noise.get_output_port()),
        sensor.GetInputPort("noise"),
    )
    return add_sensor_faults(
        builder,
        scenario.faults,
        sensor.GetOutputPort("measured_force"),
        sample_period=scenario.sensor.sample_period,
    )


def _add_plant_side(
    builder, scenario: Scenario, plant, contour, tool_point
) -> _PlantSide:
    """The cutting process on the real edge, its force law on the plant,
    and the force sensor with its noise and faults, wired to the plant."""
    process = add_cutting_process(
        builder,
        scenario,
        plant,
        contour,
        tool_point,
        spindle_input=scenario.localisation.probe.enabled,
    )
    sensor, noise = add_force_sensor(builder, scenario, plant, tool_point)
    force_law = add_force_law(builder, plant, process)
    builder.Connect(
        force_law.GetOutputPort("applied_force"),
        sensor.GetInputPort("applied_force"),
    )
    builder.Connect(
        force_law.GetOutputPort("generalized_force"),
        plant.get_applied_generalized_force_input_port(),
    )
    reading = sensor_reading(builder, scenario, sensor, noise)
    return _PlantSide(process, force_law, sensor, reading)


def _connect_actuation(builder, scenario: Scenario, plant, side, actuation):
    """The controller's ``actuation`` to the plant through the drives
    (clamped at the effort limits), and to the force law and the process
    that hold the sample's torque (``process.sample_mean``)."""
    actuation = add_effort_saturation(builder, scenario, plant, actuation)
    builder.Connect(actuation, plant.get_actuation_input_port())
    builder.Connect(actuation, side.force_law.GetInputPort("actuation"))
    if not scenario.process.sample_mean:
        return
    for port, source in (
        (
            "generalized_acceleration",
            plant.get_generalized_acceleration_output_port(),
        ),
        (
            "applied_generalized_force",
            side.force_law.GetOutputPort("generalized_force"),
        ),
        ("actuation", actuation),
    ):
        builder.Connect(source, side.process.GetInputPort(port))


def add_touch_contact(builder, plan: CellPlan, plant, tool_point, probe):
    """The probe's contact with the real mesh part while it touches
    (deburr_drake.cell.touches.TouchContact, ``touch_contact``), on the
    plant's tool, switched by ``probe``'s (MeshProbingSequence)
    ``touching``; returns it."""
    from deburr_drake.cell.touches import TouchContact, touch_law

    c = plan.scenario
    contact = builder.AddNamedSystem(
        "touch_contact",
        TouchContact(
            plant,
            tool_frame=c.robot.tool_frame,
            surface=plan.touch_surface,
            radius=plan.mesh_probe.radius,
            law=touch_law(c),
            dissipation=c.part.material.hunt_crossley_dissipation,
            sample_period=c.sensor.sample_period,
            tool_point=tool_point,
        ),
    )
    connect = builder.Connect
    connect(plant.get_state_output_port(), contact.GetInputPort("plant_state"))
    connect(probe.GetOutputPort("touching"), contact.GetInputPort("touching"))
    connect(
        plant.get_contact_results_output_port(),
        contact.GetInputPort("contact_results"),
    )
    connect(
        plant.get_body_poses_output_port(), contact.GetInputPort("body_poses")
    )
    connect(
        contact.GetOutputPort("spatial_forces"),
        plant.get_applied_spatial_force_input_port(),
    )
    return contact


def _add_touch_contact(
    builder, plan: CellPlan, plant, tool_point, probe, process
):
    """:func:`add_touch_contact`; returns the process state as the guards
    see it (TouchGate: no chamfer while touching)."""
    from deburr_drake.cell.touches import TouchGate

    add_touch_contact(builder, plan, plant, tool_point, probe)
    connect = builder.Connect
    gate = builder.AddNamedSystem("touch_gate", TouchGate())
    connect(probe.GetOutputPort("touching"), gate.GetInputPort("touching"))
    connect(
        process.GetOutputPort("process_state"),
        gate.GetInputPort("process_state"),
    )
    return gate.GetOutputPort("process_state")


def _logged_signals(builder, loops, probing: bool, touch_gate=None) -> dict:
    """{logger name: output port} of :data:`LOGGED` and, where the systems
    are there, :data:`LOCALISATION_LOGGED`."""
    logged = {
        name: builder.GetSubsystemByName(system).GetOutputPort(port)
        for name, (system, port) in LOGGED.items()
    }
    if probing:
        # The guards and the metrics see the pass: no contact while probing.
        logged["chamfer"] = loops.chamfer
        logged["desired_normal_force"] = loops.gate.GetOutputPort(
            "desired_normal_force"
        )
    if touch_gate is not None:
        # No chamfer is cut while a mesh part is touched.
        logged["process"] = touch_gate
    for name, (system, port) in LOCALISATION_LOGGED.items():
        if builder.HasSubsystemNamed(system):
            logged[name] = builder.GetSubsystemByName(system).GetOutputPort(
                port
            )
    return logged


def _add_loggers(builder, scenario: Scenario, logged, extra_logs):
    """A ``log_<name>`` VectorLogSink per ``logged`` signal and per entry
    of ``extra_logs``, at ``simulation.log_period``."""
    logged = dict(logged)
    for name, (system, port) in (extra_logs or {}).items():
        if name in logged:
            raise ConfigError(
                f"extra_logs: {name!r} is logged already: "
                f"allowed a name not in {sorted(logged)}"
            )
        logged[name] = builder.GetSubsystemByName(system).GetOutputPort(port)
    for name, port in logged.items():
        logger = LogVectorOutput(port, builder, scenario.simulation.log_period)
        logger.set_name(f"log_{name}")


def _add_meshcat(builder, meshcat, plan, plant, scene_graph, process):
    """The cell, its contact forces and the edge drawn in ``meshcat``."""
    from deburr_drake.cell.meshcat import add_meshcat

    add_meshcat(
        builder,
        meshcat,
        plant=plant,
        scene_graph=scene_graph,
        process=process,
        edge_points=edge_points(plan.scenario, process.bins.centers),
        edge_axes=_edge_axes(plan.contour, process.bins.centers),
    )


def _edge_axes(contour, arc):
    """The tool axis at arc positions ``arc`` along a turning (3-D) edge,
    else None (vertical)."""
    if not contour.varying_frame:
        return None
    return np.array([contour.tool_axis_at(s) for s in arc])


def _the_plan(plan, scenario) -> CellPlan:
    """The plan given, or ``scenario``'s; TypeError for neither, both, or
    a scenario passed as the plan."""
    if (plan is None) == (scenario is None):
        raise TypeError(
            "make_deburring_diagram: pass a plan (plan_cell(scenario)) or "
            "scenario=, not both"
        )
    if isinstance(plan, Scenario):
        raise TypeError(
            "make_deburring_diagram: got a Scenario as the plan: pass "
            "plan_cell(scenario) or scenario=scenario"
        )
    return plan_cell(scenario) if plan is None else plan


def _wire_probe(builder, plan: CellPlan, plant, tool_point, loops, side):
    """Touch probing on the plant's side: the loops turn the spindle off
    and on; on a mesh part the probe touches the real part's faces
    (returns that contact's gate; None on a planar part)."""
    if plan.scenario.localisation.probe.enabled:
        builder.Connect(loops.spindle, side.process.GetInputPort("spindle"))
    if plan.mesh_probe is None:
        return None
    return _add_touch_contact(
        builder, plan, plant, tool_point, loops.probe, side.process
    )


def _probe_route(plan: CellPlan):
    """Where a mesh part's probe leaves the edge ((N, 3) m, world), which
    the guards' workspace must hold; None without one."""
    if plan.mesh_probe is None:
        return None
    return plan.mesh_probe.route(plan.scenario.localisation.probe.standoff)


def make_deburring_diagram(
    plan: Optional[CellPlan] = None,
    *,
    scenario: Optional[Scenario] = None,
    meshcat=None,
    extra_logs: Optional[Mapping[str, Tuple[str, str]]] = None,
) -> Diagram:
    """The closed loop of ``plan`` (deburr_drake.cell.plan.plan_cell) as a
    named Diagram ``deburr_<scenario name>``.

    Systems: :data:`SYSTEM_NAMES`, ``guards`` (deburr_drake.cell.guards,
    unless ``guards.enabled`` is false), ``drive_saturation`` (the drives
    clamp the commanded torque at the effort limits, unless
    ``guards.saturate_effort`` is false), ``sensor_faults`` and
    ``sensor_noise_scale`` with faults (deburr_drake.cell.faults), and a
    ``log_<name>`` VectorLogSink per entry of :data:`LOGGED`. The tool
    starts at the plan's start, in contact. With a ``meshcat``, the cell
    is drawn there too (deburr_drake.cell.meshcat).

    Built from ``plan.scenario`` (its designed values resolved), the
    plan's edges, robot model and start: nothing is derived again from
    the raw scenario. ``scenario=`` instead of a plan plans it first
    (``plan_cell(scenario)``: a convenience; to build more than once, or
    to report the values built, plan once and pass the plan).

    ``extra_logs`` ({name: (system name, output port name)}) logs more
    signals, e.g. ``{"feed": ("command_generator", "feed")}``: loggers
    ``log_<name>`` that :func:`deburr_drake.runs.simulation.simulate`
    collects as ``log[name]`` (``t`` and ``value``)."""
    plan = _the_plan(plan, scenario)
    count(DIAGRAMS)
    c = plan.scenario
    probing = c.localisation.probe.enabled
    builder = DiagramBuilder()
    # The plant: the robot with its cutter and friction, the real part,
    # posed at the start.
    plant, scene_graph = add_cell_plant(builder, c)
    plant.SetDefaultPositions(plan.start.q)
    # One kinematics memo for the process (truth), the sensor, the observer
    # and the controller: they read the same joint state.
    model = plan.model
    tool_point = ToolPoint(model, model.GetFrameByName(c.robot.tool_frame))
    # The plant side: the cutting process on the real edge, its force law,
    # the force sensor and its faults.
    side = _add_plant_side(builder, c, plant, plan.contour, tool_point)
    # The paper's loops around the plant (deburr_drake.control.loop), on
    # the edge the controller believes in.
    loops = add_deburring_controller(
        builder,
        scenario=c,
        plant=model,
        contour=plan.belief,
        plant_state=plant.get_state_output_port(),
        measured_force=side.reading,
        tool_frame=c.robot.tool_frame,
        start=plan.start.position,
        desired_rotation=plan.start.rotation,
        tool_point=tool_point,
        contour_step=plan.belief_step,  # after the part moved
        true_plant=plant,
        posture=plan.start.q,
        mesh_probe=plan.mesh_probe,
    )
    touch_gate = _wire_probe(builder, plan, plant, tool_point, loops, side)
    # The drives: the controller's torque to the plant and the force law.
    _connect_actuation(builder, c, plant, side, loops.actuation)
    # The cell drawn in Meshcat.
    if meshcat is not None:
        _add_meshcat(builder, meshcat, plan, plant, scene_graph, side.process)
    # The guards read the standard signals, the loggers those and more.
    logged = _logged_signals(builder, loops, probing, touch_gate)
    add_guards(builder, c, plant, plan.contour, logged, _probe_route(plan))
    _add_loggers(builder, c, logged, extra_logs)
    diagram = builder.Build()
    diagram.set_name(f"deburr_{c.name}")
    return diagram
