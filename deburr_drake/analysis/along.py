"""The run ``analyze`` answers for, and the sampled loop's stability along
it.

:func:`analysis_run` simulates the scenario as the user will run it
(adaptation, noise, outer loop all live) with the runtime guards off (so
that the run shows what the loop does; :func:`guard_that_would_stop`
names the guard that would have stopped it), for the scenario's duration
or pass, or ``until`` seconds. On the way it

- captures the operating point (the full Context) at ``at``, moved to the
  next inner-loop sample that is not an outer-loop sample, and on past a
  burr (as :func:`deburr_drake.analysis.find_operating_point`); without
  ``at`` (``after_contact`` s after the first contact) also on, 0.5 s at a
  time, while the run is not steady there (a transient), to the end of
  the run at most;
- takes the one-period (2.5 ms) map of the frozen loop
  (:class:`deburr_drake.analysis.FrozenMap`, one diagram for the whole
  run) at points along the pass: in the contact transient (0.25 s after
  the first contact), every ``spacing`` seconds of cutting, at the middle
  of each burr (where its cross-section under the tool starts to fall) and
  where the edge's curvature |dn1/dt| / |v| changes by more than 20 %.

A point's map is kept only if the run was steady over the 0.25 s before
it (:func:`deburr_drake.analysis.settled.settle_check`): a map taken on a
limit cycle is not a linearization of anything, so such a point gets
``rho`` None and the reason.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass, field
import time
from typing import Callable, Dict, List, Optional

import numpy as np
from pydrake.common import RandomGenerator

from deburr_drake.analysis.operating_point import (
    CONTACT_FORCE,
    DEFAULT_TIME_AFTER_CONTACT,
    MAX_TIME_TO_CONTACT,
    OperatingPoint,
    _next_analysis_time,
    _signals,
    first_contact,
)
from deburr_drake.analysis.sampled import FrozenMap, spectral_radius
from deburr_drake.analysis.settled import (
    RunSignals,
    SettleTolerances,
    first_guard_trip,
    settle_check,
)
from deburr_drake.cell.diagram import make_deburring_diagram
from deburr_drake.config import ConfigError, Scenario
from deburr_drake.runs.simulation import _collect, logger_names, make_simulator

__all__ = [
    "RhoPoint",
    "AnalysisRun",
    "analysis_run",
    "rho_of_map",
    "guard_that_would_stop",
    "plot_rho_along_run",
    "without_guards",
    "DEFAULT_SPACING",
]

#: Seconds of cutting between two maps along the run (default).
DEFAULT_SPACING = 5.0
#: The steady window before a point along the run (s).
POINT_WINDOW = 0.25
_CHUNK = 0.05  # s between checks of the run's signals


@dataclass
class RhoPoint:
    t: float  # s
    arc_position: float  # m
    kind: str  # transient, cutting, burr <k>, curvature, operating point
    rho: Optional[float] = None
    frequency_hz: Optional[float] = None  # of the dominant eigenvalue
    decay_rate: Optional[float] = None  # 1/s, -ln(rho) / T
    rho_oscillatory: Optional[float] = None  # modes above 1 Hz
    burr_area: float = 0.0  # m^2 under the tool
    note: str = ""
    context: object = None  # the run's Context there (robust margin)

    def to_dict(self):
        return {
            "t": self.t,
            "arc_position": self.arc_position,
            "rho": self.rho,
            "kind": self.kind,
            "frequency_hz": self.frequency_hz,
            "decay_rate_per_s": self.decay_rate,
            "rho_oscillatory": self.rho_oscillatory,
            "on_burr": self.burr_area > 0,
            "note": self.note,
        }


def rho_of_map(
    Phi: np.ndarray, period: float, *, oscillatory_hz: float = 1.0
) -> Dict[str, float]:
    """rho, the dominant eigenvalue's frequency (Hz), the decay rate
    -ln(rho) / T (1/s: the slowest mode's, negative when it grows) and
    ``rho_oscillatory``, the largest |eig| of the modes above
    ``oscillatory_hz`` (the loop's oscillations; rho itself is usually
    the arm's slow joint mode near z = 1, which the contact does not
    move)."""
    eigs = np.linalg.eigvals(Phi)
    worst = eigs[int(np.argmax(np.abs(eigs)))]
    rho = spectral_radius(Phi)
    fast = np.abs(np.angle(eigs)) > 2 * np.pi * oscillatory_hz * period
    return {
        "rho": rho,
        "rho_oscillatory": float(np.max(np.abs(eigs[fast])))
        if fast.any()
        else 0.0,
        "frequency_hz": float(abs(np.angle(worst)) / (2 * np.pi * period)),
        "decay_rate": float(-np.log(rho) / period) if rho > 0 else float("inf"),
    }


@dataclass
class AnalysisRun:
    scenario: Scenario  # as run (guards off)
    diagram: object
    log: Dict  # logger -> block -> array (as RunLog.signals)
    signals: RunSignals
    contact_time: float
    end_time: float
    stop_reason: str  # duration, pass_complete, nan, error
    stop_detail: str = ""
    op: Optional[OperatingPoint] = None
    op_note: str = ""
    points: List[RhoPoint] = field(default_factory=list)
    wall_time_s: float = 0.0
    map_time_s: float = 0.0


def without_guards(scenario: Scenario) -> Scenario:
    """A copy of ``scenario`` with its runtime guards off (the drives'
    torque clamp as configured: it is the drives, not a guard)."""
    run = copy.deepcopy(scenario)
    run.guards.enabled = False
    return run.validate()


def analysis_run(
    scenario: Scenario,
    *,
    at: Optional[float] = None,
    after_contact: float = DEFAULT_TIME_AFTER_CONTACT,
    until: Optional[float] = None,
    spacing: float = DEFAULT_SPACING,
    maps: bool = True,
    max_burr_delay: float = 5.0,
    progress: Optional[Callable[[str], None]] = None,
) -> AnalysisRun:
    """The run and the maps along it (module docstring). ``until``
    (s) ends the run earlier than the scenario's duration or pass;
    ``maps`` False takes none (the settled test alone). ConfigError when
    the tool never reaches contact within 5 s."""
    say = progress or (lambda m: None)
    if at is not None and not (np.isfinite(at) and at > 0):
        raise ConfigError(f"--at = {at!r} is invalid: allowed a time > 0 s")
    if not (np.isfinite(after_contact) and after_contact >= 0):
        raise ConfigError(
            f"--after-contact = {after_contact!r} is invalid:"
            " allowed a time >= 0 s"
        )
    if not (np.isfinite(spacing) and spacing > 0):
        raise ConfigError(
            f"--spacing = {spacing!r} is invalid: allowed a time > 0 s"
        )
    scenario.validate()
    run = without_guards(scenario)
    duration = run.simulation.duration if until is None else until
    if not (np.isfinite(duration) and duration > 0):
        raise ConfigError(
            f"--until = {until!r} is invalid: allowed a time > 0 s"
        )
    period = run.controller.control_period or run.sensor.sample_period
    outer = run.command.period
    diagram = make_deburring_diagram(scenario=run)
    simulator = make_simulator(diagram, run)
    context = simulator.get_mutable_context()
    diagram.SetRandomContext(context, RandomGenerator(run.sensor.noise_seed))
    generator = diagram.GetSubsystemByName("command_generator")
    gen_context = generator.GetMyContextFromRoot(context)
    passes = run.simulation.stop_after_passes
    pass_end = generator.start_arc_position + passes * generator.contour.length
    frozen = FrozenMap(scenario) if maps else None
    wall0 = time.perf_counter()
    map_time = 0.0
    result = AnalysisRun(
        scenario=run,
        diagram=diagram,
        log={},
        signals=None,
        contact_time=float("nan"),
        end_time=0.0,
        stop_reason="duration",
    )
    simulator.Initialize()

    def advance(t):
        simulator.AdvanceTo(min(t, duration))
        return context.get_time()

    def take_map(kind, s):
        nonlocal map_time
        point = RhoPoint(
            t=context.get_time(),
            arc_position=s["arc_position"],
            kind=kind,
            burr_area=s["burr_area"],
        )
        if frozen is not None:
            t0 = time.perf_counter()
            point.context = context.Clone()
            try:
                r = rho_of_map(frozen.at(diagram, context), frozen.period)
                point.rho, point.frequency_hz, point.decay_rate = (
                    r["rho"],
                    r["frequency_hz"],
                    r["decay_rate"],
                )
                point.rho_oscillatory = r["rho_oscillatory"]
            except (RuntimeError, ValueError) as e:
                point.note = f"map failed: {type(e).__name__}: {e}"
            map_time += time.perf_counter() - t0
            say(
                f"map at t = {point.t:.3f} s ({kind}): rho = "
                f"{point.rho if point.rho is None else round(point.rho, 5)}"
            )
        result.points.append(point)

    try:
        contact = first_contact(
            diagram,
            context,
            advance,
            limit=min(MAX_TIME_TO_CONTACT, duration),
            name=scenario.name,
        )
        t = context.get_time()
        result.contact_time = contact
        target = at if at is not None else contact + after_contact
        op_time = _next_analysis_time(target, period, outer)
        op_limit = op_time + max_burr_delay
        schedule = [contact + 0.25] + list(
            np.arange(contact + 1.0, duration, spacing)
        )
        schedule = [_next_analysis_time(x, period, outer) for x in schedule]
        burr_max, burr_done, burr_count = 0.0, False, 0
        last_curvature = None
        while t < duration - 1e-9:
            nxt = min(
                [x for x in schedule if x > t + 1e-9]
                + [
                    op_time
                    if result.op is None and op_time > t + 1e-9
                    else np.inf,
                    t + _CHUNK,
                ]
            )
            t = advance(nxt)
            if passes > 0 and generator.arc_progress(gen_context) >= pass_end:
                result.stop_reason = "pass_complete"
                break
            s = _signals(diagram, context)
            on_sample = (
                abs(t / period - round(t / period)) < 1e-6
                and abs(t / outer - round(t / outer)) > 1e-6
            )
            if result.op is None and t >= op_time - 1e-9 and on_sample:
                if s["burr_area"] > 0 and t < op_limit:
                    op_time = _next_analysis_time(t + 0.1, period, outer)
                elif s["depth"] <= 0 or s["normal_force"] <= CONTACT_FORCE:
                    result.op_note = (
                        f"out of contact at t = {t:g} s (depth "
                        f"{s['depth']:.3g} m, ||f_n|| "
                        f"{s['normal_force']:.3g} N): no operating point"
                    )
                    op_time = np.inf
                elif (
                    at is None
                    and not settle_check(
                        RunSignals.from_log(
                            _collect(
                                diagram, context, ["chamfer", "controller"]
                            ),
                            run,
                        ),
                        t,
                    ).settled
                ):
                    # still in a transient (or oscillating): look again
                    # 0.5 s later; the user's own --at is kept as given
                    op_time = _next_analysis_time(t + 0.5, period, outer)
                else:
                    result.op = OperatingPoint(
                        scenario=scenario,
                        diagram=diagram,
                        context=context.Clone(),
                        time=t,
                        contact_time=contact,
                        signals=s,
                    )
            if any(abs(x - t) < 1e-9 for x in schedule):
                take_map("transient" if t < contact + 0.5 else "cutting", s)
                continue
            if not on_sample:
                continue
            # a burr's middle: its area under the tool starts to fall
            if s["burr_area"] > 0:
                if s["burr_area"] >= burr_max:
                    burr_max = s["burr_area"]
                elif not burr_done and s["burr_area"] < 0.98 * burr_max:
                    burr_count += 1
                    burr_done = True
                    take_map(f"burr {burr_count}", s)
            else:
                burr_max, burr_done = 0.0, False
            speed = abs(s["tangential_speed"])
            if speed > 1e-4:
                chamfer = diagram.GetSubsystemByName("chamfer_observer")
                from deburr_drake.control.layout import CHAMFER_STATE

                rate = CHAMFER_STATE.get(
                    chamfer.GetOutputPort("chamfer_state").Eval(
                        chamfer.GetMyContextFromRoot(context)
                    ),
                    "n1_rate",
                )
                kappa = float(np.linalg.norm(rate)) / speed
                if last_curvature is None:
                    last_curvature = kappa
                elif (
                    abs(kappa - last_curvature)
                    > 0.2 * abs(last_curvature) + 1.0
                ):
                    last_curvature = kappa
                    take_map("curvature", s)
    except ConfigError:
        raise
    except Exception as e:  # NaN or a failure: keep what was computed
        result.stop_reason = "nan" if "NaN" in str(e) else "error"
        result.stop_detail = f"{type(e).__name__}: {e}"
    result.end_time = context.get_time()
    result.log = _collect(diagram, context, logger_names(diagram))
    result.signals = RunSignals.from_log(result.log, run)
    result.wall_time_s = time.perf_counter() - wall0
    result.map_time_s = map_time
    tol = SettleTolerances()
    for p in result.points:
        if p.rho is None:
            continue
        check = settle_check(result.signals, p.t, tol, window=POINT_WINDOW)
        if p.kind != "transient" and not check.settled:
            p.note = "not steady: " + "; ".join(check.reasons[:2])
            p.rho = p.frequency_hz = p.decay_rate = None
            p.rho_oscillatory = None
    return result


def guard_that_would_stop(
    run: AnalysisRun, scenario: Scenario
) -> Optional[Dict]:
    """The runtime guard (the user's ``guards`` settings) that would have
    stopped ``run`` first, with its time and values, or None (also None
    when the user's guards are off)."""
    if not scenario.guards.enabled:
        return None
    from deburr_drake.cell.guards import guard_limits

    plant = run.diagram.GetSubsystemByName("plant")
    contour = run.diagram.GetSubsystemByName("command_generator").contour
    lim = guard_limits(scenario, plant, contour)
    log = run.log
    ch = log["chamfer"]
    n = len(ch["t"])

    def rows(logger, block="value"):
        a = np.asarray(log[logger][block])
        return a[:n] if len(a) >= n else None

    return first_guard_trip(
        ch["t"],
        actuation=rows("actuation"),
        effort_limits=lim.effort_limits,
        torque_fraction=lim.joint_torque_fraction,
        names=lim.joint_names,
        tool_force=rows("tool_force"),
        tool_force_limit=lim.tool_force,
        depth=ch["delta"],
        true_depth=rows("process", "delta"),
        depth_limit=lim.depth,
        x_p=ch["x_p"],
        workspace_low=lim.workspace_low,
        workspace_high=lim.workspace_high,
        normal_force=ch["f_n"],
        contact_force=lim.contact_force,
        contact_lost_time=lim.contact_lost_time,
    )


def plot_rho_along_run(
    points: List[Dict],
    path,
    *,
    title: str = "",
    contour_length: float | None = None,
):
    """rho against time and against arc position (mm), the unit circle's
    rho = 1 marked, the largest |z| of the oscillatory modes as open
    circles, points not steady (rho None) as crosses at the bottom."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(13.5, 4.2), sharey=True)
    good = [p for p in points if p["rho"] is not None]
    bad = [p for p in points if p["rho"] is None]
    rhos = [p["rho"] for p in good] + [
        p["rho_oscillatory"] for p in good if p.get("rho_oscillatory")
    ] or [1.0]
    lo = min(min(rhos), 0.99)
    hi = max(max(rhos), 1.001)
    pad = 0.1 * (hi - lo)
    for ax, key, scale, label in (
        (axes[0], "t", 1.0, "time (s)"),
        (axes[1], "arc_position", 1e3, "arc position along the edge (mm)"),
    ):
        for kind, marker in (
            ("transient", "s"),
            ("cutting", "o"),
            ("burr", "^"),
            ("curvature", "D"),
            ("operating point", "*"),
        ):
            sel = [p for p in good if p["kind"].startswith(kind)]
            if sel:
                ax.plot(
                    [p[key] * scale for p in sel],
                    [p["rho"] for p in sel],
                    marker,
                    ls="none",
                    label=kind,
                    ms=9 if kind == "operating point" else 6,
                )
        if good:
            order = sorted(good, key=lambda p: p["t"])
            ax.plot(
                [p[key] * scale for p in order],
                [p["rho"] for p in order],
                "-",
                color="0.6",
                lw=0.7,
                zorder=0,
            )
            fast = [p for p in order if p.get("rho_oscillatory")]
            if fast:
                ax.plot(
                    [p[key] * scale for p in fast],
                    [p["rho_oscillatory"] for p in fast],
                    "o",
                    mfc="none",
                    color="0.4",
                    ms=5,
                    label="|z| of the modes above 1 Hz",
                )
        if bad:
            ax.plot(
                [p[key] * scale for p in bad],
                [lo - 0.5 * pad] * len(bad),
                "x",
                color="r",
                label="not steady (no map)",
            )
        ax.axhline(1.0, color="r", lw=1)
        ax.set(xlabel=label)
    axes[0].set(
        ylabel="rho, spectral radius of the 2.5 ms map (-)",
        ylim=(lo - pad, hi + pad),
    )
    axes[1].legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    fig.suptitle(
        f"{title}: stability of the sampled loop along the run (rho < 1 stable)"
    )
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
