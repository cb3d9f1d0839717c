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

import numpy as np
from pydrake.common import RandomDistribution
from pydrake.systems.framework import Diagram, DiagramBuilder
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
from deburr_drake.cell.gains import resolve_gains, resolve_slope_bound
from deburr_drake.cell.guards import add_effort_saturation, add_guards
from deburr_drake.cell.plant import add_cell_plant
from deburr_drake.cell.process import CuttingProcess
from deburr_drake.cell.reach import check_part_in_reach
from deburr_drake.cell.robot import ik_seed, make_robot_model
from deburr_drake.cell.sensor import ForceSensor
from deburr_drake.config import RobotConfig, Scenario
from deburr_drake.control.kinematics import ToolPoint
from deburr_drake.control.loop import add_deburring_controller

__all__ = [
    "make_deburring_diagram",
    "MakeDeburringDiagram",
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
    "tool_force": ("force_sensor", "tool_force"),
}

#: Logged when localisation adds the system (issue 21).
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


def _initial_positions(plant, scenario: Scenario, x0) -> np.ndarray:
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
    )


def make_deburring_diagram(
    *, scenario: Scenario, meshcat=None, extra_logs=None
) -> Diagram:
    """The closed loop as a named Diagram.

    Systems (see :data:`SYSTEM_NAMES`): ``plant``, ``scene_graph``,
    ``cutting_process`` and its force law ``cutting_force``,
    ``force_sensor``, ``sensor_noise``, ``chamfer_observer``,
    ``command_generator``, ``first_order_hold``, ``contact_estimator``,
    ``controller``, ``guards`` (deburr_drake.cell.guards, unless
    ``guards.enabled`` is false) and ``drive_saturation`` (the drives clamp
    the commanded torque at the effort limits, unless
    ``guards.saturate_effort`` is false),
    and one ``log_<name>`` VectorLogSink per entry of :data:`LOGGED`. The
    plant's default positions put the tool tip at the contour start (by
    inverse kinematics for the arm), in contact. With a ``meshcat``, the
    cell is drawn there too (see :mod:`deburr_drake.cell.meshcat`).

    With ``controller.design`` auto (the default for a robot from a file)
    the gains are designed from the model first and written into
    ``scenario`` (deburr_drake.cell.gains.resolve_gains; the command line
    also proves them, deburr_drake.analysis.preflight).

    ``extra_logs`` ({name: (system name, output port name)}) logs more
    signals at ``simulation.log_period``, e.g. ``{"feed": ("command_generator",
    "feed"), "state": ("plant", "state")}``: loggers ``log_<name>`` that
    :func:`deburr_drake.runs.simulation.simulate` collects as ``log[name]``
    (``t`` and ``value``)."""
    scenario.validate()
    c = scenario
    check_part_in_reach(c)
    # controller.design auto: the gains from the model, written into the
    # scenario (deburr_drake.cell.gains).
    resolve_gains(c)
    # fuzzy.max_slope 0: the learned surface's slope bound from the model.
    resolve_slope_bound(c)
    builder = DiagramBuilder()
    plant, _ = add_cell_plant(builder, c)
    contour = make_contour(c)  # the real part: the plant's truth
    belief = believed_contour(c)  # the part the controller believes in
    belief_step = believed_contour_step(c)  # ... after the part moved
    probing = c.localisation.probe.enabled
    x0 = start_position(c, belief)
    if probing:  # off the part, the probe's standoff before the start
        x0 = x0 - (
            c.simulation.initial_depth + c.localisation.probe.standoff
        ) * belief.n1(x0)
    q0 = _initial_positions(plant, c, x0)
    plant.SetDefaultPositions(q0)

    model = make_robot_model(c.robot)
    tool_frame = c.robot.tool_frame
    model_context = model.CreateDefaultContext()
    model.SetPositions(model_context, q0)
    # The tool's orientation at the start is held (the tool axis vertical;
    # on a 6-DOF arm also its rotation about that axis).
    desired_rotation = (
        model.GetFrameByName(tool_frame)
        .CalcPoseInWorld(model_context)
        .rotation()
        .matrix()
    )

    # The process (truth), the sensor, the observer (measurement) and the
    # controller read the same joint state through the same kinematics: one
    # memo serves all.
    tool_point = ToolPoint(model, model.GetFrameByName(tool_frame))
    process = builder.AddNamedSystem(
        "cutting_process",
        CuttingProcess(
            plant,
            tool_frame,
            contour,
            c.process,
            cut_height=c.tool.engagement,
            cutter_radius=c.tool.cutter_radius,
            tool_point=tool_point,
            spindle_input=probing,
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
    state = plant.get_state_output_port()
    for system in (process, sensor):
        builder.Connect(state, system.GetInputPort("plant_state"))
    force_law = builder.AddSystem(process.force_law())
    builder.Connect(
        process.GetOutputPort("force_law_terms"),
        force_law.GetInputPort("force_law_terms"),
    )
    builder.Connect(
        force_law.GetOutputPort("tool_force"),
        sensor.GetInputPort("applied_force"),
    )
    builder.Connect(state, force_law.GetInputPort("plant_state"))
    builder.Connect(
        force_law.GetOutputPort("generalized_force"),
        plant.get_applied_generalized_force_input_port(),
    )
    builder.Connect(
        plant.get_reaction_forces_output_port(),
        sensor.GetInputPort("reaction_forces"),
    )
    builder.Connect(
        add_noise_scale(builder, c.faults, noise.get_output_port()),
        sensor.GetInputPort("noise"),
    )
    # What the observer and the controller read (faults: bias, dropouts).
    force = add_sensor_faults(
        builder,
        c.faults,
        sensor.GetOutputPort("tool_force"),
        sample_period=c.sensor.sample_period,
    )
    # The paper's loops around the plant (deburr_drake.control.loop).
    loops = add_deburring_controller(
        builder,
        scenario=c,
        plant=model,
        contour=belief,
        plant_state=state,
        tool_force=force,
        tool_frame=tool_frame,
        start=x0,
        desired_rotation=desired_rotation,
        tool_point=tool_point,
        contour_step=belief_step,
        true_plant=plant,
        posture=q0,
    )
    if probing:
        builder.Connect(loops.spindle, process.GetInputPort("spindle"))
    actuation = add_effort_saturation(builder, c, plant, loops.actuation)
    builder.Connect(actuation, plant.get_actuation_input_port())
    # The law's held mean (process.sample_mean) takes the sample's torque.
    builder.Connect(actuation, force_law.GetInputPort("actuation"))
    if c.process.sample_mean:
        for port, source in (
            (
                "generalized_acceleration",
                plant.get_generalized_acceleration_output_port(),
            ),
            (
                "applied_generalized_force",
                force_law.GetOutputPort("generalized_force"),
            ),
            ("actuation", actuation),
        ):
            builder.Connect(source, process.GetInputPort(port))

    if meshcat is not None:
        from deburr_drake.cell.meshcat import add_meshcat

        scene_graph = builder.GetSubsystemByName("scene_graph")
        add_meshcat(
            builder,
            meshcat,
            plant=plant,
            scene_graph=scene_graph,
            process=process,
            edge_points=edge_points(c, process.bins.centers),
        )

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
    add_guards(builder, c, plant, contour, logged)
    for name, (system, port) in (extra_logs or {}).items():
        if name in logged:
            raise ValueError(
                f"extra_logs: {name!r} is logged already: "
                f"allowed a name not in {sorted(logged)}"
            )
        logged_port = builder.GetSubsystemByName(system).GetOutputPort(port)
        # After add_guards: the guards read the standard signals only.
        logged = {**logged, name: logged_port}
    for name, port in logged.items():
        logger = LogVectorOutput(port, builder, c.simulation.log_period)
        logger.set_name(f"log_{name}")
    diagram = builder.Build()
    diagram.set_name(f"deburr_{c.name}")
    return diagram


#: The builder under the name the design uses.
MakeDeburringDiagram = make_deburring_diagram
