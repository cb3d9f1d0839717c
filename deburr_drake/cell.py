"""The deburring cell as a named Drake Diagram: a robot (the 5-DOF arm of
Section IV, the 6-DOF arm6, any arm from a model file (deburr_drake.robot),
or a Cartesian point-mass tool) whose cylindrical cutter chamfers
a tube's inner edge through hydroelastic contact, closed by the paper's
command generator, first-order hold, contact estimator and hybrid
controller, with the plant-side cutting process, joint friction and force
sensor.

Use: ``diagram = make_deburring_diagram(scenario=load_scenario("paper"))``,
then :func:`deburr_drake.simulation.simulate`. Every system is named
(:data:`SYSTEM_NAMES`), every logged output is in :data:`LOGGED` (logger
``log_<name>``); pass ``meshcat=`` to draw the cell (deburr_drake.replay).
The controller side alone, around a plant of your own, is
:func:`deburr_drake.loop.add_deburring_controller`."""

from __future__ import annotations

import copy

import numpy as np
from pydrake.common import RandomDistribution
from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlantConfig
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import LogVectorOutput, RandomSource

from deburr_drake.arm import check_reach, solve_tool_pose
from deburr_drake.config import ConfigError, RobotConfig, Scenario
from deburr_drake.faults import add_noise_scale, add_sensor_faults
from deburr_drake.friction import add_joint_friction
from deburr_drake.geometry import CircularContour, Contour, StraightContour
from deburr_drake.guards import add_effort_saturation, add_guards
from deburr_drake.kinematics import ToolPoint
from deburr_drake.loop import add_deburring_controller
from deburr_drake.part import (contact_force_on_body,
                               register_compliant_ring,
                               register_compliant_wall, register_tube_visual)
from deburr_drake.process import CuttingProcess
from deburr_drake.robot import (add_robot, check_robot, ik_seed,
                                make_robot_model)
from deburr_drake.sensor import ForceSensor

__all__ = ["make_deburring_diagram", "MakeDeburringDiagram", "make_contour",
           "edge_points", "contact_normal_force",
           "start_position", "check_part_in_reach", "believed_scenario",
           "believed_contour", "believed_contour_step", "TOOL_FRAME",
           "SENSOR_JOINT", "LOGGED",
           "SYSTEM_NAMES"]

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

#: Every system the builder adds (besides the loggers ``log_<name>``).
SYSTEM_NAMES = ("plant", "scene_graph", "cutting_process", "cutting_force",
                "force_sensor", "sensor_noise", "chamfer_observer",
                "command_generator", "first_order_hold", "contact_estimator",
                "controller")


def _straight_frame(scenario: Scenario):
    """(edge midpoint on the wall face at the top, travel direction,
    material normal) of a straight edge."""
    edge = scenario.edge
    tube = scenario.tube
    mid = np.array(tube.position, float)
    mid[2] += tube.height
    tangent = np.array([np.cos(edge.heading), np.sin(edge.heading), 0.0])
    normal = np.array([tangent[1], -tangent[0], 0.0])  # material on the right
    return mid, tangent, normal


def make_contour(scenario: Scenario) -> Contour:
    """The zero-depth path of the tool tip: the part's edge offset by the
    cutter radius, at the height where the cutter tip runs."""
    tube, tool, edge = scenario.tube, scenario.tool, scenario.edge
    if edge.kind == "straight":
        mid, tangent, normal = _straight_frame(scenario)
        start = (mid - tool.cutter_radius * normal
                 - 0.5 * edge.length * tangent)
        start[2] -= tool.engagement
        return StraightContour(start, tangent, normal, length=edge.length)
    center = np.array(tube.position, float)
    center[2] += tube.height - tool.engagement
    return CircularContour(center, tube.inner_radius - tool.cutter_radius,
                           start_angle=edge.start_angle,
                           direction=edge.direction)


def believed_scenario(scenario: Scenario) -> Scenario:
    """The scenario with the part the controller believes in
    (``part_error`` applied to ``tube`` and ``edge``); the scenario itself
    when there is no error."""
    e = scenario.part_error
    if not any(e.offset) and e.yaw == 0.0 and e.radius == 0.0:
        return scenario
    believed = copy.deepcopy(scenario)
    believed.tube.position = [p + d for p, d in zip(scenario.tube.position,
                                                    e.offset)]
    believed.tube.inner_radius += e.radius
    if scenario.edge.kind == "straight":
        believed.edge.heading += e.yaw
    else:
        believed.edge.start_angle += e.yaw
    return believed


