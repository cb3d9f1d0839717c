"""Scenario loading and validation: typed YAML, one clear error per field."""

import pytest

from deburr_drake.config import (
    ConfigError,
    Scenario,
    load_scenario,
    scenario_names,
    set_field,
)


def test_shipped_scenarios_load_and_validate():
    assert "point_mass" in scenario_names()
    for name in scenario_names():
        scenario = load_scenario(name)
        assert isinstance(scenario, Scenario)
        assert scenario.name == name


def test_overrides_keep_other_defaults():
    scenario = load_scenario(
        "point_mass",
        text="""
controller:
  fuzzy: {order: 0}
task: {desired_depth: 0.0008}
""",
    )
    assert scenario.controller.fuzzy.order == 0
    assert scenario.controller.fuzzy.upsilon == 5
    assert scenario.task.desired_depth == 0.0008
    assert scenario.task.desired_chamfering_force == 10.0


@pytest.mark.parametrize(
    "text, field",
    [
        ("controller: {fuzzy: {order: 4}}", "fuzzy.order"),
        ("controller: {fuzzy: {upsilon: 0}}", "fuzzy.upsilon"),
        (
            "controller: {fuzzy: {dead_zone_half_widths: [0.1, 0.1]}}",
            "fuzzy.dead_zone_half_widths",
        ),
        ("command: {period: 0.0}", "command.period"),
        ("command: {period: -0.025}", "command.period"),
        (
            "controller: {sliding_gain: [1.0, -2.0, 3.0]}",
            "controller.sliding_gain",
        ),
        (
            "estimator: {initial_estimates: [0.01, 4000.0, 20.0]}",
            "estimator.initial_estimates",
        ),
        ("sensor: {cutoff_frequency: 300.0}", "sensor.cutoff_frequency"),
        ("simulation: {integrator: euler}", "simulation.integrator"),
        ("part: {edge: {direction: 2}}", "part.edge.direction"),
        ("part: {edge: {inner_radius: 0.002}}", "tool.cutter_radius"),
        ("process: {implicit_damping: 3}", "process.implicit_damping"),
    ],
)
def test_invalid_values_name_the_field(text, field):
    with pytest.raises(ConfigError, match=field.replace(".", r"\.")):
        load_scenario("point_mass", text=text)


def test_unknown_key_is_an_error():
    with pytest.raises(ConfigError, match="gain_typo"):
        load_scenario("point_mass", text="controller: {gain_typo: 1.0}")


def test_unknown_scenario_lists_the_known_ones():
    with pytest.raises(ConfigError, match="point_mass"):
        load_scenario("no_such_scenario")


def test_wrong_type_is_an_error():
    with pytest.raises(ConfigError):
        load_scenario("point_mass", text="command: {period: fast}")


@pytest.mark.parametrize(
    "text, field, words",
    [
        (
            "part: {edge: {fillet_radius: 0.002}}",
            "part.edge.fillet_radius",
            "larger than tool.cutter_radius",
        ),
        (
            "part: {edge: {vertices: [[0, 0], [0.03, 0.03], [0.03, 0], [0, "
            "0.03]]}}",
            "part.edge.vertices",
            "intersects itself|counter-clockwise",
        ),
        (
            "part: {edge: {vertices: [[0, 0], [0.03, 0], [0.03, 0], [0, "
            "0.03]]}}",
            "part.edge.vertices",
            "coincide",
        ),
        (
            "part: {edge: {vertices: [[-0.03, 0.02], [0.03, 0.02], "
            "[0.03, -0.02], [-0.03, -0.02]]}}",
            "part.edge.vertices",
            "counter-clockwise",
        ),
        (
            "part: {edge: {vertices: [[0, 0], [0.03, 0]]}}",
            "part.edge.vertices",
            "at least 3",
        ),
        (
            "part: {edge: {vertices: [[0, 0], [0.03, 0, 1], [0, 0.03]]}}",
            "part.edge.vertices[1]",
            "2 numbers",
        ),
        (
            "part: {edge: {fillet_radius: 0.03}}",
            "part.edge.vertices",
            "do not fit",
        ),
        ("part: {edge: {side: left}}", "part.edge.side", "inner"),
        (
            "part: {edge: {start_angle: 0.0, vertices: [[0.01, 0.01], "
            "[0.05, 0.01], [0.05, 0.05], [0.01, 0.05]]}}",
            "part.edge.start_angle",
            "meets no point",
        ),
        # a U-shaped pocket around a tongue 8 mm wide: the 5 mm walls on its
        # two sides would overlap
        (
            "part: {edge: {vertices: [[-0.04, -0.02], [0.04, -0.02], "
            "[0.04, 0.02], [0.004, 0.02], [0.004, -0.005], [-0.004, -0.005], "
            "[-0.004, 0.02], [-0.04, 0.02]], fillet_radius: 0.0035}}",
            "part.edge.wall_thickness",
            "overlaps itself",
        ),
        (
            "{part: {edge: {fillet_radius: 0.0035}}, part_error: {radius: "
            "-0.001}}",
            "part_error.radius",
            "larger than the cutter",
        ),
    ],
)
def test_bad_profiles_name_the_field(text, field, words):
    with pytest.raises(ConfigError) as error:
        load_scenario("pocket", text=text)
    message = str(error.value)
    assert message.startswith(field + " = ") or f"{field} = " in message
    assert "\n" not in message
    import re

    assert re.search(words, message), message


