"""Scenario loading and validation: typed YAML, one clear error per field."""

import pytest

from deburr_drake.config import (
    ConfigError,
    Scenario,
    load_scenario,
    scenario_names,
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
        ("edge: {direction: 2}", "edge.direction"),
        ("tube: {inner_radius: 0.002}", "tool.cutter_radius"),
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
            "edge: {fillet_radius: 0.002}",
            "edge.fillet_radius",
            "larger than tool.cutter_radius",
        ),
        (
            "edge: {vertices: [[0, 0], [0.03, 0.03], [0.03, 0], [0, 0.03]]}",
            "edge.vertices",
            "intersects itself|counter-clockwise",
        ),
        (
            "edge: {vertices: [[0, 0], [0.03, 0], [0.03, 0], [0, 0.03]]}",
            "edge.vertices",
            "coincide",
        ),
        (
            "edge: {vertices: [[-0.03, 0.02], [0.03, 0.02], [0.03, -0.02], "
            "[-0.03, -0.02]]}",
            "edge.vertices",
            "counter-clockwise",
        ),
        (
            "edge: {vertices: [[0, 0], [0.03, 0]]}",
            "edge.vertices",
            "at least 3",
        ),
        (
            "edge: {vertices: [[0, 0], [0.03, 0, 1], [0, 0.03]]}",
            "edge.vertices[1]",
            "2 numbers",
        ),
        ("edge: {fillet_radius: 0.03}", "edge.vertices", "do not fit"),
        ("edge: {side: left}", "edge.side", "inner"),
        (
            "edge: {start_angle: 0.0, vertices: [[0.01, 0.01], [0.05, 0.01], "
            "[0.05, 0.05], [0.01, 0.05]]}",
            "edge.start_angle",
            "meets no point",
        ),
        # a U-shaped pocket around a tongue 8 mm wide: the 5 mm walls on its
        # two sides would overlap
        (
            "edge: {vertices: [[-0.04, -0.02], [0.04, -0.02], [0.04, 0.02], "
            "[0.004, 0.02], [0.004, -0.005], [-0.004, -0.005], [-0.004, 0.02], "
            "[-0.04, 0.02]], fillet_radius: 0.0035}",
            "tube.wall_thickness",
            "overlaps itself",
        ),
        (
            "{edge: {fillet_radius: 0.0035}, part_error: {radius: -0.001}}",
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
        assert scenario.edge.kind == "profile"
        assert len(scenario.edge.vertices) == 4


@pytest.mark.parametrize("name", ["boss", "pocket"])
def test_probe_fit_radius_only_on_a_circle(name):
    text = "localisation: {probe: {enabled: true, fit_radius: true}}"
    with pytest.raises(
        ConfigError,
        match=r"^localisation\.probe\.fit_radius"
        r" = True is invalid: allowed false on a profile",
    ):
        load_scenario(name, text=text)
    load_scenario("paper", text=text)
