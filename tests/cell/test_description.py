"""A robot description package as the cell reads it
(deburr_drake.cell.description): packages by folder name, visual meshes
converted, collision geometry left out, drives for joints without a
transmission, joints past the flange welded, and what ROS tools read but
Drake refuses repaired (a material defined twice, a mimic on a fixed joint,
transmissions Drake cannot use)."""

from importlib import metadata
from pathlib import Path
import xml.etree.ElementTree as ET

import numpy as np
from pydrake.geometry import Role
from pydrake.multibody.parsing import Parser
from pydrake.multibody.plant import AddMultibodyPlantSceneGraph, MultibodyPlant
from pydrake.systems.framework import DiagramBuilder
import pytest
from test_robot import _urdf_of_arm6
import trimesh

from deburr_drake.cell.description import (
    add_packages,
    convert_mesh,
    model_path,
)
from deburr_drake.cell.edge import make_contour
from deburr_drake.cell.reach import check_part_in_reach
from deburr_drake.cell.robot import add_robot, check_robot, robot_joints
from deburr_drake.config import ConfigError, RobotConfig, load_scenario


def _geometries(config):
    builder = DiagramBuilder()
    plant, scene_graph = AddMultibodyPlantSceneGraph(builder, 0.0)
    add_robot(plant, config)
    plant.Finalize()
    inspector = scene_graph.model_inspector()
    ids = inspector.GetAllGeometryIds()
    roles = {
        role: [g for g in ids if inspector.GetProperties(g, role) is not None]
        for role in (Role.kIllustration, Role.kProximity)
    }
    return plant, inspector, roles


def _package(tmp_path, *, xml_name="not_the_folder_name"):
    """A description package laid out as pip wheels ship them: folder
    ``my_arm_data`` (the name the URIs use) whose package.xml names another
    package; an STL and a DAE visual, an STL collision mesh."""
    share = tmp_path / "share"
    root = share / "my_arm_data"
    (root / "meshes").mkdir(parents=True)
    (root / "package.xml").write_text(
        f'<?xml version="1.0"?><package format="3"><name>{xml_name}</name>'
        "<version>1.0.0</version><description>d</description>"
        '<maintainer email="m@example.com">m</maintainer>'
        "<license>BSD</license></package>"
    )
    box = trimesh.creation.box([0.1, 0.1, 0.2])
    box.export(str(root / "meshes" / "link3.stl"))
    box.export(str(root / "meshes" / "link5.dae"))
    box.export(str(root / "meshes" / "collision.STL"))
    urdf = _urdf_of_arm6(root / "arm6.urdf", world_joint=False)
    text = urdf.read_text()
    uri = "package://my_arm_data/meshes"
    for link, mesh in (("link3", "link3.stl"), ("link5", "link5.dae")):
        text = text.replace(
            f'<link name="{link}"><inertial>',
            f'<link name="{link}"><visual><geometry>'
            f'<mesh filename="{uri}/{mesh}"/></geometry></visual>'
            f'<collision><geometry><mesh filename="{uri}/collision.STL"/>'
            "</geometry></collision><inertial>",
        )
    urdf.write_text(text)
    return share, urdf


def test_a_package_resolves_by_folder_name_whose_package_xml_says_otherwise(
    tmp_path,
):
    share, _ = _package(tmp_path)
    config = RobotConfig(
        model="package://my_arm_data/arm6.urdf",
        package_paths=[str(share)],
        flange_frame="flange",
    )
    plant, inspector, roles = _geometries(config)
    assert [j.name() for j in robot_joints(plant)] == [
        "a1",
        "a2",
        "a3",
        "a4",
        "a5",
        "a6",
    ]
    # robot.packages names a package's folder directly.
    named = RobotConfig(
        model="package://arm/arm6.urdf",
        packages={
            "arm": str(share / "my_arm_data"),
            "my_arm_data": str(share / "my_arm_data"),
        },
        flange_frame="flange",
    )
    assert check_robot(named).num_positions() == 6


def test_an_unknown_package_is_one_line_naming_it_and_where_it_was_looked_for(
    tmp_path,
):
    share, urdf = _package(tmp_path)
    config = RobotConfig(
        model=str(urdf), flange_frame="flange"
    )  # no package folders
    with pytest.raises(ConfigError) as e:
        check_robot(config)
    message = str(e.value)
    assert "\n" not in message
    assert "package 'my_arm_data' is unknown" in message
    assert "robot.package_paths" in message and "ROS_PACKAGE_PATH" in message


