"""Configuration of the paper's controller: the task (desired depth and
force), the outer-loop command generator, the contact estimator, the
hybrid controller with its fuzzy rule base and the baselines' gains. SI
units; each field's comment gives its unit."""

from dataclasses import dataclass, field
from typing import List

from deburr_drake.config.checks import (
    _non_negative,
    _positive,
    _require,
    _vector,
)

__all__ = [
    "TaskConfig",
    "CommandConfig",
    "EstimatorConfig",
    "FuzzyConfig",
    "RobustConfig",
    "ImpedanceConfig",
    "PositionConfig",
    "ControllerConfig",
]


@dataclass
class TaskConfig:
    """The deburring task of Section IV."""

    desired_depth: float = 0.0005  # m, delta_d^* of (6)
    desired_chamfering_force: float = 10.0  # N, ||f_td||

    def validate(self):
        _positive("task", "desired_depth", self.desired_depth)
        _positive(
            "task", "desired_chamfering_force", self.desired_chamfering_force
        )


@dataclass
class CommandConfig:
    """Outer-loop command generator (feedrate law before (5))."""

    period: float = 0.025  # s, T
    default_feed: float = 0.001  # m/s, v0
    force_offset: float = 0.5  # N, v_eps
    threshold_power_force: float = 2.0  # N, P'_th as the controller knows it
    min_tangential_speed: float = 1e-5  # m/s, below it n2 = contour tangent
    # m/s: the feed of the constant-feed baselines (controller.kind
    # impedance, position; no feedrate law), about the paper's average feed.
    constant_feed: float = 0.0024
    # m/s: the feed law's output is clamped here, as a machine's feed is.
    # The law scales the tool's speed by (f_td - P'_th) / (f_t - P'_th),
    # which grows without bound where the chamfer vanishes under the tool
    # (a part error larger than the depth: f_t stays near P'_th + v_eps).
    # The clamp sits above the steady feeds (f_td - P'_th) / g of the
    # scenarios' ranges.
    max_feed: float = 0.02
    # -, the feed law (FEED_LAWS). paper: v scales the tool's measured
    # speed, and x_c starts v T ahead of x_p every period (R6). A steady
    # lag e of the tool behind x_c then costs e / T of feed, and the law,
    # proportional in the force error, leaves that loss as a steady force
    # error: a lag the fuzzy terms leave where the load along the edge
    # turns faster than they learn it (a 3-D edge's turning tool axis and
    # tight curves). integrating: while cutting, v scales the last
    # commanded feed instead (v_{k+1} = v_k (f_td - P'_th) / (f_t -
    # P'_th)), so the law integrates the force error and no lag leaves
    # one; below the cutting threshold the default feed advances x_c from
    # the last command, not from x_p, so a tool held back at the entry by
    # joint friction and the model's gravity error meets a growing
    # position error instead of one capped at v0 T. auto: the paper's law
    # on a planar edge (the paper's experiment as published), integrating
    # along a CAD part's 3-D edge, where the tool axis and the load turn.
    feed_law: str = "auto"

    FEED_LAWS = ("auto", "paper", "integrating")

    def validate(self):
        _require(
            self.feed_law in self.FEED_LAWS,
            "command.feed_law",
            self.feed_law,
            "one of " + ", ".join(self.FEED_LAWS),
        )
        for name in (
            "period",
            "default_feed",
            "force_offset",
            "min_tangential_speed",
            "constant_feed",
            "max_feed",
        ):
            _positive("command", name, getattr(self, name))
        _require(
            self.max_feed >= self.default_feed,
            "command.max_feed",
            self.max_feed,
            f">= command.default_feed ({self.default_feed})",
        )
        _non_negative(
            "command", "threshold_power_force", self.threshold_power_force
        )


@dataclass
class EstimatorConfig:
    """Contact-parameter estimator (13)-(18) with R3."""

    initial_estimates: List[float] = field(
        default_factory=lambda: [3.0, 4000.0, 20.0]
    )  # [N, N/m, N s/m], c0, c1, c2 at the start
    gains: List[float] = field(
        default_factory=lambda: [20.0, 2.0e7, 0.0]
    )  # -, r_i per parameter (R3)
    lower_bounds: List[float] = field(
        default_factory=lambda: [0.1, 100.0, 0.0]
    )  # [N, N/m, N s/m], eps_i (R3)
    contact_force_threshold: float = 0.2  # N, adapt only above it
    adapt: bool = True  # -, false: the estimates stay at their start

    def validate(self):
        o = "estimator"
        _vector(o, "initial_estimates", self.initial_estimates, 3, _positive)
        _vector(o, "gains", self.gains, 3, _non_negative)
        _vector(o, "lower_bounds", self.lower_bounds, 3, _non_negative)
        for i in range(3):
            _require(
                self.initial_estimates[i] >= self.lower_bounds[i],
                f"{o}.initial_estimates[{i}]",
                self.initial_estimates[i],
                f">= {o}.lower_bounds[{i}] ({self.lower_bounds[i]})",
            )
        _non_negative(
            o, "contact_force_threshold", self.contact_force_threshold
        )


