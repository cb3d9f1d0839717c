"""Typed configuration of deburr_drake: one dataclass per component, composed
into a :class:`Scenario` and loaded from YAML with ``yaml_load_typed``.

Every field is in SI units (m, N, s, rad); the comment on each field gives the
unit. ``validate()`` on each class raises :class:`ConfigError` naming the field
and the allowed range; nothing is clamped. :func:`load_scenario` validates the
whole tree, so a loaded scenario is always usable.
"""


import dataclasses
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import List, Optional

from pydrake.common.yaml import yaml_load_typed

__all__ = [
    "ConfigError",
    "TubeConfig",
    "ToolConfig",
    "EdgeConfig",
    "TaskConfig",
    "CommandConfig",
    "EstimatorConfig",
    "FuzzyConfig",
    "RobustConfig",
    "ImpedanceConfig",
    "PositionConfig",
    "ControllerConfig",
    "SensorConfig",
    "ProcessConfig",
    "BurrConfig",
    "RobotConfig",
    "SimulationConfig",
    "GuardsConfig",
    "PartErrorConfig",
    "DropoutConfig",
    "PartStepConfig",
    "FaultsConfig",
    "Scenario",
    "load_scenario",
    "scenario_names",
    "scenario_path",
    "get_field",
    "set_field",
    "field_type",
]


class ConfigError(ValueError):
    """A configuration value is invalid; the message names the field."""


def _require(ok: bool, name: str, value, allowed: str):
    if not ok:
        raise ConfigError(f"{name} = {value!r} is invalid: allowed {allowed}")


def _positive(owner: str, name: str, value: float):
    _require(
        isinstance(value, (int, float)) and math.isfinite(value) and value > 0,
        f"{owner}.{name}", value, "a finite number > 0")


def _non_negative(owner: str, name: str, value: float):
    _require(
        isinstance(value, (int, float)) and math.isfinite(value)
        and value >= 0,
        f"{owner}.{name}", value, "a finite number >= 0")


def _vector(owner: str, name: str, value, size: int, check):
    _require(len(value) == size, f"{owner}.{name}", value,
             f"a list of {size} numbers")
    for i, v in enumerate(value):
        check(owner, f"{name}[{i}]", v)


@dataclass
class TubeConfig:
    """The part: a tube whose inner top edge is chamfered. Only the edge
    region (the top ``compliant_layer_height`` of the wall) is modelled, as a
    compliant hydroelastic volume mesh."""

    inner_radius: float = 0.030  # m
    wall_thickness: float = 0.005  # m, radial thickness of the modelled wall
    height: float = 0.050  # m, part spans 0 <= z <= height in its frame
    position: List[float] = field(
        default_factory=lambda: [0.0, 0.0, 0.0])  # m, world, bottom centre
    compliant_layer_height: float = 0.006  # m, top part of the wall modelled
    hydroelastic_modulus: float = 4.5e6  # Pa, 10 N/mm at 0.5 mm
    hunt_crossley_dissipation: float = 5.0  # s/m
    # Around the circumference. 120 (chord sag 10 um at 30 mm) with the
    # cutter's 0.6 mm mesh gives within 0.3 % the normal force of 240 with
    # a 0.4 mm cutter mesh (1.835/1.830, 3.695/3.700, 5.711/5.728 N at 0.3,
    # 0.5, 0.7 mm), a ripple along the edge of +-0.006 N (against the
    # sensor's 0.1 N noise) and a contact evaluation 38 % cheaper (188
    # against 301 us): scripts/contact_mesh.py.
    mesh_segments: int = 120
    mesh_radial_cells: int = 2  # through the wall
    mesh_height_cells: int = 2  # through the modelled layer

    def validate(self):
        o = "tube"
        for name in ("inner_radius", "wall_thickness", "height",
                     "compliant_layer_height", "hydroelastic_modulus"):
            _positive(o, name, getattr(self, name))
        _non_negative(o, "hunt_crossley_dissipation",
                      self.hunt_crossley_dissipation)
        _vector(o, "position", self.position, 3, _finite)
        # 1e300 Pa stopped the process inside Drake's contact solver (a
        # C++ failure Python cannot catch, so nothing was written).
        _require(self.hydroelastic_modulus <= 1e12,
                 "tube.hydroelastic_modulus", self.hydroelastic_modulus,
                 "a number in (0, 1e12] Pa (steel's Young's modulus is "
                 "2e11)")
        _require(self.compliant_layer_height <= self.height,
                 "tube.compliant_layer_height", self.compliant_layer_height,
                 f"<= tube.height ({self.height})")
        _require(isinstance(self.mesh_segments, int)
                 and self.mesh_segments >= 16,
                 "tube.mesh_segments", self.mesh_segments, "an integer >= 16")
        for name in ("mesh_radial_cells", "mesh_height_cells"):
            v = getattr(self, name)
            _require(isinstance(v, int) and v >= 2, f"tube.{name}", v,
                     "an integer >= 2 (the mesh needs interior vertices)")


def _finite(owner, name, value):
    _require(isinstance(value, (int, float)) and math.isfinite(value),
             f"{owner}.{name}", value, "a finite number")


@dataclass
class ToolConfig:
    """The cylindrical burr cutter (vertical axis)."""

    cutter_radius: float = 0.003  # m
    cutter_length: float = 0.020  # m
    engagement: float = 0.002  # m, cutter tip below the top edge
    resolution_hint: float = 6.0e-4  # m, the cutter's mesh (TubeConfig)

    def validate(self):
        for name in ("cutter_radius", "cutter_length", "engagement",
                     "resolution_hint"):
            _positive("tool", name, getattr(self, name))
        _require(self.engagement < self.cutter_length, "tool.engagement",
                 self.engagement,
                 f"< tool.cutter_length ({self.cutter_length})")


