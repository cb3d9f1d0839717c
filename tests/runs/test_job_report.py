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
from deburr_drake.control.sequencer import JOB_COMPLETE, JOB_PHASE
from deburr_drake.runs import job_report as jr
from deburr_drake.runs.job_log import EdgeSource, JobSignals, make_job_log
from deburr_drake.runs.pass_metrics import TRANSIENT

CUT_TIME = 6.0  # s, each edge's cut
MOVE = (1.0, 2.0, 1.0)  # s, retract, transit, approach
DT = 0.01  # s, the logs' period
F_T_ERROR = (0.3, 0.5, 0.7, 0.9)  # N, each edge's f_t error after its transient


def _samples(start, span):
    return start + np.arange(0.0, span - DT / 2, DT)


def _cut_signals(sc, t, t0, order, stop_at):
    """The shared loggers and the edge's own process over one cut from
    ``t0``: contact 0.5 s in, f_t ``F_T_ERROR[order]`` N off after the
    transient (50 N in it), the tool along the edge at the pace of a
    whole edge in CUT_TIME."""
    d_star = sc.task.desired_depth
    L = make_contour(sc).length
    n = len(t)
    arc = L * (t - t0) / CUT_TIME
    n2 = np.tile([0.0, 1.0, 0.0], (n, 1))
    contact = t0 + 0.5
    f_t = np.where(
        t >= contact + TRANSIENT,
        sc.task.desired_chamfering_force + F_T_ERROR[order],
        50.0,
    )
    shared = {
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
        "command": {"t": t, "feed": np.full(n, 2e-3)},
    }
    process = {"t": t, "f_t": f_t, "arc_position": arc}
    # the bins up to where the tool got, 20 um deeper than asked
    bins = np.linspace(0, L, 400, endpoint=False)
    reached = L if stop_at is None else arc[-1]
    finish = {
        "arc": bins,
        "depth": np.where(bins <= reached, d_star + 2e-5, 0.0),
        "burr_remaining": np.zeros(1),
    }
    return shared, process, finish


def _move_signals(sc, t):
    """The shared loggers on a move: no force, nothing along an edge."""
    n = len(t)
    zero3 = np.zeros((n, 3))
    return {
        "chamfer": {
            "t": t,
            "f_n": np.zeros(n),
            "n2": zero3,
            "xdot_p": zero3,
            "arc_position": np.zeros(n),
            "delta": np.zeros(n),
            "x_p": zero3,
        },
        "controller": {
            "t": t,
            "e_f": np.zeros(n),
            "delta_d": np.zeros(n),
            "u_fuzzy": np.zeros((n, 6)),
            "s": np.zeros((n, 6)),
        },
        "command": {"t": t, "feed": np.zeros(n)},
    }


def _job(*, stop_on=None, edges=4, stop_reason=JOB_COMPLETE, refused=()):
    """(JobLog, plan) of ``edges`` cuts of the paper scenario's edge, each
    CUT_TIME s, with a move (MOVE s) between two; with ``stop_on`` the
    run stops 3 s into that cut, with ``stop_reason``. The fake robot's
    tool tip is q[:3] (1 m/s on the moves, still on the cuts); its
    clearance q[3]: 4 mm on the moves, 2 mm on the transit to the second
    cut, -1 mm (in the part) on the cuts; the cutter 1 mm nearer."""
    sc = load_scenario("paper")
    L = make_contour(sc).length
    cuts = [
        SimpleNamespace(
            index=10 + k,
            point=np.array([0.01 * k, 0.0, 0.0]),
            contour=SimpleNamespace(length=L),
        )
        for k in range(edges)
    ]
    moves = [
        SimpleNamespace(
            duration_s=sum(MOVE), travel_m=sum(MOVE), min_clearance_m=0.0049
        )
        for _ in range(edges - 1)
    ]
    plan = SimpleNamespace(cuts=cuts, moves=lambda: moves)
    segments, sources = [], []
    now = travelled = 0.0
    for k in range(edges):
        if k:
            for name, span in zip(("retract", "move", "approach"), MOVE):
                t = _samples(now, span)
                q = np.zeros((len(t), 6))
                q[:, 0] = travelled + t - now
                q[:, 3] = 0.002 if (k == 1 and name == "move") else 0.004
                segments.append((t, name, -1, q, _move_signals(sc, t)))
                now += span
                travelled += span
        if stop_on is not None and k > stop_on:
            break
        stop_at = 3.0 if k == stop_on else None
        t = _samples(now, CUT_TIME if stop_at is None else stop_at)
        shared, process, finish = _cut_signals(sc, t, now, k, stop_at)
        q = np.zeros((len(t), 6))
        q[:, 0] = travelled
        q[:, 3] = -0.001
        segments.append((t, "cut", k, q, shared))
        sources.append((process, finish, stop_at is None))
        now += CUT_TIME if stop_at is None else stop_at
    t = np.concatenate([s[0] for s in segments])
    signals = JobSignals(
        t=t,
        q=np.concatenate([s[3] for s in segments]),
        phase=np.concatenate(
            [np.full(len(s[0]), JOB_PHASE[s[1]]) for s in segments]
        ),
        cut=np.concatenate([np.full(len(s[0]), s[2]) for s in segments]),
    )
    shared = {
        logger: {
            block: np.concatenate([s[4][logger][block] for s in segments])
            for block in segments[0][4][logger]
        }
        for logger in segments[0][4]
    }
    # every planned cut has its source; those never cut are left out
    while len(sources) < edges:
        sources.append(sources[-1][:2] + (False,))
    edge_sources = [
        EdgeSource(
            index=c.index,
            point=c.point,
            length_m=L,
            scenario=sc,
            process=process,
            final={"finish": finish},
            completed=done,
        )
        for c, (process, finish, done) in zip(cuts, sources)
    ]
    job = make_job_log(
        sc,
        edge_sources,
        shared,
        signals,
        moves,
        stop_reason=stop_reason,
        stop_time=now,
        wall_time=12.0,
        refused=refused,
    )
    return job, plan


