"""Gains designed from the robot model (deburr_drake.cell.gains): arm6's
written gains come out of the rules; arm5's differ on x3 only, by the
numbers; a light arm gets gains its sampled loop holds."""

import copy
import math

import numpy as np
import pytest

from deburr_drake.cell.gains import (
    SAMPLED_RATE,
    SLOPE_LIMIT_FRACTION,
    VERTICAL_ERROR,
    apply_gains,
    design_gains,
    feed_loop_damping,
    resolve_design,
    resolve_gains,
    resolve_slope_bound,
    slope_bound,
)
from deburr_drake.cell.robot import loop_numbers
from deburr_drake.config import load_scenario


def test_arm6_gets_its_written_gains():
    scenario = load_scenario("paper_6dof")
    design = design_gains(scenario)
    c = scenario.controller
    assert design.sliding_gain == c.sliding_gain
    assert design.sliding_lambda == c.sliding_lambda
    assert design.orientation_gain == c.orientation_gain
    assert design.orientation_lambda == c.orientation_lambda
    assert design.sliding_scales == pytest.approx(c.fuzzy.sliding_scales)
    assert design.position_scale == c.fuzzy.position_scale
    assert design.max_step == scenario.simulation.max_step
    assert design.numbers["sampled_rate"] == pytest.approx(0.333, abs=0.002)


def test_arm5_differs_on_x3_only_with_the_same_vertical_error_bound():
    scenario = load_scenario("paper")
    design = design_gains(scenario)
    c = scenario.controller
    assert design.sliding_gain[:2] == c.sliding_gain[:2]
    assert design.sliding_lambda[:2] == c.sliding_lambda[:2]
    assert design.orientation_gain == c.orientation_gain
    assert design.sliding_scales == pytest.approx(c.fuzzy.sliding_scales)
    assert design.position_scale == c.fuzzy.position_scale
    assert design.max_step == scenario.simulation.max_step
    assert design.as_fields()["process.implicit_damping"] is False
    # x3: written K lambda = 1500 x 50 = 7.5e4 N/m (0.19 mm under the
    # 13.9 N gravity error), designed 1000 x 100 = 1e5 N/m (0.14 mm): the
    # rule's lambda is x1's, K rounded up to 1000 N s/m.
    assert (c.sliding_gain[2], c.sliding_lambda[2]) == (1500.0, 50.0)
    assert (design.sliding_gain[2], design.sliding_lambda[2]) == (1000.0, 100.0)
    f_z = abs(loop_numbers(scenario)["gravity_error_force"][2])
    assert f_z / (1000.0 * 100.0) < VERTICAL_ERROR
    assert f_z / (1500.0 * 50.0) < VERTICAL_ERROR


def test_a_light_wrist_gets_lower_gains_within_the_sampled_rate():
    """arm6 without its motors' reflected inertia (robot.reflected_inertia
    zero): the rule's gains exceed the sampled rate, the design scales them
    to it."""
    scenario = load_scenario(
        "paper_6dof", text="robot: {reflected_inertia: [0, 0, 0, 0, 0, 0]}"
    )
    before = loop_numbers(scenario)["sampled_rate"]
    design = design_gains(scenario)
    assert before > SAMPLED_RATE
    assert design.numbers["sampled_rate"] <= SAMPLED_RATE + 1e-9
    assert design.numbers["sampled_rate"] > 0.8 * SAMPLED_RATE
    assert design.orientation_gain[0] < 20.0


def test_resolve_designs_the_gains_of_a_file_robot_only_on_a_copy():
    shipped = load_scenario("paper_6dof")
    assert resolve_gains(shipped) == shipped  # written: an equal copy
    auto = load_scenario(
        "paper_6dof",
        text="controller: {design: auto, sliding_gain: [1.0, 1.0, 1.0]}",
    )
    given = copy.deepcopy(auto)
    resolved = resolve_gains(auto)
    assert auto == given
    assert resolved.controller.sliding_gain == shipped.controller.sliding_gain
    assert resolved.controller.design == "written"
    design = design_gains(auto)
    assert apply_gains(auto, design) == resolved and auto == given


