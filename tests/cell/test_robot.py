"""Bring your own robot (deburr_drake.cell.robot): the shipped 6-DOF arm
(models/arm6.sdf) and its spindle, the one-line errors of a model the cell
cannot use, a user's model file outside the package, and a short closed
loop of the paper_6dof scenario."""

import re
import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.cell.models import models_dir
from deburr_drake.cell.reach import check_part_in_reach
from deburr_drake.cell.robot import (
    check_robot,
    loop_numbers,
    make_robot_model,
    robot_joints,
)
from deburr_drake.config import (
    ConfigError,
    RobotConfig,
    ToolMountConfig,
    load_scenario,
    scenario_path,
)
from deburr_drake.control.layout import CHAMFER_STATE
from deburr_drake.math import metrics
from deburr_drake.runs.simulation import make_simulator, simulate

ARM6_JOINTS = ("a1", "a2", "a3", "a4", "a5", "a6")


def _arm6(**fields):
    return RobotConfig(**{"model": "arm6", "flange_frame": "flange", **fields})


def test_arm6_is_a_6dof_arm_with_drives_masses_and_limits():
    plant = check_robot(_arm6())
    joints = robot_joints(plant)
    assert tuple(j.name() for j in joints) == ARM6_JOINTS
    assert plant.num_actuators() == 6
    ns = "{http://drake.mit.edu}"
    root = ET.parse(models_dir() / "arm6.sdf").getroot()
    for joint in root.iter("joint"):
        if joint.get("type") != "revolute":
            continue
        actuator = plant.GetJointActuatorByName(joint.get("name"))
        rotor = float(joint.find(f"{ns}rotor_inertia").text)
        gear = float(joint.find(f"{ns}gear_ratio").text)
        assert (
            actuator.default_rotor_inertia() == pytest.approx(rotor)
            and rotor > 0
        )
        assert (
            actuator.default_gear_ratio() == pytest.approx(gear)
            and 50 <= gear <= 200
        )
        assert actuator.effort_limit() == pytest.approx(
            float(joint.find("axis/limit/effort").text)
        )
        assert float(joint.find("axis/dynamics/damping").text) > 0
    for joint in joints:
        assert (
            joint.position_lower_limits()[0]
            < 0
            < joint.position_upper_limits()[0]
        )
        assert 2.0 <= joint.velocity_upper_limits()[0] <= 11.0
    links = [plant.GetBodyByName(f"link{i}") for i in range(1, 7)]
    masses = np.array([b.default_mass() for b in links])
    assert np.all(masses > 0)
    # A 16 kg payload class arm: about 140 kg moving, 210 kg with the base.
    assert 120 <= masses.sum() <= 160
    for body in links:  # physically valid inertias (triangle inequality)
        I = body.default_rotational_inertia().CopyToFullMatrix3()
        d = np.diag(I)
        assert np.all(d > 0) and np.all(d.sum() - 2 * d >= -1e-9)


def test_the_spindle_hangs_from_the_flange_on_the_sensor_weld():
    plant = make_robot_model(_arm6(tool_length=0.12, tool_mass=1.5))
    context = plant.CreateDefaultContext()
    tool = plant.GetBodyByName("tool")
    assert tool.default_mass() == pytest.approx(1.5)
    sensor = plant.GetJointByName("ft_sensor")
    assert (
        sensor.num_velocities() == 0
        and sensor.child_body().index() == tool.index()
    )
    X_WF = plant.GetFrameByName("flange").CalcPoseInWorld(context)
    X_WT = plant.GetFrameByName("tool_tip").CalcPoseInWorld(context)
    flange_z = X_WF.rotation().matrix()[:, 2]
    np.testing.assert_allclose(
        X_WT.translation(), X_WF.translation() + 0.12 * flange_z, atol=1e-12
    )
    np.testing.assert_allclose(
        X_WT.rotation().matrix()[:, 2], -flange_z, atol=1e-12
    )


