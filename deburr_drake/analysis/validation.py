"""Predicted against simulated stability limits.

For a parameter (the sensor's cutoff frequency, the sliding gain K on the
fuzzy axes, the slope of the fuzzy surface u_f of (30)), the predicted
boundary is where the spectral radius rho of the one-period (2.5 ms) map
crosses 1 (bisection); the simulated boundary is where short runs from
the operating point go unstable (bisection on a growth test). Both freeze
the adaptation (with it on, (35) would reshape the surface being tested);
the simulation keeps the outer loop running. (A 25 ms map with the feed
law live is not used: see :func:`~deburr_drake.analysis.sampled.sampled_loop`.)

The growth test: two runs of ``duration`` from the operating point with
the parameter set, one as is and one kicked (0.05 N on the sensor's
filter along n1 and n2, 1e-4 on every joint velocity). Unstable: a run
diverges (non-finite state, or the depth leaves [delta*/2, 3 delta*/2]
after the first 10 periods), or the second difference of the kicked
run's deviation from the other, sampled once per inner period, has a
larger RMS over the last quarter of the run than over the first 10
periods (the kick's response): a growing or sustained oscillation. The
deviation removes what both runs share (the outer loop's 25 ms steps);
the second difference removes the slow modes near z = 1 (the 1.8 s joint
mode of the arm) and amplifies an oscillation near the Nyquist frequency
4 times. An unstable loop saturates into a limit cycle within the run,
so comparing the late with the early quarter would miss it; and when the
loop is unstable on its own both runs settle on the same limit cycle, so
the unkicked run's late RMS is also compared with
:data:`LIMIT_CYCLE_FACTOR` times that of a run with the scenario's own
(stable) parameters. (Approaching the limit, a lightly damped mode near
z = -1 amplifies the outer loop's 25 ms steps: on the paper arm the RMS
grows 37 times from K = 400 to 4000 N s/m, stable, then 400 times more by
4500, a limit cycle.)
"""

from __future__ import annotations

from dataclasses import dataclass, field
import math
from typing import Callable, Dict, List, Optional, Tuple

import numpy as np
from pydrake.systems.analysis import InitializeParams

from deburr_drake.analysis.along import at_numerics, without_guards
from deburr_drake.analysis.operating_point import (
    OperatingPoint,
    frozen_scenario,
    transfer_state,
)
from deburr_drake.analysis.sampled import sampled_loop
from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.runs.simulation import make_simulator

__all__ = [
    "Parameter",
    "PARAMETERS",
    "add_fuzzy_slope",
    "baseline_oscillation",
    "predicted_boundary",
    "simulated_growth",
    "simulated_boundary",
    "validate_boundaries",
    "VERDICT_SCENARIOS",
    "simulated_verdict",
    "truth_scenario",
    "verdict_row",
]


def add_fuzzy_slope(diagram, context, slope: float):
    """Adds ``slope`` (N s/m) times s_k to the fuzzy surface u_fk(y0, s_k)
    of every fuzzy axis: theta_ij += slope j Delta_k. Central B-splines of
    order m >= 1 reproduce linear functions (sum_j j Delta N(y - j Delta)
    = y) and sum to one over y0, so u_f gains exactly slope s_k inside the
    rule grid: the local slope of a learned surface, as in the notes'
    "total gain on s" K + slope."""
    controller = diagram.GetSubsystemByName("controller")
    cc = controller.GetMyMutableContextFromRoot(context)
    x = cc.get_continuous_state_vector().CopyToVector()
    for k, rb in enumerate(controller.rule_bases):
        U = rb._U
        j = np.arange(-U, U + 1)
        grid = np.tile(slope * j * rb._dk, (2 * U + 1, 1))  # [i, j]
        start = 1 + k * rb.n_rules
        x[start : start + rb.n_rules] += grid.ravel()
    cc.SetContinuousState(x)


