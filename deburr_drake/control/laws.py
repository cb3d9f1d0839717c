"""The inner loop's control laws, one class per ``controller.kind``, and
:func:`make_law`, which picks one when the controller is built.

A law is the part of the inner loop that the baselines change: the depth
reference delta_d, the task-space force f_tau and the joint-space model
terms. ``HybridController`` (:mod:`deburr_drake.control.controller`) holds
one law and does everything else (ports, states, e and s, Jacobians, the
orientation PD, the posture, the sampled hold). At every evaluation it
calls, in order, :meth:`ControlLaw.depth_reference`,
:meth:`ControlLaw.task_force` and :meth:`ControlLaw.model_torque`.

- :class:`FuzzyLaw`: the paper's law, K s - f + u_f (36), (37), theta
  adapted by (35).
- :class:`RobustLaw`: K s - f + H (22) on the fuzzy axes.
- :class:`IdealLaw`: K s - f (12) with the true model's inverse dynamics.
- :class:`ImpedanceLaw` (ref. [2]) and :class:`PositionLaw`: the nominal
  path at the desired depth, no force feedback, constant feed.

The terms of (22), the Appendix's gains and the impedance force are also
pure functions (no Drake): :func:`robust_term`, :func:`appendix_gains`,
:func:`impedance_force`. Every law is T-generic (float and AutoDiffXd)."""

from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Any, List, NamedTuple, Optional

import numpy as np
from pydrake.multibody.tree import JacobianWrtVariable, MultibodyForces_

from deburr_drake.config import ConfigError, ControllerConfig
from deburr_drake.math.fuzzy import RuleBase

__all__ = [
    "LAWS",
    "ControlLaw",
    "FuzzyLaw",
    "RobustLaw",
    "IdealLaw",
    "ImpedanceLaw",
    "PositionLaw",
    "LawSetting",
    "TaskTerms",
    "TaskForce",
    "make_law",
    "robust_term",
    "appendix_gains",
    "impedance_force",
    "saturation",
    "sign",
]


def _value(y):
    return y.value() if hasattr(y, "value") else float(y)


def float_values(J):
    """J's values as floats (an AutoDiffXd array's values; a float array
    as is): what pseudo-inverses are taken of."""
    return np.vectorize(_value)(J) if J.dtype == object else J


def sign(x):
    """sgn(x) in {-1, 0, 1} (T-generic: a constant of x's type)."""
    v = _value(x)
    return (1.0 if v > 0 else -1.0 if v < 0 else 0.0) + 0.0 * x


def saturation(x):
    """sat(x) = x for |x| <= 1, sign(x) otherwise (T-generic)."""
    v = _value(x)
    if v > 1.0:
        return 1.0 + 0.0 * x
    if v < -1.0:
        return -1.0 + 0.0 * x
    return x


def robust_term(s_k, x_norm, gains):
    """H(||x||, s_k) of (22) on one task axis:
    (b1 + b2 ||x|| + b3 ||x||^2) sgn(s_k) + (b4 + b5 ||x||) s_k (N)."""
    b1, b2, b3, b4, b5 = gains
    return (b1 + b2 * x_norm + b3 * x_norm**2) * sign(s_k) + (
        b4 + b5 * x_norm
    ) * s_k


def appendix_gains(*, m_bar, h0, h1, h2, h3, d0, d1, d2, lambda_bar):
    """b1..b5 of the Appendix from the bounds P1 (m_bar, kg), P2 (h0 N s/m,
    h1 N s^2/m^2), A1 (h2 N, h3 N s/m), A2 (d0 m, d1 m/s, d2 m/s^2) and
    D1 (lambda_bar 1/s).

    On the paper cell (m_bar = 36 kg task inertia, lambda_bar = 100 1/s,
    d0 = ||x_d|| = 0.43 m, d1 = 5 mm/s, d2 = 0.04 m/s^2, h2 = 5 N,
    h0 = h1 = h3 = 1) this gives b1 = 1.6e5 N (the term lambda^2 m d0
    alone is 1.55e5 N) and b4 = 3.6e3 N s/m, above the sampled loop's
    M / T = 2800 N s/m: the literal bounds are the "overestimated" gains of
    the paper's Section III.B. ``RobustConfig`` therefore defaults to
    b1 = 5 N (h2 + m_bar d2, rounded up) and b2..b5 = 0."""
    lb = lambda_bar
    b1 = (
        m_bar * d2
        + h2
        + d1 * h0
        + d1 * h3
        + d1**2 * h1
        + lb**2 * m_bar * d0
        + lb * d0 * h0
        + lb * d0 * h3
        + lb**2 * d0**2 * h1
        + 2 * lb * d0 * d1 * h1
    )
    b2 = lb * (h0 + h3 + m_bar + 2 * h1 * d1 + 2 * lb * d0 * h1)
    b3 = lb**2 * h1
    b4 = h3 + m_bar * lb + lb * d0 * h1 + d1 * h1
    b5 = lb * h1
    return [b1, b2, b3, b4, b5]


