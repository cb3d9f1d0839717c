"""A run's files: logs.npz (every logged array by name, SI units) and
metrics.json (the metrics of :mod:`deburr_drake.runs.pass_metrics`, how the
run ended, and why any metric is null).

Use: ``values = pass_metrics(log, only_cut=True)``;
``log_arrays(log, values)`` is the flat dict the figures read;
``write_run(log, out_dir, values)`` writes both files."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Dict

import numpy as np

from deburr_drake.runs.simulation import RunLog

__all__ = ["run_summary", "write_run", "log_arrays", "SUMMARY_FIELDS"]

#: What metrics.json holds besides the metrics (:func:`run_summary`), for
#: the generated metrics reference: name -> (unit, meaning).
SUMMARY_FIELDS: Dict[str, tuple] = {
    "scenario": ("-", "the scenario's name"),
    "completed_pass": (
        "-",
        "true if the tool went once round the edge (a boolean here, 1 or 0 "
        "among the printed metrics)",
    ),
    "stop_reason": (
        "-",
        "what ended the run: one of ``simulation.STOP_REASONS`` "
        "(``pass_complete``, ``duration``, ``guard:<name>``, ...)",
    ),
    "stop_time_s": ("s", "the simulated time the run stopped at"),
    "stop_detail": (
        "-",
        "a guard's values at the trip, an exception's message, a signal's "
        "name; empty otherwise",
    ),
    "unavailable": (
        "-",
        "for each metric that is null, why this run cannot give it",
    ),
}


def _json_value(value):
    """Strict JSON: nan and infinities become null."""
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, float, np.floating, np.integer)):
        value = float(value)
        return value if np.isfinite(value) else None
    return value


def run_summary(log: RunLog, metrics_: Dict[str, float]) -> dict:
    """What metrics.json holds: the scenario, how the run ended
    (``completed_pass``, ``stop_reason``, ``stop_time_s``,
    ``stop_detail``), every metric (null where it cannot be computed) and
    ``unavailable``: the reason for each null."""
    reasons = dict(getattr(metrics_, "reasons", {}))
    values = {}
    for key, value in metrics_.items():
        values[key] = _json_value(value)
        if values[key] is None and key not in reasons:
            reasons[key] = "not finite (the run diverged)"
    values.update(
        {
            "scenario": log.scenario.name,
            "completed_pass": bool(log.completed_pass),
            "stop_reason": log.stop_reason,
            "stop_time_s": float(log.stop_time),
            "stop_detail": log.stop_detail,
            "unavailable": reasons,
        }
    )
    return values


def log_arrays(
    log: RunLog, metrics_: Dict[str, float]
) -> Dict[str, np.ndarray]:
    """Every array of the run as ``"<logger>.<block>"`` plus the
    ``meta.*`` entries the figures read (desired depth and force, contact
    start, stop time and reason): what logs.npz holds, and what
    :func:`deburr_drake.runs.figures.make_figures` takes without a file."""
    arrays = log.flat()
    sc = log.scenario
    arrays["meta.desired_depth"] = np.array(sc.task.desired_depth)
    arrays["meta.desired_force"] = np.array(sc.task.desired_chamfering_force)
    if np.isfinite(metrics_.get("contact_time_s", np.nan)):
        arrays["meta.contact_start"] = np.array(metrics_["contact_time_s"])
    arrays["meta.stop_time"] = np.array(log.stop_time)
    arrays["meta.stop_reason"] = np.array(log.stop_reason)
    return arrays


def write_run(
    log: RunLog, out_dir, metrics_: Dict[str, float]
) -> Dict[str, Path]:
    """logs.npz (:func:`log_arrays`: named arrays, SI units) and
    metrics.json (strict JSON, see :func:`run_summary`) in ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(out / "logs.npz", **log_arrays(log, metrics_))
    with open(out / "metrics.json", "w") as f:
        json.dump(
            run_summary(log, metrics_),
            f,
            indent=2,
            sort_keys=True,
            allow_nan=False,
        )
    return {"logs": out / "logs.npz", "metrics": out / "metrics.json"}
