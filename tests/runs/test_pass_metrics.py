"""Each family of a pass's metrics (deburr_drake.runs.pass_metrics) alone,
on a hand-made log of the paper scenario whose answers are known, and
pass_metrics as their union."""

import math

import numpy as np
import pytest

from deburr_drake.cell.edge import make_contour
from deburr_drake.config import load_scenario
from deburr_drake.runs.pass_metrics import (
    CONTACT_FORCE,
    TRANSIENT,
    estimate_metrics,
    feed_metrics,
    finish_metrics,
    force_metrics,
    force_settling_metrics,
    pass_metrics,
    pass_window,
    smoothness_metrics,
    status_metrics,
)
from deburr_drake.runs.simulation import RunLog

CONTACT = 0.5  # s, ||f_n|| crosses CONTACT_FORCE here
START = CONTACT + TRANSIENT
V_OFF, V_ON = 2.0e-3, 1.0e-3  # m/s, the tool's speed off and on burrs


def _log(*, nan=False):
    sc = load_scenario("paper")
    d_star = sc.task.desired_depth
    contour = make_contour(sc)
    L = contour.length
    t = np.arange(0.0, 10.0, 0.01)
    n = len(t)
    burrs = [(b.center_fraction * L, b.length / 2) for b in sc.process.burrs]
    arc = np.linspace(0.0, 0.5 * L, n)
    lead = arc + sc.tool.cutter_radius
    on = np.zeros(n, bool)
    for center, half in burrs:
        on |= np.abs(lead - center) < half
    assert on[t >= START].any() and (~on[t >= START]).any()
    n2 = np.tile([0.0, 1.0, 0.0], (n, 1))
    speed = np.where(on, V_ON, V_OFF)
    f_n = np.where(t >= CONTACT, 5.0, 0.0)
    f_t = np.where(
        t >= START, sc.task.desired_chamfering_force + 0.3, 50.0
    )  # the transient's 50 N must not count
    actuation = np.zeros((n, 5))
    actuation[:, 0] = np.where(t >= START, np.arange(n) % 2, 7.0 * t)
    signals = {
        "chamfer": {
            "t": t,
            "f_n": f_n,
            "n2": n2,
            "xdot_p": speed[:, None] * n2,
            "arc_position": arc,
            "delta": np.full(n, d_star),
            "x_p": np.tile([0.4, 0.0, 0.05], (n, 1)),
        },
        "controller": {
            "t": t,
            "e_f": np.where(t >= START, 0.2, 9.0),
            "delta_d": np.full(n, d_star - 1e-6),
            "u_fuzzy": np.zeros((n, 6)),
            "s": np.zeros((n, 6)),
        },
        "process": {"t": t, "f_t": f_t, "arc_position": arc},
        "command": {"t": t[::10], "feed": np.full(n // 10, 2.4e-3)},
        "estimates": {"t": t, "value": np.tile([2.0, 8000.0, 0.0], (n, 1))},
        "actuation": {"t": t, "value": actuation},
        # the bins a pass leaves: 20 um deeper than asked everywhere but
        # one bin 0.1 mm shallow; one 5 um burr stub left
        "finish": {
            "arc": np.linspace(0, L, 400, endpoint=False),
            "depth": np.r_[np.full(399, d_star + 2e-5), d_star - 1e-4],
            "burr_remaining": np.array([0.0, 5e-6, 0.0]),
        },
    }
    # the process logged only after the transient: no bin is skipped
    proc = signals["process"]
    late = t > START + 1e-6
    signals["process"] = {k: v[late] for k, v in proc.items()}
    if nan:
        signals["controller"]["e_f"][-1] = np.nan
    return RunLog(
        scenario=sc,
        signals=signals,
        wall_time=3.0,
        sim_time=10.0,
        completed_pass=True,
        stop_reason="pass_complete",
        stop_time=10.0,
    )


def test_the_window_starts_transient_after_contact():
    window = pass_window(_log())
    assert window.contact == pytest.approx(CONTACT)
    assert window.start == pytest.approx(START)
    assert CONTACT_FORCE < 5.0


def test_finish_metrics_on_known_bins():
    log = _log()
    out = finish_metrics(log, pass_window(log))
    error = np.r_[np.full(399, 2e-5), -1e-4]
    assert out["chamfer_depth_mean_error_mm"] == pytest.approx(
        np.mean(error) * 1e3
    )
    assert out["chamfer_depth_rms_error_mm"] == pytest.approx(
        math.sqrt(np.mean(error**2)) * 1e3
    )
    assert out["chamfer_depth_max_error_mm"] == pytest.approx(0.1)
    assert out["edge_coverage"] == 1.0
    assert out["burr_remaining_max_mm"] == pytest.approx(0.005)


def test_force_metrics_skip_the_transient():
    log = _log()
    out = force_metrics(log, pass_window(log))
    assert out["chamfering_force_rms_error_N"] == pytest.approx(0.3)
    assert out["normal_force_rms_error_N"] == pytest.approx(0.2)
    assert out["depth_tracking_rms_error_mm"] == pytest.approx(1e-3)


def test_feed_metrics_split_on_and_off_the_burrs():
    log = _log()
    out = feed_metrics(log, pass_window(log))
    assert out["feed_mean_off_burrs_mm_s"] == pytest.approx(V_OFF * 1e3)
    assert out["feed_mean_on_burrs_mm_s"] == pytest.approx(V_ON * 1e3)
    assert out["feed_at_max_fraction"] == 0.0


def test_estimate_metrics_against_a_truth():
    log = _log()
    d_star = log.scenario.task.desired_depth
    predicted = 2.0 + 8000.0 * d_star
    out = estimate_metrics(log, 1.25 * predicted)
    assert out["predicted_force_at_desired_depth_N"] == pytest.approx(predicted)
    assert out["force_prediction_error_rel"] == pytest.approx(0.2)
    alone = estimate_metrics(log)
    assert math.isnan(alone["force_prediction_error_rel"])
    assert "not given" in alone.reasons["force_prediction_error_rel"]


def test_estimate_metrics_read_the_estimate_before_the_cutter_left_the_part():
    log = _log()
    t = log["estimates"]["t"]
    # an open edge's end: the cutter runs off it over the last second and
    # the estimator learns the partial contact
    off = t > t[-1] - 1.0
    log["estimates"]["value"] = log["estimates"]["value"].copy()
    log["estimates"]["value"][off] = [1.0, 4000.0, 0.0]
    process = log.signals["process"]
    process["engagement"] = np.where(np.isin(process["t"], t[off]), 0.5, 1.0)
    d_star = log.scenario.task.desired_depth
    out = estimate_metrics(log, 6.0)
    assert out["predicted_force_at_desired_depth_N"] == pytest.approx(
        2.0 + 8000.0 * d_star
    )
    process["engagement"][:] = 1.0  # a closed edge: the last estimate
    out = estimate_metrics(log, 6.0)
    assert out["predicted_force_at_desired_depth_N"] == pytest.approx(
        1.0 + 4000.0 * d_star
    )


def test_smoothness_metrics_count_only_after_the_transient():
    log = _log()
    out = smoothness_metrics(log, pass_window(log))
    late = int(np.sum(log["actuation"]["t"] >= START))
    assert out["torque_total_variation"] == pytest.approx(late - 1)
    assert out["fuzzy_term_total_variation"] == 0.0
    assert out["sliding_variable_p99_mm_s"] == 0.0


def test_status_metrics_see_a_nan():
    assert status_metrics(_log())["nan_detected"] == 0.0
    out = status_metrics(_log(nan=True))
    assert out["nan_detected"] == 1.0
    assert out["completed_pass"] == 1.0 and out["sim_time_s"] == 10.0


def test_pass_metrics_is_the_union_of_the_families():
    log = _log()
    window = pass_window(log)
    families = [
        finish_metrics(log, window),
        force_metrics(log, window),
        feed_metrics(log, window),
        estimate_metrics(log, 6.0),
        smoothness_metrics(log, window),
        status_metrics(log),
    ]
    out = pass_metrics(log, true_force_at_desired_depth=6.0)
    names = set().union(*families) | {"contact_time_s"}
    assert set(out) == names
    for family in families:
        for name, value in family.items():
            assert out[name] == pytest.approx(value, nan_ok=True)


def test_a_run_without_contact_gives_reasons_not_errors():
    log = _log()
    log.signals["chamfer"]["f_n"][:] = 0.0
    out = pass_metrics(log)
    assert math.isnan(out["contact_time_s"])
    assert "no contact" in out.reasons["chamfering_force_rms_error_N"]


@pytest.mark.parametrize("name", ["pocket", "boss", "paper"])
def test_registration_error_of_the_true_registration_is_zero(name):
    from deburr_drake.runs.pass_metrics import registration_error

    scenario = load_scenario(
        name, text=("part_error: {offset: [0.0006, -0.0004, 0.0], yaw: 0.01}")
    )
    # Believed minus real is (offset, yaw), turned about part.pose.xyz
    # (the vertices' centroid and the circle's centre here): the real
    # part is the believed one turned back and moved back.
    truth = [-0.0006, 0.0004, -0.01, 0.0]
    assert registration_error(scenario, truth) < 1e-9
    # None: the offset and the turn at the far corners.
    assert registration_error(scenario, np.zeros(4)) > 6e-4


def test_force_settling_judges_off_the_burrs_from_full_contact_on():
    sc = load_scenario("paper")
    d_star, f_d = sc.task.desired_depth, sc.task.desired_chamfering_force
    L = make_contour(sc).length
    t = np.arange(0.0, 20.0, 0.01)
    arc = np.linspace(0.0, 0.25 * L, len(t))
    full = 2.0  # s: engagement 1 at the desired depth from here
    engaged = t >= full
    on_burr = np.zeros(len(t), bool)
    for b in sc.process.burrs:
        half = b.length / 2 + sc.tool.cutter_radius
        on_burr |= np.abs(arc - b.center_fraction * L) < half
    assert on_burr[t >= full + 3.0].any()
    # Off the burrs from full + 3 s: 9 of 10 samples within the band, one
    # 2 N off; on the burrs 30 N, which must not count; before, 50 N.
    f_t = np.where(np.arange(len(t)) % 10 == 0, f_d + 2.0, f_d + 0.5)
    f_t = np.where(on_burr, 30.0, f_t)
    f_t = np.where(t < full + 3.0, 50.0, f_t)
    log = RunLog(
        scenario=sc,
        signals={
            "process": {
                "t": t,
                "f_t": f_t,
                "arc_position": arc,
                "engagement": np.where(engaged, 1.0, 0.5),
                "delta": np.where(engaged, d_star, 0.5 * d_star),
            }
        },
        wall_time=1.0,
        sim_time=20.0,
    )
    found = force_settling_metrics(log)
    assert found["full_contact_time_s"] == pytest.approx(full)
    judged = (t >= full + 3.0) & ~on_burr
    expected = np.mean(np.abs(f_t[judged] - f_d) <= 1.0)
    assert expected == pytest.approx(0.9, abs=0.01)
    assert found["chamfering_force_settled_fraction"] == pytest.approx(expected)
