"""The metrics of a deburring pass from a run's logs, one
function per family, each usable alone:

- :func:`finish_metrics`: the chamfer left on the edge (Fig. 8), coverage,
  burr left;
- :func:`force_metrics`: chamfering force (Fig. 10), normal force and depth
  tracking (Fig. 9);
- :func:`feed_metrics`: the feed on and off the burrs, the feed clamp;
- :func:`estimate_metrics`: the contact estimator's force prediction
  against the plant's truth;
- :func:`smoothness_metrics`: torque and fuzzy-term variation, the learned
  surface's roughness, the sliding variable's range;
- :func:`status_metrics`: times, completion, NaN;
- :func:`localisation_metrics` (runs with localisation only): probing and
  cycle time, the probe's fit, the registration;
- :func:`first_edge_error`: the depth error over the first part of the edge
  cut (the batch's measure of learning from part to part).

:func:`pass_metrics` is all of them. Every family takes the run's
:class:`PassWindow` (contact, then ``TRANSIENT`` s excluded) where it
needs one, and returns a :class:`PassMetrics`: values by name, nan with a
reason where this run cannot give a metric. Nothing raises on a short or
stopped run."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Dict, Optional

import numpy as np

from deburr_drake.cell.edge import believed_contour, make_contour
from deburr_drake.cell.truth import contact_truth
from deburr_drake.control.controller import make_rule_bases
from deburr_drake.control.online import ONLINE_STATE
from deburr_drake.control.probe import PROBE_STATE
from deburr_drake.math import metrics
from deburr_drake.math.edge_registration import (
    CORRECTION_SIZE,
    corrected,
    edge_pivot,
)
from deburr_drake.math.registration import (
    POSE_REGISTRATION_SIZE,
    moved_contour,
)
from deburr_drake.math.rigid import matrix_rotvec, rotvec_matrix, rpy_matrix
from deburr_drake.runs.simulation import RunLog

__all__ = [
    "pass_metrics",
    "PassMetrics",
    "PassWindow",
    "pass_window",
    "finish_metrics",
    "force_metrics",
    "feed_metrics",
    "estimate_metrics",
    "smoothness_metrics",
    "status_metrics",
    "localisation_metrics",
    "registration_error",
    "pose_errors",
    "first_edge_error",
    "force_at_desired_depth",
    "force_settling_metrics",
    "TRANSIENT",
    "SETTLE_TIME",
    "SETTLE_BAND",
    "CONTACT_FORCE",
    "MetricDoc",
    "METRICS",
    "MESH_PROBE_METRICS",
    "MESH_ONLINE_METRICS",
]

#: Excluded after contact is established (s): the contact transient is not
#: the steady cutting the metrics judge.
TRANSIENT = 2.0
#: Contact is established when ||f_n|| exceeds this (N).
CONTACT_FORCE = 1.0


@dataclass(frozen=True)
class MetricDoc:
    """What a metric is, for the generated metrics reference
    (``deburr_drake.runs.metrics_reference``): its family (the function
    that computes it), unit (``-``: a ratio, a count or a flag), meaning
    and how it is computed."""

    family: str
    unit: str
    meaning: str
    how: str


def _docs(family, rows):
    return {
        name: MetricDoc(family, unit, meaning, how)
        for name, unit, meaning, how in rows
    }


_AFTER = "after the transient (contact, then ``TRANSIENT`` s)"

#: Every metric :func:`pass_metrics` gives, by name. Kept next to the code
#: that computes them: a test checks that a real run's metrics are all
#: here and that every name here is still computed.
METRICS: Dict[str, MetricDoc] = {
    **_docs(
        "pass_metrics",
        [
            (
                "contact_time_s",
                "s",
                "when contact was first established",
                "the first chamfer sample whose normal force ||f_n|| "
                "exceeds ``CONTACT_FORCE`` (1 N); the transient starts "
                "here",
            ),
        ],
    ),
    **_docs(
        "finish_metrics",
        [
            (
                "chamfer_depth_mean_error_mm",
                "mm",
                "mean error of the chamfer depth left on the edge (Fig. 8)",
                "over the edge bins cut " + _AFTER + ": achieved depth "
                "minus ``task.desired_depth``; with ``only_cut`` (a run "
                "shorter than a pass) only the bins the tool reached",
            ),
            (
                "chamfer_depth_rms_error_mm",
                "mm",
                "RMS error of the chamfer depth left on the edge",
                "RMS over the same bins as the mean error",
            ),
            (
                "chamfer_depth_max_error_mm",
                "mm",
                "largest absolute error of the chamfer depth on the edge",
                "max |depth - desired depth| over the same bins",
            ),
            (
                "edge_coverage",
                "-",
                "fraction of the edge the tool cut",
                "the fraction of the edge's bins with a depth above 0 "
                "(1: the whole edge)",
            ),
            (
                "burr_remaining_max_mm",
                "mm",
                "the tallest burr left on the edge",
                "the largest remaining burr height over the edge's bins "
                "at the end of the run",
            ),
        ],
    ),
    **_docs(
        "force_metrics",
        [
            (
                "chamfering_force_rms_error_N",
                "N",
                "RMS error of the chamfering force (Fig. 10)",
                "||f_t|| - ``task.desired_chamfering_force`` over the "
                "process's samples " + _AFTER,
            ),
            (
                "normal_force_rms_error_N",
                "N",
                "RMS of the normal-force error e_f (Fig. 9)",
                "the controller's e_f over its samples " + _AFTER,
            ),
            (
                "depth_tracking_rms_error_mm",
                "mm",
                "RMS of the depth tracking error delta - delta_d (Fig. 9)",
                "the measured depth delta, interpolated at the controller's "
                "samples, minus its desired depth delta_d, " + _AFTER,
            ),
        ],
    ),
    **_docs(
        "feed_metrics",
        [
            (
                "feed_mean_on_burrs_mm_s",
                "mm/s",
                "mean speed along the edge while the tool is on a burr",
                "|xdot_p . n2| " + _AFTER + " while the cutter's front "
                "(arc position + cutter radius) is within a burr's span; "
                "null when the tool never reached a burr",
            ),
            (
                "feed_mean_off_burrs_mm_s",
                "mm/s",
                "mean speed along the edge off the burrs",
                "the same speed where the cutter's front is on no burr",
            ),
            (
                "feed_at_max_fraction",
                "-",
                "fraction of the time the feed command sat at its clamp",
                "the fraction of the outer loop's samples whose commanded "
                "feed is at ``command.max_feed``",
            ),
        ],
    ),
    **_docs(
        "estimate_metrics",
        [
            (
                "predicted_force_at_desired_depth_N",
                "N",
                "the contact estimator's normal force at the desired depth",
                "c0 hat + c1 hat delta* from the last estimate logged while "
                "the cutter was wholly on the part",
            ),
            (
                "true_force_at_desired_depth_N",
                "N",
                "the plant's normal force at the desired depth",
                "``cell.truth.contact_truth`` of the scenario (the "
                "hydroelastic contact and the cutting law at delta*)",
            ),
            (
                "force_prediction_error_rel",
                "-",
                "relative error of the estimator's prediction",
                "|predicted - true| / true, of the two metrics above",
            ),
        ],
    ),
    **_docs(
        "smoothness_metrics",
        [
            (
                "torque_total_variation",
                "N m",
                "how much the commanded joint torques move",
                "total variation (sum over samples and joints of "
                "|tau[k+1] - tau[k]|) of the actuation " + _AFTER,
            ),
            (
                "fuzzy_term_total_variation",
                "N",
                "how much the fuzzy compensator's output u_f moves",
                "total variation of u_f on the fuzzy axes "
                "(``controller.fuzzy.axes``) " + _AFTER + "; what the "
                "m = 0 and m = 2 rule bases differ in",
            ),
            (
                "control_surface_roughness_N",
                "N",
                "how far the learned surface u_f(y0, s) departs from a plane",
                "RMS residual of a plane fitted to the final rule weights' "
                "surface over the y0 = ||x_p|| and s ranges visited "
                + _AFTER
                + " (``math.metrics.surface_roughness``), the "
                "largest over the fuzzy axes",
            ),
            (
                "sliding_variable_p01_mm_s",
                "mm/s",
                "1st percentile of the sliding variable s",
                "of s on the fuzzy axes " + _AFTER + "; against the dead "
                "zone Delta_k it says whether the adaptation was active",
            ),
            (
                "sliding_variable_p99_mm_s",
                "mm/s",
                "99th percentile of the sliding variable s",
                "as the 1st percentile",
            ),
        ],
    ),
    **_docs(
        "status_metrics",
        [
            (
                "sim_time_s",
                "s",
                "simulated time the run reached",
                "the simulator's time at the end",
            ),
            (
                "wall_time_s",
                "s",
                "wall-clock time of the simulation",
                "measured around the simulation loop (no start-up, "
                "pre-flight or metrics); varies from run to run",
            ),
            (
                "completed_pass",
                "-",
                "1 if the tool went once round the edge, else 0",
                "the run stopped on ``pass_complete``",
            ),
            (
                "nan_detected",
                "-",
                "1 if any logged signal holds a NaN, else 0",
                "the run stopped on NaN, or a NaN in any logged array",
            ),
        ],
    ),
    **_docs(
        "localisation_metrics",
        [
            (
                "probing_time_s",
                "s",
                "time spent touch probing (with ``localisation.probe``)",
                "when the probing sequence handed over to the pass",
            ),
            (
                "pass_time_s",
                "s",
                "time from the end of probing to the end of the run",
                "stop time minus ``probing_time_s``",
            ),
            (
                "cycle_time_s",
                "s",
                "probing and the pass, when the pass completed",
                "the stop time of a run that completed its pass",
            ),
            (
                "probe_touches",
                "-",
                "touches the probe made",
                "the probing sequence's count",
            ),
            (
                "probe_touches_kept",
                "-",
                "touches the fit kept",
                "the largest set that agrees within "
                "``localisation.probe.max_residual`` (a burr under the "
                "others)",
            ),
            (
                "probe_fit_rms_mm",
                "mm",
                "RMS residual of the kept touches about the fit",
                "the fit's residual RMS",
            ),
            (
                "probe_offset_x_mm",
                "mm",
                "x of the registration the probe found (real minus believed)",
                "the fit's dx",
            ),
            (
                "probe_offset_y_mm",
                "mm",
                "y of the registration the probe found (real minus believed)",
                "the fit's dy",
            ),
            (
                "probe_yaw_rad",
                "rad",
                "turn of the registration the probe found",
                "the fit's dyaw about the contour's pivot",
            ),
            (
                "probe_radius_mm",
                "mm",
                "radius change the probe found (a circle with "
                "``fit_radius``; else 0)",
                "the fit's dradius",
            ),
            (
                "probe_registration_error_mm",
                "mm",
                "how far the probe's registration leaves the believed edge "
                "from the real one",
                "the largest distance along the real edge's normal between "
                "the believed zero-depth path moved by the registration and "
                "the real one (``registration_error``)",
            ),
            (
                "online_offset_x_mm",
                "mm",
                "x of the final correction while cutting "
                "(``localisation.online``)",
                "the online registration's last state",
            ),
            (
                "online_offset_y_mm",
                "mm",
                "y of the final correction while cutting",
                "the online registration's last state",
            ),
            (
                "online_yaw_rad",
                "rad",
                "turn of the final correction while cutting",
                "the online registration's last state",
            ),
            (
                "online_registration_error_mm",
                "mm",
                "the error of the final registration (the probe's and the "
                "correction while cutting)",
                "as ``probe_registration_error_mm``, with both moves added",
            ),
            (
                "online_offset_z_mm",
                "mm",
                "z of the final correction while cutting (a mesh part)",
                "the online registration's last state",
            ),
            (
                "online_rotation_deg",
                "deg",
                "angle of the final correction's turn (a mesh part)",
                "the online registration's last state",
            ),
            (
                "registration_position_error_mm",
                "mm",
                "how far a mesh part's final registration leaves the "
                "believed edge's pivot from the real one",
                "|v - v_true| of the registration (v, omega) about the "
                "pivot (``edge_registration_errors``)",
            ),
            (
                "registration_orientation_error_deg",
                "deg",
                "the turn a mesh part's final registration leaves",
                "the angle of R(omega)^T R_true",
            ),
        ],
    ),
}


def _per_axis(name, unit, meaning, how):
    """A metric and its components along (about) x, y and z."""
    rows = [(name, unit, meaning, how)]
    for axis in "xyz":
        rows.append(
            (
                name.replace(f"_{unit}", f"_{axis}_{unit}"),
                unit,
                f"{meaning}: its {axis} component",
                how,
            )
        )
    return rows


_MESH_PROBE_ROWS = [
    *_per_axis(
        "probe_position_error_mm",
        "mm",
        "a mesh part: how far the registered pose puts the edge's centre "
        "from where the real part has it",
        "T c - T_true c, T the registration, T_true the real part's pose "
        "against the believed one, c the mean of the believed edge's "
        "points (the metric: its length)",
    ),
    *_per_axis(
        "probe_orientation_error_deg",
        "deg",
        "a mesh part: the turn between the registered and the real part's "
        "orientation",
        "the rotation vector of R_true R^T (the metric: its angle)",
    ),
    *_per_axis(
        "probe_sigma_position_mm",
        "mm",
        "a mesh part: the registration's reported standard deviation of "
        "position",
        "sqrt of the covariance's diagonal, sigma^2 (J^T J)^-1 (sigma the "
        "kept touches' residual RMS), about the touches' centroid (the "
        "metric: sqrt of its trace)",
    ),
    *_per_axis(
        "probe_sigma_orientation_deg",
        "deg",
        "a mesh part: the registration's reported standard deviation of "
        "orientation",
        "as ``probe_sigma_position_mm``",
    ),
    (
        "probe_mahalanobis",
        "-",
        "a mesh part: the pose error against the reported covariance",
        "e^T C^-1 e, e the error (rotation vector, the touches' "
        "centroid's move) and C the 6 x 6 covariance: chi-square(6) when "
        "the covariance is right",
    ),
    (
        "probe_hole_size_mm",
        "mm",
        "a mesh part: how much larger the hole the edge runs round is than "
        "the file's",
        "the fitted uniform offset of the hole's faces (nan where the "
        "touches cannot tell it from the pose)",
    ),
    (
        "probe_sigma_hole_size_mm",
        "mm",
        "a mesh part: the hole size's reported standard deviation",
        "sqrt of the covariance's size entry",
    ),
    (
        "probe_amplification",
        "-",
        "a mesh part: how much the kept touches amplify touch noise",
        "1 / the smallest singular value of their scaled point-to-plane "
        "Jacobian (docs/part-errors.md)",
    ),
]
#: The metrics only a mesh part's probing gives.
MESH_PROBE_METRICS = tuple(row[0] for row in _MESH_PROBE_ROWS)
#: The metrics only a mesh part's localisation gives (its registration
#: while cutting, its final registration).
MESH_ONLINE_METRICS = (
    "online_offset_z_mm",
    "online_rotation_deg",
    "registration_position_error_mm",
    "registration_orientation_error_deg",
)
METRICS.update(_docs("localisation_metrics", _MESH_PROBE_ROWS))

#: The chamfering force is judged settled from this long after the first
#: full contact (s) ...
SETTLE_TIME = 3.0
#: ... within this band about the desired force (N).
SETTLE_BAND = 1.0

_FINISH = (
    "chamfer_depth_mean_error_mm",
    "chamfer_depth_rms_error_mm",
    "chamfer_depth_max_error_mm",
)


class PassMetrics(dict):
    """The metrics by name (float, nan where a metric cannot be computed on
    this run) with ``reasons[name]``: why that metric is nan."""

    def __init__(self):
        super().__init__()
        self.reasons: Dict[str, str] = {}

    def unavailable(self, name: str, reason: str):
        self[name] = float("nan")
        self.reasons[name] = reason

    def merge(self, other: "PassMetrics") -> "PassMetrics":
        """Adds ``other``'s values and reasons; returns self."""
        self.update(other)
        self.reasons.update(other.reasons)
        return self


