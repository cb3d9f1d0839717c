"""The metrics of a deburring pass (DESIGN §6 and the cell issue) from a
run's logs, and their files: logs.npz, metrics.json."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Dict, Optional

import numpy as np

from deburr_drake import metrics
from deburr_drake.cell import make_contour
from deburr_drake.simulation import RunLog

__all__ = ["pass_metrics", "write_run", "TRANSIENT", "CONTACT_FORCE"]

#: Excluded after contact is established (s), as the issue asks.
TRANSIENT = 2.0
#: Contact is established when ||f_n|| exceeds this (N).
CONTACT_FORCE = 1.0


def _burr_spans(scenario, length):
    return [(b.center_fraction * length, b.length / 2)
            for b in scenario.process.burrs]


def pass_metrics(log: RunLog, *,
                 true_force_at_desired_depth: Optional[float] = None,
                 only_cut: bool = False) -> Dict[str, float]:
    """Every metric of the pass, SI units unless the name says mm.

    Excludes the first ``TRANSIENT`` s after contact (||f_n|| >
    ``CONTACT_FORCE``); the surface finish excludes the bins cut in that
    time; with ``only_cut`` (a run shorter than a pass) also the bins the
    tool has not reached. ``true_force_at_desired_depth`` (N) is the plant's
    normal force at delta* (see demo.contact_truth); without it the
    force-prediction error is nan."""
    sc = log.scenario
    d_star = sc.task.desired_depth
    f_td = sc.task.desired_chamfering_force
    contour = make_contour(sc)
    L, closed = contour.length, contour.closed
    ch, ctl, proc = log["chamfer"], log["controller"], log["process"]
    t_contact = metrics.first_time(ch["t"], ch["f_n"] > CONTACT_FORCE)
    t0 = t_contact + TRANSIENT
    out: Dict[str, float] = {"contact_time_s": t_contact}

    # Surface finish (Fig. 8): bins cut after the transient.
    finish = log["finish"]
    arc, depth = finish["arc"], finish["depth"]
    s_proc = proc["arc_position"]
    transient = metrics.window(proc["t"], t_contact, t0)
    if np.any(transient):
        s_span = np.unwrap(s_proc[transient] / L * 2 * np.pi) * L / (2 * np.pi)
        start = s_span[0]
        skip = metrics.arc_span_mask(arc, start - sc.tool.cutter_radius,
                                     max(s_span.max(), start), L, closed)
    else:
        skip = np.zeros(arc.shape, bool)
    if only_cut:
        skip |= depth <= 0.0
    error = depth[~skip] - d_star
    out["chamfer_depth_mean_error_mm"] = float(np.mean(error)) * 1e3
    out["chamfer_depth_rms_error_mm"] = metrics.rms(error) * 1e3
    out["chamfer_depth_max_error_mm"] = float(np.max(np.abs(error))) * 1e3
    out["edge_coverage"] = float(np.mean(depth > 0.0))
    out["burr_remaining_max_mm"] = float(np.max(finish["burr_remaining"])) \
        * 1e3 if finish["burr_remaining"].size else 0.0

    late = metrics.window(proc["t"], t0)
    out["chamfering_force_rms_error_N"] = metrics.rms(
        proc["f_t"][late] - f_td)
    late_c = metrics.window(ctl["t"], t0)
    out["normal_force_rms_error_N"] = metrics.rms(ctl["e_f"][late_c])
    out["depth_tracking_rms_error_mm"] = metrics.rms(
        np.interp(ctl["t"][late_c], ch["t"], ch["delta"])
        - ctl["delta_d"][late_c]) * 1e3

    # Feed on and off the burrs: the tool's speed along the edge while its
    # front (arc + r) is inside a burr's span.
    late_ch = metrics.window(ch["t"], t0)
    speed = np.abs(np.einsum("ij,ij->i", ch["xdot_p"], ch["n2"]))[late_ch]
    lead = ch["arc_position"][late_ch] + sc.tool.cutter_radius
    on = np.zeros(lead.shape, bool)
    for center, half in _burr_spans(sc, L):
        on |= np.abs(metrics.arc_distance(lead, center, L, closed)) < half
    out["feed_mean_on_burrs_mm_s"] = float(np.mean(speed[on])) * 1e3 \
        if np.any(on) else float("nan")
    out["feed_mean_off_burrs_mm_s"] = float(np.mean(speed[~on])) * 1e3 \
        if np.any(~on) else float("nan")

    c_hat = log["estimates"]["value"][-1]
    predicted = float(c_hat[0] + c_hat[1] * d_star)
    out["predicted_force_at_desired_depth_N"] = predicted
    if true_force_at_desired_depth is None:
        out["force_prediction_error_rel"] = float("nan")
    else:
        out["true_force_at_desired_depth_N"] = true_force_at_desired_depth
        out["force_prediction_error_rel"] = abs(
            predicted - true_force_at_desired_depth) \
            / true_force_at_desired_depth

    act = log["actuation"]
    out["torque_total_variation"] = metrics.total_variation(
        act["value"][metrics.window(act["t"], t0)])
    # What the m = 0 / m = 2 comparison turns on: the fuzzy term's own
    # variation, and how far s roams on the fuzzy axes (against Delta_k).
    axes = list(sc.controller.fuzzy.axes)
    out["fuzzy_term_total_variation"] = metrics.total_variation(
        ctl["u_fuzzy"][late_c][:, axes])
    s_fuzzy = ctl["s"][late_c][:, axes]
    out["sliding_variable_p01_mm_s"] = float(np.percentile(s_fuzzy, 1)) * 1e3
    out["sliding_variable_p99_mm_s"] = float(np.percentile(s_fuzzy, 99)) * 1e3
    out["sim_time_s"] = log.sim_time
    out["wall_time_s"] = log.wall_time
    out["completed_pass"] = float(log.completed_pass)
    out["nan_detected"] = float(metrics.any_nan(
        *[v for blocks in log.signals.values() for v in blocks.values()]))
    return out


def write_run(log: RunLog, out_dir, metrics_: Dict[str, float]) -> Dict[
        str, Path]:
    """logs.npz (named arrays, SI units) and metrics.json in ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    arrays = log.flat()
    sc = log.scenario
    arrays["meta.desired_depth"] = np.array(sc.task.desired_depth)
    arrays["meta.desired_force"] = np.array(
        sc.task.desired_chamfering_force)
    if np.isfinite(metrics_.get("contact_time_s", np.nan)):
        arrays["meta.contact_start"] = np.array(metrics_["contact_time_s"])
    np.savez_compressed(out / "logs.npz", **arrays)
    with open(out / "metrics.json", "w") as f:
        json.dump({"scenario": sc.name, **metrics_}, f, indent=2,
                  sort_keys=True)
    return {"logs": out / "logs.npz", "metrics": out / "metrics.json"}
