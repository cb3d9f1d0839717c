"""The plant's truth is the real part: the cutting process
applies force only where the cutter overlaps material, so running off a
straight edge's end cuts nothing, and the contact-lost guard stops the
run."""

import numpy as np
import pytest

from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.cell.process import cutting_force, material_overlap
from deburr_drake.config import ProcessConfig, load_scenario
from deburr_drake.math.geometry import CircularContour, StraightContour
from deburr_drake.runs.simulation import simulate

R = 0.003  # m, cutter radius
LINE = StraightContour(
    [0.0, 0.0, 0.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0], length=0.01
)


def test_a_closed_edge_is_material_everywhere():
    circle = CircularContour(np.zeros(3), 0.027)
    assert material_overlap(circle, 0.5, 5e-4, R) == 1.0


@pytest.mark.parametrize(
    "arc, overlap",
    [
        (0.005, 1.0),  # the middle of the edge
        (0.0, 0.5),  # the cutter's chord half on the wall at its start
        (0.01, 0.5),  # and at its end
        (0.0121, 0.0),  # past the end by more than the half chord (1.73 mm)
        (-0.002, 0.0),
    ],
)
def test_overlap_of_the_cutter_chord_with_a_straight_wall(arc, overlap):
    assert material_overlap(LINE, arc, 5e-4, R) == pytest.approx(
        overlap, abs=1e-9
    )


def test_no_force_off_the_material():
    config = ProcessConfig()
    p = np.array([5e-4, 0.015, 0.0])  # 0.5 mm deep, 5 mm past the end
    force, state = cutting_force(
        config, LINE, p, [0.0, 2.4e-3, 0.0], cut_height=0.002, overlap=0.0
    )
    assert np.all(force == 0.0)
    inside, _ = cutting_force(
        config, LINE, p - [0, 0.01, 0], [0.0, 2.4e-3, 0.0], cut_height=0.002
    )
    assert np.linalg.norm(inside) > 8.0


@pytest.mark.slow
def test_running_off_a_straight_edge_cuts_nothing_and_stops():
    scenario = load_scenario(
        "paper",
        text="""
part: {edge: {kind: straight, length: 0.01}}
process: {burrs: []}
simulation: {stop_after_passes: 0}
guards: {joint_torque_fraction: 1000.0}
""",
    )
    log = simulate(
        make_deburring_diagram(scenario=scenario),
        scenario,
        duration=10.0,
        progress_interval=10.0,
    )
    proc = log["process"]
    # Past the end by more than the cutter chord's half-width at the depth
    # of each sample (the tool plunges once it has no material ahead).
    half_chord = np.sqrt(2 * R * np.maximum(proc["delta"], 0.0))
    off = proc["arc_position"] > 0.01 + half_chord + 1e-4
    assert np.any(off)
    assert np.all(proc["f_t"][off] == 0.0)
    assert np.all(proc["f_threshold"][off] == 0.0)
    assert log.stop_reason == "guard:contact_lost"
    assert log.stop_time < 7.0
    # The finish records nothing beyond the wall.
    assert log["finish"]["depth"][-1] < 1e-3


def test_the_believed_part_is_the_real_one_moved_turned_and_resized():
    from deburr_drake.cell.edge import believed_contour, make_contour

    real = load_scenario("paper")
    assert believed_contour(real).radius == make_contour(real).radius
    wrong = load_scenario(
        "paper",
        text="part_error: {offset: [0.001, 0.0, "
        "0.0], yaw: 0.1, radius: 0.0003}",
    )
    believed, truth = believed_contour(wrong), make_contour(wrong)
    assert believed.radius == pytest.approx(truth.radius + 3e-4)
    np.testing.assert_allclose(
        believed.center - truth.center, [1e-3, 0.0, 0.0], atol=1e-12
    )
    assert wrong.part.pose.xyz == [0.4, 0.0, 0.0]  # the real part stays


