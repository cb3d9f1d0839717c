"""Tests of deburr_drake.cell.part: the compliant ring and the tool/ring contact
law."""

import numpy as np
import pytest

from deburr_drake.cell.part import (
    CALIBRATED_FORCE_AT_HALF_MM,
    CALIBRATED_HYDROELASTIC_MODULUS,
    EdgeContactProbe,
    RingContactProbe,
    add_cartesian_tool,
    measure_normal_force,
    register_compliant_edge,
    register_compliant_ring,
    register_part_visual,
)

E = CALIBRATED_HYDROELASTIC_MODULUS


@pytest.fixture(scope="module")
def probe():
    return RingContactProbe(hydroelastic_modulus=E)


def test_force_at_half_mm_matches_calibration():
    f = measure_normal_force([5e-4], hydroelastic_modulus=E)[0]
    assert (
        abs(f - CALIBRATED_FORCE_AT_HALF_MM)
        <= 0.2 * CALIBRATED_FORCE_AT_HALF_MM
    )


def test_force_increases_with_depth():
    f = measure_normal_force(np.arange(1, 11) * 1e-4, hydroelastic_modulus=E)
    assert f[0] > 0 and np.all(np.diff(f) > 0)
    # Local stiffness near 0.5 mm is about 10 N/mm (the calibration target).
    k = (f[5] - f[3]) / 2e-4
    assert 8e3 < k < 12e3


def test_zero_force_out_of_contact(probe):
    assert measure_normal_force(
        [-1e-4, -1e-3], hydroelastic_modulus=E
    ).tolist() == [0.0, 0.0]
    np.testing.assert_array_equal(
        probe.contact_force_on_tool([0.0, 0.0, 0.048]), 0.0
    )


def test_force_on_tool_points_inward_and_scales_with_modulus(probe):
    rho, angle = 0.030 - 0.003 + 5e-4, 1.0
    e_r = np.array([np.cos(angle), np.sin(angle), 0.0])
    f = probe.contact_force_on_tool(rho * e_r + [0.0, 0.0, 0.048])
    assert f @ e_r < -0.9 * np.linalg.norm(
        f
    )  # the wall pushes the tool toward the axis
    f2 = measure_normal_force([5e-4], hydroelastic_modulus=2 * E, angle=angle)[
        0
    ]
    np.testing.assert_allclose(f2, -2 * (f @ e_r), rtol=1e-9)


def test_register_compliant_ring_roles_and_errors():
    from pydrake.geometry import Role
    from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
    from pydrake.systems.framework import DiagramBuilder

    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
    add_cartesian_tool(plant)
    kw = dict(
        inner_radius=0.03,
        outer_radius=0.035,
        z_bottom=0.044,
        z_top=0.05,
        n_theta=36,
    )
    with pytest.raises(ValueError, match="hydroelastic_modulus"):
        register_compliant_ring(
            plant, hydroelastic_modulus=0.0, hunt_crossley_dissipation=1.0, **kw
        )
    with pytest.raises(ValueError, match="hunt_crossley_dissipation"):
        register_compliant_ring(
            plant, hydroelastic_modulus=E, hunt_crossley_dissipation=-1.0, **kw
        )
    gid = register_compliant_ring(
        plant, hydroelastic_modulus=E, hunt_crossley_dissipation=1.0, **kw
    )
    inspector = scene_graph.model_inspector()
    props = inspector.GetProximityProperties(gid)
    assert props.GetProperty("hydroelastic", "hydroelastic_modulus") == E
    assert props.GetProperty("material", "hunt_crossley_dissipation") == 1.0
    assert (
        props.GetProperty("material", "coulomb_friction").dynamic_friction()
        == 0.0
    )
    assert inspector.GetFrameId(gid) == plant.GetBodyFrameIdOrThrow(
        plant.world_body().index()
    )
    world_frame = inspector.world_frame_id()
    assert len(inspector.GetGeometries(world_frame, Role.kIllustration)) == 1
    plant.Finalize()
    with pytest.raises(ValueError, match="plant"):
        register_compliant_ring(
            plant, hydroelastic_modulus=E, hunt_crossley_dissipation=1.0, **kw
        )


