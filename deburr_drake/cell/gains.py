"""Gains designed from the robot model (``controller.design: auto``).

The rules docs/own-robot-measurements.md states ("Gains designed from the
model"), made code, from the numbers
:func:`deburr_drake.cell.robot.loop_numbers` gives at the start pose (the
robot model's masses, with the rotor inertia the file gives or
``robot.reflected_inertia``):

- x1, x2 (the fuzzy axes): the paper's K = 400 N s/m and lambda = 100 1/s;
- x3 (a PD axis, R9): K lambda large enough that the gravity error the
  controller's model leaves at the tool (``model_mass_scale``) holds the
  tool at most :data:`VERTICAL_ERROR` (0.2 mm) low: lambda 100 1/s, K
  rounded up to 1000 N s/m;
- the orientation PD: the paper's K_o = 20 N m s/rad, lambda_o = 20 1/s;
- the 2.5 ms loop: the sampled rate max eig(M^-1 D) T (D = J_v^T K J_v +
  J_w^T K_o J_w) at most :data:`SAMPLED_RATE` (0.35, well below the
  loop's limit; arm5's and arm6's written gains are within it): above it
  the translational and orientation gains are scaled down, each part to
  half the limit (the rate is linear in the gains), then both up together
  to the limit (never above the rule's values);
- lambda on the fuzzy axes: where the sampled rate lowered K, raised so
  that K lambda keeps the rule's 4e4 N/m (:data:`FEED_STIFFNESS`, at most
  :data:`MAX_LAMBDA`): K lambda T_c is the feed/force loop's gain, and
  without it that loop rings (:func:`feed_loop_damping`);
- Delta_k (``fuzzy.sliding_scales`` x ``width_fraction``): the learned
  surface's slope, about f / Delta_k for a learned force f (the gravity
  error along x1, x2), must stay below :data:`SLOPE_RATE` (0.4) of the
  lightest task mass over T and below arm5's 3.9 N / 4 mm/s; at least
  4 mm/s, rounded up (1 mm/s steps below 10 mm/s, 5 mm/s above);
- the plant's integration step (``simulation.max_step``, only ever
  lowered, to a whole fraction of T), only with ``process.sample_mean``
  false (with it, the default, the cutting damping is integrated exactly
  over the sample at any step): cenic treats the cutting force's damping
  g a a^T explicitly but for its diagonal, and on a light arm eq. (3)
  between samples oscillates once g h / m exceeds about 4-5. The step
  keeps g_max h / m below :data:`STEP_RATE` (2.5), g_max = k_c (delta* x
  engagement + the tallest burr's area): arm5 and arm6 two steps per
  sample (``process.implicit_damping`` stays off: it moves the loop's
  limits);
- more than 6 joints: the null-space posture PD keeps 200 N m/rad and
  10 N m s/rad unless its damping d (I - J^T J^T+) alone takes more than
  half the rate's limit, then d to that half and k = 20 d;
- x_max (``fuzzy.position_scale``): 1.25 ||x_p|| at the part rounded up to
  0.5 m, at least 1 m (y0 = ||x_p|| / x_max inside the rule base).

:func:`design_gains` returns them with the numbers they came from;
:func:`resolve_design` returns a copy of a scenario with every designed
value resolved (the gains where ``controller.design`` is ``auto``, the
fuzzy slope bound where it is 0); no function here changes the scenario
it is given. The analysis package proves the choice with the one-period
map (deburr_drake.analysis.preflight).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
import math
from typing import Dict, Optional

import numpy as np

from deburr_drake.config import Scenario
from deburr_drake.control.command import feedrate_law
from deburr_drake.math.feedrate import cutting_damping

__all__ = [
    "GainDesign",
    "design_gains",
    "resolve_design",
    "resolve_gains",
    "apply_gains",
    "resolve_slope_bound",
    "slope_bound",
    "SLOPE_LIMIT_FRACTION",
    "MIN_SLOPE_BOUND",
    "VERTICAL_ERROR",
    "SAMPLED_RATE",
    "SLOPE_RATE",
    "feed_loop_damping",
]

#: m: the vertical error x3's PD may leave under the gravity error.
VERTICAL_ERROR = 2.0e-4
#: max eig(M^-1 D) T the design allows.
SAMPLED_RATE = 0.35
#: The fuzzy surface's slope f / Delta_k, at most this x (lightest task
#: mass / T) ...
SLOPE_RATE = 0.4
#: ... and at most arm5's (3.9 N over 4 mm/s, rounded), N s/m.
SLOPE_MAX = 1000.0
MIN_DELTA_K = 0.004  # m/s, paper.yaml's
#: N/m: K lambda on the fuzzy axes, the rule's 400 x 100 ...
FEED_STIFFNESS = 4.0e4
#: ... with lambda at most this (1/s).
MAX_LAMBDA = 1000.0
#: g_max h / (lightest task mass) the integration step allows.
STEP_RATE = 2.5

#: The fields the design sets (dotted names).
DESIGNED_FIELDS = (
    "controller.sliding_gain",
    "controller.sliding_lambda",
    "controller.orientation_gain",
    "controller.orientation_lambda",
    "controller.fuzzy.sliding_scales",
    "controller.fuzzy.position_scale",
    "simulation.max_step",
    "controller.null_space_stiffness",
    "controller.null_space_damping",
)


@dataclass
class GainDesign:
    """Designed gains (SI) and the numbers behind them."""

    sliding_gain: list
    sliding_lambda: list
    orientation_gain: list
    orientation_lambda: list
    sliding_scales: list
    position_scale: float
    max_step: float
    null_space_stiffness: float = 200.0
    null_space_damping: float = 10.0
    numbers: Dict[str, float] = field(default_factory=dict)

    def as_fields(self) -> Dict[str, object]:
        """{dotted field: value} of the designed gains."""
        return {
            "controller.sliding_gain": list(self.sliding_gain),
            "controller.sliding_lambda": list(self.sliding_lambda),
            "controller.orientation_gain": list(self.orientation_gain),
            "controller.orientation_lambda": list(self.orientation_lambda),
            "controller.fuzzy.sliding_scales": list(self.sliding_scales),
            "controller.fuzzy.position_scale": self.position_scale,
            "simulation.max_step": self.max_step,
            # eq. (3) as is at that step: the law's implicit-damping
            # term moves the sampled loop's limits
            "process.implicit_damping": False,
            "controller.null_space_stiffness": self.null_space_stiffness,
            "controller.null_space_damping": self.null_space_damping,
        }

    def scaled(self, factor: float) -> "GainDesign":
        """The design with K and K_o times ``factor`` (the rest as is)."""
        return GainDesign(
            [k * factor for k in self.sliding_gain],
            list(self.sliding_lambda),
            [k * factor for k in self.orientation_gain],
            list(self.orientation_lambda),
            list(self.sliding_scales),
            self.position_scale,
            self.max_step,
            self.null_space_stiffness,
            self.null_space_damping,
            dict(self.numbers),
        )


def _ceil_to(x: float, step: float) -> float:
    # 0.5 % tolerance: a value the rule gives exactly stays (arm5's 4 mm/s).
    return float(round(step * math.ceil(x / step * (1 - 5e-3)), 12))


def _nice(v: float) -> float:
    """Two significant digits, rounded down (a gain scaled to a limit)."""
    if v <= 0:
        return 0.0
    e = 10 ** (math.floor(math.log10(v)) - 1)
    return float(round(math.floor(v / e + 1e-9) * e, 12))


def _rates(plant, q, frame_name, K, K_o, period, d_n=0.0):
    """The sampled rate of D_v alone, D_w alone and of both (with the
    null-space damping d_n (I - J^T J^T+) on more than 6 joints)."""
    from pydrake.multibody.tree import JacobianWrtVariable

    context = plant.CreateDefaultContext()
    plant.SetPositions(context, q)
    frame = plant.GetFrameByName(frame_name)
    J = plant.CalcJacobianSpatialVelocity(
        context,
        JacobianWrtVariable.kV,
        frame,
        np.zeros(3),
        plant.world_frame(),
        plant.world_frame(),
    )
    M = plant.CalcMassMatrix(context)

    def rate(D):
        return float(
            np.max(np.linalg.eigvals(np.linalg.solve(M, D)).real) * period
        )

    D_v = J[3:].T @ np.diag(K) @ J[3:]
    D_w = J[:3].T @ np.diag(K_o) @ J[:3]
    D_n = (
        d_n * (np.eye(J.shape[1]) - J.T @ np.linalg.pinv(J.T))
        if J.shape[1] > 6
        else 0.0
    )
    return rate(D_v), rate(D_w), rate(D_v + D_w + D_n)


def _rule_gains(gravity_error_force):
    """(K, lambda, K_o, lambda_o) of the rules before the sampled rate:
    x1, x2 the paper's, x3's K large enough for :data:`VERTICAL_ERROR`."""
    lam = [100.0, 100.0, 100.0]
    K3 = max(
        1000.0,
        _ceil_to(
            abs(gravity_error_force[2]) / (VERTICAL_ERROR * lam[2]), 1000.0
        ),
    )
    return [400.0, 400.0, K3], lam, [20.0, 20.0, 20.0], [20.0, 20.0, 20.0]


def _within_sampled_rate(rates, K, K_o):
    """(K, K_o, rate_v, rate_w, rate): the rule's gains, scaled down to
    :data:`SAMPLED_RATE` when they exceed it; ``rates(K, K_o)`` gives
    :func:`_rates`' three rates."""
    rate_v, rate_w, rate = rates(K, K_o)
    if rate <= SAMPLED_RATE:
        return K, K_o, rate_v, rate_w, rate
    # Each part to its share of the limit, as the rate is linear in the
    # gains (lambda max of a sum of PSD pencils <= the sum).
    share = SAMPLED_RATE / 2
    sv = min(1.0, share / rate_v) if rate_v > 0 else 1.0
    sw = min(1.0, share / rate_w) if rate_w > 0 else 1.0
    if sv == 1.0:
        sw = min(1.0, (SAMPLED_RATE - rate_v) / rate_w)
    elif sw == 1.0:
        sv = min(1.0, (SAMPLED_RATE - rate_w) / rate_v)
    K_v = [k * sv for k in K]
    K_w = [k * sw for k in K_o]
    # Both parts act on different joints mostly: the sum's rate is below
    # the parts' sum; scale both up to the limit again (never above the
    # rule's gains).
    up = SAMPLED_RATE / rates(K_v, K_w)[2]
    K = [_nice(min(k, kv * up)) for k, kv in zip(K, K_v)]
    K_o = [_nice(min(k, kw * up)) for k, kw in zip(K_o, K_w)]
    return (K, K_o, *rates(K, K_o))