def test_the_tool_mount_turns_and_offsets_the_spindle_on_the_flange():
    """robot.tool_mount is the spindle's pose in the flange frame (URDF's
    roll, pitch, yaw): pitched a quarter turn, the tool points along the
    flange's +x, from the mount's offset."""
    xyz = [0.01, -0.02, 0.03]
    mounted = _arm6(
        tool_length=0.12,
        tool_mount=ToolMountConfig(xyz=xyz, rpy=[0.0, np.pi / 2, 0.0]),
    )
    plant = make_robot_model(mounted)
    context = plant.CreateDefaultContext()
    X_WF = plant.GetFrameByName("flange").CalcPoseInWorld(context)
    X_WT = plant.GetFrameByName("tool_tip").CalcPoseInWorld(context)
    R_WF = X_WF.rotation().matrix()
    np.testing.assert_allclose(
        X_WT.translation(),
        X_WF.translation() + R_WF @ (np.array(xyz) + [0.12, 0.0, 0.0]),
        atol=1e-12,
    )
    np.testing.assert_allclose(
        X_WT.rotation().matrix()[:, 2], -R_WF[:, 0], atol=1e-12
    )


def test_a_tool_mount_on_a_model_holding_its_own_tool_is_one_line():
    with pytest.raises(ConfigError, match=r"^robot.tool_mount = .*flange"):
        RobotConfig(
            model="arm5", tool_mount=ToolMountConfig(rpy=[0.0, 1.0, 0.0])
        ).validate()
    with pytest.raises(ConfigError, match=r"robot.tool_mount.rpy\[1\]"):
        _arm6(tool_mount=ToolMountConfig(rpy=[0.0, np.nan, 0.0])).validate()


def test_loop_numbers_give_the_gravity_error_and_the_sampled_rate():
    """The numbers paper_6dof's gains are derived from (its comments)."""
    arm5 = loop_numbers(load_scenario("paper"))
    arm6 = loop_numbers(load_scenario("paper_6dof"))
    np.testing.assert_allclose(
        arm5["gravity_error_force"], [3.94, 0.0, -13.91], atol=0.01
    )
    np.testing.assert_allclose(
        arm6["gravity_error_force"], [25.84, 0.0, -69.17], atol=0.01
    )
    assert arm6["gravity_error_moment"][1] == pytest.approx(7.18, abs=0.01)
    assert arm5["sampled_rate"] == pytest.approx(0.30, abs=0.005)
    assert arm6["sampled_rate"] == pytest.approx(0.33, abs=0.005)
    assert arm6["lightest_task_mass"] == pytest.approx(5.9, abs=0.05)
    # The vertical error of the PD axis: 69 N / (4000 x 100) N/m.
    assert arm6["static_error"][2] == pytest.approx(-69.17 / 4e5, rel=1e-3)


def _one_line_error(config_or_call, field):
    with pytest.raises(ConfigError) as info:
        config_or_call()
    message = str(info.value)
    assert "\n" not in message and message.startswith(field), message
    return message


def test_a_missing_model_file_is_one_line():
    _one_line_error(
        RobotConfig(model="/no/such/arm.urdf").validate, "robot.model"
    )
    _one_line_error(RobotConfig(model="arm7").validate, "robot.model")


def test_a_missing_frame_lists_the_frames_there_are():
    message = _one_line_error(
        lambda: check_robot(_arm6(flange_frame="tool0")), "robot.flange_frame"
    )
    assert "'flange'" in message and "'link6'" in message
    _one_line_error(
        lambda: check_robot(RobotConfig(model="arm6")), "robot.tool_frame"
    )
    _one_line_error(
        lambda: check_robot(RobotConfig(model="arm5", sensor_joint="sensor")),
        "robot.sensor_joint",
    )


def test_wrong_lengths_of_the_per_joint_lists_are_one_line():
    _one_line_error(
        lambda: check_robot(_arm6(joint_coulomb_friction=[1.0] * 5)),
        "robot.joint_coulomb_friction",
    )
    _one_line_error(
        lambda: check_robot(_arm6(ik_seed=[0.0] * 5)), "robot.ik_seed"
    )


def _arm_file(tmp_path, n_joints):
    """arm6.sdf cut down to its first n_joints joints, flange on the last
    link."""
    tree = ET.parse(models_dir() / "arm6.sdf")
    model = tree.getroot().find("model")
    keep = {f"link{i}" for i in range(1, n_joints + 1)} | {"base"}
    for child in list(model):
        name = child.get("name")
        if child.tag == "link" and name not in keep:
            model.remove(child)
        if child.tag == "joint" and child.find("child").text not in keep:
            model.remove(child)
        if child.tag == "frame":
            child.set("attached_to", f"link{n_joints}")
            child.find("pose").set("relative_to", f"link{n_joints}")
    path = tmp_path / f"arm{n_joints}.sdf"
    tree.write(path)
    return path