def test_cartesian_tool_model():
    from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
    from pydrake.systems.framework import DiagramBuilder

    builder = DiagramBuilder()
    plant, _ = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
    instance = add_cartesian_tool(plant)
    plant.Finalize()
    assert plant.num_positions() == 3 and plant.num_actuators() == 3
    for name, axis in zip("xyz", np.eye(3)):
        joint = plant.GetJointByName(name, instance)
        np.testing.assert_array_equal(joint.translation_axis(), axis)
        assert joint.default_damping() == 0.0
        assert (
            plant.GetJointActuatorByName(name, instance).effort_limit() == 200.0
        )
    masses = [
        plant.GetBodyByName(b, instance).default_mass()
        for b in ("x_carriage", "y_carriage", "tool")
    ]
    assert masses == [0.5, 0.5, 1.0]
    context = plant.CreateDefaultContext()
    plant.SetPositions(context, [0.1, -0.2, 0.3])
    tip = plant.GetFrameByName("tool_tip", instance)
    np.testing.assert_allclose(
        tip.CalcPoseInWorld(context).translation(), [0.1, -0.2, 0.3]
    )


def test_a_profile_part_is_a_compliant_mesh_with_visuals():
    from pydrake.systems.framework import DiagramBuilder

    from deburr_drake.cell.plant import add_cell_plant
    from deburr_drake.config import load_scenario

    builder = DiagramBuilder()
    plant, scene_graph = add_cell_plant(builder, load_scenario("boss"))
    inspector = scene_graph.model_inspector()
    names = {inspector.GetName(g): g for g in inspector.GetAllGeometryIds()}
    edge = names["profile_edge"]
    assert type(inspector.GetShape(edge)).__name__ == "Mesh"
    props = inspector.GetProximityProperties(edge)
    assert props.HasProperty("hydroelastic", "compliance_type")
    assert props.GetProperty("hydroelastic", "hydroelastic_modulus") == 4.5e6
    for visual in ("profile_edge_visual", "profile_edge_body"):
        assert inspector.GetIllustrationProperties(names[visual]) is not None
    assert "tube_edge" not in names


# -- the compliant band along a 3-D edge --------------------------------------

DEPTHS = np.array([3e-4, 5e-4, 7e-4])
BAND = dict(width=0.005, height=0.006, closed=True, hydroelastic_modulus=E)


def _rx(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])


def _circle_stations(spacing, rotation=np.eye(3), radius=0.030, z=0.050):
    """The bore's top inner edge (n1 radially out, axis +z) as stations
    about ``spacing`` (m) apart, turned by ``rotation`` about the origin."""
    n = round(2 * np.pi * radius / spacing)
    theta = 2 * np.pi * np.arange(n) / n
    radial = np.stack([np.cos(theta), np.sin(theta), 0 * theta], axis=1)
    points = (radius * radial + [0.0, 0.0, z]) @ rotation.T
    axis = np.tile([0.0, 0.0, 1.0], (n, 1)) @ rotation.T
    return (
        radius * theta,
        points,
        radial @ rotation.T,
        axis,
        np.full(n, np.pi / 2),
    )


def _band_forces(probe, angles, rotation=np.eye(3)):
    """Normal forces (len(angles), len(DEPTHS)) on the bore's edge at these
    azimuths (rad) of the circle turned by ``rotation``."""
    rows = []
    for angle in angles:
        radial = np.array([np.cos(angle), np.sin(angle), 0.0])
        point = rotation @ (0.030 * radial + [0.0, 0.0, 0.050])
        rows.append(
            [
                probe.normal_force(
                    point, rotation @ radial, rotation[:, 2], depth
                )
                for depth in DEPTHS
            ]
        )
    return np.array(rows)


# On a station, between two and at a quarter of the way round.
ANGLES = [0.0, 0.011, 0.7, np.pi / 2 + 0.004]


@pytest.fixture(scope="module")
def horizontal_probe():
    # stations 1.5 mm apart: not the ring's angles
    return EdgeContactProbe(_circle_stations(1.5e-3), **BAND)


@pytest.fixture(scope="module")
def horizontal_band_forces(horizontal_probe):
    return _band_forces(horizontal_probe, ANGLES)