def _feed_loop_lambda(K, lam, axes):
    """lambda on the fuzzy axes raised so that K lambda keeps the rule's
    400 x 100 N/m where the sampled rate lowered K (at most
    :data:`MAX_LAMBDA`); the other axes as they are.

    Between two outer-loop samples the position error along the edge is
    the feed's lag, e = T_c (v - v_t) (the command starts from x_p), so
    K lambda T_c is the outer loop's proportional gain on the feed error;
    it is what damps the feed/force loop against the tool's mass and the
    mass the sensor filter's lag adds to the cancelled cutting force
    (:func:`feed_loop_damping`)."""
    lam = list(lam)
    for a in axes:
        lam[a] = min(
            MAX_LAMBDA, max(lam[a], _ceil_to(FEED_STIFFNESS / K[a], 10.0))
        )
    return lam


def feed_loop_damping(scenario: Scenario, *, mass: float) -> float:
    """The feed/force loop's damping ratio along the edge on a fuzzy axis,
    linearised at the desired force (``scenario``'s gains as written):

        M s^2 + k_p s + k_i = 0,  zeta = k_p / (2 sqrt(k_i M)),

    - k_p = K lambda T_c c: the command starts each outer period T_c from
      x_p, so the position error is the feed's lag T_c (v - v_t) and
      K lambda e a force on the speed error; c = f_td / (f_td - P'_th)
      is the feed law's slope at the desired force (FeedrateLaw.slope);
    - k_i = r |nu|^2 lambda T_c c: the fuzzy term integrates s at the
      adaptation gain r times the active rules' |nu|^2 (at s = 0, the
      tool's distance y0);
    - M = ``mass`` (kg, the tool's task mass) + g tau: -f cancels the
      cutting damping g = k_c delta* b through the sensor's filter
      (tau = 1 / (2 pi f_c)), which leaves the mass g tau.

    nan for a controller without fuzzy axes."""
    from deburr_drake.cell.edge import believed_contour, start_position
    from deburr_drake.control.controller import make_rule_bases

    c = scenario.controller
    if c.kind != "fuzzy" or not c.fuzzy.axes:
        return float("nan")
    task, cmd = scenario.task, scenario.command
    slope = feedrate_law(cmd, task).slope
    y0 = float(
        np.linalg.norm(start_position(scenario, believed_contour(scenario)))
    )
    rb = make_rule_bases(c)[0]
    _, nu = rb.active_rules(y0, 0.0)
    g = cutting_damping(
        scenario.process.cutting_coefficient,
        task.desired_depth * scenario.tool.engagement,
    )
    M = mass + g / (2 * math.pi * scenario.sensor.cutoff_frequency)
    zetas = []
    for a in c.fuzzy.axes:
        gain = c.sliding_lambda[a] * cmd.period * slope
        k_p = c.sliding_gain[a] * gain
        k_i = c.fuzzy.adaptation_gain * float(np.dot(nu, nu)) * gain
        zetas.append(k_p / (2 * math.sqrt(k_i * M)))
    return float(min(zetas))


