"""``part.edge.kind: mesh``: the part's file found relative to the scenario
file, and one line naming the field for each thing that is wrong."""

import math
from pathlib import Path
import shutil

import pytest
import trimesh

from deburr_drake.config import ConfigError, load_scenario

PARTS = Path(__file__).resolve().parents[2] / "models" / "parts"
BORE = 2 * math.pi * (0.030 - 0.003)  # the paper's cutter path


@pytest.fixture(scope="module")
def scenario_file(tmp_path_factory):
    folder = tmp_path_factory.mktemp("job")
    (folder / "parts").mkdir()
    shutil.copy(PARTS / "tube.stl", folder / "parts" / "tube.stl")
    path = folder / "tube.yaml"
    path.write_text(
        "base: paper\n"
        "part:\n"
        "  pose: {xyz: [0.0, 0.0, 0.0], rpy: [0.0, 0.0, 0.0]}\n"
        "  edge:\n"
        "    kind: mesh\n"
        "    file: parts/tube.stl\n"
        "    units: mm\n"
        "    near: [0.03, 0.0, 0.05]\n"
        "    tool_rule: right\n"
    )
    return path


def test_the_file_is_found_beside_the_scenario(scenario_file, tmp_path):
    scenario = load_scenario(scenario_file)
    assert scenario.part.edge.file == str(
        scenario_file.parent / "parts/tube.stl"
    )
    length = scenario.part.path_length(scenario.tool)
    assert length == pytest.approx(BORE, rel=1e-6)
    # a scenario elsewhere that starts from it keeps the base's part
    child = tmp_path / "child.yaml"
    child.write_text(
        f"base: {scenario_file}\npart: {{edge: {{direction: -1}}}}\n"
    )
    assert load_scenario(child).part.edge.file == scenario.part.edge.file
    # a bare name not beside the file: a shipped part
    shipped = load_scenario(
        scenario_file, text="part: {edge: {file: tube.stl}}"
    )
    assert shipped.part.edge.mesh_file() == PARTS / "tube.stl"


def _refusal(scenario_file, text):
    with pytest.raises(ConfigError) as refused:
        load_scenario(scenario_file, text=text)
    message = str(refused.value)
    assert "\n" not in message
    return message


@pytest.mark.parametrize(
    "text,starts",
    [
        (
            "part: {edge: {file: missing.stl}}",
            "part.edge.file = 'missing.stl' is invalid",
        ),
        ("part: {edge: {units: ft}}", "part.edge.units = 'ft' is invalid"),
        (
            "part: {edge: {near: [30.0, 0.0, 50.0]}}",
            "part.edge.near = [30.0, 0.0, 50.0]",
        ),
        (
            "part: {edge: {tool_rule: bisector}}",
            "part.edge.tool_rule = 'bisector'",
        ),
        ("part: {pose: {xyz: [0, 0]}}", "part.pose.xyz = [0.0, 0.0] is"),
        (
            "part: {edge: {start_angle: 0.5}}",
            "--scenario-text:1:15: part.edge.start_angle does not apply "
            "to a mesh edge",
        ),
        (  # a tube's radius neither limits the cutter nor is silently kept
            "part: {edge: {inner_radius: 0.001}}",
            "--scenario-text:1:15: part.edge.inner_radius does not apply "
            "to a mesh edge",
        ),
        ("part_error: {yaw: 0.01}", "part_error.yaw = 0.01 is invalid"),
        ("part_error: {radius: 0.001}", "part_error.radius = 0.001 is"),
        ("part_error: {rpy: [0, 0]}", "part_error.rpy = [0.0, 0.0] is invalid"),
        ("part_error: {rpy: [0, 4, 0]}", "part_error.rpy[1] = 4.0 is invalid"),
        (
            "faults: {part_step: {time: 1.0, rpy: [.nan, 0, 0]}}",
            "faults.part_step.rpy[0] = nan is invalid",
        ),
    ],
)
def test_one_line_naming_the_field(scenario_file, text, starts):
    message = _refusal(scenario_file, text)
    assert message.startswith(starts)
    assert "\n" not in message


def test_an_open_mesh_is_refused(scenario_file, tmp_path):
    box = trimesh.creation.box(extents=[0.1, 0.1, 0.1])
    box.update_faces([True] * 11 + [False])
    box.export(tmp_path / "open.stl")
    message = _refusal(
        scenario_file,
        f"part: {{edge: {{file: {tmp_path / 'open.stl'}, units: m}}}}",
    )
    assert message.startswith("part.edge.file = ")
    assert "the mesh is open, not watertight" in message


def test_the_wedge_needs_its_tilt(scenario_file):
    wedge = (
        "part: {edge: {file: wedge.stl, near: [0.04, 0.03, 0.02], "
        "tool_rule: left"
    )
    message = _refusal(scenario_file, wedge + "}}")
    assert message.startswith(
        "part.edge.tilt = 0.0 is invalid: the cutter's side"
    )
    assert "a tilt of -0.5236 rad (-30.0 deg) clears it" in message
    scenario = load_scenario(scenario_file, text=wedge + ", tilt: -0.5236}}")
    length = scenario.part.path_length(scenario.tool)
    assert length == pytest.approx(0.06, rel=1e-6)


def test_registration_while_cutting_is_accepted_on_a_mesh_edge(scenario_file):
    scenario = load_scenario(
        scenario_file, text="localisation: {online: {enabled: true}}"
    )
    assert scenario.localisation.online.enabled
