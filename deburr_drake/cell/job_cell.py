"""A whole part's job as one Diagram: the plan of the run (the job planned,
the first cut's cell plan, each cut's single-edge scenario, contour and
start) and the Diagram built once from it.

Use: ``plan = plan_job_cell(scenario)`` for a scenario with a ``job:``
section, then ``make_job_diagram(plan)`` and
:func:`deburr_drake.runs.job_run.run_job`. The Diagram is the single
pass's cell with, for a job:

- a compliant band on every edge cut (``part_edge_<k>``) and a cutting
  process per edge (``cutting_process_<k>``, its spindle on only while
  the tool is at that edge), their forces summed on the plant;
- one set of the paper's loops on a JobContour of every cut's path (the
  observer, the command generator and the controller follow the edge
  being cut), gated off the part as touch probing gates them;
- the JobSequencer (deburr_drake.control.sequencer): it holds the
  command generator, gates the force loop and freezes the adaptation off
  the part, and gives the planned joint path to a position loop
  (``position_loop``, inverse dynamics on the controller's model) whose
  actuation drives the arm on the moves (``actuation_switch``).

What is carried from edge to edge, and why: the estimator's c-hat (it is
the part's material, the same on every edge), the fuzzy weights theta
(the rules learn the loop, the arm's dynamics and friction and the
cutting, which the edges share), delta_d and the integral of the sliding
variable (a force fixed in the world: the model's gravity error); each is
held while the tool is off the part.

With ``localisation.probe`` the job probes once, before its first cut:
the touches planned on the whole part's faces (the first cut's cell
plan's ``mesh_probe``, deburr_drake.cell.touches.plan_mesh_probe: they
pin all six degrees of freedom), the part's pose registered from them,
and every cut on the registered part (the loops' contour moved by that
one pose); the sequencer moves every planned move's path with it
(deburr_drake.cell.job_probe). A job registers the pose alone: a hole's
size is one edge's, the registration moves every edge, so
``localisation.probe.fit_radius`` is resolved to false. ``part_error``
moves the plant's part (its bands, processes and the probe's surface);
``faults.part_step`` steps the part the loops believe in, as in a
single pass."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Optional, Tuple

import numpy as np
from pydrake.systems.controllers import InverseDynamicsController
from pydrake.systems.framework import Diagram, DiagramBuilder
from pydrake.systems.primitives import (
    Adder,
    Demultiplexer,
    LogVectorOutput,
    MatrixGain,
)

from deburr_drake.cell.counts import DIAGRAMS, count
from deburr_drake.cell.diagram import (
    LOCALISATION_LOGGED,
    LOGGED,
    add_cutting_process,
    add_force_law,
    add_force_sensor,
    add_touch_contact,
    sensor_reading,
)
from deburr_drake.cell.edge import believed_contour_step, make_contour
from deburr_drake.cell.guards import add_effort_saturation, add_guards
from deburr_drake.cell.job import JobPlan, plan_job
from deburr_drake.cell.job_probe import check_probe_route, path_mover
from deburr_drake.cell.moves import MoveSettings
from deburr_drake.cell.plan import CellPlan, plan_cell
from deburr_drake.cell.plant import add_cell_plant
from deburr_drake.config import ConfigError, Scenario
from deburr_drake.config.job import JobConfig
from deburr_drake.control.kinematics import ToolPoint
from deburr_drake.control.loop import add_deburring_controller
from deburr_drake.control.sequencer import (
    ActuationSwitch,
    CutPlan,
    JobProbe,
    JobSequencer,
    MovePlan,
)
from deburr_drake.math.job_contour import JobContour
from deburr_drake.math.registration import POSE_REGISTRATION_SIZE

__all__ = [
    "JobCellPlan",
    "plan_job_cell",
    "make_job_diagram",
    "edge_scenario",
    "JOB_LOGGED",
    "POSITION_LOOP_FREQUENCY",
]

#: rad/s, the position loop's natural frequency on the moves (critically
#: damped, on the controller's model: an arm's joint servo)
POSITION_LOOP_FREQUENCY = 20.0

#: The job's own loggers besides LOGGED's (``process`` is per edge,
#: ``process_<k>``; ``actuation`` the switch's).
JOB_LOGGED = ("job", "plant_state")


@dataclass(frozen=True)
class JobCellPlan:
    """A job resolved for a run: ``job`` (deburr_drake.cell.job.JobPlan),
    ``cell`` (the first cut's CellPlan: the gains designed at its start,
    the controller's model, the start), ``edges`` (each cut's single-edge
    scenario, resolved as ``cell.scenario``), ``contour`` (the JobContour
    of every cut's path), ``cuts`` (what the sequencer needs of each),
    ``workspace`` (m, world: points on every cut and move, and the
    probe's route), ``section`` (the scenario's ``job:``), ``real``
    (each cut's path on the real part, moved by ``part_error``: the
    plant's), ``contour_step`` (``faults.part_step``: (time, the
    JobContour the loops believe in from then on), else None) and
    ``probe_clearance`` (m, with touch probing: the arm's least clearance
    to the part at the probe's route, deburr_drake.cell.job_probe.
    check_probe_route; else None)."""

    job: JobPlan
    cell: CellPlan
    edges: Tuple[Scenario, ...]
    contour: JobContour
    cuts: Tuple[CutPlan, ...]
    workspace: np.ndarray
    section: JobConfig  # the scenario's job section
    real: Tuple[object, ...] = ()
    contour_step: Optional[tuple] = None
    probe_clearance: Optional[float] = None

    @property
    def scenario(self) -> Scenario:
        """The job's scenario as it runs (the first cut's, resolved)."""
        return self.cell.scenario


def edge_scenario(scenario: Scenario, edge, pose) -> Scenario:
    """The single-edge scenario of one of a job's cuts: ``scenario`` with
    its part at ``pose`` and ``edge`` (an EdgeConfig), and no job."""
    part = dataclasses.replace(scenario.part, pose=pose, edge=edge)
    return dataclasses.replace(scenario, part=part, job=JobConfig())


def _check(scenario: Scenario):
    if not scenario.job.file:
        raise ConfigError("job.file is empty: the scenario has no job")
    if scenario.localisation.online.enabled:
        raise ConfigError(
            "localisation.online.enabled = True is invalid with a job: "
            "allowed false (a job registers its part by touch probing, "
            "localisation.probe)"
        )


def _resolved(scenario: Scenario) -> Scenario:
    """``scenario`` as a job runs it: with touch probing, the pose alone
    registered (``localisation.probe.fit_radius`` false)."""
    probe = scenario.localisation.probe
    if not (probe.enabled and probe.fit_radius):
        return scenario
    localisation = dataclasses.replace(
        scenario.localisation,
        probe=dataclasses.replace(probe, fit_radius=False),
    )
    return dataclasses.replace(scenario, localisation=localisation)


def _rotation(model, frame_name, q):
    context = model.CreateDefaultContext()
    model.SetPositions(context, q)
    pose = model.GetFrameByName(frame_name).CalcPoseInWorld(context)
    return pose.rotation().matrix(), pose.translation()


def _move_plan(move, job: JobConfig, settings: MoveSettings) -> MovePlan:
    times = np.asarray(move.times, float)
    return MovePlan(
        times=times,
        path=np.asarray(move.path, float),
        retract_end=job.retract / settings.axial_speed,
        approach_start=times[-1] - job.approach / settings.axial_speed,
    )


def plan_job_cell(scenario: Scenario) -> JobCellPlan:
    """The plan of ``scenario``'s job (see the module docstring): the job
    planned (deburr_drake.cell.job.plan_job), the first cut planned as a
    single pass's cell (gains designed at its start), each cut's
    scenario, path and start rotation."""
    scenario.validate()
    _check(scenario)
    scenario = _resolved(scenario)
    settings = MoveSettings()
    job = plan_job(scenario, settings=settings)
    if not job.cuts:
        reasons = "; ".join(why for _, why in job.refused) or "none selected"
        raise ConfigError(f"job: no edge can be cut ({reasons})")
    pose = scenario.job.pose
    first = edge_scenario(scenario, job.cuts[0].edge, pose)
    cell = plan_cell(first)
    resolved = cell.scenario
    edges = tuple(edge_scenario(resolved, c.edge, pose) for c in job.cuts)
    tool_frame = resolved.robot.tool_frame
    rotations = [cell.start.rotation] + [
        _rotation(cell.model, tool_frame, c.start[2])[0] for c in job.cuts[1:]
    ]
    contours = [cell.belief] + [c.contour for c in job.cuts[1:]]
    contour = JobContour(contours, rotations)
    real = [cell.contour] + [
        make_contour(e) if scenario.part_error.moves() else c.contour
        for e, c in zip(edges[1:], job.cuts[1:])
    ]
    passes = resolved.simulation.stop_after_passes or 1.0
    cuts = []
    workspace = []
    for k, c in enumerate(job.cuts):
        start = cell.start.position if k == 0 else c.start[0]
        s0 = contours[k].arc_position(start)
        following = job.cuts[k + 1].move if k + 1 < len(job.cuts) else None
        cuts.append(
            CutPlan(
                end_arc=contour.offset(k) + s0 + passes * contours[k].length,
                move=None
                if following is None
                else _move_plan(following, scenario.job, settings),
            )
        )
        workspace += [
            contours[k].point_at(s)
            for s in np.linspace(0.0, contours[k].length, 65)
        ]
        if following is not None:
            workspace += [
                _rotation(cell.model, tool_frame, q)[1]
                for q in following.path[:: max(1, len(following.path) // 50)]
            ]
    probe_clearance = None
    if cell.mesh_probe is not None:
        # The probe's touches, reached by the job's arm clear of the part.
        route = cell.mesh_probe.route(resolved.localisation.probe.standoff)
        probe_clearance = check_probe_route(
            job.cell,
            cell.model,
            resolved.robot.tool_frame,
            route,
            rotation=cell.start.rotation,
            q_start=cell.start.q,
        )
        workspace += list(route)
    return JobCellPlan(
        job=job,
        cell=cell,
        edges=edges,
        contour=contour,
        cuts=tuple(cuts),
        workspace=np.array(workspace),
        section=scenario.job,
        real=tuple(real),
        contour_step=_contour_step(edges, rotations),
        probe_clearance=probe_clearance,
    )


def _contour_step(edges, rotations) -> Optional[tuple]:
    """``faults.part_step`` on a job: (time, the JobContour of every
    cut's believed path after the step), else None."""
    steps = [believed_contour_step(e) for e in edges]
    if steps[0] is None:
        return None
    return steps[0][0], JobContour([c for _, c in steps], rotations)


def _add_processes(builder, plan: JobCellPlan, plant, tool_point):
    """A cutting process per edge, its force law, and the forces summed
    on the plant; (processes, force laws, summed applied force, the
    generalized forces' sum)."""
    n = len(plan.edges)
    generalized = builder.AddNamedSystem(
        "cutting_forces", Adder(n, plant.num_velocities())
    )
    applied = builder.AddNamedSystem("cutting_force_sum", Adder(n, 3))
    processes, laws = [], []
    for k, contour in enumerate(plan.real):
        process = add_cutting_process(
            builder,
            plan.scenario,
            plant,
            contour,
            tool_point,
            name=f"cutting_process_{k}",
            spindle_input=True,
        )
        law = add_force_law(builder, plant, process, f"cutting_force_{k}")
        builder.Connect(
            law.GetOutputPort("generalized_force"),
            generalized.get_input_port(k),
        )
        builder.Connect(
            law.GetOutputPort("applied_force"), applied.get_input_port(k)
        )
        processes.append(process)
        laws.append(law)
    builder.Connect(
        generalized.get_output_port(),
        plant.get_applied_generalized_force_input_port(),
    )
    return processes, laws, applied.get_output_port(), generalized


def _add_sensor(builder, c: Scenario, plant, tool_point, applied):
    """The force sensor on the summed force, its noise and faults; the
    reading the controller side gets."""
    sensor, noise = add_force_sensor(builder, c, plant, tool_point)
    builder.Connect(applied, sensor.GetInputPort("applied_force"))
    return sensor_reading(builder, c, sensor, noise)


def _add_position_loop(builder, plan: JobCellPlan, plant, reference):
    """Inverse dynamics on the controller's model along the sequencer's
    joint reference; its actuation (nu)."""
    model = plan.cell.model
    n = model.num_positions()
    w = POSITION_LOOP_FREQUENCY
    loop = builder.AddNamedSystem(
        "position_loop",
        InverseDynamicsController(
            model,
            kp=np.full(n, w * w),
            ki=np.zeros(n),
            kd=np.full(n, 2.0 * w),
            has_reference_acceleration=False,
        ),
    )
    builder.Connect(
        plant.get_state_output_port(), loop.get_input_port_estimated_state()
    )
    builder.Connect(reference, loop.get_input_port_desired_state())
    # generalized forces to actuation: B^+ (B = I on the shipped arms)
    B = plant.MakeActuationMatrix()
    to_actuation = builder.AddNamedSystem(
        "position_loop_actuation", MatrixGain(np.linalg.pinv(B))
    )
    builder.Connect(
        loop.get_output_port_control(), to_actuation.get_input_port()
    )
    return to_actuation.get_output_port()


def _connect_actuation(builder, c, plant, processes, laws, generalized, port):
    """The switch's actuation to the plant through the drives, and to the
    force laws and processes that hold the sample's torque."""
    actuation = add_effort_saturation(builder, c, plant, port)
    builder.Connect(actuation, plant.get_actuation_input_port())
    for process, law in zip(processes, laws):
        builder.Connect(actuation, law.GetInputPort("actuation"))
        if not c.process.sample_mean:
            continue
        builder.Connect(
            plant.get_generalized_acceleration_output_port(),
            process.GetInputPort("generalized_acceleration"),
        )
        builder.Connect(
            generalized.get_output_port(),
            process.GetInputPort("applied_generalized_force"),
        )
        builder.Connect(actuation, process.GetInputPort("actuation"))
    return actuation


def _add_sequencer(builder, plan: JobCellPlan, plant, loops, processes):
    """The JobSequencer, wired to the loops (the generator's hold, the
    gate, the controller's fuzzy weight and activity) and the spindles."""
    c = plan.scenario
    probe = None
    if loops.probe is not None:
        probe = JobProbe(
            registration=POSE_REGISTRATION_SIZE,
            move=path_mover(plan.cell.model, c.robot.tool_frame),
        )
    sequencer = builder.AddNamedSystem(
        "job_sequencer",
        JobSequencer(
            plan.cuts,
            period=c.command.period,
            desired_depth=c.task.desired_depth,
            entry_dwell=plan.section.entry_dwell,
            num_positions=plant.num_positions(),
            probe=probe,
        ),
    )
    connect = builder.Connect
    if probe is not None:
        for port in ("probing", "registration"):
            connect(
                loops.probe.GetOutputPort(port), sequencer.GetInputPort(port)
            )
    for source, port, target in (
        ("command_state", "command_state", loops.command_generator),
        ("chamfer_state", "chamfer_state", loops.observer),
    ):
        connect(target.GetOutputPort(source), sequencer.GetInputPort(port))
    # The job's gate (with probing, the probe's gate follows it).
    job_gate = builder.GetSubsystemByName("job_gate")
    for output, system, port in (
        ("off_part", job_gate, "probing"),
        ("hold", loops.command_generator, "hold"),
        ("fuzzy_weight", loops.controller, "fuzzy_weight"),
        ("force_loop", loops.controller, "active"),
    ):
        connect(sequencer.GetOutputPort(output), system.GetInputPort(port))
    spindles = builder.AddNamedSystem(
        "spindles", Demultiplexer(len(processes), 1)
    )
    connect(sequencer.GetOutputPort("spindles"), spindles.get_input_port())
    for k, process in enumerate(processes):
        connect(spindles.get_output_port(k), process.GetInputPort("spindle"))
    return sequencer


def _add_guards_and_loggers(builder, plan, plant, loops, sequencer, switch):
    """The guards (contact judged on the cuts, the workspace every cut and
    move and the probe's route span) and the loggers (``log_<name>``;
    with probing ``log_probe`` and ``log_touch_points`` too)."""
    c = plan.scenario
    logged = {
        name: builder.GetSubsystemByName(system).GetOutputPort(port)
        for name, (system, port) in LOGGED.items()
        if name not in ("process", "actuation")
    }
    logged["chamfer"] = loops.chamfer
    logged["desired_normal_force"] = loops.gate.GetOutputPort(
        "desired_normal_force"
    )
    logged["actuation"] = switch.GetOutputPort("actuation")
    if loops.probe is not None:
        for name, (system, port) in LOCALISATION_LOGGED.items():
            if builder.HasSubsystemNamed(system):
                logged[name] = builder.GetSubsystemByName(system).GetOutputPort(
                    port
                )
    cutting = sequencer.GetOutputPort("cutting")
    add_guards(
        builder, c, plant, plan.contour, logged, job=(cutting, plan.workspace)
    )
    logged["job"] = sequencer.GetOutputPort("job_state")
    logged["plant_state"] = plant.get_state_output_port()
    for k in range(len(plan.edges)):
        process = builder.GetSubsystemByName(f"cutting_process_{k}")
        logged[f"process_{k}"] = process.GetOutputPort("process_state")
    for name, port in logged.items():
        LogVectorOutput(port, builder, c.simulation.log_period).set_name(
            f"log_{name}"
        )


def _add_meshcat(builder, meshcat, plan, plant, scene_graph, processes):
    """The cell, its contact forces and every edge's finish drawn in
    ``meshcat``."""
    from deburr_drake.cell.meshcat import add_job_meshcat

    edges = []
    for contour, process in zip(plan.real, processes):
        arc = process.bins.centers
        edges.append(
            (
                process,
                np.array([contour.edge_point(s) for s in arc]),
                np.array([contour.tool_axis_at(s) for s in arc]),
            )
        )
    add_job_meshcat(
        builder, meshcat, plant=plant, scene_graph=scene_graph, edges=edges
    )


def make_job_diagram(plan: JobCellPlan, *, meshcat=None) -> Diagram:
    """The job's closed loop as a named Diagram ``job_<scenario name>``
    (see the module docstring), built from ``plan`` alone. Loggers: those
    of LOGGED but ``process`` (``actuation`` is the switch's), a
    ``log_process_<k>`` per edge, ``log_job`` (the sequencer's state) and
    ``log_plant_state``. With a ``meshcat``, the cell is drawn there,
    each edge's finish too (deburr_drake.cell.meshcat.add_job_meshcat)."""
    count(DIAGRAMS)
    c = plan.scenario
    cell = plan.cell
    builder = DiagramBuilder()
    # The plant: the robot, and a band on every edge cut.
    plant, scene_graph = add_cell_plant(builder, c, edges=list(plan.edges))
    plant.SetDefaultPositions(cell.start.q)
    model = cell.model
    tool_point = ToolPoint(model, model.GetFrameByName(c.robot.tool_frame))
    # The plant side: a cutting process per edge, the force sensor.
    processes, laws, applied, generalized = _add_processes(
        builder, plan, plant, tool_point
    )
    reading = _add_sensor(builder, c, plant, tool_point, applied)
    # The paper's loops on every edge's path, gated off the part.
    loops = add_deburring_controller(
        builder,
        scenario=c,
        plant=model,
        contour=plan.contour,
        plant_state=plant.get_state_output_port(),
        measured_force=reading,
        tool_frame=c.robot.tool_frame,
        start=cell.start.position,
        desired_rotation=cell.start.rotation,
        tool_point=tool_point,
        true_plant=plant,
        posture=cell.start.q,
        sequenced=True,
        contour_step=plan.contour_step,  # after the part moved
        mesh_probe=cell.mesh_probe,
    )
    # With touch probing, the probe's contact with the real part.
    if loops.probe is not None:
        add_touch_contact(builder, cell, plant, tool_point, loops.probe)
    # The sequencer drives the loops, the spindles and the moves.
    sequencer = _add_sequencer(builder, plan, plant, loops, processes)
    force_loop = sequencer.GetOutputPort("force_loop")
    # The drives: the force loop's actuation on cuts, the position loop's
    # on moves.
    position = _add_position_loop(
        builder, plan, plant, sequencer.GetOutputPort("joint_reference")
    )
    switch = builder.AddNamedSystem(
        "actuation_switch", ActuationSwitch(plant.num_actuators())
    )
    builder.Connect(force_loop, switch.GetInputPort("cutting"))
    builder.Connect(loops.actuation, switch.GetInputPort("force_loop"))
    builder.Connect(position, switch.GetInputPort("position_loop"))
    _connect_actuation(
        builder,
        c,
        plant,
        processes,
        laws,
        generalized,
        switch.GetOutputPort("actuation"),
    )
    # The guards and the loggers.
    _add_guards_and_loggers(builder, plan, plant, loops, sequencer, switch)
    if meshcat is not None:
        _add_meshcat(builder, meshcat, plan, plant, scene_graph, processes)
    diagram = builder.Build()
    diagram.set_name(f"job_{c.name}")
    return diagram
