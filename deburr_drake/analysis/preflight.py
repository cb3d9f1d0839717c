"""Pre-flight: the sampled loop at the start pose, before a run.

``deburr-drake simulate``, ``compare`` and ``sweep`` call :func:`preflight`
on every scenario before anything runs (``--no-preflight`` skips it):

- with ``controller.design: auto`` (the default for a robot from a file)
  the gains are designed from the model (deburr_drake.cell.gains) and
  proven here: the one-period map of the 2.5 ms loop at the start pose
  must have rho < 1 at the designed gains **and at twice their K and K_o**
  (a gain margin of 2, 6 dB). A margin on rho itself says nothing: at any
  pose rho sits within 1e-3 of 1 from the slow depth and posture modes
  (the paper arm's 0.99915), while what goes unstable when a gain is too
  high for the sampled loop is a fast mode near the Nyquist frequency,
  whose distance from the unit circle a factor on the gains measures.
  Where twice the gains are not stable, K and K_o are scaled down
  together until they are;
- for every robot and written gains too, rho >= 1 at the start pose
  refuses the run: one ConfigError line naming the gain, the predicted
  rho and the largest stable value of that gain (the others as written).

The map is :func:`deburr_drake.analysis.sampled.period_map` on the cell
frozen as the analysis freezes it (:func:`frozen_scenario`), taken at the
first inner-loop sample after the start (2.5 ms), the tool at the start of
the edge, reached with the feedback gains near zero (so the state is the
same for every gain checked). It is split, as
:func:`deburr_drake.analysis.maps.fast_rho` does, into the sample at t_k
(affine in each gain: f_tau = K s ..., m = K_o s_o) and the integration
over the period, so rho at other gains costs an eigenvalue problem each.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
import time
from typing import Callable, Dict, List, Optional, Union

import numpy as np
from pydrake.systems.framework import Diagram

from deburr_drake.analysis.operating_point import (
    OperatingPoint,
    _next_analysis_time,
    _signals,
    frozen_scenario,
)
from deburr_drake.analysis.sampled import (
    frozen_cell,
    frozen_in_place,
    period_map,
    rest_of_period_map,
    simulator_config,
    spectral_radius,
)
from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.cell.gains import GainDesign
from deburr_drake.cell.plan import CellPlan, plan_cell
from deburr_drake.config import ConfigError, Scenario, get_field
from deburr_drake.runs.simulation import make_simulator

__all__ = [
    "Preflight",
    "preflight",
    "start_operating_point",
    "GainMaps",
    "GAIN_MARGIN",
]

#: The designed K and K_o times this must still give rho < 1.
GAIN_MARGIN = 2.0
#: The design's K and K_o are scaled down for the margin to this at most.
MIN_MARGIN_SCALE = 0.25
#: |z| of the map known to this: its columns are finite differences of
#: 1e-8..1e-5 perturbations. A mode within it of the unit circle is neutral
#: (marginal), not predicted unstable: a held torque's mode can sit there
#: whatever the gains, and the run completes.
NEUTRAL_TOLERANCE = 1e-6


def predicted_unstable(rho: float) -> bool:
    """rho (the map's spectral radius) beyond the unit circle by more than
    :data:`NEUTRAL_TOLERANCE`, or not finite."""
    return not rho <= 1.0 + NEUTRAL_TOLERANCE


#: Gains the pre-flight names, element by element, then as groups.
GAIN_FIELDS = (
    "controller.sliding_gain",
    "controller.orientation_gain",
    "controller.null_space_damping",
)
_SPLIT = 1e-9  # s: the sample's end within the period


def _planned(plan) -> CellPlan:
    return plan_cell(plan) if isinstance(plan, Scenario) else plan


def start_operating_point(
    plan: Union[CellPlan, Scenario], *, diagram: Optional[Diagram] = None
) -> OperatingPoint:
    """The cell at the first inner-loop sample after the start that is not
    an outer-loop sample (2.5 ms: the tool at the start of the edge), its
    updates pending, as an :class:`OperatingPoint` of the plan's scenario
    (a scenario is planned first). ``diagram``: the plan's, if built
    already (the run's: the pre-flight builds none of its own). The first
    period is run with K and K_o (the controller's parameters) at 1e-9 of
    theirs, so the state does not depend on the gains checked (a gain far
    too high moves the arm within one sample); the operating point's
    context holds them as the scenario has them."""
    plan = _planned(plan)
    scenario = plan.scenario
    if diagram is None:
        diagram = make_deburring_diagram(plan)
    simulator = make_simulator(diagram, scenario)
    context = simulator.get_mutable_context()
    controller = diagram.GetSubsystemByName("controller")
    K, K_o = controller.gains(controller.GetMyContextFromRoot(context))
    controller.set_gains(
        controller.GetMyMutableContextFromRoot(context),
        sliding_gain=1e-9 * K,
        orientation_gain=1e-9 * K_o,
    )
    simulator.Initialize()
    inner = scenario.controller.control_period
    t = _next_analysis_time(0.5 * inner, inner, scenario.command.period)
    simulator.AdvanceTo(t)
    signals = _signals(diagram, context)
    context = context.Clone()
    controller.set_gains(
        controller.GetMyMutableContextFromRoot(context),
        sliding_gain=K,
        orientation_gain=K_o,
    )
    return OperatingPoint(
        scenario=scenario,
        diagram=diagram,
        context=context,
        time=t,
        contact_time=0.0,
        signals=signals,
        plan=plan,
    )


class GainMaps:
    """The one-period map at an operating point split into the sample
    (affine in each gain) and the integration; :meth:`rho` at any gains
    along the paths given to :meth:`add_path`."""

    def __init__(self, op: OperatingPoint):
        self.op = op
        self.base = frozen_scenario(op.scenario)
        self.config = simulator_config(self.base)
        self.period = self.base.controller.control_period
        # The run's own diagram as the frozen cell (sampled.frozen_in_place).
        self._frozen = frozen_in_place(op)
        diagram, context, entries = self._prepared({})
        self.sample0 = period_map(
            diagram, context, entries, period=_SPLIT, config=self.config
        )
        self.integrate = rest_of_period_map(
            diagram, context, entries, _SPLIT, self.period, self.config
        )
        self.slopes: Dict[str, np.ndarray] = {}

    def _prepared(self, overrides):
        """(diagram, context, entries) of the frozen cell with
        ``overrides``: the one frozen diagram with K and K_o set in a
        context (the controller's parameters) where only they change, a
        diagram of its own otherwise."""
        variant = frozen_scenario(self.op.scenario, **overrides)
        c = variant.controller
        same = copy.deepcopy(variant)
        same.controller.sliding_gain = self.base.controller.sliding_gain
        same.controller.orientation_gain = self.base.controller.orientation_gain
        if same != self.base:
            return frozen_cell(self.op, overrides)
        diagram, context, entries = self._frozen
        context = context.Clone()
        controller = diagram.GetSubsystemByName("controller")
        controller.set_gains(
            controller.GetMyMutableContextFromRoot(context),
            sliding_gain=c.sliding_gain,
            orientation_gain=c.orientation_gain,
        )
        return diagram, context, entries

    def add_path(self, name: str, overrides_at: Callable[[float], dict]):
        """A path through the gains: ``overrides_at(c)`` the scenario
        fields at coordinate c (c = 1: as the scenario has them), affine in
        c."""
        d, c, e = self._prepared(overrides_at(2.0))
        sample = period_map(d, c, e, period=_SPLIT, config=self.config)
        self.slopes[name] = sample - self.sample0  # per unit of c

    def rho(self, **coordinates) -> float:
        """rho with each path's coordinate (default 1)."""
        S = self.sample0.copy()
        for name, c in coordinates.items():
            S += (c - 1.0) * self.slopes[name]
        return spectral_radius(self.integrate @ S)

    @property
    def rho_full(self) -> float:
        """rho of the whole period's map at the gains as written: the
        integration after the sample. The period's map taken in one piece
        (:meth:`full_map`) gives the same within the maps' resolution
        (paper: 1.2e-10, a point mass 1e-7, below NEUTRAL_TOLERANCE) at
        half again the cost."""
        return self.rho()

    def full_map(self) -> np.ndarray:
        """The whole period's map, not split (a check of the split)."""
        diagram, context, entries = self._prepared({})
        return period_map(
            diagram, context, entries, period=self.period, config=self.config
        )

    def largest_stable(
        self, name: str, *, iterations: int = 20
    ) -> Optional[float]:
        """The largest coordinate in (0, 1] of path ``name`` with rho < 1
        (the others at 1): down from 1 by factors of 0.7 to the first
        stable one, then bisection; None if none down to 1e-3 is (a gain
        of zero leaves a position loop open: rho = 1 there)."""
        hi = 1.0
        if not predicted_unstable(self.rho(**{name: hi})):
            return hi
        lo = hi
        while True:
            lo *= 0.7
            if lo < 1e-3:
                return None
            if not predicted_unstable(self.rho(**{name: lo})):
                break
            hi = lo
        for _ in range(iterations):
            mid = 0.5 * (lo + hi)
            if not predicted_unstable(self.rho(**{name: mid})):
                lo = mid
            else:
                hi = mid
        return lo


def _scaled(path: str, values, c: float) -> dict:
    return {f"{path}[{i}]": c * v for i, v in enumerate(values)}


@dataclass
class Preflight:
    """What the pre-flight found (SI units)."""

    rho: float  # the one-period map's spectral radius at the start pose
    time: float  # s, where it was taken
    design: Optional[GainDesign] = None  # when controller.design is auto
    # The plan checked: the caller's, or with the design scaled for the
    # gain margin a new plan of the same cell.
    plan: Optional[CellPlan] = None
    # The plan's diagram the maps were taken on (None: no sampled loop).
    diagram: Optional[Diagram] = None
    rho_at_margin: Optional[float] = None  # rho at GAIN_MARGIN x K, K_o
    margin_scale: float = 1.0  # the design's K, K_o scaled by this
    seconds: float = 0.0
    lines: List[str] = field(default_factory=list)

    @property
    def scenario(self) -> Optional[Scenario]:
        """The scenario checked, as it will run (the design written)."""
        return None if self.plan is None else self.plan.scenario

    def to_dict(self) -> dict:
        out = {
            "predicted_rho": self.rho,
            "time_s": self.time,
            "seconds": self.seconds,
        }
        if self.design is not None:
            out.update(
                {
                    "design": "auto",
                    "gains": self.design.as_fields(),
                    "numbers": self.design.numbers,
                    "gain_margin": GAIN_MARGIN,
                    "rho_at_gain_margin": self.rho_at_margin,
                    "margin_scale": self.margin_scale,
                }
            )
        return out


def op_joints(maps: GainMaps) -> int:
    """The robot's joints (the plant's velocities) at the operating point."""
    return maps.op.diagram.GetSubsystemByName("plant").num_velocities()


def _down(x: float) -> str:
    """x to 3 significant digits, rounded toward zero: a largest stable
    value printed is itself stable (rounding up may cross the limit)."""
    if not x > 0:
        return f"{x:.3g}"
    unit = 10.0 ** (np.floor(np.log10(x)) - 2)
    return f"{np.floor(x / unit) * unit:.3g}"


def _refusal(scenario: Scenario, maps: GainMaps, rho: float) -> str:
    """The one line naming the gain to lower: an element whose largest
    stable value is the smallest change, else a whole gain vector scaled,
    else all of K and K_o scaled together."""
    candidates = []
    for path in GAIN_FIELDS:
        if path == "controller.null_space_damping" and op_joints(maps) <= 6:
            continue
        value = get_field(scenario, path)
        values = value if isinstance(value, list) else [value]
        for i, v in enumerate(values):
            if v <= 0:
                continue
            name = f"{path}[{i}]" if isinstance(value, list) else path
            maps.add_path(name, lambda c, n=name, v=v: {n: c * v})
            c = maps.largest_stable(name)
            if c is not None:
                candidates.append((c, name, v, c * v))
    if candidates:
        c, name, v, stable = max(candidates)
        return (
            f"{name} = {v:g} is predicted unstable: the sampled loop "
            f"at the start pose has rho = {rho:.4f} (> 1); the largest "
            f"stable {name} is {_down(stable)} with the other gains as "
            "written (--no-preflight runs anyway)"
        )
    for path in GAIN_FIELDS[:2]:
        values = list(get_field(scenario, path))
        maps.add_path(path, lambda c, p=path, v=values: _scaled(p, v, c))
        c = maps.largest_stable(path)
        if c is not None:
            candidates.append((c, path, values))
    if candidates:
        c, path, values = max(candidates)
        return (
            f"{path} = {values} is predicted unstable: the sampled loop"
            f" at the start pose has rho = {rho:.4f} (> 1); the largest "
            f"stable {path}, scaled together, is "
            f"{[float(f'{c * v:.3g}') for v in values]} with the other "
            "gains as written (--no-preflight runs anyway)"
        )
    K = list(scenario.controller.sliding_gain)
    K_o = list(scenario.controller.orientation_gain)
    maps.add_path(
        "both",
        lambda c: {
            **_scaled("controller.sliding_gain", K, c),
            **_scaled("controller.orientation_gain", K_o, c),
        },
    )
    c = maps.largest_stable("both")
    if c is None:
        return (
            f"controller.sliding_gain = {K} and "
            f"controller.orientation_gain = {K_o} are predicted "
            f"unstable: the sampled loop at the start pose has rho = "
            f"{rho:.4f} (> 1), and lowering them does not make it "
            "stable (--no-preflight runs anyway)"
        )
    return (
        f"controller.sliding_gain = {K} and controller.orientation_gain"
        f" = {K_o} are predicted unstable: the sampled loop at the start "
        f"pose has rho = {rho:.4f} (> 1), and neither lowered alone makes"
        f" it stable; the largest stable, both scaled together: "
        f"{[float(_down(c * v)) for v in K]} and "
        f"{[float(_down(c * v)) for v in K_o]} (x {_down(c)}; "
        "controller.design: auto designs them; --no-preflight runs "
        "anyway)"
    )


def _both_paths(maps: GainMaps, scenario: Scenario):
    K = list(scenario.controller.sliding_gain)
    K_o = list(scenario.controller.orientation_gain)
    maps.add_path("K", lambda c: _scaled("controller.sliding_gain", K, c))
    maps.add_path(
        "K_o", lambda c: _scaled("controller.orientation_gain", K_o, c)
    )


def preflight(
    plan: Union[CellPlan, Scenario],
    *,
    diagram: Optional[Diagram] = None,
    say: Callable[[str], None] = lambda line: None,
) -> Preflight:
    """Proves the gains the plan designed (``controller.design`` auto; a
    scenario is planned first), then checks the sampled loop at the start
    pose; ConfigError (one line: the gain, rho, its largest stable value)
    if it is predicted unstable. ``diagram``: the plan's, if built
    already (the run's): the operating point is taken on it. Returns what
    it found, with ``plan`` the one checked (a new plan, the design
    scaled, where the design did not hold the gain margin)."""
    t0 = time.perf_counter()
    plan = _planned(plan)
    scenario = plan.scenario
    c = scenario.controller
    if not c.control_period > 0:
        return Preflight(
            rho=float("nan"),
            time=0.0,
            lines=[
                "pre-flight: controller.control_period 0 "
                "(a continuous controller): no sampled "
                "loop to check"
            ],
            plan=plan,
        )
    # The one-period map at the start pose.
    op = start_operating_point(plan, diagram=diagram)
    maps = GainMaps(op)
    result = Preflight(
        rho=maps.rho_full,
        time=op.time,
        design=plan.design,
        plan=plan,
        diagram=op.diagram,
    )
    # A design must hold the gain margin: K and K_o scaled down till it
    # does.
    if plan.design is not None and not predicted_unstable(result.rho):
        maps = _hold_gain_margin(scenario, maps, result)
    scenario, rho = result.scenario, result.rho
    if result.design is not None:
        result.lines += _design_lines(result, scenario.controller)
    for line in result.lines:
        say(line)
    # Predicted unstable: the one line naming the gain to lower.
    if predicted_unstable(rho):
        raise ConfigError(_refusal(scenario, maps, rho))
    if rho >= 1.0:
        result.lines.append(
            f"pre-flight: a mode at |z| = {rho:.7f}, on the unit circle within"
            f" the map's resolution ({NEUTRAL_TOLERANCE:g}): neutral"
        )
        say(result.lines[-1])
    result.seconds = time.perf_counter() - t0
    result.lines.append(
        f"pre-flight: the sampled loop at the start pose is "
        f"{'stable' if rho < 1.0 else 'not unstable (neutral)'}, "
        f"rho = {rho:.7f} ({result.seconds:.1f} s)"
    )
    say(result.lines[-1])
    return result


def _hold_gain_margin(
    scenario: Scenario, maps: GainMaps, result: Preflight
) -> GainMaps:
    """rho at GAIN_MARGIN x the designed K and K_o into ``result``; where
    it is not stable, K and K_o scaled down by 0.7 at a time (to
    MIN_MARGIN_SCALE at most) until it is, the scaled design written into
    ``result`` (and a plan of it: the slope bound follows the gains, so
    its diagram is built anew) and the start pose's map taken again.
    Returns the maps of the gains kept."""
    _both_paths(maps, scenario)
    result.rho_at_margin = maps.rho(K=GAIN_MARGIN, K_o=GAIN_MARGIN)
    scale = 1.0
    while predicted_unstable(result.rho_at_margin) and scale > MIN_MARGIN_SCALE:
        scale *= 0.7
        result.rho_at_margin = maps.rho(
            K=GAIN_MARGIN * scale, K_o=GAIN_MARGIN * scale
        )
    if predicted_unstable(result.rho_at_margin):
        # Not the gains (twice a quarter of them is not stable either):
        # the design as it is, and the margin it does not hold said.
        result.rho_at_margin = maps.rho(K=GAIN_MARGIN, K_o=GAIN_MARGIN)
    elif scale < 1.0:
        design = result.design.scaled(scale)
        plan = result.plan.with_design(design)
        result.design, result.margin_scale = design, scale
        result.plan = plan
        scenario = plan.scenario
        op = start_operating_point(plan)
        result.diagram = op.diagram
        maps = GainMaps(op)
        _both_paths(maps, scenario)
        result.rho = maps.rho_full
        result.rho_at_margin = maps.rho(K=GAIN_MARGIN, K_o=GAIN_MARGIN)
    return maps


def _design_lines(result: Preflight, c) -> List[str]:
    """What the design gave (``c``: the scenario's controller), its rho
    and whether it holds the gain margin."""
    design, scale, n = result.design, result.margin_scale, result.design.numbers
    margin = (
        "not computed (unstable at the design)"
        if result.rho_at_margin is None
        else f"{result.rho_at_margin:.5f}"
        + (
            ""
            if not predicted_unstable(result.rho_at_margin)
            else " (the margin is NOT held)"
        )
    )
    return [
        f"gains designed from the model (controller.design: auto; "
        f"lightest task mass {n['lightest_task_mass_kg']:.2f} kg, "
        f"gravity error at the tool "
        f"{np.round(n['gravity_error_force_N'], 1).tolist()} N, "
        f"max eig(M^-1 D) T = {n['sampled_rate']:.2f}"
        + (
            f", K and K_o x {scale:.3g} for the gain margin"
            if scale < 1.0
            else ""
        )
        + "):",
        f"  sliding_gain {design.sliding_gain} N s/m, sliding_lambda "
        f"{design.sliding_lambda} 1/s, orientation_gain "
        f"{design.orientation_gain} N m s/rad, orientation_lambda "
        f"{design.orientation_lambda} 1/s",
        f"  fuzzy.sliding_scales {design.sliding_scales} m/s (Delta_k "
        f"{design.sliding_scales[0] * c.fuzzy.width_fraction * 1e3:g} "
        f"mm/s), fuzzy.position_scale {design.position_scale:g} m",
        f"  predicted rho {result.rho:.5f} at the start pose, {margin} with "
        f"K and K_o x {GAIN_MARGIN:g}",
        f"  feed/force loop damping ratio "
        f"{n.get('feed_loop_damping', float('nan')):.2f} (linearised at "
        f"the desired force, cell.gains.feed_loop_damping)",
    ]


def loop_key(scenario: Scenario) -> str:
    """What the pre-flight's answer depends on, as text: the scenario
    without its name, burrs and sensor noise (a sweep checks each distinct
    key once)."""
    from pydrake.common.yaml import yaml_dump_typed

    s = copy.deepcopy(scenario)
    s.name = "x"
    s.process.burrs = []
    s.sensor.noise_std = 0.0
    s.sensor.noise_seed = 0
    s.simulation.duration = 1.0
    return yaml_dump_typed(s)