@dataclass
class EdgeConfig:
    """Which edge, and where and which way the tool runs along it.

    ``circle``: the tube's inner top edge (``tube.*``), from ``start_angle``
    in ``direction``. ``straight``: the top edge of a straight wall of the
    ``tube``'s thickness, height and material, ``length`` long, its middle
    above ``tube.position``; the tool runs along ``heading`` with the
    material on its right."""

    kind: str = "circle"  # circle or straight
    start_angle: float = 0.0  # rad, polar angle of the contour start
    direction: int = 1  # +1 counter-clockwise seen from +z, -1 clockwise
    length: float = 0.1  # m, straight edge only
    heading: float = 1.5707963267948966  # rad, straight: travel direction

    KINDS = ("circle", "straight")

    def validate(self):
        _require(self.kind in self.KINDS, "edge.kind", self.kind,
                 f"one of {self.KINDS}")
        for name in ("start_angle", "heading"):
            v = getattr(self, name)
            _require(isinstance(v, (int, float)) and math.isfinite(v)
                     and abs(v) <= 2 * math.pi, f"edge.{name}", v,
                     "a number in [-2 pi, 2 pi] rad")
        _require(self.direction in (1, -1), "edge.direction", self.direction,
                 "1 or -1")
        _positive("edge", "length", self.length)


@dataclass
class TaskConfig:
    """The deburring task of Section IV."""

    desired_depth: float = 0.0005  # m, delta_d^* of (6)
    desired_chamfering_force: float = 10.0  # N, ||f_td||

    def validate(self):
        _positive("task", "desired_depth", self.desired_depth)
        _positive("task", "desired_chamfering_force",
                  self.desired_chamfering_force)


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
    # The law scales the tool's speed by (f_td - P'_th) / (f_t - P'_th):
    # on a chamfer that vanishes under the tool (a part error larger than
    # the depth) f_t stays near P'_th + v_eps and the feed grew about 20 x
    # per 25 ms sample, to 450 mm/s and the joint-torque guard (the
    # robustness study, issue 12). The steady feed (f_td - P'_th) / g of the
    # study's ranges is at most 14 mm/s (0.2 mm deep, 15 N, k_c - 30 %).
    max_feed: float = 0.02

    def validate(self):
        for name in ("period", "default_feed", "force_offset",
                     "min_tangential_speed", "constant_feed", "max_feed"):
            _positive("command", name, getattr(self, name))
        _require(self.max_feed >= self.default_feed, "command.max_feed",
                 self.max_feed, f">= command.default_feed "
                 f"({self.default_feed})")
        _non_negative("command", "threshold_power_force",
                      self.threshold_power_force)


@dataclass
class EstimatorConfig:
    """Contact-parameter estimator (13)-(18) with R3."""

    initial_estimates: List[float] = field(
        default_factory=lambda: [3.0, 4000.0, 20.0])  # N, N/m, N s/m
    gains: List[float] = field(
        default_factory=lambda: [20.0, 2.0e7, 0.0])  # per parameter
    lower_bounds: List[float] = field(
        default_factory=lambda: [0.1, 100.0, 0.0])  # eps_i: N, N/m, N s/m
    contact_force_threshold: float = 0.2  # N, adapt only above it
    adapt: bool = True

    def validate(self):
        o = "estimator"
        _vector(o, "initial_estimates", self.initial_estimates, 3, _positive)
        _vector(o, "gains", self.gains, 3, _non_negative)
        _vector(o, "lower_bounds", self.lower_bounds, 3, _non_negative)
        for i in range(3):
            _require(self.initial_estimates[i] >= self.lower_bounds[i],
                     f"{o}.initial_estimates[{i}]",
                     self.initial_estimates[i],
                     f">= {o}.lower_bounds[{i}] ({self.lower_bounds[i]})")
        _non_negative(o, "contact_force_threshold",
                      self.contact_force_threshold)


@dataclass
class FuzzyConfig:
    """B-spline adaptive fuzzy compensator (24)-(35), R1, R4, R8."""

    order: int = 2  # m, 0..3
    upsilon: int = 5  # rules per input: 2*upsilon + 1
    position_scale: float = 0.1  # m, x_max normalizing ||x|| (R8)
    sliding_scales: List[float] = field(
        default_factory=lambda: [0.005, 0.005])  # m/s, s_k,max per axis
    width_fraction: float = 0.2  # Delta = width_fraction * scale
    # m/s per axis; empty: (m+1)/2 * Delta_k (R4).
    dead_zone_half_widths: List[float] = field(default_factory=list)
    adaptation_gain: float = 2000.0  # r of (35), N s/m per s
    axes: List[int] = field(default_factory=lambda: [0, 1])  # task axes
    adapt: bool = True

    def deltas(self):
        """(Delta_0, [Delta_k]) in m and m/s."""
        return (self.width_fraction * self.position_scale,
                [self.width_fraction * s for s in self.sliding_scales])

    def validate(self, o="controller.fuzzy"):
        _require(isinstance(self.order, int) and 0 <= self.order <= 3,
                 f"{o}.order", self.order, "an integer in 0..3")
        _require(isinstance(self.upsilon, int) and self.upsilon >= 1,
                 f"{o}.upsilon", self.upsilon, "an integer >= 1")
        _positive(o, "position_scale", self.position_scale)
        _positive(o, "width_fraction", self.width_fraction)
        _positive(o, "adaptation_gain", self.adaptation_gain)
        _require(len(set(self.axes)) == len(self.axes)
                 and all(a in (0, 1, 2) for a in self.axes),
                 f"{o}.axes", self.axes, "distinct task axes from {0, 1, 2}")
        _vector(o, "sliding_scales", self.sliding_scales, len(self.axes),
                _positive)
        _, deltas = self.deltas()
        if self.dead_zone_half_widths:
            _vector(o, "dead_zone_half_widths", self.dead_zone_half_widths,
                    len(self.axes), _non_negative)
            for k, (w, d) in enumerate(zip(self.dead_zone_half_widths,
                                           deltas)):
                _require(w <= self.upsilon * d,
                         f"{o}.dead_zone_half_widths[{k}]", w,
                         f"<= upsilon * Delta_k = {self.upsilon * d:g} m/s "
                         "(the dead zone must lie inside Omega_k)")


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

    gains: List[float] = field(
        default_factory=lambda: [5.0, 0.0, 0.0, 0.0, 0.0])
    # b1 N, b2 N/m, b3 N/m^2, b4 N s/m, b5 N s/m^2

    def validate(self, o="controller.robust"):
        _vector(o, "gains", self.gains, 5, _non_negative)


