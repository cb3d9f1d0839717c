"""The deburring cell: named systems, the arm's start pose, the cutting
process's burrs and surface-finish record."""

import copy

import numpy as np
import pytest

from deburr_drake.cell.diagram import SYSTEM_NAMES, make_deburring_diagram
from deburr_drake.cell.edge import make_contour, start_position
from deburr_drake.cell.gains import resolve_design
from deburr_drake.cell.models import POINT_MASS_URL, make_kinematic_model
from deburr_drake.cell.process import CuttingProcess, burr_profile
from deburr_drake.config import BurrConfig, ProcessConfig, load_scenario
from deburr_drake.math.geometry import CircularContour


@pytest.fixture(scope="module")
def paper_diagram(paper_cell):
    return paper_cell()


def test_every_system_is_named(paper_diagram):
    scenario, diagram = paper_diagram
    names = {s.get_name() for s in diagram.GetSystems()}
    for name in SYSTEM_NAMES:
        assert name in names
    for name in ("log_chamfer", "log_controller", "log_process"):
        assert name in names
    assert diagram.get_name() == "deburr_paper"
    controller = diagram.GetSubsystemByName("controller")
    # 242 rules (2 x 11^2) plus delta_d.
    assert controller.num_continuous_states() == 243


@pytest.mark.parametrize(
    "name, text",
    [("paper", None), ("paper_6dof", "controller: {design: auto}")],
)
def test_the_builder_leaves_the_scenario_as_it_is_and_builds_the_design(
    name, text
):
    """The diagram is built from the designed values (the gains of
    ``design: auto``, the fuzzy slope bound), the scenario given stays as
    it was."""
    scenario = load_scenario(name, text=text)
    given = copy.deepcopy(scenario)
    diagram = make_deburring_diagram(scenario=scenario)
    assert scenario == given
    resolved = resolve_design(scenario)
    built = diagram.GetSubsystemByName("controller").config
    assert built == resolved.controller != scenario.controller


def test_the_force_path_ports_say_where_the_force_comes_from(paper_diagram):
    """The force law's ``applied_force`` (the true force on the tool) into
    the sensor, whose ``measured_force`` the controller side reads."""
    _, diagram = paper_diagram
    law = diagram.GetSubsystemByName("cutting_force")
    sensor = diagram.GetSubsystemByName("force_sensor")
    assert law.HasOutputPort("applied_force")
    assert sensor.HasInputPort("applied_force")
    assert [
        sensor.get_output_port(i).get_name()
        for i in range(sensor.num_output_ports())
    ] == ["measured_force"]


def test_arm_starts_at_the_contour_start_in_contact(paper_diagram):
    scenario, diagram = paper_diagram
    context = diagram.CreateDefaultContext()
    plant = diagram.GetSubsystemByName("plant")
    pc = plant.GetMyContextFromRoot(context)
    tip = plant.GetFrameByName("tool_tip").CalcPoseInWorld(pc)
    np.testing.assert_allclose(
        tip.translation(), start_position(scenario), atol=1e-7
    )
    # Tool axis vertical.
    np.testing.assert_allclose(
        tip.rotation().matrix()[:, 2], [0, 0, 1], atol=1e-7
    )
    contour = make_contour(scenario)
    assert contour.depth(tip.translation()) == pytest.approx(0.0, abs=1e-7)


def test_burr_profile_raised_cosine():
    burrs = [BurrConfig(center_fraction=0.25, length=0.008, height=0.001)]
    L = 0.1
    arc = np.array([0.025, 0.025 + 0.002, 0.025 + 0.004, 0.06])
    h = burr_profile(arc, burrs, L, closed=True)
    np.testing.assert_allclose(h, [0.001, 0.0005, 0.0, 0.0], atol=1e-15)
    # Wraps on a closed edge.
    h_wrap = burr_profile(
        [0.099], [BurrConfig(center_fraction=0.0)], L, closed=True
    )
    assert h_wrap[0] > 0


