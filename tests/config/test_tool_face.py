"""``part.edge.tool_face``: the tool stands on the face whose outward normal is
nearest a direction of the part frame, whichever way the edge's chain
runs; one line when the direction names neither face or tool_rule also
picks one. ``part.edge.start_near``: the pass starts at the edge's point
nearest a part-frame point."""

import numpy as np
import pytest

from deburr_drake.cell.edge import make_contour
from deburr_drake.config import ConfigError, load_scenario

TUBE = (
    "base: paper\n"
    "part:\n"
    "  pose: {xyz: [0.4, 0.0, 0.0], rpy: [0.0, 0.0, 0.0]}\n"
    "  edge:\n"
    "    kind: mesh\n"
    "    file: tube.stl\n"
    "    units: mm\n"
    "    near: [0.03, 0.0, 0.05]\n"
)


@pytest.fixture(scope="module")
def tube_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("job") / "tube.yaml"
    path.write_text(TUBE)
    return path


def _axis(scenario):
    contour = make_contour(scenario)
    return contour.tool_axis_at(0.3 * contour.length)


def test_the_face_looking_up_is_the_top_face_either_way(tube_file):
    for direction in (1, -1):
        scenario = load_scenario(
            tube_file,
            text=(
                f"part: {{edge: {{tool_face: [0, 0, 1], direction: "
                f"{direction}}}}}"
            ),
        )
        np.testing.assert_allclose(_axis(scenario), [0, 0, 1], atol=1e-6)
    # the part turned on its side: the face is named in the part's frame
    turned = load_scenario(
        tube_file,
        text="part: {edge: {tool_face: [0, 0, 1]}, pose: {xyz: [0.4, 0, 0.1], "
        "rpy: [1.5707963, 0, 0]}}",
    )
    np.testing.assert_allclose(_axis(turned), [0, -1, 0], atol=1e-6)


def test_left_and_right_still_pick_by_the_chains_direction(tube_file):
    right = load_scenario(tube_file, text="part: {edge: {tool_rule: right}}")
    np.testing.assert_allclose(_axis(right), [0, 0, 1], atol=1e-6)
    # left is the bore's wall: the tool would lie across the bore, its
    # spindle in the far wall; refused for that, not for reach
    with pytest.raises(
        ConfigError, match=r"^part.edge.tool_rule = 'left' is invalid: "
    ) as refused:
        load_scenario(tube_file, text="part: {edge: {tool_rule: left}}")
    assert "the spindle stands in the part" in str(refused.value)
    assert "reach" not in str(refused.value)


def test_the_default_on_a_bore_is_the_bores_axis(tube_file):
    """Neither tool_rule nor tool_face: the bore's rim is a loop round a
    cylindrical wall, so the tool stands along its axis, out of the part,
    whichever way the pass runs."""
    for direction in (1, -1):
        scenario = load_scenario(
            tube_file, text=f"part: {{edge: {{direction: {direction}}}}}"
        )
        rule = scenario.part.edge.mesh_rule(scenario.part.pose)
        assert rule.kind == "axis"
        np.testing.assert_allclose(_axis(scenario), [0, 0, 1], atol=1e-6)


@pytest.mark.parametrize(
    "text,starts",
    [
        (
            "part: {edge: {tool_face: [1, 0, 0]}}",
            "part.edge.tool_face = [1.0, 0.0, 0.0] is",
        ),
        (
            "part: {edge: {tool_face: [0, 0, 0]}}",
            "part.edge.tool_face = [0.0, 0.0, 0.0] is",
        ),
        (
            "part: {edge: {tool_face: [0, 1]}}",
            "part.edge.tool_face = [0.0, 1.0] is",
        ),
        (
            "part: {edge: {tool_face: [0, 0, 1], tool_rule: right}}",
            "part.edge.tool_rule = 'right' is invalid",
        ),
    ],
)
def test_one_line_naming_the_field(tube_file, text, starts):
    with pytest.raises(ConfigError) as refused:
        load_scenario(tube_file, text=text)
    message = str(refused.value)
    assert "\n" not in message
    assert message.startswith(starts), message


def test_the_pass_starts_at_the_point_nearest_start_near(tube_file):
    scenario = load_scenario(
        tube_file,
        text=(
            "part: {edge: {start_near: [0.0, 0.03, 0.05], tool_face: [0, 0, "
            "1]}}"
        ),
    )
    start = make_contour(scenario).point_at(0.0)
    np.testing.assert_allclose(start, [0.4, 0.027, 0.048], atol=1e-6)
    with pytest.raises(
        ConfigError, match=r"^part.edge.start_fraction = 0.2 is"
    ):
        load_scenario(
            tube_file,
            text=(
                "part: {edge: {start_near: [0.0, 0.03, 0.05], "
                "start_fraction: 0.2}}"
            ),
        )