@dataclass
class ImpedanceConfig:
    """Impedance control at constant feed (the paper's ref. [2]): along n1
    f = k (delta* - delta_x) + d (0 - delta_x') about the nominal path at the
    desired depth, a PD (K s) on the other directions, no force feedback,
    no feedrate law (``command.constant_feed``), no contact estimator."""

    stiffness: float = 40000.0  # N/m along n1 (= lambda K of the x1, x2 PD)
    damping: float = 400.0  # N s/m along n1

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
        default_factory=lambda: [1500.0, 1500.0, 1500.0])  # N s/m

    def validate(self, o="controller.position"):
        _vector(o, "sliding_gain", self.sliding_gain, 3, _positive)


@dataclass
class ControllerConfig:
    """Inner-loop hybrid position/force controller (7), (9)-(11), (36), (37),
    R9, R10. Task axes are world x, y, z of the tool tip.

    ``kind`` selects the law (deburr_drake.baselines): ``fuzzy`` (36), (37);
    ``robust`` (22); ``ideal`` (12) with the true model; ``impedance`` and
    ``position`` at constant feed. Everything else is shared."""

    KINDS = ("fuzzy", "robust", "ideal", "impedance", "position")
    #: Kinds that run at constant feed and ignore the estimator.
    CONSTANT_FEED_KINDS = ("impedance", "position")

    kind: str = "fuzzy"
    sliding_lambda: List[float] = field(
        default_factory=lambda: [40.0, 40.0, 80.0])  # 1/s, lambda
    sliding_gain: List[float] = field(
        default_factory=lambda: [400.0, 400.0, 800.0])  # N s/m, K
    depth_gain: float = 4.0e-4  # m/(N s), k_delta of (7)
    robust_gain: List[float] = field(
        default_factory=lambda: [2.0, 2.0])  # N, h_bar_k (R10), fuzzy axes
    robust_boundary_layer: List[float] = field(
        default_factory=lambda: [0.005, 0.005])  # m/s, phi_k (R10)
    # s; the paper's 2.5 ms inner loop holds f_tau (zero-order hold);
    # 0: continuous (then use an integrator that is accurate for the
    # controller, e.g. runge_kutta3: cenic treats non-plant systems lagged).
    control_period: float = 0.0025
    # Tool orientation (R9: a PD on the sliding variable s_o = -omega +
    # lambda_o e_o, e_o the rotation vector of R_d R^T, world frame).
    orientation_lambda: List[float] = field(
        default_factory=lambda: [20.0, 20.0, 20.0])  # 1/s
    orientation_gain: List[float] = field(
        default_factory=lambda: [0.0, 0.0, 0.0])  # N m s/rad
    # A robot of more than 6 joints: a joint-space PD towards the start
    # posture, projected into the null space of the tool frame's Jacobian
    # (tau_n = (I - J^T J^T+) (k (q_0 - q) - d v)), so the redundancy does
    # not drift; unused on 5 and 6 joints. A 7-joint arm6 (two coaxial
    # flange rolls) held its null coordinate within 1 mrad against 0.04 N m
    # of joint friction; d T / I = 0.13 on its lightest joint.
    null_space_stiffness: float = 200.0  # N m/rad
    null_space_damping: float = 10.0  # N m s/rad
    gravity_compensation: bool = True
    model_mass_scale: float = 1.2  # controller's model masses / true masses
    fuzzy: FuzzyConfig = field(default_factory=FuzzyConfig)
    robust: RobustConfig = field(default_factory=RobustConfig)
    impedance: ImpedanceConfig = field(default_factory=ImpedanceConfig)
    position: PositionConfig = field(default_factory=PositionConfig)

    def validate(self):
        o = "controller"
        _require(self.kind in self.KINDS, f"{o}.kind", self.kind,
                 "one of " + ", ".join(self.KINDS))
        _vector(o, "sliding_lambda", self.sliding_lambda, 3, _positive)
        _vector(o, "sliding_gain", self.sliding_gain, 3, _positive)
        _positive(o, "depth_gain", self.depth_gain)
        _non_negative(o, "control_period", self.control_period)
        _vector(o, "orientation_lambda", self.orientation_lambda, 3,
                _positive)
        _vector(o, "orientation_gain", self.orientation_gain, 3,
                _non_negative)
        _positive(o, "model_mass_scale", self.model_mass_scale)
        _non_negative(o, "null_space_stiffness", self.null_space_stiffness)
        _non_negative(o, "null_space_damping", self.null_space_damping)
        n = len(self.fuzzy.axes)
        _vector(o, "robust_gain", self.robust_gain, n, _non_negative)
        _vector(o, "robust_boundary_layer", self.robust_boundary_layer, n,
                _positive)
        self.fuzzy.validate()
        self.robust.validate()
        self.impedance.validate()
        self.position.validate()