@pytest.mark.slow
def test_the_metrics_measure_depth_on_the_real_part():
    """The controller believes the inner radius 0.3 mm larger: it holds
    its (believed) 0.5 mm, the real chamfer is 0.8 mm deep."""
    scenario = load_scenario("paper", text="part_error: {radius: 0.0003}")
    log = simulate(
        make_deburring_diagram(scenario=scenario),
        scenario,
        duration=4.0,
        progress_interval=4.0,
    )
    late = log["process"]["t"] > 3.0
    np.testing.assert_allclose(log["process"]["delta"][late], 8e-4, atol=3e-5)
    late = log["chamfer"]["t"] > 3.0
    np.testing.assert_allclose(log["chamfer"]["delta"][late], 5e-4, atol=3e-5)
    from deburr_drake.runs.pass_metrics import pass_metrics

    values = pass_metrics(log, only_cut=True)
    assert values["chamfer_depth_mean_error_mm"] == pytest.approx(0.3, abs=0.03)


SQUARE_2R = (
    "part: {edge: {kind: profile, vertices: [[-0.03, -0.03], [0.03, -0.03], "
    "[0.03, 0.03], [-0.03, 0.03]], fillet_radius: 0.03}}"
)


def test_truth_is_measured_on_the_body_built_for_the_edge():
    from deburr_drake.cell.truth import contact_normal_force, contact_truth

    tube = load_scenario("paper")
    square = load_scenario("paper", text=SQUARE_2R)
    depths = [2e-4, 5e-4, 8e-4]
    # the square pocket of side 2R with fillets R is the ring: same mesh
    np.testing.assert_allclose(
        contact_normal_force(square, depths, arc_fraction=[0.1, 0.6]),
        contact_normal_force(tube, depths, arc_fraction=[0.1, 0.6]),
        rtol=1e-9,
    )
    pocket = contact_truth(load_scenario("pocket"))
    low, high = pocket.force_range
    # the lines' force at delta*, below the concave fillets'
    line = contact_normal_force(load_scenario("pocket"), [5e-4])[0] + 2.0
    assert low == pytest.approx(line, rel=0.01)
    assert high > 1.1 * low
    # measured where the pass ends: the middle of the right side, a line
    assert pocket.force_at_desired_depth == pytest.approx(line, rel=1e-9)
    boss = contact_truth(load_scenario("boss"))
    # a convex fillet touches less material than a line
    assert boss.force_range[0] < 0.95 * boss.force_range[1]
    assert boss.force_range[1] == pytest.approx(low, rel=0.01)


def test_the_truth_is_measured_once_for_the_same_inputs(tmp_path, monkeypatch):
    from deburr_drake.cell import truth

    scenario = load_scenario("paper")
    measured = truth.contact_truth(scenario, cache_dir=tmp_path)
    assert len(list(tmp_path.glob("*.json"))) == 1

    def measure_again(*args):
        raise AssertionError("measured again for the same inputs")

    monkeypatch.setattr(truth, "_measured_truth", measure_again)
    assert truth.contact_truth(scenario, cache_dir=tmp_path) == measured
    # A file that does not read is measured again, not trusted.
    (cached,) = tmp_path.glob("*.json")
    cached.write_text("{")
    monkeypatch.undo()
    assert truth.contact_truth(scenario, cache_dir=tmp_path) == measured


@pytest.mark.parametrize(
    "change",
    [
        "part: {material: {hydroelastic_modulus: 2.0e7}}",
        "tool: {cutter_radius: 0.0025}",
        "task: {desired_depth: 0.0004}",
        "robot: {model: cartesian_tool}",
    ],
)
def test_a_change_of_part_tool_task_or_robot_measures_again(change):
    from deburr_drake.cell.truth import _truth_key

    assert _truth_key(load_scenario("paper"), 2e-5) != _truth_key(
        load_scenario("paper", text=change), 2e-5
    )


def test_a_change_of_the_package_source_measures_again(monkeypatch):
    from pathlib import Path

    from deburr_drake.cell import truth

    scenario = load_scenario("paper")
    key = truth._truth_key(scenario, 2e-5)
    read = Path.read_bytes

    def edited(path):
        data = read(path)
        return data + b"#" if path.name == "plant.py" else data

    monkeypatch.setattr(Path, "read_bytes", edited)
    assert truth._truth_key(scenario, 2e-5) != key