@dataclass
class FuzzyConfig:
    """B-spline adaptive fuzzy compensator (24)-(35), R1, R4, R8."""

    order: int = 2  # -, m: the B-splines' order, 0..3
    upsilon: int = 5  # -, Upsilon: rules per input 2*upsilon + 1
    position_scale: float = 0.1  # m, x_max normalizing ||x|| (R8)
    sliding_scales: List[float] = field(
        default_factory=lambda: [0.005, 0.005]
    )  # m/s, s_k,max per axis
    width_fraction: float = 0.2  # -, Delta = width_fraction * scale
    # m/s, per axis; empty: (m+1)/2 * Delta_k (R4).
    dead_zone_half_widths: List[float] = field(default_factory=list)
    adaptation_gain: float = 2000.0  # N s/m per s, r of (35)
    axes: List[int] = field(default_factory=lambda: [0, 1])  # -, task axes
    adapt: bool = True  # -, false: the rule weights stay fixed
    # N s/m, the learned surface's slope |d u_f / d s_k| at most this on
    # every fuzzy axis (adjacent weights along s_k differ by at most
    # max_slope x Delta_k; an excess is pulled back at max_slope_rate).
    # The slope adds to K_k on the sampled loop, whose limit on the total
    # gain is about 2 m / T (m the lightest task mass), and (35) alone
    # can steepen the surface past it over many parts. 0: designed,
    # 1.5 m / T - K_k at the start pose (the total then at most 3/4 of
    # the limit, deburr_drake.cell.gains.resolve_slope_bound); inf: no
    # bound.
    max_slope: float = (
        0.0  # N s/m, bound on the learned surface's slope in s_k (0: designed)
    )
    max_slope_rate: float = (
        80.0  # 1/s, how fast a slope beyond max_slope is pulled back
    )

    def deltas(self):
        """(Delta_0, [Delta_k]) in m and m/s."""
        return (
            self.width_fraction * self.position_scale,
            [self.width_fraction * s for s in self.sliding_scales],
        )

    def validate(self, o="controller.fuzzy"):
        """The fuzzy law's section: the rule base and its adaptation."""
        self.validate_rule_base(o)
        _positive(o, "adaptation_gain", self.adaptation_gain)
        _require(
            isinstance(self.max_slope, (int, float)) and self.max_slope >= 0.0,
            f"{o}.max_slope",
            self.max_slope,
            "a number >= 0 (0: designed; .inf: none)",
        )
        _positive(o, "max_slope_rate", self.max_slope_rate)

    def validate_rule_base(self, o="controller.fuzzy"):
        """The task axes and the rule base on them: what the controller's
        state (the rule weights) and the robust law are shaped by."""
        _require(
            isinstance(self.order, int) and 0 <= self.order <= 3,
            f"{o}.order",
            self.order,
            "an integer in 0..3",
        )
        _require(
            isinstance(self.upsilon, int) and self.upsilon >= 1,
            f"{o}.upsilon",
            self.upsilon,
            "an integer >= 1",
        )
        _positive(o, "position_scale", self.position_scale)
        _positive(o, "width_fraction", self.width_fraction)
        _require(
            len(set(self.axes)) == len(self.axes)
            and all(a in (0, 1, 2) for a in self.axes),
            f"{o}.axes",
            self.axes,
            "distinct task axes from {0, 1, 2}",
        )
        _vector(
            o, "sliding_scales", self.sliding_scales, len(self.axes), _positive
        )
        _, deltas = self.deltas()
        if self.dead_zone_half_widths:
            _vector(
                o,
                "dead_zone_half_widths",
                self.dead_zone_half_widths,
                len(self.axes),
                _non_negative,
            )
            for k, (w, d) in enumerate(zip(self.dead_zone_half_widths, deltas)):
                _require(
                    w <= self.upsilon * d,
                    f"{o}.dead_zone_half_widths[{k}]",
                    w,
                    f"<= upsilon * Delta_k = {self.upsilon * d:g} m/s "
                    "(the dead zone must lie inside Omega_k)",
                )


