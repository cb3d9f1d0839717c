"""Does a run's answer hold when the integration step is refined? The same
scenario (or a window of it) run at its shipped numerics and at the step
halved, then halved again, until the metrics stop changing.

Use: ``study = converge(scenario, duration=4.0)``; ``study.runs`` are the
runs from the shipped step to the finest, ``study.changes[i]`` run i's
relative change of every metric against the finest, ``study.converged``
whether the last halving moved every compared metric by at most
``study.tolerance``; :func:`write_convergence` writes convergence.json and
convergence.md.

The refined runs hold the cutting force's damping between samples as
eq. (3) gives it (``process.sample_mean: false``): the held sample mean
is the one-step treatment of the shipped numerics, what the refined runs
check. The runtime guards stay as the scenario has them; a guard that
stops one run and not another is a change of the answer too
(``stop_reason`` per run)."""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
import json
from pathlib import Path
from typing import Callable, Dict, List, Optional, Sequence

import numpy as np

from deburr_drake.cell.gains import resolve_design
from deburr_drake.cell.plan import CellPlan, plan_cell
from deburr_drake.config import ConfigError, Scenario
from deburr_drake.runs.passes import run_pass, truth_force
from deburr_drake.runs.simulation import RunLog

__all__ = [
    "ConvergenceRun",
    "Convergence",
    "COMPARED",
    "refined",
    "converge",
    "write_convergence",
    "convergence_markdown",
]

#: The metrics whose change decides convergence (those a run gives): the
#: finish and force errors of the pass, the feeds, and the loop's
#: stability as a force signal shows it (the true chamfering force's fast
#: part and its largest value after the contact transient).
COMPARED = (
    "chamfer_depth_rms_error_mm",
    "chamfering_force_rms_error_N",
    "normal_force_rms_error_N",
    "depth_tracking_rms_error_mm",
    "feed_mean_off_burrs_mm_s",
    "feed_mean_on_burrs_mm_s",
    "fast_chamfering_force_std_N",
    "max_chamfering_force_N",
)
#: Metrics that say how the run was computed, not what it gave.
_NOT_ANSWERS = ("wall_time_s", "sim_time_s")
#: The moving average the fast part of the force leaves out (s).
FAST_AVERAGE = 0.1
#: Seconds after the first contact before the force's stability measures.
SETTLE = 2.0


@dataclass
class ConvergenceRun:
    """One run of the study: its numerics and what it gave."""

    max_step: float  # s
    sample_mean: bool
    stop_reason: str
    stop_time: float  # s
    wall_time: float  # s
    metrics: Dict[str, float] = field(default_factory=dict)


@dataclass
class Convergence:
    scenario: str
    duration: float  # s, simulated per run
    tolerance: float  # relative change that counts as no change
    runs: List[ConvergenceRun] = field(default_factory=list)
    changes: List[Dict[str, float]] = field(default_factory=list)
    last_change: Dict[str, float] = field(default_factory=dict)
    converged: bool = False
    note: str = ""

    def to_dict(self) -> Dict:
        out = asdict(self)
        return _finite(out)


def _finite(x):
    """JSON-safe: non-finite numbers become None."""
    if isinstance(x, dict):
        return {k: _finite(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_finite(v) for v in x]
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (float, int, np.floating, np.integer)):
        return float(x) if np.isfinite(x) else None
    return x


def refined(scenario: Scenario, halvings: int) -> Scenario:
    """A copy of ``scenario`` (its designed values resolved) with
    ``simulation.max_step`` halved ``halvings`` times and, refined,
    eq. (3) followed between samples (``process.sample_mean`` false)."""
    run = resolve_design(scenario)  # a copy: changed below
    if halvings > 0:
        run.simulation.max_step /= 2**halvings
        run.process.sample_mean = False
    return run.validate()