def _urdf_of_arm6(path, *, transmissions=True, world_joint=True):
    """models/arm6.sdf written as URDF (inertias, joints, limits, damping,
    drives; no visuals): its links are parallel to the model frame at q = 0, so
    a joint's origin is the child's position less the parent's."""
    ns = "{http://drake.mit.edu}"
    model = ET.parse(models_dir() / "arm6.sdf").getroot().find("model")
    position = {"world": np.zeros(3)}
    out = [
        '<?xml version="1.0"?>',
        '<robot name="arm6" xmlns:drake="http://drake.mit.edu">',
    ]
    for link in model.findall("link"):
        name = link.get("name")
        position[name] = np.array(link.find("pose").text.split(), float)[:3]
        inertial = link.find("inertial")
        com = " ".join(inertial.find("pose").text.split()[:3])
        I = {
            k: inertial.find(f"inertia/{k}").text for k in ("ixx", "iyy", "izz")
        }
        out.append(
            f'<link name="{name}"><inertial><origin xyz="{com}"/>'
            f'<mass value="{inertial.find("mass").text}"/>'
            f'<inertia ixx="{I["ixx"]}" iyy="{I["iyy"]}" izz="{I["izz"]}" '
            'ixy="0" ixz="0" iyz="0"/></inertial></link>'
        )
    for joint in model.findall("joint"):
        name, kind = joint.get("name"), joint.get("type")
        parent, child = joint.find("parent").text, joint.find("child").text
        if parent == "world" and not world_joint:
            continue
        xyz = " ".join(f"{v:.6g}" for v in position[child] - position[parent])
        text = (
            f'<joint name="{name}" type="{kind}"><parent link="{parent}"/>'
            f'<child link="{child}"/><origin xyz="{xyz}"/>'
        )
        if kind == "revolute":
            limit = {
                k: joint.find(f"axis/limit/{k}").text
                for k in ("lower", "upper", "effort", "velocity")
            }
            damping = joint.find("axis/dynamics/damping").text
            text += (
                f'<axis xyz="{joint.find("axis/xyz").text}"/>'
                f'<limit lower="{limit["lower"]}" upper="{limit["upper"]}" '
                f'effort="{limit["effort"]}" velocity="{limit["velocity"]}"/>'
                f'<dynamics damping="{damping}"/>'
            )
            if transmissions:
                rotor = joint.find(ns + "rotor_inertia").text
                gear = joint.find(ns + "gear_ratio").text
                out.append(
                    f'<transmission name="{name}_drive"><type>'
                    "transmission_interface/SimpleTransmission</type>"
                    f'<joint name="{name}"><hardwareInterface>'
                    "EffortJointInterface</hardwareInterface></joint>"
                    f'<actuator name="{name}_motor">'
                    f'<drake:rotor_inertia value="{rotor}"/>'
                    f'<drake:gear_ratio value="{gear}"/>'
                    "</actuator></transmission>"
                )
        out.append(text + "</joint>")
    frame = model.find("frame")
    xyz_rpy = frame.find("pose").text.split()
    out.append('<link name="flange"/>')
    out.append(
        '<joint name="flange_mount" type="fixed">'
        f'<parent link="{frame.get("attached_to")}"/>'
        f'<child link="flange"/><origin xyz="{" ".join(xyz_rpy[:3])}" '
        f'rpy="{" ".join(xyz_rpy[3:])}"/></joint>'
    )
    path.write_text("\n".join(out + ["</robot>"]))
    return path


def test_a_urdf_arm_is_the_same_arm(tmp_path):
    """arm6 as a user's URDF: the same joints, drives, kinematics and mass
    matrix as the shipped SDF; without its <transmission>s, one line."""
    # As many URDFs are: no joint to the world (the base is welded at the
    # origin).
    urdf = RobotConfig(
        model=str(_urdf_of_arm6(tmp_path / "arm6.urdf", world_joint=False)),
        flange_frame="flange",
    )
    plant, shipped = check_robot(urdf), make_robot_model(_arm6())
    assert [j.name() for j in robot_joints(plant)] == list(ARM6_JOINTS)
    q = np.array([0.3, 0.5, 0.4, -0.7, 0.8, 1.1])
    frames, mass = [], []
    for p in (plant, shipped):
        context = p.CreateDefaultContext()
        p.SetPositions(context, q)
        frames.append(
            p.GetFrameByName("tool_tip").CalcPoseInWorld(context).GetAsMatrix4()
        )
        mass.append(p.CalcMassMatrix(context))
        drives = {
            p.get_joint_actuator(i).joint().name(): p.get_joint_actuator(i)
            for i in p.GetJointActuatorIndices()
        }
        assert drives["a2"].default_reflected_inertia() == pytest.approx(
            185**2 * 2.4e-4
        )
        assert drives["a6"].effort_limit() == pytest.approx(70.0)
    np.testing.assert_allclose(frames[0], frames[1], atol=1e-12)
    np.testing.assert_allclose(mass[0], mass[1], rtol=1e-9, atol=1e-9)
    # Without <transmission>s each joint gets a drive at its effort limit
    # (tests/cell/test_description.py); a joint without an effort limit
    # gets none, which is one line.
    path = _urdf_of_arm6(tmp_path / "bare.urdf", transmissions=False)
    bare = RobotConfig(model=str(path), flange_frame="flange")
    assert check_robot(bare).num_actuators() == 6
    path.write_text(
        re.sub(r'effort="[^"]+"', 'effort="0"', path.read_text(), count=1)
    )
    assert "have no actuator" in _one_line_error(
        lambda: check_robot(bare), "robot.model"
    )