def test_shipped_profile_scenarios():
    for name in ("pocket", "boss"):
        scenario = load_scenario(name)
        assert scenario.part.edge.kind == "profile"
        assert len(scenario.part.edge.vertices) == 4


@pytest.mark.parametrize("name", ["paper", "boss", "pocket"])
def test_probe_fits_the_size_by_default_with_the_calibrated_bias(name):
    probe = load_scenario(
        name, text="localisation: {probe: {enabled: true}}"
    ).localisation.probe
    assert probe.fit_radius is True
    # The qualification's mean radius error on the reference ring
    # (docs/localisation.md, The part's real size).
    assert probe.detection_bias == pytest.approx(-10.3e-6)
    assert load_scenario("paper_localised").localisation.probe.fit_radius


def test_probe_detection_bias_within_the_search():
    with pytest.raises(
        ConfigError, match=r"^localisation\.probe\.detection_bias = 0\.01"
    ):
        load_scenario(
            "paper",
            text="localisation: {probe: {enabled: true, detection_bias: 0.01}}",
        )


@pytest.mark.parametrize("value", [0.5, -1.0, float("nan")])
def test_probe_stiffness_threshold_past_the_contact_threshold(value):
    # The stiffness is taken on the way from force_threshold (1 N) on.
    with pytest.raises(
        ConfigError, match=r"^localisation\.probe\.stiffness_threshold = "
    ):
        load_scenario(
            "paper",
            text="localisation: {probe: {enabled: true, "
            f"stiffness_threshold: {value}}}}}",
        )
    probe = load_scenario(
        "paper",
        text="localisation: {probe: {enabled: true, stiffness_threshold: 0}}",
    ).localisation.probe
    assert probe.stiffness_threshold == 0


def _file(tmp_path, text, name="cell.yaml"):
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def test_a_base_file_inherits_every_section_it_does_not_set(tmp_path):
    pocket = load_scenario("pocket")
    loaded = load_scenario(
        _file(
            tmp_path,
            "name: my_pocket\nbase: pocket\n"
            "part: {edge: {vertices: [[-0.02, -0.02], [0.02, -0.02], "
            "[0.02, 0.02], [-0.02, 0.02]]}}\n"
            "process: {burrs: [{center_fraction: 0.3, length: 0.006, "
            "height: 0.0008, thickness: 0.002}]}\n"
            "task: {desired_chamfering_force: 8.0}\n",
        )
    )
    assert loaded.robot == pocket.robot and loaded.robot.model == "arm5"
    assert loaded.controller == pocket.controller
    # A section set in part keeps the base's other fields.
    assert (
        loaded.part.edge.kind == "profile" and loaded.part.edge.side == "inner"
    )
    assert loaded.part.edge.fillet_radius == pocket.part.edge.fillet_radius
    assert loaded.task.desired_depth == pocket.task.desired_depth
    assert loaded.task.desired_chamfering_force == 8.0
    assert loaded.process.cutting_coefficient == (
        pocket.process.cutting_coefficient
    )
    assert len(loaded.process.burrs) == 1