def _meshes(share):
    """The package's arm: its visual meshes and its geometries by role."""
    config = RobotConfig(
        model="package://my_arm_data/arm6.urdf",
        package_paths=[str(share)],
        flange_frame="flange",
    )
    plant, inspector, roles = _geometries(config)
    meshes = [
        g
        for g in roles[Role.kIllustration]
        if type(inspector.GetShape(g)).__name__ == "Mesh"
    ]
    return inspector, meshes, roles


def test_stl_and_dae_visuals_are_converted_and_collisions_left_out(tmp_path):
    share, _ = _package(tmp_path)
    inspector, meshes, roles = _meshes(share)
    # Two converted meshes (plus the spindle's cylinder); no collision geometry.
    assert len(meshes) == 2
    assert roles[Role.kProximity] == []
    for g in meshes:
        path = str(inspector.GetShape(g).source().path())
        assert path.endswith(".obj")
        converted = trimesh.load(path, force="mesh")
        np.testing.assert_allclose(
            converted.extents, [0.1, 0.1, 0.2], atol=1e-9
        )


def test_a_mesh_that_cannot_be_converted_is_dropped_with_one_warning(
    tmp_path, capsys
):
    share, _ = _package(tmp_path)
    (share / "my_arm_data" / "meshes" / "link5.dae").write_text("not a mesh")
    _, meshes, _ = _meshes(share)
    assert len(meshes) == 1
    warnings = [
        line
        for line in capsys.readouterr().err.splitlines()
        if "link5.dae" in line
    ]
    assert len(warnings) == 1 and "dropped" in warnings[0]


def test_conversion_is_done_once(tmp_path):
    source = tmp_path / "part.stl"
    trimesh.creation.box([1, 2, 3]).export(str(source))
    first = convert_mesh(source, tmp_path / "cache")
    stamp = first.stat().st_mtime_ns
    assert convert_mesh(source, tmp_path / "cache") == first
    assert first.stat().st_mtime_ns == stamp
    with pytest.raises(ValueError):
        bad = tmp_path / "bad.stl"
        bad.write_bytes(b"\x00" * 10)
        convert_mesh(bad, tmp_path / "cache")


def _with_gripper(path):
    """arm6's URDF without transmissions, with a two-finger gripper past
    the flange (prismatic fingers, the second mimicking the first, and 0
    outside one finger's limits) and a joint beside it (on link6, off the
    chain to the flange)."""
    text = path.read_text()
    gripper = """
<link name="hand"><inertial><mass value="0.5"/>
  <inertia ixx="1e-3" iyy="1e-3" izz="1e-3" ixy="0" ixz="0" iyz="0"/>
</inertial></link>
<joint name="hand_mount" type="fixed"><parent link="flange"/>
  <child link="hand"/></joint>
<link name="finger1"><inertial><mass value="0.05"/>
  <inertia ixx="1e-5" iyy="1e-5" izz="1e-5" ixy="0" ixz="0" iyz="0"/>
</inertial></link>
<link name="finger2"><inertial><mass value="0.05"/>
  <inertia ixx="1e-5" iyy="1e-5" izz="1e-5" ixy="0" ixz="0" iyz="0"/>
</inertial></link>
<joint name="finger_joint1" type="prismatic"><parent link="hand"/>
  <child link="finger1"/><origin xyz="0 0 0.05"/><axis xyz="0 1 0"/>
  <limit effort="100" lower="0.01" upper="0.04" velocity="0.2"/></joint>
<joint name="finger_joint2" type="prismatic"><parent link="hand"/>
  <child link="finger2"/><origin xyz="0 0 0.05"/><axis xyz="0 -1 0"/>
  <limit effort="100" lower="0.0" upper="0.04" velocity="0.2"/>
  <mimic joint="finger_joint1"/></joint>
<link name="side"><inertial><mass value="0.05"/>
  <inertia ixx="1e-5" iyy="1e-5" izz="1e-5" ixy="0" ixz="0" iyz="0"/>
</inertial></link>
<joint name="side_joint" type="revolute"><parent link="link6"/>
  <child link="side"/><axis xyz="0 0 1"/>
  <limit effort="10" lower="-1" upper="1" velocity="1"/></joint>
</robot>"""
    path.write_text(text.replace("</robot>", gripper))
    return path