def _arm7_file(tmp_path):
    """arm6 with a seventh joint: a second flange roll a7, coaxial with a6
    (a redundant arm whose null space is a6 - a7)."""
    text = (models_dir() / "arm6.sdf").read_text()
    flange = text[
        text.index(
            '    <frame name="flange" attached_to="link6">'
        ) : text.index('    <joint name="base_weld"')
    ]
    link7 = """<link name="link7"><pose>1.088 0 1.39 0 0 0</pose>
      <inertial><pose>0.01 0 0 0 0 0</pose><mass>0.3</mass><inertia>
      <ixx>3.04e-4</ixx><iyy>1.62e-4</iyy><izz>1.62e-4</izz>
      <ixy>0</ixy><ixz>0</ixz><iyz>0</iyz></inertia>
      </inertial></link>
    <joint name="a7" type="revolute"><parent>link6</parent><child>link7</child>
      <axis><xyz expressed_in="__model__">1 0 0</xyz>
      <limit><lower>-6.1</lower><upper>6.1</upper>
      <effort>70</effort><velocity>10.7</velocity></limit>
      <dynamics><damping>1.0</damping>
      </dynamics></axis><drake:rotor_inertia>3.0e-5</drake:rotor_inertia>
      <drake:gear_ratio>80</drake:gear_ratio></joint>
    <frame name="flange" attached_to="link7">
      <pose relative_to="link7">0.02 0 0 0 1.5707963267948966 0</pose></frame>
"""
    path = tmp_path / "arm7.sdf"
    path.write_text(
        text.replace(flange, link7).replace(
            '<model name="arm6">', '<model name="arm7">'
        )
    )
    return path


def test_a_redundant_arm_holds_its_posture_in_the_null_space(tmp_path):
    path = _arm7_file(tmp_path)
    scenario = load_scenario(
        "paper_6dof",
        text=(
            f"robot: {{model: {path}, "
            "ik_seed: [0.0, 0.45, 0.5, 0.0, 0.6, 0.0, 0.0], "
            "joint_coulomb_friction: [10.0, 8.0, 2.5, 0.12, 0.12, 0.04, 0.04]}"
        ),
    )
    joints = [j.name() for j in robot_joints(check_robot(scenario.robot))]
    assert sorted(joints) == sorted(ARM6_JOINTS + ("a7",))
    a6, a7 = joints.index("a6"), joints.index("a7")  # position order
    diagram = make_deburring_diagram(scenario=scenario)
    plant = diagram.GetSubsystemByName("plant")
    simulator = make_simulator(diagram, scenario)
    context = simulator.get_mutable_context()
    plant_context = plant.GetMyMutableContextFromRoot(context)
    q0 = plant.GetPositions(plant_context).copy()
    # Turn a6 and a7 0.05 rad apart: the tool does not move, only the
    # null-space posture term brings them back (joint friction holds them
    # otherwise).
    q = q0.copy()
    q[a6] += 0.05
    q[a7] -= 0.05
    plant.SetPositions(plant_context, q)
    simulator.AdvanceTo(1.5)
    q = plant.GetPositions(plant_context)
    assert np.all(np.isfinite(q))
    # From 0.1 rad apart; without the posture term friction keeps them there.
    null = (q - q0)[a6] - (q - q0)[a7]
    assert abs(null) < 0.01, q - q0
    chamfer = (
        diagram.GetSubsystemByName("chamfer_observer")
        .GetOutputPort("chamfer_state")
        .Eval(
            diagram.GetSubsystemContext(
                diagram.GetSubsystemByName("chamfer_observer"), context
            )
        )
    )
    assert CHAMFER_STATE.get(chamfer, "f_n") > 2.0  # in contact