def _null_space_gains(rates, K, K_o):
    """(k_n, d_n, rate) of more than 6 joints: the null-space posture PD
    (200 N m/rad, 10 N m s/rad: stiffness over damping 20 1/s) within
    what the sampled rate leaves; ``rates(K, K_o, d_n)`` as in
    :func:`_within_sampled_rate`."""
    d_n, k_n = 10.0, 200.0
    if rates(K, K_o, d_n)[2] > SAMPLED_RATE * 1.2:
        per_unit_damping = rates([0.0] * 3, [0.0] * 3, 1.0)[2]
        d_n = _nice(min(10.0, 0.5 * SAMPLED_RATE / per_unit_damping))
        k_n = _nice(20.0 * d_n)
    return k_n, d_n, rates(K, K_o, d_n)[2]


def _sliding_scale(fuzzy, gravity_error_force, mass, period):
    """(Delta_k, the learned force): the fuzzy surface's slope f / Delta_k
    within :data:`SLOPE_RATE` x mass / T and :data:`SLOPE_MAX`."""
    slope = (
        min(SLOPE_MAX, SLOPE_RATE * mass / period) if period > 0 else SLOPE_MAX
    )
    learned = (
        max(abs(gravity_error_force[a]) for a in fuzzy.axes)
        if fuzzy.axes
        else 0.0
    )
    delta_k = max(MIN_DELTA_K, learned / slope)
    return _ceil_to(delta_k, 0.001 if delta_k < 0.01 else 0.005), learned