def test_a_urdf_without_transmissions_gets_drives_and_its_fingers_are_welded(
    tmp_path, capsys
):
    path = _with_gripper(
        _urdf_of_arm6(tmp_path / "bare.urdf", transmissions=False)
    )
    config = RobotConfig(model=str(path), flange_frame="flange")
    plant = check_robot(config)
    joints = robot_joints(plant)
    assert [j.name() for j in joints] == ["a1", "a2", "a3", "a4", "a5", "a6"]
    assert plant.num_actuators() == 6
    limits = {
        j.get("name"): float(j.find("limit").get("effort"))
        for j in ET.parse(path).getroot().findall("joint")
        if j.find("limit") is not None
    }
    for i in plant.GetJointActuatorIndices():
        actuator = plant.get_joint_actuator(i)
        assert actuator.effort_limit() == pytest.approx(
            limits[actuator.joint().name()]
        )
    # finger1 welded at its lower limit (0 is outside [0.01, 0.04]), finger2 at
    # 0.
    context = plant.CreateDefaultContext()
    X_1 = plant.GetFrameByName("finger1").CalcPoseInWorld(context)
    X_2 = plant.GetFrameByName("finger2").CalcPoseInWorld(context)
    X_H = plant.GetFrameByName("hand").CalcPoseInWorld(context)
    offset = X_H.rotation().inverse() @ (X_1.translation() - X_2.translation())
    np.testing.assert_allclose(offset, [0.0, 0.01, 0.0], atol=1e-12)
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if "get a drive" in line]
    assert len(lines) == 1 and "'a1'" in lines[0] and "finger" not in lines[0]
    welded = [line for line in err.splitlines() if "welded" in line]
    assert len(welded) == 1
    assert all(
        name in welded[0]
        for name in ("finger_joint1", "finger_joint2", "side_joint")
    )


def test_reflected_inertia_sets_the_drives_rotor_inertia(tmp_path):
    path = _urdf_of_arm6(tmp_path / "bare.urdf", transmissions=False)
    inertia = [1.0, 2.0, 0.5, 0.1, 0.1, 0.05]
    plant = check_robot(
        RobotConfig(
            model=str(path), flange_frame="flange", reflected_inertia=inertia
        )
    )
    by_joint = {
        plant.get_joint_actuator(i).joint().name(): plant.get_joint_actuator(i)
        for i in plant.GetJointActuatorIndices()
    }
    for k, value in enumerate(inertia):
        assert by_joint[
            f"a{k + 1}"
        ].default_reflected_inertia() == pytest.approx(value)
    with pytest.raises(ConfigError, match="robot.reflected_inertia"):
        check_robot(
            RobotConfig(
                model=str(path),
                flange_frame="flange",
                reflected_inertia=[1.0, 2.0],
            )
        )


def test_pip_package_folders_and_a_missing_distribution(tmp_path):
    with pytest.raises(ConfigError) as e:
        RobotConfig(
            model="arm6", package_paths=["pip:no-such-dist-xyz/share"]
        ).validate()
    assert "robot.package_paths[0]" in str(
        e.value
    ) and "pip install no-such-dist-xyz" in str(e.value)
    scenario = tmp_path / "cell.yaml"
    (tmp_path / "pkgs").mkdir()
    scenario.write_text(
        "name: c\nbase: paper_6dof\nrobot: {model: arm6, flange_frame: flange,"
        " package_paths: [pkgs]}\n"
    )
    loaded = load_scenario(str(scenario))
    assert loaded.robot.package_paths == [str((tmp_path / "pkgs").resolve())]
    # base: the part and the task of paper_6dof, the robot's own section.
    assert loaded.part.pose.xyz == [0.95, 0.0, 0.45]
    assert loaded.robot.joint_coulomb_friction == []


def _has_example_robot_data():
    try:
        metadata.distribution("example-robot-data")
        return True
    except metadata.PackageNotFoundError:
        return False


needs_erd = pytest.mark.skipif(
    not _has_example_robot_data(),
    reason="example-robot-data is not installed (the test extra)",
)


@needs_erd
@pytest.mark.parametrize(
    "urdf, flange, joints",
    [
        ("ur_description/urdf/ur10_robot.urdf", "tool0", 6),
        ("panda_description/urdf/panda.urdf", "panda_link8", 7),
        ("xarm_description/urdf/xarm7.urdf", "link7", 7),
    ],
)
def test_example_robot_data_arms_load(urdf, flange, joints):
    config = RobotConfig(
        model=f"package://example-robot-data/robots/{urdf}",
        package_paths=["pip:example-robot-data/cmeel.prefix/share"],
        flange_frame=flange,
    )
    plant = check_robot(config)
    assert len(robot_joints(plant)) == joints == plant.num_actuators()