@dataclass(frozen=True)
class PassWindow:
    """Which samples the metrics read: from ``start`` (first contact plus
    ``TRANSIENT``, s) on; ``contact`` is the first time ||f_n|| exceeds
    ``CONTACT_FORCE`` (inf without contact); ``reason`` says why a metric
    over the window is nan when no sample is in it."""

    contact: float
    start: float
    reason: str

    def mask(self, t) -> np.ndarray:
        return metrics.window(t, self.start)

    def late(self, out: PassMetrics, name: str, t, value_of):
        """out[name] = value_of(mask) over the samples in the window, or
        nan with the window's reason."""
        mask = self.mask(t)
        if not np.any(mask):
            out.unavailable(name, self.reason)
        else:
            out[name] = value_of(mask)


def pass_window(log: RunLog) -> PassWindow:
    ch = log["chamfer"]
    contact = metrics.first_time(ch["t"], ch["f_n"] > CONTACT_FORCE)
    if np.isfinite(contact):
        reason = (
            f"no sample after the transient (contact at "
            f"{contact:.3f} s + {TRANSIENT:g} s; the run "
            f"stopped at {log.sim_time:.3f} s)"
        )
    else:
        reason = f"no contact (||f_n|| never above {CONTACT_FORCE:g} N)"
    return PassWindow(contact=contact, start=contact + TRANSIENT, reason=reason)