@pytest.fixture
def fake_robot(monkeypatch):
    monkeypatch.setattr(jr, "tip_positions", lambda cell, q: q[:, :3])
    monkeypatch.setattr(
        jr,
        "clearance",
        lambda cell, q, cutter=True: q[3] - (0.001 if cutter else 0.0),
    )


def test_each_edge_reports_its_pass_metrics_and_the_job_completes(
    fake_robot,
):
    job, plan = _job()
    report = jr.job_report(job, plan, None)
    assert report.stop_reason == JOB_COMPLETE
    for k, edge in enumerate(report.edges):
        v = edge.values
        assert v["index"] == 10 + k and v["order"] == k
        assert v["cut_to_end"] and v["stop"] == "pass_complete"
        assert v["edge_coverage"] == 1.0
        assert v["chamfer_depth_rms_error_mm"] == pytest.approx(0.02)
        # the transient's 50 N left out of the RMS, not out of the max
        assert v["chamfering_force_rms_error_N"] == pytest.approx(F_T_ERROR[k])
        assert v["chamfering_force_max_N"] == 50.0
        assert v["feed_mean_off_burrs_mm_s"] == pytest.approx(2.0)
        assert v["start_time_s"] == pytest.approx(k * (CUT_TIME + sum(MOVE)))
        assert v["cut_time_s"] == pytest.approx(CUT_TIME - DT)
        assert v["contact_time_s"] == pytest.approx(0.5)
    values = report.job
    assert values["cutting_time_s"] == pytest.approx(4 * CUT_TIME)
    assert values["retract_time_s"] == pytest.approx(3 * MOVE[0])
    assert values["move_time_s"] == pytest.approx(3 * MOVE[1])
    assert values["moving_time_s"] == pytest.approx(3 * sum(MOVE))
    assert values["cycle_time_s"] == pytest.approx(4 * CUT_TIME + 3 * sum(MOVE))
    # 1 m/s while moving, the tool still while cutting: the step from a
    # move's last sample to the cut's first counts for the move
    assert values["moving_travel_m"] == pytest.approx(3 * sum(MOVE))
    assert values["cutting_travel_m"] == 0.0
    # the transit to the second cut, with the cutter: 2 - 1 mm; the cuts
    # (in the part) never count, nor the cutter on retract and approach
    assert values["min_clearance_m"] == pytest.approx(0.001)
    assert values["min_clearance_at"].startswith(
        "the move from edge 10 to edge 11, move, at t = 7.0"
    )
    assert values["planned_min_clearance_m"] == 0.0049
    assert values["edges_cut"] == 4 and values["cut_share"] == 1.0


