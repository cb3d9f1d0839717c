"""The point-mass testbed: a Cartesian tool (three prismatic joints, J = I,
gravity on) whose cylindrical cutter presses on the inner edge of a tube
through hydroelastic contact, closed by the paper's four control systems."""

from __future__ import annotations

import numpy as np
from pydrake.multibody.plant import AddMultibodyPlant, MultibodyPlantConfig
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.common import RandomDistribution
from pydrake.systems.primitives import (LogVectorOutput, RandomSource,
                                        ZeroOrderHold)

from deburr_drake.command import CommandGenerator, FirstOrderHold
from deburr_drake.config import Scenario
from deburr_drake.controller import HybridController
from deburr_drake.estimator import ContactParameterEstimator
from deburr_drake.geometry import CircularContour
from deburr_drake.models import POINT_MASS_URL, make_kinematic_model
from deburr_drake.observer import ChamferObserver
from deburr_drake.part import add_cartesian_tool, register_compliant_ring
from deburr_drake.process import CuttingProcess
from deburr_drake.sensor import ForceSensor

__all__ = ["make_point_mass_diagram", "make_contour", "start_position",
           "TOOL_FRAME", "SENSOR_JOINT", "LOGGED"]

TOOL_FRAME = "tool_tip"
SENSOR_JOINT = "ft_sensor"

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


def make_contour(scenario: Scenario) -> CircularContour:
    """The zero-depth path of the tool tip: the tube's inner edge offset by
    the cutter radius, at the height where the cutter tip runs."""
    tube, tool = scenario.tube, scenario.tool
    center = np.array(tube.position, float)
    center[2] += tube.height - tool.engagement
    return CircularContour(center, tube.inner_radius - tool.cutter_radius,
                           start_angle=scenario.edge.start_angle,
                           direction=scenario.edge.direction)


def _add_plant(builder: DiagramBuilder, scenario: Scenario):
    sim = scenario.simulation
    config = MultibodyPlantConfig(
        time_step=sim.plant_time_step,
        contact_model="hydroelastic_with_fallback")
    if sim.plant_time_step > 0:
        config.discrete_contact_approximation = sim.contact_approximation
    plant, scene_graph = AddMultibodyPlant(config, builder)
    add_cartesian_tool(plant, cutter_radius=scenario.tool.cutter_radius,
                       cutter_length=scenario.tool.cutter_length)
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
    plant.Finalize()
    return plant, scene_graph


def start_position(scenario: Scenario, contour=None) -> np.ndarray:
    """Tool tip at the contour start, ``initial_depth`` into the material."""
    contour = contour or make_contour(scenario)
    p = contour.point_at(0.0)
    return p + scenario.simulation.initial_depth * contour.n1(p)


def make_point_mass_diagram(*, scenario: Scenario) -> Diagram:
    """The closed-loop point-mass testbed as a named Diagram.

    Systems: ``plant``, ``scene_graph``, ``cutting_process``,
    ``force_sensor``, ``chamfer_observer``, ``command_generator``,
    ``first_order_hold``, ``contact_estimator``, ``controller``, and one
    ``log_<name>`` VectorLogSink per entry of :data:`LOGGED`. The plant's
    default positions put the tool tip at the contour start."""
    scenario.validate()
    builder = DiagramBuilder()
    plant, _ = _add_plant(builder, scenario)
    contour = make_contour(scenario)
    x0 = start_position(scenario, contour)
    # The Cartesian tool's joints are world-aligned with the tip at the
    # origin for q = 0, so q = tip position.
    plant.SetDefaultPositions(x0)

    model = make_kinematic_model(POINT_MASS_URL)
    c = scenario
    process = builder.AddNamedSystem("cutting_process", CuttingProcess(
        plant, TOOL_FRAME, contour, c.process, cut_height=c.tool.engagement))
    sensor = builder.AddNamedSystem("force_sensor", ForceSensor(
        plant, SENSOR_JOINT, c.sensor))
    noise = builder.AddNamedSystem("sensor_noise", RandomSource(
        RandomDistribution.kGaussian, 3, c.sensor.sample_period))
    builder.Connect(noise.get_output_port(), sensor.GetInputPort("noise"))
    observer = builder.AddNamedSystem("chamfer_observer", ChamferObserver(
        model, TOOL_FRAME, contour,
        min_tangential_speed=c.command.min_tangential_speed))
    generator = builder.AddNamedSystem("command_generator", CommandGenerator(
        c.command, c.task, contour, x0))
    foh = builder.AddNamedSystem("first_order_hold", FirstOrderHold(
        c.command.period, contour.project(x0)))
    estimator = builder.AddNamedSystem(
        "contact_estimator", ContactParameterEstimator(c.estimator, c.task))
    controller = builder.AddNamedSystem("controller", HybridController(
        model, TOOL_FRAME, c.controller))

    state = plant.get_state_output_port()
    for system in (process, sensor, observer, controller):
        builder.Connect(state, system.GetInputPort("plant_state"))
    builder.Connect(plant.get_reaction_forces_output_port(),
                    sensor.GetInputPort("reaction_forces"))
    builder.Connect(process.GetOutputPort("spatial_forces"),
                    plant.get_applied_spatial_force_input_port())
    force = sensor.GetOutputPort("tool_force")
    builder.Connect(force, observer.GetInputPort("tool_force"))
    builder.Connect(force, controller.GetInputPort("tool_force"))
    chamfer = observer.GetOutputPort("chamfer_state")
    for system in (generator, estimator, controller):
        builder.Connect(chamfer, system.GetInputPort("chamfer_state"))
    builder.Connect(generator.GetOutputPort("command"),
                    foh.GetInputPort("sampled"))
    builder.Connect(foh.GetOutputPort("position"),
                    controller.GetInputPort("commanded_position"))
    builder.Connect(foh.GetOutputPort("velocity"),
                    controller.GetInputPort("commanded_velocity"))
    builder.Connect(estimator.GetOutputPort("desired_normal_force"),
                    controller.GetInputPort("desired_normal_force"))
    actuation = controller.GetOutputPort("actuation")
    if c.controller.control_period > 0:
        hold = builder.AddNamedSystem("actuation_hold", ZeroOrderHold(
            c.controller.control_period, plant.num_actuators()))
        builder.Connect(actuation, hold.get_input_port())
        actuation = hold.get_output_port()
    builder.Connect(actuation, plant.get_actuation_input_port())

    for name, (system, port) in LOGGED.items():
        logger = LogVectorOutput(
            builder.GetSubsystemByName(system).GetOutputPort(port), builder,
            c.simulation.log_period)
        logger.set_name(f"log_{name}")
    diagram = builder.Build()
    diagram.set_name(f"deburr_{c.name}")
    return diagram
