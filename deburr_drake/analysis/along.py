"""The run ``analyze`` answers for, and the sampled loop's stability along
it.

:func:`analysis_run` simulates the scenario as the user will run it
(adaptation, noise, outer loop all live) with the runtime guards off (so
that the run shows what the loop does; :func:`guard_that_would_stop`
names the guard that would have stopped it), for the scenario's duration
or pass, or ``until`` seconds, at the numerics :func:`at_numerics` gives:
by default refined (a quarter of the scenario's ``simulation.max_step``,
eq. (3) followed between samples), since near the stability boundary the
shipped one step per sample describes the integrator, not the loop. The
maps along the run integrate their period at the same numerics: a map is
the linearization of what the integrator does over one period, and its
limits move with the step as the runs' do (docs/numerics.md). On the way
it

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
from pydrake.systems.framework import EventStatus

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
from deburr_drake.cell.plan import plan_cell
from deburr_drake.config import ConfigError, Scenario
from deburr_drake.control.layout import CHAMFER_STATE
from deburr_drake.runs.convergence import refined
from deburr_drake.runs.simulation import (
    DIVERGED,
    NumericalSanity,
    PassProgress,
    _collect,
    logger_names,
    make_simulator,
)

__all__ = [
    "RhoPoint",
    "AnalysisRun",
    "analysis_run",
    "rho_of_map",
    "guard_that_would_stop",
    "plot_rho_along_run",
    "without_guards",
    "at_numerics",
    "NUMERICS",
    "REFINED_HALVINGS",
    "DEFAULT_SPACING",
]

#: Seconds of cutting between two maps along the run (default).
DEFAULT_SPACING = 5.0
#: The steady window before a point along the run (s).
POINT_WINDOW = 0.25
_CHUNK = 0.05  # s between checks of the run's signals
#: The numerics the verdict's run may use, the default first.
NUMERICS = ("refined", "shipped")
#: Halvings of ``simulation.max_step`` at the refined numerics: a quarter
#: of the step (0.625 ms on the paper), where the paper's fast force
#: stopped changing (a further halving moved it by under 15 %, the
#: shipped step by 98 %).
REFINED_HALVINGS = 2


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
    stop_reason: str  # duration, pass_complete, diverged, nan, error
    stop_detail: str = ""
    op: Optional[OperatingPoint] = None
    op_note: str = ""
    points: List[RhoPoint] = field(default_factory=list)
    wall_time_s: float = 0.0
    map_time_s: float = 0.0
    # The scenario at the run's numerics, guards as given (what the
    # operating point's analysis and the robust margin build on).
    analysed: Optional[Scenario] = None
    numerics: Dict = field(default_factory=dict)


def at_numerics(scenario: Scenario, numerics: str = "refined") -> Scenario:
    """``scenario`` as the verdict runs it: "shipped" as given; "refined"
    its ``simulation.max_step`` divided by 2 ** :data:`REFINED_HALVINGS`
    with eq. (3) between samples (``process.sample_mean`` false), as
    :func:`deburr_drake.runs.convergence.refined` makes it."""
    if numerics == "shipped":
        return scenario
    if numerics == "refined":
        return refined(scenario, REFINED_HALVINGS)
    raise ConfigError(
        f"--numerics = {numerics!r} is invalid: allowed "
        + " or ".join(NUMERICS)
    )


def _numerics_summary(name, shipped: Scenario, run: Scenario, maps) -> Dict:
    """Which numerics the run and its maps used (steps in s)."""
    summary = {
        "name": name,
        "integrator": run.simulation.integrator,
        "max_step_s": run.simulation.max_step,
        "error_control": run.simulation.error_control,
        "sample_mean": run.process.sample_mean,
        "shipped_max_step_s": shipped.simulation.max_step,
        "maps_max_step_s": None,
        "maps_sample_mean": None,
    }
    if maps is not None:
        summary["maps_max_step_s"] = maps.config.max_step_size
        summary["maps_sample_mean"] = maps.scenario.process.sample_mean
    return summary


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
    numerics: str = "refined",
    progress: Optional[Callable[[str], None]] = None,
) -> AnalysisRun:
    """The run and the maps along it (module docstring), at ``numerics``
    (:func:`at_numerics`). ``until`` (s) ends the run earlier than the
    scenario's duration or pass; ``maps`` False takes none (the settled
    test alone). ConfigError when the tool never reaches contact within
    5 s."""
    # The times asked for, before anything is built.
    _check_times(at=at, after_contact=after_contact, spacing=spacing)
    shipped = scenario.validate()
    # The scenario as run: at its numerics, the runtime guards off, to
    # ``until`` if given.
    scenario = at_numerics(shipped, numerics)
    run = without_guards(scenario)
    duration = run.simulation.duration if until is None else until
    if not (np.isfinite(duration) and duration > 0):
        raise ConfigError(
            f"--until = {until!r} is invalid: allowed a time > 0 s"
        )
    # One diagram and simulator for the whole run, its noise seeded.
    walk = _Walk(
        scenario, run, duration, maps=maps, say=progress or (lambda m: None)
    )
    # To the first contact, then along the pass: the operating point and
    # the maps on the way. A NaN or a failure ends it, keeping what was
    # computed.
    try:
        walk.to_contact()
        walk.along(
            at=at,
            after_contact=after_contact,
            spacing=spacing,
            max_burr_delay=max_burr_delay,
        )
    except ConfigError:
        raise
    except _Diverged as e:
        walk.result.stop_reason = DIVERGED
        walk.result.stop_detail = str(e)
    except Exception as e:
        walk.result.stop_reason = "nan" if "NaN" in str(e) else "error"
        walk.result.stop_detail = f"{type(e).__name__}: {e}"
    # The run's logs, then the maps not preceded by steady cutting voided.
    result = walk.finish()
    result.analysed = scenario
    result.numerics = _numerics_summary(numerics, shipped, run, walk.frozen)
    _void_unsteady_maps(result)
    return result


def _check_times(*, at, after_contact, spacing):
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


def _void_unsteady_maps(result: AnalysisRun):
    """A map on a limit cycle linearizes nothing: past the contact
    transient, a point's rho counts only if the run was steady over the
    POINT_WINDOW before it."""
    tol = SettleTolerances()
    for p in result.points:
        if p.rho is None:
            continue
        check = settle_check(result.signals, p.t, tol, window=POINT_WINDOW)
        if p.kind != "transient" and not check.settled:
            p.note = "not steady: " + "; ".join(check.reasons[:2])
            p.rho = p.frequency_hz = p.decay_rate = None
            p.rho_oscillatory = None


class _Diverged(Exception):
    """The run diverged (:class:`NumericalSanity`); the message says how
    and when."""


class _Walk:
    """The simulation :func:`analysis_run` steps through, the operating
    point and the maps taken from its Context on the way, into
    ``result``."""

    def __init__(self, scenario, run, duration, *, maps, say):
        self.scenario, self.run, self.duration = scenario, run, duration
        self.say = say
        self.period = run.controller.control_period or run.sensor.sample_period
        self.outer = run.command.period
        # Planned once: the run's diagram and the frozen variant whose
        # maps are taken along it share the cell.
        plan = plan_cell(run)
        self.diagram = make_deburring_diagram(plan)
        # The numerical sanity check ends a diverging run before Drake's
        # contact solver fails on its state (an abort would lose it).
        sanity = NumericalSanity(self.diagram, run)
        self.simulator = make_simulator(
            self.diagram,
            run,
            monitor=lambda root: (
                sanity.monitor_status(root, self.diagram)
                or EventStatus.Succeeded()
            ),
        )
        self.context = self.simulator.get_mutable_context()
        self.diagram.SetRandomContext(
            self.context, RandomGenerator(run.sensor.noise_seed)
        )
        self.generator = self.diagram.GetSubsystemByName("command_generator")
        self.gen_context = self.generator.GetMyContextFromRoot(self.context)
        self.progress = PassProgress(
            self.diagram, run.simulation.stop_after_passes
        )
        self.frozen = FrozenMap(plan.scenario, plan=plan) if maps else None
        self.wall0 = time.perf_counter()
        self.map_time = 0.0
        self.result = AnalysisRun(
            scenario=run,
            diagram=self.diagram,
            log={},
            signals=None,
            contact_time=float("nan"),
            end_time=0.0,
            stop_reason="duration",
        )
        # The burr under the tool (its largest area so far, whether its
        # middle was mapped, how many were) and the last mapped curvature.
        self.burr_max, self.burr_done, self.burr_count = 0.0, False, 0
        self.last_curvature = None
        # When to try for the operating point next, and till when a burr
        # may delay it (set by along).
        self.op_time = self.op_limit = np.inf
        self.simulator.Initialize()

    def advance(self, t):
        status = self.simulator.AdvanceTo(min(t, self.duration))
        if status.reason() == status.ReturnReason.kReachedTerminationCondition:
            raise _Diverged(status.message().split(":", 1)[1].strip())
        return self.context.get_time()

    def to_contact(self):
        self.result.contact_time = first_contact(
            self.diagram,
            self.context,
            self.advance,
            limit=min(MAX_TIME_TO_CONTACT, self.duration),
            name=self.scenario.name,
        )

    def along(self, *, at, after_contact, spacing, max_burr_delay):
        """On in chunks of _CHUNK s, stopping at the scheduled maps and the
        operating point's time, to the run's end or the pass's."""
        contact = self.result.contact_time
        t = self.context.get_time()
        target = at if at is not None else contact + after_contact
        self.op_time = self._analysis_time(target)
        self.op_limit = self.op_time + max_burr_delay
        schedule = [contact + 0.25] + list(
            np.arange(contact + 1.0, self.duration, spacing)
        )
        schedule = [self._analysis_time(x) for x in schedule]
        while t < self.duration - 1e-9:
            pending_op = self.result.op is None and self.op_time > t + 1e-9
            t = self.advance(
                min(
                    [x for x in schedule if x > t + 1e-9]
                    + [self.op_time if pending_op else np.inf, t + _CHUNK]
                )
            )
            if self.progress.done(self.context):
                self.result.stop_reason = "pass_complete"
                break
            s = _signals(self.diagram, self.context)
            on_sample = (
                abs(t / self.period - round(t / self.period)) < 1e-6
                and abs(t / self.outer - round(t / self.outer)) > 1e-6
            )
            if (
                self.result.op is None
                and t >= self.op_time - 1e-9
                and on_sample
            ):
                self._operating_point(t, s, free=at is None)
            if any(abs(x - t) < 1e-9 for x in schedule):
                kind = "transient" if t < contact + 0.5 else "cutting"
                self._take_map(kind, s)
            elif on_sample:
                self._burr_middle(s)
                self._curvature_change(s)

    def _analysis_time(self, t):
        return _next_analysis_time(t, self.period, self.outer)

    def _operating_point(self, t, s, *, free):
        """The operating point here, or the time to look again: past a
        burr, and (unless the user gave --at, ``free`` False) past a
        transient or an oscillation, 0.5 s at a time; none out of
        contact."""
        if s["burr_area"] > 0 and t < self.op_limit:
            self.op_time = self._analysis_time(t + 0.1)
        elif s["depth"] <= 0 or s["normal_force"] <= CONTACT_FORCE:
            self.result.op_note = (
                f"out of contact at t = {t:g} s (depth "
                f"{s['depth']:.3g} m, ||f_n|| "
                f"{s['normal_force']:.3g} N): no operating point"
            )
            self.op_time = np.inf
        elif free and not self._settled(t):
            self.op_time = self._analysis_time(t + 0.5)
        else:
            self.result.op = OperatingPoint(
                scenario=self.scenario,
                diagram=self.diagram,
                context=self.context.Clone(),
                time=t,
                contact_time=self.result.contact_time,
                signals=s,
            )

    def _settled(self, t) -> bool:
        log = _collect(self.diagram, self.context, ["chamfer", "controller"])
        return settle_check(RunSignals.from_log(log, self.run), t).settled

    def _burr_middle(self, s):
        """A map at a burr's middle: where its area under the tool starts
        to fall."""
        area = s["burr_area"]
        if not area > 0:
            self.burr_max, self.burr_done = 0.0, False
        elif area >= self.burr_max:
            self.burr_max = area
        elif not self.burr_done and area < 0.98 * self.burr_max:
            self.burr_count += 1
            self.burr_done = True
            self._take_map(f"burr {self.burr_count}", s)

    def _curvature_change(self, s):
        """A map where the edge's curvature |dn1/dt| / |v| changed by more
        than 20 % (and 1 1/m) since the last one."""
        speed = abs(s["tangential_speed"])
        if not speed > 1e-4:
            return
        chamfer = self.diagram.GetSubsystemByName("chamfer_observer")
        rate = CHAMFER_STATE.get(
            chamfer.GetOutputPort("chamfer_state").Eval(
                chamfer.GetMyContextFromRoot(self.context)
            ),
            "n1_rate",
        )
        kappa = float(np.linalg.norm(rate)) / speed
        if self.last_curvature is None:
            self.last_curvature = kappa
        elif (
            abs(kappa - self.last_curvature)
            > 0.2 * abs(self.last_curvature) + 1.0
        ):
            self.last_curvature = kappa
            self._take_map("curvature", s)

    def _take_map(self, kind, s):
        point = RhoPoint(
            t=self.context.get_time(),
            arc_position=s["arc_position"],
            kind=kind,
            burr_area=s["burr_area"],
        )
        if self.frozen is not None:
            t0 = time.perf_counter()
            point.context = self.context.Clone()
            try:
                r = rho_of_map(
                    self.frozen.at(self.diagram, self.context),
                    self.frozen.period,
                )
                point.rho = r["rho"]
                point.frequency_hz = r["frequency_hz"]
                point.decay_rate = r["decay_rate"]
                point.rho_oscillatory = r["rho_oscillatory"]
            except (RuntimeError, ValueError) as e:
                point.note = f"map failed: {type(e).__name__}: {e}"
            self.map_time += time.perf_counter() - t0
            shown = point.rho if point.rho is None else round(point.rho, 5)
            self.say(f"map at t = {point.t:.3f} s ({kind}): rho = {shown}")
        self.result.points.append(point)

    def finish(self) -> AnalysisRun:
        """The result with the run's end, logs and times."""
        result = self.result
        result.end_time = self.context.get_time()
        result.log = _collect(
            self.diagram, self.context, logger_names(self.diagram)
        )
        result.signals = RunSignals.from_log(result.log, self.run)
        result.wall_time_s = time.perf_counter() - self.wall0
        result.map_time_s = self.map_time
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
        _plot_rho_axis(ax, good, lambda p: p[key] * scale)
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


def _plot_rho_axis(ax, good, x):
    """The steady points' rho on ``ax`` against ``x(point)``: a marker per
    kind, a line in time order and the oscillatory modes' |z|."""
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
                [x(p) for p in sel],
                [p["rho"] for p in sel],
                marker,
                ls="none",
                label=kind,
                ms=9 if kind == "operating point" else 6,
            )
    if not good:
        return
    order = sorted(good, key=lambda p: p["t"])
    ax.plot(
        [x(p) for p in order],
        [p["rho"] for p in order],
        "-",
        color="0.6",
        lw=0.7,
        zorder=0,
    )
    fast = [p for p in order if p.get("rho_oscillatory")]
    if fast:
        ax.plot(
            [x(p) for p in fast],
            [p["rho_oscillatory"] for p in fast],
            "o",
            mfc="none",
            color="0.4",
            ms=5,
            label="|z| of the modes above 1 Hz",
        )