def finish_metrics(
    log: RunLog, window: PassWindow, *, only_cut: bool = False
) -> PassMetrics:
    """The surface finish (Fig. 8): the depth error of the edge bins cut
    after the transient (mean, RMS, max, mm), ``edge_coverage`` (the
    fraction of bins cut) and ``burr_remaining_max_mm``. With ``only_cut``
    (a run shorter than a pass) the bins the tool has not reached are left
    out too."""
    out = PassMetrics()
    sc = log.scenario
    finish = log.signals.get("finish")
    if finish is None:
        for name in _FINISH + ("edge_coverage", "burr_remaining_max_mm"):
            out.unavailable(
                name,
                "the process's final state could not be "
                "read (" + log.stop_detail + ")",
            )
        return out
    contour = make_contour(sc)
    L, closed = contour.length, contour.closed
    proc = log["process"]
    arc, depth = finish["arc"], finish["depth"]
    transient = metrics.window(proc["t"], window.contact, window.start)
    if np.any(transient):
        s_span = (
            np.unwrap(proc["arc_position"][transient] / L * 2 * np.pi)
            * L
            / (2 * np.pi)
        )
        start = s_span[0]
        skip = metrics.arc_span_mask(
            arc,
            start - sc.tool.cutter_radius,
            max(s_span.max(), start),
            L,
            closed,
        )
    else:
        skip = np.zeros(arc.shape, bool)
    if only_cut:
        skip |= depth <= 0.0
    error = depth[~skip] - sc.task.desired_depth
    after = np.any(proc["t"] > window.start)
    if error.size and after:
        out["chamfer_depth_mean_error_mm"] = float(np.mean(error)) * 1e3
        out["chamfer_depth_rms_error_mm"] = metrics.rms(error) * 1e3
        out["chamfer_depth_max_error_mm"] = float(np.max(np.abs(error))) * 1e3
    else:
        reason = (
            window.reason
            if not after
            else "no edge bin was cut after the transient"
        )
        for name in _FINISH:
            out.unavailable(name, reason)
    out["edge_coverage"] = float(np.mean(depth > 0.0))
    out["burr_remaining_max_mm"] = (
        float(np.max(finish["burr_remaining"])) * 1e3
        if finish["burr_remaining"].size
        else 0.0
    )
    return out