def impedance_force(e, edot, n1, s, *, stiffness, damping, gain):
    """Impedance along n1 and a PD elsewhere (N):
    f = n1 (k n1.e + d n1.edot) + (I - n1 n1^T) (K * s).
    ``e``, ``edot``: nominal-path error and its rate; ``gain``: K per task
    axis; no force feedback."""
    e_n = n1 @ e
    edot_n = n1 @ edot
    ks = gain * s
    return n1 * (stiffness * e_n + damping * edot_n) + ks - n1 * (n1 @ ks)


@dataclass(frozen=True)
class LawSetting:
    """What a law may need besides the configuration, for scalar type
    ``T``: the rule bases of the fuzzy axes (the controller's state holds
    their weights), the nominal depth delta* (m; the constant-feed laws),
    the plant's own model and the tool frame's name (the ideal law)."""

    T: type
    rule_bases: List[RuleBase]
    nominal_depth: Optional[float] = None
    true_plant: Any = None  # a float MultibodyPlant
    tool_frame_name: str = ""


class TaskTerms(NamedTuple):
    """The task-space quantities at one evaluation (world frame, T-generic
    arrays): tool point x_p (m), n1, measured force f (N), the errors e (m)
    and edot (m/s), s (m/s), the rule weights theta (n_axes x n_rules, N)
    and the ``fuzzy_weight`` input's value (None: no such port)."""

    x_p: Any
    n1: Any
    f: Any
    e: Any
    edot: Any
    s: Any
    theta: Any
    fuzzy_weight: Any
    K: Any  # N s/m per task axis: the sliding gain (a parameter)


class TaskForce(NamedTuple):
    """A law's task-space command f_tau (N), its compensator's part
    u_fuzzy (N) and zeta (1 where the fuzzy rules act (37)), per task
    axis."""

    f_tau: Any
    u_fuzzy: Any
    zeta: Any


class ControlLaw:
    """The interface, with what the force-feedback laws share: the depth
    law (7), f_tau = K s - f + u with the law's compensator u
    (:meth:`compensator`), and gravity compensation from the controller's
    model.

    ``rates`` is the controller's continuous-state derivative [delta_d',
    theta'] (zero on entry); a law writes the rates of the states it
    drives into it."""

    #: The law ignores the force loop: delta_d is the nominal depth and the
    #: command runs at constant feed (no feedrate law).
    constant_feed = False

    def __init__(self, config: ControllerConfig, setting: LawSetting):
        self._depth_gain = config.depth_gain
        self._gravity_compensation = config.gravity_compensation

    def depth_reference(self, delta_d, e_f, rates):
        """(delta_d (m), delta_d' (m/s)) from the state delta_d and the
        normal-force error e_f (N): (7), delta_d' = k_delta e_f."""
        delta_d_dot = self._depth_gain * e_f
        rates[0] = delta_d_dot
        return delta_d, delta_d_dot

    def task_force(self, terms: TaskTerms, rates) -> TaskForce:
        """f_tau = K s - f + u (36) (N, world)."""
        u, zeta = self.compensator(terms, rates)
        return TaskForce(terms.K * terms.s - terms.f + u, u, zeta)

    def compensator(self, terms: TaskTerms, rates):
        """(u, zeta) per task axis: none here."""
        return np.zeros_like(terms.s), np.zeros(3)

    def model_torque(self, tau, state, J, tau_g, edot, omega):
        """``tau`` plus the joint-space model terms: -tau_g, the gravity
        forces of the controller's model (``gravity_compensation``)."""
        if self._gravity_compensation:
            return tau - tau_g
        return tau