@dataclass
class SensorConfig:
    """Tool force measurement."""

    sample_period: float = 0.0025  # s
    # Hz, first-order low-pass. The controller cancels the measured force
    # (-f in (36)), which holds the process damping g of (3) through the
    # sampled sensor: with the light point-mass testbed that loop went
    # unstable at 50 Hz and was stable at 20 and 30 Hz (measured).
    cutoff_frequency: float = 20.0
    noise_std: float = 0.0  # N, white noise per axis before the filter
    noise_seed: int = 0  # seeds the noise (RandomSource)

    def validate(self):
        _positive("sensor", "sample_period", self.sample_period)
        _positive("sensor", "cutoff_frequency", self.cutoff_frequency)
        _non_negative("sensor", "noise_std", self.noise_std)
        _require(self.cutoff_frequency < 0.5 / self.sample_period,
                 "sensor.cutoff_frequency", self.cutoff_frequency,
                 f"< the Nyquist frequency {0.5 / self.sample_period:g} Hz")
        _require(isinstance(self.noise_seed, int) and self.noise_seed >= 0,
                 "sensor.noise_seed", self.noise_seed, "an integer >= 0")


@dataclass
class BurrConfig:
    """One burr on the edge: a raised-cosine bump of material the cutter
    removes (its cross-section area adds to g of (3))."""

    center_fraction: float = 0.125  # of the edge length from the start
    length: float = 0.008  # m of arc
    height: float = 0.001  # m
    thickness: float = 0.002  # m; cross-section area = height * thickness

    def validate(self, owner="process.burrs[]"):
        _require(isinstance(self.center_fraction, (int, float))
                 and 0.0 <= self.center_fraction < 1.0,
                 f"{owner}.center_fraction", self.center_fraction,
                 "a number in [0, 1)")
        for name in ("length", "height", "thickness"):
            _non_negative(owner, name, getattr(self, name))
        _positive(owner, "length", self.length)


@dataclass
class ProcessConfig:
    """Plant-side truth of the cutting process, eq. (3) and the threshold
    c0 of (4). The controller never reads these values."""

    cutting_coefficient: float = 3.3e9  # N s/m^3, k_c: g = k_c * area
    plunge_coefficient: float = 0.0  # N s/m, h of (3)
    threshold_power_force: float = 2.0  # N, P'_th
    contact_threshold_force: float = 2.0  # N, c0 of (4)
    threshold_depth: float = 2.0e-5  # m, c0 ramps in over this depth
    # m/s: the direction of the threshold force P'_th is sat(v_t / this).
    # The integrator treats a sign flip beyond this band explicitly, so the
    # band must exceed the speed one 2.5 ms step can give it (P'_th h / m:
    # 3 mm/s on the 1.8 kg point mass): at 0.05 mm/s the point mass chattered
    # at 200 Hz after a 2 mm/s kick, at 0.5 mm/s it does not
    # (tests/test_closed_loop.py). No operating point is this slow
    # (v0 = 1 mm/s).
    smoothing_speed: float = 5.0e-4
    burrs: List[BurrConfig] = field(default_factory=list)
    finish_bin_length: float = 2.0e-4  # m of arc per surface-finish bin
    # s: the process samples the tool's place on the edge for the force law
    # (depth, directions, burr at the cutter), records the finish and
    # removes the burr this often.
    sample_period: float = 0.0025

    def validate(self):
        o = "process"
        for name in ("cutting_coefficient", "plunge_coefficient",
                     "threshold_power_force", "contact_threshold_force"):
            _non_negative(o, name, getattr(self, name))
        _positive(o, "threshold_depth", self.threshold_depth)
        _positive(o, "smoothing_speed", self.smoothing_speed)
        _positive(o, "sample_period", self.sample_period)
        _require(isinstance(self.finish_bin_length, (int, float))
                 and 0 < self.finish_bin_length <= 2.0e-4,
                 f"{o}.finish_bin_length", self.finish_bin_length,
                 "a number in (0, 0.0002] m")
        for k, burr in enumerate(self.burrs):
            burr.validate(f"{o}.burrs[{k}]")