def force_metrics(log: RunLog, window: PassWindow) -> PassMetrics:
    """After the transient: the chamfering force's RMS error against
    ``task.desired_chamfering_force`` (Fig. 10), the normal-force error
    e_f's RMS and the depth tracking error delta - delta_d's RMS (Fig. 9)."""
    out = PassMetrics()
    ch, ctl, proc = log["chamfer"], log["controller"], log["process"]
    f_td = log.scenario.task.desired_chamfering_force
    window.late(
        out,
        "chamfering_force_rms_error_N",
        proc["t"],
        lambda m: metrics.rms(proc["f_t"][m] - f_td),
    )
    window.late(
        out,
        "normal_force_rms_error_N",
        ctl["t"],
        lambda m: metrics.rms(ctl["e_f"][m]),
    )
    window.late(
        out,
        "depth_tracking_rms_error_mm",
        ctl["t"],
        lambda m: (
            metrics.rms(
                np.interp(ctl["t"][m], ch["t"], ch["delta"]) - ctl["delta_d"][m]
            )
            * 1e3
        ),
    )
    return out


def _burr_spans(scenario, length):
    return [
        (b.center_fraction * length, b.length / 2)
        for b in scenario.process.burrs
    ]


def feed_metrics(log: RunLog, window: PassWindow) -> PassMetrics:
    """The tool's mean speed along the edge after the transient while its
    front (arc + cutter radius) is on a burr's span and while it is off
    them (mm/s), and ``feed_at_max_fraction``: the fraction of the run's
    outer-loop samples held at ``command.max_feed`` (the clamp is never
    silent)."""
    out = PassMetrics()
    sc = log.scenario
    ch = log["chamfer"]
    contour = make_contour(sc)
    L, closed = contour.length, contour.closed
    late = window.mask(ch["t"])
    speed = np.abs(np.einsum("ij,ij->i", ch["xdot_p"], ch["n2"]))[late]
    lead = ch["arc_position"][late] + sc.tool.cutter_radius
    on = np.zeros(lead.shape, bool)
    for center, half in _burr_spans(sc, L):
        on |= np.abs(metrics.arc_distance(lead, center, L, closed)) < half
    for name, mask, where in (
        ("feed_mean_on_burrs_mm_s", on, "on"),
        ("feed_mean_off_burrs_mm_s", ~on, "off"),
    ):
        if np.any(mask):
            out[name] = float(np.mean(speed[mask])) * 1e3
        else:
            out.unavailable(
                name,
                window.reason
                if not np.any(late)
                else f"the tool was never {where} a burr after the transient",
            )
    feed = log["command"]["feed"]
    if len(feed):
        out["feed_at_max_fraction"] = float(
            np.mean(feed >= sc.command.max_feed * (1.0 - 1e-9))
        )
    else:
        out.unavailable("feed_at_max_fraction", "no command sample")
    return out