def force_stability(log: RunLog, contact_time: float) -> Dict[str, float]:
    """The true chamfering force after ``SETTLE`` s of contact: the std
    of its fast part (minus its ``FAST_AVERAGE`` s moving average) and
    its largest value (N); nan when the run is shorter."""
    out = {
        "fast_chamfering_force_std_N": float("nan"),
        "max_chamfering_force_N": float("nan"),
    }
    proc = log.signals.get("process")
    if proc is None or not np.isfinite(contact_time):
        return out
    t, f = np.asarray(proc["t"], float), np.asarray(proc["f_t"], float)
    late = t >= contact_time + SETTLE
    if late.sum() < 8:
        return out
    dt = float(np.median(np.diff(t)))
    n = 2 * int(round(FAST_AVERAGE / dt / 2)) + 1
    f_late = f[late]
    n = min(n, 2 * ((len(f_late) - 1) // 2) + 1)
    kernel = np.ones(n)
    mean = np.convolve(f_late, kernel, "same") / np.convolve(
        np.ones_like(f_late), kernel, "same"
    )
    out["fast_chamfering_force_std_N"] = float(np.std(f_late - mean))
    out["max_chamfering_force_N"] = float(np.max(np.abs(f_late)))
    return out


def relative_change(a: float, b: float) -> float:
    """|a - b| / max(|a|, |b|): 0 for equal values (both 0 too), at most
    1 unless the signs differ; nan when either is not finite."""
    if not (np.isfinite(a) and np.isfinite(b)):
        return float("nan")
    scale = max(abs(a), abs(b))
    return 0.0 if scale == 0 else abs(a - b) / scale


def _run_once(plan: CellPlan, duration, truth) -> ConvergenceRun:
    scenario = plan.scenario
    done = run_pass(plan, duration=duration, truth=truth)
    log, wall = done.log, done.log.wall_time
    values = dict(done.metrics)
    values.update(
        force_stability(log, values.get("contact_time_s", float("nan")))
    )
    return ConvergenceRun(
        max_step=scenario.simulation.max_step,
        sample_mean=scenario.process.sample_mean,
        stop_reason=log.stop_reason,
        stop_time=log.stop_time,
        wall_time=wall,
        metrics={
            k: float(v)
            for k, v in values.items()
            if k not in _NOT_ANSWERS and np.isscalar(v)
        },
    )


def converge(
    scenario: Scenario,
    *,
    duration: Optional[float] = None,
    max_halvings: int = 3,
    tolerance: float = 0.05,
    compared: Sequence[str] = COMPARED,
    progress: Optional[Callable[[str], None]] = None,
) -> Convergence:
    """Runs ``scenario`` for ``duration`` (its own by default) at its
    shipped numerics, then at ``simulation.max_step`` / 2, / 4, ...
    (:func:`refined`) until the last halving changed every ``compared``
    metric the runs give by at most ``tolerance`` (relative) and ended
    the run the same way, or after ``max_halvings`` refined runs. The
    changes are against the finest run."""
    if not (isinstance(max_halvings, int) and max_halvings >= 1):
        raise ConfigError(
            f"--steps = {max_halvings!r} is invalid: allowed an integer >= 1"
        )
    if not (np.isfinite(tolerance) and tolerance > 0):
        raise ConfigError(
            f"--tolerance = {tolerance!r} is invalid: allowed a number > 0"
        )
    say = progress or (lambda message: None)
    scenario.validate()
    duration = scenario.simulation.duration if duration is None else duration
    study = Convergence(scenario.name, duration, tolerance)
    # One plan: the refined runs change only the numerics.
    plan = plan_cell(scenario)
    truth, why = truth_force(plan)
    if truth is None:  # the metrics then leave out what needs it
        study.note = f"no contact truth: {why}"
    for halvings in range(max_halvings + 1):
        run = _run_once(
            plan.varied(refined(plan.scenario, halvings)), duration, truth
        )
        study.runs.append(run)
        say(
            f"max_step {run.max_step * 1e3:.4g} ms, sample_mean "
            f"{str(run.sample_mean).lower()}: {run.stop_reason} at "
            f"{run.stop_time:.3f} s, {run.wall_time:.1f} s wall"
        )
        if halvings == 0:
            continue
        study.last_change = _changes(study.runs[-2], run, compared)
        if _settled(study.runs[-2], run, study.last_change, tolerance):
            study.converged = True
            break
    finest = study.runs[-1]
    study.changes = [
        _changes(run, finest, list(run.metrics)) for run in study.runs
    ]
    return study


def _changes(run, other, keys) -> Dict[str, float]:
    return {
        k: relative_change(
            run.metrics.get(k, float("nan")), other.metrics.get(k, float("nan"))
        )
        for k in keys
        if k in run.metrics or k in other.metrics
    }


def _settled(coarse, fine, change, tolerance) -> bool:
    """The last halving changed nothing that counts: the same ending,
    every compared metric the runs give within ``tolerance``."""
    if coarse.stop_reason != fine.stop_reason:
        return False
    given = [v for v in change.values() if not np.isnan(v)]
    return bool(given) and max(given) <= tolerance


def convergence_markdown(study: Convergence) -> str:
    """The study as a markdown table: each run's compared metrics (with
    its relative change against the finest) and how it ended."""
    runs = study.runs
    head = ["metric"] + [
        f"{r.max_step * 1e3:.4g} ms" + ("" if r.sample_mean else ", eq. (3)")
        for r in runs
    ]
    lines = [
        f"# Convergence: {study.scenario}, {study.duration:g} s",
        "",
        f"Step halved until every compared metric changed by at most "
        f"{study.tolerance:.3g} (relative) and the run ended the same way: "
        + (
            "converged."
            if study.converged
            else "not converged within the halvings run."
        ),
        "",
        "| " + " | ".join(head) + " |",
        "|" + "---|" * len(head),
    ]
    keys = [k for k in COMPARED if any(k in r.metrics for r in runs)]
    for key in keys:
        cells = []
        for r, change in zip(runs, study.changes):
            v = r.metrics.get(key, float("nan"))
            c = change.get(key, float("nan"))
            cells.append(
                "n/a"
                if not np.isfinite(v)
                else f"{v:.4g}"
                + ("" if not np.isfinite(c) else f" ({100 * c:.1f} %)")
            )
        lines.append(f"| {key} | " + " | ".join(cells) + " |")
    lines.append(
        "| stop | "
        + " | ".join(f"{r.stop_reason} at {r.stop_time:.2f} s" for r in runs)
        + " |"
    )
    lines.append(
        "| wall time | "
        + " | ".join(f"{r.wall_time:.1f} s" for r in runs)
        + " |"
    )
    lines += [
        "",
        "(x %): the relative change |a - b| / max(|a|, |b|) against the "
        "finest run.",
    ]
    if study.note:
        lines += ["", study.note]
    return "\n".join(lines) + "\n"


def write_convergence(study: Convergence, out) -> Dict[str, Path]:
    """convergence.json (strict JSON) and convergence.md in ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    paths = {
        "json": out / "convergence.json",
        "markdown": out / "convergence.md",
    }
    paths["json"].write_text(
        json.dumps(study.to_dict(), indent=2, sort_keys=True, allow_nan=False)
    )
    paths["markdown"].write_text(convergence_markdown(study))
    return paths