def test_process_records_finish_and_removes_swept_burr():
    contour = CircularContour([0.0, 0.0, 0.048], 0.027)
    config = ProcessConfig(
        burrs=[BurrConfig(center_fraction=0.1, length=0.008, height=0.001)]
    )
    model = make_kinematic_model(POINT_MASS_URL)
    process = CuttingProcess(
        model,
        "tool_tip",
        contour,
        config,
        cut_height=0.002,
        cutter_radius=0.003,
    )
    context = process.CreateDefaultContext()
    s = 0.1 * contour.length  # the tool's contact point at the burr centre
    p = contour.point_at(s)
    x_p = p + 4e-4 * contour.n1(p)
    v = 2e-3 * contour.tangent(p)
    process.GetInputPort("plant_state").FixValue(
        context, np.concatenate([x_p, v])
    )
    # process.sample_mean's inputs: nothing else acts on the point.
    for name in (
        "generalized_acceleration",
        "applied_generalized_force",
        "actuation",
    ):
        port = process.GetInputPort(name)
        port.FixValue(context, np.zeros(port.size()))
    burr0 = process.GetOutputPort("burr_height").Eval(context).copy()
    # One sample: records the finish, removes the swept burr, samples the
    # process state.
    context.SetDiscreteState(process.EvalUniquePeriodicDiscreteUpdate(context))
    state = process.GetOutputPort("process_state").Eval(context)
    # The burr is cut at the cutter's front, s + r: raised cosine there.
    front = burr_profile([s + 0.003], config.burrs, contour.length, True)[0]
    from deburr_drake.cell.process import PROCESS_STATE

    area = PROCESS_STATE.get(state, "burr_area")
    bins = process.bins
    assert area == pytest.approx(burr0[bins.index(s + 0.003)] * 0.002)
    assert 0 < area <= 0.001 * 0.002
    assert front > 0
    g = PROCESS_STATE.get(state, "g")
    # the bore (path radius 27 mm, cutter 3 mm): the band 30 .. 30.4 mm
    # per metre of the cutter centre's travel at 27.4 mm
    scale = (0.0304**2 - 0.03**2) / 2 / 0.0274 / 4e-4
    assert g == pytest.approx(
        config.cutting_coefficient * scale * (4e-4 * 0.002 + area), rel=1e-3
    )
    burr1 = process.GetOutputPort("burr_height").Eval(context)
    finish = process.GetOutputPort("finish_depth").Eval(context)
    k = bins.index(s)
    assert finish[k] == pytest.approx(4e-4, rel=1e-3)
    assert np.count_nonzero(finish) == 1
    d = bins.centers - s
    swept = (d >= -0.003) & (d < 0.003 - bins.width)
    np.testing.assert_array_equal(burr1[swept], 0.0)
    np.testing.assert_array_equal(burr1[~swept], burr0[~swept])
    assert burr1[bins.index(s + 0.003)] > 0  # the front is still uncut
    assert bins.width <= 2e-4


def test_straight_edge_cell():
    from deburr_drake.cell.truth import contact_normal_force
    from deburr_drake.math.geometry import StraightContour

    scenario = load_scenario("paper", text="part: {edge: {kind: straight}}")
    contour = make_contour(scenario)
    assert isinstance(contour, StraightContour)
    assert contour.length == pytest.approx(0.1)
    # Material on the right of the travel direction (+y): n1 = +x.
    np.testing.assert_allclose(
        contour.n1(contour.point_at(0.0)), [1, 0, 0], atol=1e-12
    )
    f = contact_normal_force(scenario, [-1e-4, 2e-4, 5e-4, 8e-4])
    assert f[0] == 0.0 and 0 < f[1] < f[2] < f[3]
    # About the ring's 10 N/mm at 0.5 mm: the same material and wall.
    k = (
        contact_normal_force(scenario, [5.2e-4])[0]
        - contact_normal_force(scenario, [4.8e-4])[0]
    ) / 4e-5
    assert 8e3 < k < 12e3
    diagram = make_deburring_diagram(scenario=scenario)
    context = diagram.CreateDefaultContext()
    plant = diagram.GetSubsystemByName("plant")
    tip = (
        plant.GetFrameByName("tool_tip")
        .CalcPoseInWorld(plant.GetMyContextFromRoot(context))
        .translation()
    )
    np.testing.assert_allclose(tip, contour.point_at(0.0), atol=1e-7)