def force_settling_metrics(
    log: RunLog, *, after: float = SETTLE_TIME, band: float = SETTLE_BAND
) -> PassMetrics:
    """How the chamfering force settles: ``full_contact_time_s``, the first
    time the cutter is wholly on the part at the desired depth (process
    engagement 1, depth >= delta*), and
    ``chamfering_force_settled_fraction``, the fraction of the process's
    samples from ``after`` s later on, off the burrs, whose f_t lies within
    ``band`` N of ``task.desired_chamfering_force``. Off the burrs: no
    part of the cutter (arc +- cutter radius) on a burr's span, where the
    feed law's slow-down moves the force by design."""
    out = PassMetrics()
    sc = log.scenario
    proc = log["process"]
    t = proc["t"]
    full = metrics.first_time(
        t,
        (proc["engagement"] >= 1.0 - 1e-9)
        & (proc["delta"] >= sc.task.desired_depth),
    )
    if not np.isfinite(full):
        reason = "the cutter never reached the desired depth on the part"
        out.unavailable("full_contact_time_s", reason)
        out.unavailable("chamfering_force_settled_fraction", reason)
        return out
    out["full_contact_time_s"] = full
    contour = make_contour(sc)
    L, closed = contour.length, contour.closed
    arc = proc["arc_position"]
    on = np.zeros(arc.shape, bool)
    for center, half in _burr_spans(sc, L):
        reach = half + sc.tool.cutter_radius
        on |= np.abs(metrics.arc_distance(arc, center, L, closed)) < reach
    judged = metrics.window(t, full + after) & ~on
    if not np.any(judged):
        out.unavailable(
            "chamfering_force_settled_fraction",
            f"no sample off the burrs from {full + after:.3f} s on "
            f"(the run stopped at {log.sim_time:.3f} s)",
        )
        return out
    error = proc["f_t"][judged] - sc.task.desired_chamfering_force
    out["chamfering_force_settled_fraction"] = float(
        np.mean(np.abs(error) <= band)
    )
    return out


def force_at_desired_depth(scenario) -> Optional[float]:
    """The plant's normal force at delta* (cell.truth.contact_truth), or
    None when it cannot be computed: the metrics that need it are then
    null with their reason."""
    try:
        return contact_truth(scenario).force_at_desired_depth
    except Exception:
        return None


def _last_estimate_on_the_part(log: RunLog) -> int:
    """Index of the last estimate logged while the cutter was wholly on the
    part (the process's engagement 1): where an open edge ends, the cutter
    runs off it and the estimator learns the partial contact there (on the
    100 mm straight wall c0 + c1 delta* falls from 5.13 to 2.91 N in the
    last 1.5 s); on a closed edge it is the last estimate."""
    process = log.signals.get("process", {})
    engagement = process.get("engagement")
    if engagement is None or not len(engagement):
        return -1
    full = process["t"][engagement >= 1.0 - 1e-9]
    if not len(full):
        return -1
    times = log["estimates"]["t"]
    return max(int(np.searchsorted(times, full[-1], side="right")) - 1, 0)


def estimate_metrics(
    log: RunLog, true_force_at_desired_depth: Optional[float] = None
) -> PassMetrics:
    """The estimator's c0 + c1 delta* (``predicted_...``, N) at the end of
    the pass on the part (:func:`_last_estimate_on_the_part`) against
    ``true_force_at_desired_depth`` (the plant's normal force at delta*,
    :func:`force_at_desired_depth`): their relative error; nan without a
    truth."""
    out = PassMetrics()
    estimates = log["estimates"]["value"]
    if not len(estimates):
        for name in (
            "predicted_force_at_desired_depth_N",
            "force_prediction_error_rel",
        ):
            out.unavailable(name, "no estimate was logged")
        return out
    c_hat = estimates[_last_estimate_on_the_part(log)]
    predicted = float(c_hat[0] + c_hat[1] * log.scenario.task.desired_depth)
    out["predicted_force_at_desired_depth_N"] = predicted
    if true_force_at_desired_depth is None:
        out.unavailable(
            "force_prediction_error_rel",
            "the true force at delta* was not given",
        )
    else:
        out["true_force_at_desired_depth_N"] = true_force_at_desired_depth
        out["force_prediction_error_rel"] = (
            abs(predicted - true_force_at_desired_depth)
            / true_force_at_desired_depth
        )
    return out