@dataclass
class Parameter:
    """A parameter of a stability limit: ``overrides(value)`` gives scenario
    fields by dotted name, ``modify(diagram, context, value)`` changes the
    operating point's state (or None)."""

    name: str
    unit: str
    overrides: Callable[[float], Dict[str, float]]
    modify: Optional[Callable] = None
    # search range per robot model (lo stable, hi beyond the limit)
    ranges: Dict[str, Tuple[float, float]] = field(default_factory=dict)

    def bind(self, value):
        mod = None
        if self.modify is not None:

            def mod(diagram, context):
                self.modify(diagram, context, value)

        return self.overrides(value), mod


def _sliding_gain(scenario):
    def overrides(value):
        return {
            f"controller.sliding_gain[{a}]": value
            for a in scenario.controller.fuzzy.axes
        }

    return overrides


def PARAMETERS(scenario) -> List[Parameter]:
    """The three validated parameters for ``scenario``: the sensor's cutoff,
    the sliding gain on the fuzzy axes, the fuzzy surface's slope."""
    nyquist = 0.5 / scenario.sensor.sample_period
    return [
        Parameter(
            "sensor.cutoff_frequency",
            "Hz",
            lambda v: {"sensor.cutoff_frequency": v},
            ranges={
                "cartesian_tool": (10.0, 0.99 * nyquist),
                "arm5": (10.0, 0.99 * nyquist),
            },
        ),
        Parameter(
            "controller.sliding_gain[fuzzy axes]",
            "N s/m",
            _sliding_gain(scenario),
            ranges={
                "cartesian_tool": (100.0, 20000.0),
                "arm5": (400.0, 20000.0),
            },
        ),
        Parameter(
            "fuzzy surface slope (theta_ij += slope j Delta_k)",
            "N s/m",
            lambda v: {},
            modify=lambda d, c, v: add_fuzzy_slope(d, c, v),
            ranges={"cartesian_tool": (0.0, 20000.0), "arm5": (0.0, 20000.0)},
        ),
    ]


def _bisect(
    unstable: Callable[[float], bool], lo: float, hi: float, rel_tol: float
) -> Optional[float]:
    """The boundary between a stable ``lo`` and an unstable ``hi`` (None
    when ``hi`` is stable: no limit in range; nan when ``lo`` is not
    stable)."""
    if not unstable(hi):
        return None
    if unstable(lo):
        return float("nan")
    while hi - lo > rel_tol * max(abs(hi), 1e-9):
        mid = 0.5 * (lo + hi)
        if unstable(mid):
            hi = mid
        else:
            lo = mid
    return 0.5 * (lo + hi)


def predicted_boundary(
    op: OperatingPoint,
    parameter: Parameter,
    *,
    lo: float,
    hi: float,
    rel_tol: float = 0.02,
):
    """Where rho of the one-period (2.5 ms) map crosses 1."""

    def unstable(value):
        overrides, modify = parameter.bind(value)
        return (
            sampled_loop(op, modify=modify, **overrides).spectral_radius > 1.0
        )

    return _bisect(unstable, lo, hi, rel_tol)