def believed_contour(scenario: Scenario) -> Contour:
    """The zero-depth path on the part the controller believes in."""
    return make_contour(believed_scenario(scenario))


def believed_contour_step(scenario: Scenario):
    """(time (s), believed contour from then on) of ``faults.part_step``:
    the believed part moved by minus the real part's step; None without a
    step."""
    step = scenario.faults.part_step
    if not step.active():
        return None
    after = copy.deepcopy(scenario)
    after.part_error.offset = [e - d for e, d in zip(
        scenario.part_error.offset, step.offset)]
    return step.time, believed_contour(after)


def start_position(scenario: Scenario, contour=None) -> np.ndarray:
    """Tool tip at the contour start, ``initial_depth`` into the material."""
    contour = contour or make_contour(scenario)
    p = contour.point_at(0.0)
    return p + scenario.simulation.initial_depth * contour.n1(p)


def _add_plant(builder: DiagramBuilder, scenario: Scenario):
    sim = scenario.simulation
    config = MultibodyPlantConfig(
        time_step=sim.plant_time_step,
        contact_model="hydroelastic_with_fallback")
    if sim.plant_time_step > 0:
        config.discrete_contact_approximation = sim.contact_approximation
    plant, scene_graph = AddMultibodyPlant(config, builder)
    add_robot(plant, scenario.robot, cutter=dict(
        cutter_radius=scenario.tool.cutter_radius,
        cutter_length=scenario.tool.cutter_length,
        resolution_hint=scenario.tool.resolution_hint))
    add_joint_friction(plant, scenario.robot)
    if scenario.edge.kind == "straight":
        mid, tangent, normal = _straight_frame(scenario)
        register_compliant_wall(
            plant, mid=mid, tangent=tangent, normal=normal,
            length=scenario.edge.length, thickness=scenario.tube.wall_thickness,
            height=scenario.tube.height,
            layer_height=scenario.tube.compliant_layer_height,
            hydroelastic_modulus=scenario.tube.hydroelastic_modulus,
            hunt_crossley_dissipation=scenario.tube.hunt_crossley_dissipation,
            # The wall is the edge: the process cuts only where it is
            # (process.material_overlap), and off its ends there is no
            # contact either.
            margin=0.0)
        plant.Finalize()
        return plant, scene_graph
    tube = scenario.tube
    z_top = tube.position[2] + tube.height
    register_compliant_ring(
        plant,
        inner_radius=tube.inner_radius,
        outer_radius=tube.inner_radius + tube.wall_thickness,
        z_bottom=z_top - tube.compliant_layer_height, z_top=z_top,
        center_xy=tube.position[:2],
        hydroelastic_modulus=tube.hydroelastic_modulus,
        hunt_crossley_dissipation=tube.hunt_crossley_dissipation,
        n_theta=tube.mesh_segments, n_radial=tube.mesh_radial_cells,
        n_z=tube.mesh_height_cells)
    register_tube_visual(
        plant, inner_radius=tube.inner_radius,
        outer_radius=tube.inner_radius + tube.wall_thickness,
        z_bottom=tube.position[2], z_top=z_top - tube.compliant_layer_height,
        center_xy=tube.position[:2], n_theta=tube.mesh_segments)
    plant.Finalize()
    return plant, scene_graph