@dataclass
class RobotConfig:
    """Which robot holds the tool, the names the cell needs on it, and the
    plant's joint friction (the D term of (1)): viscous damping comes from
    the model file, smooth Coulomb friction F_c tanh(v / v_s) from here.

    ``model`` is a shipped name (``SHIPPED``) or a path to a URDF or SDF
    file (``package://`` URIs inside it resolve as Drake's parser resolves
    them: the ``package.xml`` files in the directories above the file, and
    ``ROS_PACKAGE_PATH``); a relative path in a scenario file is relative to
    that file. The tool: either the model has a body holding the tool, with
    frame ``tool_frame`` at the tool tip (+z along the tool axis, away from
    the part) and a weld joint ``sensor_joint`` (the force/torque sensor)
    as its parent joint (``flange_frame`` empty: arm5 and cartesian_tool),
    or ``flange_frame`` names the model's mounting face (+z out of the
    flange) and the cell welds the sensor (joint ``sensor_joint``) and a
    spindle of ``tool_mass`` there, its tip ``tool_length`` along the
    flange's +z (deburr_drake.cell.robot). The controller's model of the arm
    differs from the plant by ``controller.model_mass_scale``."""

    model: str = "cartesian_tool"  # shipped name, or a .urdf / .sdf path
    joint_coulomb_friction: List[float] = field(
        default_factory=list)  # N or N m per joint; empty: none
    friction_smoothing_speed: float = 1.0e-3  # m/s or rad/s
    tool_frame: str = "tool_tip"  # frame at the tool tip
    sensor_joint: str = "ft_sensor"  # weld joint: the force/torque sensor
    flange_frame: str = ""  # frame the spindle is mounted on; "": none
    tool_length: float = 0.12  # m, flange face to tool tip (flange_frame)
    tool_mass: float = 1.5  # kg, sensor and spindle (flange_frame)
    # rad, one per joint: the inverse kinematics' start and the posture it
    # stays near (elbow up, wrist flipped or not); empty: the model's
    # default (arm5: its ready pose turned towards the part).
    ik_seed: List[float] = field(default_factory=list)

    #: Models shipped in models/ (deburr_drake.cell.robot.SHIPPED_ROBOTS).
    SHIPPED = ("cartesian_tool", "arm5", "arm6")
    FILE_SUFFIXES = (".urdf", ".sdf")

    def is_file(self) -> bool:
        """Whether ``model`` names a file rather than a shipped model."""
        return self.model not in self.SHIPPED

    def validate(self):
        o = "robot"
        _require(isinstance(self.model, str) and (
            self.model in self.SHIPPED
            or Path(self.model).suffix.lower() in self.FILE_SUFFIXES),
            f"{o}.model", self.model,
            f"one of {self.SHIPPED} or a path to a .urdf or .sdf file")
        if self.is_file():
            _require(Path(self.model).is_file(), f"{o}.model", self.model,
                     "an existing .urdf or .sdf file (no such file)")
        for i, f in enumerate(self.joint_coulomb_friction):
            _non_negative(o, f"joint_coulomb_friction[{i}]", f)
        _positive(o, "friction_smoothing_speed",
                  self.friction_smoothing_speed)
        for name in ("tool_frame", "sensor_joint"):
            _require(isinstance(getattr(self, name), str)
                     and getattr(self, name) != "", f"{o}.{name}",
                     getattr(self, name), "a frame or joint name")
        _positive(o, "tool_length", self.tool_length)
        _positive(o, "tool_mass", self.tool_mass)
        for i, q in enumerate(self.ik_seed):
            _require(isinstance(q, (int, float)) and math.isfinite(q),
                     f"{o}.ik_seed[{i}]", q, "a finite angle (rad)")


@dataclass
class SimulationConfig:
    duration: float = 10.0  # s
    plant_time_step: float = 0.0  # s; 0: continuous plant
    contact_approximation: str = "lagged"  # discrete plant only
    integrator: str = "cenic"
    accuracy: float = 1.0e-4
    # s. With cenic and fixed steps it bounds the cutting process's
    # damping the step can hold: cenic treats only the diagonal of the
    # applied forces' d tau / dv implicitly, and the cutting force's g a a^T
    # (a = J^T n2) is off-diagonal on an arm; the paper scenarios take two
    # steps per 2.5 ms sample (README, numerical choices).
    max_step: float = 0.01
    # False: fixed steps of max_step (accuracy unused). With the 2.5 ms
    # sampled loop every step ends at a sample anyway; on 12 s of the paper
    # run cenic's error control at 1e-4 took 14 % more steps and 19 % more
    # wall time for means within 1.5e-4 (scripts/integrator_check.py).
    error_control: bool = True
    # s; the control period: no extra integrator stops (an unaligned 4 ms
    # log cost 50 % more steps), and a limit cycle at the loop's Nyquist
    # frequency shows as sample-to-sample alternation instead of aliasing to
    # a constant as a 5 ms log did.
    log_period: float = 0.0025
    initial_depth: float = 0.0  # m, tool starts at this depth (in contact)
    # Stop when the command has run this many edge lengths (0: run for the
    # whole duration). 1.0 is one full pass of a closed edge.
    stop_after_passes: float = 0.0

    INTEGRATORS = ("cenic", "runge_kutta2", "runge_kutta3", "runge_kutta5",
                   "explicit_euler", "implicit_euler", "radau3")

    def validate(self):
        o = "simulation"
        _positive(o, "duration", self.duration)
        _non_negative(o, "plant_time_step", self.plant_time_step)
        _require(self.contact_approximation in ("lagged", "similar", "sap",
                                                "tamsi"),
                 f"{o}.contact_approximation", self.contact_approximation,
                 "one of lagged, similar, sap, tamsi")
        _require(self.integrator in self.INTEGRATORS,
                 f"{o}.integrator", self.integrator,
                 f"one of {', '.join(self.INTEGRATORS)}")
        for name in ("accuracy", "max_step", "log_period"):
            _positive(o, name, getattr(self, name))
        _non_negative(o, "initial_depth", self.initial_depth)
        _non_negative(o, "stop_after_passes", self.stop_after_passes)


@dataclass
class PartErrorConfig:
    """How the part the controller believes in differs from the real one.
    ``tube`` and ``edge`` describe the real part (the plant, the contact,
    the cutting process and the metrics use it); the command generator,
    the first-order hold, the observer and the start pose use the believed
    part: the real one moved by ``offset``, turned by ``yaw`` about its
    vertical axis (circle: the start angle; straight: the heading about
    ``tube.position``) and with an inner radius ``radius`` larger."""

    offset: List[float] = field(
        default_factory=lambda: [0.0, 0.0, 0.0])  # m, believed - real
    yaw: float = 0.0  # rad, believed - real, about the vertical
    radius: float = 0.0  # m, believed - real inner radius (circle)

    def validate(self):
        o = "part_error"
        _vector(o, "offset", self.offset, 3, _finite)
        _require(isinstance(self.yaw, (int, float)) and math.isfinite(
            self.yaw) and abs(self.yaw) <= math.pi, f"{o}.yaw", self.yaw,
            "a number in [-pi, pi] rad")
        _finite(o, "radius", self.radius)


