"""The job's report (deburr_drake.runs.job_report) on hand-made job logs
whose answers are known: each edge's metrics are the single pass's on its
slice, the job's time, travel and clearance are split by phase, and a job
a guard stopped on its third edge reports the two before it and does not
claim job_complete."""

import json
from types import SimpleNamespace

import numpy as np
import pytest

from deburr_drake.cell.edge import make_contour
from deburr_drake.config import load_scenario
from deburr_drake.runs import job_report as jr
from deburr_drake.runs.pass_metrics import TRANSIENT
from deburr_drake.runs.simulation import RunLog

PHASES = {0: jr.CUTTING, 1: jr.RETRACT, 2: jr.TRANSIT, 3: jr.APPROACH}
CUT_TIME = 6.0  # s, each edge's cut
MOVE = (1.0, 2.0, 1.0)  # s, retract, transit, approach
DT = 0.01  # s, the logs' period
F_T_ERROR = (0.3, 0.5, 0.7, 0.9)  # N, each edge's f_t error after its transient


def _edge_log(sc, t0, order, *, stop_at=None):
    """A pass's log of the paper scenario from ``t0``: contact 0.5 s in,
    f_t ``F_T_ERROR[order]`` N off after the transient (50 N in it), the
    whole edge cut 20 um deep; with ``stop_at`` (s after t0) the log
    ends there with the bins up to where the tool got cut."""
    d_star = sc.task.desired_depth
    L = make_contour(sc).length
    end = CUT_TIME if stop_at is None else stop_at
    t = t0 + np.arange(0.0, end, DT)
    n = len(t)
    arc = np.linspace(0.0, L * end / CUT_TIME, n, endpoint=False)
    n2 = np.tile([0.0, 1.0, 0.0], (n, 1))
    contact = t0 + 0.5
    f_t = np.where(
        t >= contact + TRANSIENT,
        sc.task.desired_chamfering_force + F_T_ERROR[order],
        50.0,
    )
    bins = np.linspace(0, L, 400, endpoint=False)
    depth = np.where(bins <= arc[-1], d_star + 2e-5, 0.0)
    signals = {
        "chamfer": {
            "t": t,
            "f_n": np.where(t >= contact, 5.0, 0.0),
            "n2": n2,
            "xdot_p": 2e-3 * n2,
            "arc_position": arc,
            "delta": np.full(n, d_star),
            "x_p": np.tile([0.4, 0.0, 0.05], (n, 1)),
        },
        "controller": {
            "t": t,
            "e_f": np.full(n, 0.2),
            "delta_d": np.full(n, d_star),
            "u_fuzzy": np.zeros((n, 6)),
            "s": np.zeros((n, 6)),
        },
        "process": {"t": t, "f_t": f_t, "arc_position": arc},
        "command": {"t": t, "feed": np.full(n, 2e-3)},
        "finish": {
            "arc": bins,
            "depth": depth,
            "burr_remaining": np.zeros(1),
        },
    }
    done = stop_at is None
    return RunLog(
        scenario=sc,
        signals=signals,
        sim_time=t0 + end,
        completed_pass=done,
        stop_reason="pass_complete" if done else "guard:max_force",
        stop_time=t0 + end,
    )


def _job(*, stop_on=None, edges=4):
    """(cuts, edge logs, job signals): ``edges`` cuts, each after a move
    (the first too: the job starts on a move here), each 6 s; with
    ``stop_on`` the run stops 3 s into that cut. The fake robot's tool
    tip is q[:3]; its clearance q[3], 1 mm less with the cutter."""
    sc = load_scenario("paper")
    L = make_contour(sc).length
    cuts, logs = [], []
    t, phase, cut, q = [], [], [], []
    now = travelled = 0.0
    for k in range(edges):
        cuts.append(
            SimpleNamespace(
                index=10 + k,
                point=np.array([0.01 * k, 0.0, 0.0]),
                contour=SimpleNamespace(length=L),
            )
        )
        if stop_on is not None and k > stop_on:
            logs.append(None)
            continue
        for code, span in zip((1, 2, 3), MOVE):
            samples = np.arange(now, now + span, DT)
            t.append(samples)
            phase.append(np.full(len(samples), code))
            cut.append(np.full(len(samples), k))
            # 1 m/s along x on the moves; clearance 4 mm, 2 mm on edge 1's
            # transit (the cutter 1 mm nearer still)
            rows = np.zeros((len(samples), 6))
            rows[:, 0] = travelled + samples - now
            rows[:, 3] = 0.002 if (k == 1 and code == 2) else 0.004
            q.append(rows)
            now += span
            travelled += span
        stop_at = 3.0 if k == stop_on else None
        logs.append(_edge_log(sc, now, k, stop_at=stop_at))
        samples = logs[-1]["chamfer"]["t"]
        t.append(samples)
        phase.append(np.zeros(len(samples), int))
        cut.append(np.full(len(samples), k))
        # still while cutting (the edge is a point to the fake robot); in
        # the part (clearance -1 mm): never counted
        rows = np.zeros((len(samples), 6))
        rows[:, 0] = travelled
        rows[:, 3] = -0.001
        q.append(rows)
        now += CUT_TIME if stop_at is None else stop_at
    signals = {
        "t": np.concatenate(t),
        "phase": np.concatenate(phase),
        "cut": np.concatenate(cut),
        "q": np.concatenate(q),
        "stop_time": now,
    }
    return cuts, logs, signals


@pytest.fixture
def fake_robot(monkeypatch):
    monkeypatch.setattr(jr, "tip_positions", lambda cell, q: q[:, :3])
    monkeypatch.setattr(
        jr,
        "clearance",
        lambda cell, q, cutter=True: q[3] - (0.001 if cutter else 0.0),
    )