def test_framed_band_of_the_bore_has_the_rings_force_law(
    horizontal_band_forces,
):
    # The paper's ring: the scenario's 120 segments, 2 pi 30 mm / 120 =
    # 1.57 mm apart.
    ring = measure_normal_force(DEPTHS, hydroelastic_modulus=E, n_theta=120)
    np.testing.assert_allclose(
        horizontal_band_forces, np.tile(ring, (len(ANGLES), 1)), rtol=0.02
    )


def test_band_of_a_circle_in_an_inclined_plane_is_the_same_law(
    horizontal_probe, horizontal_band_forces
):
    R = _rx(np.radians(30.0))
    probe = EdgeContactProbe(_circle_stations(1.5e-3, R), **BAND)
    np.testing.assert_allclose(
        _band_forces(probe, ANGLES, R), horizontal_band_forces, rtol=0.02
    )
    # the whole force turns with the band (the layer's top face pushes the
    # tool along its axis, as the ring's does)
    tip = np.array([0.030 - 0.003 + 5e-4, 0.0, 0.048])
    f = horizontal_probe.contact_force_on_tool(tip, [0.0, 0.0, 1.0])
    np.testing.assert_allclose(
        probe.contact_force_on_tool(R @ tip, R[:, 2]),
        R @ f,
        atol=0.02 * np.linalg.norm(f),
    )


def test_register_compliant_edge_and_part_visual_roles(tmp_path):
    from pydrake.geometry import Role
    from pydrake.multibody.plant import AddMultibodyPlantSceneGraph
    from pydrake.systems.framework import DiagramBuilder
    import trimesh

    from deburr_drake.math.mesh_part import MeshPart

    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, time_step=0.0)
    stations = _circle_stations(3e-3)
    band = dict(BAND, hunt_crossley_dissipation=5.0)
    with pytest.raises(ValueError, match="hunt_crossley_dissipation"):
        register_compliant_edge(
            plant, stations, **dict(band, hunt_crossley_dissipation=-1.0)
        )
    gid = register_compliant_edge(plant, stations, **band)
    box = trimesh.creation.box(extents=[0.1, 0.1, 0.05])
    register_part_visual(
        plant, MeshPart(box, None, np.eye(3), np.zeros(3)), name="part"
    )
    inspector = scene_graph.model_inspector()
    props = inspector.GetProximityProperties(gid)
    assert type(inspector.GetShape(gid)).__name__ == "Mesh"
    assert props.GetProperty("hydroelastic", "hydroelastic_modulus") == E
    assert props.GetProperty("material", "hunt_crossley_dissipation") == 5.0
    world = inspector.world_frame_id()
    (visual,) = inspector.GetGeometries(world, Role.kIllustration)
    assert inspector.GetName(visual) == "part"
    assert inspector.GetProximityProperties(visual) is None
    assert inspector.GetIllustrationProperties(gid) is None
    plant.Finalize()
    with pytest.raises(ValueError, match="Finalize"):
        register_compliant_edge(plant, stations, **band)


def test_a_mesh_edge_is_a_compliant_band_and_the_parts_mesh():
    from pathlib import Path

    from pydrake.systems.framework import DiagramBuilder

    import deburr_drake.cell.plant as cell_plant
    from deburr_drake.config import load_scenario

    example = Path(__file__).parents[2] / "examples" / "tube_stl.yaml"
    scenario = load_scenario(str(example))
    builder = DiagramBuilder()
    plant, scene_graph = cell_plant.add_cell_plant(builder, scenario)
    inspector = scene_graph.model_inspector()
    names = {inspector.GetName(g): g for g in inspector.GetAllGeometryIds()}
    edge = names["part_edge"]
    assert type(inspector.GetShape(edge)).__name__ == "Mesh"
    props = inspector.GetProximityProperties(edge)
    assert props.GetProperty("hydroelastic", "hydroelastic_modulus") == 4.5e6
    assert inspector.GetIllustrationProperties(names["part_visual"])
    assert "tube_edge" not in names
    # the bore's curvature asks for no finer stations than the ring's
    stations, band = cell_plant.mesh_edge_band(scenario)
    spacing = np.diff(stations.arc)
    np.testing.assert_allclose(spacing, 2 * np.pi * 0.027 / 120, rtol=0.02)
    assert band["width"] == scenario.part.edge.wall_thickness
