"""A short job on the shipped block: two holes cut a tenth of the way
round each, with a move between them, simulated as one Diagram."""

import numpy as np
import pytest

from deburr_drake.config import load_scenario
from deburr_drake.config.job import JobEdgeConfig
from deburr_drake.control.sequencer import JOB_COMPLETE, JOB_PHASES

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def job_run():
    """The 15- and 30-degree holes of examples/block_job.yaml, 0.1 of a
    pass each, 10 mm of retract and approach, 2 mm clear: 5 s simulated."""
    from deburr_drake.cell.job_cell import plan_job_cell
    from deburr_drake.runs.job_run import run_job

    scenario = load_scenario("examples/block_job.yaml")
    scenario.job.edges = [JobEdgeConfig(index=10), JobEdgeConfig(index=8)]
    scenario.job.order = "listed"
    scenario.job.retract = scenario.job.approach = 0.01
    scenario.job.clearance = 0.002
    scenario.simulation.stop_after_passes = 0.1
    plan = plan_job_cell(scenario)
    return plan, run_job(plan, duration=20.0)


def test_the_phases_and_the_stop_reason(job_run):
    plan, result = job_run
    log = result.log
    assert [c.index for c in plan.job.cuts] == [10, 8]
    assert log.stop_reason == JOB_COMPLETE and log.completed
    signals = log.signals
    changes = np.flatnonzero(np.diff(signals.phase) != 0) + 1
    sequence = [(JOB_PHASES[signals.phase[0]], 0)] + [
        (JOB_PHASES[signals.phase[i]], int(signals.cut[i])) for i in changes
    ]
    assert sequence == [
        ("cut", 0),
        ("retract", -1),
        ("move", -1),
        ("approach", -1),
        ("cut", 1),
    ]
    assert [e.index for e in log.edges] == [10, 8]
    assert all(e.completed for e in log.edges)
    (move,) = log.moves
    assert move.end_time - move.start_time == pytest.approx(
        move.planned_duration_s, abs=0.01
    )


def test_each_edge_was_cut_by_its_own_process(job_run):
    _, result = job_run
    for edge in result.log.edges:
        process, finish = edge.log["process"], edge.log["finish"]
        moved = process["arc_position"].max() - process["arc_position"].min()
        assert moved > 0.05 * edge.length_m
        assert np.count_nonzero(finish["depth"] > 0) >= 2
        assert (
            np.max(process["f_t"])
            > 0.5 * edge.log.scenario.task.desired_chamfering_force
        )


def test_clear_of_the_part_on_the_move_and_the_estimate_carried(job_run):
    _, result = job_run
    log = result.log
    first, second = log.edges
    moving = ~log.signals.in_phase("cut")
    clearance = log.signals.clearance[moving]
    computed = np.isfinite(clearance)
    assert np.count_nonzero(computed) > 0.2 * computed.size
    assert np.min(clearance[computed]) > 0.0
    assert np.all(np.isnan(log.signals.clearance[~moving]))
    # c-hat carried: the second cut starts from the first's estimate
    np.testing.assert_allclose(
        second.log["estimates"]["value"][0],
        first.log["estimates"]["value"][-1],
        rtol=1e-3,
    )


def test_the_files_written(job_run, tmp_path):
    import json

    from deburr_drake.runs.job_report import job_report, write_job_report

    plan, result = job_run
    report = job_report(result.log, plan.job)
    files = write_job_report(report, result.log, tmp_path, figures=False)
    summary = json.loads((tmp_path / "metrics.json").read_text())
    assert summary["stop_reason"] == JOB_COMPLETE
    assert [e["index"] for e in summary["edges"]] == [10, 8]
    assert all(e["cut_to_end"] for e in summary["edges"])
    assert summary["job"]["min_clearance_m"] > 0.0
    for edge in (10, 8):
        assert (tmp_path / f"edge_{edge}" / "logs.npz").is_file()
        assert edge in files["edges"]