def check_part_in_reach(scenario: Scenario, contour=None, *, samples=24):
    """Raises ConfigError if the robot cannot serve the cell
    (deburr_drake.robot.check_robot: the model file, its frames, its
    joints), or naming the first point of the tool's path (the start, then
    ``samples`` points along the edge) the arm cannot reach with the tool
    vertical, and how far out of reach it is."""
    robot = scenario.robot
    model = check_robot(robot)
    if robot.model == "cartesian_tool":
        return  # the Cartesian tool reaches everywhere
    contour = contour or believed_contour(scenario)
    arcs = np.linspace(0.0, contour.length, samples,
                       endpoint=not contour.closed)
    points = [start_position(scenario, contour)] + [
        contour.point_at(s) for s in arcs]
    instance = model.GetFrameByName(robot.tool_frame).model_instance()
    miss = check_reach(model, points, instance=instance,
                       q_guess=lambda p: ik_seed(robot, p),
                       tool_frame=robot.tool_frame)
    if miss is not None:
        k, p, distance = miss
        where = "the start point" if k == 0 else \
            f"the edge point at arc {arcs[k - 1] * 1e3:.1f} mm"
        raise ConfigError(
            f"tube.position = {list(scenario.tube.position)} is out of the "
            f"arm's reach: {where}, tool tip at {np.round(p, 4).tolist()} m, "
            f"is {distance * 1e3:.1f} mm beyond the nearest reachable tool "
            "position (tool vertical, joint limits): allowed a part whose "
            f"edge the arm reaches (arm5: [0.40, 0.0, 0.0]; {robot.model!r}"
            ": see its robot.ik_seed and the model's joint limits)")


def _initial_positions(plant, scenario: Scenario, x0) -> np.ndarray:
    robot = scenario.robot
    if robot.model == "cartesian_tool":
        # World-aligned prismatic joints, tip at the origin for q = 0.
        return np.asarray(x0, float)
    frame = plant.GetFrameByName(robot.tool_frame)
    return solve_tool_pose(plant, x0, instance=frame.model_instance(),
                           q_guess=ik_seed(robot, x0),
                           tool_frame=robot.tool_frame)


def edge_points(scenario: Scenario, arc) -> np.ndarray:
    """Points (m, world) on the tube's inner top edge at contour arc
    positions ``arc`` (m): where the chamfer is cut, for drawing."""
    contour = make_contour(scenario)
    tube, tool = scenario.tube, scenario.tool
    top = tube.position[2] + tube.height
    points = []
    for s in np.asarray(arc, float):
        p = contour.point_at(s)
        q = p + tool.cutter_radius * contour.n1(p)
        q[2] = top
        points.append(q)
    return np.array(points)


def contact_normal_force(scenario: Scenario, depths, *,
                         arc_fraction: float = 0.5) -> np.ndarray:
    """The hydroelastic normal force (N) on the scenario's cutter at each
    depth (m) into its part, the tool vertical at ``arc_fraction`` of the
    edge, at rest: the contact part of (4), measured on the same geometry
    the cell simulates (a Cartesian tool holds the cutter)."""
    probe = copy.deepcopy(scenario)
    probe.robot = RobotConfig(model="cartesian_tool")
    probe.simulation.plant_time_step = 0.0
    builder = DiagramBuilder()
    plant, _ = _add_plant(builder, probe)
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    pc = plant.GetMyMutableContextFromRoot(context)
    tool = plant.GetBodyByName("tool")
    (cutter,) = plant.GetCollisionGeometriesForBody(tool)
    contour = make_contour(scenario)
    p = contour.point_at(arc_fraction * contour.length)
    n1 = contour.n1(p)
    port = plant.get_contact_results_output_port()
    forces = []
    for depth in np.atleast_1d(np.asarray(depths, float)):
        plant.SetPositions(pc, p + depth * n1)
        f = contact_force_on_body(port.Eval(pc), cutter, tool.index())
        forces.append(-float(f @ n1))
    return np.array(forces)