_Z1 = """
name: z1_cell
base: paper_6dof
robot:
  model: package://example-robot-data/robots/z1_description/urdf/z1.urdf
  package_paths: ["pip:example-robot-data/cmeel.prefix/share"]
  flange_frame: link06
controller: {design: auto}
part: {pose: {xyz: [0.35, 0.0, 0.0]}}
"""

#: Unitree Z1's link06 points its tool along +x: the mount that says so.
_Z1_MOUNT = "robot: {tool_mount: {rpy: [0.0, 1.5707963, 0.0]}}"


@needs_erd
def test_a_flange_pointing_its_tool_along_x_names_the_tool_mount(tmp_path):
    from deburr_drake.cell.reach import check_part_in_reach

    path = tmp_path / "z1.yaml"
    path.write_text(_Z1)
    with pytest.raises(ConfigError) as e:
        check_part_in_reach(load_scenario(str(path)))
    message = str(e.value)
    assert message.startswith("robot.tool_mount = ") and "\n" not in message
    assert "the tool axis, not the distance" in message
    assert "along +x of the flange frame" in message
    assert "every point of the path" in message
    check_part_in_reach(load_scenario(str(path), text=_Z1_MOUNT))


@needs_erd
@pytest.mark.slow
def test_a_flange_along_x_with_its_tool_mount_cuts(tmp_path):
    """Z1 with the mount, designed gains, 4 s of paper_6dof: in contact,
    at the desired depth, no guard."""
    from deburr_drake.cell.diagram import make_deburring_diagram
    from deburr_drake.cell.gains import resolve_design
    from deburr_drake.math import metrics
    from deburr_drake.runs.simulation import simulate

    path = tmp_path / "z1.yaml"
    path.write_text(_Z1)
    scenario = resolve_design(load_scenario(str(path), text=_Z1_MOUNT))
    log = simulate(
        make_deburring_diagram(scenario=scenario), scenario, duration=4.0
    )
    assert log.stop_reason == "duration"
    ch = log["chamfer"]
    t_contact = metrics.first_time(ch["t"], ch["f_n"] > 1.0)
    assert t_contact < 0.5
    late = metrics.window(ch["t"], 2.0)
    assert np.max(np.abs(ch["delta"][late] - 5e-4)) < 3e-5


@needs_erd
def test_a_tool_turned_onto_a_wrist_singularity_starts_away_from_it():
    """The UR5 with its tool along the flange's x: the posture nearest the
    seed puts two wrist axes in line (conditioning 4e-9, a gravity error
    of 5.6e7 N at the tool); the start pose is the nearest one away from
    it, and the design's numbers are the arm's."""
    from deburr_drake.cell.arm import MIN_CONDITIONING, tool_conditioning
    from deburr_drake.cell.reach import check_part_in_reach
    from deburr_drake.cell.robot import (
        loop_numbers,
        make_robot_model,
        start_pose,
    )

    example = Path(__file__).parents[2] / "examples" / "ur5_cell.yaml"
    scenario = load_scenario(
        str(example),
        text="robot: {tool_mount: {rpy: [0, 1.5707963, 0]}}",
    )
    check_part_in_reach(scenario)
    q = start_pose(scenario)
    plant = make_robot_model(scenario.robot)
    frame = plant.GetFrameByName(scenario.robot.tool_frame)
    c = tool_conditioning(
        plant,
        q,
        instance=frame.model_instance(),
        tool_frame=scenario.robot.tool_frame,
    )
    assert c > MIN_CONDITIONING
    numbers = loop_numbers(scenario, q)
    assert np.linalg.norm(numbers["gravity_error_force"]) < 100.0
    assert numbers["lightest_task_mass"] > 0.5


def _diffuse(inspector, geometry):
    props = inspector.GetProperties(geometry, Role.kIllustration)
    return list(props.GetProperty("phong", "diffuse").rgba)