def test_a_base_files_robot_merges_unless_it_names_its_model(tmp_path):
    same_arm = load_scenario(
        _file(
            tmp_path, "base: pocket\nrobot: {friction_smoothing_speed: 0.002}"
        )
    )
    pocket = load_scenario("pocket").robot
    assert same_arm.robot.model == "arm5"
    assert same_arm.robot.joint_coulomb_friction == (
        pocket.joint_coulomb_friction
    )
    assert same_arm.robot.friction_smoothing_speed == 0.002
    # Naming the model describes the arm whole: the base's friction list
    # (five joints of arm5) is not carried to it.
    other = load_scenario(
        _file(
            tmp_path,
            "base: pocket\nrobot: {model: arm6, flange_frame: flange}\n"
            "part: {pose: {xyz: [0.95, 0.0, 0.45]}}",
            "other.yaml",
        )
    )
    assert other.robot.joint_coulomb_friction == []
    assert other.robot.model == "arm6"


def test_a_base_files_relative_robot_model_is_relative_to_the_base(
    tmp_path,
):
    from deburr_drake.config import scenario_path

    folder = tmp_path / "cells"
    folder.mkdir()
    sdf = (
        scenario_path("paper").parents[2] / "models" / "arm6.sdf"
    ).read_text()
    (folder / "my_arm.sdf").write_text(sdf)
    _file(
        folder,
        "base: paper_6dof\nrobot: {model: my_arm.sdf, flange_frame: flange}",
        "base.yaml",
    )
    child = load_scenario(
        _file(tmp_path, "base: cells/base.yaml\ntask: {desired_depth: 4e-4}")
    )
    assert child.robot.model == str((folder / "my_arm.sdf").resolve())


@pytest.mark.parametrize(
    "burr, field, allowed",
    [
        # Written in mm: each size a thousand times too large.
        ("{length: 8, height: 0.001, thickness: 0.002}", "length", "(0, "),
        ("{length: 0.008, height: 1.5, thickness: 0.002}", "height", "[0, "),
        ("{length: 0.008, height: 0.001, thickness: 2}", "thickness", "[0, "),
        ("{length: 8, height: 1.5, thickness: 2}", "length", "m, not mm"),
        # Longer than the bore's path (2 pi 27 mm), taller than the cutter
        # above the edge (18 mm), thicker than the wall (5 mm).
        ("{length: 0.2}", "length", "0.169646] m"),
        ("{height: 0.019}", "height", "0.018] m"),
        ("{thickness: 0.006}", "thickness", "0.005] m"),
    ],
)
def test_a_burr_larger_than_the_part_or_the_tool_is_one_line(
    burr, field, allowed
):
    with pytest.raises(ConfigError) as e:
        load_scenario("paper", text=f"process: {{burrs: [{burr}]}}")
    message = str(e.value)
    assert message.startswith(f"process.burrs[0].{field} = ")
    assert "\n" not in message and allowed in message


def test_a_burr_as_long_as_a_straight_edge_fits_and_longer_does_not():
    text = (
        "part: {edge: {kind: straight, length: 0.05}}\nprocess: {burrs: [%s]}"
    )
    load_scenario("paper", text=text % "{center_fraction: 0.5, length: 0.05}")
    with pytest.raises(ConfigError, match=r"burrs\[0\].length = 0.051"):
        load_scenario("paper", text=text % "{length: 0.051}")


@pytest.mark.parametrize(
    "text, field",
    [
        ("part: {edge: {start_vertex: 0}}", "part.edge.start_vertex"),
        ("part: {edge: {start_fraction: 0.5}}", "part.edge.start_fraction"),
        ("part: {edge: {vertices: [[0, 0], [1, 0], [0, 1]]}}", "vertices"),
        ("part: {edge: {kind: circle, file: tube.stl}}", "part.edge.file"),
    ],
)
def test_a_field_of_another_kind_is_refused_by_its_full_name(text, field):
    """A field the circle edge would ignore: one line naming it with its
    place in the text, and what a circle edge takes."""
    with pytest.raises(ConfigError) as e:
        load_scenario("paper", text=text)
    message = str(e.value)
    assert f"{field.split('.')[-1]} does not apply to a circle edge" in message
    assert message.startswith("--scenario-text:1:")
    assert "part.edge.kind circle: kind, inner_radius" in message
    assert "\n" not in message


