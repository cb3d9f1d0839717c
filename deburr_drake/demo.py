"""The point-mass demo: runs the testbed and measures what the foundation
issue asks for (depth convergence and eq. (8)'s time constant, estimator
convergence, feedrate, dead zone, NaN).

Also :func:`run` (build a scenario's cell and simulate it in one call) and
:func:`contact_truth` (the plant's normal-force law near the desired depth,
what an ideal estimator would report)."""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Dict

import numpy as np

from deburr_drake import metrics
from deburr_drake.config import Scenario
from deburr_drake.controller import make_rule_bases
from deburr_drake.cell import contact_normal_force
from deburr_drake.simulation import RunLog, simulate
from deburr_drake.cell import make_deburring_diagram

__all__ = ["ContactTruth", "contact_truth", "frozen_adaptation",
           "run", "summarize", "SETTLE_TIME"]

#: Samples before this time (s) are the transient.
SETTLE_TIME = 2.0


@dataclass
class ContactTruth:
    """The plant's normal-force law near the desired depth, measured on
    Drake's hydroelastic contact plus the process threshold c0 (N, N/m,
    N s/m); what an ideal estimator would report."""

    force_at_desired_depth: float  # N, ||f_n|| at delta*
    c0: float  # N
    secant_stiffness: float  # N/m, (F(delta*) - c0) / delta*
    local_stiffness: float  # N/m, dF/d(delta) at delta*
    c2: float  # N s/m, Hunt-Crossley: d * F_hydro(delta*)


def contact_truth(scenario: Scenario, *, step: float = 2e-5) -> ContactTruth:
    tube, d = scenario.tube, scenario.task.desired_depth
    forces = contact_normal_force(scenario, [d - step, d, d + step])
    c0 = scenario.process.contact_threshold_force
    return ContactTruth(
        force_at_desired_depth=float(forces[1] + c0), c0=c0,
        secant_stiffness=float(forces[1] / d),
        local_stiffness=float((forces[2] - forces[0]) / (2 * step)),
        c2=float(tube.hunt_crossley_dissipation * forces[1]))


def frozen_adaptation(scenario: Scenario, truth: ContactTruth) -> Scenario:
    """The scenario with every adaptation switched off and the estimates
    set to the truth: then (8) governs delta_d."""
    frozen = copy.deepcopy(scenario)
    frozen.estimator.adapt = False
    frozen.estimator.initial_estimates = [
        truth.c0, truth.secant_stiffness, truth.c2]
    frozen.controller.fuzzy.adapt = False
    return frozen


def run(scenario: Scenario, duration: float, **kwargs) -> RunLog:
    """Builds the scenario's cell (:func:`make_deburring_diagram`) and
    simulates it for ``duration`` s; ``kwargs`` go to :func:`simulate`."""
    return simulate(make_deburring_diagram(scenario=scenario), scenario,
                    duration=duration, **kwargs)


def summarize(log: RunLog, truth: ContactTruth,
              frozen: RunLog = None) -> Dict[str, float]:
    """The numbers of the foundation issue, SI units."""
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
    out["force_prediction_error_rel"] = abs(
        predicted - truth.force_at_desired_depth) / truth.force_at_desired_depth

    # Feed: the command's arc speed against the feedrate law evaluated on
    # the logged tangential speed and chamfering force.
    cmd = log["command"]
    c = sc.command
    cmd_late = metrics.window(cmd["t"], SETTLE_TIME)
    out["command_speed"] = metrics.mean_speed(
        cmd["t"][cmd_late], cmd["arc_position"][cmd_late])
    out["commanded_feed_mean"] = float(np.mean(cmd["feed"][cmd_late]))
    v_t = np.einsum("ij,ij->i", ch["n2"], ch["xdot_p"])[late]
    f_t = ch["f_t"][late]
    excess = f_t - c.threshold_power_force
    law = np.where(excess > c.force_offset,
                   np.abs(v_t) * (sc.task.desired_chamfering_force
                                  - c.threshold_power_force) / excess,
                   c.default_feed)
    out["feedrate_law_mean"] = float(np.mean(law))
    out["chamfering_force_mean"] = float(np.mean(f_t))

    rule_bases = make_rule_bases(sc.controller)
    fractions = []
    for k, axis in enumerate(sc.controller.fuzzy.axes):
        hw = rule_bases[k].resolved_dead_zone_half_width
        fractions.append(metrics.dead_zone_fraction(
            ctl["s"][metrics.window(ctl["t"], SETTLE_TIME), axis], hw))
    out["dead_zone_fraction_after_settle"] = float(min(fractions))
    out["nan_detected"] = float(metrics.any_nan(
        *[v for blocks in log.signals.values() for v in blocks.values()]))
    out["wall_time_s"] = log.wall_time
    out["sim_time_s"] = log.sim_time

    if frozen is not None:
        fc = frozen["controller"]
        k_delta = frozen.scenario.controller.depth_gain
        final = float(np.mean(fc["delta_d"][metrics.window(
            fc["t"], fc["t"][-1] - 0.2)]))
        out["depth_final_frozen"] = final
        out["depth_time_constant"] = metrics.exponential_time_constant(
            fc["t"], fc["delta_d"], final, lower=0.02 * d_star,
            upper=0.3 * d_star)
        out["depth_time_constant_eq8"] = (1 + k_delta * truth.c2) / (
            k_delta * truth.local_stiffness)
    return out
