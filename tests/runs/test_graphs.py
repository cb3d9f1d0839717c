"""GraphViz export: every system and port named as the builder names them;
rendering with dot, or one clear line when dot is missing."""

import shutil

import pytest

from deburr_drake.config import ConfigError
from deburr_drake.runs import graphs


@pytest.fixture(scope="module")
def diagram(paper_cell):
    return paper_cell()[1]


def test_graph_names_every_system_and_port(diagram, tmp_path):
    written, message = graphs.write_graphs(diagram, tmp_path / "cell.dot")
    assert message is None
    text = (tmp_path / "cell.dot").read_text()
    for name in (
        "command_generator",
        "first_order_hold",
        "contact_estimator",
        "controller",
        "plant",
        "scene_graph",
        "cutting_process",
        "force_sensor",
        "chamfer_observer",
        "cutting_force",
    ):
        assert f"name={name}" in text, name
    for port in (
        "chamfer_state",
        "desired_normal_force",
        "commanded_position",
        "force_law_terms",
        "generalized_force",
        "tool_force",
    ):
        assert port in text, port
    controller = (tmp_path / "cell_controller.dot").read_text()
    assert "name=controller" in controller and "actuation" in controller
    assert [p.name for p in written] == ["cell.dot", "cell_controller.dot"]


@pytest.mark.skipif(
    shutil.which("dot") is None, reason="GraphViz's dot is not installed"
)
@pytest.mark.parametrize("fmt", ["svg", "png"])
def test_renders_with_dot(diagram, tmp_path, fmt):
    written, message = graphs.write_graphs(
        diagram, tmp_path / "cell", fmt=fmt, max_depth=1
    )
    assert message is None
    for name in (f"cell.{fmt}", f"cell_controller.{fmt}"):
        assert (tmp_path / name).stat().st_size > 1000


def test_missing_dot_says_so_and_keeps_the_dot_file(
    diagram, tmp_path, monkeypatch
):
    monkeypatch.setattr(graphs.shutil, "which", lambda name: None)
    written, message = graphs.write_graphs(
        diagram, tmp_path / "cell", fmt="svg"
    )
    assert "apt-get install graphviz" in message
    assert (tmp_path / "cell.dot").exists()
    assert not (tmp_path / "cell.svg").exists()


def test_bad_format(diagram, tmp_path):
    with pytest.raises(ConfigError, match="format"):
        graphs.write_graphs(diagram, tmp_path / "cell", fmt="pdf")