@dataclass
class RobustConfig:
    """The robust law (22) of Theorem 1 on the fuzzy axes:
    H(||x||, s_k) = (b1 + b2 ||x|| + b3 ||x||^2) sgn(s_k) + (b4 + b5 ||x||) s_k
    with ||x|| = ||x_p|| (m, R8). The Appendix's bounds taken literally give
    gains no sampled servo survives (``deburr_drake.control.laws.
    appendix_gains``: b1 about 1.6e5 N on this cell, from lambda^2 m d0);
    the default keeps the sign term sized for the residual it must dominate
    here (h2: the gravity model's 20 % error and joint friction along x1,
    x2, a few N; m d2: about 1.4 N), see docs in ``laws``."""

    # [N, N/m, N/m^2, N s/m, N s/m^2], b1..b5 of (22)
    gains: List[float] = field(
        default_factory=lambda: [5.0, 0.0, 0.0, 0.0, 0.0]
    )

    def validate(self, o="controller.robust"):
        _vector(o, "gains", self.gains, 5, _non_negative)


@dataclass
class ImpedanceConfig:
    """Impedance control at constant feed (the paper's ref. [2]): along n1
    f = k (delta* - delta_x) + d (0 - delta_x') about the nominal path at the
    desired depth, a PD (K s) on the other directions, no force feedback,
    no feedrate law (``command.constant_feed``), no contact estimator."""

    stiffness: float = 40000.0  # N/m, along n1 (= lambda K of the x1, x2 PD)
    damping: float = 400.0  # N s/m, along n1

    def validate(self, o="controller.impedance"):
        _positive(o, "stiffness", self.stiffness)
        _non_negative(o, "damping", self.damping)


@dataclass
class PositionConfig:
    """Stiff position control of the nominal path (desired depth) at
    constant feed: f = K_p s on every task axis, s = edot + lambda e, no
    force feedback. K_p below M / T of the 2.5 ms servo (7 kg / 2.5 ms =
    2800 N s/m) keeps it stable."""

    sliding_gain: List[float] = field(
        default_factory=lambda: [1500.0, 1500.0, 1500.0]
    )  # N s/m, K_p

    def validate(self, o="controller.position"):
        _vector(o, "sliding_gain", self.sliding_gain, 3, _positive)


