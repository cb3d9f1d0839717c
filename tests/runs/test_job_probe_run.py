"""A short job that probes first: the block off by 0.5 mm and 0.5 degree
about every axis, its bore and a hole cut on the part the probe
registered;
and a job whose first touch finds nothing."""

import json

import numpy as np
import pytest

from deburr_drake.config import load_scenario
from deburr_drake.config.job import JobEdgeConfig
from deburr_drake.control.sequencer import JOB_COMPLETE, JOB_PHASES

pytestmark = pytest.mark.slow


def _scenario(offset, rpy):
    """The bore and the 15-degree hole of examples/block_job.yaml, half
    a pass each, probed with 7 touches (the fewest) and quicker travels
    between them than the defaults (the bore first: the probe is held as
    the first cut's tool, upright)."""
    scenario = load_scenario("examples/block_job.yaml")
    scenario.job.edges = [JobEdgeConfig(index=7), JobEdgeConfig(index=10)]
    scenario.job.order = "listed"
    scenario.job.retract = scenario.job.approach = 0.01
    scenario.job.clearance = 0.002
    scenario.simulation.stop_after_passes = 0.5
    probe = scenario.localisation.probe
    probe.enabled = True
    probe.points = 7
    probe.clear_travel_speed = 0.15
    probe.clear_settle_time = 0.3
    scenario.part_error.offset = offset
    scenario.part_error.rpy = rpy
    return scenario


@pytest.fixture(scope="module")
def probed():
    from deburr_drake.cell.job_cell import plan_job_cell
    from deburr_drake.runs.job_report import job_report
    from deburr_drake.runs.job_run import run_job

    half = 5e-4
    scenario = _scenario(
        [half, -half, half], list(np.radians([0.5, -0.5, 0.5]))
    )
    plan = plan_job_cell(scenario)
    result = run_job(plan, duration=60.0)
    return plan, result, job_report(result.log, plan.job)


def test_the_job_probes_once_then_cuts_both_edges(probed):
    _, result, report = probed
    log = result.log
    assert log.stop_reason == JOB_COMPLETE
    signals = log.signals
    changes = np.flatnonzero(np.diff(signals.phase) != 0) + 1
    phases = [JOB_PHASES[signals.phase[0]]] + [
        JOB_PHASES[signals.phase[i]] for i in changes
    ]
    assert phases == ["probe", "cut", "retract", "move", "approach", "cut"]
    job = report.job
    assert job["probe_touches"] == job["probe_touches_kept"] == 7
    first_cut = signals.t[signals.in_phase("cut")][0]
    assert job["probing_time_s"] == pytest.approx(first_cut, abs=0.01)
    assert 10.0 < job["probing_time_s"] < 40.0
    # The moves stay clear of the part they were planned on.
    assert job["min_clearance_m"] > 0.0


def test_the_registration_finds_the_moved_part(probed):
    _, _, report = probed
    job = report.job
    # Against 0.87 mm and 0.87 degree of error.
    assert job["registration_position_error_mm"] < 0.1
    assert job["registration_orientation_error_deg"] < 0.25


def test_every_edge_is_cut_to_the_depth_on_the_real_part(probed):
    _, result, report = probed
    depth = result.log.scenario.task.desired_depth
    for edge, entry in zip(result.log.edges, report.edges):
        assert entry.values["cut_to_end"]
        bins = np.asarray(edge.log["finish"]["depth"])
        cut = bins[bins > 0]
        assert len(cut) > 0.3 * len(bins)
        # Past the entry's transient (its first quarter), within the
        # depth rule of every pass (RMS error <= 0.05 mm); unregistered,
        # the part's error leaves hundreds of microns.
        steady = cut[len(cut) // 4 : -2]
        rms = float(np.sqrt(np.mean((steady - depth) ** 2)))
        assert rms < 5e-5, (edge.index, rms)


def test_a_touch_that_finds_nothing_ends_the_job_naming_it(tmp_path):
    from deburr_drake.cell.job_cell import plan_job_cell
    from deburr_drake.runs.job_report import job_report, write_job_report
    from deburr_drake.runs.job_run import run_job

    # The block 8 mm lower than believed: the touches on its walls find
    # them lower down; a touch on its top finds nothing within its search
    # (which one depends on what lies below each within its search).
    plan = plan_job_cell(_scenario([0.0, 0.0, -0.008], [0.0, 0.0, 0.0]))
    normals = plan.cell.mesh_probe.touches.normals
    tops = np.flatnonzero(normals[:, 2] > 0.99)
    result = run_job(plan, duration=60.0)
    log = result.log
    missed = log.stop_reason
    assert missed.startswith("probe_missed:")
    top = int(missed.removeprefix("probe_missed:"))
    assert top in tops
    assert f"touch {top} of 7" in log.stop_detail
    assert log.edges == []
    report = job_report(log, plan.job)
    assert report.stop_reason == missed
    assert [e.values["stop"] for e in report.edges] == ["not_reached"] * 2
    assert report.job["probe_touches"] == top
    assert np.isnan(report.job["registration_position_error_mm"])
    assert "probing did not finish" in report.reasons["probing_time_s"]
    written = write_job_report(report, log, tmp_path, figures=False)
    record = json.loads(written["metrics"].read_text())
    assert record["stop_reason"] == missed
    assert record["job"]["registration_orientation_error_deg"] is None