def _run(op, scenario, modify, duration, kick):
    """Joint velocities once per period over ``duration`` from the
    operating point (kicked by ``kick`` times the module's kick), or None
    when the run diverges."""
    from deburr_drake.control.layout import CHAMFER_STATE

    diagram = make_deburring_diagram(scenario=scenario)
    plant = diagram.GetSubsystemByName("plant")
    sensor = diagram.GetSubsystemByName("force_sensor")
    observer = diagram.GetSubsystemByName("chamfer_observer")
    period = scenario.controller.control_period
    d_star = scenario.task.desired_depth
    simulator = make_simulator(diagram, scenario)
    context = simulator.get_mutable_context()
    transfer_state(op.diagram, op.context, diagram, context)
    if modify is not None:
        modify(diagram, context)
    oc = observer.GetMyContextFromRoot(context)
    chamfer = observer.GetOutputPort("chamfer_state").Eval(oc)
    sc = sensor.GetMyMutableContextFromRoot(context)
    sc.SetDiscreteState(
        0,
        sc.get_discrete_state(0).get_value()
        + 0.05
        * kick
        * (CHAMFER_STATE.get(chamfer, "n1") + CHAMFER_STATE.get(chamfer, "n2")),
    )
    pc = plant.GetMyMutableContextFromRoot(context)
    plant.SetVelocities(pc, plant.GetVelocities(pc) + 1e-4 * kick)
    t0 = context.get_time()
    simulator.Initialize(InitializeParams(suppress_initialization_events=True))
    v = []
    try:
        for k in range(1, int(round(duration / period)) + 1):
            simulator.AdvanceTo(t0 + k * period)
            v.append(plant.GetVelocities(pc).copy())
            depth = CHAMFER_STATE.get(
                observer.GetOutputPort("chamfer_state").Eval(oc), "delta"
            )
            if not np.all(np.isfinite(v[-1])) or (
                k > 10 and abs(depth - d_star) > 0.5 * d_star
            ):
                return None
    except (RuntimeError, ValueError):
        return None
    return np.array(v)


#: A run oscillates on its own when the late RMS of its velocities' second
#: difference exceeds this many times that of the scenario's stable run.
LIMIT_CYCLE_FACTOR = 100.0