def test_a_material_defined_twice_keeps_its_first_definition(tmp_path, capsys):
    """Two robot-level definitions of a name (same colour, then different
    colours), as two xacro files composed give: Drake refuses the file, the
    prepared copy keeps each name's first definition and says so."""
    path = _urdf_of_arm6(tmp_path / "materials_twice.urdf")
    grey = '<material name="grey"><color rgba="0.5 0.5 0.5 1"/></material>'
    red = '<material name="red"><color rgba="{}"/></material>'
    box = '<visual><geometry><box size="0.05 0.05 0.05"/></geometry>'
    text = (
        path.read_text()
        .replace(
            '<link name="link3">',
            f'<link name="link3">{box}<material name="red"/></visual>',
        )
        .replace(
            '<link name="link5">',
            f'<link name="link5">{box}<material name="grey"/></visual>',
        )
    )
    materials = grey + red.format("0.8 0 0 1") + grey + red.format(".2 .2 .9 1")
    text = text.replace(
        'xmlns:drake="http://drake.mit.edu">',
        'xmlns:drake="http://drake.mit.edu">' + materials,
        1,
    )
    path.write_text(text)
    plant = MultibodyPlant(0.0)
    with pytest.raises(RuntimeError, match="previously defined"):
        Parser(plant).AddModels(str(path))

    _, inspector, roles = _geometries(
        RobotConfig(model=str(path), flange_frame="flange")
    )
    colours = {
        inspector.GetName(inspector.GetFrameId(g)).split("::")[-1]: _diffuse(
            inspector, g
        )
        for g in roles[Role.kIllustration]
        if inspector.GetShape(g).__class__.__name__ == "Box"
    }
    np.testing.assert_allclose(colours["link3"], [0.8, 0.0, 0.0, 1.0])
    np.testing.assert_allclose(colours["link5"], [0.5, 0.5, 0.5, 1.0])
    lines = [
        line
        for line in capsys.readouterr().err.splitlines()
        if "materials_twice.urdf" in line and "material " in line
    ]
    assert lines == [
        "deburr-drake: robot.model materials_twice.urdf: material 'grey' "
        "defined twice (same colour): kept the first",
        "deburr-drake: robot.model materials_twice.urdf: material 'red' "
        "defined twice (different colours: rgba 0.8 0 0 1 kept, rgba 0.2 "
        "0.2 0.9 1 dropped, as urdfdom does for a name a visual defines "
        "again): kept the first",
    ]


_TALOS_ARM = (
    "package://example-robot-data/robots/talos_data/robots/talos_left_arm.urdf"
)


@needs_erd
def test_an_arm_cut_from_a_whole_robots_file_parses_after_preparation(capsys):
    """Talos's left arm: fixed gripper joints with a <mimic>, a transmission
    of the shoulder joint the file does not have and a differential wrist
    transmission. Drake refuses the file as shipped."""
    config = RobotConfig(
        model=_TALOS_ARM,
        package_paths=["pip:example-robot-data/cmeel.prefix/share"],
        flange_frame="wrist_left_ft_tool_link",
    )
    plant = MultibodyPlant(0.0)
    parser = Parser(plant)
    add_packages(parser.package_map(), config)
    with pytest.raises(RuntimeError, match="cannot mimic"):
        parser.AddModels(str(model_path(parser.package_map(), config)))

    plant = check_robot(config)
    joints = [j.name() for j in robot_joints(plant)]
    assert joints == [f"arm_left_{k}_joint" for k in range(2, 8)]
    driven = {
        plant.get_joint_actuator(i).joint().name(): plant.get_joint_actuator(
            i
        ).effort_limit()
        for i in plant.GetJointActuatorIndices()
    }
    assert set(driven) == set(joints)
    assert driven["arm_left_6_joint"] == driven["arm_left_7_joint"] == 6.6
    err = capsys.readouterr().err.splitlines()
    said = [line for line in err if "talos_left_arm.urdf" in line]
    assert sum("<mimic> removed from 6 fixed joint(s)" in s for s in said) == 1
    assert (
        sum("{'arm_left_1_trans': ['arm_left_1_joint']}" in s for s in said)
        == 1
    )
    assert (
        sum(
            "1 transmission(s) of a type Drake does not model" in s
            and "{'wrist_left_trans': ('DifferentialTransmission', "
            "['arm_left_6_joint', 'arm_left_7_joint'])}"
            in s
            for s in said
        )
        == 1
    )
    assert not any("WARNING:drake" in line and "mimic" in line for line in err)


@needs_erd
def test_the_talos_arm_example_reaches_its_whole_edge():
    """examples/talos_arm_cell.yaml: the tool mounted along the gripper
    reaches every point of the edge with the tool vertical."""
    examples = Path(__file__).resolve().parents[2] / "examples"
    scenario = load_scenario(str(examples / "talos_arm_cell.yaml"))
    check_part_in_reach(scenario, make_contour(scenario))