def smoothness_metrics(log: RunLog, window: PassWindow) -> PassMetrics:
    """What the m = 0 / m = 2 comparison turns on, after the transient:
    the commanded torque's total variation, the fuzzy term's own, the
    roughness of the learned surface u_f(y0, s_k) over the region the run
    visited, and the sliding variable's 1st and 99th percentiles on the
    fuzzy axes (mm/s, against Delta_k)."""
    out = PassMetrics()
    sc = log.scenario
    ch, ctl, act = log["chamfer"], log["controller"], log["actuation"]
    window.late(
        out,
        "torque_total_variation",
        act["t"],
        lambda m: metrics.total_variation(act["value"][m]),
    )
    axes = list(sc.controller.fuzzy.axes)
    window.late(
        out,
        "fuzzy_term_total_variation",
        ctl["t"],
        lambda m: metrics.total_variation(ctl["u_fuzzy"][m][:, axes]),
    )
    # The roughness over y0 = ||x_p|| and s_k from their least to their
    # largest value after the transient: the rare excursions into the next
    # cells are where an m = 0 surface steps; the largest over the axes.
    theta = log.signals.get("theta", {}).get("final")
    if theta is not None:
        window.late(
            out,
            "control_surface_roughness_N",
            ctl["t"],
            lambda m: _surface_roughness(
                make_rule_bases(sc.controller),
                theta,
                np.linalg.norm(ch["x_p"], axis=1)[window.mask(ch["t"])],
                ctl["s"][m][:, axes],
            ),
        )
    window.late(
        out,
        "sliding_variable_p01_mm_s",
        ctl["t"],
        lambda m: float(np.percentile(ctl["s"][m][:, axes], 1)) * 1e3,
    )
    window.late(
        out,
        "sliding_variable_p99_mm_s",
        ctl["t"],
        lambda m: float(np.percentile(ctl["s"][m][:, axes], 99)) * 1e3,
    )
    return out


def _surface_roughness(rule_bases, theta, y0, s) -> float:
    """metrics.surface_roughness of each fuzzy axis's u_f over the
    visited ranges of y0 and of its s; the largest (nan when no axis has a
    range to measure)."""
    if not len(y0):
        return float("nan")
    y0_range = (float(np.min(y0)), float(np.max(y0)))
    values = [
        metrics.surface_roughness(
            lambda a, b, rb=rb, w=theta[k]: rb.evaluate(w, a, b),
            y0_range,
            (float(np.min(s[:, k])), float(np.max(s[:, k]))),
        )
        for k, rb in enumerate(rule_bases)
    ]
    finite = [v for v in values if np.isfinite(v)]
    return max(finite) if finite else float("nan")


def status_metrics(log: RunLog) -> PassMetrics:
    """Simulated and wall time (s), whether the pass completed, and
    whether any logged signal is NaN (or the run stopped on NaN)."""
    out = PassMetrics()
    out["sim_time_s"] = log.sim_time
    out["wall_time_s"] = log.wall_time
    out["completed_pass"] = float(log.completed_pass)
    out["nan_detected"] = float(
        log.stop_reason == "nan"
        or metrics.any_nan(
            *[v for blocks in log.signals.values() for v in blocks.values()]
        )
    )
    return out


# A mesh part's online state: the correction follows theta and P, whose
# size is the model's (deburr_drake.control.online.online_state).
def _correction_slice(size):
    return slice(size - 3 - CORRECTION_SIZE, size - 3)


def registration_error(scenario, registration, samples: int = 400) -> float:
    """m: the largest distance, along the real edge's normal, between the
    believed part's zero-depth path moved by ``registration`` (dx, dy,
    dyaw, dradius) and the real one, over ``samples`` points evenly along
    it (any contour kind; 0 for a perfect registration)."""
    moved = moved_contour(believed_contour(scenario), registration)
    real = make_contour(scenario)
    L = moved.length if np.isfinite(moved.length) else 1.0
    return float(
        max(
            abs(real.phi(moved.point_at(s)))
            for s in np.linspace(0.0, L, samples, endpoint=not moved.closed)
        )
    )


def _true_move(scenario):
    """(R_t, p_t): x_real = R_t x + p_t, from a mesh part's believed pose
    to the real one."""
    part = scenario.part
    real = part.real_pose(scenario.part_error)
    R_wb, p_wb = rpy_matrix(part.pose.rpy), np.asarray(part.pose.xyz, float)
    R_wr, p_wr = rpy_matrix(real.rpy), np.asarray(real.xyz, float)
    R_t = R_wr @ R_wb.T
    return R_t, p_wr - R_t @ p_wb


def _pose_errors(scenario, registration):
    """(position (3, m), turn (3, rad)) of a mesh part's pose
    ``registration`` (w, p, ...; x_real = R(w) x + p) against the truth
    (T_true, from the believed pose to the real one): T c - T_true c, c
    the mean of the believed edge's points, and the rotation vector of
    R_true R^T."""
    belief = believed_contour(scenario)
    c = np.mean(
        [belief.point_at(s) for s in np.linspace(0, belief.length, 200)], 0
    )
    return pose_errors(scenario, registration, c)


