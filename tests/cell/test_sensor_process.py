"""ForceSensor (weld reaction, weight compensation, sampled low-pass) and
CuttingProcess (eq. (3) and the threshold c0 of (4))."""

import numpy as np
from pydrake.multibody.math import SpatialForce
from pydrake.multibody.plant import (
    AddMultibodyPlant,
    ExternallyAppliedSpatialForce,
    MultibodyPlantConfig,
)
from pydrake.systems.framework import DiagramBuilder
import pytest

from deburr_drake.cell.arm import ARM_URL
from deburr_drake.cell.models import make_kinematic_model
from deburr_drake.cell.part import add_cartesian_tool, add_tool_robot
from deburr_drake.cell.process import PROCESS_STATE, cutting_force
from deburr_drake.cell.sensor import ForceSensor
from deburr_drake.config import ProcessConfig, SensorConfig
from deburr_drake.control.kinematics import ToolPoint
from deburr_drake.math.geometry import CircularContour

CONTOUR = CircularContour([0.0, 0.0, 0.048], 0.027)


def _connect_sensor(builder, plant, sensor):
    builder.Connect(
        plant.get_reaction_forces_output_port(),
        sensor.GetInputPort("reaction_forces"),
    )
    builder.Connect(
        plant.get_state_output_port(), sensor.GetInputPort("plant_state")
    )


def _held_tool(f_ext, config=SensorConfig()):
    """Tool at rest, actuators balancing gravity and f_ext exactly."""
    builder = DiagramBuilder()
    plant, _ = AddMultibodyPlant(
        MultibodyPlantConfig(
            time_step=0.0, contact_model="hydroelastic_with_fallback"
        ),
        builder,
    )
    add_cartesian_tool(plant)
    plant.Finalize()
    sensor = builder.AddSystem(ForceSensor(plant, "ft_sensor", config))
    _connect_sensor(builder, plant, sensor)
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    pc = plant.GetMyMutableContextFromRoot(context)
    plant.SetPositions(pc, [0.1, -0.05, 0.2])
    total_mass = sum(
        plant.GetBodyByName(b).default_mass()
        for b in ("x_carriage", "y_carriage", "flange", "tool")
    )
    masses = np.array([total_mass, total_mass - 0.5, 1.3])
    plant.get_actuation_input_port().FixValue(
        pc, masses * np.array([0, 0, 9.81]) - f_ext
    )
    applied = ExternallyAppliedSpatialForce()
    applied.body_index = plant.GetBodyByName("tool").index()
    applied.p_BoBq_B = np.zeros(3)
    applied.F_Bq_W = SpatialForce(np.zeros(3), f_ext)
    plant.get_applied_spatial_force_input_port().FixValue(pc, [applied])
    sc = sensor.GetMyMutableContextFromRoot(context)
    sensor.GetInputPort("noise").FixValue(sc, np.zeros(3))
    return plant, pc, sensor, sc


def test_reads_the_external_force_with_weight_compensated():
    f_ext = np.array([-3.0, 7.5, 1.25])
    plant, pc, sensor, sc = _held_tool(f_ext)
    vdot = plant.get_generalized_acceleration_output_port().Eval(pc)
    np.testing.assert_allclose(vdot, 0.0, atol=1e-12)
    np.testing.assert_allclose(sensor.raw_force(sc), f_ext, atol=1e-9)


def test_shared_tool_point_gives_the_same_reading_on_the_arm():
    """The arm's tool is tilted: the rotation into world matters. A sensor
    that takes it from a ToolPoint on the kinematic model reads what one
    computing it on the plant reads."""
    builder = DiagramBuilder()
    plant, _ = AddMultibodyPlant(MultibodyPlantConfig(time_step=0.0), builder)
    add_tool_robot(plant, ARM_URL)
    plant.Finalize()
    model = make_kinematic_model(ARM_URL)
    tool_point = ToolPoint(model, model.GetFrameByName("tool_tip"))
    sensors = [
        builder.AddNamedSystem(
            name, ForceSensor(plant, "ft_sensor", SensorConfig(), tool_point=tp)
        )
        for name, tp in (("own", None), ("shared", tool_point))
    ]
    for sensor in sensors:
        _connect_sensor(builder, plant, sensor)
    diagram = builder.Build()
    context = diagram.CreateDefaultContext()
    pc = plant.GetMyMutableContextFromRoot(context)
    plant.SetPositions(pc, [0.3, 0.7, -1.1, 0.6, 0.4])
    plant.get_actuation_input_port().FixValue(pc, [1.0, -2.0, 3.0, 0.5, 0.1])
    readings = [s.raw_force(s.GetMyContextFromRoot(context)) for s in sensors]
    assert np.linalg.norm(readings[0]) > 1.0
    np.testing.assert_allclose(readings[1], readings[0], atol=1e-12)
    assert tool_point.full_evaluations == 1