def test_a_kind_chosen_later_takes_its_own_fields():
    """A file's edge fields are checked against the kind that file gives:
    a profile over the circle of its base takes a start vertex, and a
    circle's radius over the pocket's profile is refused."""
    pocket = load_scenario(
        "paper",
        text="part: {edge: {kind: profile, side: inner, start_vertex: 1, "
        "vertices: [[-0.03, -0.02], [0.03, -0.02], [0.03, 0.02], "
        "[-0.03, 0.02]]}}",
    )
    assert pocket.part.edge.start_vertex == 1
    with pytest.raises(ConfigError, match="inner_radius does not apply to a"):
        load_scenario("pocket", text="part: {edge: {inner_radius: 0.025}}")


@pytest.mark.parametrize(
    "text, replacement",
    [
        ("tube: {inner_radius: 0.02}", "write part: {pose: {xyz: "),
        ("edge: {start_angle: 0.1}", "write it as part: {edge: {...}}"),
        ("edge: {pose: {xyz: [0, 0, 0]}}", "edge.pose as part.pose"),
    ],
)
def test_the_tube_only_form_is_refused_naming_the_new_one(
    tmp_path, text, replacement
):
    """A file in the tube-only form (top-level tube:, edge:) is refused,
    one line saying what to write, before anything is built."""
    path = tmp_path / "old.yaml"
    path.write_text("base: paper\n" + text + "\n")
    with pytest.raises(ConfigError) as e:
        load_scenario(path)
    message = str(e.value)
    assert message.startswith(f"{path}:2:1: ")
    assert "is the tube-only form" in message and replacement in message
    assert "\n" not in message


def test_set_field_takes_the_part_paths_and_names_the_old_ones():
    scenario = load_scenario("paper")
    set_field(scenario, "part.edge.inner_radius", 0.025)
    set_field(scenario, "part.pose.xyz[1]", 0.01)
    set_field(scenario, "part.material.hydroelastic_modulus", 5e6)
    assert scenario.part.edge.inner_radius == 0.025
    assert scenario.part.pose.xyz == [0.4, 0.01, 0.0]
    assert scenario.part.material.hydroelastic_modulus == 5e6
    with pytest.raises(ConfigError, match="write 'part.pose.xyz\\[0\\]'"):
        set_field(scenario, "tube.position[0]", 0.3)
    with pytest.raises(ConfigError, match="vertices does not apply to a c"):
        set_field(scenario, "part.edge.vertices", [[0, 0], [1, 0], [0, 1]])


@pytest.mark.parametrize(
    "text, message",
    [
        (
            "part: {edge: {start_vertex: 4}}",
            "part.edge.start_vertex = 4 is invalid",
        ),
        (
            "part: {edge: {start_fraction: 1.0}}",
            "part.edge.start_fraction = 1.0",
        ),
        (
            "part: {edge: {start_vertex: 1, start_fraction: 0.2}}",
            r"part.edge.start_fraction = 0.2 is invalid: allowed -1 while",
        ),
        (
            "part: {edge: {start_vertex: 1, start_angle: 0.5}}",
            "part.edge.start_angle = 0.5 is invalid: allowed 0 while "
            "part.edge.start_vertex",
        ),
    ],
)
def test_one_start_of_a_profile(text, message):
    with pytest.raises(ConfigError, match=message):
        load_scenario("pocket", text=text)
    load_scenario("pocket", text="part: {edge: {start_vertex: 3}}")


def test_a_scenario_written_back_whole_reads_again(tmp_path):
    """The run's scenario.yaml gives every edge field: those of other
    kinds at their defaults pass, and a base's circle radius under a mesh
    edge is dropped on loading, not written back."""
    from pydrake.common.yaml import yaml_dump_typed

    for name in ("paper", "pocket"):
        path = tmp_path / f"{name}.yaml"
        path.write_text(yaml_dump_typed(load_scenario(name)))
        assert load_scenario(path) == load_scenario(name)
    mesh = load_scenario(
        "paper",
        text="part: {edge: {kind: mesh, file: tube.stl, units: mm, "
        "near: [0.03, 0.0, 0.05]}}",
    )
    assert mesh.part.edge.inner_radius == 0.030  # paper's, now unused
    with pytest.raises(ConfigError, match="inner_radius does not apply"):
        load_scenario(
            "paper",
            text="part: {edge: {kind: mesh, file: tube.stl, units: mm, "
            "near: [0.03, 0.0, 0.05], inner_radius: 0.02}}",
        )
