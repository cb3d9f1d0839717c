"""The point-mass demo: runs the testbed and measures what the
controller promises there (depth convergence and eq. (8)'s time constant,
estimator convergence, feedrate, dead zone, NaN).

The plant's contact truth it compares with is
:func:`deburr_drake.cell.truth.contact_truth`."""

from __future__ import annotations

import copy
from typing import Dict

import numpy as np

from deburr_drake.cell.edge import believed_contour
from deburr_drake.cell.truth import ContactTruth
from deburr_drake.config import Scenario
from deburr_drake.control.command import feedrate_law
from deburr_drake.control.controller import make_rule_bases
from deburr_drake.math import metrics
from deburr_drake.runs.simulation import RunLog

__all__ = ["frozen_adaptation", "summarize", "SETTLE_TIME"]

#: Samples before this time (s) are the transient.
SETTLE_TIME = 2.0


def frozen_adaptation(scenario: Scenario, truth: ContactTruth) -> Scenario:
    """The scenario with every adaptation switched off and the estimates
    set to the truth: then (8) governs delta_d."""
    frozen = copy.deepcopy(scenario)
    frozen.estimator.adapt = False
    frozen.estimator.initial_estimates = [
        truth.c0,
        truth.secant_stiffness,
        truth.c2,
    ]
    frozen.controller.fuzzy.adapt = False
    return frozen


def summarize(
    log: RunLog, truth: ContactTruth, frozen: RunLog = None
) -> Dict[str, float]:
    """The testbed's numbers (depth convergence, time constant, estimator,
    feedrate, dead zone, NaN), SI units."""
    sc = log.scenario
    d_star = sc.task.desired_depth
    ch, ctl = log["chamfer"], log["controller"]
    late = metrics.window(ch["t"], SETTLE_TIME)
    out = {}
    delta = ch["delta"][late]
    out["depth_final"] = float(ch["delta"][-1])
    out["depth_max_error_after_settle"] = float(np.max(np.abs(delta - d_star)))
    c_hat = log["estimates"]["value"][-1]
    predicted = float(c_hat[0] + c_hat[1] * d_star)
    out["predicted_force_at_desired_depth"] = predicted
    out["true_force_at_desired_depth"] = truth.force_at_desired_depth
    out["force_prediction_error_rel"] = (
        abs(predicted - truth.force_at_desired_depth)
        / truth.force_at_desired_depth
    )

    # Feed: the command's arc speed against the feedrate law evaluated on
    # the logged tangential speed and chamfering force (and, integrating,
    # the feed commanded before each sample).
    cmd = log["command"]
    cmd_late = metrics.window(cmd["t"], SETTLE_TIME)
    out["command_speed"] = metrics.mean_speed(
        cmd["t"][cmd_late], cmd["arc_position"][cmd_late]
    )
    out["commanded_feed_mean"] = float(np.mean(cmd["feed"][cmd_late]))
    v_t = np.einsum("ij,ij->i", ch["n2"], ch["xdot_p"])[late]
    f_t = ch["f_t"][late]
    before = np.searchsorted(cmd["t"], ch["t"][late], side="left") - 1
    law = feedrate_law(
        sc.command,
        sc.task,
        varying_frame=believed_contour(sc).varying_frame,
    )(v_t, f_t, cmd["feed"][np.maximum(before, 0)])
    out["feedrate_law_mean"] = float(np.mean(law))
    out["chamfering_force_mean"] = float(np.mean(f_t))

    rule_bases = make_rule_bases(sc.controller)
    fractions = []
    for k, axis in enumerate(sc.controller.fuzzy.axes):
        hw = rule_bases[k].resolved_dead_zone_half_width
        fractions.append(
            metrics.dead_zone_fraction(
                ctl["s"][metrics.window(ctl["t"], SETTLE_TIME), axis], hw
            )
        )
    out["dead_zone_fraction_after_settle"] = float(min(fractions))
    out["nan_detected"] = float(
        metrics.any_nan(
            *[v for blocks in log.signals.values() for v in blocks.values()]
        )
    )
    out["wall_time_s"] = log.wall_time
    out["sim_time_s"] = log.sim_time

    if frozen is not None:
        fc = frozen["controller"]
        k_delta = frozen.scenario.controller.depth_gain
        final = float(
            np.mean(fc["delta_d"][metrics.window(fc["t"], fc["t"][-1] - 0.2)])
        )
        out["depth_final_frozen"] = final
        out["depth_time_constant"] = metrics.exponential_time_constant(
            fc["t"],
            fc["delta_d"],
            final,
            lower=0.02 * d_star,
            upper=0.3 * d_star,
        )
        out["depth_time_constant_eq8"] = (1 + k_delta * truth.c2) / (
            k_delta * truth.local_stiffness
        )
    return out