def _max_step(scenario: Scenario, period: float, mass: float):
    """(g_max, the integration step): with eq. (3) between samples
    (``process.sample_mean`` false), g_max h / mass below
    :data:`STEP_RATE`; the step is only ever lowered, to a whole fraction
    of T."""
    p = scenario.process
    g_max = cutting_damping(
        p.cutting_coefficient,
        scenario.task.desired_depth * scenario.tool.engagement,
        max([b.height * b.thickness for b in p.burrs], default=0.0),
    )
    max_step = scenario.simulation.max_step
    # With process.sample_mean the damping is exact at any step.
    if period > 0 and g_max > 0 and not p.sample_mean:
        steps = max(
            1, math.ceil(g_max * period / (STEP_RATE * mass) * (1 - 5e-3))
        )
        max_step = min(max_step, period / steps)
    return g_max, max_step


def design_gains(scenario: Scenario, q=None, *, model=None) -> GainDesign:
    """The gains the rules of the module docstring give for ``scenario``'s
    robot at joint angles ``q`` (default: the start pose, tool vertical;
    deburr_drake.cell.plan designs at the pose the run starts from).
    ``model``: the robot's model if the caller holds it."""
    from deburr_drake.cell.edge import believed_contour, start_position
    from deburr_drake.cell.robot import (
        loop_numbers,
        make_robot_model,
        start_pose,
    )

    c = scenario.controller
    period = c.control_period
    if q is None:
        q = start_pose(scenario)
    plant = make_robot_model(scenario.robot) if model is None else model
    numbers = loop_numbers(scenario, q, model=plant)
    f = numbers["gravity_error_force"]
    mass = numbers["lightest_task_mass"]
    frame = scenario.robot.tool_frame

    def rates(K, K_o, d_n=0.0):
        if not period > 0:
            return 0.0, 0.0, 0.0
        return _rates(plant, q, frame, K, K_o, period, d_n)

    K, lam, K_o, lam_o = _rule_gains(f)
    K, K_o, rate_v, rate_w, rate = _within_sampled_rate(rates, K, K_o)
    lam = _feed_loop_lambda(K, lam, c.fuzzy.axes)
    k_n, d_n = c.null_space_stiffness, c.null_space_damping
    if len(q) > 6 and period > 0:
        k_n, d_n, rate = _null_space_gains(rates, K, K_o)
    delta_k, learned = _sliding_scale(c.fuzzy, f, mass, period)
    x_p = float(
        np.linalg.norm(start_position(scenario, believed_contour(scenario)))
    )
    # y0 = ||x_p|| / x_max inside the rule base, with room.
    x_max = max(1.0, _ceil_to(1.25 * x_p, 0.5))
    g_max, max_step = _max_step(scenario, period, mass)
    numbers = {
        "cutting_damping_max_Ns_per_m": float(g_max),
        "gravity_error_force_N": [float(v) for v in f],
        "gravity_error_moment_Nm": [
            float(v) for v in numbers["gravity_error_moment"]
        ],
        "lightest_task_mass_kg": float(mass),
        "sampled_rate": rate,
        "sampled_rate_translation": rate_v,
        "sampled_rate_orientation": rate_w,
        "vertical_error_m": float(abs(f[2]) / (K[2] * lam[2])),
        "learned_force_N": float(learned),
        "fuzzy_slope_Ns_per_m": float(learned / delta_k),
        "tool_distance_m": x_p,
    }
    design = GainDesign(
        K,
        lam,
        K_o,
        lam_o,
        [round(delta_k / c.fuzzy.width_fraction, 12)] * len(c.fuzzy.axes),
        x_max,
        max_step,
        k_n,
        d_n,
        numbers,
    )
    numbers["feed_loop_damping"] = feed_loop_damping(
        apply_gains(scenario, design), mass=mass
    )
    return design