def test_low_pass_update():
    config = SensorConfig(sample_period=0.0025, cutoff_frequency=20.0)
    f_ext = np.array([1.0, 2.0, 3.0])
    _, _, sensor, sc = _held_tool(f_ext, config)
    alpha = 1 - np.exp(-2 * np.pi * 20.0 * 0.0025)
    y = sensor.EvalUniquePeriodicDiscreteUpdate(sc).get_vector(0)
    np.testing.assert_allclose(y.CopyToVector(), alpha * f_ext, rtol=1e-9)
    assert sensor.GetOutputPort("measured_force").Eval(sc) == pytest.approx(
        np.zeros(3)
    )  # no feedthrough: the state, not the input


def test_cutting_force_by_hand():
    config = ProcessConfig(
        cutting_coefficient=3.3e9,
        plunge_coefficient=50.0,
        threshold_power_force=2.0,
        contact_threshold_force=2.0,
    )
    p = CONTOUR.point_at(0.02)
    n1, t = CONTOUR.n1(p), CONTOUR.tangent(p)
    delta, v_t, v_n = 5e-4, 2.4e-3, 1e-4
    force, state = cutting_force(
        config, CONTOUR, p + delta * n1, v_t * t + v_n * n1, cut_height=0.002
    )
    g = 3.3e9 * delta * 0.002
    f_t = g * v_t + 50.0 * v_n + 2.0
    np.testing.assert_allclose(force, -f_t * t - 2.0 * n1, rtol=1e-9)
    # Below smoothing_speed the direction ramps: sat(v_t / v_s).
    slow = 0.25 * config.smoothing_speed
    force, _ = cutting_force(
        config, CONTOUR, p + delta * n1, slow * t, cut_height=0.002
    )
    np.testing.assert_allclose(
        force, -(g * slow + 2.0 * 0.25) * t - 2.0 * n1, rtol=1e-9
    )
    s = PROCESS_STATE.split(state)
    assert s["g"] == pytest.approx(g)
    assert s["engagement"] == 1.0
    assert s["f_threshold"] == pytest.approx(2.0)


def test_no_cutting_force_out_of_contact_and_smooth_onset():
    config = ProcessConfig()
    p = CONTOUR.point_at(0.0)
    n1, t = CONTOUR.n1(p), CONTOUR.tangent(p)
    force, _ = cutting_force(
        config, CONTOUR, p - 1e-4 * n1, 2e-3 * t, cut_height=0.002
    )
    np.testing.assert_array_equal(force, 0.0)
    half, _ = cutting_force(
        config,
        CONTOUR,
        p + 0.5 * config.threshold_depth * n1,
        2e-3 * t,
        cut_height=0.002,
    )
    full, _ = cutting_force(
        config,
        CONTOUR,
        p + 2.0 * config.threshold_depth * n1,
        2e-3 * t,
        cut_height=0.002,
    )
    assert 0 < -half @ n1 < -full @ n1


def test_force_applied_through_the_joints_is_read_as_on_the_tool():
    """The cell applies the cutting force as J^T f through the joints; the
    sensor adds f back to the weld's reading (the weld would carry it)."""
    config = SensorConfig(sample_period=0.0025, cutoff_frequency=20.0)
    f_ext = np.array([1.0, 2.0, 3.0])
    _, _, sensor, sc = _held_tool(f_ext, config)
    base = sensor.raw_force(sc)
    sensor.GetInputPort("applied_force").FixValue(sc, [0.5, -1.0, 0.25])
    np.testing.assert_allclose(
        sensor.raw_force(sc) - base, [0.5, -1.0, 0.25], rtol=1e-12
    )


