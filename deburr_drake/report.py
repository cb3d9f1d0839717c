"""The metrics of a deburring pass (DESIGN §6 and the cell issue) from a
run's logs, and their files: logs.npz, metrics.json.

Use: ``values = pass_metrics(log, only_cut=True)`` (a dict by metric name,
nan with ``values.reasons[name]`` where a short run cannot give one);
``log_arrays(log, values)`` is the flat dict the figures read;
``write_run(log, out_dir, values)`` writes both files."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Dict, Optional

import numpy as np

from deburr_drake import metrics
from deburr_drake.cell import make_contour
from deburr_drake.simulation import RunLog

__all__ = ["pass_metrics", "PassMetrics", "force_at_desired_depth",
           "run_summary", "write_run", "log_arrays", "TRANSIENT",
           "CONTACT_FORCE"]

#: Excluded after contact is established (s), as the issue asks.
TRANSIENT = 2.0
#: Contact is established when ||f_n|| exceeds this (N).
CONTACT_FORCE = 1.0


def _burr_spans(scenario, length):
    return [(b.center_fraction * length, b.length / 2)
            for b in scenario.process.burrs]


class PassMetrics(dict):
    """The metrics by name (float, nan where a metric cannot be computed on
    this run) with ``reasons[name]``: why that metric is nan."""

    def __init__(self):
        super().__init__()
        self.reasons: Dict[str, str] = {}

    def unavailable(self, name: str, reason: str):
        self[name] = float("nan")
        self.reasons[name] = reason


def force_at_desired_depth(scenario) -> Optional[float]:
    """The plant's normal force at delta* (demo.contact_truth), or None
    when it cannot be computed: the metrics that need it are then null
    with their reason."""
    from deburr_drake import demo
    try:
        return demo.contact_truth(scenario).force_at_desired_depth
    except Exception:
        return None


def pass_metrics(log: RunLog, *,
                 true_force_at_desired_depth: Optional[float] = None,
                 only_cut: bool = False) -> PassMetrics:
    """Every metric of the pass, SI units unless the name says mm.

    Excludes the first ``TRANSIENT`` s after contact (||f_n|| >
    ``CONTACT_FORCE``); the surface finish excludes the bins cut in that
    time; with ``only_cut`` (a run shorter than a pass) also the bins the
    tool has not reached. ``true_force_at_desired_depth`` (N) is the plant's
    normal force at delta* (see demo.contact_truth); without it the
    force-prediction error is nan. A metric that this run cannot give (no
    contact, no sample after the transient, an empty log) is nan, with the
    reason in ``reasons``; nothing raises on a short or stopped run."""
    sc = log.scenario
    d_star = sc.task.desired_depth
    f_td = sc.task.desired_chamfering_force
    contour = make_contour(sc)
    L, closed = contour.length, contour.closed
    ch, ctl, proc = log["chamfer"], log["controller"], log["process"]
    out = PassMetrics()
    t_contact = metrics.first_time(ch["t"], ch["f_n"] > CONTACT_FORCE)
    t0 = t_contact + TRANSIENT
    if np.isfinite(t_contact):
        out["contact_time_s"] = t_contact
        late_reason = (f"no sample after the transient (contact at "
                       f"{t_contact:.3f} s + {TRANSIENT:g} s; the run "
                       f"stopped at {log.sim_time:.3f} s)")
    else:
        late_reason = (f"no contact (||f_n|| never above {CONTACT_FORCE:g} "
                       "N)")
        out.unavailable("contact_time_s", late_reason)

    def late_metric(name, t, value_of):
        """value_of(mask) over the samples after the transient."""
        mask = metrics.window(t, t0)
        if not np.any(mask):
            out.unavailable(name, late_reason)
        else:
            out[name] = value_of(mask)

    # Surface finish (Fig. 8): bins cut after the transient.
    finish = log.signals.get("finish")
    if finish is None:
        for name in ("chamfer_depth_mean_error_mm",
                     "chamfer_depth_rms_error_mm",
                     "chamfer_depth_max_error_mm", "edge_coverage",
                     "burr_remaining_max_mm"):
            out.unavailable(name, "the process's final state could not be "
                                  "read (" + log.stop_detail + ")")
    else:
        arc, depth = finish["arc"], finish["depth"]
        s_proc = proc["arc_position"]
        transient = metrics.window(proc["t"], t_contact, t0)
        if np.any(transient):
            s_span = np.unwrap(s_proc[transient] / L * 2 * np.pi) * L \
                / (2 * np.pi)
            start = s_span[0]
            skip = metrics.arc_span_mask(arc, start - sc.tool.cutter_radius,
                                         max(s_span.max(), start), L, closed)
        else:
            skip = np.zeros(arc.shape, bool)
        if only_cut:
            skip |= depth <= 0.0
        error = depth[~skip] - d_star
        if error.size and np.any(proc["t"] > t0):
            out["chamfer_depth_mean_error_mm"] = float(np.mean(error)) * 1e3
            out["chamfer_depth_rms_error_mm"] = metrics.rms(error) * 1e3
            out["chamfer_depth_max_error_mm"] = \
                float(np.max(np.abs(error))) * 1e3
        else:
            reason = late_reason if not np.any(proc["t"] > t0) else \
                "no edge bin was cut after the transient"
            for name in ("chamfer_depth_mean_error_mm",
                         "chamfer_depth_rms_error_mm",
                         "chamfer_depth_max_error_mm"):
                out.unavailable(name, reason)
        out["edge_coverage"] = float(np.mean(depth > 0.0))
        out["burr_remaining_max_mm"] = \
            float(np.max(finish["burr_remaining"])) * 1e3 \
            if finish["burr_remaining"].size else 0.0

    late_metric("chamfering_force_rms_error_N", proc["t"],
                lambda m: metrics.rms(proc["f_t"][m] - f_td))
    late_metric("normal_force_rms_error_N", ctl["t"],
                lambda m: metrics.rms(ctl["e_f"][m]))
    late_metric("depth_tracking_rms_error_mm", ctl["t"],
                lambda m: metrics.rms(
                    np.interp(ctl["t"][m], ch["t"], ch["delta"])
                    - ctl["delta_d"][m]) * 1e3)

    # Feed on and off the burrs: the tool's speed along the edge while its
    # front (arc + r) is inside a burr's span.
    late_ch = metrics.window(ch["t"], t0)
    speed = np.abs(np.einsum("ij,ij->i", ch["xdot_p"], ch["n2"]))[late_ch]
    lead = ch["arc_position"][late_ch] + sc.tool.cutter_radius
    on = np.zeros(lead.shape, bool)
    for center, half in _burr_spans(sc, L):
        on |= np.abs(metrics.arc_distance(lead, center, L, closed)) < half
    for name, mask, where in (("feed_mean_on_burrs_mm_s", on, "on"),
                              ("feed_mean_off_burrs_mm_s", ~on, "off")):
        if np.any(mask):
            out[name] = float(np.mean(speed[mask])) * 1e3
        else:
            out.unavailable(name, late_reason if not np.any(late_ch) else
                            f"the tool was never {where} a burr after the "
                            "transient")

    # The feed law's output held at command.max_feed (the clamp is never
    # silent): the fraction of the run's outer-loop samples, whole run.
    feed = log["command"]["feed"]
    if len(feed):
        out["feed_at_max_fraction"] = float(
            np.mean(feed >= sc.command.max_feed * (1.0 - 1e-9)))
    else:
        out.unavailable("feed_at_max_fraction", "no command sample")

    estimates = log["estimates"]["value"]
    if len(estimates):
        c_hat = estimates[-1]
        predicted = float(c_hat[0] + c_hat[1] * d_star)
        out["predicted_force_at_desired_depth_N"] = predicted
        if true_force_at_desired_depth is None:
            out.unavailable("force_prediction_error_rel",
                            "the true force at delta* was not given")
        else:
            out["true_force_at_desired_depth_N"] = \
                true_force_at_desired_depth
            out["force_prediction_error_rel"] = abs(
                predicted - true_force_at_desired_depth) \
                / true_force_at_desired_depth
    else:
        for name in ("predicted_force_at_desired_depth_N",
                     "force_prediction_error_rel"):
            out.unavailable(name, "no estimate was logged")

    act = log["actuation"]
    late_metric("torque_total_variation", act["t"],
                lambda m: metrics.total_variation(act["value"][m]))
    # What the m = 0 / m = 2 comparison turns on: the fuzzy term's own
    # variation, and how far s roams on the fuzzy axes (against Delta_k).
    axes = list(sc.controller.fuzzy.axes)
    late_metric("fuzzy_term_total_variation", ctl["t"],
                lambda m: metrics.total_variation(ctl["u_fuzzy"][m][:, axes]))
    # The roughness of the learned surface u_f(y0, s_k) over the region the
    # run visited after the transient (y0 = ||x_p||, s_k from its least to
    # its largest value: the rare excursions into the next cells are where
    # an m = 0 surface steps), the largest over the fuzzy axes.
    theta = log.signals.get("theta", {}).get("final")
    if theta is not None:
        from deburr_drake.controller import make_rule_bases
        late_metric("control_surface_roughness_N", ctl["t"],
                    lambda m: _surface_roughness(
                        make_rule_bases(sc.controller), theta,
                        np.linalg.norm(ch["x_p"], axis=1)[
                            metrics.window(ch["t"], t0)],
                        ctl["s"][m][:, axes]))
    late_metric("sliding_variable_p01_mm_s", ctl["t"],
                lambda m: float(np.percentile(ctl["s"][m][:, axes], 1)) * 1e3)
    late_metric("sliding_variable_p99_mm_s", ctl["t"],
                lambda m: float(np.percentile(ctl["s"][m][:, axes], 99))
                * 1e3)
    out["sim_time_s"] = log.sim_time
    out["wall_time_s"] = log.wall_time
    out["completed_pass"] = float(log.completed_pass)
    out["nan_detected"] = float(log.stop_reason == "nan" or metrics.any_nan(
        *[v for blocks in log.signals.values() for v in blocks.values()]))
    return out


def _surface_roughness(rule_bases, theta, y0, s) -> float:
    """metrics.surface_roughness of each fuzzy axis's u_f over the
    visited ranges of y0 and of its s; the largest (nan when no axis has a
    range to measure)."""
    if not len(y0):
        return float("nan")
    y0_range = (float(np.min(y0)), float(np.max(y0)))
    values = [metrics.surface_roughness(
        lambda a, b, rb=rb, w=theta[k]: rb.evaluate(w, a, b), y0_range,
        (float(np.min(s[:, k])), float(np.max(s[:, k]))))
        for k, rb in enumerate(rule_bases)]
    finite = [v for v in values if np.isfinite(v)]
    return max(finite) if finite else float("nan")


def _json_value(value):
    """Strict JSON: nan and infinities become null."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, float, np.floating, np.integer)):
        value = float(value)
        return value if np.isfinite(value) else None
    return value