def _write_gains(scenario: Scenario, design: GainDesign):
    """Writes ``design`` into ``scenario``, a copy the caller owns."""
    from deburr_drake.config import set_field

    for path, value in design.as_fields().items():
        set_field(scenario, path, value)
    scenario.controller.design = "written"
    scenario.validate()


def apply_gains(scenario: Scenario, design: GainDesign) -> Scenario:
    """A copy of ``scenario`` with ``design``'s gains written and marked
    written (``controller.design: written``); ``scenario`` is left as
    it is."""
    resolved = copy.deepcopy(scenario)
    _write_gains(resolved, design)
    return resolved


def resolve_gains(scenario: Scenario) -> Scenario:
    """A copy of ``scenario`` with its gains designed
    (:func:`design_gains`) if ``controller.design`` resolves to ``auto``
    (the default for a robot from a file), else an equal copy;
    ``scenario`` is left as it is."""
    resolved = copy.deepcopy(scenario)
    if scenario.controller.resolved_design(scenario.robot) == "auto":
        _write_gains(resolved, design_gains(scenario))
    return resolved


#: The designed slope bound keeps K_k plus the learned slope at this
#: fraction of the sampled loop's limit 2 m / T.
SLOPE_LIMIT_FRACTION = 0.75
#: N s/m: the designed slope bound when K_k alone already takes that
#: fraction: the surface may learn a level, not a slope.
MIN_SLOPE_BOUND = 1.0


def slope_bound(scenario: Scenario, q=None, *, model=None) -> Optional[float]:
    """The designed ``controller.fuzzy.max_slope`` (N s/m) of a fuzzy
    controller whose bound is 0 (designed), else None:
    SLOPE_LIMIT_FRACTION x 2 m / T - max K_k over the fuzzy axes, m the
    lightest task mass at joint angles ``q`` (default: the start pose,
    tool vertical; :func:`deburr_drake.cell.robot.loop_numbers`, on
    ``model`` if given).

    The sampled loop's limit on the total gain on s_k is about 2 m / T (a
    mass under a sampled damper: the per-sample factor 1 - K T / m
    reaches -1); the fraction leaves the learned slope room below it.
    docs/stability-measurements.md compares the bound with arm5's measured
    limit and with what its paper pass learns."""
    c = scenario.controller
    f = c.fuzzy
    if f.max_slope != 0 or c.kind != "fuzzy" or not c.control_period > 0:
        return None  # (a continuous law, T = 0, has no sampled limit)
    from deburr_drake.cell.robot import loop_numbers

    m = loop_numbers(scenario, q, model=model)["lightest_task_mass"]
    K = max(c.sliding_gain[a] for a in f.axes)
    return max(
        SLOPE_LIMIT_FRACTION * 2.0 * m / c.control_period - K, MIN_SLOPE_BOUND
    )


def resolve_slope_bound(scenario: Scenario, q=None, *, model=None) -> Scenario:
    """A copy of ``scenario`` with ``controller.fuzzy.max_slope`` designed
    (:func:`slope_bound`, at ``q`` on ``model``) where it is 0, else an
    equal copy; ``scenario`` is left as it is."""
    resolved = copy.deepcopy(scenario)
    bound = slope_bound(scenario, q, model=model)
    if bound is not None:
        resolved.controller.fuzzy.max_slope = bound
    return resolved


def resolve_design(scenario: Scenario) -> Scenario:
    """A copy of ``scenario`` with every designed value resolved: the
    gains (:func:`resolve_gains`), then the fuzzy slope bound from them
    (:func:`resolve_slope_bound`). What the diagram is built from and
    what a run is simulated with; a resolved scenario comes back equal."""
    return resolve_slope_bound(resolve_gains(scenario))
