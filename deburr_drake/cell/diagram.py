"""The deburring cell as a named Drake Diagram: a robot (the 5-DOF arm of
Section IV, the 6-DOF arm6, any arm from a model file (deburr_drake.cell.robot),
or a Cartesian point-mass tool) whose cylindrical cutter chamfers
a tube's inner edge through hydroelastic contact, closed by the paper's
command generator, first-order hold, contact estimator and hybrid
controller, with the plant-side cutting process, joint friction and force
sensor.

Use: ``diagram = make_deburring_diagram(scenario=load_scenario("paper"))``,
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

from deburr_drake.cell.arm import solve_tool_pose
from deburr_drake.cell.edge import (
    believed_contour,
    believed_contour_step,
    edge_points,
    make_contour,
    start_position,
)
from deburr_drake.cell.faults import add_noise_scale, add_sensor_faults
from deburr_drake.cell.gains import resolve_design
from deburr_drake.cell.guards import add_effort_saturation, add_guards
from deburr_drake.cell.plant import add_cell_plant
from deburr_drake.cell.process import CuttingProcess
from deburr_drake.cell.reach import check_part_in_reach
from deburr_drake.cell.robot import ik_seed, make_robot_model
from deburr_drake.cell.sensor import ForceSensor
from deburr_drake.config import ConfigError, RobotConfig, Scenario
from deburr_drake.control.kinematics import ToolPoint
from deburr_drake.control.loop import add_deburring_controller

__all__ = [
    "make_deburring_diagram",
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


class _Start(NamedTuple):
    """Where the pass starts."""

    position: np.ndarray  # m, world: the tool tip
    q: np.ndarray  # the plant's positions there
    rotation: np.ndarray  # the tool's orientation there, held on the pass


class _PlantSide(NamedTuple):
    """The systems between the plant and the controller side."""

    process: CuttingProcess
    force_law: Diagram
    sensor: ForceSensor
    reading: OutputPort  # what the controller side reads (after faults)


def _initial_positions(
    plant, scenario: Scenario, x0, tool_axis=None
) -> np.ndarray:
    robot = scenario.robot
    if robot.model == "cartesian_tool":
        # World-aligned prismatic joints, tip at the origin for q = 0.
        return np.asarray(x0, float)
    frame = plant.GetFrameByName(robot.tool_frame)
    return solve_tool_pose(
        plant,
        x0,
        instance=frame.model_instance(),
        q_guess=ik_seed(robot, x0),
        tool_frame=robot.tool_frame,
        tool_axis=tool_axis,
    )


def _start(scenario: Scenario, plant, model, belief) -> _Start:
    """The tool at the believed contour's start, in contact (with touch
    probing, the probe's standoff off the part before it), the arm posed
    there by inverse kinematics."""
    c = scenario
    x0 = start_position(c, belief)
    if c.localisation.probe.enabled:
        x0 = x0 - (
            c.simulation.initial_depth + c.localisation.probe.standoff
        ) * belief.n1(x0)
    # The tool vertical; along a 3-D edge, along its axis there.
    axis = (
        belief.tool_axis_at(belief.arc_position(x0))
        if belief.varying_frame
        else None
    )
    q0 = _initial_positions(plant, c, x0, axis)
    model_context = model.CreateDefaultContext()
    model.SetPositions(model_context, q0)
    # The tool's axis; on a 6-DOF arm also its rotation about it.
    rotation = (
        model.GetFrameByName(c.robot.tool_frame)
        .CalcPoseInWorld(model_context)
        .rotation()
        .matrix()
    )
    return _Start(x0, q0, rotation)


def _add_plant_side(
    builder, scenario: Scenario, plant, contour, tool_point
) -> _PlantSide:
    """The cutting process on the real edge, its force law on the plant,
    and the force sensor with its noise and faults, wired to the plant."""
    c = scenario
    process = builder.AddNamedSystem(
        "cutting_process",
        CuttingProcess(
            plant,
            c.robot.tool_frame,
            contour,
            c.process,
            cut_height=c.tool.engagement,
            cutter_radius=c.tool.cutter_radius,
            tool_point=tool_point,
            spindle_input=c.localisation.probe.enabled,
        ),
    )
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
    force_law = builder.AddSystem(process.force_law())
    state = plant.get_state_output_port()
    connect = builder.Connect
    for system in (process, sensor, force_law):
        connect(state, system.GetInputPort("plant_state"))
    connect(
        process.GetOutputPort("force_law_terms"),
        force_law.GetInputPort("force_law_terms"),
    )
    connect(
        force_law.GetOutputPort("applied_force"),
        sensor.GetInputPort("applied_force"),
    )
    connect(
        force_law.GetOutputPort("generalized_force"),
        plant.get_applied_generalized_force_input_port(),
    )
    connect(
        plant.get_reaction_forces_output_port(),
        sensor.GetInputPort("reaction_forces"),
    )
    connect(
        add_noise_scale(builder, c.faults, noise.get_output_port()),
        sensor.GetInputPort("noise"),
    )
    # What the observer and the controller read (faults: bias, dropouts).
    reading = add_sensor_faults(
        builder,
        c.faults,
        sensor.GetOutputPort("measured_force"),
        sample_period=c.sensor.sample_period,
    )
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


def _logged_signals(builder, loops, probing: bool) -> dict:
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


def _add_meshcat(builder, meshcat, scenario, plant, scene_graph, process):
    """The cell, its contact forces and the edge drawn in ``meshcat``."""
    from deburr_drake.cell.meshcat import add_meshcat

    add_meshcat(
        builder,
        meshcat,
        plant=plant,
        scene_graph=scene_graph,
        process=process,
        edge_points=edge_points(scenario, process.bins.centers),
        edge_axes=_edge_axes(scenario, process.bins.centers),
    )


def _edge_axes(scenario, arc):
    """The tool axis at arc positions ``arc`` along a turning (3-D) edge,
    else None (vertical)."""
    contour = make_contour(scenario)
    if not contour.varying_frame:
        return None
    return np.array([contour.tool_axis_at(s) for s in arc])


def make_deburring_diagram(
    *,
    scenario: Scenario,
    meshcat=None,
    extra_logs: Optional[Mapping[str, Tuple[str, str]]] = None,
) -> Diagram:
    """The closed loop as a named Diagram ``deburr_<scenario name>``.

    Systems: :data:`SYSTEM_NAMES`, ``guards`` (deburr_drake.cell.guards,
    unless ``guards.enabled`` is false), ``drive_saturation`` (the drives
    clamp the commanded torque at the effort limits, unless
    ``guards.saturate_effort`` is false), ``sensor_faults`` and
    ``sensor_noise_scale`` with faults (deburr_drake.cell.faults), and a
    ``log_<name>`` VectorLogSink per entry of :data:`LOGGED`. The tool
    starts at the contour start, in contact. With a ``meshcat``, the cell
    is drawn there too (deburr_drake.cell.meshcat).

    Built from ``scenario`` with its designed values resolved
    (:func:`deburr_drake.cell.gains.resolve_design`: the gains where
    ``controller.design`` resolves to auto, the fuzzy slope bound where it
    is 0); ``scenario`` itself is left as it is. To report the values
    built, resolve it first: ``scenario = resolve_design(scenario)``.

    ``extra_logs`` ({name: (system name, output port name)}) logs more
    signals, e.g. ``{"feed": ("command_generator", "feed")}``: loggers
    ``log_<name>`` that :func:`deburr_drake.runs.simulation.simulate`
    collects as ``log[name]`` (``t`` and ``value``)."""
    scenario.validate()
    # The designed values resolved on a copy; the caller's scenario stays.
    c = resolve_design(scenario)
    check_part_in_reach(c)
    probing = c.localisation.probe.enabled
    builder = DiagramBuilder()
    # The plant: the robot with its cutter and friction, the real part.
    plant, scene_graph = add_cell_plant(builder, c)
    # The real edge (the plant's truth), the one the controller believes in.
    contour, belief = make_contour(c), believed_contour(c)
    # The controller's model of the robot, its pose at the start.
    model = make_robot_model(c.robot)
    start = _start(c, plant, model, belief)
    plant.SetDefaultPositions(start.q)
    # One kinematics memo for the process (truth), the sensor, the observer
    # and the controller: they read the same joint state.
    tool_point = ToolPoint(model, model.GetFrameByName(c.robot.tool_frame))
    # The plant side: the cutting process, its force law, the force sensor
    # and its faults.
    side = _add_plant_side(builder, c, plant, contour, tool_point)
    # The paper's loops around the plant (deburr_drake.control.loop).
    loops = add_deburring_controller(
        builder,
        scenario=c,
        plant=model,
        contour=belief,
        plant_state=plant.get_state_output_port(),
        measured_force=side.reading,
        tool_frame=c.robot.tool_frame,
        start=start.position,
        desired_rotation=start.rotation,
        tool_point=tool_point,
        contour_step=believed_contour_step(c),  # after the part moved
        true_plant=plant,
        posture=start.q,
    )
    # Touch probing: the loops turn the spindle off and on.
    if probing:
        builder.Connect(loops.spindle, side.process.GetInputPort("spindle"))
    # The drives: the controller's torque to the plant and the force law.
    _connect_actuation(builder, c, plant, side, loops.actuation)
    # The cell drawn in Meshcat.
    if meshcat is not None:
        _add_meshcat(builder, meshcat, c, plant, scene_graph, side.process)
    # The guards read the standard signals, the loggers those and more.
    logged = _logged_signals(builder, loops, probing)
    add_guards(builder, c, plant, contour, logged)
    _add_loggers(builder, c, logged, extra_logs)
    diagram = builder.Build()
    diagram.set_name(f"deburr_{c.name}")
    return diagram