def pose_errors(scenario, registration, centre):
    """(position (3, m), turn (3, rad)) of a mesh part's pose
    ``registration`` (w, p, ...; x_real = R(w) x + p) against the truth
    (``part_error``: T_true, from the believed pose to the real one) at
    ``centre`` (m, world, on the believed part): T c - T_true c, and the
    rotation vector of R_true R^T."""
    reg = np.asarray(registration, float)
    R, p = rotvec_matrix(reg[:3]), reg[3:6]
    R_t, p_t = _true_move(scenario)
    c = np.asarray(centre, float)
    return (R @ c + p) - (R_t @ c + p_t), matrix_rotvec(R_t @ R.T)


def _edge_online_metrics(scenario, online, base) -> PassMetrics:
    """A mesh part's registration while cutting: its final correction
    (mm, deg) and the final registration's error
    (``online_registration_error_mm``); and the final registration
    (``base``, the probe's, corrected) as ``registration_*``."""
    out = PassMetrics()
    final = np.asarray(base, float)
    if online is not None and len(online["t"]):
        last = online["value"][-1]
        correction = last[_correction_slice(len(last))]
        for axis, value in zip("xyz", correction[:3]):
            out[f"online_offset_{axis}_mm"] = float(value) * 1e3
        out["online_rotation_deg"] = float(
            np.degrees(np.linalg.norm(correction[3:]))
        )
        pivot, _ = edge_pivot(believed_contour(scenario))
        final = corrected(final, correction, pivot)
        out["online_registration_error_mm"] = (
            registration_error(scenario, final) * 1e3
        )
    position, turn = _pose_errors(scenario, final)
    out["registration_position_error_mm"] = (
        float(np.linalg.norm(position)) * 1e3
    )
    out["registration_orientation_error_deg"] = float(
        np.degrees(np.linalg.norm(turn))
    )
    return out


def localisation_metrics(log: RunLog) -> PassMetrics:
    """With touch probing: ``probing_time_s`` (when the pass started),
    ``pass_time_s`` (after it) and ``cycle_time_s`` (both, when the pass
    completed), the touches made and kept, the fit's residual RMS and the
    registration it found (mm, rad) and its error
    (``probe_registration_error_mm``, :func:`registration_error`); with
    registration while cutting the final correction (mm) and the error of
    the final registration (the probe's and the correction,
    ``online_registration_error_mm``). Empty without localisation."""
    out = PassMetrics()
    base = np.zeros(4)
    probe = log.signals.get("probe")
    if not log.scenario.localisation.enabled:
        return out
    if _mesh_probed(log):
        return _mesh_metrics(log, probe, log.signals.get("registration"))
    if probe is not None and len(probe["t"]):
        last = probe["value"][-1]
        done = float(PROBE_STATE.get(last, "done_time"))
        _times(out, log, done)
        out["probe_touches"] = float(PROBE_STATE.get(last, "touches"))
        out["probe_touches_kept"] = float(PROBE_STATE.get(last, "kept"))
        out["probe_fit_rms_mm"] = float(PROBE_STATE.get(last, "fit_rms")) * 1e3
        reg = PROBE_STATE.get(last, "registration")
        out["probe_offset_x_mm"] = float(reg[0]) * 1e3
        out["probe_offset_y_mm"] = float(reg[1]) * 1e3
        out["probe_yaw_rad"] = float(reg[2])
        out["probe_radius_mm"] = float(reg[3]) * 1e3
        if done >= 0.0:
            base = np.array(reg, float)
            out["probe_registration_error_mm"] = (
                registration_error(log.scenario, base) * 1e3
            )
    online = log.signals.get("registration")
    if online is not None and len(online["t"]):
        corr = ONLINE_STATE.get(online["value"][-1], "correction")
        out["online_offset_x_mm"] = float(corr[0]) * 1e3
        out["online_offset_y_mm"] = float(corr[1]) * 1e3
        out["online_yaw_rad"] = float(corr[2])
        out["online_registration_error_mm"] = (
            registration_error(log.scenario, base + np.asarray(corr, float))
            * 1e3
        )
    return out


def _mesh_metrics(log: RunLog, probe, online) -> PassMetrics:
    """:func:`localisation_metrics` of a mesh part: its probing's
    (:func:`_mesh_probe_metrics`) and its registration while cutting's
    (:func:`_edge_online_metrics`)."""
    from deburr_drake.control.mesh_probe import MESH_PROBE_STATE

    out = PassMetrics()
    base = np.zeros(POSE_REGISTRATION_SIZE)
    if probe is not None and len(probe["t"]):
        last = probe["value"][-1]
        out = _mesh_probe_metrics(log, last)
        if float(MESH_PROBE_STATE.get(last, "done_time")) >= 0.0:
            base = np.asarray(MESH_PROBE_STATE.get(last, "registration"))
    out.update(_edge_online_metrics(log.scenario, online, base))
    return out


def _mesh_probed(log: RunLog) -> bool:
    return log.scenario.part.edge.kind == "mesh"


def _times(out: PassMetrics, log: RunLog, done: float):
    """probing_time_s, pass_time_s, cycle_time_s of a probed run."""
    if done >= 0.0:
        out["probing_time_s"] = done
        out["pass_time_s"] = log.stop_time - done
    else:
        out.unavailable(
            "probing_time_s",
            "probing did not finish "
            f"(the run stopped at {log.stop_time:.3f} s)",
        )
        out.unavailable("pass_time_s", "probing did not finish")
    if log.completed_pass:
        out["cycle_time_s"] = log.stop_time
    else:
        out.unavailable(
            "cycle_time_s", f"the pass did not complete ({log.stop_reason})"
        )