@dataclass
class DropoutConfig:
    """A window in which the force sensor's reading is lost."""

    start: float = 0.0  # s
    duration: float = 0.0  # s
    mode: str = "hold"  # hold: the last reading; zero: 0 N

    MODES = ("hold", "zero")

    def validate(self, owner="faults.dropouts[]"):
        _non_negative(owner, "start", self.start)
        _positive(owner, "duration", self.duration)
        _require(self.mode in self.MODES, f"{owner}.mode", self.mode,
                 f"one of {self.MODES}")


@dataclass
class PartStepConfig:
    """The part moves in its fixture at ``time`` by ``offset``. The real
    part is fixed in the plant (welded hydroelastic geometry), so the step
    is applied to the part the controller believes in, by -``offset``:
    from ``time`` on, the observer and the command generator see the part
    where it was before while it is ``offset`` away, the error a slipped
    fixture gives the controller (without the contact's own jolt)."""

    time: float = 0.0  # s; 0: no step
    offset: List[float] = field(
        default_factory=lambda: [0.0, 0.0, 0.0])  # m, world, real part's move

    def validate(self, owner="faults.part_step"):
        _non_negative(owner, "time", self.time)
        _vector(owner, "offset", self.offset, 3, _finite)
        _require(self.time == 0.0 or any(self.offset), f"{owner}.offset",
                 self.offset, f"not all zero when {owner}.time > 0")

    def active(self) -> bool:
        return self.time > 0.0


@dataclass
class FaultsConfig:
    """Faults a deburring cell meets, injected by Drake systems in the
    diagram (deburr_drake.cell.faults); none by default. See also
    ``part_error`` (the part not where the controller thinks it is)."""

    # N, world, added to the force reading the controller and observer get
    sensor_bias: List[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    noise_scale: float = 1.0  # x sensor.noise_std
    dropouts: List[DropoutConfig] = field(default_factory=list)
    part_step: PartStepConfig = field(default_factory=PartStepConfig)

    def validate(self):
        o = "faults"
        _vector(o, "sensor_bias", self.sensor_bias, 3, _finite)
        _non_negative(o, "noise_scale", self.noise_scale)
        for k, d in enumerate(self.dropouts):
            d.validate(f"{o}.dropouts[{k}]")
        self.part_step.validate(f"{o}.part_step")

    def sensor_faults(self) -> bool:
        """True if the force reading is biased or drops out."""
        return any(self.sensor_bias) or bool(self.dropouts)


@dataclass
class GuardsConfig:
    """Runtime safety guards (deburr_drake.cell.guards): each stops the run with
    ``stop_reason`` ``guard:<name>`` and its values at the trip. A limit of
    0 takes the default derived from the models and the task."""

    enabled: bool = True
    # Trip when any |tau_i| exceeds this fraction of the joint's effort
    # limit (the robot model's <effort>); joints without one are not checked.
    joint_torque_fraction: float = 1.0
    tool_force: float = 0.0  # N, |measured f|; 0: 10 x desired |f_t|
    depth: float = 0.0  # m, chamfer depth; 0: min(4 x desired, cutter radius)
    workspace_margin: float = 0.02  # m, around the edge's bounding box
    contact_lost_time: float = 1.0  # s below contact_force after contact
    contact_force: float = 1.0  # N, ||f_n|| above it is contact
    nan: bool = True  # any NaN or infinity in a logged signal
    # s; all guards are checked this often, the joint torque also at every
    # inner-loop sample. A multiple of the 2.5 ms inner loop adds no
    # integrator steps. On a 10 s paper run (scripts/bench_guards.py) all
    # guards every 2.5 ms took 4.5-4.7 % of the CPU time; every 10 ms with
    # the torque every 2.5 ms 2.7-2.8 %.
    check_period: float = 0.02
    # The drives clamp the commanded torque at the effort limits, as real
    # ones do: a guard sees a torque one sample after it is commanded, so
    # without the clamp the plant would take one sample of it.
    saturate_effort: bool = True

    def validate(self):
        o = "guards"
        _positive(o, "joint_torque_fraction", self.joint_torque_fraction)
        for name in ("tool_force", "depth"):
            _non_negative(o, name, getattr(self, name))
        for name in ("workspace_margin", "contact_lost_time",
                     "contact_force", "check_period"):
            _positive(o, name, getattr(self, name))
        _require(self.contact_lost_time > self.check_period,
                 "guards.contact_lost_time", self.contact_lost_time,
                 f"> guards.check_period ({self.check_period})")


@dataclass
class Scenario:
    """Everything one simulation needs."""

    name: str = "point_mass"
    robot: RobotConfig = field(default_factory=RobotConfig)
    tube: TubeConfig = field(default_factory=TubeConfig)
    tool: ToolConfig = field(default_factory=ToolConfig)
    edge: EdgeConfig = field(default_factory=EdgeConfig)
    task: TaskConfig = field(default_factory=TaskConfig)
    command: CommandConfig = field(default_factory=CommandConfig)
    estimator: EstimatorConfig = field(default_factory=EstimatorConfig)
    controller: ControllerConfig = field(default_factory=ControllerConfig)
    sensor: SensorConfig = field(default_factory=SensorConfig)
    process: ProcessConfig = field(default_factory=ProcessConfig)
    simulation: SimulationConfig = field(default_factory=SimulationConfig)
    guards: GuardsConfig = field(default_factory=GuardsConfig)
    part_error: PartErrorConfig = field(default_factory=PartErrorConfig)
    faults: FaultsConfig = field(default_factory=FaultsConfig)

    def validate(self):
        # The default output directory is out/<name>: a plain file name.
        _require(isinstance(self.name, str)
                 and re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9_.+-]*", self.name)
                 is not None, "name", self.name,
                 "a plain file name of letters, digits and _ . + - "
                 "(no path separators, no leading dot)")
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if hasattr(value, "validate"):
                value.validate()
        _require(self.task.desired_depth < self.tube.wall_thickness,
                 "task.desired_depth", self.task.desired_depth,
                 f"< tube.wall_thickness ({self.tube.wall_thickness})")
        _require(self.tool.engagement < self.tube.compliant_layer_height,
                 "tool.engagement", self.tool.engagement,
                 "< tube.compliant_layer_height "
                 f"({self.tube.compliant_layer_height})")
        _require(self.tool.cutter_radius < self.tube.inner_radius,
                 "tool.cutter_radius", self.tool.cutter_radius,
                 f"< tube.inner_radius ({self.tube.inner_radius})")
        _require(self.task.desired_depth < self.tool.cutter_radius,
                 "task.desired_depth", self.task.desired_depth,
                 f"< tool.cutter_radius ({self.tool.cutter_radius})")
        _require(self.simulation.initial_depth
                 < min(self.tool.cutter_radius, self.tube.wall_thickness),
                 "simulation.initial_depth", self.simulation.initial_depth,
                 "< tool.cutter_radius and tube.wall_thickness "
                 f"({min(self.tool.cutter_radius, self.tube.wall_thickness)})")
        believed = self.tube.inner_radius + self.part_error.radius
        _require(self.tool.cutter_radius < believed
                 and abs(self.part_error.radius) < self.tube.wall_thickness,
                 "part_error.radius", self.part_error.radius,
                 "|radius| < tube.wall_thickness "
                 f"({self.tube.wall_thickness}) with the believed inner "
                 f"radius > tool.cutter_radius ({self.tool.cutter_radius})")
        inner = self.controller.control_period
        if inner > 0:
            period = self.command.period
            ratio = period / inner
            _require(ratio >= 1 - 1e-9 and abs(ratio - round(ratio)) < 1e-6,
                     "command.period", period,
                     "a whole multiple >= 1 of controller.control_period "
                     f"({inner:g} s): the outer loop samples the inner one")
            ratio = self.guards.check_period / inner
            _require(ratio >= 1 - 1e-9 and abs(ratio - round(ratio)) < 1e-6,
                     "guards.check_period", self.guards.check_period,
                     "a whole multiple >= 1 of controller.control_period "
                     f"({inner:g} s): other times add integrator steps")
        return self