def _late_rms(h):
    q = max(1, len(h) // 4)
    return float(np.sqrt(np.mean(h[-q:] ** 2)))


def baseline_oscillation(op: OperatingPoint, *, duration: float = 1.0) -> float:
    """The late RMS of the second difference of the joint velocities of an
    unkicked run with the scenario's own parameters (the outer loop's
    25 ms steps in a stable loop): the reference of the self-oscillation
    test."""
    scenario = frozen_scenario(op.scenario)
    run = _run(op, scenario, None, duration, 0.0)
    return _late_rms(np.diff(run, n=2, axis=0)) if run is not None else math.nan


def simulated_growth(
    op: OperatingPoint,
    parameter: Parameter,
    value: float,
    *,
    duration: float = 1.0,
    kick: float = 1.0,
    baseline: float | None = None,
) -> float:
    """The growth test (module docstring): the larger of (a) the RMS of the
    second difference of the kicked run's deviation from the unkicked one
    over the last quarter over its RMS over the first 10 periods and (b)
    the unkicked run's own late RMS of that difference over
    :data:`LIMIT_CYCLE_FACTOR` times ``baseline`` (:func:`baseline_oscillation`;
    a loop unstable on its own settles both runs on the same limit cycle, which
    (a) misses); inf when a run diverges."""
    overrides, modify = parameter.bind(value)
    scenario = frozen_scenario(op.scenario, **overrides)
    runs = [_run(op, scenario, modify, duration, k) for k in (0.0, kick)]
    if any(r is None for r in runs):
        return math.inf
    h = np.diff(runs[1] - runs[0], n=2, axis=0)
    early = np.sqrt(np.mean(h[:10] ** 2))
    growth = _late_rms(h) / early if early > 0 else math.inf
    if baseline is not None and baseline > 0:
        own = _late_rms(np.diff(runs[0], n=2, axis=0)) / (
            LIMIT_CYCLE_FACTOR * baseline
        )
        growth = max(growth, own)
    return float(growth)


def simulated_boundary(
    op: OperatingPoint,
    parameter: Parameter,
    *,
    lo: float,
    hi: float,
    rel_tol: float = 0.02,
    duration: float = 1.0,
):
    """Where short runs from the operating point start to grow."""
    baseline = baseline_oscillation(op, duration=duration)
    return _bisect(
        lambda v: (
            simulated_growth(
                op, parameter, v, duration=duration, baseline=baseline
            )
            > 1.0
        ),
        lo,
        hi,
        rel_tol,
    )


def validate_boundaries(
    op: OperatingPoint,
    *,
    parameters=None,
    duration: float = 1.0,
    rel_tol: float = 0.02,
    progress=None,
) -> List[Dict]:
    """[{parameter, unit, range, predicted, simulated, error_rel}] for the
    three :func:`PARAMETERS` (None: no limit in the searched range)."""
    say = progress or (lambda m: None)
    rows = []
    for p in parameters or PARAMETERS(op.scenario):
        model = op.scenario.robot.model
        # Any arm other than the shipped ones is searched over arm5's range.
        lo, hi = p.ranges.get(model, p.ranges["arm5"])
        say(f"boundary of {p.name}: rho = 1 (bisection)")
        pred = predicted_boundary(op, p, lo=lo, hi=hi, rel_tol=rel_tol)
        say(f"boundary of {p.name}: simulation (bisection)")
        sim = simulated_boundary(
            op, p, lo=lo, hi=hi, rel_tol=rel_tol, duration=duration
        )
        err = (
            abs(pred - sim) / abs(sim)
            if pred is not None and sim is not None and sim != 0
            else None
        )
        rows.append(
            {
                "parameter": p.name,
                "unit": p.unit,
                "range": [lo, hi],
                "predicted": pred,
                "simulated": sim,
                "error_rel": err,
            }
        )
    return rows


# --- the verdict against simulation ---------------------------------------

#: Scenarios of the verdict table: (label, base scenario, --scenario-text).
VERDICT_SCENARIOS = (
    ("paper as shipped", "paper", ""),
    (
        "K = 5500",
        "paper",
        "controller: {sliding_gain: [5500.0, 5500.0, 1500.0]}",
    ),
    (
        "K = 5656",
        "paper",
        "controller: {sliding_gain: [5656.0, 5656.0, 1500.0]}",
    ),
    (
        "K = 6000",
        "paper",
        "controller: {sliding_gain: [6000.0, 6000.0, 1500.0]}",
    ),
    (
        "K = 7000",
        "paper",
        "controller: {sliding_gain: [7000.0, 7000.0, 1500.0]}",
    ),
    ("sensor cutoff 40 Hz", "paper", "sensor: {cutoff_frequency: 40.0}"),
    ("sensor cutoff 120 Hz", "paper", "sensor: {cutoff_frequency: 120.0}"),
    (
        "fuzzy: steep surface (Delta_k 0.5 mm/s)",
        "paper",
        "controller: {fuzzy: {sliding_scales: [0.0025, 0.0025]}}",
    ),
    (
        "fuzzy: adaptation gain x 40",
        "paper",
        "controller: {fuzzy: {adaptation_gain: 200000.0}}",
    ),
    (
        "burrs 2 mm, first at 10 deg",
        "paper",
        "process: {burrs: [{center_fraction: 0.03, length: 0.008, height: "
        "0.002, thickness: 0.002}]}",
    ),
    (
        "burr 4 mm at 10 deg",
        "paper",
        "process: {burrs: [{center_fraction: 0.03, length: 0.008, height: "
        "0.004, thickness: 0.002}]}",
    ),
    ("depth gain x 10", "paper", "controller: {depth_gain: 4.0e-3}"),
    (
        "fuzzy: steep surface learned fast (Delta_k 0.5 mm/s, r x 20)",
        "paper",
        "controller: {fuzzy: {sliding_scales: [0.0025, 0.0025], "
        "adaptation_gain: 100000.0}}",
    ),
    (
        "sliding lambda 400/s",
        "paper",
        "controller: {sliding_lambda: [400.0, 400.0, 50.0]}",
    ),
    ("6-DOF arm as shipped", "paper_6dof", ""),
    (
        "6-DOF arm, K = 6000",
        "paper_6dof",
        "controller: {sliding_gain: [6000.0, 6000.0, 4000.0]}",
    ),
    (
        "orientation gain 300",
        "paper",
        "controller: {orientation_gain: [300.0, 300.0, 300.0]}",
    ),
    (
        "orientation gain 600",
        "paper",
        "controller: {orientation_gain: [600.0, 600.0, 600.0]}",
    ),
)


def simulated_verdict(
    log,
    scenario,
    *,
    transient: float = 2.0,
    force_factor: float = 2.0,
    depth_band: float = 0.5,
) -> Dict:
    """The reference verdict of a run without guards, by a rule that
    shares nothing with the settled test: "unstable" when the run did not
    reach its duration (NaN, error), or after ``transient`` s of contact
    the measured chamfering force exceeds ``force_factor`` x the desired
    one, or the depth leaves delta* (1 +- ``depth_band``); else "stable".
    Returns {verdict, max_f_t_N, depth_range_mm, stop_reason}."""
    ch = log["chamfer"]
    t = np.asarray(ch["t"])
    on = (np.asarray(ch["delta"]) > 0) & (np.asarray(ch["f_n"]) > 0.5)
    start = (t[np.argmax(on)] if on.any() else np.inf) + transient
    after = t >= start
    d_star = scenario.task.desired_depth
    f_star = scenario.task.desired_chamfering_force
    out = {
        "stop_reason": log.stop_reason,
        "max_f_t_N": None,
        "depth_range_mm": None,
    }
    if log.stop_reason not in ("duration", "pass_complete") or not after.any():
        out["verdict"] = "unstable"
        return out
    ft = np.abs(np.asarray(ch["f_t"])[after])
    depth = np.asarray(ch["delta"])[after]
    out["max_f_t_N"] = float(np.max(ft))
    out["depth_range_mm"] = [float(depth.min() * 1e3), float(depth.max() * 1e3)]
    bad = (
        np.max(ft) > force_factor * f_star
        or depth.min() < (1 - depth_band) * d_star
        or depth.max() > (1 + depth_band) * d_star
    )
    out["verdict"] = "unstable" if bad else "stable"
    return out


def truth_scenario(scenario, numerics: str = "refined"):
    """The scenario of the reference simulation: ``scenario`` at the
    verdict's ``numerics`` (:func:`~deburr_drake.analysis.along.at_numerics`:
    a truth at the shipped step would judge the step, not the loop) with
    its guards off."""
    return without_guards(at_numerics(scenario, numerics))


def verdict_row(
    label: str,
    base: str,
    text: str,
    *,
    duration: float = 20.0,
    numerics: str = "refined",
    progress=None,
) -> Dict:
    """analyze's verdict on the scenario's run to ``duration`` against a
    ``duration`` s simulation with the guards off judged by
    :func:`simulated_verdict`, both at ``numerics``
    (:func:`truth_scenario`)."""
    import time

    from deburr_drake.analysis.analyze_run import analyze
    from deburr_drake.config import load_scenario
    from deburr_drake.runs.simulation import simulate

    scenario = load_scenario(base, text=text or None)
    t0 = time.perf_counter()
    result = analyze(
        scenario,
        until=duration,
        robust=False,
        numerics=numerics,
        progress=progress,
    )
    wall_analyze = time.perf_counter() - t0
    sim_scenario = truth_scenario(scenario, numerics)
    t1 = time.perf_counter()
    log = simulate(
        make_deburring_diagram(scenario=sim_scenario),
        sim_scenario,
        duration=duration,
    )
    reference = simulated_verdict(log, scenario)
    sm = result.get("smallest_margin") or {}
    osc = result.get("oscillation") or {}
    guard = result.get("guard_that_would_stop") or {}
    return {
        "label": label,
        "base": base,
        "scenario_text": text,
        "verdict": result["verdict"],
        "verdict_reason": result["verdict_reason"],
        "rho_max_along_run": sm.get("rho"),
        "oscillation_hz": osc.get("frequency_hz"),
        "oscillation_start_s": osc.get("start_time"),
        "guard": guard.get("guard"),
        "guard_time_s": guard.get("time"),
        "simulation": reference,
        "agree": result["verdict"] == reference["verdict"],
        "numerics": numerics,
        "truth_max_step_s": sim_scenario.simulation.max_step,
        "wall_analyze_s": wall_analyze,
        "wall_simulation_s": time.perf_counter() - t1,
    }