def run_summary(log: RunLog, metrics_: Dict[str, float]) -> dict:
    """What metrics.json holds: the scenario, how the run ended
    (``completed_pass``, ``stop_reason``, ``stop_time_s``,
    ``stop_detail``), every metric (null where it cannot be computed) and
    ``unavailable``: the reason for each null."""
    reasons = dict(getattr(metrics_, "reasons", {}))
    values = {}
    for key, value in metrics_.items():
        values[key] = _json_value(value)
        if values[key] is None and key not in reasons:
            reasons[key] = "not finite (the run diverged)"
    values.update({
        "scenario": log.scenario.name,
        "completed_pass": bool(log.completed_pass),
        "stop_reason": log.stop_reason,
        "stop_time_s": float(log.stop_time),
        "stop_detail": log.stop_detail,
        "unavailable": reasons,
    })
    return values


def log_arrays(log: RunLog, metrics_: Dict[str, float]) -> Dict[
        str, np.ndarray]:
    """Every array of the run as ``"<logger>.<block>"`` plus the
    ``meta.*`` entries the figures read (desired depth and force, contact
    start, stop time and reason): what logs.npz holds, and what
    :func:`deburr_drake.figures.make_figures` takes without a file."""
    arrays = log.flat()
    sc = log.scenario
    arrays["meta.desired_depth"] = np.array(sc.task.desired_depth)
    arrays["meta.desired_force"] = np.array(
        sc.task.desired_chamfering_force)
    if np.isfinite(metrics_.get("contact_time_s", np.nan)):
        arrays["meta.contact_start"] = np.array(metrics_["contact_time_s"])
    arrays["meta.stop_time"] = np.array(log.stop_time)
    arrays["meta.stop_reason"] = np.array(log.stop_reason)
    return arrays


def write_run(log: RunLog, out_dir, metrics_: Dict[str, float]) -> Dict[
        str, Path]:
    """logs.npz (:func:`log_arrays`: named arrays, SI units) and
    metrics.json (strict JSON, see :func:`run_summary`) in ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(out / "logs.npz", **log_arrays(log, metrics_))
    with open(out / "metrics.json", "w") as f:
        json.dump(run_summary(log, metrics_), f, indent=2, sort_keys=True,
                  allow_nan=False)
    return {"logs": out / "logs.npz", "metrics": out / "metrics.json"}