# Scenario fields by dotted name (``--set``, stability maps, sweeps).

def _parse_path(path: str):
    """'controller.sliding_gain[0]' -> [('controller', None),
    ('sliding_gain', 0)]."""
    parts = []
    for token in path.split("."):
        index = None
        if token.endswith("]") and "[" in token:
            token, _, rest = token.partition("[")
            try:
                index = int(rest[:-1])
            except ValueError:
                raise ConfigError(f"{path!r}: bad index [{rest}") from None
        parts.append((token, index))
    return parts


def get_field(scenario, path: str):
    obj = scenario
    for name, index in _parse_path(path):
        if not hasattr(obj, "__dataclass_fields__") or \
                name not in obj.__dataclass_fields__:
            raise ConfigError(f"{path!r} is not a scenario field "
                              f"({name!r} unknown)")
        obj = getattr(obj, name)
        if index is not None:
            if not isinstance(obj, list) or not -len(obj) <= index < len(obj):
                raise ConfigError(f"{path!r}: index {index} out of range")
            obj = obj[index]
    return obj


def set_field(scenario, path: str, value):
    """Sets a scenario field by dotted name (``sensor.cutoff_frequency``,
    ``controller.sliding_gain[0]``); ConfigError names an unknown one."""
    get_field(scenario, path)  # validates the path
    parts = _parse_path(path)
    obj = scenario
    for name, index in parts[:-1]:
        obj = getattr(obj, name)
        if index is not None:
            obj = obj[index]
    name, index = parts[-1]
    if index is None:
        current = getattr(obj, name)
        setattr(obj, name, type(current)(value)
                if isinstance(current, (int, float)) else value)
    else:
        getattr(obj, name)[index] = float(value)


def field_type(scenario, path: str):
    """The declared type of a scenario field by dotted name: ``float``,
    ``int``, ``bool``, ``str``, a ``List[...]`` or a dataclass."""
    import typing
    get_field(scenario, path)  # validates the path
    obj = scenario
    for name, index in _parse_path(path):
        hint = typing.get_type_hints(type(obj))[name]
        obj = getattr(obj, name)
        if index is not None:
            (hint,) = typing.get_args(hint)
            obj = obj[index]
    return hint


_SCENARIO_DIR = Path(__file__).resolve().parent / "scenarios"


def scenario_names() -> List[str]:
    """Names of the scenarios shipped in the package."""
    return sorted(p.stem for p in _SCENARIO_DIR.glob("*.yaml"))


def scenario_path(name: str) -> Path:
    path = _SCENARIO_DIR / f"{name}.yaml"
    if not path.exists():
        raise ConfigError(
            f"scenario {name!r} is unknown: allowed {scenario_names()} "
            "or a path to a YAML file")
    return path


def _schema_error(where: str, node, message: str):
    mark = node.start_mark
    raise ConfigError(f"{where}:{mark.line + 1}:{mark.column + 1}: {message}")


_TAG = "tag:yaml.org,2002:"