def _report(cuts, logs, signals, *, stop_reason, refused=()):
    return jr.job_report(
        cuts=cuts,
        edge_logs=logs,
        refused=refused,
        planned_clearance=0.0049,
        t=signals["t"],
        q=signals["q"],
        phase=signals["phase"],
        cut=signals["cut"],
        phase_names=PHASES,
        stop_reason=stop_reason,
        stop_time=signals["stop_time"],
        wall_time=12.0,
        cell=None,
    )


def test_each_edge_reports_its_pass_metrics_and_the_job_completes(
    fake_robot,
):
    cuts, logs, signals = _job()
    report = _report(cuts, logs, signals, stop_reason=jr.JOB_COMPLETE)
    assert report.stop_reason == jr.JOB_COMPLETE
    for k, edge in enumerate(report.edges):
        v = edge.values
        assert v["index"] == 10 + k and v["order"] == k
        assert v["cut_to_end"] and v["stop"] == "pass_complete"
        assert v["edge_coverage"] == 1.0
        assert v["chamfer_depth_rms_error_mm"] == pytest.approx(0.02)
        # the transient's 50 N excluded from the RMS, not from the max
        assert v["chamfering_force_rms_error_N"] == pytest.approx(F_T_ERROR[k])
        assert v["chamfering_force_max_N"] == 50.0
        assert v["feed_mean_off_burrs_mm_s"] == pytest.approx(2.0)
        assert v["cut_time_s"] == pytest.approx(CUT_TIME)
        assert v["contact_time_s"] == pytest.approx(v["start_time_s"] + 0.5)
    job = report.job
    assert job["cutting_time_s"] == pytest.approx(4 * CUT_TIME)
    assert job["retract_time_s"] == pytest.approx(4 * MOVE[0])
    assert job["transit_time_s"] == pytest.approx(4 * MOVE[1])
    assert job["moving_time_s"] == pytest.approx(4 * sum(MOVE))
    assert job["cycle_time_s"] == pytest.approx(4 * (CUT_TIME + sum(MOVE)))
    # 1 m/s while moving; the tool still while cutting (one step of 10 ms
    # at each move's end counts for the move it starts in)
    assert job["moving_travel_m"] == pytest.approx(4 * sum(MOVE), abs=0.05)
    assert job["cutting_travel_m"] == pytest.approx(0.0, abs=0.05)
    # edge 1's transit, with the cutter: 2 - 1 mm; the cuts never count
    assert job["min_clearance_m"] == pytest.approx(0.001)
    assert job["min_clearance_at"].startswith("transit into the cut of order 1")
    assert job["planned_min_clearance_m"] == 0.0049
    assert job["edges_cut"] == 4 and job["cut_share"] == 1.0


def test_a_guard_on_the_third_edge_reports_the_two_before(fake_robot):
    cuts, logs, signals = _job(stop_on=2)
    refused = [(99, "edge 99: no posture at its start")]
    report = _report(
        cuts, logs, signals, stop_reason="guard:max_force", refused=refused
    )
    assert report.stop_reason == "guard:max_force"
    first, second, third, fourth = (e.values for e in report.edges)
    for v in (first, second):
        assert v["cut_to_end"] and v["edge_coverage"] == 1.0
        assert np.isfinite(v["chamfer_depth_rms_error_mm"])
    # the third: stopped half way, its finish over the bins it cut
    assert not third["cut_to_end"] and third["stop"] == "guard:max_force"
    assert third["edge_coverage"] == pytest.approx(0.5, abs=0.01)
    assert third["chamfer_depth_rms_error_mm"] == pytest.approx(0.02)
    assert fourth["stop"] == "not_reached"
    assert np.isnan(fourth["edge_coverage"])
    job = report.job
    assert job["edges_selected"] == 5 and job["edges_cut"] == 2
    assert job["cut_share"] == pytest.approx(2 / 5)
    assert job["cutting_time_s"] == pytest.approx(2 * CUT_TIME + 3.0)
    record = report.record()
    assert record["stop_reason"] == "guard:max_force"
    assert record["edges"][3]["edge_coverage"] is None
    assert (
        "before this edge" in record["edges"][3]["unavailable"]["edge_coverage"]
    )
    assert record["job"]["refused"] == [
        {"index": 99, "why": "edge 99: no posture at its start"}
    ]
    json.dumps(record, allow_nan=False)


def test_a_run_that_says_complete_with_an_edge_uncut_is_not(fake_robot):
    cuts, logs, signals = _job(stop_on=1, edges=2)
    report = _report(cuts, logs, signals, stop_reason="pass_complete")
    assert report.stop_reason == "edges_not_cut"
    assert report.edges[1].values["stop"] == "edges_not_cut"


def test_the_report_is_written_with_each_edges_logs(fake_robot, tmp_path):
    cuts, logs, signals = _job(stop_on=0, edges=2)
    report = _report(cuts, logs, signals, stop_reason="guard:max_force")
    files = jr.write_job_report(
        report, logs, tmp_path, scenario_name="job", figures=False
    )
    record = json.loads(files["metrics"].read_text())
    assert record["scenario"] == "job"
    assert record["job"]["stop_reason"] == "guard:max_force"
    assert [e["index"] for e in record["edges"]] == [10, 11]
    assert list(files["edges"]) == [10]
    with np.load(tmp_path / "edge_10" / "logs.npz") as saved:
        assert saved["meta.contact_start"] == pytest.approx(
            1.0 + 2.0 + 1.0 + 0.5
        )
        assert saved["meta.stop_reason"] == "guard:max_force"
    assert not (tmp_path / "edge_11").exists()