class FuzzyLaw(ControlLaw):
    """(36), (37): on each fuzzy axis k, u_f of (30) with y0 = ||x_p||,
    y_k = s_k inside Omega_k (zeta_k = 1) and H_bar_k = h_bar_k
    sat(s_k / phi_k) outside it (R10); theta_k' = r nu_k s_Delta,k (35) on
    the active rules, with the dead zone of R4 and, with a finite
    ``fuzzy.max_slope``, the slope bound's pull. A ``fuzzy_weight`` w
    scales u_f and the rates (35): the output the rules move is
    w theta . nu, so its gradient is w nu; theta is frozen while w <= 0."""

    def __init__(self, config: ControllerConfig, setting: LawSetting):
        super().__init__(config, setting)
        f = config.fuzzy
        self._rule_bases = setting.rule_bases
        self._axes = list(f.axes)
        self._n_rules = setting.rule_bases[0].n_rules
        self._adaptation_gain = f.adaptation_gain
        self._adapt = f.adapt
        self._max_slope_rate = f.max_slope_rate
        # fuzzy.max_slope 0 is "designed" (the diagram builder writes the
        # design, deburr_drake.cell.gains.resolve_slope_bound); a law built
        # from a configuration nobody designed bounds nothing.
        self._max_slope = float(f.max_slope) if f.max_slope > 0 else math.inf
        self._robust_gain = config.robust_gain
        self._boundary_layer = config.robust_boundary_layer

    def compensator(self, terms, rates):
        u_fuzzy, zeta = np.zeros_like(terms.s), np.zeros(3)
        y0 = np.sqrt(terms.x_p @ terms.x_p)
        n = self._n_rules
        for k, (axis, rb) in enumerate(zip(self._axes, self._rule_bases)):
            s_k, theta_k = terms.s[axis], terms.theta[k]
            if rb.in_domain(s_k):
                u, idx, rate = rb.evaluate_and_rate(
                    theta_k, y0, s_k, self._adaptation_gain
                )
                zeta[axis] = 1.0
                if self._adapt and len(idx):
                    rates[1 + k * n + idx] = rate
            else:
                u = self._robust_gain[k] * saturation(
                    s_k / self._boundary_layer[k]
                )
            if self._adapt and self._max_slope < math.inf:
                rates[1 + k * n : 1 + (k + 1) * n] += rb.slope_rate(
                    theta_k, self._max_slope, self._max_slope_rate
                )
            u_fuzzy[axis] = u
        if terms.fuzzy_weight is not None:
            self._weigh(_value(terms.fuzzy_weight[0]), u_fuzzy, zeta, rates)
        return u_fuzzy, zeta

    def _weigh(self, w, u_fuzzy, zeta, rates):
        """u_f and the rates (35) scaled by w; theta frozen while w <= 0
        (touch probing: the travel between touches is not the cutting the
        rules learn)."""
        theta = slice(1, 1 + len(self._axes) * self._n_rules)
        if w <= 0.0:
            rates[theta] = 0.0
        elif w < 1.0:
            rates[theta] = w * rates[theta]
        for axis in self._axes:
            if zeta[axis] == 1.0:
                u_fuzzy[axis] = w * u_fuzzy[axis]


class RobustLaw(ControlLaw):
    """(22): H(||x_p||, s_k) of :func:`robust_term` on the fuzzy axes
    (``fuzzy.axes``) with ``robust.gains``; theta is not adapted."""

    def __init__(self, config: ControllerConfig, setting: LawSetting):
        super().__init__(config, setting)
        self._axes = list(config.fuzzy.axes)
        self._gains = config.robust.gains

    def compensator(self, terms, rates):
        u, zeta = np.zeros_like(terms.s), np.zeros(3)
        y0 = np.sqrt(terms.x_p @ terms.x_p)
        for axis in self._axes:
            u[axis] = robust_term(terms.s[axis], y0, self._gains)
        return u, zeta