@dataclass
class ControllerConfig:
    """Inner-loop hybrid position/force controller (7), (9)-(11), (36), (37),
    R9, R10. Task axes are world x, y, z of the tool tip.

    ``kind`` selects the law (deburr_drake.control.laws): ``fuzzy`` (36),
    (37); ``robust`` (22); ``ideal`` (12) with the true model;
    ``impedance`` and ``position`` at constant feed. Each reads its own
    fields (:meth:`validate` checks those and the shared ones only)."""

    KINDS = ("fuzzy", "robust", "ideal", "impedance", "position")
    #: Kinds that run at constant feed and ignore the estimator.
    CONSTANT_FEED_KINDS = ("impedance", "position")

    kind: str = "fuzzy"  # -, the inner-loop law (KINDS)
    # Where K, lambda, the orientation gains, Delta_k and x_max come from:
    # designed from the robot model at the start pose
    # (deburr_drake.cell.gains) and proven by the one-period map
    # (deburr_drake.analysis.preflight), or as written here.
    design: str = ""  # -, auto, written, or "": auto for a robot from a file
    sliding_lambda: List[float] = field(
        default_factory=lambda: [40.0, 40.0, 80.0]
    )  # 1/s, lambda
    sliding_gain: List[float] = field(
        default_factory=lambda: [400.0, 400.0, 800.0]
    )  # N s/m, K
    # On an axis without a fuzzy term (R9's PD axes, x3 by default),
    # f_tau_k gets K_k lambda_I,k int s_k dt: K lambda e alone leaves a
    # steady error of (the model's gravity error) / (K lambda) there, and
    # on x3 that error is the cutter's engagement. 0: none (the paper's
    # PD). Below lambda_k, so the integral is the slowest of the axis's
    # modes.
    integral_lambda: List[float] = field(
        default_factory=lambda: [0.0, 0.0, 0.0]
    )  # 1/s, lambda_I
    depth_gain: float = 4.0e-4  # m/(N s), k_delta of (7)
    robust_gain: List[float] = field(
        default_factory=lambda: [2.0, 2.0]
    )  # N, h_bar_k (R10), fuzzy axes
    robust_boundary_layer: List[float] = field(
        default_factory=lambda: [0.005, 0.005]
    )  # m/s, phi_k (R10)
    # s; the paper's 2.5 ms inner loop holds f_tau (zero-order hold);
    # 0: continuous (then use an integrator that is accurate for the
    # controller, e.g. runge_kutta3: cenic treats non-plant systems lagged).
    control_period: float = 0.0025
    # Tool orientation (R9: a PD on the sliding variable s_o = -omega +
    # lambda_o e_o, e_o the rotation vector of R_d R^T, world frame).
    orientation_lambda: List[float] = field(
        default_factory=lambda: [20.0, 20.0, 20.0]
    )  # 1/s
    orientation_gain: List[float] = field(
        default_factory=lambda: [0.0, 0.0, 0.0]
    )  # N m s/rad, K_o
    # A robot of more than 6 joints: a joint-space PD towards the start
    # posture, projected into the null space of the tool frame's Jacobian
    # (tau_n = (I - J^T J^T+) (k (q_0 - q) - d v)), so the redundancy does
    # not drift; unused on 5 and 6 joints. d T / I below 1 on the lightest
    # joint (I its inertia, T control_period) keeps the sampled damper
    # from oscillating.
    null_space_stiffness: float = 200.0  # N m/rad, k
    null_space_damping: float = 10.0  # N m s/rad, d
    gravity_compensation: bool = True  # -, -tau_g from the controller's model
    model_mass_scale: float = 1.2  # -, controller's model masses / true masses
    fuzzy: FuzzyConfig = field(default_factory=FuzzyConfig)
    robust: RobustConfig = field(default_factory=RobustConfig)
    impedance: ImpedanceConfig = field(default_factory=ImpedanceConfig)
    position: PositionConfig = field(default_factory=PositionConfig)

    DESIGNS = ("", "auto", "written")

    def resolved_design(self, robot) -> str:
        """``auto`` or ``written``: ``design``, or by default auto for a
        robot from a file (``robot``: a RobotConfig)."""
        if self.design:
            return self.design
        return "auto" if robot.is_file() else "written"

    def validate(self):
        o = "controller"
        _require(
            self.kind in self.KINDS,
            f"{o}.kind",
            self.kind,
            "one of " + ", ".join(self.KINDS),
        )
        self._validate_shared(o)
        {
            "fuzzy": self._validate_fuzzy,
            "robust": self._validate_robust,
            "ideal": self._validate_ideal,
            "impedance": self.impedance.validate,
            "position": self.position.validate,
        }[self.kind]()

    def _validate_shared(self, o):
        """What every law reads: the controller's shell, K and lambda (the
        gains design writes them whatever the kind), and the fuzzy axes'
        rule base. Every law's state holds the rule weights on those axes
        (one state layout, one log format, whatever the kind), and the
        robust law acts on the same axes, so the rule base is shared; the
        fuzzy law's own part is its adaptation (FuzzyConfig.validate)."""
        _require(
            self.design in self.DESIGNS,
            f"{o}.design",
            self.design,
            "auto, written or '' (auto for a robot from a file)",
        )
        _vector(o, "sliding_lambda", self.sliding_lambda, 3, _positive)
        _vector(o, "sliding_gain", self.sliding_gain, 3, _positive)
        self._validate_integral(o)
        _non_negative(o, "control_period", self.control_period)
        _vector(o, "orientation_lambda", self.orientation_lambda, 3, _positive)
        _vector(o, "orientation_gain", self.orientation_gain, 3, _non_negative)
        _positive(o, "model_mass_scale", self.model_mass_scale)
        _non_negative(o, "null_space_stiffness", self.null_space_stiffness)
        _non_negative(o, "null_space_damping", self.null_space_damping)
        self.fuzzy.validate_rule_base()

    def _validate_integral(self, o):
        _vector(o, "integral_lambda", self.integral_lambda, 3, _non_negative)
        for k, (rate, lam) in enumerate(
            zip(self.integral_lambda, self.sliding_lambda)
        ):
            _require(
                rate == 0.0 or k not in self.fuzzy.axes,
                f"{o}.integral_lambda[{k}]",
                rate,
                "0 on a fuzzy axis (its compensator learns the steady "
                "force there)",
            )
            _require(
                rate < lam,
                f"{o}.integral_lambda[{k}]",
                rate,
                f"a number below sliding_lambda[{k}] = {lam}",
            )

    def _validate_fuzzy(self):
        # robust_gain and robust_boundary_layer are R10's H_bar, the fuzzy
        # law's fallback outside Omega_k (not the robust law's gains), one
        # per fuzzy axis.
        o, n = "controller", len(self.fuzzy.axes)
        _positive(o, "depth_gain", self.depth_gain)
        _vector(o, "robust_gain", self.robust_gain, n, _non_negative)
        _vector(
            o, "robust_boundary_layer", self.robust_boundary_layer, n, _positive
        )
        self.fuzzy.validate()

    def _validate_robust(self):
        _positive("controller", "depth_gain", self.depth_gain)
        self.robust.validate()

    def _validate_ideal(self):
        _positive("controller", "depth_gain", self.depth_gain)