def _mesh_probe_metrics(log: RunLog, last) -> PassMetrics:
    """:func:`localisation_metrics` of a mesh part's probing
    (MESH_PROBE_STATE): the times, the touches, the registration's pose
    error against the truth, its covariance, the hole's size."""
    from deburr_drake.control.mesh_probe import MESH_PROBE_STATE, covariance_of

    L, out = MESH_PROBE_STATE, PassMetrics()
    done = float(L.get(last, "done_time"))
    _times(out, log, done)
    out["probe_touches"] = float(L.get(last, "touches"))
    out["probe_touches_kept"] = float(L.get(last, "kept"))
    out["probe_fit_rms_mm"] = float(L.get(last, "fit_rms")) * 1e3
    if float(L.get(last, "kept")) == 0.0:
        why = "the touches did not register the part"
        for name in MESH_PROBE_METRICS + ("probe_registration_error_mm",):
            out.unavailable(name, why)
        return out
    reg = np.asarray(L.get(last, "registration"), float)
    R, p = rotvec_matrix(reg[:3]), reg[3:6]
    R_t, p_t = _true_move(log.scenario)
    position, turn = _pose_errors(log.scenario, reg)
    for name, v, scale, unit in (
        ("probe_position_error", position, 1e3, "mm"),
        ("probe_orientation_error", turn, np.degrees(1.0), "deg"),
    ):
        out[f"{name}_{unit}"] = float(np.linalg.norm(v)) * scale
        for axis, x in zip("xyz", v):
            out[f"{name}_{axis}_{unit}"] = float(x) * scale
    cov = covariance_of(last)
    sigma = np.sqrt(np.maximum(np.diag(cov), 0.0))
    for name, block, scale, unit in (
        ("probe_sigma_orientation", sigma[:3], np.degrees(1.0), "deg"),
        ("probe_sigma_position", sigma[3:6], 1e3, "mm"),
    ):
        out[f"{name}_{unit}"] = float(np.linalg.norm(block)) * scale
        for axis, x in zip("xyz", block):
            out[f"{name}_{axis}_{unit}"] = float(x) * scale
    # The error e = (omega, v) about the fit's pivot, T_true = exp(e) T.
    pivot = np.asarray(L.get(last, "pivot"), float)
    R_e = R_t @ R.T
    e = np.concatenate([turn, R_e @ pivot + (p_t - R_e @ p) - pivot])
    out["probe_mahalanobis"] = float(e @ np.linalg.solve(cov[:6, :6], e))
    if float(L.get(last, "size_fitted")) > 0.5:
        out["probe_hole_size_mm"] = float(reg[6]) * 1e3
        out["probe_sigma_hole_size_mm"] = float(sigma[6]) * 1e3
    else:
        why = "the touches could not tell the hole's size (or fit_radius off)"
        out.unavailable("probe_hole_size_mm", why)
        out.unavailable("probe_sigma_hole_size_mm", why)
    out["probe_amplification"] = float(L.get(last, "amplification"))
    if done >= 0.0:
        out["probe_registration_error_mm"] = (
            registration_error(log.scenario, reg) * 1e3
        )
    else:
        out.unavailable("probe_registration_error_mm", "probing did not finish")
    return out


def first_edge_error(log: RunLog, fraction: float = 0.1) -> float:
    """RMS depth error (mm) over the first ``fraction`` of the edge from
    where the pass made contact, the entry's transient included (what a
    cell that has learned from earlier parts does better); nan when the
    run has no finish record or no contact."""
    finish = log.signals.get("finish")
    window = pass_window(log)
    if finish is None or not np.isfinite(window.contact):
        return float("nan")
    sc = log.scenario
    contour = make_contour(sc)
    L, closed = contour.length, contour.closed
    proc = log["process"]
    k = int(np.searchsorted(proc["t"], window.contact))
    start = float(proc["arc_position"][min(k, len(proc["t"]) - 1)])
    span = metrics.arc_span_mask(
        finish["arc"], start, start + fraction * L, L, closed
    )
    if not np.any(span):
        return float("nan")
    error = finish["depth"][span] - sc.task.desired_depth
    return metrics.rms(error) * 1e3


def pass_metrics(
    log: RunLog,
    *,
    true_force_at_desired_depth: Optional[float] = None,
    only_cut: bool = False,
) -> PassMetrics:
    """Every metric of the pass, SI units unless the name says mm: the
    families above over :func:`pass_window`, and ``contact_time_s``.

    ``true_force_at_desired_depth`` (N) is the plant's normal force at
    delta* (:func:`force_at_desired_depth`); without it the
    force-prediction error is nan. ``only_cut``: see
    :func:`finish_metrics`."""
    window = pass_window(log)
    out = PassMetrics()
    if np.isfinite(window.contact):
        out["contact_time_s"] = window.contact
    else:
        out.unavailable("contact_time_s", window.reason)
    for family in (
        finish_metrics(log, window, only_cut=only_cut),
        force_metrics(log, window),
        feed_metrics(log, window),
        estimate_metrics(log, true_force_at_desired_depth),
        smoothness_metrics(log, window),
        status_metrics(log),
        localisation_metrics(log),
    ):
        out.merge(family)
    return out