def _check_node(where: str, node, schema, path: str):
    """Checks a composed YAML node against the dataclass ``schema``: every
    key known (named with its full dotted path), no key twice, every value
    of the field's type. One ConfigError with file:line:column."""
    import typing

    import yaml
    origin = typing.get_origin(schema)
    if dataclasses.is_dataclass(schema):
        known = {f.name for f in dataclasses.fields(schema)}
        if not isinstance(node, yaml.MappingNode):
            _schema_error(where, node, f"{path or 'the scenario'} must be a "
                          f"mapping of {sorted(known)}")
        hints = typing.get_type_hints(schema)
        seen = {}
        for key_node, value_node in node.value:
            key = key_node.value
            name = f"{path}.{key}" if path else key
            if key in seen:
                _schema_error(where, key_node,
                              f"{name} is given twice (first at line "
                              f"{seen[key].start_mark.line + 1})")
            seen[key] = key_node
            if key not in known:
                _schema_error(where, key_node,
                              f"{name} is unknown: allowed fields of "
                              f"{path or 'the scenario'}: {sorted(known)}")
            _check_node(where, value_node, hints[key], name)
        return
    if origin is dict:
        key_type, item = typing.get_args(schema)
        if not isinstance(node, yaml.MappingNode):
            _schema_error(where, node, f"{path} = {_shown(node)} is invalid: "
                          "allowed a mapping")
        seen = {}
        for key_node, value_node in node.value:
            name = f"{path}.{key_node.value}"
            if key_node.value in seen:
                _schema_error(where, key_node,
                              f"{name} is given twice (first at line "
                              f"{seen[key_node.value].start_mark.line + 1})")
            seen[key_node.value] = key_node
            _check_node(where, value_node, item, name)
        return
    if origin in (list, List):
        (item,) = typing.get_args(schema)
        if not isinstance(node, yaml.SequenceNode):
            kind = {float: "numbers", int: "integers", bool: "booleans",
                    str: "strings"}.get(item, "mappings")
            _schema_error(where, node, f"{path} = {_shown(node)} is invalid: "
                          f"allowed a list of {kind}")
        for k, child in enumerate(node.value):
            _check_node(where, child, item, f"{path}[{k}]")
        return
    tags = {float: ("float", "int"), int: ("int",), bool: ("bool",),
            str: ("str",)}.get(schema)
    if tags is None:
        return
    kinds = {float: "a number", int: "an integer", bool: "true or false",
             str: "a string"}
    if schema is float and isinstance(node, yaml.ScalarNode) \
            and node.tag == _TAG + "str" and node.style is None:
        try:  # YAML 1.1 reads 4.5e6 as a string; the loader takes it
            float(node.value)
            return
        except ValueError:
            pass
    if not (isinstance(node, yaml.ScalarNode)
            and node.tag in [_TAG + t for t in tags]):
        _schema_error(where, node, f"{path} = {_shown(node)} is invalid: "
                      f"allowed {kinds[schema]}")


def _shown(node) -> str:
    import yaml
    if isinstance(node, yaml.ScalarNode):
        return repr(node.value)
    return "a list" if isinstance(node, yaml.SequenceNode) else "a mapping"


def _check_yaml(text: str, where: str, schema=None, path: str = ""):
    """Syntax (file:line:column), duplicate and unknown keys, and types of
    the YAML ``text`` against ``schema`` (:class:`Scenario` by default;
    fields named under ``path``), before it is loaded."""
    import yaml
    try:
        root = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.MarkedYAMLError as e:
        mark = e.problem_mark or e.context_mark
        problem = e.problem or ""
        if e.context:
            c = e.context_mark
            problem += f" ({e.context}" + (
                f" at {c.line + 1}:{c.column + 1})" if c else ")")
        at = f":{mark.line + 1}:{mark.column + 1}" if mark else ""
        raise ConfigError(f"{where}{at}: YAML syntax error: {problem}") \
            from None
    except yaml.YAMLError as e:
        raise ConfigError(f"{where}: YAML error: "
                          f"{' '.join(str(e).split())}") from None
    if root is None:
        return
    _check_node(where, root, schema or Scenario, path)


def _scenario_file(name_or_path: str) -> Path:
    path = Path(name_or_path)
    looks_like_path = path.suffix in (".yaml", ".yml") or len(path.parts) > 1
    if not looks_like_path:
        return scenario_path(str(name_or_path))
    if path.is_dir():
        raise ConfigError(f"--scenario {name_or_path} is a directory: "
                          "allowed a YAML file or one of "
                          f"{scenario_names()}")
    if not path.is_file():
        raise ConfigError(f"--scenario {name_or_path}: no such file: "
                          f"allowed a YAML file or one of {scenario_names()}")
    return path


def _resolve_robot_model(robot: RobotConfig, directory: Path):
    """A relative model file in a scenario file is relative to that file."""
    if robot.is_file() and not Path(robot.model).is_absolute():
        candidate = directory / robot.model
        if candidate.is_file():
            robot.model = str(candidate.resolve())


def load_scenario(name_or_path: Optional[str] = None, *,
                  text: Optional[str] = None) -> Scenario:
    """Loads a scenario by package name or file path, then applies ``text``
    (YAML overrides) on top, and validates it.

    Raises ConfigError with one line naming the problem (unknown field,
    wrong type, value out of range)."""
    scenario = Scenario()
    try:
        if name_or_path is not None:
            path = _scenario_file(str(name_or_path))
            try:
                source = path.read_text()
            except (OSError, UnicodeDecodeError) as e:
                raise ConfigError(f"--scenario {path}: cannot read: {e}") \
                    from None
            _check_yaml(source, str(path))
            scenario = yaml_load_typed(filename=str(path), defaults=scenario)
            _resolve_robot_model(scenario.robot, path.parent)
        if text:
            _check_yaml(text, "--scenario-text")
            scenario = yaml_load_typed(data=text, defaults=scenario)
    except ConfigError:
        raise
    except (RuntimeError, ValueError, TypeError, AssertionError) as e:
        where = name_or_path if text is None else "--scenario-text"
        raise ConfigError(f"{where}: {e}") from None
    return scenario.validate()