def test_fewer_than_five_actuated_joints_is_one_line(tmp_path):
    path = _arm_file(tmp_path, 4)
    message = _one_line_error(
        lambda: check_robot(
            RobotConfig(model=str(path), flange_frame="flange")
        ),
        "robot.model",
    )
    assert "4 actuated joints" in message


def test_a_part_out_of_reach_is_one_line():
    scenario = load_scenario(
        "paper_6dof", text="part: {pose: {xyz: [2.5, 0.0, 0.45]}}"
    )
    message = _one_line_error(
        lambda: check_part_in_reach(scenario), "part.pose.xyz"
    )
    assert "beyond the nearest reachable" in message


def test_the_cli_says_a_bad_robot_in_one_line_and_runs_nothing(tmp_path):
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "deburr_drake.cli",
            "simulate",
            "--scenario",
            "paper_6dof",
            "--scenario-text",
            "robot: {flange_frame: tool0}",
            "--out",
            str(tmp_path / "out"),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "robot.flange_frame" in lines[0], result.stderr
    assert not (tmp_path / "out").exists()


def _user_scenario(tmp_path):
    """paper_6dof as a user writes it: the model copied into their own
    package (package.xml, a mesh it names by package://), the scenario
    beside it naming the model by a relative path."""
    package = tmp_path / "my_cell" / "my_arms"
    (package / "meshes").mkdir(parents=True)
    (package / "package.xml").write_text(
        '<?xml version="1.0"?><package format="2"><name>my_arms</name>'
        "<version>0.0.1</version><description>a user arm</description>"
        '<maintainer email="u@example.com">u</maintainer>'
        "<license>BSD</license></package>"
    )
    (package / "meshes" / "cover.obj").write_text(
        "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\n"
        "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
    )
    sdf = (
        (models_dir() / "arm6.sdf")
        .read_text()
        .replace(
            '<visual name="carousel">',
            '<visual name="cover"><geometry><mesh><uri>package://my_arms/meshes/cover.obj</uri>'
            '</mesh></geometry></visual>\n      <visual name="carousel">',
        )
    )
    (package / "my_arm.sdf").write_text(sdf)
    text = scenario_path("paper_6dof").read_text()
    assert "  model: arm6\n" in text
    text = text.replace("  model: arm6\n", "  model: my_arms/my_arm.sdf\n")
    text = text.replace("name: paper_6dof", "name: my_cell")
    path = tmp_path / "my_cell" / "cell.yaml"
    path.write_text(text)
    return path


def test_a_user_model_file_outside_the_package_runs_in_contact(tmp_path):
    path = _user_scenario(tmp_path)
    scenario = load_scenario(str(path), text="simulation: {duration: 1.5}")
    assert scenario.robot.model == str(path.parent / "my_arms" / "my_arm.sdf")
    assert str(models_dir()) not in scenario.robot.model
    check_part_in_reach(scenario)
    log = simulate(make_deburring_diagram(scenario=scenario), scenario)
    ch = log["chamfer"]
    assert not metrics.any_nan(
        *[v for b in log.signals.values() for v in b.values()]
    )
    t_contact = metrics.first_time(ch["t"], ch["f_n"] > 1.0)
    assert t_contact < 0.5
    assert np.all(ch["f_n"][metrics.window(ch["t"], t_contact + 0.5)] > 2.0)


@pytest.mark.slow
def test_paper_6dof_converges_in_a_short_run():
    scenario = load_scenario("paper_6dof")
    log = simulate(
        make_deburring_diagram(scenario=scenario), scenario, duration=4.0
    )
    ch = log["chamfer"]
    late = metrics.window(ch["t"], 3.0)
    assert np.max(np.abs(ch["delta"][late] - 5e-4)) < 2e-5
    cmd = log["command"]
    feed = metrics.window(cmd["t"], 2.0)
    assert (
        2.0e-3
        < metrics.mean_speed(cmd["t"][feed], cmd["arc_position"][feed])
        < 2.8e-3
    )
    process = log["process"]
    settled = metrics.window(process["t"], 2.0)
    assert np.mean(process["f_t"][settled]) == pytest.approx(10.0, abs=1.0)
    assert not metrics.any_nan(
        *[v for b in log.signals.values() for v in b.values()]
    )