def test_a_guard_on_the_third_edge_reports_the_two_before(fake_robot):
    refused = [(99, "edge 99: no posture at its start")]
    job, plan = _job(stop_on=2, stop_reason="guard:max_force", refused=refused)
    report = jr.job_report(job, plan, None)
    assert report.stop_reason == "guard:max_force"
    first, second, third, fourth = (e.values for e in report.edges)
    for v in (first, second):
        assert v["cut_to_end"] and v["edge_coverage"] == 1.0
        assert v["chamfer_depth_rms_error_mm"] == pytest.approx(0.02)
    # the third: stopped half way, its finish over the bins it cut
    assert not third["cut_to_end"] and third["stop"] == "guard:max_force"
    assert third["edge_coverage"] == pytest.approx(0.5, abs=0.01)
    assert third["chamfer_depth_rms_error_mm"] == pytest.approx(0.02)
    assert third["chamfering_force_rms_error_N"] == pytest.approx(0.7)
    assert fourth["stop"] == "not_reached" and not fourth["cut_to_end"]
    assert np.isnan(fourth["edge_coverage"])
    values = report.job
    assert values["edges_selected"] == 5 and values["edges_cut"] == 2
    assert values["cut_share"] == pytest.approx(2 / 5)
    assert values["cutting_time_s"] == pytest.approx(2 * CUT_TIME + 3.0)
    record = report.record()
    assert record["stop_reason"] == "guard:max_force"
    assert record["edges"][3]["edge_coverage"] is None
    why = record["edges"][3]["unavailable"]["edge_coverage"]
    assert "before this edge" in why
    assert record["job"]["refused"] == [
        {"index": 99, "why": "edge 99: no posture at its start"}
    ]
    json.dumps(record, allow_nan=False)


def test_a_run_that_says_complete_with_an_edge_uncut_is_not(fake_robot):
    job, plan = _job(stop_on=1, edges=2, stop_reason=JOB_COMPLETE)
    report = jr.job_report(job, plan, None)
    assert report.stop_reason == "edges_not_cut"
    assert report.edges[1].values["stop"] == "edges_not_cut"


def test_the_report_is_written_with_each_edges_logs(fake_robot, tmp_path):
    job, plan = _job(stop_on=0, edges=2, stop_reason="guard:max_force")
    report = jr.job_report(job, plan, None)
    files = jr.write_job_report(report, job, tmp_path, figures=False)
    record = json.loads(files["metrics"].read_text())
    assert record["scenario"] == "paper"
    assert record["job"]["stop_reason"] == "guard:max_force"
    assert [e["index"] for e in record["edges"]] == [10, 11]
    assert isinstance(record["edges"][0]["order"], int)
    assert isinstance(record["job"]["edges_cut"], int)
    assert list(files["edges"]) == [10]
    with np.load(tmp_path / "edge_10" / "logs.npz") as saved:
        assert saved["meta.contact_start"] == pytest.approx(0.5)
        assert saved["meta.stop_reason"] == "guard:max_force"
    assert not (tmp_path / "edge_11").exists()


def test_the_checks_pass_a_complete_job_and_fail_a_stopped_one(fake_robot):
    job, plan = _job()
    checks = jr.job_checks(jr.job_report(job, plan, None))
    assert len(checks) == 4 * 3 + 2 and all(c.ok for c in checks)
    job, plan = _job(stop_on=2, stop_reason="guard:max_force")
    failed = [
        c.what
        for c in jr.job_checks(jr.job_report(job, plan, None))
        if not c.ok
    ]
    # the third edge's coverage (half), the fourth's every metric (null),
    # and the job's ending; the moves stayed clear
    assert failed == [
        "edge 12 edge_coverage",
        "edge 13 edge_coverage",
        "edge 13 chamfer_depth_rms_error_mm",
        "edge 13 chamfering_force_rms_error_N",
        "job stop_reason",
    ]


def test_the_report_as_text_names_the_misses(fake_robot):
    job, plan = _job(stop_on=2, stop_reason="guard:max_force")
    report = jr.job_report(job, plan, None)
    lines = jr.report_lines(report, jr.job_checks(report))
    rows = {int(line.split()[0]): line for line in lines[1:5]}
    assert rows[10].endswith("pass_complete")
    assert rows[12].endswith("guard:max_force  MISSES A RULE")
    assert " n/a " in rows[13]
    assert "job: guard:max_force at 27.000 s" in lines
    assert "cycle time 27.00 s: cutting 15.00 s, moving 12.00 s" in lines[6]
    assert lines[-1].startswith("rules: 9 of 14 held")


def test_the_clearance_is_the_runs_own_when_it_holds_it(fake_robot):
    job, plan = _job(edges=3)
    signals = job.signals
    computed = jr.move_clearances(None, signals)
    cutting = signals.phase == JOB_PHASE["cut"]
    assert np.all(np.isnan(computed[cutting]))
    assert np.nanmin(computed) == pytest.approx(0.001)
    # the run's own, with its least on the approach to the third cut
    signals.clearance = computed.copy()
    approach = np.flatnonzero(signals.phase == JOB_PHASE["approach"])
    signals.clearance[approach[-1]] = 0.0005
    least, where = jr.move_clearance(None, job)
    assert least == 0.0005
    assert where.startswith("the move from edge 11 to edge 12, approach")
