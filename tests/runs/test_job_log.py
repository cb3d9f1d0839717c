"""The job log: per edge a pass log cut to its edge, the job's signals and
moves, built from synthetic job signals over a real pass's loggers."""

from types import SimpleNamespace

import numpy as np
import pytest

from deburr_drake.control.sequencer import JOB_COMPLETE, JOB_PHASE
from deburr_drake.runs.job_log import (
    FINAL_BLOCKS,
    EdgeSource,
    JobSignals,
    edge_window,
    make_job_log,
    slice_signals,
)
from deburr_drake.runs.pass_metrics import pass_metrics


def _job_signals(t, split=(3.5, 4.0)):
    """Cut 0 before split[0], a move to split[1], cut 1 after."""
    phase = np.where(
        t < split[0],
        JOB_PHASE["cut"],
        np.where(t < split[1], JOB_PHASE["move"], JOB_PHASE["cut"]),
    )
    cut = np.where(t < split[0], 0, np.where(t < split[1], -1, 1))
    return JobSignals(t=t, q=np.zeros((len(t), 6)), phase=phase, cut=cut)


def _sources(log, completed=(True, False)):
    shared = {k: v for k, v in log.signals.items() if k not in FINAL_BLOCKS}
    final = {k: log.signals[k] for k in FINAL_BLOCKS}
    edges = [
        EdgeSource(
            index=k,
            point=np.zeros(3),
            length_m=0.1,
            scenario=log.scenario,
            process=log["process"],
            final=final,
            completed=done,
        )
        for k, done in enumerate(completed)
    ]
    return shared, edges


def test_each_edge_log_is_a_pass_log_of_its_cut(paper_log):
    t = paper_log["chamfer"]["t"]
    signals = _job_signals(t)
    shared, sources = _sources(paper_log)
    move = SimpleNamespace(duration_s=1.0, travel_m=0.05, min_clearance_m=0.01)
    job = make_job_log(
        paper_log.scenario,
        sources,
        shared,
        signals,
        [move],
        stop_reason="guard:force",
        stop_time=float(t[-1]),
        stop_detail="f_n above the limit",
    )
    assert [e.position for e in job.edges] == [0, 1]
    first, second = job.edges
    # Each log holds the same loggers and blocks as the pass's.
    for edge in job.edges:
        assert edge.log.signals.keys() == paper_log.signals.keys()
        for name, blocks in paper_log.signals.items():
            assert edge.log[name].keys() == blocks.keys()
    # Cut to its window and counted from its start.
    assert first.start_time == t[0] and first.end_time < 3.5
    assert second.start_time >= 4.0 and second.end_time == t[-1]
    for edge in job.edges:
        assert edge.log["chamfer"]["t"][0] == pytest.approx(0.0)
        assert edge.log["process"]["t"][-1] == pytest.approx(
            edge.end_time - edge.start_time
        )
    n = np.count_nonzero(signals.cut == 1)
    assert len(second.log["controller"]["e_f"]) == n
    # The first completed; the second ended with the job.
    assert first.completed and first.log.stop_reason == "pass_complete"
    assert not second.completed
    assert second.log.stop_reason == "guard:force"
    assert second.log.stop_detail == "f_n above the limit"
    # The pass metrics read it as a pass.
    values = pass_metrics(first.log, only_cut=True)
    assert np.isfinite(values["chamfering_force_rms_error_N"])
    # The move between them.
    (moved,) = job.moves
    assert moved.after == 0 and moved.planned_min_clearance_m == 0.01
    assert first.end_time < moved.start_time < moved.end_time
    assert moved.end_time < second.start_time
    assert not job.completed and job.planned_cuts == 2


def test_an_edge_never_cut_is_left_out(paper_log):
    t = paper_log["chamfer"]["t"]
    signals = _job_signals(t, split=(10.0, 11.0))
    shared, sources = _sources(paper_log)
    job = make_job_log(
        paper_log.scenario,
        sources,
        shared,
        signals,
        [SimpleNamespace(duration_s=1.0, travel_m=0.05, min_clearance_m=0.01)],
        stop_reason=JOB_COMPLETE,
        stop_time=float(t[-1]),
    )
    assert [e.position for e in job.edges] == [0]
    assert job.moves == [] and job.completed
    assert edge_window(signals, 1) is None


def test_slice_keeps_the_window_and_drops_final_state():
    logs = {
        "a": {"t": np.arange(5.0), "x": np.arange(5.0) * 2},
        "finish": {"arc": np.arange(3.0)},
    }
    out = slice_signals(logs, 1.0, 3.0)
    assert list(out) == ["a"]
    np.testing.assert_array_equal(out["a"]["t"], [0.0, 1.0, 2.0])
    np.testing.assert_array_equal(out["a"]["x"], [2.0, 4.0, 6.0])


def test_job_signals_refuse_a_misshapen_column():
    with pytest.raises(ValueError, match="JobSignals.phase"):
        JobSignals(t=np.arange(3.0), q=np.zeros((3, 2)), phase=[0], cut=[0] * 3)
