"""The batch: part errors drawn within their disc, and the cell's learning
(c hat and theta) carried from one part to the next (or not, fresh)."""

import numpy as np
import pytest

from deburr_drake.config import ConfigError, load_scenario
from deburr_drake.runs.batch import (
    CarriedState,
    draw_part_errors,
    run_batch,
    write_batch,
)


def test_part_errors_seeded_within_the_disc():
    a = draw_part_errors(50, seed=3, max_offset=0.001, max_yaw=0.01)
    b = draw_part_errors(50, seed=3, max_offset=0.001, max_yaw=0.01)
    assert a == b
    r = [np.hypot(o[0], o[1]) for o, _ in a]
    assert max(r) <= 0.001 and max(r) > 0.0008
    assert max(abs(y) for _, y in a) <= 0.01
    with pytest.raises(ConfigError, match="max_offset"):
        draw_part_errors(2, seed=0, max_offset=-1.0)


def _short():
    return load_scenario("paper", text="simulation: {duration: 0.3}")


@pytest.mark.parametrize("fresh", [False, True])
def test_batch_carries_the_estimates_and_weights(fresh, tmp_path):
    logs = []
    parts = run_batch(
        _short(),
        count=2,
        seed=1,
        max_offset=0.0002,
        fresh=fresh,
        on_part=lambda p, log: logs.append(log),
    )
    assert [p.part for p in parts] == [1, 2]
    first_end = logs[0]["estimates"]["value"][-1]
    second_start = logs[1]["estimates"]["value"][0]
    initial = np.array(_short().estimator.initial_estimates)
    assert not np.allclose(first_end, initial)  # part 1 learned something
    np.testing.assert_allclose(
        second_start, initial if fresh else first_end, rtol=1e-9
    )
    paths = write_batch(parts, tmp_path)
    assert paths["md"].read_text().count("\n") == 4  # header, rule, 2 parts


def test_carry_estimates_only_and_a_bad_carry():
    logs = []
    run_batch(
        _short(),
        count=2,
        seed=1,
        max_offset=0.0002,
        carry="estimates",
        on_part=lambda p, log: logs.append(log),
    )
    np.testing.assert_allclose(
        logs[1]["estimates"]["value"][0],
        logs[0]["estimates"]["value"][-1],
        rtol=1e-9,
    )
    with pytest.raises(ConfigError, match="carry"):
        run_batch(_short(), count=1, seed=1, max_offset=0.0, carry="some")


def test_carried_weights_set_in_the_next_parts_context():
    from deburr_drake.cell.diagram import make_deburring_diagram

    scenario = _short()
    diagram = make_deburring_diagram(scenario=scenario)
    controller = diagram.GetSubsystemByName("controller")
    context = diagram.CreateDefaultContext()
    theta = np.random.default_rng(0).normal(
        size=controller.theta(controller.GetMyContextFromRoot(context)).shape
    )
    carried = CarriedState(estimates=np.array([1.5, 9000.0, 5.0]), theta=theta)
    carried.set_theta(diagram, context)
    np.testing.assert_allclose(
        controller.theta(controller.GetMyContextFromRoot(context)), theta
    )
    assert carried.apply(scenario).estimator.initial_estimates == [
        1.5,
        9000.0,
        5.0,
    ]