def _one_sample_from(source, context, cell, kick):
    """The tool's speed along the edge after one 2.5 ms sample of
    ``cell`` ((scenario, its diagram)) started from ``context`` of
    ``source`` (its state copied by subsystem; in a simulator of its own),
    with the tool's joint velocities kicked by ``kick`` along the edge's
    direction (joint space, J^+ n2)."""
    from pydrake.systems.analysis import InitializeParams

    from deburr_drake.analysis.operating_point import transfer_state
    from deburr_drake.runs.simulation import make_simulator

    scenario, diagram = cell
    simulator = make_simulator(diagram, scenario)
    root = simulator.get_mutable_context()
    transfer_state(source, context, diagram, root)
    plant = diagram.GetSubsystemByName("plant")
    pc = plant.GetMyMutableContextFromRoot(root)
    plant.SetVelocities(pc, plant.GetVelocities(pc) + kick)
    simulator.Initialize(InitializeParams(suppress_initialization_events=True))
    # from just before the sample at 1 s: its updates (the process's terms)
    # are each scenario's own
    simulator.AdvanceTo(1.0 + scenario.controller.control_period)
    frame = plant.GetFrameByName(scenario.robot.tool_frame)
    v_tool = frame.CalcSpatialVelocityInWorld(pc).translational()
    return v_tool


@pytest.mark.slow
def test_held_mean_at_one_step_follows_eq3_at_fine_steps(paper_cell):
    """The paper cell in cutting, the tool kicked 2 mm/s along the edge,
    one 2.5 ms sample: with the cutting force held at its exact mean
    (process.sample_mean, one cenic step) the tool's speed along the edge
    at the sample's end is that of eq. (3) at 20 steps per sample within
    1 % of the kick (measured: 0.3 %); eq. (3) at one step (its
    off-diagonal damping explicit) is more than 3 times as far off
    (measured: 3.4 % of the kick)."""
    from deburr_drake.runs.simulation import make_simulator

    shipped, diagram = paper_cell()
    assert shipped.process.sample_mean
    assert shipped.simulation.max_step == shipped.controller.control_period
    simulator = make_simulator(diagram, shipped)
    simulator.Initialize()
    simulator.AdvanceTo(1.0 - 1e-9)  # cutting, off the burrs
    context = simulator.get_context()
    plant = diagram.GetSubsystemByName("plant")
    pc = plant.GetMyContextFromRoot(context)
    frame = plant.GetFrameByName(shipped.robot.tool_frame)
    from pydrake.multibody.tree import JacobianWrtVariable

    J = plant.CalcJacobianTranslationalVelocity(
        pc,
        JacobianWrtVariable.kV,
        frame,
        [0, 0, 0],
        plant.world_frame(),
        plant.world_frame(),
    )
    observer = diagram.GetSubsystemByName("chamfer_observer")
    from deburr_drake.control.layout import CHAMFER_STATE

    n2 = CHAMFER_STATE.get(
        observer.GetOutputPort("chamfer_state").Eval(
            observer.GetMyContextFromRoot(context)
        ),
        "n2",
    )
    kick = np.linalg.pinv(J) @ (2e-3 * n2)
    speeds = {}
    for name, text in (
        ("held", None),
        (
            "fine",
            "{process: {sample_mean: false}, simulation: {max_step: 0.000125}}",
        ),
        ("explicit", "{process: {sample_mean: false}}"),
    ):
        if text is None:  # the shipped cell: its diagram, a new simulator
            cell = (shipped, diagram)
        else:
            scenario = load_scenario("paper", text=text)
            cell = (scenario, make_deburring_diagram(scenario=scenario))
        speeds[name] = float(
            _one_sample_from(diagram, context, cell, kick) @ n2
        )
    assert abs(speeds["held"] - speeds["fine"]) < 0.01 * 2e-3, speeds
    assert abs(speeds["explicit"] - speeds["fine"]) > 3 * abs(
        speeds["held"] - speeds["fine"]
    ), speeds