@pytest.mark.parametrize("closed", [True, False])
def test_finish_bins_near_covers_every_bin_within_the_radius(closed):
    from deburr_drake.cell.process import FinishBins
    from deburr_drake.math.metrics import arc_distance

    length, radius = 0.1696, 0.003
    bins = FinishBins(length, 2e-4)
    for s in np.r_[
        np.linspace(0.0, length, 97, endpoint=False),
        [1e-9, length - 1e-9, radius, length - radius],
    ]:
        d = arc_distance(bins.centers, s, length, closed)
        within = set(np.flatnonzero(np.abs(d) <= radius))
        near = bins.near(s, radius, closed)
        assert within <= set(near)
        assert len(set(near)) == len(near) < bins.count
    np.testing.assert_array_equal(
        FinishBins(0.001, 2e-4).near(5e-4, radius, closed), np.arange(5)
    )


def test_chamfering_force_on_fillets_follows_the_material_removed():
    """On a pocket's (concave) fillet the cutter centre runs a shorter path
    than the edge: more chamfer per metre of feed, a larger g; on a boss's
    (convex) fillet less. g = k_c s (delta h + burr), s = removal_scale."""
    from deburr_drake.cell.process import PROCESS_STATE, cutting_force
    from deburr_drake.math.geometry import removal_scale
    from deburr_drake.math.profile import ProfileContour

    config = ProcessConfig(cutting_coefficient=3.0e9)
    r, delta, h = 0.003, 5e-4, 0.002
    rect = [[-0.03, -0.02], [0.03, -0.02], [0.03, 0.02], [-0.03, 0.02]]
    g = {}
    for name, material, fillet in (
        ("pocket", "outside", 0.008),
        ("boss", "inside", 0.010),
    ):
        c = ProfileContour(rect, fillet, material=material, offset=r)
        for where, s in (
            ("line", 0.0),
            ("fillet", 0.02 - fillet + 0.25 * c.arcs()[0][4]),
        ):
            p = c.point_at(s)
            x = p + delta * c.n1(p)
            _, state = cutting_force(
                config, c, x, 2e-3 * c.tangent(x), cut_height=h, cutter_radius=r
            )
            g[name, where] = PROCESS_STATE.get(state, "g")
            assert g[name, where] == pytest.approx(
                3.0e9 * delta * h * removal_scale(c.curvature(x), delta, r)
            )
    assert g["pocket", "line"] == pytest.approx(3.0e9 * delta * h)
    # pocket fillet: path radius 5 mm, the edge's 8 mm
    assert g["pocket", "fillet"] / g["pocket", "line"] == pytest.approx(
        (0.008 + delta / 2) / (0.005 + delta)
    )
    # boss fillet: path radius 13 mm, the edge's 10 mm
    assert g["boss", "fillet"] / g["boss", "line"] == pytest.approx(
        (0.010 - delta / 2) / (0.013 - delta)
    )


def test_chamfering_force_along_a_cad_edge_cuts_the_faces_wedge():
    """Along the 120-degree wedge (the tool along its sloped face) the
    chamfer is delta h plus the triangle the rising top face adds:
    g = k_c (delta h + delta^2 tan(30 deg) / 2)."""
    import math
    from pathlib import Path

    from deburr_drake.cell.process import PROCESS_STATE, cutting_force
    from deburr_drake.math.edge_contour import EdgeContour
    from deburr_drake.math.mesh_part import (
        EdgeCurve,
        choose_edge,
        load_part,
        sharp_edges,
    )

    part = load_part(
        Path(__file__).resolve().parents[2] / "models/parts/wedge.stl",
        units="mm",
    )
    curve = EdgeCurve(choose_edge(sharp_edges(part), near=[0.04, 0.03, 0.02]))
    h, delta = 0.002, 5e-4
    c = EdgeContour(
        curve, cutter_radius=0.003, engagement=h, rule="left", tilt=-math.pi / 6
    )
    config = ProcessConfig(cutting_coefficient=3.0e9)
    p = c.point_at(0.5 * c.length)
    x = p + delta * c.n1(p)
    _, state = cutting_force(config, c, x, 2e-3 * c.tangent(x), cut_height=h)
    area = delta * h + 0.5 * delta**2 * math.tan(math.pi / 6)
    assert PROCESS_STATE.get(state, "g") == pytest.approx(
        3.0e9 * area, rel=1e-5
    )