def make_deburring_diagram(*, scenario: Scenario, meshcat=None,
                           extra_logs=None) -> Diagram:
    """The closed loop as a named Diagram.

    Systems (see :data:`SYSTEM_NAMES`): ``plant``, ``scene_graph``,
    ``cutting_process`` and its force law ``cutting_force``,
    ``force_sensor``, ``sensor_noise``, ``chamfer_observer``,
    ``command_generator``, ``first_order_hold``, ``contact_estimator``,
    ``controller``, ``guards`` (deburr_drake.guards, unless
    ``guards.enabled`` is false) and ``drive_saturation`` (the drives clamp
    the commanded torque at the effort limits, unless
    ``guards.saturate_effort`` is false),
    and one ``log_<name>`` VectorLogSink per entry of :data:`LOGGED`. The
    plant's default positions put the tool tip at the contour start (by
    inverse kinematics for the arm), in contact. With a ``meshcat``, the
    cell is drawn there too (see :mod:`deburr_drake.replay`).

    ``extra_logs`` ({name: (system name, output port name)}) logs more
    signals at ``simulation.log_period``, e.g. ``{"feed": ("command_generator",
    "feed"), "state": ("plant", "state")}``: loggers ``log_<name>`` that
    :func:`deburr_drake.simulation.simulate` collects as ``log[name]``
    (``t`` and ``value``)."""
    scenario.validate()
    c = scenario
    check_part_in_reach(c)
    builder = DiagramBuilder()
    plant, _ = _add_plant(builder, c)
    contour = make_contour(c)  # the real part: the plant's truth
    belief = believed_contour(c)  # the part the controller believes in
    belief_step = believed_contour_step(c)  # ... after the part moved
    x0 = start_position(c, belief)
    q0 = _initial_positions(plant, c, x0)
    plant.SetDefaultPositions(q0)

    model = make_robot_model(c.robot)
    tool_frame = c.robot.tool_frame
    model_context = model.CreateDefaultContext()
    model.SetPositions(model_context, q0)
    # The tool's orientation at the start is held (the tool axis vertical;
    # on a 6-DOF arm also its rotation about that axis).
    desired_rotation = model.GetFrameByName(tool_frame).CalcPoseInWorld(
        model_context).rotation().matrix()

    # The process (truth), the sensor, the observer (measurement) and the
    # controller read the same joint state through the same kinematics: one
    # memo serves all.
    tool_point = ToolPoint(model, model.GetFrameByName(tool_frame))
    process = builder.AddNamedSystem("cutting_process", CuttingProcess(
        plant, tool_frame, contour, c.process, cut_height=c.tool.engagement,
        cutter_radius=c.tool.cutter_radius, tool_point=tool_point))
    sensor = builder.AddNamedSystem("force_sensor", ForceSensor(
        plant, c.robot.sensor_joint, c.sensor, tool_point=tool_point))
    noise = builder.AddNamedSystem("sensor_noise", RandomSource(
        RandomDistribution.kGaussian, 3, c.sensor.sample_period))
    state = plant.get_state_output_port()
    for system in (process, sensor):
        builder.Connect(state, system.GetInputPort("plant_state"))
    force_law = builder.AddSystem(process.force_law())
    builder.Connect(process.GetOutputPort("force_law_terms"),
                    force_law.GetInputPort("force_law_terms"))
    builder.Connect(force_law.GetOutputPort("tool_force"),
                    sensor.GetInputPort("applied_force"))
    builder.Connect(state, force_law.GetInputPort("plant_state"))
    builder.Connect(force_law.GetOutputPort("generalized_force"),
                    plant.get_applied_generalized_force_input_port())
    builder.Connect(plant.get_reaction_forces_output_port(),
                    sensor.GetInputPort("reaction_forces"))
    builder.Connect(
        add_noise_scale(builder, c.faults, noise.get_output_port()),
        sensor.GetInputPort("noise"))
    # What the observer and the controller read (faults: bias, dropouts).
    force = add_sensor_faults(builder, c.faults,
                              sensor.GetOutputPort("tool_force"),
                              sample_period=c.sensor.sample_period)
    # The paper's loops around the plant (deburr_drake.loop).
    loops = add_deburring_controller(
        builder, scenario=c, plant=model, contour=belief,
        plant_state=state, tool_force=force, tool_frame=tool_frame,
        start=x0, desired_rotation=desired_rotation, tool_point=tool_point,
        contour_step=belief_step, true_plant=plant, posture=q0)
    builder.Connect(
        add_effort_saturation(builder, c, plant, loops.actuation),
        plant.get_actuation_input_port())

    if meshcat is not None:
        from deburr_drake.replay import add_meshcat
        scene_graph = builder.GetSubsystemByName("scene_graph")
        add_meshcat(builder, meshcat, plant=plant, scene_graph=scene_graph,
                    process=process,
                    edge_points=edge_points(c, process.bins.centers))

    logged = {name: builder.GetSubsystemByName(system).GetOutputPort(port)
              for name, (system, port) in LOGGED.items()}
    add_guards(builder, c, plant, contour, logged)
    for name, (system, port) in (extra_logs or {}).items():
        if name in logged:
            raise ValueError(f"extra_logs: {name!r} is logged already: "
                             f"allowed a name not in {sorted(logged)}")
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