class IdealLaw(ControlLaw):
    """(12): K s - f, plus in joint space the true model (its own M, C,
    gravity, friction and damping) M vdot_r + C v - tau_g - tau_friction by
    Drake's inverse dynamics, with J vdot_r + Jdot v = [-lambda_o omega;
    lambda edot] (xddot_d = 0 between the hold's samples; -lambda_o omega
    only with orientation control) in the least-squares sense. Its own
    gravity replaces the controller model's."""

    def __init__(self, config: ControllerConfig, setting: LawSetting):
        super().__init__(config, setting)
        if setting.true_plant is None:
            raise ConfigError(
                "controller.kind = 'ideal' is invalid here: it needs "
                "true_plant (the plant's own model)"
            )
        T, plant = setting.T, setting.true_plant
        self._plant = plant if T is float else plant.ToAutoDiffXd()
        self._context = self._plant.CreateDefaultContext()
        self._frame = self._plant.GetFrameByName(setting.tool_frame_name)
        self._forces = MultibodyForces_[T](self._plant)
        self._lambda = np.asarray(config.sliding_lambda, float)
        self._lambda_o = np.asarray(config.orientation_lambda, float)
        self._orientation_control = bool(
            np.any(np.asarray(config.orientation_gain, float) > 0)
        )

    def model_torque(self, tau, state, J, tau_g, edot, omega):
        alpha_r = (
            -self._lambda_o * omega
            if self._orientation_control
            else 0.0 * omega
        )
        return tau + self._inverse_dynamics(
            state, J, self._lambda * edot, alpha_r
        )

    def _inverse_dynamics(self, state, J, a_r, alpha_r):
        """M vdot_r + C v - tau_g - tau_friction of the true plant (its
        force elements: joint friction; its joint damping), with vdot_r
        the least-squares solution of J vdot_r = [alpha_r; a_r] - Jdot v
        (the pseudo-inverse from float values)."""
        plant, ctx = self._plant, self._context
        plant.SetPositionsAndVelocities(ctx, state)
        bias = plant.CalcBiasSpatialAcceleration(
            ctx,
            JacobianWrtVariable.kV,
            self._frame,
            np.zeros(3),
            plant.world_frame(),
            plant.world_frame(),
        )
        target = np.concatenate(
            [alpha_r - bias.rotational(), a_r - bias.translational()]
        )
        vdot_r = np.linalg.pinv(float_values(J)) @ target
        plant.CalcForceElementsContribution(ctx, self._forces)
        return plant.CalcInverseDynamics(ctx, vdot_r, self._forces)


class _ConstantFeedLaw(ControlLaw):
    """The nominal path at the desired depth: delta_d = delta*
    (``nominal_depth``), no depth law, no force feedback."""

    constant_feed = True

    def __init__(self, config: ControllerConfig, setting: LawSetting):
        super().__init__(config, setting)
        if setting.nominal_depth is None:
            raise ConfigError(
                f"controller.kind = {config.kind!r} is invalid here: it "
                "needs nominal_depth (the desired depth, m)"
            )
        self._nominal_depth = setting.nominal_depth

    def depth_reference(self, delta_d, e_f, rates):
        # T-generic constants of the state's type.
        return self._nominal_depth + 0.0 * delta_d, 0.0 * delta_d


class ImpedanceLaw(_ConstantFeedLaw):
    """Ref. [2]: f_tau = n1 (k e_n + d edot_n) + (I - n1 n1^T) K s about
    the nominal path (:func:`impedance_force`)."""

    def __init__(self, config: ControllerConfig, setting: LawSetting):
        super().__init__(config, setting)
        self._stiffness = config.impedance.stiffness
        self._damping = config.impedance.damping

    def task_force(self, terms, rates):
        f_tau = impedance_force(
            terms.e,
            terms.edot,
            terms.n1,
            terms.s,
            stiffness=self._stiffness,
            damping=self._damping,
            gain=terms.K,
        )
        return TaskForce(f_tau, *self.compensator(terms, rates))


class PositionLaw(_ConstantFeedLaw):
    """f_tau = K_p s on every task axis (``position.sliding_gain``)."""

    def __init__(self, config: ControllerConfig, setting: LawSetting):
        super().__init__(config, setting)
        self._K_p = np.asarray(config.position.sliding_gain, float)

    def task_force(self, terms, rates):
        return TaskForce(self._K_p * terms.s, *self.compensator(terms, rates))


#: The law of each ``controller.kind`` (ControllerConfig.KINDS).
LAWS = {
    "fuzzy": FuzzyLaw,
    "robust": RobustLaw,
    "ideal": IdealLaw,
    "impedance": ImpedanceLaw,
    "position": PositionLaw,
}


def make_law(config: ControllerConfig, setting: LawSetting) -> ControlLaw:
    """The law ``config.kind`` names, built for ``setting.T``."""
    return LAWS[config.kind](config, setting)