def test_slope_bound_designed_from_the_lightest_task_mass():
    """fuzzy.max_slope 0: 0.75 x 2 m / T - K (m the lightest task mass at
    the start pose), in a resolved copy; a given bound is kept."""
    from deburr_drake.cell.robot import loop_numbers

    for name in ("paper", "point_mass"):
        s = load_scenario(name)
        m = loop_numbers(s)["lightest_task_mass"]
        T = s.controller.control_period
        expected = SLOPE_LIMIT_FRACTION * 2 * m / T - 400.0
        assert slope_bound(s) == pytest.approx(expected)
        resolved = resolve_slope_bound(s)
        assert s.controller.fuzzy.max_slope == 0.0
        assert resolved.controller.fuzzy.max_slope == pytest.approx(expected)
        assert slope_bound(resolved) is None  # designed once
        assert resolve_slope_bound(resolved) == resolved
    s = load_scenario("paper")
    s.controller.fuzzy.max_slope = 1234.0
    assert slope_bound(s) is None
    assert resolve_slope_bound(s).controller.fuzzy.max_slope == 1234.0


@pytest.mark.parametrize(
    "name, text",
    [("paper", None), ("paper_6dof", "controller: {design: auto}")],
)
def test_the_design_leaves_the_scenario_it_is_given_as_it_is(name, text):
    scenario = load_scenario(name, text=text)
    given = copy.deepcopy(scenario)
    resolved = resolve_design(scenario)
    assert scenario == given
    assert resolved != scenario  # something was designed
    assert resolve_design(resolved) == resolved
    design_gains(scenario)
    assert scenario == given


def test_the_step_is_lowered_only_for_eq3_between_samples():
    """With process.sample_mean (the default) the cutting damping is exact
    at any step: the design leaves paper's one 2.5 ms step per sample.
    With eq. (3) between samples it keeps g_max h / m below STEP_RATE:
    arm5 (g_max = k_c (0.5 mm x 2 mm + 1 mm x 2 mm) = 9900 N s/m, 7.03 kg)
    two steps per sample."""
    from deburr_drake.cell.gains import STEP_RATE

    scenario = load_scenario("paper")
    assert scenario.simulation.max_step == 0.0025
    assert design_gains(scenario).max_step == 0.0025
    eq3 = load_scenario("paper", text="process: {sample_mean: false}")
    design = design_gains(eq3)
    assert design.max_step == pytest.approx(0.00125)
    g_max = design.numbers["cutting_damping_max_Ns_per_m"]
    mass = design.numbers["lightest_task_mass_kg"]
    assert g_max * design.max_step / mass < STEP_RATE
    assert g_max * 0.0025 / mass > STEP_RATE


def test_feed_loop_damping_of_arm6_by_hand():
    """paper_6dof: K lambda T_c c = 400 x 100 x 0.025 x 10 / 8 = 1250 N s/m,
    k_i = 5000 |nu|^2 x 3.125, M = 1 kg + g tau with g = 3e9 x 0.5 mm x
    2 mm = 3000 N s/m and tau = 1 / (2 pi 10 Hz)."""
    from deburr_drake.cell.edge import believed_contour, start_position
    from deburr_drake.control.controller import make_rule_bases

    scenario = load_scenario("paper_6dof")
    y0 = np.linalg.norm(start_position(scenario, believed_contour(scenario)))
    _, nu = make_rule_bases(scenario.controller)[0].active_rules(y0, 0.0)
    M = 1.0 + 3000.0 / (2 * math.pi * 10.0)
    expected = 1250.0 / (2 * math.sqrt(5000.0 * (nu @ nu) * 3.125 * M))
    assert feed_loop_damping(scenario, mass=1.0) == pytest.approx(expected)
    assert expected == pytest.approx(1.28, abs=0.01)


def test_a_lowered_k_gets_lambda_for_the_feed_loop():
    """Where the sampled rate lowers K on a fuzzy axis, lambda rises so
    that K lambda stays 4e4 N/m (the feed loop's gain K lambda T_c), and
    the design states the loop's damping; arm6's gains are not lowered
    and keep lambda 100."""
    scenario = load_scenario(
        "paper_6dof", text="robot: {reflected_inertia: [0, 0, 0, 0, 0, 0]}"
    )
    design = design_gains(scenario)
    for a in scenario.controller.fuzzy.axes:
        assert design.sliding_gain[a] < 400.0
        K_lambda = design.sliding_gain[a] * design.sliding_lambda[a]
        assert 4.0e4 <= K_lambda < 4.0e4 + 10.0 * design.sliding_gain[a]
    assert design.sliding_lambda[2] == 100.0
    before = feed_loop_damping(
        apply_gains(
            scenario,
            design_with_lambda(design, 100.0),
        ),
        mass=design.numbers["lightest_task_mass_kg"],
    )
    assert design.numbers["feed_loop_damping"] > before
    assert (
        design_gains(load_scenario("paper_6dof")).sliding_lambda == [100.0] * 3
    )


def design_with_lambda(design, lam):
    d = copy.deepcopy(design)
    d.sliding_lambda = [lam] * 3
    return d
